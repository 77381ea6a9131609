#pragma once
// Laser-aided selection of sonar measurements and sonar-aided laser segmentation (thesis
// §3.3.1; not recovered, designed here after the principle of docs/algorithms.md §17.1 items 1–2 and §17.4).
//
// Each sonar reflection point (an edge's point, a corner's apex, a plane's normal foot) is
// looked up in a laser scan taken at (or motion-compensated to) the same time:
//  - outside the laser's field of view, or only "no return" beams around it: the laser cannot
//    judge it (glass with nothing behind in range, open space) — kept;
//  - every laser return around it lies beyond it: it sits in laser-observed free space. Kept only
//    if a sonar plane passes through it (a glass wall the laser looks through), else spurious;
//  - every laser return around it lies in front of it: sound cannot pass a surface the laser
//    sees, so it is spurious (counted with the free-space ones);
//  - the laser sees a surface at it: a line or corner is consistent; a point (edge) is kept only
//    if the laser shows a break there — a segment end or corner of the laser features, a "no
//    return" neighbour, a range jump, a bend or step between the surfaces on either side, or a
//    bump: a short run of readings next to the point standing off the surface fitted to the
//    readings around it. A door jamb 4 cm deep is invisible to a jump detector at 1 cm range
//    noise, but tested exactly where the sonar says an edge is, the few readings on it stand out
//    from a reference line fitted to ~20 readings: this is where the sonar tells the laser where
//    to look. Segment ends the laser segmenter made at a sonar break hint are no evidence (they
//    would make the test circular) and are left out by FeatureFusion.
// Break hints: sonar corners and edges as bearings in the laser frame, for the laser segmenter.
#include <vector>

#include "geometry/features.hpp"
#include "laser/laser_scan.hpp"

namespace polarslam {

struct SonarSelectionParams {
  double laser_range_sigma = 0.012;  ///< m: laser range noise used by the gates and the break tests
  double gate_sigmas = 3.0;
  double gate_margin = 0.05;         ///< m: array–laser parallax, residual timing and mount errors
  int step_side_beams = 12;          ///< reference readings on each side beyond the bump radius
  int step_min_beams = 4;
  double step_max_extent = 0.5;      ///< m: readings farther than this from the point are not used
  double step_sigmas = 3.0;          ///< a step between the two sides larger than this many σ is a break
  double min_step = 0.01;            ///< m: smaller steps and bumps are not breaks
  double bend_angle = deg2rad(15.0); ///< the two sides' directions differing by more is a break
  double bump_radius = 0.12;         ///< m: readings this close to the point may belong to a jamb
  int bump_max_readings = 6;         ///< longest run of readings tested as a bump
  double bump_sigmas = 3.5;          ///< a run standing off the surface by more than this many σ is a bump
  double jump = 0.15;                ///< m: a range jump between neighbouring beams is a break
  double segment_end_gate = 0.10;    ///< m (added to the gate): laser segment ends this close support
};

enum class SonarVerdict : int8_t {
  LaserBreak,          ///< the laser shows a discontinuity at the sonar point
  LaserSegmentEnd,     ///< a laser segment end or corner lies at it
  LaserSurface,        ///< the laser sees a surface there, without a break
  NoLaserReturn,       ///< only "no return" beams around it
  OutsideLaserView,
  Glass,               ///< in laser free space, on a sonar plane
  FreeSpace,           ///< in laser free space: spurious
  BehindLaserSurface,  ///< behind a surface the laser sees: spurious
};
const char* toString(SonarVerdict verdict);

/// Laser evidence in the robot base frame at the scan's time.
struct LaserEvidence {
  const LaserScan* scan = nullptr;   ///< normalised scan (see normalizedScan), or null: no raw scan
  std::vector<Vec2> segment_ends;    ///< laser line endpoints and corner apexes
  std::vector<LineFeature> sonar_planes;  ///< sonar lines of the same time (glass evidence)
};

/// Where a sonar reflection point at `point` (base frame, covariance `cov`) stands.
SonarVerdict judgeSonarPoint(const Vec2& point, const Mat2& cov, const LaserEvidence& evidence,
                             const SonarSelectionParams& params);

struct SelectionCounts {
  int spurious = 0;     ///< in laser free space or behind a laser surface (all kinds)
  int unsupported = 0;  ///< points on a laser surface without a break
  int kept_unverified = 0;  ///< kept because the laser could not see there
  int kept_glass = 0;
  int kept_supported = 0;
};

/// Applies the rules above to sonar features (base frame, same time as the laser evidence).
/// Lines and corners are dropped only when spurious; points also when unsupported.
FeatureSet selectSonarFeatures(const FeatureSet& sonar, const LaserEvidence& evidence,
                               const SonarSelectionParams& params, SelectionCounts* counts = nullptr);

/// Laser evidence from a normalised raw scan, the laser features (any frame) and sonar features
/// (base frame). Laser segment ends within `hint_tolerance` of a bearing in `hint_bearings` (laser
/// frame: the break hints the segmenter was given) are left out.
LaserEvidence makeLaserEvidence(const LaserScan* normalized_scan, const FeatureSet& laser_features,
                                const FeatureSet& sonar_base, const std::vector<double>& hint_bearings = {},
                                double hint_tolerance = deg2rad(2.5));

struct BreakHint {
  double bearing = 0.0;  ///< rad, laser frame
  double range = 0.0;    ///< m, laser frame
  double bearing_sigma = 0.0;
  bool corner = false;   ///< from a sonar corner (else an edge)
};

/// Sonar corners and edges (base frame) as break hints for the laser segmenter, sorted by bearing.
std::vector<BreakHint> sonarBreakHints(const FeatureSet& sonar_base, const Pose2& laser_pose);

}  // namespace polarslam
