// MapFitField: a scan fits the map at its true pose, and a wrong pose either fits poorly or sees
// through mapped walls (the global-localisation checks of map_localizer.hpp).
#include <gtest/gtest.h>

#include <random>

#include "slam/map_fit_field.hpp"
#include "unit/slam/synthetic_run.hpp"

namespace polarslam {
namespace {

struct Fixture {
  World world = testing::makeLoopWorld();
  testing::SyntheticRunOptions options;
  std::mt19937_64 rng{3};
  std::vector<LaserScan> scans;
  std::vector<Pose2> poses;
  Fixture() {
    const std::vector<Pose2> path = testing::loopPath(options);
    for (size_t k = 0; k < path.size(); k += 5) {
      scans.push_back(testing::castScan(world, path[k], options, rng, static_cast<int64_t>(k)));
      poses.push_back(path[k]);
    }
  }
  LaserScan scanAt(const Pose2& pose) { return testing::castScan(world, pose, options, rng, 0); }
};

TEST(MapFitField, AScanFitsAtItsTruePoseAndNotAtAShiftedOrTurnedOne) {
  Fixture f;
  const MapFitField field(f.scans, f.poses, 10.0, 0.1);
  const Pose2 truth(-2.0, -3.0, 0.0);  // in the lower corridor, between two mapped scans
  const LaserScan scan = f.scanAt(truth);
  EXPECT_GT(field.fit(scan, truth), 0.95);
  EXPECT_LT(field.seeThrough(scan, truth, 0.5), 0.02);
  EXPECT_LT(field.fit(scan, Pose2(-2.0, -2.5, 0.0)), 0.6) << "0.5 m to the side";
  const Pose2 turned(-2.0, -3.0, M_PI);
  EXPECT_TRUE(field.fit(scan, turned) < 0.7 || field.seeThrough(scan, turned, 0.5) > 0.1);
}

TEST(MapFitField, ALookAlikeCorridorElsewhereSeesThroughAMappedWall) {
  Fixture f;
  const MapFitField field(f.scans, f.poses, 10.0, 0.1);
  // The upper corridor seen from the lower one's pose, mirrored: its walls fit, what lies beyond does not.
  const LaserScan scan = f.scanAt(Pose2(0.0, -3.0, 0.0));
  const Pose2 elsewhere(0.0, -3.0 + 0.6, 0.0);
  EXPECT_GT(field.seeThrough(scan, elsewhere, 0.5) + (1.0 - field.fit(scan, elsewhere)), 0.3);
  EXPECT_EQ(field.fit(LaserScan{}, Pose2()), 0.0) << "an empty scan fits nothing";
}

}  // namespace
}  // namespace polarslam
