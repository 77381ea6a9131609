#include "scanmatch/scan_matcher.hpp"

#include "scanmatch/match_sums.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace polarslam {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
/// §7: the translation normal matrix is singular below this (dimensionless) determinant.
constexpr double kMinDeterminant = 1e-3;
/// §8: parabolic refinement only when the curvature exceeds 0.01 cm.
constexpr double kMinCurvature = 1e-4;
/// §10: PSM-C fails below this total weight.
constexpr double kMinWeightSum = 1e-2;

/// Weighted (or plain) 2D rigid alignment q ≈ R(θ)p + t of point pairs (Lu & Milios style, §10).
struct Alignment {
  double w = 0.0, px = 0.0, py = 0.0, qx = 0.0, qy = 0.0;
  double pxqx = 0.0, pxqy = 0.0, pyqx = 0.0, pyqy = 0.0;

  void add(double weight, double p_x, double p_y, double q_x, double q_y) {
    w += weight;
    px += weight * p_x; py += weight * p_y;
    qx += weight * q_x; qy += weight * q_y;
    pxqx += weight * p_x * q_x; pxqy += weight * p_x * q_y;
    pyqx += weight * p_y * q_x; pyqy += weight * p_y * q_y;
  }
  /// Rotation and translation; the centred cross sums are formed from the raw ones.
  Pose2 solve() const {
    const double mpx = px / w, mpy = py / w, mqx = qx / w, mqy = qy / w;
    const double sxx = pxqx - w * mpx * mqx, sxy = pxqy - w * mpx * mqy;
    const double syx = pyqx - w * mpy * mqx, syy = pyqy - w * mpy * mqy;
    const double theta = std::atan2(sxy - syx, sxx + syy);
    const double c = std::cos(theta), s = std::sin(theta);
    return {mqx - (c * mpx - s * mpy), mqy - (s * mpx + c * mpy), theta};
  }
};

/// The 2007 ICP option (§12): the closest point to p on the reference segments [j−1, j] and
/// [j, j+1] (within one segment of the scan), or reading j itself.
Vec2 closestOnReference(const PreparedScan& ref, size_t j, const Vec2& p) {
  Vec2 best(ref.x[j], ref.y[j]);
  double best_d2 = (p - best).squaredNorm();
  for (size_t k : {j - 1, j + 1}) {
    if (k >= ref.size() || ref.segment[k] == 0 || ref.segment[k] != ref.segment[j]) continue;
    const Vec2 a(ref.x[j], ref.y[j]), d = Vec2(ref.x[k], ref.y[k]) - a;
    const double t = std::clamp((p - a).dot(d) / d.squaredNorm(), 0.0, 1.0);
    const Vec2 q = a + t * d;
    if ((p - q).squaredNorm() < best_d2) {
      best = q;
      best_d2 = (p - q).squaredNorm();
    }
  }
  return best;
}

/// The information matrix in the eigenbasis of its unit-balanced form: the rotation is put on
/// the scale of the translation by one factor (so a weak translation direction stays visible),
/// and eigen-directions with less than kObservable of the strongest one's information count as
/// unobservable. Along a featureless corridor the only "information" comes from noise in the
/// surface slopes, about 1 % of the across-corridor information with 1 cm range noise.
struct ObservableSpace {
  static constexpr double kObservable = 0.02;
  Vec3 scale, values;
  Mat3 vectors;
  /// Set when bounds on the eigenvalues already show every direction observable (or, for a
  /// translation-only block, both translations): then A⁻¹ is the plain inverse, with no
  /// eigen-decomposition (which costs more than the rest of a Gauss–Newton step).
  bool direct = false;
  Mat3 balanced_inverse;  ///< the balanced form's inverse when `direct`; 0 in an empty rotation row
  bool observable(int k) const { return values(k) > kObservable * values.maxCoeff(); }

