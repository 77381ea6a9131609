#include "scanmatch/projection.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>

namespace polarslam {

void projectScan(const BeamGeometry& g, const PreparedScan& cur, const Pose2& pose, Projection& out) {
  static const VectorKernels widest = widestVectorKernels();
  projectScan(g, cur, pose, out, widest);
}

void projectScan(const BeamGeometry& g, const PreparedScan& cur, const Pose2& pose, Projection& out,
                 VectorKernels kernels) {
  const size_t padded = cur.xf.size();
  out.range.assign(g.size, kInfF);
  out.tag.assign(g.size, kFlagEmpty);
  for (auto* v : {&out.px, &out.py, &out.index, &out.dx, &out.dy, &out.cross, &out.near_end}) v->resize(padded);
  for (auto* v : {&out.first, &out.count, &out.back_facing}) v->resize(padded);
  detail::projectReadings(g, cur, pose, out, kernels);
  // Raw pointers: the tag stores are bytes, which may alias anything, so the compiler would
  // otherwise reload every vector's data pointer after each of them.
  const float* cos_table = g.cos_float.data();
  const float* sin_table = g.sin_float.data();
  const float* dxs = out.dx.data();
  const float* dys = out.dy.data();
  const float* crosses = out.cross.data();
  const float* near_ends = out.near_end.data();
  const int32_t* firsts = out.first.data();
  const int32_t* counts = out.count.data();
  const int32_t* back_facing = out.back_facing.data();
  float* range = out.range.data();
  uint8_t* tag = out.tag.data();
  const size_t m = cur.size();
  for (size_t i = 1; i < m; ++i) {
    const int32_t count = counts[i];
    if (count == 0) continue;
    const float dx = dxs[i], dy = dys[i], cross = crosses[i];
    const uint8_t sample_tag = back_facing[i] ? kFlagOccluded : 0;
    const int32_t end = firsts[i] + count;
    for (int32_t j = firsts[i]; j < end; ++j) {
      // The ray t·u_j meets the line a + λ·d at t = (a × d)/(u_j × d).
      float r = cross / (cos_table[j] * dy - sin_table[j] * dx);
      if (!(r > 0.0f && r < kInfF)) r = near_ends[i];  // the segment lies along the ray
      if (r < range[j]) {
        range[j] = r;
        tag[j] = sample_tag;
      }
    }
  }
}

}  // namespace polarslam
