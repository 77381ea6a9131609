#include "slam/ekf_state.hpp"

#include <Eigen/Cholesky>
#include <algorithm>

namespace polarslam {

EkfState::EkfState(const Pose2& start, const Mat3& start_cov) {
  reserve(64);
  mean_.head<3>() = start.vec();
  cov_.topLeftCorner<3, 3>() = start_cov;
}

void EkfState::reserve(int dimension) {
  const int capacity = static_cast<int>(mean_.size());
  if (dimension <= capacity) return;
  const int grown = std::max(dimension, 2 * capacity);
  Eigen::VectorXd mean = Eigen::VectorXd::Zero(grown);
  Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(grown, grown);
  if (capacity > 0) {
    mean.head(n_) = mean_.head(n_);
    cov.topLeftCorner(n_, n_) = cov_.topLeftCorner(n_, n_);
  }
  mean_.swap(mean);
  cov_.swap(cov);
}

Vec3 EkfState::featureMean(int feature) const {
  const StateFeature& f = features_[static_cast<size_t>(feature)];
  Vec3 y = Vec3::Zero();
  y.head(f.size()) = mean_.segment(f.offset, f.size());
  return y;
}

Mat3 EkfState::featureCovariance(int feature) const {
  const StateFeature& f = features_[static_cast<size_t>(feature)];
  Mat3 P = Mat3::Zero();
  P.topLeftCorner(f.size(), f.size()) = cov_.block(f.offset, f.offset, f.size(), f.size());
  return P;
}

Mat3 EkfState::robotFeatureCovariance(int feature) const {
  const StateFeature& f = features_[static_cast<size_t>(feature)];
  Mat3 P = Mat3::Zero();
  P.leftCols(f.size()) = cov_.block(0, f.offset, 3, f.size());
  return P;
}

void EkfState::predict(const OdometryMotion& motion) {
  const Pose2 before = pose();
  const Mat3 Ja = composeJacobianA(before, motion.delta);
  const Mat3 Jb = composeJacobianB(before);
  const int map = n_ - 3;
  cov_.topLeftCorner<3, 3>() = Ja * cov_.topLeftCorner<3, 3>() * Ja.transpose() + Jb * motion.cov * Jb.transpose();
  if (map > 0) {
    const Eigen::MatrixXd cross = Ja * cov_.block(0, 3, 3, map);
    cov_.block(0, 3, 3, map) = cross;
    cov_.block(3, 0, map, 3) = cross.transpose();
  }
  mean_.head<3>() = (before * motion.delta).vec();
}

Eigen::MatrixXd EkfState::covarianceTimesHt(const LinearizedObservation& o) const {
  const StateFeature& f = features_[static_cast<size_t>(o.feature)];
  return cov_.block(0, 0, n_, 3) * o.H_x.topRows(o.dim).transpose() +
         cov_.block(0, f.offset, n_, f.size()) * o.H_y.block(0, 0, o.dim, f.size()).transpose();
}

Mat3 EkfState::crossCovariance(const LinearizedObservation& a, const LinearizedObservation& b) const {
  const StateFeature& fa = features_[static_cast<size_t>(a.feature)];
  const StateFeature& fb = features_[static_cast<size_t>(b.feature)];
  const int na = fa.size(), nb = fb.size();
  const auto Hxa = a.H_x.topRows(a.dim);
  const auto Hya = a.H_y.block(0, 0, a.dim, na);
  const auto Hxb = b.H_x.topRows(b.dim);
  const auto Hyb = b.H_y.block(0, 0, b.dim, nb);
  Mat3 S = Mat3::Zero();
  S.topLeftCorner(a.dim, b.dim) =
      Hxa * cov_.topLeftCorner<3, 3>() * Hxb.transpose() +
      Hxa * cov_.block(0, fb.offset, 3, nb) * Hyb.transpose() +
      Hya * cov_.block(fa.offset, 0, na, 3) * Hxb.transpose() +
      Hya * cov_.block(fa.offset, fb.offset, na, nb) * Hyb.transpose();
  return S;
}

Mat3 EkfState::innovationCovariance(const LinearizedObservation& o) const {
  Mat3 S = crossCovariance(o, o);
  S.topLeftCorner(o.dim, o.dim) += o.R.topLeftCorner(o.dim, o.dim);
  return S;
}

bool EkfState::update(const std::vector<LinearizedObservation>& observations) {
  int m = 0;
  std::vector<int> start;
  for (const auto& o : observations) {
    start.push_back(m);
    m += o.dim;
  }
  if (m == 0) return true;
  Eigen::MatrixXd W(n_, m);  // P·Hᵀ
  Eigen::VectorXd nu(m);
  for (size_t k = 0; k < observations.size(); ++k) {
    const auto& o = observations[k];
    W.middleCols(start[k], o.dim) = covarianceTimesHt(o);
    nu.segment(start[k], o.dim) = o.innovation.head(o.dim);
  }
  Eigen::MatrixXd S(m, m);  // H·P·Hᵀ + R, built from the two non-zero blocks of each H row
  for (size_t k = 0; k < observations.size(); ++k) {
    const auto& o = observations[k];
    const StateFeature& f = features_[static_cast<size_t>(o.feature)];
    S.middleRows(start[k], o.dim) = o.H_x.topRows(o.dim) * W.topRows(3) +
                                    o.H_y.block(0, 0, o.dim, f.size()) * W.middleRows(f.offset, f.size());
    S.block(start[k], start[k], o.dim, o.dim) += o.R.topLeftCorner(o.dim, o.dim);
  }
  S = 0.5 * (S + S.transpose());
  const Eigen::LLT<Eigen::MatrixXd> llt(S);
  if (llt.info() != Eigen::Success || !nu.allFinite()) return false;
  // x += W·S⁻¹·ν;  P −= W·S⁻¹·Wᵀ = V·Vᵀ with V = W·L⁻ᵀ (S = L·Lᵀ).
  mean_.head(n_) += W * llt.solve(nu);
  const Eigen::MatrixXd Vt = llt.matrixL().solve(W.transpose());
  auto P = cov_.topLeftCorner(n_, n_);
  P.selfadjointView<Eigen::Lower>().rankUpdate(Vt.transpose(), -1.0);
  for (int j = 1; j < n_; ++j) P.col(j).head(j) = P.row(j).head(j).transpose();
  wrapAngles();
  return true;
}

int EkfState::addFeature(int64_t id, MapFeatureKind kind, const Vec3& y, const Mat3& G_x, const Mat3& G_z,
                         const Mat3& R) {
  const int k = parameterCount(kind);
  const int offset = n_;
  reserve(n_ + k);
  const auto Gx = G_x.topRows(k);
  const auto Gz = G_z.block(0, 0, k, k);
  const Eigen::MatrixXd cross = Gx * cov_.block(0, 0, 3, n_);  // k × n: P(y, everything so far)
  mean_.segment(offset, k) = y.head(k);
  cov_.block(offset, 0, k, n_) = cross;
  cov_.block(0, offset, n_, k) = cross.transpose();
  cov_.block(offset, offset, k, k) =
      Gx * cov_.topLeftCorner<3, 3>() * Gx.transpose() + Gz * R.topLeftCorner(k, k) * Gz.transpose();
  n_ += k;
  features_.push_back({id, kind, offset});
  return static_cast<int>(features_.size()) - 1;
}

void EkfState::wrapAngles() {
  mean_(2) = wrapAngle(mean_(2));
  for (const StateFeature& f : features_) {
    if (f.kind == MapFeatureKind::Line) mean_(f.offset) = wrapAngle(mean_(f.offset));
    if (f.kind == MapFeatureKind::Corner) mean_(f.offset + 2) = wrapAngle(mean_(f.offset + 2));
  }
}

}  // namespace polarslam
