#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "io/relations.hpp"
#include "io/text_fields.hpp"

namespace polarslam {
namespace {

std::string relationsErrorOf(const std::string& text) {
  try {
    parseRelations(text, "r.relations");
  } catch (const TextFormatError& e) {
    return e.what();
  }
  return "";
}

TEST(Relations, ParsesKuemmerleLines) {
  const std::vector<Relation> r = parseRelations(
      "1134864645.90321 1134864646.32420 0.31293 0.02935 0.00000  0.00000 0.00000 0.24198\n"
      "\n"
      "5.5 7 -1 2 0.1 0.2 0.3 -3\n",
      "r.relations");
  ASSERT_EQ(r.size(), 2u);
  EXPECT_EQ(r[0].t1, 1134864645903210);
  EXPECT_EQ(r[0].t2, 1134864646324200);
  EXPECT_DOUBLE_EQ(r[0].x, 0.31293);
  EXPECT_DOUBLE_EQ(r[0].y, 0.02935);
  EXPECT_DOUBLE_EQ(r[0].yaw, 0.24198);
  EXPECT_EQ(r[0].line, 1);
  EXPECT_EQ(r[1].line, 3);
  EXPECT_DOUBLE_EQ(r[1].z, 0.1);
  EXPECT_DOUBLE_EQ(r[1].roll, 0.2);
  EXPECT_DOUBLE_EQ(r[1].pitch, 0.3);
  EXPECT_DOUBLE_EQ(r[1].motion().theta, -3.0);
}

TEST(Relations, ErrorsNameFileAndLine) {
  const std::string good = "1 2 0 0 0 0 0 0\n";
  EXPECT_EQ(relationsErrorOf(good + "1 2 0 0 0 0 0\n"), "r.relations:2: expected 8 fields 't1 t2 x y z roll pitch yaw', found 7");
  EXPECT_EQ(relationsErrorOf(good + good + "1 2 0 0 0 0 0 0 9\n"),
            "r.relations:3: expected 8 fields 't1 t2 x y z roll pitch yaw', found 9");
  EXPECT_EQ(relationsErrorOf(good + "1 x2 0 0 0 0 0 0\n"), "r.relations:2: bad timestamp t2 'x2'");
  EXPECT_EQ(relationsErrorOf(good + "1 2 0 0 0 0 0 1e999\n"), "r.relations:2: bad yaw '1e999'");
  EXPECT_EQ(relationsErrorOf(good + "1 2 0 0,5 0 0 0 0\n"), "r.relations:2: bad y '0,5'");
}

TEST(Relations, TruncatedFileNamesItsLastLine) {
  EXPECT_EQ(relationsErrorOf("1 2 0 0 0 0 0 0\n3 4 0.1 0."), "r.relations:2: expected 8 fields 't1 t2 x y z roll pitch yaw', found 4");
}

TEST(Relations, BinaryContentIsRejectedWithItsLine) {
  std::string binary = "1 2 0 0 0 0 0 0\n";
  binary += std::string("\x89PNG\r\n\x1a\n\0\0\0", 11);
  const std::string what = relationsErrorOf(binary);
  EXPECT_EQ(what, "r.relations:3: binary content (byte 0x1a), not a text file");
}

TEST(Relations, EmptyFileIsAnError) {
  EXPECT_EQ(relationsErrorOf(""), "r.relations:1: no relations in file");
  EXPECT_EQ(relationsErrorOf("# only a comment\n\n"), "r.relations:1: no relations in file");
}

TEST(Relations, MissingFileNamesIt) {
  try {
    readRelations("/nonexistent/x.relations");
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/x.relations"), std::string::npos);
  }
}

TEST(Relations, ParsesTheMitCsailRelationsWhenPresent) {
  const std::string path = std::string(POLARSLAM_SHARED_DATA_DIR) + "/mit-csail/mit-csail.relations";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "shared data absent: " << path << " (only in the full workspace)";
  const std::vector<Relation> r = readRelations(path);
  ASSERT_EQ(r.size(), 1172u);
  EXPECT_EQ(r[0].t1, 1134864645903210);
  EXPECT_EQ(r[0].t2, 1134864646324200);
  EXPECT_DOUBLE_EQ(r[0].yaw, 0.24198);
  for (const Relation& rel : r) {
    EXPECT_EQ(rel.z, 0.0);
    EXPECT_EQ(rel.roll, 0.0);
    EXPECT_EQ(rel.pitch, 0.0);
  }
}

}  // namespace
}  // namespace polarslam
