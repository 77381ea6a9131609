// ParameterTable: one description of a component's keys reads YAML (ranges, degrees, unknown keys
// rejected with file and line), prints the effective values, and finds keys a file leaves out.
#include <gtest/gtest.h>

#include "config/parameter_table.hpp"
#include "scratch_files.hpp"

namespace polarslam {
namespace {

struct Params {
  double distance = 0.6;
  double angle = deg2rad(25.0);
  int count = 3;
  bool enabled = true;
  std::string mode = "fast";
  double inner = 1.5;
};

void describe(ParameterTable& t, Params& p) {
  t.number("distance", p.distance, 0.0, 10.0, "m");
  t.angle("angle_deg", p.angle, 0.0, 180.0, "heading");
  t.integer("count", p.count, 1, 10, "how many");
  t.boolean("enabled", p.enabled, "on or off");
  t.choice(
      "mode", {"fast", "slow"}, [&p](const std::string& w) { p.mode = w; return true; }, [&p] { return p.mode; },
      "speed");
  t.section("inner", "a nested map").number("value", p.inner, 0.0, 5.0, "inside");
}

ScratchFiles scratch;  // removed as the test process ends

Params readParams(const std::string& text) {
  const YamlFields yaml(scratch.write("parameters.yaml", text));
  Params p;
  ParameterTable table;
  describe(table, p);
  table.read(yaml, yaml.root(), "test");
  return p;
}

std::string errorOf(const std::string& text) {
  try {
    readParams(text);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

TEST(ParameterTable, ReadsNumbersDegreesWholeNumbersFlagsWordsAndSections) {
  const Params p = readParams("distance: 1.25\nangle_deg: 90\ncount: 7\nenabled: false\nmode: slow\ninner: {value: 4}\n");
  EXPECT_DOUBLE_EQ(p.distance, 1.25);
  EXPECT_DOUBLE_EQ(p.angle, deg2rad(90.0));
  EXPECT_EQ(p.count, 7);
  EXPECT_FALSE(p.enabled);
  EXPECT_EQ(p.mode, "slow");
  EXPECT_DOUBLE_EQ(p.inner, 4.0);
  const Params defaults = readParams("count: 3\n");
  EXPECT_DOUBLE_EQ(defaults.distance, 0.6) << "keys left out keep their defaults";
}

TEST(ParameterTable, BadValuesAreErrorsNamingFileLineAndKey) {
  const std::string path = scratch.path("parameters.yaml");
  EXPECT_NE(errorOf("distance: 1\ndistanse: 2\n").find(path + ":2: unknown key 'distanse'"), std::string::npos)
      << errorOf("distance: 1\ndistanse: 2\n");
  EXPECT_NE(errorOf("distance: 11\n").find(path + ":1: test.distance: 11 is outside"), std::string::npos);
  EXPECT_NE(errorOf("count: 2.5\n").find("whole number"), std::string::npos);
  EXPECT_NE(errorOf("enabled: maybe\n").find("true or false"), std::string::npos);
  EXPECT_NE(errorOf("mode: medium\n").find("expected one of fast, slow"), std::string::npos);
  EXPECT_NE(errorOf("inner: {value: 9}\n").find("test.inner.value"), std::string::npos);
  EXPECT_NE(errorOf("angle_deg: .nan\n").find("finite"), std::string::npos);
}

TEST(ParameterTable, PrintsWhatItReadsAndFindsKeysAFileLeavesOut) {
  Params p;
  ParameterTable table;
  describe(table, p);
  EXPECT_EQ(table.keys(), (std::vector<std::string>{"distance", "angle_deg", "count", "enabled", "mode", "inner.value"}));
  const std::string printed = table.yaml();
  const YamlFields full(scratch.write("printed.yaml", printed));
  EXPECT_TRUE(table.missingFrom(full.root()).empty()) << printed;
  const YamlFields partial(scratch.write("partial.yaml", "distance: 1\ninner: {}\n"));
  EXPECT_EQ(table.missingFrom(partial.root()),
            (std::vector<std::string>{"angle_deg", "count", "enabled", "mode", "inner.value"}));
  p = readParams(printed);
  EXPECT_DOUBLE_EQ(p.angle, deg2rad(25.0)) << "degrees in the file, radians in the code";
}

TEST(ParameterTable, AnAngleKeyMustSayDegrees) {
  double radians = 0.0;
  ParameterTable table;
  EXPECT_THROW(table.angle("heading", radians, 0, 90, ""), std::logic_error);
  table.number("x", radians, 0, 1, "");
  EXPECT_THROW(table.number("x", radians, 0, 1, ""), std::logic_error) << "declared twice";
}

}  // namespace
}  // namespace polarslam