  explicit ObservableSpace(const Mat3& information) {
    const double translation = 0.5 * (information(0, 0) + information(1, 1));
    const double rotation = information(2, 2) > 0.0 && translation > 0.0 ? std::sqrt(translation / information(2, 2)) : 1.0;
    scale = Vec3(1.0, 1.0, rotation);
    const Mat3 balanced = scale.asDiagonal() * information * scale.asDiagonal();
    if ((direct = clearlyObservable(balanced))) return;
    Eigen::SelfAdjointEigenSolver<Mat3> eigen;
    eigen.computeDirect(balanced);
    values = eigen.eigenvalues();
    vectors = eigen.eigenvectors();
  }
  /// Gauss–Newton step A⁻¹g along the observable directions only: elsewhere the estimate keeps
  /// its prior instead of sliding along a corridor on noise.
  Vec3 step(const Vec3& gradient) const {
    if (direct) return scale.cwiseProduct(balanced_inverse * scale.cwiseProduct(gradient));
    const Vec3 projected = vectors.transpose() * scale.cwiseProduct(gradient);
    Vec3 s = Vec3::Zero();
    for (int k = 0; k < 3; ++k)
      if (observable(k)) s += vectors.col(k) * (projected(k) / values(k));
    return scale.cwiseProduct(s);
  }
  /// A⁻¹ with the unobservable directions given `free_variance` (in the balanced units).
  Mat3 inverse(double free_variance) const {
    if (direct) {
      Mat3 inverse = balanced_inverse;
      if (inverse(2, 2) == 0.0) inverse(2, 2) = free_variance;  // a translation-only block
      return scale.asDiagonal() * inverse * scale.asDiagonal();
    }
    Vec3 variances;
    for (int k = 0; k < 3; ++k) variances(k) = observable(k) ? 1.0 / values(k) : free_variance;
    return scale.asDiagonal() * vectors * variances.asDiagonal() * vectors.transpose() * scale.asDiagonal();
  }

 private:
  /// For a symmetric matrix with trace t > 0, sum of principal 2×2 minors m > 0 and determinant d,
  /// d > kObservable·t·m means every eigenvalue is positive (the characteristic polynomial's
  /// signs alternate) and λmin ≥ d/m > kObservable·t ≥ kObservable·λmax. The same with 2×2 when
  /// the rotation row is empty: λmin ≥ d/t and λmax ≤ t.
  bool clearlyObservable(const Mat3& a) {
    const bool translation_only = a(2, 2) == 0.0 && a(0, 2) == 0.0 && a(1, 2) == 0.0;
    if (translation_only) {
      const double t = a(0, 0) + a(1, 1), d = a(0, 0) * a(1, 1) - a(0, 1) * a(0, 1);
      if (!(t > 0.0 && d > kObservable * t * t)) return false;
      balanced_inverse.setZero();
      balanced_inverse.topLeftCorner<2, 2>() << a(1, 1) / d, -a(0, 1) / d, -a(0, 1) / d, a(0, 0) / d;
      return true;
    }
    const double t = a.trace();
    const double m = a(0, 0) * a(1, 1) - a(0, 1) * a(1, 0) + a(0, 0) * a(2, 2) - a(0, 2) * a(2, 0) +
                     a(1, 1) * a(2, 2) - a(1, 2) * a(2, 1);
    const double d = a.determinant();
    if (!(t > 0.0 && m > 0.0 && d > kObservable * t * m)) return false;
    balanced_inverse = a.inverse();
    return true;
  }
};

}  // namespace

const char* statusText(MatchStatus status) {
  switch (status) {
    case MatchStatus::Ok: return "ok";
    case MatchStatus::NotEnoughPoints: return "not enough points";
    case MatchStatus::SingularTranslation: return "singular translation";
    case MatchStatus::OrientationSearchFailed: return "orientation search failed";
    case MatchStatus::Diverged: return "diverged";
  }
  return "unknown";
}

const char* methodName(MatchMethod method) {
  switch (method) {
    case MatchMethod::Psm: return "psm";
    case MatchMethod::PsmC: return "psm-c";
    case MatchMethod::Icp: return "icp";
  }
  return "unknown";
}

bool parseMatchMethod(const std::string& name, MatchMethod& method) {
  if (name == "psm") method = MatchMethod::Psm;
  else if (name == "psm-c" || name == "psmc") method = MatchMethod::PsmC;
  else if (name == "icp") method = MatchMethod::Icp;
  else return false;
  return true;
}

const char* covarianceModelName(CovarianceModel model) {
  return model == CovarianceModel::Wls ? "wls" : "heuristic";
}

bool parseCovarianceModel(const std::string& name, CovarianceModel& model) {
  if (name == "wls") model = CovarianceModel::Wls;
  else if (name == "heuristic") model = CovarianceModel::Heuristic;
  else return false;
  return true;
}

// ---------------------------------------------------------------------------------------------
// PSM (§7–§9)

ScanMatcher::ScanMatcher(PsmParams params) : params_(std::move(params)) {}

MatchResult ScanMatcher::match(const PreparedScan& ref, const PreparedScan& cur, const Pose2& guess,
                               MatchMethod method) {
  switch (method) {
    case MatchMethod::PsmC: return matchPsmC(ref, cur, guess);
    case MatchMethod::Icp: return matchIcp(ref, cur, guess);
    case MatchMethod::Psm: break;
  }
  return matchPsm(ref, cur, guess);
}

double ScanMatcher::stepMinPoints() const { return params_.step_min_points_fraction * params_.min_valid_points; }

