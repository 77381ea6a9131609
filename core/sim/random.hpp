#pragma once
// Deterministic random numbers for the simulator: std::mt19937_64 (fully specified by the
// standard) with our own distributions, so a seed gives the same numbers with any standard
// library. Each sensor draws from its own stream, so enabling one sensor does not change
// another's noise.
#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>

namespace polarslam {

/// SplitMix64 of (seed, stream): well-mixed, independent seeds for separate streams.
inline uint64_t streamSeed(uint64_t seed, uint64_t stream) {
  uint64_t z = seed + 0x9E3779B97F4A7C15ull * (stream + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

class Rng {
 public:
  explicit Rng(uint64_t seed) : engine_(seed) {}

  /// Uniform in [0, 1) with 53 random bits.
  double uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  /// Uniform integer in [0, n).
  int uniformInt(int n) { return static_cast<int>(uniform() * n); }
  bool bernoulli(double p) { return uniform() < p; }

  /// Standard normal by the Box–Muller transform (the second value is kept for the next call).
  double normal() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    double u1 = uniform();
    while (u1 <= 0.0) u1 = uniform();
    const double u2 = uniform();
    const double radius = std::sqrt(-2.0 * std::log(u1));
    spare_ = radius * std::sin(2.0 * std::numbers::pi * u2);
    has_spare_ = true;
    return radius * std::cos(2.0 * std::numbers::pi * u2);
  }
  double normal(double mean, double sigma) { return sigma > 0.0 ? mean + sigma * normal() : mean; }

  /// Poisson count with mean `lambda` (Knuth's multiplication method; lambda is small here).
  int poisson(double lambda) {
    if (lambda <= 0.0) return 0;
    const double limit = std::exp(-lambda);
    int k = 0;
    for (double p = uniform(); p > limit && k < 10000; p *= uniform()) ++k;
    return k;
  }

 private:
  std::mt19937_64 engine_;
  bool has_spare_ = false;
  double spare_ = 0.0;
};

}  // namespace polarslam
