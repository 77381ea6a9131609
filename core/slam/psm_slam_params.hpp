#pragma once
// Parameters of PSM SLAM (psm_slam.hpp), SI units and radians. Defaults were tuned on the MIT
// CSAIL log and checked on the simulated office (docs/algorithms.md).
#include <string>

#include "odometry/odometry_model.hpp"
#include "config/parameter_table.hpp"
#include "scanmatch/psm_params.hpp"
#include "slam/pose_graph.hpp"

namespace polarslam {

/// The end of a run: every reference scan is matched against the other reference scans that
/// overlap it, not only the one it was tracked against, and each good match becomes a graph
/// edge (docs/algorithms.md §18): the per-match noise that one edge per scan leaves in the map
/// averages out over several.
struct GraphRefinementParams {
  /// Off by default: docs/algorithms.md §18 says what it gains and what still stands in its way.
  bool enabled = false;
  /// Pairs of reference scans at most this far apart and this much turned, not yet joined by an
  /// edge, are matched; of each scan's pairs with earlier scans, the nearest max_pairs_per_scan.
  double max_distance = 2.5;             ///< m
  double max_heading = deg2rad(90.0);
  int max_pairs_per_scan = 12;
  /// A match counts when its error index is that of a good tracking match, its overlap at least
  /// min_overlap (the loop closures' 0.15 and a little), and it lands within agree_translation /
  /// agree_rotation of where the optimised graph puts the pair (a match that far off converged
  /// elsewhere; the robust loss and χ² rejection deal with the subtler ones).
  double max_error_index = 0.10;         ///< m
  double min_overlap = 0.2;
  double agree_translation = 0.3;        ///< m
  double agree_rotation = deg2rad(5.0);
  /// Also during the run: after each loop-closure optimisation the pairs of reference scans the
  /// filter no longer holds are matched in the background, their edges joining the graph at the
  /// next one. Off: the live poses get worse (each optimisation moves the filter's keyframes by
  /// information it does not hold), and the final map no better (docs/algorithms.md §18).
  bool online = false;
};

/// Localisation in a stored map (map_localizer.hpp): `polarslam run --load-map M --mode localize`.
struct MapLocalizationParams {
  /// Once placed in the map, the robot is tracked by PSM SLAM over the map held fixed, with
  /// temporary reference scans of its own for ground the map does not hold (never saved; like
  /// Cartographer's pure localisation): docs/maps.md. Off: the map's reference scans only, and a
  /// single local reference on new ground (map_localizer.hpp).
  bool temporary_mapping = true;
  /// Tracking: reference scans within this distance and heading of the predicted pose are
  /// matched, nearest first, at most track_candidates of them per scan.
  double track_radius = 2.0;             ///< m
  double track_heading = deg2rad(90.0);
  int track_candidates = 2;
  /// This many scans in a row that match neither the map nor the local reference (new ground,
  /// map_localizer.hpp): the robot is lost (kidnapped, or its odometry failed) and the global
  /// search takes over.
  int lost_after_scans = 5;
  /// This many scans in a row with reference scans within track_radius but no match with the map
  /// (even if new-ground tracking placed them): lost too.
  int lost_near_map_after_scans = 100;
  /// On new ground, the robot is lost once its position's standard deviation exceeds this:
  /// tracking could not pick the map up from so vague a pose.
  double max_off_map_sigma = 1.0;        ///< m
  /// While lost, a search is repeated only once the robot has moved this far or turned this much:
  /// the same view gives the same answer, every search matches every reference scan, and a hit is
  /// confirmed only by a search from another viewpoint.
  double global_search_spacing = 0.25;   ///< m
  double global_search_turn = deg2rad(15.0);
  /// Global search (correlative_search.hpp): every robot pose within global_region_radius of a
  /// reference pose, at every heading, is scored by how well at most global_points readings of the
  /// scan lie on the map's points (a likelihood field of spread global_sigma on a grid of
  /// global_resolution). The best needs global_min_score; another pose elsewhere (more than
  /// global_ambiguity_distance or loop_ambiguity_heading away) within global_score_margin of it,
  /// and misfitting (1 − score) at most global_misfit_ratio times as much, makes the search
  /// ambiguous: no fix. The best is then refined by PSM with the reference scans
  /// nearest to it. While lost, the scans seen since within global_sequence_distance of the
  /// robot, placed by dead reckoning, are scored with it: a longer view tells look-alikes apart.
  double global_sequence_distance = 4.0;  ///< m
  double global_resolution = 0.05;       ///< m
  double global_sigma = 0.1;             ///< m
  double global_region_radius = 1.5;     ///< m
  int global_points = 64;
  double global_min_score = 0.65;
  double global_score_margin = 0.05;
  double global_misfit_ratio = 2.0;
  /// A PSM refinement needs this overlap (stricter than tracking) and loop_max_error_index.
  double global_min_overlap = 0.5;
  /// The refined pose must fit the whole scan to the map (map_fit_field.hpp): at least
  /// global_min_fit of its readings within global_fit_distance of a map point.
  double global_fit_distance = 0.1;      ///< m
  double global_min_fit = 0.7;
  /// A hit whose rays cross the map more than global_see_through_clearance before their
  /// endpoints (seeing through a mapped wall) on more than this fraction of the scan is refused.
  /// (Not applied to tracking: rays grazing door jambs would count, and a tracked pose is local.)
  double global_max_see_through = 0.1;
  double global_see_through_clearance = 0.5;  ///< m
  double global_ambiguity_distance = 0.5;  ///< m
  /// While tracked: a scan near the map's reference scans with less than this fraction of its
  /// readings within global_fit_distance of the map starts a doubt (MapLocalizer::doubt).
  double doubt_max_fit = 0.95;
  /// The hit of the next search must agree with the previous one after the odometry in between.
  double confirm_translation = 0.15;     ///< m
  double confirm_rotation = deg2rad(5.0);
  /// ... unless the hit's scans were seen along at least this much path: the search has then
  /// placed views from several viewpoints already, which the next one would mostly repeat
  /// (m; 0: always a confirming search).
  double confirm_sequence_length = 1.5;
  /// Temporary mapping: the fix that ends the search after a loss re-places the lost stretch's
  /// scans since its last map match (they drifted on their own reference scans) when it moves the
  /// stretch's last pose by at most tail_max_shift + tail_shift_per_metre·d and turns it by at most
  /// tail_max_turn + tail_turn_per_metre·d, d the distance travelled since that match: drift, not
  /// a kidnapping (map_localization_estimator.hpp).
  double tail_max_shift = 0.5;           ///< m
  double tail_shift_per_metre = 0.1;
  double tail_max_turn = deg2rad(5.0);
  double tail_turn_per_metre = deg2rad(1.0);  ///< rad per m
};

struct PsmSlamParams {
  PsmParams psm;                         ///< the matcher's own parameters
  MatchMethod method = MatchMethod::Psm;
  OdometryModelParams odometry;          ///< prediction: the §17.6 model

