#include "slam/psm_slam_filter.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace polarslam {
namespace {

Vec3 measurementResidual(const Pose2& z, const Pose2& h) {
  return {z.x - h.x, z.y - h.y, wrapAngle(z.theta - h.theta)};
}

}  // namespace

RelativePoseJacobians relativePoseJacobians(const Pose2& keyframe, const Pose2& robot) {
  const double c = std::cos(keyframe.theta), s = std::sin(keyframe.theta);
  const Pose2 h = between(keyframe, robot);
  RelativePoseJacobians J;
  J.robot << c, s, 0.0, -s, c, 0.0, 0.0, 0.0, 1.0;
  J.keyframe << -c, -s, h.y, s, -c, -h.x, 0.0, 0.0, -1.0;
  return J;
}

void PsmSlamFilter::reset(const Pose2& pose, const Mat3& cov) {
  x_ = Eigen::VectorXd::Zero(3 * 16);
  P_ = Eigen::MatrixXd::Zero(3 * 16, 3 * 16);
  slot_end_ = 1;
  free_slots_.clear();
  slot_of_.clear();
  active_id_ = -1;
  active_slot_ = 0;
  x_.head<3>() = pose.vec();
  P_.topLeftCorner<3, 3>() = cov;
  loadLocal();
  flushes_ = 0;
}

Mat3 PsmSlamFilter::block(Eigen::Index s, Eigen::Index t) const {
  if (s > t) return P_.block<3, 3>(s, t);
  if (s < t) return P_.block<3, 3>(t, s).transpose();
  return P_.block<3, 3>(s, s).selfadjointView<Eigen::Lower>();
}

void PsmSlamFilter::setBlock(Eigen::Index s, Eigen::Index t, const Mat3& value) {
  if (s >= t) P_.block<3, 3>(s, t) = value;
  else P_.block<3, 3>(t, s) = value.transpose();
}

Eigen::MatrixXd PsmSlamFilter::column(Eigen::Index t) const {
  const Eigen::Index n = static_cast<Eigen::Index>(dimension());
  Eigen::MatrixXd c(n, 3);
  c.topRows(t) = P_.block(t, 0, 3, t).transpose();
  c.middleRows<3>(t) = block(t, t);
  c.bottomRows(n - t - 3) = P_.block(t + 3, t, n - t - 3, 3);
  return c;
}

void PsmSlamFilter::setColumn(Eigen::Index t, const Eigen::MatrixXd& value) {
  const Eigen::Index n = static_cast<Eigen::Index>(dimension());
  P_.block(t, 0, 3, t) = value.topRows(t).transpose();
  P_.block<3, 3>(t, t) = value.middleRows<3>(t);
  P_.block(t + 3, t, n - t - 3, 3) = value.bottomRows(n - t - 3);
}

void PsmSlamFilter::loadLocal() {
  local_x_.setZero();
  local_P_.setZero();
  local_x_.head<3>() = x_.head<3>();
  local_P_.topLeftCorner<3, 3>() = block(0, 0);
  if (active_slot_ != 0) {
    const Eigen::Index a = offset(active_slot_);
    local_x_.tail<3>() = x_.segment<3>(a);
    local_P_.block<3, 3>(0, 3) = block(0, a);
    local_P_.block<3, 3>(3, 0) = block(a, 0);
    local_P_.block<3, 3>(3, 3) = block(a, a);
  }
  phi_.setIdentity();
  psi_.setZero();
  theta_.setZero();
  pending_ = false;
}

