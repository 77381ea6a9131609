#include "grid/pose_regeneration.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "grid/anchor_model.hpp"

namespace polarslam {
namespace {

struct AnchorTerm {
  const AnchorObservation* observation = nullptr;
  const MapFeature* feature = nullptr;
};

/// One Gauss–Newton linearisation: information Σ HᵀWH, Σ HᵀWr and per-anchor NIS.
struct NormalEquations {
  Mat3 information = Mat3::Zero();
  Vec3 gradient = Vec3::Zero();
  double chi2 = 0.0;
  std::vector<double> nis;  ///< per term; -1 when the term could not be evaluated
  int used = 0;
};

double chi2Quantile999(int dims) { return dims == 3 ? 16.266 : 13.816; }

Mat3 topLeftOnly(const Mat3& m, int dims) {
  Mat3 out = Mat3::Zero();
  out.topLeftCorner(dims, dims) = m.topLeftCorner(dims, dims);
  return out;
}

/// Inverse of the top-left dims×dims block, padded with zeros. False if not positive definite.
bool invertBlock(const Mat3& S, int dims, Mat3& W) {
  Mat3 padded = Mat3::Identity();
  padded.topLeftCorner(dims, dims) = S.topLeftCorner(dims, dims);
  if (!padded.allFinite()) return false;
  const Eigen::LLT<Mat3> llt(padded);
  if (llt.info() != Eigen::Success) return false;
  W = topLeftOnly(llt.solve(Mat3::Identity()), dims);
  return W.allFinite();
}

NormalEquations linearize(const Pose2& pose, const std::vector<AnchorTerm>& terms, const RegenerationOptions& o) {
  NormalEquations eq;
  eq.nis.assign(terms.size(), -1.0);
  for (size_t i = 0; i < terms.size(); ++i) {
    const AnchorTerm& term = terms[i];
    const AnchorPrediction p = predictAnchor(pose, *term.feature, o.min_line_distance);
    if (!p.valid) continue;
    Mat3 S = topLeftOnly(term.observation->cov, p.dims);
    if (o.include_map_covariance) {
      const Mat3 P = topLeftOnly(term.feature->cov, parameterCount(term.feature->kind));
      S += p.H_y * P * p.H_y.transpose();
    }
    Mat3 W;
    if (!invertBlock(S, p.dims, W)) continue;
    const Vec3 r = anchorResidual(term.feature->kind, term.observation->z, p.z);
    const double nis = r.dot(W * r);
    eq.information += p.H_x.transpose() * W * p.H_x;
    eq.gradient += p.H_x.transpose() * W * r;
    eq.chi2 += nis;
    eq.nis[i] = nis;
    ++eq.used;
  }
  return eq;
}

/// Every direction of the pose must be known to within the configured sigmas.
bool fullyConstrained(const Mat3& information, const RegenerationOptions& o) {
  const Vec3 scale(o.max_position_sigma, o.max_position_sigma, o.max_heading_sigma);
  const Mat3 normalized = scale.asDiagonal() * information * scale.asDiagonal();
  if (!normalized.allFinite()) return false;
  const Eigen::SelfAdjointEigenSolver<Mat3> eigen(normalized, Eigen::EigenvaluesOnly);
  return eigen.info() == Eigen::Success && eigen.eigenvalues().minCoeff() >= 1.0;
}

struct FitResult {
  bool ok = false;
  Pose2 pose;
  NormalEquations equations;
  int iterations = 0;
};

FitResult gaussNewton(Pose2 pose, const std::vector<AnchorTerm>& terms, const RegenerationOptions& o) {
  FitResult fit;
  for (int it = 0; it < o.max_iterations; ++it) {
    const NormalEquations eq = linearize(pose, terms, o);
    if (!fullyConstrained(eq.information, o)) return fit;
    const Vec3 step = eq.information.ldlt().solve(eq.gradient);
    if (!step.allFinite()) return fit;
    pose = Pose2(pose.x + step.x(), pose.y + step.y(), wrapAngle(pose.theta + step.z()));
    fit.iterations = it + 1;
    if (step.head<2>().norm() < 1e-7 && std::abs(step.z()) < 1e-8) break;
  }
  fit.equations = linearize(pose, terms, o);
  fit.ok = fullyConstrained(fit.equations.information, o);
  fit.pose = pose;
  return fit;
}

/// Index of the worst anchor beyond its χ² gate, or -1.
int worstOutlier(const std::vector<AnchorTerm>& terms, const std::vector<double>& nis) {
  int worst = -1;
  double worst_excess = 1.0;
  for (size_t i = 0; i < terms.size(); ++i) {
    if (nis[i] < 0.0) continue;
    const double excess = nis[i] / chi2Quantile999(parameterCount(terms[i].feature->kind));
    if (excess > worst_excess) {
      worst_excess = excess;
      worst = static_cast<int>(i);
    }
  }
  return worst;
}

std::vector<AnchorTerm> matchAnchors(const ScanAnchors& anchors, const FeatureIndex& map) {
  std::vector<AnchorTerm> terms;
  for (const AnchorObservation& a : anchors.anchors) {
    const auto it = map.find(a.feature_id);
    if (it == map.end() || it->second->kind != a.kind || !a.z.allFinite()) continue;
    terms.push_back({&a, it->second});
  }
  return terms;
}

RegeneratedPose storedPose(const ScanAnchors& anchors) {
  RegeneratedPose out;
  out.pose = anchors.pose.pose;
  out.cov = anchors.pose.cov;
  out.source = PoseSource::Stored;
  return out;
}

}  // namespace

const char* poseSourceName(PoseSource source) {
  switch (source) {
    case PoseSource::Regenerated: return "regenerated";
    case PoseSource::Chained: return "chained";
    case PoseSource::Stored: return "stored";
  }
  return "?";
}

FeatureIndex indexFeatures(const FeatureMap& map) {
  FeatureIndex index;
  index.reserve(map.features.size());
  for (const MapFeature& f : map.features) index[f.id] = &f;
  return index;
}

RegeneratedPose regeneratePose(const ScanAnchors& anchors, const FeatureIndex& map, const RegenerationOptions& o) {
  std::vector<AnchorTerm> terms = matchAnchors(anchors, map);
  const size_t min_kept = (terms.size() + 1) / 2;  // never reject more than half of the anchors
  FitResult fit = gaussNewton(anchors.pose.pose, terms, o);
  int rejected = 0;
  while (fit.ok && o.reject_outliers && terms.size() > min_kept) {
    const int worst = worstOutlier(terms, fit.equations.nis);
    if (worst < 0) break;
    terms.erase(terms.begin() + worst);
    ++rejected;
    fit = gaussNewton(fit.pose, terms, o);
  }
  if (!fit.ok) return storedPose(anchors);
  RegeneratedPose out;
  out.pose = fit.pose;
  out.cov = fit.equations.information.inverse();
  out.source = PoseSource::Regenerated;
  out.anchors_used = fit.equations.used;
  out.anchors_rejected = rejected;
  out.iterations = fit.iterations;
  out.chi2 = fit.equations.chi2;
  return out;
}

std::vector<RegeneratedPose> regeneratePoses(const std::vector<const ScanAnchors*>& anchors, const FeatureMap& map,
                                             const RegenerationOptions& o) {
  const FeatureIndex index = indexFeatures(map);
  std::vector<RegeneratedPose> poses;
  poses.reserve(anchors.size());
  std::vector<size_t> solved;  // indices of regenerated scans, in time order
  for (size_t k = 0; k < anchors.size(); ++k) {
    poses.push_back(regeneratePose(*anchors[k], index, o));
    if (poses.back().source == PoseSource::Regenerated) solved.push_back(k);
  }
  std::sort(solved.begin(), solved.end(), [&](size_t a, size_t b) { return anchors[a]->utime < anchors[b]->utime; });
  if (solved.empty()) return poses;
  for (size_t k = 0; k < anchors.size(); ++k) {
    if (poses[k].source == PoseSource::Regenerated) continue;
    const int64_t t = anchors[k]->utime;
    auto after = std::lower_bound(solved.begin(), solved.end(), t,
                                  [&](size_t j, int64_t value) { return anchors[j]->utime < value; });
    size_t nearest = after == solved.end() ? solved.back() : *after;
    if (after != solved.begin()) {
      const size_t before = *std::prev(after);
      if (after == solved.end() || t - anchors[before]->utime <= anchors[*after]->utime - t) nearest = before;
    }
    const Pose2 correction = poses[nearest].pose * anchors[nearest]->pose.pose.inverse();
    poses[k].pose = correction * anchors[k]->pose.pose;
    poses[k].cov = poses[nearest].cov;
    poses[k].source = PoseSource::Chained;
  }
  return poses;
}

std::vector<RegeneratedPose> regeneratePoses(const std::vector<ScanAnchors>& anchors, const FeatureMap& map,
                                             const RegenerationOptions& o) {
  std::vector<const ScanAnchors*> pointers;
  pointers.reserve(anchors.size());
  for (const ScanAnchors& a : anchors) pointers.push_back(&a);
  return regeneratePoses(pointers, map, o);
}

RegenerationSummary summarize(const std::vector<const ScanAnchors*>& anchors, const std::vector<RegeneratedPose>& poses) {
  RegenerationSummary s;
  double shift_sum = 0.0;
  for (size_t k = 0; k < poses.size() && k < anchors.size(); ++k) {
    switch (poses[k].source) {
      case PoseSource::Regenerated: ++s.regenerated; break;
      case PoseSource::Chained: ++s.chained; break;
      case PoseSource::Stored: ++s.stored; break;
    }
    s.anchors_rejected += poses[k].anchors_rejected;
    const double shift = (poses[k].pose.translation() - anchors[k]->pose.pose.translation()).norm();
    shift_sum += shift;
    s.max_shift = std::max(s.max_shift, shift);
  }
  if (!poses.empty()) s.mean_shift = shift_sum / static_cast<double>(poses.size());
  return s;
}

}  // namespace polarslam