bool ScanMatcher::usableSample(const PreparedScan& ref, size_t j) const {
  const float r = projection_.range[j];
  return !ref.bad(j) && projection_.tag[j] == 0 && r > params_.min_range && r < params_.max_range;
}

double ScanMatcher::weightingFactor(int iteration, const PreparedScan& ref) const {
  if (iteration >= params_.change_weight_iteration) return params_.late_weighting_factor;
  if (params_.adaptive_weighting_scale <= 0.0) return params_.weighting_factor;
  const double scale = params_.adaptive_weighting_scale * projectedErrorIndex(ref);
  return std::clamp(scale * scale, params_.late_weighting_factor, params_.weighting_factor);
}

/// The error index (v0.3 pm_error_index2) of the current projection: mean |Δr| within max_error/2.
double ScanMatcher::projectedErrorIndex(const PreparedScan& ref) const {
  const float gate = static_cast<float>(0.5 * params_.max_error);
  double sum = 0.0;
  int count = 0;
  for (size_t j = 0; j < ref.size(); ++j) {
    if (!usableSample(ref, j)) continue;
    const float e = std::abs(ref.range[j] - projection_.range[j]);
    if (e < gate) {
      sum += e;
      ++count;
    }
  }
  return count > 0 ? sum / count : params_.max_error;
}

ScanMatcher::TranslationStep ScanMatcher::solveTranslation(const PreparedScan& ref, const Pose2& pose, double c) {
  TranslationStep step;
  double h11 = 0.0, h12 = 0.0, h22 = 0.0, b1 = 0.0, b2 = 0.0;
  if (params_.surface_jacobian) {
    // The translation block of the joint system: normal-distance residuals, so that walls seen
    // at grazing angles neither dominate nor slow convergence down.
    const JointSystem system = jointSystem(ref, pose, c, JointTerms::Translation);
    step.used = system.used;
    if (step.used < stepMinPoints()) {
      step.status = MatchStatus::NotEnoughPoints;
      return step;
    }
    // Only along the directions the scans constrain (a corridor leaves one free).
    Mat3 block = Mat3::Zero();
    block.topLeftCorner<2, 2>() = system.information.topLeftCorner<2, 2>();
    const Vec3 delta = ObservableSpace(block).step(Vec3(system.gradient(0), system.gradient(1), 0.0));
    step.dx = delta(0);
    step.dy = delta(1);
    return step;
  } else {
    const BeamGeometry& g = *ref.geometry;
    for (size_t j = 0; j < ref.size(); ++j) {
      if (!usableSample(ref, j)) continue;
      const double dr = static_cast<double>(ref.range[j]) - projection_.range[j];
      if (std::abs(dr) >= params_.max_error) continue;
      // H_j = [cos φ_j, sin φ_j] at the reference bearing; Dudek & Jenkin weights.
      const double w = c / (c + dr * dr);
      const double co = g.cos_table[j], si = g.sin_table[j];
      h11 += w * co * co;
      h12 += w * co * si;
      h22 += w * si * si;
      b1 += w * co * dr;
      b2 += w * si * dr;
      ++step.used;
    }
  }
  if (step.used < stepMinPoints()) {
    step.status = MatchStatus::NotEnoughPoints;
    return step;
  }
  const double det = h11 * h22 - h12 * h12;  // the full symmetric determinant (v0.3 dropped h12², §14.2)
  if (det < kMinDeterminant) {
    step.status = MatchStatus::SingularTranslation;
    return step;
  }
  step.dx = (h22 * b1 - h12 * b2) / det;
  step.dy = (h11 * b2 - h12 * b1) / det;
  return step;
}

namespace {

/// e(k) of §8 over arrays where the masks are 1 for usable samples and the values 0 elsewhere:
/// the mean of min(|p_i − r_{i+k}|, truncation) over pairs usable in both, and their count.
/// Differences are truncated at the outlier gate so that unmatched surfaces (occlusions, what
/// only one scan sees) cost a constant instead of pulling the minimum (v0.3 gates them for its
/// Hokuyo UTM preset only).
double shiftCost(const float* p, const float* pm, const float* r, const float* rm, int n, int shift,
                 float truncation, VectorKernels kernels, int& overlap) {
  const int first = std::max(0, -shift);
  const int count = std::min(n, n - shift) - first;
  overlap = 0;
  if (count <= 0) return kInf;
  const ShiftCostInputs inputs{p + first, pm + first, r + first + shift, rm + first + shift,
                               static_cast<size_t>(count), truncation};
  const ShiftCostSums sums = sumShiftCost(inputs, kernels);
  overlap = static_cast<int>(sums.pairs + 0.5f);
  return overlap > 0 ? static_cast<double>(sums.sum) / sums.pairs : kInf;
}

void decimate(const std::vector<float>& in, int stride, std::vector<float>& out) {
  const auto step = static_cast<size_t>(stride);
  out.resize((in.size() + step - 1) / step);
  for (size_t k = 0; k < out.size(); ++k) out[k] = in[k * step];
}

}  // namespace

