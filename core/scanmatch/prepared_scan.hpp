#pragma once
// A scan preprocessed once for matching (docs/algorithms.md §4): bearings made increasing, optional
// decimation, median filter on a copy of the ranges, far-point flags, segmentation, Cartesian
// points, and the masked arrays the orientation search reads. Matching never allocates per
// scan pair: everything that depends on one scan alone is here.
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include "laser/laser_scan.hpp"
#include "scanmatch/beam_geometry.hpp"
#include "scanmatch/psm_params.hpp"

namespace polarslam {

/// Scans are padded to this many readings for the vectorised projection (AVX2: eight floats).
inline constexpr size_t kSimdWidth = 8;
/// A bearing without a reading, in float range arrays.
inline constexpr float kInfF = std::numeric_limits<float>::infinity();

/// Reading flags (§3.2). Only kFlagRange is set on prepared scans; projection adds the others.
enum : uint8_t {
  kFlagRange = 1,     ///< PM_RANGE: no return, too far or too near
  kFlagMoving = 2,    ///< PM_MOVING (reserved)
  kFlagMixed = 4,     ///< PM_MIXED (reserved)
  kFlagOccluded = 8,  ///< PM_OCCLUDED: projected sample of a surface seen from behind
  kFlagEmpty = 16,    ///< PM_EMPTY: no projected sample at this bearing
};

struct CorridorInfo {
  bool is_corridor = false;
  double angle = 0.0;       ///< direction of the corridor axis in the laser frame, [0, π)
  double spread = 0.0;      ///< smallest std of the smoothed wall directions (rad)
};

struct PreparedScan {
  int64_t utime = 0;
  std::shared_ptr<const BeamGeometry> geometry;
  std::vector<float> range;       ///< median-filtered ranges (m); +inf = no return
  std::vector<uint8_t> flags;
  std::vector<int32_t> segment;   ///< segment id, 0 = isolated reading (§4.3)
  /// −1 where readings i−1 and i are in one segment (projection interpolates between them),
  /// 0 elsewhere; zero-padded like xf.
  std::vector<int32_t> pair_mask;
  std::vector<double> x, y;       ///< Cartesian points of the filtered ranges (0 where flagged)
  /// The same points in single precision, zero-padded to a multiple of kSimdWidth, for the
  /// vectorised projection.
  std::vector<float> xf, yf;
  std::vector<float> masked_range;///< range where usable, 0 otherwise (orientation search)
  std::vector<float> mask;        ///< 1 where usable, 0 otherwise
  std::vector<float> slope;       ///< dr/dj (m per beam) inside a segment (5-point fit), NaN elsewhere
  /// var(slope)/σ_r² of each fitted slope, 3/(k(k+1)(2k+1)) for a fit over i−k…i+k (NaN where no slope).
  std::vector<float> slope_variance;
  /// The reference-only part of PSM's surface Jacobian (§11.1), per bearing: ρ = (∂r/∂φ)/r
  /// (NaN where the slope is unknown), cos β = 1/√(1+ρ²), the unit surface normal terms
  /// (cos φ + ρ sin φ)·cos β and (sin φ − ρ cos φ)·cos β, and ρ·cos β.
  struct SurfaceTerms {
    std::vector<double> rho, cos_beta, normal_x, normal_y, rho_cos_beta;
    /// var(β)/σ_r², β = atan ρ the angle between ray and surface normal, from the slope's fit.
    std::vector<double> beta_variance;
  } surface;
  int valid_count = 0;

  size_t size() const { return range.size(); }
  bool bad(size_t i) const { return flags[i] != 0; }
  bool empty() const { return range.empty(); }
};

/// Preprocesses a scan for PSM, PSM-C and ICP. The scan must pass validateScan().
PreparedScan prepareScan(const LaserScan& scan, const PsmParams& params);

/// 5-point median filter with clamped indices (§4.1), out of place.
void medianFilter5(const std::vector<float>& in, std::vector<float>& out);

/// Segmentation of §4.3 on filtered ranges; `bad` marks flagged readings.
void segmentScan(const std::vector<float>& range, const std::vector<uint8_t>& flags, double max_distance,
                 std::vector<int32_t>& segment);

/// Corridor test and corridor direction of §11.2 (parts 2 and 3), with the v0.3 bug of the
/// ineffective second-pass median fixed (§14.4). Only the heuristic covariance needs it, so it
/// is computed when asked for, not with every scan (it would be 40 % of a scan's preparation).
CorridorInfo detectCorridor(const PreparedScan& scan, double threshold);

}  // namespace polarslam
