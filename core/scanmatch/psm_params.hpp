#pragma once
// Parameters of PSM, PSM-C and the ICP baseline in SI units (docs/algorithms.md §13, converted from
// the original centimetre constants). Defaults are the thesis-era SICK LMS values unless a
// comment says why polarslam departs from them.
#include <string>

#include "geometry/pose2.hpp"

namespace polarslam {

enum class MatchMethod { Psm, PsmC, Icp };
const char* methodName(MatchMethod method);
/// "psm", "psm-c" or "icp"; returns false for anything else.
bool parseMatchMethod(const std::string& name, MatchMethod& method);

/// Which step PSM runs first when it alternates translation (T) and orientation (R) (§9).
enum class IterationOrder {
  TranslationFirst,  ///< v0.2: T, R, T, R, ...
  OrientationFirst,  ///< v0.3: R, T, R, T, ...
};

/// How the orientation step places its minimum between two range shifts (§8).
enum class OrientationRefinement {
  Parabola,  ///< the original: a parabola through e(k−1), e(k), e(k+1)
  /// Least squares on the reference range profile's slope: P_i ≈ R(i + k + δ). The L1 cost is
  /// V-shaped at the minimum, so the parabola's vertex is biased by the asymmetry of the two
  /// sides (up to half a beam); the slope step has its fixed point at the true rotation.
  Gradient,
};

enum class CovarianceModel {
  Heuristic,  ///< §11.2: scaled constant covariance, stretched along a detected corridor
  Wls,        ///< §11.1 reconstruction: σ̂²(HᵀWH)⁻¹ with the surface-consistent 3-DOF Jacobian
};
const char* covarianceModelName(CovarianceModel model);
bool parseCovarianceModel(const std::string& name, CovarianceModel& model);

/// Constants of the heuristic covariance (§11.2 table). v0.3: 20 cm / 4°, corridor 400 / 30 cm;
/// the older (likely thesis-era) set is 10 cm / 2°, corridor 400 / 10 cm.
struct HeuristicCovarianceParams {
  double sigma_xy = 0.20;                 ///< PM_MIN_STD_XY, m
  double sigma_theta = deg2rad(4.0);      ///< PM_MIN_STD_ORIENTATION
  double sigma_along = 4.0;               ///< corridor, along its axis, m
  double sigma_across = 0.30;             ///< corridor, across, m
  double error_offset_cm = 5.0;           ///< PM_MATCH_ERROR_OFFSET; the scale is computed in cm (§14.8)
  static HeuristicCovarianceParams v03() { return {}; }
  static HeuristicCovarianceParams thesis() { return {0.10, deg2rad(2.0), 4.0, 0.10, 5.0}; }
};

struct PsmParams {
  // --- preprocessing (§4) ---
  bool median_filter = true;          ///< window 5 (§4.1), on a copy of the ranges
  /// A reading is replaced by its median only when they differ by more than this (m). 0 is the
  /// original, which replaces every reading and so rounds corners differently from different
  /// viewpoints (a bias of millimetres); a threshold still removes legs and spurious readings.
  double median_replace_threshold = 0.0;
  double max_range = 10.0;            ///< PM_MAX_RANGE: farther readings are flagged (§4.2)
  double min_range = 0.10;            ///< PM_MIN_RANGE: nearer readings and projections are unused
  double segment_max_distance = 0.20; ///< PM_SEG_MAX_DIST (§4.3)
  /// The slope of the range profile (the surface normal of the joint step and of the WLS
  /// covariance) is a least-squares line over at least two readings either side, and over at
  /// least this length of arc (m; at most 12 readings) where readings are denser: 1 cm of range
  /// noise over five readings half a metre away tilts a normal by about 20°, which claims
  /// information along a corridor that the ranges do not carry. 0 keeps five readings everywhere:
  /// 0.05 makes corridor covariances honest but is not the default yet (core/scanmatch/README.md).
  double slope_half_span = 0.0;
  int decimation = 1;                 ///< keep every n-th beam (2 reproduces the thesis 1° grid from 0.5° logs)