ScanMatcher::OrientationStep ScanMatcher::searchOrientation(const PreparedScan& ref, double window, double c) {
  const size_t n = ref.size();
  const double increment = ref.geometry->angle_increment;
  proj_masked_.resize(n);
  proj_mask_.resize(n);
  maskSamples({projection_.range.data(), projection_.tag.data(), n, params_.min_range, params_.max_range},
              proj_masked_.data(), proj_mask_.data(), kernels_);
  const int w = std::clamp(static_cast<int>(std::lround(window / increment)), 1, static_cast<int>(n) - 1);
  shift_cost_.assign(static_cast<size_t>(2 * w + 1), std::numeric_limits<double>::quiet_NaN());
  const auto truncation = static_cast<float>(params_.max_error);
  const auto size = static_cast<int>(n);
  // e(k), the mean |r''_i − r_ref,i+k| (§8); too little overlap makes a shift invalid (+inf).
  auto cost = [&](int k) {
    double& e = shift_cost_[static_cast<size_t>(k + w)];
    if (std::isnan(e)) {
      int overlap = 0;
      e = shiftCost(proj_masked_.data(), proj_mask_.data(), ref.masked_range.data(), ref.mask.data(), size, k,
                    truncation, kernels_, overlap);
      if (overlap < stepMinPoints()) e = kInf;
    }
    return e;
  };
  int lo = -w, hi = w;
  const int stride = params_.coarse_search_step > 0.0
                         ? static_cast<int>(std::lround(params_.coarse_search_step / increment)) : 1;
  if (stride >= 2 && w > 2 * stride) {
    // Coarse pass: every stride-th shift on every stride-th bearing, then a full-resolution
    // search around the best coarse shift: s² fewer operations over the wide part of the window.
    decimate(proj_masked_, stride, coarse_[0]);
    decimate(proj_mask_, stride, coarse_[1]);
    decimate(ref.masked_range, stride, coarse_[2]);
    decimate(ref.mask, stride, coarse_[3]);
    const auto coarse_size = static_cast<int>(coarse_[0].size());
    double best = kInf;
    int best_k = 0;
    for (int m = -(w / stride); m <= w / stride; ++m) {
      int overlap = 0;
      const double e = shiftCost(coarse_[0].data(), coarse_[1].data(), coarse_[2].data(), coarse_[3].data(),
                                 coarse_size, m, truncation, kernels_, overlap);
      if (overlap * stride >= stepMinPoints() && e < best) {
        best = e;
        best_k = m * stride;
      }
    }
    if (!std::isfinite(best)) return {MatchStatus::OrientationSearchFailed, 0.0};
    lo = std::max(-w, best_k - stride);
    hi = std::min(w, best_k + stride);
  }
  double best = kInf;
  int best_k = 0;
  for (int k = lo; k <= hi; ++k) {
    const double e = cost(k);
    if (e < best) {
      best = e;
      best_k = k;
    }
  }
  if (!std::isfinite(best)) return {MatchStatus::OrientationSearchFailed, 0.0};
  double dtheta = best_k * increment;
  if (params_.orientation_refinement == OrientationRefinement::Gradient) {
    dtheta += gradientRefinement(ref, best_k, c) * increment;
  } else if (best_k > -w && best_k < w) {  // parabolic interpolation of the minimum
    const double em = cost(best_k - 1), ep = cost(best_k + 1);
    const double curvature = em + ep - 2.0 * best;
    if (std::isfinite(curvature) && std::abs(curvature) > kMinCurvature && em > best && ep > best) {
      const double d = (em - ep) / (2.0 * curvature);
      if (std::abs(d) < 1.0) dtheta += d * increment;
    }
  }
  return {MatchStatus::Ok, dtheta};
}

double ScanMatcher::gradientRefinement(const PreparedScan& ref, int shift, double c) const {
  // Least squares for δ in P_i ≈ R(i + k + δ) ≈ R_{i+k} + δ·R'_{i+k}, robustly weighted.
  const auto n = static_cast<int>(ref.size());
  const int first = std::max(0, -shift), end = std::min(n, n - shift);
  if (end <= first) return 0.0;
  const auto i = static_cast<size_t>(first), j = static_cast<size_t>(first + shift);
  const SlopeFitInputs inputs{proj_masked_.data() + i, proj_mask_.data() + i, ref.range.data() + j,
                              ref.mask.data() + j, ref.slope.data() + j, static_cast<size_t>(end - first),
                              params_.max_error};
  const SlopeFitSums sums = sumSlopeFit(inputs, c, kernels_);
  if (!(sums.den > 0.0)) return 0.0;
  // Beyond one beam the linearisation is poor, but the direction is right: the next
  // orientation step continues from there.
  return std::clamp(sums.num / sums.den, -1.0, 1.0);
}

