#pragma once
// The simulated robot and its sensors: every term a knob. Defaults here equal those in
// config/robots/default.yaml (format documented in config/worlds/README.md).
#include <cstdint>
#include <numbers>
#include <string>
#include <vector>

#include "geometry/pose2.hpp"
#include "laser/laser_error_model.hpp"
#include "laser/range_error_model.hpp"

namespace polarslam {

struct PathFollowerConfig {
  double lookahead = 0.6;             ///< m: pure-pursuit look-ahead distance along the path
  double max_lateral_accel = 0.3;     ///< m/s²: speed is limited to sqrt(a/|κ|) on curves
  double turn_in_place_angle = deg2rad(60.0);  ///< rad: larger heading errors turn on the spot
  double heading_gain = 2.0;          ///< 1/s: ω = gain · heading error when turning on the spot
  double goal_tolerance = 0.05;       ///< m: the final waypoint counts as reached within this
};

struct DriveConfig {
  double wheel_base = 0.5;            ///< m, true distance between the wheels' contact points
  double wheel_radius = 0.1;          ///< m, nominal (what odometry assumes)
  double max_speed = 0.5;             ///< m/s
  double max_turn_rate = deg2rad(60.0);        ///< rad/s
  double max_accel = 0.5;             ///< m/s²
  double max_angular_accel = deg2rad(180.0);   ///< rad/s²
  double control_period = 0.01;       ///< s: the controller updates the wheel speeds this often
  PathFollowerConfig follower;
};

/// Per-wheel random error with variance growing with distance (docs/algorithms.md §17.6) and optional
/// systematic errors, which the odometry does not know about (its covariance ignores them).
struct OdometryConfig {
  double rate = 50.0;                 ///< Hz
  double k_left = 2e-5;               ///< m²/m: σ_L² = k_L·|Δs_L|
  double k_right = 2e-5;              ///< m²/m: σ_R² = k_R·|Δs_R|
  double left_radius_error = 0.0;     ///< relative: true left radius = nominal·(1 + e)
  double right_radius_error = 0.0;    ///< relative: true right radius = nominal·(1 + e)
  double wheel_base_error = 0.0;      ///< relative: odometry uses wheel_base·(1 + e)
};

struct LaserConfig {
  bool enabled = true;
  int beams = 181;
  double fov = std::numbers::pi;       ///< rad, from the first beam to the last
  double angle_min = -0.5 * std::numbers::pi;  ///< rad, bearing of beam 0 in the laser frame
  double rate = 10.0;                  ///< Hz
  double range_max = 8.1;              ///< m; readings at or beyond it are "no return" (+inf)
  double time_increment = 1.0 / (75.0 * 360.0);  ///< s between beams (SICK mirror at 75 Hz, 1°)
  Pose2 mount{0.2, 0.0, 0.0};          ///< laser pose in the robot base frame
  RangeErrorParams errors{.fixed_bias = 0.005, .scan_bias_sigma = 0.003, .growth = 0.002,
                          .incidence = 0.003, .quantum = 0.01, .noise_sigma = 0.01,
                          .max_incidence = deg2rad(80.0)};  ///< terms of (2.8)
  bool compensate_quantizer_offset = true;  ///< add q/2 after the quantiser (the manufacturer's fix)
  double output_noise_sigma = 0.0;     ///< m: extra white noise r_n added after the quantiser
  double tilt = 0.0;                   ///< rad: scan-plane tilt ε about an in-plane axis
  double tilt_axis = 0.0;              ///< rad: bearing ψ of that axis; beam elevation ε·sin(φ − ψ)

  double angleIncrement() const { return beams > 1 ? fov / (beams - 1) : fov; }
  double scanDuration() const { return (beams - 1) * time_increment; }
};

struct SonarConfig {
  std::string name = "front";
  int id = 0;
  Pose2 mount{0.25, 0.0, 0.0};         ///< array pose in the robot base frame
  double fov = deg2rad(60.0);          ///< rad, full width of the field of view
  double rate = 10.0;                  ///< Hz
  double range_min = 0.1;              ///< m
  double range_max = 8.0;              ///< m
  double range_sigma = 0.001;          ///< m
  double bearing_sigma = deg2rad(0.1); ///< rad
  double misclassification_rate = 0.02;  ///< probability a target gets another (random) class
  double spurious_rate = 0.05;         ///< mean number of spurious targets per scan (Poisson)
  double miss_rate = 0.0;              ///< probability a visible target is not reported
  double right_angle_tolerance = deg2rad(10.0);  ///< rad: concave vertices this close to 90° are corners
};

struct RobotDescription {
  std::string source;                  ///< file it was loaded from, if any
  int64_t start_utime = 1700000000000000;  ///< µs timestamp of simulated time 0
  double ground_truth_rate = 50.0;     ///< Hz
  DriveConfig robot;
  OdometryConfig odometry;
  LaserConfig laser;
  std::vector<SonarConfig> sonars = defaultSonars();

  static std::vector<SonarConfig> defaultSonars();
};

/// Loads a robot + sensor file; keys left out keep the defaults above. Throws
/// std::runtime_error naming the file, line and key on anything malformed or absurd.
RobotDescription loadRobotDescription(const std::string& yaml_path);

/// Checks the cross-field consistency of a config built in code (the loader checks each value).
/// Throws std::invalid_argument naming the first bad key.
void validate(const RobotDescription& config);

/// The laser's error model (2.8) as a feature extractor should assume it, exactly as the simulator
/// applies it: an uncompensated quantiser's −q_r/2 becomes part of the fixed bias.
LaserErrorParams laserErrorParams(const LaserConfig& laser);

}  // namespace polarslam
