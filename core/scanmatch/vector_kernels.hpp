#pragma once
// The vector instruction sets the scan matcher's inner loops (projection, joint system) run on.
// Each kernel set adds the same terms in the same order, so every one gives the same bits; the
// matcher uses the widest the processor has, chosen at run time.

// GCC's target pragmas compile the AVX2 kernels into any x86-64 build.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define POLARSLAM_AVX2_KERNELS 1
#else
#define POLARSLAM_AVX2_KERNELS 0
#endif

namespace polarslam {

enum class VectorKernels { Baseline, Avx2 };

bool vectorKernelsAvailable(VectorKernels kernels);
/// The widest kernels this processor runs.
VectorKernels widestVectorKernels();
const char* vectorKernelsName(VectorKernels kernels);

}  // namespace polarslam