void PsmSlamFilter::flush() {
  const Eigen::Index n = static_cast<Eigen::Index>(dimension());
  const Eigen::Index a = offset(active_slot_);
  if (pending_ && active_slot_ != 0) {
    // W = P(:, A) at the last flush; the rows of A itself are overwritten below.
    Eigen::MatrixXd W(n, 6);
    W.leftCols<3>() = column(0);
    W.rightCols<3>() = column(a);
    const Eigen::MatrixXd W_psi = W * psi_;
    P_.topLeftCorner(n, n).triangularView<Eigen::Lower>() -= W_psi * W.transpose();
    x_.head(n).noalias() += W * theta_;
    const Eigen::MatrixXd cross = W * phi_.transpose();  // P(B, A) now
    setColumn(0, cross.leftCols<3>());
    setColumn(a, cross.rightCols<3>());
    ++flushes_;
  }
  x_.head<3>() = local_x_.head<3>();
  setBlock(0, 0, local_P_.topLeftCorner<3, 3>());
  if (active_slot_ != 0) {
    x_.segment<3>(a) = local_x_.tail<3>();
    setBlock(a, 0, local_P_.block<3, 3>(3, 0));
    setBlock(a, a, local_P_.block<3, 3>(3, 3));
  }
  loadLocal();
}

void PsmSlamFilter::predict(const Pose2& motion, const Mat3& motion_cov) {
  const Pose2 robot = robotPose();
  Mat6 F = Mat6::Identity();
  F.topLeftCorner<3, 3>() = composeJacobianA(robot, motion);
  const Mat3 Jb = composeJacobianB(robot);
  local_x_.head<3>() = (robot * motion).vec();
  local_P_ = F * local_P_ * F.transpose();
  local_P_.topLeftCorner<3, 3>() += Jb * motion_cov * Jb.transpose();
  phi_ = F * phi_;
  pending_ = true;
}

size_t PsmSlamFilter::slotOf(int64_t id) const {
  const auto it = slot_of_.find(id);
  if (it == slot_of_.end()) throw std::out_of_range("keyframe " + std::to_string(id) + " is not in the filter");
  return it->second;
}

void PsmSlamFilter::ensureCapacity(size_t slots) {
  const Eigen::Index needed = offset(slots);
  if (needed <= x_.size()) return;
  const Eigen::Index grown = std::max<Eigen::Index>(needed, 2 * x_.size());
  const Eigen::Index n = static_cast<Eigen::Index>(dimension());
  Eigen::VectorXd x = Eigen::VectorXd::Zero(grown);
  Eigen::MatrixXd P = Eigen::MatrixXd::Zero(grown, grown);
  x.head(n) = x_.head(n);
  P.topLeftCorner(n, n) = P_.topLeftCorner(n, n);
  x_.swap(x);
  P_.swap(P);
}

size_t PsmSlamFilter::allocateSlot() {
  if (!free_slots_.empty()) {
    const size_t slot = free_slots_.back();
    free_slots_.pop_back();
    return slot;
  }
  ensureCapacity(slot_end_ + 1);
  return slot_end_++;
}

void PsmSlamFilter::addKeyframe(int64_t id) {
  if (hasKeyframe(id)) throw std::invalid_argument("keyframe " + std::to_string(id) + " is already in the filter");
  flush();
  const size_t slot = allocateSlot();
  const Eigen::Index s = offset(slot);
  // The new keyframe is a copy of the robot pose: its row and column are the robot's.
  x_.segment<3>(s) = x_.head<3>();
  Eigen::MatrixXd robot = column(0);
  robot.middleRows<3>(s) = robot.topRows<3>();
  setColumn(s, robot);
  slot_of_[id] = slot;
  active_id_ = id;
  active_slot_ = slot;
  loadLocal();
}

void PsmSlamFilter::addIndependentKeyframe(int64_t id, const Pose2& pose, const Mat3& cov) {
  if (hasKeyframe(id)) throw std::invalid_argument("keyframe " + std::to_string(id) + " is already in the filter");
  flush();
  const size_t slot = allocateSlot();
  const Eigen::Index s = offset(slot), n = static_cast<Eigen::Index>(dimension());
  x_.segment<3>(s) = pose.vec();
  Eigen::MatrixXd independent = Eigen::MatrixXd::Zero(n, 3);
  independent.middleRows<3>(s) = cov;
  setColumn(s, independent);
  slot_of_[id] = slot;
  loadLocal();
}

