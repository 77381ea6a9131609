#pragma once
// Scan projection (docs/algorithms.md §6, thesis fig. 4.9): the current scan, seen from its pose in
// the reference laser frame, resampled at the reference bearings with z-buffering, so that
// readings associate by bearing. Between two readings of one segment the surface is the straight
// line through them and each reference ray is intersected with it (the original interpolates
// range linearly in bearing, which errs by millimetres on walls seen at grazing angles).
#include <cstdint>
#include <vector>

#include "geometry/pose2.hpp"
#include "scanmatch/beam_geometry.hpp"
#include "scanmatch/prepared_scan.hpp"
#include "scanmatch/vector_kernels.hpp"

namespace polarslam {

struct Projection {
  std::vector<float> range;   ///< projected range r''_j at reference bearing j; +inf where empty
  std::vector<uint8_t> tag;   ///< kFlagEmpty / kFlagOccluded, 0 = usable sample
  std::vector<float> px, py;  ///< current readings in the reference laser frame (padded)
  std::vector<float> index;   ///< fractional reference-bearing index of each current reading
  // Work arrays, one entry per reading pair (i−1, i): the first reference bearing it covers,
  // how many it covers, whether the surface is seen from behind, and the line through the two.
  std::vector<int32_t> first, count, back_facing;
  std::vector<float> dx, dy, cross;
  std::vector<float> near_end;  ///< range of the pair's nearer reading (for rays along the line)
};

/// Projects `cur`, whose laser sits at `pose` in the reference laser frame, onto the bearings of
/// `ref_geometry`. Samples of surfaces seen from behind hide what lies beyond them and are tagged
/// kFlagOccluded; bearings no segment covers are kFlagEmpty.
void projectScan(const BeamGeometry& ref_geometry, const PreparedScan& cur, const Pose2& pose, Projection& out);
/// The same with the given vector kernels (the baseline where they are not available); the
/// first form uses the widest the processor has. Each gives the same bits.
void projectScan(const BeamGeometry& ref_geometry, const PreparedScan& cur, const Pose2& pose, Projection& out,
                 VectorKernels kernels);

namespace detail {
/// projectScan's work reading by reading, before its z-buffer (vector_kernels.cpp): each reading
/// in the reference frame and its bearing index, each pair's bearing span and line.
void projectReadings(const BeamGeometry& ref_geometry, const PreparedScan& cur, const Pose2& pose, Projection& out,
                     VectorKernels kernels);
}  // namespace detail

}  // namespace polarslam
