#pragma once
// Segmentation of a laser scan into line and right-angle corner candidates: range breaks
// (adaptive breakpoint detector), optional break hints (bearings, e.g. from sonar edges and
// corners, thesis §3.3.1), split-and-merge, and perpendicular neighbouring lines as corner
// candidates. Works on any beam count and field of view.
#include <span>
#include <vector>

#include "geometry/pose2.hpp"
#include "laser/polar_line_fit.hpp"

namespace polarslam {

struct SegmentationParams {
  int min_line_points = 6;           ///< fewer readings: not a line
  double min_line_length = 0.30;     ///< m, between the first and the last reading (shorter lines
                                     ///< next to small structures are not reliably consistent)
  double split_distance = 0.02;      ///< m: split when a reading is farther from the chord than this
  double split_sigmas = 3.0;         ///<   plus this many range σ
  double break_angle = deg2rad(10);  ///< λ of the adaptive breakpoint detector (Borges & Aldon)
  double break_sigmas = 3.0;         ///< σ added to its distance threshold
  int max_gap_beams = 1;             ///< invalid beams tolerated inside a segment
  double corner_tolerance = deg2rad(15);  ///< neighbouring lines at 90° ± this become a corner candidate
};

/// Readings first..last (inclusive) of the valid-reading sequence.
struct LineSegment {
  int first = 0, last = -1;
  int count() const { return last - first + 1; }
};

/// Two kept line segments that meet at a right angle: lines[first] is followed by lines[second].
struct CornerCandidate {
  int first = 0, second = 0;
};

struct Segmentation {
  std::vector<LineSegment> lines;
  std::vector<CornerCandidate> corners;
};

/// Segments the valid readings of a scan. `readings` are in increasing bearing order,
/// `beam_index[i]` is reading i's beam in the (normalised) scan; `break_bearings` are hinted breaks (a break goes before the first reading at or
/// beyond each bearing; a hinted break splits lines but still lets its two sides form a corner).
Segmentation segmentReadings(const PolarReadings& readings, std::span<const int> beam_index,
                             std::span<const double> break_bearings, double range_sigma,
                             const SegmentationParams& params = {});

}  // namespace polarslam