void PsmSlamFilter::removeKeyframe(int64_t id) {
  if (id == active_id_) throw std::logic_error("the active keyframe cannot be removed from the filter");
  const size_t slot = slotOf(id);
  flush();
  const Eigen::Index s = offset(slot), n = static_cast<Eigen::Index>(dimension());
  x_.segment<3>(s).setZero();
  setColumn(s, Eigen::MatrixXd::Zero(n, 3));
  slot_of_.erase(id);
  free_slots_.push_back(slot);
  loadLocal();
}

void PsmSlamFilter::setActiveKeyframe(int64_t id) {
  if (id == active_id_) return;
  const size_t slot = slotOf(id);
  flush();
  active_id_ = id;
  active_slot_ = slot;
  loadLocal();
}

Pose2 PsmSlamFilter::keyframePose(int64_t id) const {
  const size_t slot = slotOf(id);
  if (slot == active_slot_) return Pose2(local_x_.tail<3>());
  const Eigen::Index s = offset(slot), a = offset(active_slot_);
  Vec3 x = x_.segment<3>(s);
  if (pending_) x += block(s, 0) * theta_.head<3>() + block(s, a) * theta_.tail<3>();
  return Pose2(x);
}

Mat3 PsmSlamFilter::keyframeCovariance(int64_t id) const {
  const size_t slot = slotOf(id);
  if (slot == active_slot_) return local_P_.bottomRightCorner<3, 3>();
  const Eigen::Index s = offset(slot), a = offset(active_slot_);
  Mat3 P = block(s, s);
  if (pending_) {
    Mat36 P_kA;
    P_kA << block(s, 0), block(s, a);
    P -= P_kA * psi_ * P_kA.transpose();
  }
  return P;
}

RelativePosePrediction PsmSlamFilter::predictRelative(int64_t id) const {
  const size_t slot = slotOf(id);
  const Pose2 robot = robotPose();
  const Pose2 keyframe = keyframePose(id);
  Mat3 P_rr = robotCovariance(), P_kk, P_rk;
  if (slot == active_slot_) {
    P_kk = local_P_.bottomRightCorner<3, 3>();
    P_rk = local_P_.topRightCorner<3, 3>();
  } else {
    const Eigen::Index s = offset(slot), a = offset(active_slot_);
    P_kk = keyframeCovariance(id);
    Eigen::Matrix<double, 6, 3> P_Ak;
    P_Ak << block(0, s), block(a, s);
    P_rk = (phi_ * P_Ak).topRows<3>();
  }
  const RelativePoseJacobians J = relativePoseJacobians(keyframe, robot);
  RelativePosePrediction prediction;
  prediction.mean = between(keyframe, robot);
  prediction.cov = J.robot * P_rr * J.robot.transpose() + J.keyframe * P_kk * J.keyframe.transpose() +
                   J.robot * P_rk * J.keyframe.transpose() + J.keyframe * P_rk.transpose() * J.robot.transpose();
  return prediction;
}

// Along the direction u of the relative translation t = R_kᵀ(t_r − t_k), the keyframe's heading
// moves t across u only, so var(uᵀt) = var(uᵀR_kᵀ(t_r − t_k)), at most (σ_r + σ_k)² with σ² the
// trace of each position covariance (Cauchy–Schwarz on the cross term). The keyframe's stored
// block bounds its covariance: the pending updates only subtract from it (keyframeCovariance).
RelativePoseBound PsmSlamFilter::boundRelative(int64_t id) const {
  const size_t slot = slotOf(id);
  const Mat3 P_rr = robotCovariance();
  const Mat3 P_kk = slot == active_slot_ ? Mat3(local_P_.bottomRightCorner<3, 3>()) : block(offset(slot), offset(slot));
  RelativePoseBound bound;
  bound.mean = between(keyframePose(id), robotPose());
  bound.position_sigma = std::sqrt(std::max(0.0, P_rr(0, 0) + P_rr(1, 1))) + std::sqrt(std::max(0.0, P_kk(0, 0) + P_kk(1, 1)));
  bound.heading_sigma = std::sqrt(std::max(0.0, P_rr(2, 2))) + std::sqrt(std::max(0.0, P_kk(2, 2)));
  return bound;
}

