// libFuzzer target: the saved-map loader (core/map/map_store). The input is a map folder packed as
// text: each file starts with a line "@@ NAME" (graph.txt, scans.txt, parameters.yaml,
// uncertainty.json, resume.json, ...). Unless the input brings its own manifest.json, one is
// written that lists every file with its true size and CRC32, so that the damage reaches the
// parsers behind the checksums. Bad input must give a MapFormatError; anything else (another
// exception, a crash, UB, a hang) is a finding.
#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

#include "fuzz_support.hpp"
#include "map/map_store.hpp"

namespace {

namespace fs = std::filesystem;

/// The sections "@@ NAME\n..." of the input, by name; text before the first one is ignored.
std::map<std::string, std::string> unpack(std::string_view text) {
  std::map<std::string, std::string> files;
  std::string* current = nullptr;
  size_t at = 0;
  while (at < text.size()) {
    const size_t end = std::min(text.find('\n', at), text.size());
    const std::string_view line = text.substr(at, end - at);
    if (line.starts_with("@@ ")) {
      std::string name(line.substr(3));
      // Names stay inside the folder and fit in the manifest: letters, digits, '.', '_', '-', not hidden.
      const bool plain = std::all_of(name.begin(), name.end(), [](unsigned char c) {
        return std::isalnum(c) || c == '.' || c == '_' || c == '-';
      });
      if (!plain || name.empty() || name[0] == '.' || name.size() > 64) name = "junk";
      current = &files[name];
    } else if (current) {
      current->append(line);
      if (end < text.size()) current->push_back('\n');
    }
    at = end + 1;
  }
  return files;
}

/// The manifest a map with these files would have, its laser the seed corpus's.
std::string manifestFor(const std::map<std::string, std::string>& files) {
  nlohmann::json listed = nlohmann::json::object();
  for (const auto& [name, content] : files) listed[name] = {{"bytes", content.size()}, {"crc32", polarslam::mapCrc32(content)}};
  const nlohmann::json manifest = {
      {"format", polarslam::kMapFormatName},
      {"version", polarslam::kMapFormatVersion},
      {"files", listed},
      {"laser",
       {{"angle_min", -1.5707963267948966}, {"angle_increment", 0.017453292519943295}, {"beams", 181},
        {"range_max", 8.1}, {"mount", {0.2, 0.0, 0.0}}}}};
  return manifest.dump(1);
}

class MapFolder {
 public:
  MapFolder() {
    const char* tmp = std::getenv("TMPDIR");
    std::string pattern = std::string(tmp && *tmp ? tmp : "/tmp") + "/polarslam-fuzz-map-XXXXXX";
    if (!mkdtemp(pattern.data())) throw std::runtime_error("fuzz: cannot create a temporary folder");
    dir_ = pattern;
  }
  ~MapFolder() {
    std::error_code ignored;
    fs::remove_all(dir_, ignored);
  }
  MapFolder(const MapFolder&) = delete;
  MapFolder& operator=(const MapFolder&) = delete;

  /// Replaces the folder's files with `files` (and a fitting manifest unless one is given).
  const std::string& write(std::map<std::string, std::string> files) {
    for (const auto& entry : fs::directory_iterator(dir_)) fs::remove(entry.path());
    if (!files.count("manifest.json")) {
      const std::string manifest = manifestFor(files);
      files["manifest.json"] = manifest;
    }
    for (const auto& [name, content] : files) std::ofstream(dir_ + "/" + name, std::ios::binary) << content;
    return dir_;
  }

 private:
  std::string dir_;
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static MapFolder folder;
  const std::string& dir = folder.write(unpack(polarslam::fuzz::asText(data, size)));
  try {
    const polarslam::StoredMap map = polarslam::loadMap(dir);
    for (const polarslam::MapReference& r : polarslam::mapReferences(map)) (void)r.pose.vec();
  } catch (const polarslam::MapFormatError&) {
  }
  return 0;
}
