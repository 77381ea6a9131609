#pragma once
// JSON forms of the evaluation results, shared by `polarslam eval` and `polarslam run`
// (field names documented in core/eval/README.md). NaN statistics (no samples) become null.
#include <nlohmann/json.hpp>

#include "eval/ate.hpp"
#include "eval/error_statistics.hpp"
#include "eval/relation_metric.hpp"

namespace polarslam {

/// {"count", "mean", "std", "min", "max", "median", "rmse"}
nlohmann::json errorStatisticsJson(const ErrorStatistics& s);

/// {"relations", "evaluated", "skipped_no_pose", "translation_m", "rotation_deg",
///  "translation_squared_m2", "rotation_squared_deg2"}
nlohmann::json relationMetricJson(const RelationMetric& metric);

/// {"estimated", "matched", "unmatched", "raw": {"translation_m", "rotation_deg"},
///  "aligned": {"translation_m", "rotation_deg", "alignment": {"x", "y", "theta"}}}
nlohmann::json ateJson(const AteResult& ate);

}  // namespace polarslam
