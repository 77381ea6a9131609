#include "eval/eval_json.hpp"

#include <cmath>

namespace polarslam {
namespace {

nlohmann::json numberOrNull(double value) { return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(); }

}  // namespace

nlohmann::json errorStatisticsJson(const ErrorStatistics& s) {
  return {{"count", s.count},           {"mean", numberOrNull(s.mean)},     {"std", numberOrNull(s.std)},
          {"min", numberOrNull(s.min)}, {"max", numberOrNull(s.max)},       {"median", numberOrNull(s.median)},
          {"rmse", numberOrNull(s.rmse)}};
}

nlohmann::json relationMetricJson(const RelationMetric& m) {
  return {{"relations", m.relations},
          {"evaluated", m.evaluated},
          {"skipped_no_pose", m.skipped_no_pose},
          {"translation_m", errorStatisticsJson(m.translation)},
          {"rotation_deg", errorStatisticsJson(m.rotation_deg)},
          {"translation_squared_m2", errorStatisticsJson(m.translation_squared)},
          {"rotation_squared_deg2", errorStatisticsJson(m.rotation_squared)}};
}

nlohmann::json ateJson(const AteResult& ate) {
  return {{"estimated", ate.estimated},
          {"matched", ate.matched},
          {"unmatched", ate.unmatched},
          {"raw", {{"translation_m", errorStatisticsJson(ate.raw_translation)},
                   {"rotation_deg", errorStatisticsJson(ate.raw_rotation_deg)}}},
          {"aligned", {{"translation_m", errorStatisticsJson(ate.aligned_translation)},
                       {"rotation_deg", errorStatisticsJson(ate.aligned_rotation_deg)},
                       {"alignment", {{"x", ate.alignment.x}, {"y", ate.alignment.y}, {"theta", ate.alignment.theta}}}}}};
}

}  // namespace polarslam