  // --- prediction ---
  /// Random-walk noise added per second of elapsed time, on top of the odometry model: real
  /// odometry goes stale for a scan or two and wheels slip, and a prior tighter than the match
  /// would make the χ² gate reject good matches.
  double time_noise_xy = 2e-4;           ///< m²/s
  /// MIT CSAIL tracking innovations: heading σ ≈ 1-3° per scan (5 Hz) on most scans beyond the
  /// §17.6 model; 2e-3 rad²/s gives ≈ 1.2° per scan, and the rarer larger jumps are left to the
  /// odometry-fault path (max_odometry_fault_*).
  double time_noise_theta = 2e-3;        ///< rad²/s
  /// Without any odometry the prior is the previous scan-to-scan motion (constant velocity)
  /// with this much extra noise per second.
  double no_odometry_noise_xy = 0.5;     ///< m²/s
  double no_odometry_noise_theta = 0.5;  ///< rad²/s

  /// When the odometry prior and the previous scan-to-scan motion differ by more than this, the
  /// scan is matched from both and the better match is kept.
  double odometry_check_translation = 0.05;  ///< m
  double odometry_check_rotation = deg2rad(3.0);

  // --- matches ---
  double match_cov_scale = 1.0;          ///< multiplies the matcher's covariance
  /// The smallest match covariance the filter accepts (the matcher's WLS covariance can be
  /// optimistic on feature-rich scans).
  double min_match_sigma_xy = 0.01;      ///< m
  double min_match_sigma_theta = deg2rad(0.3);
  double max_error_index = 0.10;         ///< m: a larger mean residual is a bad match
  /// Associated bearings over the smaller of the two scans' usable readings.
  double min_overlap = 0.35;
  double chi2_gate = 16.27;              ///< χ²₃(0.999) on the innovation of a tracking match
  /// A good tracking match outside the gate is taken as an odometry fault (the prior is inflated
  /// by the miss) when it is within these of the odometry prediction, or of the robot's previous
  /// motion (stale odometry catching up); otherwise the match is rejected.
  double max_odometry_fault_translation = 0.3;  ///< m
  double max_odometry_fault_rotation = deg2rad(30.0);
  /// ... and only when the odometry's own pose fits the reference scan markedly worse: its error
  /// index more than this times the match's. Where the scans allow two poses a few decimetres
  /// apart (a corridor's end seen from a turning robot), the odometry is then believed instead.
  double odometry_fault_fit_ratio = 1.5;

