#pragma once
// Data association for EKF SLAM (thesis §3.6.1; the thesis's gates and strategy are not
// recovered, docs/algorithms.md §17.7). Design:
//  1. individual compatibility: each observation is linearised against every map feature of its
//     kind that the caller deems compatible (side of a line, convexity of a corner, line extent);
//     pairs whose Mahalanobis distance passes the χ² gate are its candidates, nearest first;
//  2. joint compatibility branch and bound (JCBB, Neira & Tardós 2001): the hypothesis with the
//     most pairings whose joint innovation passes the χ² gate of the joint dimension, ties broken
//     by the smaller joint NIS; each map feature takes at most one observation per scan. A node
//     budget caps the search; the depth-first search reaches the sequential-compatibility
//     (greedy nearest-neighbour with a joint test) hypothesis first, so a cut-off search still
//     returns a jointly compatible answer;
//  3. ambiguity rejection: a pairing is dropped when swapping it for another candidate (and, if
//     that candidate is taken, giving the other observation this one's feature) is also jointly
//     compatible with a joint NIS within `ambiguity_nis_margin` of the best.
#include <vector>

#include "slam/ekf_state.hpp"

namespace polarslam {

struct AssociationParams {
  double gate_probability = 0.99;      ///< individual and joint χ² gates
  double ambiguity_nis_margin = 9.21;  ///< χ²₂(0.99): a rival within this is too close to call
  int max_nodes = 20000;               ///< JCBB search budget per scan
};

struct AssociationCandidate {
  LinearizedObservation lin;
  double d2 = 0.0;  ///< individual Mahalanobis distance²
};

struct AssociationResult {
  std::vector<int> pairing;     ///< per observation: index into its candidates, or −1
  std::vector<bool> ambiguous;  ///< per observation: had a rival as good as its pairing
  double joint_nis = 0.0;       ///< of the chosen pairings, before ambiguity removal
  int pairings = 0;             ///< after ambiguity removal
  long nodes = 0;               ///< JCBB nodes visited
  bool budget_exhausted = false;
};

/// χ² gate value for `dof` at `probability` (cached).
double chiSquaredGate(int dof, double probability);

/// Individual Mahalanobis distance² of a linearised observation.
double mahalanobis2(const EkfState& state, const LinearizedObservation& lin);

/// Joint NIS of a set of linearised observations (+inf when S is not positive definite).
double jointNis(const EkfState& state, const std::vector<const LinearizedObservation*>& set);

/// Runs steps 2 and 3 on candidate lists (each sorted nearest first).
AssociationResult associate(const EkfState& state, const std::vector<std::vector<AssociationCandidate>>& candidates,
                            const AssociationParams& params);

}  // namespace polarslam
