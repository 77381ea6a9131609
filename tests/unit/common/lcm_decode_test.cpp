// decodeLcm (processes/common/lcm_decode.hpp): malformed bytes that make lcm-gen's decode()
// throw are a rejected message, not a crash (regression for the fuzz_lcm_messages findings).
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <vector>

#include "common/lcm_decode.hpp"
#include "common/lcm_log.hpp"
#include "polarslam/features_t.hpp"
#include "polarslam/laser_scan_t.hpp"
#include "polarslam/pose_t.hpp"
#include "polarslam/sonar_targets_t.hpp"

namespace polarslam {
namespace {

template <typename MsgT>
std::vector<uint8_t> encode(const MsgT& msg) {
  std::vector<uint8_t> buf(static_cast<size_t>(msg.getEncodedSize()));
  EXPECT_GE(msg.encode(buf.data(), 0, static_cast<int>(buf.size())), 0);
  return buf;
}

/// Offset of the frame string's int32 length field: 8-byte hash, int64 utime, int64 seq.
constexpr size_t kFrameLengthOffset = 8 + 8 + 8;

TEST(LcmDecode, ValidPoseDecodes) {
  pose_t msg{};
  msg.utime = 42;
  msg.frame = "map";
  const std::vector<uint8_t> buf = encode(msg);
  pose_t out{};
  ASSERT_TRUE(decodeLcm(out, buf.data(), buf.size()));
  EXPECT_EQ(out.utime, 42);
  EXPECT_EQ(out.frame, "map");
}

TEST(LcmDecode, ZeroStringLengthIsRejectedNotThrown) {
  pose_t msg{};
  msg.frame = "map";
  std::vector<uint8_t> buf = encode(msg);
  // The encoded length of "map" is 4 (with the terminating NUL), big-endian.
  ASSERT_EQ(buf[kFrameLengthOffset + 3], 4);
  std::memset(&buf[kFrameLengthOffset], 0, 4);
  pose_t out{};
  EXPECT_THROW((void)out.decode(buf.data(), 0, static_cast<int>(buf.size())), std::length_error)
      << "lcm-gen's decode no longer throws here: this test documents why decodeLcm exists";
  EXPECT_FALSE(decodeLcm(out, buf.data(), buf.size()));
  LogEvent event;
  event.data = buf;
  EXPECT_FALSE(event.decode(out));
}

/// Big-endian int32 at `pos`.
void putCount(std::vector<uint8_t>& buf, size_t pos, uint32_t count) {
  for (int i = 0; i < 4; ++i) buf[pos + static_cast<size_t>(i)] = static_cast<uint8_t>(count >> (24 - 8 * i));
}

uint32_t getCount(const std::vector<uint8_t>& buf, size_t pos) {
  return (uint32_t{buf[pos]} << 24) | (uint32_t{buf[pos + 1]} << 16) | (uint32_t{buf[pos + 2]} << 8) | buf[pos + 3];
}

TEST(LcmDecode, HugeOrNegativeLaserCountIsRejectedBeforeAllocating) {
  laser_scan_t scan{};
  scan.num_ranges = 3;
  scan.ranges = {1.0f, 2.0f, 3.0f};
  std::vector<uint8_t> buf = encode(scan);
  laser_scan_t out{};
  ASSERT_TRUE(decodeLcm(out, buf.data(), buf.size()));
  ASSERT_EQ(out.ranges.size(), 3u);
  const size_t count_at = 8 + 2 * 8 + 4 * 8 + 3 * 8;
  ASSERT_EQ(getCount(buf, count_at), 3u);
  putCount(buf, count_at, 0x7fffffffu);  // 2^31 - 1 beams in a 92-byte message: 8 GB if trusted
  EXPECT_FALSE(decodeLcm(out, buf.data(), buf.size()));
  putCount(buf, count_at, 4);  // one more beam than the bytes hold
  EXPECT_FALSE(decodeLcm(out, buf.data(), buf.size()));
  putCount(buf, count_at, 0xffffffffu);  // -1
  EXPECT_FALSE(decodeLcm(out, buf.data(), buf.size()));
}

TEST(LcmDecode, SonarAndFeatureCountsAreChecked) {
  sonar_targets_t sonar{};
  sonar.num_targets = 2;
  sonar.targets.resize(2);
  sonar.targets[1].range = 1.5;
  std::vector<uint8_t> sbuf = encode(sonar);
  sonar_targets_t sout{};
  ASSERT_TRUE(decodeLcm(sout, sbuf.data(), sbuf.size()));
  EXPECT_EQ(sout.targets.at(1).range, 1.5);
  const size_t targets_at = 8 + 2 * 8 + 4 + 3 * 8 + 2 * 8;
  ASSERT_EQ(getCount(sbuf, targets_at), 2u);
  putCount(sbuf, targets_at, 0x40000000u);
  EXPECT_FALSE(decodeLcm(sout, sbuf.data(), sbuf.size()));

  features_t features{};
  features.frame = "laser";
  features.num_lines = 1;
  features.lines.resize(1);
  features.lines[0].d = 2.0;
  features.num_corners = 1;
  features.corners.resize(1);
  features.num_points = 2;
  features.points.resize(2);
  features.points[1].x = -0.5;
  features.num_rejected = 3;
  std::vector<uint8_t> fbuf = encode(features);
  features_t fout{};
  ASSERT_TRUE(decodeLcm(fout, fbuf.data(), fbuf.size()));
  EXPECT_EQ(fout.frame, "laser");
  EXPECT_EQ(fout.lines.at(0).d, 2.0);
  EXPECT_EQ(fout.points.at(1).x, -0.5);
  EXPECT_EQ(fout.num_rejected, 3);
  // The point count sits before 2 points, num_rejected and num_break_hints (no hints) at the end.
  const size_t points_at = fbuf.size() - 4 - 4 - 2 * static_cast<size_t>(point_feature_t{}.getEncodedSize() - 8) - 4;
  ASSERT_EQ(getCount(fbuf, points_at), 2u);
  putCount(fbuf, points_at, 0x7ffffff0u);
  EXPECT_FALSE(decodeLcm(fout, fbuf.data(), fbuf.size()));
}

}  // namespace
}  // namespace polarslam