  // --- reference scans (keyframes) ---
  double keyframe_distance = 0.6;        ///< m from the active reference scan
  double keyframe_angle = deg2rad(25.0); ///< rad from the active reference scan
  double keyframe_min_overlap = 0.6;     ///< below this overlap a new reference is sought
  /// An existing reference scan is reused instead of adding one when the robot is this close
  /// to it (fractions of keyframe_distance / keyframe_angle) and the match overlaps as much.
  double reuse_fraction = 0.5;
  /// The filter keeps the last `filter_window` keyframes, and of the older ones only a sparse
  /// skeleton for loop closure: an older keyframe within `skeleton_spacing` (and
  /// `skeleton_heading` of heading) of an older one already kept is marginalised out of the
  /// filter (it stays in the pose graph and the map). The filter's cost per new keyframe is
  /// O(n²) in the keyframes it holds, so this keeps it proportional to the area mapped, not to
  /// the length of the run.
  int filter_window = 30;
  double skeleton_spacing = 1.5;         ///< m
  double skeleton_heading = deg2rad(60.0);
  /// Hard cap on keyframes in the filter: beyond it the oldest go, skeleton or not.
  size_t max_filter_keyframes = 1500;

  // --- stationary robot ---
  double stationary_odometry_translation = 1e-3;    ///< m between scans: odometry says still
  double stationary_odometry_rotation = deg2rad(0.05);
  double stationary_match_translation = 0.03;       ///< m: the match agrees it is still
  double stationary_match_rotation = deg2rad(1.0);

