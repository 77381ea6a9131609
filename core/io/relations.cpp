#include "io/relations.hpp"

#include <optional>

#include "io/text_fields.hpp"

namespace polarslam {
namespace {

constexpr size_t kRelationFields = 8;

Relation parseRelationLine(std::string_view line, const std::string& name, int line_number) {
  const std::vector<std::string_view> fields = splitFields(line);
  if (fields.size() != kRelationFields)
    throw TextFormatError(name, line_number,
                          "expected 8 fields 't1 t2 x y z roll pitch yaw', found " + std::to_string(fields.size()));
  Relation r;
  r.line = line_number;
  int64_t* const times[] = {&r.t1, &r.t2};
  for (size_t i = 0; i < 2; ++i) {
    const std::optional<int64_t> t = parseSecondsAsUtime(fields[i]);
    if (!t)
      throw TextFormatError(name, line_number,
                            "bad timestamp t" + std::to_string(i + 1) + " '" + std::string(fields[i]) + "'");
    *times[i] = *t;
  }
  double* const values[] = {&r.x, &r.y, &r.z, &r.roll, &r.pitch, &r.yaw};
  static const char* const kNames[] = {"x", "y", "z", "roll", "pitch", "yaw"};
  for (size_t i = 0; i < 6; ++i) {
    const std::optional<double> v = parseFiniteDouble(fields[i + 2]);
    if (!v)
      throw TextFormatError(name, line_number,
                            std::string("bad ") + kNames[i] + " '" + std::string(fields[i + 2]) + "'");
    *values[i] = *v;
  }
  return r;
}

}  // namespace

std::vector<Relation> parseRelations(std::string_view text, const std::string& name) {
  std::vector<Relation> relations;
  int lines = 0;
  forEachDataLine(text, name, [&](int line_number, std::string_view line) {
    relations.push_back(parseRelationLine(line, name, line_number));
    lines = line_number;
  });
  if (relations.empty()) throw TextFormatError(name, lines + 1, "no relations in file");
  return relations;
}

std::vector<Relation> readRelations(const std::string& path) {
  return parseRelations(readTextFile(path), path);
}

}  // namespace polarslam
