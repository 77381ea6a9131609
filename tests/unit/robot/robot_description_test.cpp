// Robot + sensor config loading: the bundled default equals the built-in defaults, and bad
// files give errors naming the file, the line and the key.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include <unistd.h>

#include "robot/robot_description.hpp"
#include "unit/sim/sim_test_helpers.hpp"

namespace polarslam {
namespace {

TEST(RobotDescription, BundledDefaultEqualsBuiltInDefaults) {
  const RobotDescription file = loadRobotDescription(test::sourcePath("config/robots/default.yaml"));
  const RobotDescription code;
  EXPECT_EQ(file.start_utime, code.start_utime);
  EXPECT_DOUBLE_EQ(file.ground_truth_rate, code.ground_truth_rate);
  EXPECT_DOUBLE_EQ(file.robot.wheel_base, code.robot.wheel_base);
  EXPECT_DOUBLE_EQ(file.robot.max_speed, code.robot.max_speed);
  EXPECT_NEAR(file.robot.max_turn_rate, code.robot.max_turn_rate, 1e-12);
  EXPECT_DOUBLE_EQ(file.robot.control_period, code.robot.control_period);
  EXPECT_DOUBLE_EQ(file.robot.follower.lookahead, code.robot.follower.lookahead);
  EXPECT_NEAR(file.robot.follower.turn_in_place_angle, code.robot.follower.turn_in_place_angle, 1e-12);
  EXPECT_DOUBLE_EQ(file.odometry.rate, code.odometry.rate);
  EXPECT_DOUBLE_EQ(file.odometry.k_left, code.odometry.k_left);
  EXPECT_DOUBLE_EQ(file.odometry.k_right, code.odometry.k_right);
  EXPECT_EQ(file.laser.beams, code.laser.beams);
  EXPECT_NEAR(file.laser.fov, code.laser.fov, 1e-12);
  EXPECT_NEAR(file.laser.angle_min, code.laser.angle_min, 1e-12);
  EXPECT_DOUBLE_EQ(file.laser.range_max, code.laser.range_max);
  EXPECT_NEAR(file.laser.time_increment, code.laser.time_increment, 1e-9);
  EXPECT_DOUBLE_EQ(file.laser.mount.x, code.laser.mount.x);
  EXPECT_DOUBLE_EQ(file.laser.errors.fixed_bias, code.laser.errors.fixed_bias);
  EXPECT_DOUBLE_EQ(file.laser.errors.scan_bias_sigma, code.laser.errors.scan_bias_sigma);
  EXPECT_DOUBLE_EQ(file.laser.errors.growth, code.laser.errors.growth);
  EXPECT_DOUBLE_EQ(file.laser.errors.incidence, code.laser.errors.incidence);
  EXPECT_DOUBLE_EQ(file.laser.errors.quantum, code.laser.errors.quantum);
  EXPECT_DOUBLE_EQ(file.laser.errors.noise_sigma, code.laser.errors.noise_sigma);
  EXPECT_NEAR(file.laser.errors.max_incidence, code.laser.errors.max_incidence, 1e-12);
  EXPECT_EQ(file.laser.compensate_quantizer_offset, code.laser.compensate_quantizer_offset);
  ASSERT_EQ(file.sonars.size(), code.sonars.size());
  for (size_t i = 0; i < file.sonars.size(); ++i) {
    EXPECT_EQ(file.sonars[i].name, code.sonars[i].name);
    EXPECT_EQ(file.sonars[i].id, code.sonars[i].id);
    EXPECT_NEAR(file.sonars[i].mount.theta, code.sonars[i].mount.theta, 1e-12);
    EXPECT_NEAR(file.sonars[i].fov, code.sonars[i].fov, 1e-12);
    EXPECT_NEAR(file.sonars[i].bearing_sigma, code.sonars[i].bearing_sigma, 1e-12);
    EXPECT_DOUBLE_EQ(file.sonars[i].range_sigma, code.sonars[i].range_sigma);
    EXPECT_DOUBLE_EQ(file.sonars[i].spurious_rate, code.sonars[i].spurious_rate);
    EXPECT_DOUBLE_EQ(file.sonars[i].misclassification_rate, code.sonars[i].misclassification_rate);
  }
}

class SimConfigFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() / ("polarslam_simcfg_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  RobotDescription load(const std::string& text) {
    const std::string path = (dir_ / "robot.yaml").string();
    std::ofstream(path) << text;
    return loadRobotDescription(path);
  }
  std::string errorOf(const std::string& text) {
    try {
      load(text);
    } catch (const std::runtime_error& e) {
      return e.what();
    }
    ADD_FAILURE() << "loaded without error:\n" << text;
    return {};
  }
  std::filesystem::path dir_;
};

TEST_F(SimConfigFile, MissingKeysKeepDefaultsAndDegreesBecomeRadians) {
  const RobotDescription c = load("laser:\n  fov_deg: 90\n  beams: 91\nsonars: []\n");
  EXPECT_NEAR(c.laser.fov, M_PI / 2, 1e-12);
  EXPECT_NEAR(c.laser.angle_min, -M_PI / 4, 1e-12);  // default: centred
  EXPECT_NEAR(c.laser.angleIncrement(), deg2rad(1.0), 1e-12);
  EXPECT_TRUE(c.sonars.empty());
  EXPECT_DOUBLE_EQ(c.robot.max_speed, RobotDescription{}.robot.max_speed);
}

TEST_F(SimConfigFile, TheLaserErrorModelForFeaturesIsTheOneTheSimulatorApplies) {
  const RobotDescription robot = load(R"(
laser:
  tilt_deg: 1.5
  errors:
    fixed_bias: 0.005
    scan_bias_sigma: 0.003
    quantum: 0.01
    noise_sigma: 0.01
    compensate_quantizer_offset: false
    output_noise_sigma: 0.002
)");
  const LaserErrorParams e = laserErrorParams(robot.laser);
  EXPECT_DOUBLE_EQ(e.range.fixed_bias, 0.005 + 0.005);  // + q/2 of the uncompensated quantiser
  EXPECT_DOUBLE_EQ(e.range.scan_bias_sigma, 0.003);
  EXPECT_DOUBLE_EQ(e.range.quantum, 0.01);
  EXPECT_DOUBLE_EQ(e.output_noise_sigma, 0.002);
  EXPECT_NEAR(e.tilt, deg2rad(1.5), 1e-12);
  EXPECT_DOUBLE_EQ(laserErrorParams(load("laser:\n  errors: {fixed_bias: 0.005, quantum: 0.01}\n").laser).range.fixed_bias,
                   0.005);  // compensated by default
}

TEST_F(SimConfigFile, ErrorsNameFileLineAndKey) {
  struct Case { std::string text, line, words; };
  const Case cases[] = {
      {"robot:\n  max_speed: fast\n", ":2:", "robot.max_speed: 'fast' is not a number"},
      {"robot:\n  max_speed: -1\n", ":2:", "outside the allowed range"},
      {"laser:\n  beams: 181.5\n", ":2:", "laser.beams: expected a whole number"},
      {"laser:\n  rate: 75\n  time_increment: 0.001\n", ":3:", "longer than the scan period"},
      {"odometry:\n  k_left: 1e-5\n  k_rigth: 1e-5\n", ":3:", "unknown key 'k_rigth'"},
      {"sonars:\n  - name: a\n  - name: b\n    range_min: 9\n", ":3:", "range_min must be below range_max"},
      {"laser:\n  errors:\n    noise_sigma: .inf\n", ":3:", "finite"},
      {"laser:\n  mount: {x: 0.2, y: 0, theta: 5}\n", ":2:", "unknown key 'theta'"},
      {"start_utime: soon\n", ":1:", "start_utime"},
  };
  for (const Case& c : cases) {
    const std::string msg = errorOf(c.text);
    EXPECT_NE(msg.find("robot.yaml"), std::string::npos) << msg;
    EXPECT_NE(msg.find(c.line), std::string::npos) << "expected " << c.line << " in: " << msg;
    EXPECT_NE(msg.find(c.words), std::string::npos) << "expected '" << c.words << "' in: " << msg;
  }
}

TEST(SimConfigValidate, RejectsInconsistentConfigsBuiltInCode) {
  RobotDescription c;
  EXPECT_NO_THROW(validate(c));
  c.laser.time_increment = 0.01;  // 181 beams × 10 ms > 100 ms
  EXPECT_THROW(validate(c), std::invalid_argument);
  c = RobotDescription{};
  c.sonars[1].range_min = 10.0;
  EXPECT_THROW(validate(c), std::invalid_argument);
  c = RobotDescription{};
  c.odometry.k_left = -1.0;
  EXPECT_THROW(validate(c), std::invalid_argument);
  EXPECT_THROW(Simulator(World{}, c, 1), std::invalid_argument);
}

}  // namespace
}  // namespace polarslam
