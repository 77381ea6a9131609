#include "scanmatch/joint_sums.hpp"

#include <cmath>
#include <cstring>

namespace polarslam {
namespace {

namespace baseline {
#define POLARSLAM_LANES 2
#include "scanmatch/joint_sums_lanes.inc"
#undef POLARSLAM_LANES
}  // namespace baseline

#if POLARSLAM_AVX2_KERNELS
// Not FMA: a fused multiply-add rounds once where the baseline rounds twice.
#pragma GCC push_options
#pragma GCC target("avx2")
namespace avx2 {
#define POLARSLAM_LANES 4
#include "scanmatch/joint_sums_lanes.inc"
#undef POLARSLAM_LANES
}  // namespace avx2
#pragma GCC pop_options
#endif

}  // namespace

JointSums sumJointSystem(const JointInputs& in, const Pose2& pose, double c, const JointLimits& limits,
                         VectorKernels kernels) {
#if POLARSLAM_AVX2_KERNELS
  if (kernels == VectorKernels::Avx2 && vectorKernelsAvailable(kernels))
    return avx2::sumJointSystem(in, pose, c, limits);
#endif
  (void)kernels;
  return baseline::sumJointSystem(in, pose, c, limits);
}

SlopeFitSums sumSlopeFit(const SlopeFitInputs& in, double c, VectorKernels kernels) {
#if POLARSLAM_AVX2_KERNELS
  if (kernels == VectorKernels::Avx2 && vectorKernelsAvailable(kernels)) return avx2::sumSlopeFit(in, c);
#endif
  (void)kernels;
  return baseline::sumSlopeFit(in, c);
}

}  // namespace polarslam
