#pragma once
// Wall-clock seconds for the timing figures of reports and benchmarks.
#include <chrono>

namespace polarslam {

inline double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace polarslam