namespace {

/// The stop rule of §9: stop_count consecutive iterations whose latest translation and rotation
/// corrections are both small.
class StopRule {
 public:
  StopRule(double translation, double rotation, int needed)
      : translation_(translation), rotation_(rotation), needed_(needed) {}
  void translated(double dx, double dy) { last_translation_ = std::abs(dx) + std::abs(dy); }
  void rotated(double dtheta) { last_rotation_ = std::abs(dtheta); }
  void moved(const Pose2& delta) {
    translated(delta.x, delta.y);
    rotated(delta.theta);
  }
  /// Call once per iteration after its step.
  bool done() {
    small_ = last_translation_ < translation_ && last_rotation_ < rotation_ ? small_ + 1 : 0;
    return small_ >= needed_;
  }

 private:
  double translation_, rotation_;
  int needed_;
  double last_translation_ = kInf, last_rotation_ = kInf;
  int small_ = 0;
};

bool plausible(const Pose2& pose, double max_range) {
  return finitePose(pose) && std::abs(pose.x) < 2.0 * max_range && std::abs(pose.y) < 2.0 * max_range;
}

/// The end of every iteration: true when the match failed, left any plausible region
/// (status Diverged), or has converged (§9).
bool iterationEnds(MatchResult& result, StopRule& stop, double max_range) {
  if (!result.ok()) return true;
  if (!plausible(result.pose, max_range)) {
    result.status = MatchStatus::Diverged;
    return true;
  }
  if (result.converged || stop.done()) {
    result.converged = true;
    return true;
  }
  return false;
}

}  // namespace

MatchResult ScanMatcher::startResult(const PreparedScan& ref, const PreparedScan& cur, const Pose2& guess) const {
  MatchResult result;
  result.pose = guess;
  if (ref.valid_count < params_.min_valid_points || cur.valid_count < params_.min_valid_points)
    result.status = MatchStatus::NotEnoughPoints;
  return result;
}

MatchResult ScanMatcher::matchPsm(const PreparedScan& ref, const PreparedScan& cur, const Pose2& guess) {
  MatchResult result = startResult(ref, cur, guess);
  if (!result.ok()) return result;
  StopRule stop(params_.stop_translation, params_.stop_rotation, params_.stop_count);
  bool first_orientation = true, joint = false, translated = false, rotated = false;
  double last_translation = kInf, last_rotation = kInf;
  JointSystem system;
  int iteration = 0;
  while (iteration < params_.max_iterations) {
    const bool orientation_step = (params_.order == IterationOrder::OrientationFirst) == (iteration % 2 == 0);
    projectScan(*ref.geometry, cur, result.pose, projection_, kernels_);
    if (joint) {
      system = jointSystem(ref, result.pose, params_.late_weighting_factor);
      result.valid_points = system.used;
      if (system.used < params_.min_valid_points) {
        result.status = MatchStatus::NotEnoughPoints;
      } else {
        const Vec3 delta = ObservableSpace(system.information).step(system.gradient);
        result.pose = {result.pose.x + delta(0), result.pose.y + delta(1), wrapAngle(result.pose.theta + delta(2))};
        stop.translated(delta(0), delta(1));
        stop.rotated(delta(2));
        if (std::abs(delta(0)) + std::abs(delta(1)) < params_.stop_translation &&
            std::abs(delta(2)) < params_.stop_rotation)
          result.converged = true;
      }
    } else if (orientation_step) {
      const double window = first_orientation ? std::max(params_.initial_search_window, params_.search_window)
                                              : params_.search_window;
      first_orientation = false;
      const OrientationStep step = searchOrientation(ref, window, weightingFactor(iteration, ref));
      result.status = step.status;
      result.pose.theta = wrapAngle(result.pose.theta + step.dtheta);
      stop.rotated(step.dtheta);
      last_rotation = std::abs(step.dtheta);
      rotated = true;
    } else {
      const TranslationStep step = solveTranslation(ref, result.pose, weightingFactor(iteration, ref));
      result.status = step.status;
      result.valid_points = step.used;
      result.pose.x += step.dx;
      result.pose.y += step.dy;
      stop.translated(step.dx, step.dy);
      last_translation = std::abs(step.dx) + std::abs(step.dy);
      translated = true;
    }
    ++iteration;
    if (iterationEnds(result, stop, params_.max_range)) break;
    joint = joint || (params_.joint_refinement && translated && rotated &&
                      last_translation < params_.joint_switch_translation &&
                      last_rotation < params_.joint_switch_rotation);
  }
  result.iterations = iteration;
  if (!result.ok()) return result;
  // The last joint system was set up one (tiny) step before the end; otherwise the final pose
  // gets its own.
  if (!(joint && result.converged)) {
    projectScan(*ref.geometry, cur, result.pose, projection_, kernels_);
    system = jointSystem(ref, result.pose, params_.late_weighting_factor);
    result.valid_points = system.used;
    // The alternating steps may have had fewer (stepMinPoints); the answer may not. (A joint
    // step needs them all.)
    if (params_.step_min_points_fraction < 1.0 && system.used < params_.min_valid_points) {
      result.status = MatchStatus::NotEnoughPoints;
      return result;
    }
  }
  fillCovariance(ref, system, result);
  return result;
}

