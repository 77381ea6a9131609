// PSM preprocessing (docs/algorithms.md §4): median filter, far points, segmentation, bearing order,
// decimation, the fast atan2 and corridor detection.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numeric>

#include "scan_fixtures.hpp"
#include "scanmatch/prepared_scan.hpp"

namespace polarslam {
namespace {

LaserScan scanOf(std::vector<float> ranges, double increment = deg2rad(1.0)) {
  LaserScan s;
  s.angle_min = -increment * static_cast<double>(ranges.size() - 1) / 2.0;
  s.angle_increment = increment;
  s.range_max = 80.0;
  s.ranges = std::move(ranges);
  return s;
}

TEST(MedianFilter, FiveValuesAgreeWithSortingForEveryOrder) {
  std::array<float, 5> v{1, 2, 3, 4, 5};
  do {
    std::vector<float> in(v.begin(), v.end()), out;
    medianFilter5(in, out);
    EXPECT_EQ(out[2], 3.0f);
  } while (std::next_permutation(v.begin(), v.end()));
  // ties and infinities
  std::array<float, 5> t{2, 2, 7, INFINITY, 2};
  std::sort(t.begin(), t.end());
  do {
    std::vector<float> in(t.begin(), t.end()), out;
    medianFilter5(in, out);
    EXPECT_EQ(out[2], 2.0f);
  } while (std::next_permutation(t.begin(), t.end()));
}

TEST(MedianFilter, RemovesOneAndTwoReadingObjectsButKeepsThree) {
  // A chair leg of two readings in front of a wall disappears; a 3-reading object survives.
  std::vector<float> in{3, 3, 3, 1, 1, 3, 3, 3, 3, 1, 1, 1, 3, 3, 3};
  std::vector<float> out;
  medianFilter5(in, out);
  EXPECT_EQ(out[3], 3.0f);
  EXPECT_EQ(out[4], 3.0f);
  EXPECT_EQ(out[10], 1.0f);
  // clamped ends: the first reading sees itself three times
  std::vector<float> edge{1, 5, 5, 5, 5}, edge_out;
  medianFilter5(edge, edge_out);
  EXPECT_EQ(edge_out[0], 1.0f);  // window {1, 1, 1, 5, 5}
}

TEST(Preprocessing, FlagsFarNearAndMissingReadingsAndKeepsRawRangesApart) {
  PsmParams params;
  params.median_filter = false;
  LaserScan s = scanOf({2.0f, 12.0f, NAN, 0.05f, -1.0f, 90.0f, 2.0f});
  const PreparedScan p = prepareScan(s, params);
  const std::vector<uint8_t> expected{0, kFlagRange, kFlagRange, kFlagRange, kFlagRange, kFlagRange, 0};
  EXPECT_EQ(p.flags, expected);
  EXPECT_EQ(p.valid_count, 2);
  EXPECT_FLOAT_EQ(s.ranges[1], 12.0f);  // the input scan is untouched
}

TEST(Preprocessing, ReversesScansWithNegativeIncrement) {
  PsmParams params;
  params.median_filter = false;
  LaserScan s = scanOf({1.0f, 2.0f, 3.0f});
  s.angle_min = deg2rad(10.0);
  s.angle_increment = -deg2rad(10.0);
  const PreparedScan p = prepareScan(s, params);
  EXPECT_NEAR(p.geometry->angle_min, deg2rad(-10.0), 1e-12);
  EXPECT_NEAR(p.geometry->angle_increment, deg2rad(10.0), 1e-12);
  EXPECT_EQ(p.range, (std::vector<float>{3.0f, 2.0f, 1.0f}));
  // the reading at bearing +10° (first in the input) is now last, and its point is where it was
  EXPECT_NEAR(p.x[2], std::cos(deg2rad(10.0)), 1e-6);
  EXPECT_NEAR(p.y[2], std::sin(deg2rad(10.0)), 1e-6);
}

TEST(Preprocessing, DecimationKeepsEveryNthBeam) {
  PsmParams params;
  params.median_filter = false;
  params.decimation = 2;
  std::vector<float> r(361);
  std::iota(r.begin(), r.end(), 1.0f);
  for (float& v : r) v = 1.0f + v / 1000.0f;
  const LaserScan s = scanOf(r, deg2rad(0.5));
  const PreparedScan p = prepareScan(s, params);
  ASSERT_EQ(p.size(), 181u);
  EXPECT_NEAR(p.geometry->angle_increment, deg2rad(1.0), 1e-12);
  EXPECT_NEAR(p.geometry->angle_min, -std::numbers::pi / 2, 1e-12);
  EXPECT_EQ(p.range[180], r[360]);
}

TEST(Segmentation, BreaksAtJumpsAndBadReadingsAndMarksLonePoints) {
  std::vector<float> r{1.0f, 1.05f, 1.1f, 3.0f, 3.02f, 1.0f, 5.0f, 5.1f, 5.2f};
  std::vector<uint8_t> flags(r.size(), 0);
  flags[7] = kFlagRange;
  std::vector<int32_t> seg;
  segmentScan(r, flags, 0.2, seg);
  EXPECT_EQ(seg[0], seg[1]);
  EXPECT_EQ(seg[1], seg[2]);
  EXPECT_NE(seg[2], seg[3]);
  EXPECT_EQ(seg[3], seg[4]);
  EXPECT_NE(seg[3], 0);
  EXPECT_EQ(seg[5], 0);  // alone between two jumps
  EXPECT_EQ(seg[6], 0);  // alone before a bad reading
  EXPECT_EQ(seg[7], 0);  // bad
  EXPECT_EQ(seg[8], 0);  // alone at the end
}

TEST(Segmentation, GrazingWallStaysTogetherByExtrapolation) {
  // Ranges growing by 0.15, then 0.25, 0.35 ... per beam: consecutive steps exceed 0.2 m but
  // the linear extrapolation error stays at 0.1 m, so the wall is one segment.
  std::vector<float> r{2.0f, 2.15f, 2.4f, 2.75f, 3.2f, 3.75f};
  std::vector<uint8_t> flags(r.size(), 0);
  std::vector<int32_t> seg;
  segmentScan(r, flags, 0.2, seg);
  for (size_t i = 1; i < r.size(); ++i) EXPECT_EQ(seg[i], seg[0]) << i;
  EXPECT_NE(seg[0], 0);
}

TEST(Segmentation, ThreeCollinearLonePointsAreJoined) {
  // 1 (alone), then 1.3 (alone after a 0.3 jump), then 1.6: the three lie on a line.
  std::vector<float> r{5.0f, 1.0f, 1.3f, 1.6f};
  std::vector<uint8_t> flags(r.size(), 0);
  std::vector<int32_t> seg;
  segmentScan(r, flags, 0.2, seg);
  EXPECT_EQ(seg[0], 0);
  EXPECT_NE(seg[1], 0);
  EXPECT_EQ(seg[1], seg[2]);
  EXPECT_EQ(seg[2], seg[3]);
}

/// RMS angle (rad) between the surface normals of the prepared scans and the wall's, over the
/// readings within ±45° of a wall half a metre ahead (σ = 1 cm).
double normalNoiseNearAWall(const PsmParams& params) {
  World wall;
  wall.addPolyline({{0.5, -3.0}, {0.5, 3.0}}, {Material::Wall}, false, "wall");
  fixtures::Noise noise(7);
  fixtures::ScanSpec spec;
  spec.noise_sigma = 0.01;
  double sum = 0.0;
  int count = 0;
  for (int k = 0; k < 40; ++k) {
    const PreparedScan s = prepareScan(fixtures::simulateScan(wall, {}, spec, &noise), params);
    for (size_t j = 45; j <= 135; ++j) {
      if (!std::isfinite(s.surface.rho[j])) continue;
      const double angle = std::atan2(s.surface.normal_y[j], s.surface.normal_x[j]);  // the wall's is (1, 0)
      sum += angle * angle;
      ++count;
    }
  }
  EXPECT_GT(count, 40 * 80);
  return std::sqrt(sum / count);
}

TEST(SurfaceSlope, SpansCentimetresNearAWallSoNormalsAreNotNoise) {
  PsmParams params;
  params.slope_half_span = 0.05;
  const double wide = normalNoiseNearAWall(params);
  params.slope_half_span = 0.0;  // five readings (the default): 4 cm of wall
  const double five = normalNoiseNearAWall(params);
  std::printf("[ slope ] normal noise half a metre from a wall: %.1f deg (five readings: %.1f deg)\n", rad2deg(wide),
              rad2deg(five));
  EXPECT_LT(wide, deg2rad(8.0));
  EXPECT_GT(five, 2.0 * wide);
}

TEST(SurfaceSlope, FitIsExactOnAStraightProfileUpToTheSegmentEnds) {
  // r = 2 + 0.01·j inside one segment: the slope is 0.01 per beam wherever two readings flank it.
  std::vector<float> ranges(41);
  for (size_t j = 0; j < ranges.size(); ++j) ranges[j] = 2.0f + 0.01f * static_cast<float>(j);
  PsmParams params;
  params.median_filter = false;
  const PreparedScan s = prepareScan(scanOf(ranges), params);
  EXPECT_TRUE(std::isnan(s.slope.front()));
  EXPECT_TRUE(std::isnan(s.slope.back()));
  for (size_t j = 1; j + 1 < ranges.size(); ++j) EXPECT_NEAR(s.slope[j], 0.01f, 1e-5f) << j;
}

TEST(FastAtan2, MatchesLibmEverywhere) {
  double worst = 0.0;
  for (int i = 0; i < 20000; ++i) {
    const double a = -std::numbers::pi + 2.0 * std::numbers::pi * i / 20000.0;
    for (double r : {1e-3, 1.0, 37.0}) {
      const double x = r * std::cos(a), y = r * std::sin(a);
      worst = std::max(worst, std::abs(fastAtan2(y, x) - std::atan2(y, x)));
    }
  }
  EXPECT_LT(worst, 5e-8);
  EXPECT_EQ(fastAtan2(0.0, 0.0), 0.0);
  EXPECT_NEAR(fastAtan2(0.0, -1.0), std::numbers::pi, 1e-12);
}

TEST(Corridor, DetectedInCorridorsNotInRooms) {
  PsmParams params;
  const fixtures::ScanSpec spec;
  auto corridorOf = [&](const World& world, const Pose2& pose) {
    return detectCorridor(prepareScan(fixtures::simulateScan(world, pose, spec), params), params.corridor_threshold);
  };
  const CorridorInfo corridor = corridorOf(fixtures::psmTestCorridor(), {});
  EXPECT_TRUE(corridor.is_corridor);
  EXPECT_NEAR(std::min(corridor.angle, std::numbers::pi - corridor.angle), 0.0, deg2rad(1.0));
  EXPECT_FALSE(corridorOf(fixtures::psmTestRoom(), {}).is_corridor);
  EXPECT_FALSE(corridorOf(fixtures::clutteredOffice(), {0.5, 0.2, 0.7}).is_corridor);
}

TEST(Corridor, AngleFollowsTheCorridorInTheLaserFrame) {
  PsmParams params;
  const fixtures::ScanSpec spec;
  for (double heading : {0.3, 1.0, -0.6}) {
    const CorridorInfo corridor = detectCorridor(
        prepareScan(fixtures::simulateScan(fixtures::officeCorridor(), {0.0, 0.2, heading}, spec), params),
        params.corridor_threshold);
    EXPECT_TRUE(corridor.is_corridor) << heading;
    // the corridor runs along world x, i.e. at −heading in the laser frame (mod π)
    const double expected = std::fmod(-heading + 2.0 * std::numbers::pi, std::numbers::pi);
    double d = std::abs(corridor.angle - expected);
    d = std::min(d, std::numbers::pi - d);
    EXPECT_LT(d, deg2rad(2.0)) << heading;
  }
}

}  // namespace
}  // namespace polarslam
