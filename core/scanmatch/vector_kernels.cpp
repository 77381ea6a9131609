#include "scanmatch/vector_kernels.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>

#include "scanmatch/match_sums.hpp"
#include "scanmatch/projection.hpp"

#if defined(__x86_64__)
#include <immintrin.h>
#endif

namespace polarslam {
namespace {

using detail::SurfaceInputs;
using detail::SurfaceOutputs;

// Every kernel twice: SSE2 (any x86-64, and the vector extension's generic code elsewhere) and,
// for processors that have it, AVX2. Not FMA: a fused multiply-add rounds once where the
// baseline rounds twice.
namespace baseline {
#define POLARSLAM_VECTOR_BYTES 16
#include "scanmatch/vector_lanes.inc"
namespace projection {
#include "scanmatch/projection_lanes.inc"
}
namespace sums {
#include "scanmatch/match_sums_lanes.inc"
}
namespace preparation {
#include "scanmatch/prepared_scan_lanes.inc"
}
#undef POLARSLAM_VECTOR_BYTES
}  // namespace baseline

#if POLARSLAM_AVX2_KERNELS
#pragma GCC push_options
#pragma GCC target("avx2")
namespace avx2 {
#define POLARSLAM_VECTOR_BYTES 32
#include "scanmatch/vector_lanes.inc"
namespace projection {
#include "scanmatch/projection_lanes.inc"
}
namespace sums {
#include "scanmatch/match_sums_lanes.inc"
}
namespace preparation {
#include "scanmatch/prepared_scan_lanes.inc"
}
#undef POLARSLAM_VECTOR_BYTES
}  // namespace avx2
#pragma GCC pop_options
#else
namespace avx2 = baseline;
#endif

bool wide(VectorKernels kernels) { return kernels == VectorKernels::Avx2 && vectorKernelsAvailable(kernels); }

}  // namespace

bool vectorKernelsAvailable(VectorKernels kernels) {
  if (kernels == VectorKernels::Baseline) return true;
#if POLARSLAM_AVX2_KERNELS
  static const bool avx2 = [] {
    __builtin_cpu_init();  // may be asked from a static constructor, before libgcc's has run
    return __builtin_cpu_supports("avx2") != 0;
  }();
  return avx2;
#else
  return false;
#endif
}

VectorKernels widestVectorKernels() {
  return vectorKernelsAvailable(VectorKernels::Avx2) ? VectorKernels::Avx2 : VectorKernels::Baseline;
}

const char* vectorKernelsName(VectorKernels kernels) {
  return kernels == VectorKernels::Avx2 ? "avx2" : "baseline";
}

namespace detail {
void projectReadings(const BeamGeometry& g, const PreparedScan& cur, const Pose2& pose, Projection& out,
                     VectorKernels kernels) {
  if (wide(kernels)) avx2::projection::projectReadings(g, cur, pose, out);
  else baseline::projection::projectReadings(g, cur, pose, out);
}

void divideSlopes(const double* moment, const double* denominator, size_t n, float* slope, VectorKernels kernels) {
  if (wide(kernels)) avx2::preparation::divideSlopes(moment, denominator, n, slope);
  else baseline::preparation::divideSlopes(moment, denominator, n, slope);
}

void surfaceTerms(const SurfaceInputs& in, const SurfaceOutputs& out, VectorKernels kernels) {
  if (wide(kernels)) avx2::preparation::surfaceTerms(in, out);
  else baseline::preparation::surfaceTerms(in, out);
}
}  // namespace detail

JointSums sumJointSystem(const JointInputs& in, const Pose2& pose, double c, const JointLimits& limits,
                         VectorKernels kernels, JointTerms terms) {
  switch (terms) {
    case JointTerms::Translation:
      return wide(kernels) ? avx2::sums::sumJointSystem<JointTerms::Translation>(in, pose, c, limits)
                           : baseline::sums::sumJointSystem<JointTerms::Translation>(in, pose, c, limits);
    case JointTerms::SlopeNoise:
      return wide(kernels) ? avx2::sums::sumJointSystem<JointTerms::SlopeNoise>(in, pose, c, limits)
                           : baseline::sums::sumJointSystem<JointTerms::SlopeNoise>(in, pose, c, limits);
    case JointTerms::All: break;
  }
  return wide(kernels) ? avx2::sums::sumJointSystem<JointTerms::All>(in, pose, c, limits)
                       : baseline::sums::sumJointSystem<JointTerms::All>(in, pose, c, limits);
}

SlopeFitSums sumSlopeFit(const SlopeFitInputs& in, double c, VectorKernels kernels) {
  return wide(kernels) ? avx2::sums::sumSlopeFit(in, c) : baseline::sums::sumSlopeFit(in, c);
}

ShiftCostSums sumShiftCost(const ShiftCostInputs& in, VectorKernels kernels) {
  return wide(kernels) ? avx2::sums::sumShiftCost(in) : baseline::sums::sumShiftCost(in);
}

void maskSamples(const MaskInputs& in, float* values, float* mask, VectorKernels kernels) {
  if (wide(kernels)) avx2::sums::maskSamples(in, values, mask);
  else baseline::sums::maskSamples(in, values, mask);
}

}  // namespace polarslam