ScanMatcher::CartesianStep ScanMatcher::solveCartesian(const PreparedScan& ref, double c) {
  const BeamGeometry& g = *ref.geometry;
  Alignment alignment;
  CartesianStep step;
  for (size_t j = 0; j < ref.size(); ++j) {
    if (!usableSample(ref, j)) continue;
    const double rr = ref.range[j], pr = projection_.range[j];
    const double dr = rr - pr;
    if (std::abs(dr) >= params_.max_error) continue;
    const double co = g.cos_table[j], si = g.sin_table[j];
    alignment.add(c / (c + dr * dr), pr * co, pr * si, rr * co, rr * si);
    ++step.used;
  }
  if (step.used < params_.min_valid_points) step.status = MatchStatus::NotEnoughPoints;
  else if (alignment.w < kMinWeightSum) step.status = MatchStatus::SingularTranslation;
  else step.delta = alignment.solve();
  return step;
}

MatchResult ScanMatcher::matchPsmC(const PreparedScan& ref, const PreparedScan& cur, const Pose2& guess) {
  MatchResult result = startResult(ref, cur, guess);
  if (!result.ok()) return result;
  StopRule stop(params_.stop_translation, params_.stop_rotation, params_.stop_count);
  const int period = std::max(2, params_.psmc_orientation_period);
  // v0.1 searches orientation at iteration ≡ 3 (mod 4); with orientation first it is ≡ 0.
  const int orientation_phase = params_.order == IterationOrder::OrientationFirst ? 0 : period - 1;
  bool first_orientation = true;
  int iteration = 0;
  while (iteration < params_.max_iterations) {
    projectScan(*ref.geometry, cur, result.pose, projection_, kernels_);
    if (iteration % period == orientation_phase) {
      const double window = first_orientation ? std::max(params_.initial_search_window, params_.search_window)
                                              : params_.search_window;
      first_orientation = false;
      const OrientationStep step = searchOrientation(ref, window, weightingFactor(iteration, ref));
      result.status = step.status;
      result.pose.theta = wrapAngle(result.pose.theta + step.dtheta);
      stop.rotated(step.dtheta);
    } else {
      const CartesianStep step = solveCartesian(ref, weightingFactor(iteration, ref));
      result.status = step.status;
      result.valid_points = step.used;
      // The correction is a motion in the reference frame: compose, do not add (§10, §14.6).
      result.pose = step.delta * result.pose;
      stop.moved(step.delta);
    }
    ++iteration;
    if (iterationEnds(result, stop, params_.max_range)) break;
  }
  result.iterations = iteration;
  if (result.ok()) estimateCovariance(ref, cur, result);
  return result;
}

// ---------------------------------------------------------------------------------------------
// ICP baseline (§12)

