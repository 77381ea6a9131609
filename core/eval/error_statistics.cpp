#include "eval/error_statistics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace polarslam {

ErrorStatistics summarizeErrors(std::vector<double> values) {
  ErrorStatistics s;
  s.count = values.size();
  if (values.empty()) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    s.mean = s.std = s.min = s.max = s.median = s.rmse = nan;
    return s;
  }
  std::sort(values.begin(), values.end());
  const double n = static_cast<double>(values.size());
  double sum = 0.0, sum_squares = 0.0;
  for (double v : values) {
    sum += v;
    sum_squares += v * v;
  }
  s.mean = sum / n;
  double squared_deviations = 0.0;  // two-pass: no cancellation for tightly clustered errors
  for (double v : values) squared_deviations += (v - s.mean) * (v - s.mean);
  s.std = std::sqrt(squared_deviations / n);
  s.rmse = std::sqrt(sum_squares / n);
  s.min = values.front();
  s.max = values.back();
  const size_t mid = values.size() / 2;
  s.median = values.size() % 2 == 1 ? values[mid] : 0.5 * (values[mid - 1] + values[mid]);
  return s;
}

}  // namespace polarslam
