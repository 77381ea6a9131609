#include "slam/association.hpp"

#include <Eigen/Cholesky>
#include <limits>
#include <map>
#include <mutex>

#include "geometry/chi_squared.hpp"

namespace polarslam {

double chiSquaredGate(int dof, double probability) {
  static std::mutex mutex;
  static std::map<std::pair<int, double>, double> cache;
  const std::lock_guard<std::mutex> lock(mutex);
  const auto key = std::make_pair(dof, probability);
  if (const auto it = cache.find(key); it != cache.end()) return it->second;
  const double gate = chiSquaredQuantile(probability, dof);
  cache.emplace(key, gate);
  return gate;
}

double mahalanobis2(const EkfState& state, const LinearizedObservation& lin) {
  const Eigen::MatrixXd S = state.innovationCovariance(lin).topLeftCorner(lin.dim, lin.dim);
  const Eigen::LLT<Eigen::MatrixXd> llt(S);
  if (llt.info() != Eigen::Success) return std::numeric_limits<double>::infinity();
  const Eigen::VectorXd nu = lin.innovation.head(lin.dim);
  return nu.dot(llt.solve(nu));
}

double jointNis(const EkfState& state, const std::vector<const LinearizedObservation*>& set) {
  int m = 0;
  std::vector<int> start;
  for (const auto* o : set) {
    start.push_back(m);
    m += o->dim;
  }
  if (m == 0) return 0.0;
  Eigen::MatrixXd S(m, m);
  Eigen::VectorXd nu(m);
  for (size_t a = 0; a < set.size(); ++a) {
    nu.segment(start[a], set[a]->dim) = set[a]->innovation.head(set[a]->dim);
    for (size_t b = 0; b < set.size(); ++b) {
      const Mat3 block = a == b ? state.innovationCovariance(*set[a]) : state.crossCovariance(*set[a], *set[b]);
      S.block(start[a], start[b], set[a]->dim, set[b]->dim) = block.topLeftCorner(set[a]->dim, set[b]->dim);
    }
  }
  const Eigen::LLT<Eigen::MatrixXd> llt(S);
  if (llt.info() != Eigen::Success) return std::numeric_limits<double>::infinity();
  return nu.dot(llt.solve(nu));
}

namespace {

/// A hypothesis grown one pairing at a time: stacked innovation, S⁻¹ (kept by block inversion,
/// so adding a pairing costs O(M²·m) rather than a new factorisation) and the joint NIS.
struct Hypothesis {
  std::vector<const LinearizedObservation*> members;
  Eigen::VectorXd nu;
  Eigen::MatrixXd S_inverse;
  double nis = 0.0;
  int dim() const { return static_cast<int>(nu.size()); }
};

/// The hypothesis with `lin` added, or false when S would not stay positive definite.
bool extend(const EkfState& state, const Hypothesis& h, const LinearizedObservation& lin, Hypothesis& out) {
  const int M = h.dim(), m = lin.dim;
  Eigen::MatrixXd B(M, m);
  int row = 0;
  for (const auto* member : h.members) {
    B.middleRows(row, member->dim) = state.crossCovariance(*member, lin).topLeftCorner(member->dim, m);
    row += member->dim;
  }
  const Eigen::MatrixXd C = state.innovationCovariance(lin).topLeftCorner(m, m);
  const Eigen::MatrixXd Y = h.S_inverse * B;
  Eigen::MatrixXd Z = C - B.transpose() * Y;
  Z = 0.5 * (Z + Z.transpose());
  const Eigen::LLT<Eigen::MatrixXd> llt(Z);
  if (llt.info() != Eigen::Success) return false;
  const Eigen::MatrixXd Z_inverse = llt.solve(Eigen::MatrixXd::Identity(m, m));
  const Eigen::VectorXd v = lin.innovation.head(m) - Y.transpose() * h.nu;
  out.members = h.members;
  out.members.push_back(&lin);
  out.nu.resize(M + m);
  out.nu << h.nu, lin.innovation.head(m);
  out.S_inverse.resize(M + m, M + m);
  const Eigen::MatrixXd YZ = Y * Z_inverse;
  out.S_inverse.topLeftCorner(M, M) = h.S_inverse + YZ * Y.transpose();
  out.S_inverse.topRightCorner(M, m) = -YZ;
  out.S_inverse.bottomLeftCorner(m, M) = -YZ.transpose();
  out.S_inverse.bottomRightCorner(m, m) = Z_inverse;
  out.nis = h.nis + v.dot(Z_inverse * v);
  return true;
}

class Jcbb {
 public:
  Jcbb(const EkfState& state, const std::vector<std::vector<AssociationCandidate>>& candidates,
       const AssociationParams& params)
      : state_(state), candidates_(candidates), params_(params) {
    const size_t n = candidates.size();
    current_.assign(n, -1);
    best_.assign(n, -1);
    remaining_with_candidates_.assign(n + 1, 0);
    for (size_t i = n; i-- > 0;)
      remaining_with_candidates_[i] = remaining_with_candidates_[i + 1] + (candidates[i].empty() ? 0 : 1);
  }

  void run() {
    Hypothesis empty;
    search(0, empty, 0);
  }