MatchResult ScanMatcher::matchIcp(const PreparedScan& ref, const PreparedScan& cur, const Pose2& guess) {
  MatchResult result = startResult(ref, cur, guess);
  if (!result.ok()) return result;
  const BeamGeometry& g = *ref.geometry;
  const auto n = static_cast<long>(ref.size());
  const long window = std::max(1L, std::lround(params_.search_window / g.angle_increment));
  const double max_error2 = params_.max_error * params_.max_error;
  StopRule stop(params_.icp_stop_translation, params_.icp_stop_rotation, params_.stop_count);
  int iteration = 0;
  while (iteration < params_.icp_max_iterations) {
    // PSM's projection filters current readings hidden from, or outside the view of, the
    // reference laser; then each survivor is paired with its closest reference point within
    // ±window bearings.
    projectScan(g, cur, result.pose, projection_, kernels_);
    icp_cur_.clear();
    icp_ref_.clear();
    icp_dist_.clear();
    for (size_t i = 0; i < cur.size(); ++i) {
      if (cur.bad(i)) continue;
      const long centre = std::lround(projection_.index[i]);
      if (centre < 0 || centre >= n || projection_.tag[static_cast<size_t>(centre)] != 0) continue;
      const double px = projection_.px[i], py = projection_.py[i];
      if (std::hypot(px, py) > projection_.range[static_cast<size_t>(centre)] + params_.segment_max_distance) continue;
      double best = max_error2;
      long best_j = -1;
      for (long j = std::max(0L, centre - window); j <= std::min(n - 1, centre + window); ++j) {
        if (ref.bad(static_cast<size_t>(j))) continue;
        const double ex = px - ref.x[static_cast<size_t>(j)], ey = py - ref.y[static_cast<size_t>(j)];
        const double d2 = ex * ex + ey * ey;
        if (d2 < best) {
          best = d2;
          best_j = j;
        }
      }
      if (best_j < 0) continue;
      icp_cur_.push_back(static_cast<int>(i));
      icp_ref_.push_back(static_cast<int>(best_j));
      icp_dist_.push_back(best);
    }
    const auto pairs = static_cast<int>(icp_cur_.size());
    if (pairs < params_.min_valid_points) {
      result.status = MatchStatus::NotEnoughPoints;
      ++iteration;
      break;
    }
    // Keep the best (1 − trim) of the pairs.
    const int keep = pairs - static_cast<int>(params_.icp_trim_fraction * pairs);
    icp_sorted_ = icp_dist_;
    std::nth_element(icp_sorted_.begin(), icp_sorted_.begin() + (keep - 1), icp_sorted_.end());
    const double threshold = icp_sorted_[static_cast<size_t>(keep - 1)];
    Alignment alignment;
    int used = 0;
    for (int k = 0; k < pairs && used < keep; ++k) {
      if (icp_dist_[static_cast<size_t>(k)] > threshold) continue;
      const auto i = static_cast<size_t>(icp_cur_[static_cast<size_t>(k)]);
      const auto j = static_cast<size_t>(icp_ref_[static_cast<size_t>(k)]);
      const Vec2 p(projection_.px[i], projection_.py[i]);
      const Vec2 q = params_.icp_interpolate ? closestOnReference(ref, j, p) : Vec2(ref.x[j], ref.y[j]);
      alignment.add(1.0, p.x(), p.y(), q.x(), q.y());
      ++used;
    }
    result.valid_points = used;
    // The rigid motion in the reference frame, composed onto the current pose.
    const Pose2 delta = alignment.solve();
    const Pose2 before = result.pose;
    result.pose = delta * result.pose;
    stop.translated(result.pose.x - before.x, result.pose.y - before.y);
    stop.rotated(delta.theta);
    ++iteration;
    if (iterationEnds(result, stop, params_.max_range)) break;
  }
  result.iterations = iteration;
  if (result.ok()) estimateCovariance(ref, cur, result);
  return result;
}

// ---------------------------------------------------------------------------------------------
// Covariance (§11)

void ScanMatcher::estimateCovariance(const PreparedScan& ref, const PreparedScan& cur, MatchResult& result) {
  projectScan(*ref.geometry, cur, result.pose, projection_, kernels_);
  fillCovariance(ref, jointSystem(ref, result.pose, params_.late_weighting_factor), result);
}

void ScanMatcher::fillCovariance(const PreparedScan& ref, const JointSystem& system, MatchResult& result) const {
  result.error_index = system.error_index;
  if (params_.covariance != CovarianceModel::Wls) {
    result.cov = heuristicCovariance(ref, system.error_index);
    return;
  }
  result.cov = covarianceFrom(system, params_.slope_noise_correction ? slopeNoise(ref, system) : Mat3::Zero());
}

Mat3 ScanMatcher::heuristicCovariance(const PreparedScan& ref, double error_index) const {
  const HeuristicCovarianceParams& h = params_.heuristic;
  // The scale is computed in centimetres, as in the original (§11.2, §14.8).
  const double scale = std::max(1.0, 100.0 * error_index - h.error_offset_cm);
  Mat3 cov = Mat3::Zero();
  const CorridorInfo corridor = detectCorridor(ref, params_.corridor_threshold);
  if (corridor.is_corridor) {
    const double a = corridor.angle, ca = std::cos(a), sa = std::sin(a);
    const double along = h.sigma_along * h.sigma_along, across = h.sigma_across * h.sigma_across;
    cov(0, 0) = scale * (ca * ca * along + sa * sa * across);
    cov(0, 1) = cov(1, 0) = scale * ca * sa * (along - across);
    cov(1, 1) = scale * (sa * sa * along + ca * ca * across);
  } else {
    cov(0, 0) = cov(1, 1) = scale * h.sigma_xy * h.sigma_xy;
  }
  cov(2, 2) = scale * h.sigma_theta * h.sigma_theta;
  return cov;
}