  // --- loop closure ---
  /// Keyframes the robot may be within this distance of (allowing for 3σ of pose uncertainty
  /// along the line to them) are loop-closure candidates.
  double loop_search_radius = 2.0;       ///< m
  /// Up to 90° apart a 180° laser still shares a quarter of its view with the keyframe's, and
  /// such closures are what ties a corridor driven both ways together (MIT CSAIL: 60° and an
  /// overlap of 0.5 leave 0.037 m of relation error, 90° and 0.3 give 0.028 m, without false
  /// closures: the χ² gate and the confirmation below guard them). A robot coming back across a
  /// place at an angle shares even less: MIT CSAIL's first half returns to a place it passed
  /// 54 s before with matches of 20-28 % overlap, and with 0.3 its map ended 1-1.5 m off there.
  double loop_max_heading_difference = deg2rad(90.0);
  double loop_candidate_sigmas = 3.0;    ///< Mahalanobis neighbourhood size
  /// Keyframes at least this many ids older than the active one count as loop closures.
  int loop_min_keyframe_gap = 15;
  int max_candidates_per_scan = 3;       ///< matches tried per new-reference decision
  double loop_max_error_index = 0.06;    ///< m: stricter than tracking
  double loop_min_overlap = 0.15;
  double loop_chi2_gate = 11.34;         ///< χ²₃(0.99) against the filter's prediction
  /// When the predicted position's σ exceeds this, a closure waits for a second one from
  /// another scan, within loop_confirm_scans scans, that agrees on the robot's motion in between
  /// within loop_confirm_translation / _rotation; the confirmed one then passes a wider gate
  /// (the filter is often over-confident after a long excursion).
  double loop_confirm_sigma = 0.15;      ///< m
  int loop_confirm_scans = 20;
  double loop_confirm_translation = 0.10;  ///< m
  double loop_confirm_rotation = deg2rad(2.0);
  double loop_confirmed_chi2_gate = 100.0;
  /// From a prior wider than this (σ), the second closure must come from at least
  /// loop_wide_confirm_distance farther along the path (at any age) instead.
  double loop_wide_prior_sigma = 1.0;       ///< m
  double loop_wide_confirm_distance = 2.0;  ///< m
  /// When the prior is wider than PSM's basin, guesses on a grid of this spacing over its
  /// loop_candidate_sigmas ellipse (at most loop_max_guesses, most likely first) are tried and
  /// the best converged match kept; one such wide search per reference decision.
  double loop_guess_spacing = 0.4;       ///< m
  int loop_max_guesses = 24;
  /// Those guesses also test uniqueness: when one converges, at about the same heading
  /// (loop_ambiguity_heading), on a place more than loop_ambiguity_distance from the best, with
  /// an error index within loop_ambiguity_ratio of the best one's, the scans fit elsewhere about
  /// as well (a corridor that hardly constrains the position along it, periodic features) and
  /// the closure is dropped. In the simulated glass-partition loop a ratio of 1.5 still let such
  /// closures through (3 of 20 runs ended 4 m off); 3 stopped them. With the closure checks added
  /// since (neighbour verification, confirmation, sonar planes) 2.5 lets none through, and 3 had
  /// refused every closure of glass-partition seed 7001: on the corridor back to the start its
  /// rivals were guesses stopped along the corridor at 2.8-3.0 times the best's error index, not
  /// a second fit. Convergence at another heading is a local minimum, not a look-alike place:
  /// counting it cost good closures in the office.
  double loop_ambiguity_distance = 0.5;  ///< m
  double loop_ambiguity_ratio = 2.5;
  double loop_ambiguity_heading = deg2rad(15.0);
  /// A closure from a wide prior (loop_confirm_sigma) is also checked against the other old
  /// reference scans near where it puts the robot (within loop_search_radius and
  /// loop_max_heading_difference), each matched from that pose: a good match that lands more
  /// than loop_verify_translation / _rotation from it refutes the closure (a look-alike place
  /// fits one reference scan, rarely its neighbours as well); one that agrees verifies it. When
  /// none of them matches and the prior's loop_candidate_sigmas extent exceeds
  /// loop_unverified_max_extent, the closure is refused: the robot may be at a look-alike place no
  /// search has looked at (simulated glass-partition loop: priors of σ 1.8-2.8 m after the
  /// laser-blind corridor gave closures 5 m off, and with the sonar's planes one of σ 1.3 m did
  /// still, on seed 5051; on MIT CSAIL σ stays below 0.9 m).
  double loop_verify_translation = 0.2;  ///< m
  double loop_verify_rotation = deg2rad(3.0);
  double loop_unverified_max_extent = 3.0;  ///< m
  /// Every loop closure is matched again from its prior with both scans' raw ranges, without the
  /// median filter (§4.1). A good, unambiguous match that lands loop_verify_translation /
  /// _rotation from the closure refutes it when the raw ranges fit it markedly better: the
  /// closure's pose has an error index above loop_unfiltered_fit_ratio times the raw match's.
  /// Thin things (door jambs, mouldings 1-2 readings wide) are filtered away in one view and kept
  /// in the other, and the rest can then fit best 0.3 m along a corridor (core/scanmatch/README.md).
  /// Off by itself when the median filter is.
  bool loop_check_unfiltered = true;
  double loop_unfiltered_fit_ratio = 1.1;
  /// Orientation window of the matcher's first orientation step for loop candidates.
  double loop_search_window = deg2rad(45.0);

  // --- global optimisation ---
  PoseGraphOptimizerOptions graph;
  bool optimize_on_loop = true;
  /// Loop closures within this many new keyframes of the last optimisation wait for the next one
  /// (the filter has already applied them); the end of the run always optimises.
  int min_keyframes_between_optimizations = 15;

  // --- refinement (psm_slam_refinement.cpp) ---
  GraphRefinementParams refinement;

  // --- localisation in a stored map ---
  MapLocalizationParams localization;
};

/// Every parameter above as a configuration key (the keys of config/psm-slam.yaml, angles in
/// degrees), bound to `params`.
void describePsmSlamParams(ParameterTable& table, PsmSlamParams& params);

}  // namespace polarslam
