#pragma once
// Summary statistics of a list of per-pose or per-relation errors.
#include <cstddef>
#include <vector>

namespace polarslam {

/// Statistics of `count` values; every field but count is NaN when count is 0.
/// std is the population standard deviation (divides by count), as "mean ± std" tables use.
struct ErrorStatistics {
  size_t count = 0;
  double mean = 0.0, std = 0.0, min = 0.0, max = 0.0, median = 0.0, rmse = 0.0;
};

ErrorStatistics summarizeErrors(std::vector<double> values);

}  // namespace polarslam
