#include "scanmatch/projection.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>

namespace polarslam {
namespace {

// Four lanes of SSE through the compiler's vector extension (GCC and Clang): the per-reading
// work (transform, atan2, the pair's bearing span and line) is done four readings at a time.
using Floats = float __attribute__((vector_size(16)));
using Ints = int32_t __attribute__((vector_size(16)));
static_assert(sizeof(Floats) == kSimdWidth * sizeof(float));

/// A projected reading within this many beams of a reference bearing counts as on it; covers
/// the single-precision bearing (≈ 3e-7 rad). The straight line is extended by at most this.
constexpr float kIndexSnap = 1e-3f;

Floats splat(float v) { return Floats{v, v, v, v}; }
Ints splat(int32_t v) { return Ints{v, v, v, v}; }

template <typename V>
V load(const void* p) {
  V v;
  std::memcpy(&v, p, sizeof(v));
  return v;
}
template <typename V>
void store(void* p, const V& v) {
  std::memcpy(p, &v, sizeof(v));
}

Ints floorToInts(Floats x) {
  const Ints t = __builtin_convertvector(x, Ints);  // truncates towards zero
  return t + (__builtin_convertvector(t, Floats) > x);  // a true comparison is −1
}
Ints ceilToInts(Floats x) {
  const Ints t = __builtin_convertvector(x, Ints);
  return t - (__builtin_convertvector(t, Floats) < x);
}
Floats minimum(Floats a, Floats b) { return a < b ? a : b; }
Floats maximum(Floats a, Floats b) { return a > b ? a : b; }
Ints minimum(Ints a, Ints b) { return a < b ? a : b; }
Ints maximum(Ints a, Ints b) { return a > b ? a : b; }
Floats absolute(Floats a) { return (Floats)((Ints)a & splat(INT32_MAX)); }
Floats squareRoot(Floats a) {
#if defined(__SSE__)
  return __builtin_ia32_sqrtps(a);
#else
  for (size_t k = 0; k < kSimdWidth; ++k) a[k] = std::sqrt(a[k]);
  return a;
#endif
}

/// Transforms the readings into the reference frame and takes the fractional index of their
/// bearing: atan2 by a degree-13 odd polynomial fitted to atan on [0, 1] (2.5e-7 rad), folded
/// by octant. Bearings are measured from the middle of the reference field of view, so the
/// atan2 cut lies behind it: no wrap handling is needed for any field of view below 360°.
void projectReadings(const PreparedScan& cur, const Pose2& pose, const BeamGeometry& g, Projection& out) {
  const double centre = g.centre();
  const Floats c = splat(static_cast<float>(std::cos(pose.theta)));
  const Floats s = splat(static_cast<float>(std::sin(pose.theta)));
  const Floats tx = splat(static_cast<float>(pose.x)), ty = splat(static_cast<float>(pose.y));
  const Floats cc = splat(static_cast<float>(std::cos(centre))), sc = splat(static_cast<float>(std::sin(centre)));
  const Floats scale = splat(static_cast<float>(1.0 / g.angle_increment));
  const Floats offset = splat(static_cast<float>((centre - g.angle_min) / g.angle_increment));
  const Floats zero = splat(0.0f), one = splat(1.0f);
  const Floats half_pi = splat(static_cast<float>(std::numbers::pi / 2)), pi = splat(static_cast<float>(std::numbers::pi));
  for (size_t i = 0; i < cur.xf.size(); i += kSimdWidth) {
    const Floats x = load<Floats>(&cur.xf[i]), y = load<Floats>(&cur.yf[i]);
    const Floats wx = c * x - s * y + tx, wy = s * x + c * y + ty;
    store(&out.px[i], wx);
    store(&out.py[i], wy);
    const Floats rx = cc * wx + sc * wy, ry = cc * wy - sc * wx;
    const Floats ax = absolute(rx), ay = absolute(ry);
    const Ints steep = ay > ax;
    const Floats hi = steep ? ay : ax, lo = steep ? ax : ay;
    const Floats t = lo / (hi > zero ? hi : one);
    const Floats t2 = t * t;
    Floats p = splat(0.0068117926084996089f);
    p = p * t2 - 0.033604219141669806f;
    p = p * t2 + 0.079623671861603337f;
    p = p * t2 - 0.13233342168074008f;
    p = p * t2 + 0.19807815629220374f;
    p = p * t2 - 0.33317368071454784f;
    p = p * t2 + 0.99999611156178192f;
    Floats a = p * t;
    a = steep ? half_pi - a : a;
    a = rx < zero ? pi - a : a;
    a = (Floats)((Ints)a | ((Ints)ry & splat(INT32_MIN)));  // sign of ry
    store(&out.index[i], a * scale + offset);
  }
}

/// For every pair (i−1, i) of one segment: the reference bearings strictly inside its bearing
/// span (§6.3: j0 = ⌈a0⌉, j1 = ⌊a1⌋ in beam units), whether it is seen from behind (bearings
/// increase with index, so a front face keeps their order), and the line through the two.
void spanPairs(const PreparedScan& cur, const BeamGeometry& g, Projection& out) {
  const Floats snap = splat(kIndexSnap);
  const Floats half_turn = splat(static_cast<float>(std::numbers::pi / g.angle_increment));
  const Ints last = splat(static_cast<int32_t>(g.size) - 1), none = splat(0);
  const float* index = out.index.data();
  const float* px = out.px.data();
  const float* py = out.py.data();
  for (size_t i = 0; i < cur.xf.size(); i += kSimdWidth) {
    const Floats u1 = load<Floats>(index + i), x1 = load<Floats>(px + i), y1 = load<Floats>(py + i);
    Floats u0, x0, y0;  // the previous reading of each lane (lane 0 of the first block has none)
    if (i == 0) {
      u0 = Floats{0.0f, index[0], index[1], index[2]};
      x0 = Floats{0.0f, px[0], px[1], px[2]};
      y0 = Floats{0.0f, py[0], py[1], py[2]};
    } else {
      u0 = load<Floats>(index + i - 1);
      x0 = load<Floats>(px + i - 1);
      y0 = load<Floats>(py + i - 1);
    }
    const Ints j0 = maximum(ceilToInts(minimum(u0, u1) - snap), none);
    const Ints j1 = minimum(floorToInts(maximum(u0, u1) + snap), last);
    // A pair spanning more than half a turn crosses the cut behind the reference laser.
    const Ints usable = load<Ints>(&cur.pair_mask[i]) & (absolute(u1 - u0) <= half_turn);
    store(&out.first[i], j0);
    store(&out.count[i], maximum(j1 - j0 + 1, none) & usable);
    store(&out.back_facing[i], (Ints)(u1 < u0));
    const Floats dx = x1 - x0, dy = y1 - y0;
    store(&out.dx[i], dx);
    store(&out.dy[i], dy);
    store(&out.cross[i], x0 * dy - y0 * dx);
    store(&out.near_end[i], squareRoot(minimum(x0 * x0 + y0 * y0, x1 * x1 + y1 * y1)));
  }
}

}  // namespace

void projectScan(const BeamGeometry& g, const PreparedScan& cur, const Pose2& pose, Projection& out) {
  const size_t padded = cur.xf.size();
  out.range.assign(g.size, kInfF);
  out.tag.assign(g.size, kFlagEmpty);
  for (auto* v : {&out.px, &out.py, &out.index, &out.dx, &out.dy, &out.cross, &out.near_end}) v->resize(padded);
  for (auto* v : {&out.first, &out.count, &out.back_facing}) v->resize(padded);
  projectReadings(cur, pose, g, out);
  spanPairs(cur, g, out);
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