FilterUpdateOutcome PsmSlamFilter::update(int64_t id, const Pose2& z, const Mat3& R, double chi2_gate) {
  setActiveKeyframe(id);
  const Pose2 robot = robotPose(), keyframe(local_x_.tail<3>());
  const RelativePoseJacobians J = relativePoseJacobians(keyframe, robot);
  Mat36 H;
  H << J.robot, J.keyframe;
  const Vec3 nu = measurementResidual(z, between(keyframe, robot));
  const Mat3 S = H * local_P_ * H.transpose() + R;
  const Eigen::LDLT<Mat3> S_ldlt(S);
  FilterUpdateOutcome outcome;
  outcome.chi2 = nu.dot(S_ldlt.solve(nu));
  if (!(outcome.chi2 <= chi2_gate) || S_ldlt.info() != Eigen::Success) return outcome;

  const Mat3 S_inv = S_ldlt.solve(Mat3::Identity());
  const Eigen::Matrix<double, 6, 3> K = local_P_ * H.transpose() * S_inv;
  const Mat6 I_KH = Mat6::Identity() - K * H;
  const Mat36 H_phi = H * phi_;
  psi_ += H_phi.transpose() * S_inv * H_phi;
  theta_ += H_phi.transpose() * S_inv * nu;
  phi_ = I_KH * phi_;
  local_x_ += K * nu;
  local_x_(2) = wrapAngle(local_x_(2));
  local_x_(5) = wrapAngle(local_x_(5));
  // Joseph form: stays symmetric positive semi-definite under rounding.
  local_P_ = I_KH * local_P_ * I_KH.transpose() + K * R * K.transpose();
  pending_ = true;
  outcome.accepted = true;
  return outcome;
}

void PsmSlamFilter::setKeyframePoses(const std::unordered_map<int64_t, Pose2>& poses) {
  flush();
  const Pose2 robot = robotPose();
  const bool moves_active = active_slot_ != 0 && poses.count(active_id_) != 0;
  const Pose2 robot_in_active = moves_active ? between(keyframePose(active_id_), robot) : Pose2();
  for (const auto& [id, pose] : poses) {
    const auto it = slot_of_.find(id);
    if (it != slot_of_.end()) x_.segment<3>(offset(it->second)) = pose.vec();
  }
  if (moves_active) x_.head<3>() = (poses.at(active_id_) * robot_in_active).vec();
  loadLocal();
}

PsmSlamFilterState PsmSlamFilter::exportState() const {
  // What flush() would make of the exported blocks, computed for them alone: a copy of the filter
  // to flush would take its storage, sized by capacity (up to twice the slots in use, hundreds of
  // megabytes near max_filter_keyframes), on top of the state's own.
  PsmSlamFilterState state;
  state.active = active_id_;
  std::vector<std::pair<int64_t, size_t>> keyframes(slot_of_.begin(), slot_of_.end());
  std::sort(keyframes.begin(), keyframes.end());
  std::vector<Eigen::Index> from{0};  // state offset of each exported pose in the slots
  size_t active = 0;                  // the active keyframe's index among them (0: none)
  for (const auto& [id, slot] : keyframes) {
    state.ids.push_back(id);
    if (slot == active_slot_) active = from.size();
    from.push_back(offset(slot));
  }
  const size_t m = from.size();
  const Eigen::Index n = static_cast<Eigen::Index>(3 * m);
  const auto at = [](size_t i) { return static_cast<Eigen::Index>(3 * i); };
  state.mean.resize(n);
  state.cov.resize(n, n);
  for (size_t i = 0; i < m; ++i) {
    state.mean.segment<3>(at(i)) = x_.segment<3>(from[i]);
    for (size_t j = 0; j <= i; ++j) state.cov.block<3, 3>(at(i), at(j)) = block(from[i], from[j]);
  }
  if (pending_ && active != 0) {
    // flush(): with W = P(:, [robot, active]), P −= W Ψ Wᵀ and x += W θ, then P(:, [robot, active]) = W Φᵀ.
    const Eigen::Index a = offset(active_slot_);
    Eigen::MatrixXd W(n, 6);
    for (size_t i = 0; i < m; ++i) W.block<3, 6>(at(i), 0) << block(from[i], 0), block(from[i], a);
    state.mean.noalias() += W * theta_;
    const Eigen::MatrixXd W_psi = W * psi_;
    state.cov.triangularView<Eigen::Lower>() -= W_psi * W.transpose();
    const Eigen::MatrixXd cross = W * phi_.transpose();
    for (size_t i = 0; i < m; ++i)
      for (const auto& [column, part] : {std::pair{size_t{0}, 0}, {active, 3}}) {
        const Mat3 value = cross.block<3, 3>(at(i), part);
        if (i >= column) state.cov.block<3, 3>(at(i), at(column)) = value;
        else state.cov.block<3, 3>(at(column), at(i)) = value.transpose();
      }
  }
  state.mean.head<3>() = local_x_.head<3>();
  state.cov.topLeftCorner<3, 3>() = local_P_.topLeftCorner<3, 3>();
  if (active != 0) {
    state.mean.segment<3>(at(active)) = local_x_.tail<3>();
    state.cov.block<3, 3>(at(active), 0) = local_P_.block<3, 3>(3, 0);
    state.cov.block<3, 3>(at(active), at(active)) = local_P_.block<3, 3>(3, 3);
  }
  for (Eigen::Index c = 0; c + 1 < n; ++c) state.cov.row(c).tail(n - c - 1) = state.cov.col(c).tail(n - c - 1).transpose();
  return state;
}

