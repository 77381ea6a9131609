#include "scanmatch/vector_kernels.hpp"

namespace polarslam {

bool vectorKernelsAvailable(VectorKernels kernels) {
  if (kernels == VectorKernels::Baseline) return true;
#if POLARSLAM_AVX2_KERNELS
  static const bool avx2 = __builtin_cpu_supports("avx2");
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

}  // namespace polarslam
