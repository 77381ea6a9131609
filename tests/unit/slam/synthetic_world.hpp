#pragma once
// A small synthetic world with known truth for EKF tests: a rectangular room (4 walls, 4 concave
// corners with known orientation) and a few point reflectors; a robot driving a circle with
// wheel odometry whose errors follow exactly the model the filter assumes (docs/algorithms.md §17.6); and
// observations drawn from exactly the covariances they report. Whatever is wrong in a filter run
// on this world is the filter's fault.
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "geometry/features.hpp"
#include "odometry/odometry_model.hpp"
#include "odometry/odometry_reading.hpp"
#include "slam/feature_models.hpp"

namespace polarslam::testing {

struct SyntheticWorld {
  std::vector<Vec2> lines;    ///< (α, d), map frame = the robot's start frame
  std::vector<Vec3> corners;  ///< (x, y, γ)
  std::vector<Vec2> points;
  double max_range = 6.0;
};

/// Room x ∈ [−4, 5], y ∈ [−2, 7] in the start frame; the robot's circle (centre (0, 2.5), radius
/// 2.5) stays inside it.
inline SyntheticWorld roomWorld() {
  SyntheticWorld w;
  const double x0 = -4.0, x1 = 5.0, y0 = -2.0, y1 = 7.0;
  // Normals pointing away from the origin (d ≥ 0).
  w.lines = {{std::numbers::pi, -x0}, {0.0, x1}, {-std::numbers::pi / 2, -y0}, {std::numbers::pi / 2, y1}};
  const double q = std::numbers::pi / 4;  // bisectors point into the room
  w.corners = {{x0, y0, q}, {x1, y0, 3 * q}, {x1, y1, -3 * q}, {x0, y1, -q}};
  w.points = {{1.0, -1.9}, {3.5, -1.9}, {-3.9, 1.0}, {4.9, 3.0}, {2.0, 6.9}, {-2.0, 6.9}, {0.5, 2.5}};
  return w;
}

struct SyntheticNoise {
  double line_alpha_sigma = deg2rad(0.5), line_d_sigma = 0.01;
  double corner_xy_sigma = 0.01, corner_gamma_sigma = deg2rad(1.0);
  double point_sigma = 0.01;
  double wheel_k = 2e-5;      ///< m²/m per wheel, as FeatureSlamParams' default
  double wheelbase = 0.5;
};

/// The robot starts at the origin facing +x and drives a left-hand circle of radius `radius` at
/// speed `speed`.
class CircleRun {
 public:
  CircleRun(const SyntheticWorld& world, const SyntheticNoise& noise, uint64_t seed, double radius = 2.5,
               double speed = 0.5)
      : world_(world), noise_(noise), rng_(seed), radius_(radius), speed_(speed) {}

  static constexpr int64_t kStart = 1'000'000'000;
  static constexpr int64_t kOdometryPeriod = 20'000;  ///< 50 Hz

  /// Advances one odometry period; returns the noisy reading. The true pose follows.
  OdometryReading stepOdometry() {
    const double dt = kOdometryPeriod * 1e-6;
    const double ds = speed_ * dt, dtheta = ds / radius_;
    const double ds_right = ds + 0.5 * noise_.wheelbase * dtheta, ds_left = ds - 0.5 * noise_.wheelbase * dtheta;
    truth_ = unicycleStep(truth_, ds, dtheta);
    std::normal_distribution<double> n(0.0, 1.0);
    measured_right_ += ds_right + std::sqrt(noise_.wheel_k * std::abs(ds_right)) * n(rng_);
    measured_left_ += ds_left + std::sqrt(noise_.wheel_k * std::abs(ds_left)) * n(rng_);
    utime_ += kOdometryPeriod;
    OdometryReading r;
    r.utime = utime_;
    r.seq = seq_++;
    r.left_travel = measured_left_;
    r.right_travel = measured_right_;
    const double m_ds = 0.5 * ((measured_right_ - last_right_) + (measured_left_ - last_left_));
    const double m_dtheta = ((measured_right_ - last_right_) - (measured_left_ - last_left_)) / noise_.wheelbase;
    odometry_pose_ = unicycleStep(odometry_pose_, m_ds, m_dtheta);
    last_right_ = measured_right_;
    last_left_ = measured_left_;
    r.pose = odometry_pose_;
    return r;
  }

  /// The first reading, at the start pose, before any motion.
  OdometryReading initialOdometry() const {
    OdometryReading r;
    r.utime = utime_;
    return r;
  }

  /// Every feature within range, observed from the true pose with noise of the stated covariance.
  FeatureSet observe() {
    FeatureSet set;
    set.utime = utime_;
    set.seq = seq_;
    set.frame = "base";
    std::normal_distribution<double> n(0.0, 1.0);
    for (const Vec2& l : world_.lines) {
      const LineObservationModel m = observeLine(truth_, l);
      if (m.z.y() > world_.max_range) continue;
      LineFeature f;
      f.alpha = wrapAngle(m.z.x() + noise_.line_alpha_sigma * n(rng_));
      f.d = m.z.y() + noise_.line_d_sigma * n(rng_);
      f.cov = Vec2(noise_.line_alpha_sigma * noise_.line_alpha_sigma, noise_.line_d_sigma * noise_.line_d_sigma).asDiagonal();
      f.random_cov = f.cov;
      // The observed segment: ±1 m around the foot of the perpendicular.
      const Vec2 foot = f.d * Vec2(std::cos(f.alpha), std::sin(f.alpha)), along(-std::sin(f.alpha), std::cos(f.alpha));
      f.endpoint_a = foot - along;
      f.endpoint_b = foot + along;
      f.num_points = 30;
      set.lines.push_back(f);
    }
    for (const Vec3& c : world_.corners) {
      const Vec2 local = truth_.inverseTransform(c.head<2>());
      if (local.norm() > world_.max_range) continue;
      CornerFeature f;
      f.x = local.x() + noise_.corner_xy_sigma * n(rng_);
      f.y = local.y() + noise_.corner_xy_sigma * n(rng_);
      f.gamma = wrapAngle(c.z() - truth_.theta + noise_.corner_gamma_sigma * n(rng_));
      f.cov = Vec3(noise_.corner_xy_sigma * noise_.corner_xy_sigma, noise_.corner_xy_sigma * noise_.corner_xy_sigma,
                   noise_.corner_gamma_sigma * noise_.corner_gamma_sigma)
                  .asDiagonal();
      f.num_points = 20;
      set.corners.push_back(f);
    }
    for (const Vec2& p : world_.points) {
      const Vec2 local = truth_.inverseTransform(p);
      if (local.norm() > world_.max_range) continue;
      PointFeature f;
      f.source = FeatureSource::Sonar;
      f.x = local.x() + noise_.point_sigma * n(rng_);
      f.y = local.y() + noise_.point_sigma * n(rng_);
      f.cov = Mat2::Identity() * noise_.point_sigma * noise_.point_sigma;
      set.points.push_back(f);
    }
    return set;
  }

  const Pose2& truth() const { return truth_; }
  int64_t utime() const { return utime_; }

 private:
  SyntheticWorld world_;
  SyntheticNoise noise_;
  std::mt19937_64 rng_;
  double radius_, speed_;
  Pose2 truth_;
  Pose2 odometry_pose_;
  double measured_left_ = 0.0, measured_right_ = 0.0, last_left_ = 0.0, last_right_ = 0.0;
  int64_t utime_ = kStart;
  int64_t seq_ = 0;
};

}  // namespace polarslam::testing
