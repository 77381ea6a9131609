#pragma once
// The relation-based metric of Kümmerle et al. 2009 (data/README.md, docs/algorithms.md §20.1), written from
// its definition: for each relation (t1, t2, δ*), take the estimated poses T̂1, T̂2 nearest in
// time to t1 and t2, form d = v(T̂1⁻¹·T̂2) − v(δ*) with v = (x, y, z, roll, pitch, yaw) and the
// angles wrapped, and summarise the translational error √(dx² + dy² + dz²) in metres and the
// rotational error √(droll² + dpitch² + dyaw²) in degrees (for 2D data this is |dyaw|), as
// absolute values and squared (m², deg²), each with mean, std, min, max and count.
//
// Difference from the reference evaluator: when no estimated pose lies within the tolerance of
// a relation's timestamp, that evaluator corrects the nearest pose with odometry from a separate
// log; here the relation is skipped and counted in `skipped_no_pose` instead.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "eval/error_statistics.hpp"
#include "geometry/features.hpp"
#include "io/relations.hpp"

namespace polarslam {

struct RelationMetricOptions {
  int64_t max_time_difference_us = 100000;  ///< 0.1 s, as the reference evaluator
};

struct RelationError {
  size_t relation_index = 0;
  int64_t estimate_t1 = 0, estimate_t2 = 0;  ///< timestamps of the estimated poses used
  Pose2 estimated_motion;                     ///< T̂1⁻¹·T̂2
  double translation = 0.0;                   ///< m
  double rotation_deg = 0.0;                  ///< deg, ≥ 0
};

struct RelationMetric {
  size_t relations = 0;        ///< in the relations list
  size_t evaluated = 0;        ///< with an estimated pose within tolerance at both ends
  size_t skipped_no_pose = 0;  ///< relations − evaluated
  ErrorStatistics translation;          ///< m
  ErrorStatistics rotation_deg;         ///< deg
  ErrorStatistics translation_squared;  ///< m²
  ErrorStatistics rotation_squared;     ///< deg²
  std::vector<RelationError> errors;    ///< one per evaluated relation, in relation order
};

RelationMetric evaluateRelations(const std::vector<PoseStamped>& trajectory,
                                 const std::vector<Relation>& relations,
                                 const RelationMetricOptions& options = {});

/// How well a relations file agrees with itself: wherever three relations join three poses
/// (a→b, b→c and a→c, each in either direction), the first two composed against the third. For
/// relations taken from one trajectory this is zero; relations measured one by one carry their own
/// error, and no estimate can score below it on them. With the three relations' errors independent
/// and alike, a triangle's inconsistency is √3 times one relation's: `per_relation_translation`.
struct RelationConsistency {
  size_t triangles = 0;
  std::vector<size_t> relations;  ///< indices of the relations in at least one triangle, ascending
  ErrorStatistics translation;    ///< m, per triangle
  ErrorStatistics rotation_deg;   ///< deg, per triangle
  double per_relation_translation = 0.0;  ///< m: translation.mean / √3
};
RelationConsistency relationConsistency(const std::vector<Relation>& relations);

/// Relations taken from a ground-truth trajectory: from each ground-truth pose to the first one
/// at least spacing_us later, then onward from that one (a chain covering the whole run).
std::vector<Relation> relationsFromGroundTruth(const std::vector<PoseStamped>& ground_truth, int64_t spacing_us);

}  // namespace polarslam