  const std::vector<int>& best() const { return best_; }
  double bestNis() const { return best_nis_; }
  long nodes() const { return nodes_; }
  bool exhausted() const { return exhausted_; }

 private:
  bool featureTaken(int feature) const {
    for (size_t i = 0; i < current_.size(); ++i)
      if (current_[i] >= 0 && candidates_[i][static_cast<size_t>(current_[i])].lin.feature == feature) return true;
    return false;
  }

  void search(size_t i, const Hypothesis& h, int pairings) {
    if (++nodes_ > params_.max_nodes) exhausted_ = true;
    // A leaf, or the end of the budget: the path so far is jointly compatible, so it counts.
    if (i == candidates_.size() || exhausted_) {
      if (pairings > best_pairings_ || (pairings == best_pairings_ && h.nis < best_nis_)) {
        best_pairings_ = pairings;
        best_nis_ = h.nis;
        best_ = current_;
      }
      return;
    }
    const auto& list = candidates_[i];
    for (size_t c = 0; c < list.size() && !exhausted_; ++c) {
      if (featureTaken(list[c].lin.feature)) continue;
      Hypothesis next;
      if (!extend(state_, h, list[c].lin, next)) continue;
      if (next.nis > chiSquaredGate(next.dim(), params_.gate_probability)) continue;
      current_[i] = static_cast<int>(c);
      search(i + 1, next, pairings + 1);
      current_[i] = -1;
    }
    // Leaving observation i unpaired can only win if the rest could still beat the best.
    if (!exhausted_ && pairings + remaining_with_candidates_[i + 1] > best_pairings_) search(i + 1, h, pairings);
  }

  const EkfState& state_;
  const std::vector<std::vector<AssociationCandidate>>& candidates_;
  const AssociationParams& params_;
  std::vector<int> current_, best_;
  std::vector<int> remaining_with_candidates_;
  int best_pairings_ = -1;
  double best_nis_ = std::numeric_limits<double>::infinity();
  long nodes_ = 0;
  bool exhausted_ = false;
};

std::vector<const LinearizedObservation*> hypothesisMembers(
    const std::vector<std::vector<AssociationCandidate>>& candidates, const std::vector<int>& pairing) {
  std::vector<const LinearizedObservation*> members;
  for (size_t i = 0; i < pairing.size(); ++i)
    if (pairing[i] >= 0) members.push_back(&candidates[i][static_cast<size_t>(pairing[i])].lin);
  return members;
}

int candidateForFeature(const std::vector<AssociationCandidate>& list, int feature) {
  for (size_t c = 0; c < list.size(); ++c)
    if (list[c].lin.feature == feature) return static_cast<int>(c);
  return -1;
}

/// True when observation i has a rival candidate whose hypothesis is about as good as `best`.
bool hasRival(const EkfState& state, const std::vector<std::vector<AssociationCandidate>>& candidates,
              const std::vector<int>& best, double best_nis, size_t i, const AssociationParams& params) {
  const int own_feature = candidates[i][static_cast<size_t>(best[i])].lin.feature;
  for (size_t c = 0; c < candidates[i].size(); ++c) {
    if (static_cast<int>(c) == best[i]) continue;
    std::vector<int> rival = best;
    rival[i] = static_cast<int>(c);
    const int feature = candidates[i][c].lin.feature;
    for (size_t j = 0; j < best.size(); ++j) {
      if (j == i || best[j] < 0 || candidates[j][static_cast<size_t>(best[j])].lin.feature != feature) continue;
      rival[j] = candidateForFeature(candidates[j], own_feature);  // swap, or drop j if it cannot
    }
    size_t rival_pairings = 0, best_pairings = 0;
    for (size_t j = 0; j < best.size(); ++j) {
      rival_pairings += rival[j] >= 0;
      best_pairings += best[j] >= 0;
    }
    if (rival_pairings < best_pairings) continue;
    const auto members = hypothesisMembers(candidates, rival);
    int dim = 0;
    for (const auto* m : members) dim += m->dim;
    const double nis = jointNis(state, members);
    if (nis <= chiSquaredGate(dim, params.gate_probability) && nis - best_nis < params.ambiguity_nis_margin)
      return true;
  }
  return false;
}

}  // namespace

AssociationResult associate(const EkfState& state, const std::vector<std::vector<AssociationCandidate>>& candidates,
                            const AssociationParams& params) {
  Jcbb search(state, candidates, params);
  search.run();
  AssociationResult result;
  result.pairing = search.best();
  result.ambiguous.assign(candidates.size(), false);
  result.joint_nis = std::isfinite(search.bestNis()) ? search.bestNis() : 0.0;
  result.nodes = search.nodes();
  result.budget_exhausted = search.exhausted();
  for (size_t i = 0; i < candidates.size(); ++i)
    if (result.pairing[i] >= 0 && hasRival(state, candidates, search.best(), result.joint_nis, i, params))
      result.ambiguous[i] = true;
  for (size_t i = 0; i < candidates.size(); ++i) {
    if (result.ambiguous[i]) result.pairing[i] = -1;
    result.pairings += result.pairing[i] >= 0;
  }
  return result;
}

}  // namespace polarslam
