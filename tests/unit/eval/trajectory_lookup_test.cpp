// TrajectoryLookup: nearest and interpolated poses by time, with stamps at the ends of int64.
#include <gtest/gtest.h>

#include <limits>

#include "eval/trajectory_lookup.hpp"

namespace polarslam {
namespace {

TEST(TrajectoryLookup, InterpolatesBetweenNeighboursWithinTheLimit) {
  const TrajectoryLookup lookup({{1000, Pose2(0, 0, 0)}, {2000, Pose2(1, 2, 0.2)}});
  const auto mid = lookup.interpolate(1500, 1000);
  ASSERT_TRUE(mid.has_value());
  EXPECT_NEAR(mid->x, 0.5, 1e-12);
  EXPECT_NEAR(mid->y, 1.0, 1e-12);
  EXPECT_NEAR(mid->theta, 0.1, 1e-12);
  EXPECT_FALSE(lookup.interpolate(5000, 1000).has_value());
}

TEST(TrajectoryLookup, CorruptStampsAtTheEndsOfInt64GiveNoMatchNotOverflow) {
  constexpr int64_t kMin = std::numeric_limits<int64_t>::min(), kMax = std::numeric_limits<int64_t>::max();
  const int64_t t = 1700000000000000;
  const TrajectoryLookup lookup({{kMin, Pose2(9, 9, 0)}, {t, Pose2(1, 0, 0)}, {kMax, Pose2(8, 8, 0)}});
  const auto at = lookup.interpolate(t + 10, 100000);
  ASSERT_TRUE(at.has_value());
  EXPECT_DOUBLE_EQ(at->x, 1.0);
  EXPECT_EQ(lookup.nearest(0, 100000), nullptr);
  const auto low = lookup.interpolate(kMin + 1, 10);
  ASSERT_TRUE(low.has_value());
  EXPECT_DOUBLE_EQ(low->x, 9.0);
}

}  // namespace
}  // namespace polarslam
