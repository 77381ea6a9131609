// grid_map_t (processes/common/lcm_convert): a slice survives the round trip through the message,
// raw and zlib-compressed, to the whole percent; malformed messages are rejected with a reason,
// before anything big is allocated.
#include <gtest/gtest.h>
#include <zlib.h>

#include <cmath>
#include <limits>
#include <vector>

#include "common/lcm_convert.hpp"
#include "common/lcm_decode.hpp"

namespace polarslam {
namespace {

constexpr float kUnknown = std::numeric_limits<float>::quiet_NaN();

/// A 7 × 5 slice with unknown cells and probabilities that are not whole percents.
GridSlice sampleSlice() {
  GridSlice s;
  s.resolution = 0.05;
  s.origin = Vec2(-1.25, 3.5);
  s.width = 7;
  s.height = 5;
  for (int i = 0; i < s.width * s.height; ++i)
    s.probability.push_back(i % 4 == 0 ? kUnknown : static_cast<float>(std::fmod(0.0371 * i, 1.0)));
  s.probability[1] = 0.0f;
  s.probability[2] = 1.0f;
  return s;
}

template <typename MsgT>
MsgT throughBytes(const MsgT& msg) {
  std::vector<uint8_t> buf(static_cast<size_t>(msg.getEncodedSize()));
  EXPECT_GE(msg.encode(buf.data(), 0, static_cast<int>(buf.size())), 0);
  MsgT out{};
  EXPECT_TRUE(decodeLcm(out, buf.data(), buf.size()));
  return out;
}

void expectSameToThePercent(const GridSlice& a, const GridSlice& b) {
  EXPECT_EQ(b.width, a.width);
  EXPECT_EQ(b.height, a.height);
  EXPECT_DOUBLE_EQ(b.resolution, a.resolution);
  EXPECT_DOUBLE_EQ(b.origin.x(), a.origin.x());
  EXPECT_DOUBLE_EQ(b.origin.y(), a.origin.y());
  ASSERT_EQ(b.probability.size(), a.probability.size());
  for (size_t i = 0; i < a.probability.size(); ++i) {
    ASSERT_EQ(std::isnan(b.probability[i]), std::isnan(a.probability[i])) << i;
    if (std::isnan(a.probability[i])) continue;
    EXPECT_NEAR(b.probability[i], a.probability[i], 0.005 + 1e-6) << i;
    EXPECT_FLOAT_EQ(b.probability[i], 0.01f * std::round(100.0f * a.probability[i])) << i;  // whole percent
  }
}

TEST(GridMapMessage, RoundTripRawAndCompressed) {
  const GridSlice slice = sampleSlice();
  for (const bool compress : {false, true}) {
    const grid_map_t msg = throughBytes(toLcmGridMap(slice, 1700000000000000, 12, "psm-graph", 345, compress));
    EXPECT_EQ(msg.utime, 1700000000000000);
    EXPECT_EQ(msg.seq, 12);
    EXPECT_EQ(msg.frame, "map");
    EXPECT_EQ(msg.source, "psm-graph");
    EXPECT_EQ(msg.scans, 345);
    EXPECT_EQ(msg.origin[2], 0.0);
    EXPECT_EQ(msg.encoding, compress ? grid_map_t::ENCODING_ZLIB : grid_map_t::ENCODING_RAW);
    if (!compress) {
      ASSERT_EQ(msg.data.size(), 35u);
      EXPECT_EQ(static_cast<int8_t>(msg.data[0]), -1);
      EXPECT_EQ(msg.data[1], 0);
      EXPECT_EQ(msg.data[2], 100);
    }
    GridSlice back;
    ASSERT_EQ(fromLcm(msg, back), "");
    expectSameToThePercent(slice, back);
  }
}

TEST(GridMapMessage, BigUniformGridCompressesAndEmptyGridRoundTrips) {
  GridSlice big;
  big.width = 1000;
  big.height = 800;
  big.probability.assign(800000, kUnknown);
  for (size_t i = 0; i < big.probability.size(); i += 3) big.probability[i] = 0.12f;
  const grid_map_t msg = toLcmGridMap(big, 1, 1, "ekf-anchors", 2000, true);
  EXPECT_LT(msg.data.size(), 20000u);
  GridSlice back;
  ASSERT_EQ(fromLcm(msg, back), "");
  expectSameToThePercent(big, back);

  for (const bool compress : {false, true}) {
    GridSlice empty;
    ASSERT_EQ(fromLcm(throughBytes(toLcmGridMap(GridSlice{}, 1, 1, "ekf-anchors", 0, compress)), empty), "");
    EXPECT_EQ(empty.width, 0);
    EXPECT_TRUE(empty.probability.empty());
  }
}

/// Expects fromLcm to reject `msg` with a reason containing `words`, leaving `out` as it was.
void expectRejected(const grid_map_t& msg, const std::string& words) {
  GridSlice out = sampleSlice();
  const std::string why = fromLcm(msg, out);
  EXPECT_NE(why.find(words), std::string::npos) << "reason: '" << why << "', expected '" << words << "'";
  EXPECT_EQ(out.width, 7) << "a rejected message must not change the output";
}

TEST(GridMapMessage, MalformedHeadersAreRejected) {
  const grid_map_t good = toLcmGridMap(sampleSlice(), 1, 1, "psm-graph", 3, false);
  grid_map_t m = good;
  m.num_bytes = 34;
  expectRejected(m, "num_bytes");
  for (const double bad : {0.0, -0.05, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    m = good;
    m.resolution = bad;
    expectRejected(m, "resolution");
  }
  m = good;
  m.origin[0] = std::numeric_limits<double>::infinity();
  expectRejected(m, "non-finite origin");
  m = good;
  m.origin[2] = 0.3;
  expectRejected(m, "yaw");
  m = good;
  m.width = 8;  // 40 cells announced, 35 bytes sent
  expectRejected(m, "35 bytes for 40 cells");
  m = good;
  m.height = -5;
  expectRejected(m, "negative");
  m = good;
  m.width = 0;
  expectRejected(m, "both be zero");
  m = good;
  m.encoding = 2;
  expectRejected(m, "unknown encoding 2");
  m = good;
  m.data[3] = 101;
  expectRejected(m, "cell value 101");
  m.data[3] = static_cast<uint8_t>(-2);
  expectRejected(m, "cell value -2");
}

TEST(GridMapMessage, AbsurdDimensionsAreRejectedBeforeInflating) {
  // A few bytes of zlib data that would inflate to gigabytes: refused on the dimensions alone.
  grid_map_t m = toLcmGridMap(sampleSlice(), 1, 1, "psm-graph", 3, true);
  m.width = 2000000000;
  m.height = 2000000000;
  expectRejected(m, "more than the");
  m.width = 1 << 14;
  m.height = 1 << 13;  // 2^27 cells, twice the limit
  expectRejected(m, "more than the");
}

TEST(GridMapMessage, BadZlibDataIsAClearErrorNotACrash) {
  const grid_map_t good = toLcmGridMap(sampleSlice(), 1, 1, "psm-graph", 3, true);
  grid_map_t m = good;
  m.data = {1, 2, 3, 4, 5, 6, 7, 8};
  m.num_bytes = 8;
  expectRejected(m, "bad zlib data");
  m = good;  // truncated stream
  m.data.resize(m.data.size() / 2);
  m.num_bytes = static_cast<int32_t>(m.data.size());
  expectRejected(m, "bad zlib data");
  m = good;  // trailing garbage
  m.data.push_back(0);
  m.num_bytes = static_cast<int32_t>(m.data.size());
  expectRejected(m, "after the end");
  m = good;  // more cells than announced
  m.height = 4;
  expectRejected(m, "more than width*height");
  m = good;  // fewer cells than announced
  m.height = 6;
  expectRejected(m, "fewer than width*height");
  m = good;  // raw bytes labelled compressed
  const grid_map_t raw = toLcmGridMap(sampleSlice(), 1, 1, "psm-graph", 3, false);
  m.data = raw.data;
  m.num_bytes = raw.num_bytes;
  expectRejected(m, "bad zlib data");
}

TEST(GridMapMessage, HugeByteCountIsRejectedBeforeDecoding) {
  const grid_map_t msg = toLcmGridMap(sampleSlice(), 1, 1, "psm-graph", 3, false);
  std::vector<uint8_t> buf(static_cast<size_t>(msg.getEncodedSize()));
  ASSERT_GE(msg.encode(buf.data(), 0, static_cast<int>(buf.size())), 0);
  // num_bytes sits just before the 35 data bytes.
  const size_t count_at = buf.size() - 35 - 4;
  ASSERT_EQ(buf[count_at + 3], 35);
  buf[count_at] = 0x7f;  // about 2^31 bytes announced in a message of about 130
  grid_map_t out{};
  EXPECT_FALSE(decodeLcm(out, buf.data(), buf.size()));
}

}  // namespace
}  // namespace polarslam