  // --- matching (§6–§9) ---
  int min_valid_points = 40;          ///< PM_MIN_VALID_POINTS
  /// The steps of PSM on the way to the answer need this fraction of min_valid_points (the answer
  /// itself all of them). From a guess 0.4 m and 20° off, fewer bearings associate than at the
  /// answer, and refusing to step there refused 1.2 % of the real MIT CSAIL pairs from 0.5 m / 30°
  /// (bench-scanmatch 7b) and narrowed the ±45° edges of the convergence map. 1 = the original.
  double step_min_points_fraction = 0.5;
  double search_window = deg2rad(20.0); ///< PM_SEARCH_WINDOW as an angle (20 readings at 1°)
  /// Orientation window of the first orientation step. The original searches ±20° every time,
  /// which bounds its basin (§3.1); a coarse-to-fine search makes a wider first window cheap.
  double initial_search_window = deg2rad(45.0);
  /// Coarse step of the coarse-to-fine orientation search (0 = exhaustive search, as the original).
  double coarse_search_step = deg2rad(3.0);
  double max_error = 1.0;             ///< PM_MAX_ERROR: residual gate (m)
  double weighting_factor = 0.49;     ///< C = 70² cm², w = C/(C + Δr²)
  double late_weighting_factor = 0.01;///< C after change_weight_iteration (v0.1/v0.2: 10² cm²)
  int change_weight_iteration = 10;   ///< PM_CHANGE_WEIGHT_ITER
  /// Before change_weight_iteration, C = (scale·ē)² within [late_weighting_factor,
  /// weighting_factor], ē the mean |Δr| of the residuals within max_error/2 at the current pose:
  /// a robust scale from the residuals, so that from a good guess what only one scan sees (the
  /// space behind a wall's end that the other passes by) does not pull as hard as the surfaces
  /// both see. 0 = the fixed C of the original; 4 is not the default yet (core/scanmatch/README.md).
  double adaptive_weighting_scale = 0.0;
  int max_iterations = 30;            ///< PM_MAX_ITER
  /// Stop after stop_count consecutive iterations with |Δx|+|Δy| < stop_translation and
  /// |Δθ| < stop_rotation (§9; the original 0.4 "cm + rad" rule is effectively the 4 mm test).
  double stop_translation = 0.004;
  double stop_rotation = deg2rad(0.1);
  int stop_count = 3;
  IterationOrder order = IterationOrder::OrientationFirst;
  OrientationRefinement orientation_refinement = OrientationRefinement::Gradient;
  /// Translation rows from the projected surface's slope (normal-distance residuals, i.e. a
  /// point-to-line step in polar form) instead of the original [cos φ, sin φ], which assumes
  /// every surface faces the laser and converges slowly along walls seen at grazing angles.
  bool surface_jacobian = true;
  /// Samples seen at a grazing incidence beyond this (|tan β|, 3 ≈ 72°) are left out of the
  /// slope-based steps: neither their slope nor their range is reliable.
  double max_slope = 3.0;
  /// Once the alternating steps are smaller than these, finish with joint (x, y, θ) Gauss–Newton
  /// steps on the same polar residuals with the surface-consistent Jacobian of §11.1 — a
  /// point-to-line refinement that converges in one or two projections instead of a tail of
  /// ever smaller alternating steps (docs/algorithms.md, appendix). false = the original alternation only.
  bool joint_refinement = true;
  double joint_switch_translation = 0.05;
  double joint_switch_rotation = deg2rad(2.0);

  // --- PSM-C (§10) ---
  int psmc_orientation_period = 4;    ///< explicit orientation search every 4th iteration

  // --- ICP baseline (§12) ---
  int icp_max_iterations = 60;              ///< PM_MAX_ITER_ICP
  double icp_stop_translation = 0.001;      ///< PM_STOP_COND_ICP = 0.1 (cm + deg), split as 1 mm ...
  double icp_stop_rotation = deg2rad(0.1);  ///< ... and 0.1°
  double icp_trim_fraction = 0.2;           ///< the worst 20 % of pairs are dropped
  /// Pair each current point with the closest point on the neighbouring reference segments
  /// instead of the reading itself: the v0.3 option added in March 2007, after the thesis.
  /// Off by default so that the baseline is the ICP the thesis compared against; plain
  /// point-to-point ICP on 1° scans has stable false minima near whole-beam rotations.
  bool icp_interpolate = false;

  // --- covariance (§11) ---
  CovarianceModel covariance = CovarianceModel::Wls;
  HeuristicCovarianceParams heuristic;
  double corridor_threshold = deg2rad(25.0);  ///< PM_CORRIDOR_THRESHOLD
  /// Multiplies the WLS covariance: neighbouring projected samples share current readings, so
  /// the residuals are correlated and σ̂²(HᵀWH)⁻¹ alone is over-confident (mean NEES 4.8 on
  /// simulated office pairs). Calibrated by NEES, see README.
  double wls_inflation = 1.5;
  /// Takes out of the WLS information what the noise of the reference's fitted slopes adds to it
  /// (an errors-in-variables effect: noisy normals claim information along a corridor that the
  /// ranges do not carry). See core/scanmatch/README.md, "Taking the slope noise's information out".
  bool slope_noise_correction = true;
  /// Added to the WLS covariance: errors the residuals cannot show (the straight-line
  /// interpolation, the bearing grid).
  double wls_floor_xy = 0.0005, wls_floor_theta = deg2rad(0.02);
  /// Lower bound of the residual σ̂ (m) the WLS covariance is scaled by.
  double wls_min_sigma = 0.003;
};

}  // namespace polarslam