JointSums ScanMatcher::jointSums(const PreparedScan& ref, const Pose2& pose, double c, JointTerms terms) const {
  const PreparedScan::SurfaceTerms& surface = ref.surface;
  const JointInputs inputs{projection_.range.data(), ref.range.data(),         projection_.tag.data(),
                           ref.flags.data(),         surface.rho.data(),       surface.cos_beta.data(),
                           surface.normal_x.data(),  surface.normal_y.data(),  surface.rho_cos_beta.data(),
                           surface.beta_variance.data(), ref.size()};
  const JointLimits limits{params_.min_range, params_.max_range, params_.max_error, params_.max_slope};
  return sumJointSystem(inputs, pose, c, limits, kernels_, terms);
}

ScanMatcher::JointSystem ScanMatcher::jointSystem(const PreparedScan& ref, const Pose2& pose, double c,
                                                  JointTerms terms) const {
  const JointSums sums = jointSums(ref, pose, c, terms);
  JointSystem system;
  system.information << sums.a11, sums.a12, sums.a13, sums.a12, sums.a22, sums.a23, sums.a13, sums.a23, sums.a33;
  system.gradient << sums.g1, sums.g2, sums.g3;
  system.sum_w = sums.sum_w;
  system.sum_we2 = sums.sum_we2;
  system.used = sums.used;
  system.error_index = sums.in_index > 0 ? sums.sum_abs_error / sums.in_index : params_.max_error;
  system.pose = pose;
  system.c = c;
  return system;
}

Mat3 ScanMatcher::slopeNoise(const PreparedScan& ref, const JointSystem& system) const {
  const JointSums s = jointSums(ref, system.pose, system.c, JointTerms::SlopeNoise);
  Mat3 spurious;
  spurious << s.s11, s.s12, s.s13, s.s12, -s.s11, s.s23, s.s13, s.s23, s.s33;
  return spurious;
}

Mat3 ScanMatcher::covarianceFrom(const JointSystem& system, const Mat3& slope_noise) const {
  if (system.used < 4 || system.sum_w <= 3.0) {  // nothing to estimate from: no better than a wild guess
    Mat3 cov = Mat3::Zero();
    const double r2 = params_.max_range * params_.max_range;
    cov.diagonal() << r2, r2, std::numbers::pi * std::numbers::pi;
    return cov;
  }
  // Residuals can be (nearly) zero on ideal data; no real laser matches better than its noise.
  const double sigma2 = std::max(system.sum_we2 / (system.sum_w - 3.0), params_.wls_min_sigma * params_.wls_min_sigma);
  // Directions the scans do not constrain (along a corridor) get the variance of a wild guess
  // across the sensor's range instead of what slope noise would suggest.
  const double free_variance = params_.max_range * params_.max_range / (params_.wls_inflation * sigma2);
  // A residual is a reference reading less an interpolation between two current ones, so
  // σ̂² ≈ 1.5·σ_r²; the slopes' noise is that of the reference's ranges.
  const Mat3 information = system.information - (sigma2 / 1.5) * slope_noise;
  Mat3 cov = params_.wls_inflation * sigma2 * ObservableSpace(information).inverse(free_variance);
  cov(0, 0) += params_.wls_floor_xy * params_.wls_floor_xy;
  cov(1, 1) += params_.wls_floor_xy * params_.wls_floor_xy;
  cov(2, 2) += params_.wls_floor_theta * params_.wls_floor_theta;
  return 0.5 * (cov + cov.transpose());
}

// ---------------------------------------------------------------------------------------------
// Frames (§5)

Pose2 laserPoseInReferenceLaser(const Pose2& robot_ref, const Pose2& robot_cur, const Pose2& mount_ref,
                                const Pose2& mount_cur) {
  return between(robot_ref * mount_ref, robot_cur * mount_cur);
}

Pose2 robotMotionFromLaserMotion(const Pose2& laser_motion, const Pose2& mount_ref, const Pose2& mount_cur) {
  return mount_ref * laser_motion * mount_cur.inverse();
}

Mat3 robotMotionCovariance(const Pose2& laser_motion, const Mat3& laser_cov, const Pose2& mount_ref,
                           const Pose2& mount_cur) {
  const Pose2 left = mount_ref * laser_motion;
  const Mat3 J = composeJacobianA(left, mount_cur.inverse()) * composeJacobianB(mount_ref);
  return J * laser_cov * J.transpose();
}

}  // namespace polarslam