void PsmSlamFilter::restore(const PsmSlamFilterState& state) {
  const Eigen::Index n = static_cast<Eigen::Index>(3 * (state.ids.size() + 1));
  if (state.mean.size() != n || state.cov.rows() != n || state.cov.cols() != n)
    throw std::invalid_argument("a filter state of " + std::to_string(state.ids.size()) + " keyframes needs " +
                                std::to_string(n) + " values and a " + std::to_string(n) + "² covariance");
  if (!state.mean.allFinite() || !state.cov.allFinite())
    throw std::invalid_argument("the filter state holds a value that is not finite");
  // Not a full positive-semidefinite test (O(n³) for thousands of keyframes), but what any
  // covariance satisfies: variances ≥ 0 and correlations within ±1.
  const Eigen::VectorXd sigma = state.cov.diagonal().cwiseMax(0.0).cwiseSqrt();
  for (Eigen::Index c = 0; c < n; ++c) {
    if (!(state.cov(c, c) >= 0.0)) throw std::invalid_argument("the filter state holds a negative variance");
    for (Eigen::Index r = c + 1; r < n; ++r)
      if (!(std::abs(state.cov(r, c)) <= sigma(r) * sigma(c) * (1.0 + 1e-9) + 1e-300))
        throw std::invalid_argument("the filter state's covariance is not one: a correlation beyond ±1");
  }
  reset(Pose2(Vec3(state.mean.head<3>())), state.cov.topLeftCorner<3, 3>());
  ensureCapacity(state.ids.size() + 1);
  for (const int64_t id : state.ids) {
    if (!slot_of_.emplace(id, slot_end_++).second)
      throw std::invalid_argument("the filter state holds keyframe " + std::to_string(id) + " twice");
  }
  x_.head(n) = state.mean;
  P_.topLeftCorner(n, n).triangularView<Eigen::Lower>() = state.cov.triangularView<Eigen::Lower>();
  if (state.active >= 0 || !state.ids.empty()) {
    if (!hasKeyframe(state.active))
      throw std::invalid_argument("the filter state's active keyframe " + std::to_string(state.active) +
                                  " is not one of its keyframes");
    active_id_ = state.active;
    active_slot_ = slotOf(state.active);
  }
  loadLocal();
}

Eigen::VectorXd PsmSlamFilter::stateMean() {
  flush();
  return x_.head(static_cast<Eigen::Index>(dimension()));
}

Eigen::MatrixXd PsmSlamFilter::stateCovariance() {
  flush();
  const Eigen::Index n = static_cast<Eigen::Index>(dimension());
  return P_.topLeftCorner(n, n).selfadjointView<Eigen::Lower>();
}

}  // namespace polarslam
