#include "slam/psm_slam_params.hpp"

namespace polarslam {
namespace {

void describeMatcher(ParameterTable& t, PsmParams& p) {
  t.number("max_range", p.max_range, 0.5, 100.0, "m: farther readings are not matched");
  t.number("min_range", p.min_range, 0.0, 10.0, "m: nearer readings are not matched");
  t.boolean("median_filter", p.median_filter, "5-reading median filter: removes legs and other 1-2 reading objects");
  t.number("median_replace_threshold", p.median_replace_threshold, 0.0, 10.0,
           "m: the median filter replaces a reading only when it differs more");
  t.number("segment_max_distance", p.segment_max_distance, 0.01, 10.0, "m between neighbours of one segment");
  t.number("slope_half_span", p.slope_half_span, 0.0, 1.0, "m: surface slopes fitted over this much arc either side at least");
  t.integer("decimation", p.decimation, 1, 100, "keep every n-th beam");
  t.integer("min_valid_points", p.min_valid_points, 3, 100000, "fewer usable readings: no match");
  t.number("step_min_points_fraction", p.step_min_points_fraction, 0.05, 1.0,
           "the steps on the way need this fraction of min_valid_points (1 = the original)");
  t.angle("search_window_deg", p.search_window, 0.5, 180.0, "orientation search window");
  t.angle("initial_search_window_deg", p.initial_search_window, 0.5, 180.0, "first orientation step's window");
  t.angle("coarse_search_step_deg", p.coarse_search_step, 0.0, 45.0, "coarse-to-fine step (0 = exhaustive)");
  t.number("max_error", p.max_error, 0.01, 100.0, "m: residual gate");
  t.number("adaptive_weighting_scale", p.adaptive_weighting_scale, 0.0, 100.0,
           "early robust weights' scale in error indices (0 = the original fixed C)");
  t.integer("max_iterations", p.max_iterations, 1, 10000, "iterations at most");
  t.number("stop_translation", p.stop_translation, 0.0, 1.0, "m: convergence test");
  t.angle("stop_rotation_deg", p.stop_rotation, 0.0, 10.0, "convergence test");
  t.number("joint_switch_translation", p.joint_switch_translation, 0.0, 10.0,
           "m: alternating steps below this (and the rotation below) switch to joint (x, y, θ) steps");
  t.angle("joint_switch_rotation_deg", p.joint_switch_rotation, 0.0, 180.0, "the same for the orientation step");
  t.choice(
      "covariance", {"wls", "heuristic"}, [&p](const std::string& w) { return parseCovarianceModel(w, p.covariance); },
      [&p] { return std::string(covarianceModelName(p.covariance)); }, "match covariance model");
  t.number("wls_inflation", p.wls_inflation, 0.1, 100.0, "multiplies the WLS covariance");
  t.boolean("slope_noise_correction", p.slope_noise_correction,
            "WLS covariance without the information the reference's slope noise claims");
}

void describeOdometry(ParameterTable& t, PoseIncrementErrorParams& p) {
  t.number("k_distance", p.k_distance, 0.0, 1.0, "m²/m: distance variance per metre");
  t.number("k_heading_per_rad", p.k_heading_per_rad, 0.0, 1.0, "rad²/rad: heading variance per radian turned");
  t.number("k_heading_per_m", p.k_heading_per_m, 0.0, 1.0, "rad²/m: heading variance per metre travelled");
}

void describePrediction(ParameterTable& t, PsmSlamParams& p) {
  t.number("time_noise_xy", p.time_noise_xy, 0.0, 100.0, "m²/s: random walk on top of the odometry model");
  t.number("time_noise_theta", p.time_noise_theta, 0.0, 100.0, "rad²/s: heading random walk");
  t.number("no_odometry_noise_xy", p.no_odometry_noise_xy, 0.0, 1e4, "m²/s without odometry");
  t.number("no_odometry_noise_theta", p.no_odometry_noise_theta, 0.0, 1e4, "rad²/s without odometry");
  t.number("odometry_check_translation", p.odometry_check_translation, 0.0, 10.0,
           "m: odometry and previous motion this far apart: match from both");
  t.angle("odometry_check_rotation_deg", p.odometry_check_rotation, 0.0, 180.0, "the same for heading");
}

void describeMatches(ParameterTable& t, PsmSlamParams& p) {
  t.number("match_cov_scale", p.match_cov_scale, 0.01, 100.0, "multiplies the matcher's covariance");
  t.number("min_match_sigma_xy", p.min_match_sigma_xy, 0.0, 10.0, "m: smallest match standard deviation");
  t.angle("min_match_sigma_theta_deg", p.min_match_sigma_theta, 0.0, 45.0, "smallest heading standard deviation");
  t.number("max_error_index", p.max_error_index, 0.0, 10.0, "m: mean residual of a good match at most");
  t.number("min_overlap", p.min_overlap, 0.0, 1.0, "associated fraction of a good match at least");
  t.number("chi2_gate", p.chi2_gate, 0.0, 1e6, "χ² gate on a tracking match's innovation");
  t.number("max_odometry_fault_translation", p.max_odometry_fault_translation, 0.0, 100.0,
           "m: a gated-out match this close to odometry or previous motion is an odometry fault");
  t.angle("max_odometry_fault_rotation_deg", p.max_odometry_fault_rotation, 0.0, 180.0, "the same for heading");
  t.number("odometry_fault_fit_ratio", p.odometry_fault_fit_ratio, 0.0, 1e6,
           "... if the odometry's pose misfits (error index) more than this times the match");
}

void describeReferences(ParameterTable& t, PsmSlamParams& p) {
  t.number("keyframe_distance", p.keyframe_distance, 0.01, 100.0, "m from the active reference scan: new one");
  t.angle("keyframe_angle_deg", p.keyframe_angle, 0.1, 180.0, "from the active reference scan: new one");
  t.number("keyframe_min_overlap", p.keyframe_min_overlap, 0.0, 1.0, "below this overlap: new reference");
  t.number("reuse_fraction", p.reuse_fraction, 0.0, 1.0, "of the keyframe distances: reuse an old reference");
  t.integer("filter_window", p.filter_window, 1, 100000, "recent reference scans kept in the filter");
  t.number("skeleton_spacing", p.skeleton_spacing, 0.0, 1000.0, "m between older references kept in the filter");
  t.angle("skeleton_heading_deg", p.skeleton_heading, 0.0, 360.0, "heading apart to keep both");
  t.count("max_filter_keyframes", p.max_filter_keyframes, 2, 1000000, "reference scans in the filter at most");
}

void describeStationary(ParameterTable& t, PsmSlamParams& p) {
  t.number("stationary_odometry_translation", p.stationary_odometry_translation, 0.0, 1.0,
           "m between scans: odometry says still");
  t.angle("stationary_odometry_rotation_deg", p.stationary_odometry_rotation, 0.0, 45.0, "the same for heading");
  t.number("stationary_match_translation", p.stationary_match_translation, 0.0, 1.0, "m: the match agrees");
  t.angle("stationary_match_rotation_deg", p.stationary_match_rotation, 0.0, 45.0, "the same for heading");
}

void describeLoops(ParameterTable& t, PsmSlamParams& p) {
  t.number("loop_search_radius", p.loop_search_radius, 0.0, 1000.0, "m: loop-closure candidates within");
  t.angle("loop_max_heading_difference_deg", p.loop_max_heading_difference, 0.0, 180.0, "candidates within");
  t.number("loop_candidate_sigmas", p.loop_candidate_sigmas, 0.0, 100.0, "Mahalanobis neighbourhood");
  t.integer("loop_min_keyframe_gap", p.loop_min_keyframe_gap, 1, 1000000, "ids older than the active: a loop");
  t.integer("max_candidates_per_scan", p.max_candidates_per_scan, 1, 1000, "matches per reference decision");
  t.number("loop_max_error_index", p.loop_max_error_index, 0.0, 10.0, "m: stricter than tracking");
  t.number("loop_min_overlap", p.loop_min_overlap, 0.0, 1.0, "associated fraction at least");
  t.number("loop_chi2_gate", p.loop_chi2_gate, 0.0, 1e6, "χ² gate against the prediction");
  t.number("loop_confirm_sigma", p.loop_confirm_sigma, 0.0, 1000.0, "m: wider priors need a second closure");
  t.integer("loop_confirm_scans", p.loop_confirm_scans, 1, 100000, "the second within this many scans");
  t.number("loop_confirm_translation", p.loop_confirm_translation, 0.0, 100.0, "m: agreeing on the motion");
  t.angle("loop_confirm_rotation_deg", p.loop_confirm_rotation, 0.0, 180.0, "the same for heading");
  t.number("loop_confirmed_chi2_gate", p.loop_confirmed_chi2_gate, 0.0, 1e9, "χ² gate once confirmed");
  t.number("loop_wide_prior_sigma", p.loop_wide_prior_sigma, 0.0, 1000.0, "m: from wider priors the second closure...");
  t.number("loop_wide_confirm_distance", p.loop_wide_confirm_distance, 0.0, 1000.0, "m: ...comes from this far along the path");
  t.number("loop_guess_spacing", p.loop_guess_spacing, 0.01, 100.0, "m between wide-search initial guesses");
  t.integer("loop_max_guesses", p.loop_max_guesses, 1, 10000, "wide-search guesses at most");
  t.number("loop_ambiguity_distance", p.loop_ambiguity_distance, 0.0, 1000.0, "m: another fit this far away ...");
  t.number("loop_ambiguity_ratio", p.loop_ambiguity_ratio, 1.0, 1000.0, "... this nearly as good: ambiguous");
  t.angle("loop_ambiguity_heading_deg", p.loop_ambiguity_heading, 0.0, 180.0, "... at about this heading");
  t.number("loop_verify_translation", p.loop_verify_translation, 0.0, 100.0,
           "m: a neighbouring reference's match this far from the closure refutes it");
  t.angle("loop_verify_rotation_deg", p.loop_verify_rotation, 0.0, 180.0, "the same for heading");
  t.number("loop_unverified_max_extent", p.loop_unverified_max_extent, 0.0, 1000.0,
           "m: a closure no neighbour verifies needs a prior this narrow (its 3σ)");
  t.boolean("loop_check_unfiltered", p.loop_check_unfiltered,
            "match each closure again without the median filter: landing elsewhere refutes it ...");
  t.number("loop_unfiltered_fit_ratio", p.loop_unfiltered_fit_ratio, 1.0, 1000.0,
           "... where the raw ranges fit that pose this much better than the closure's");
  t.angle("loop_search_window_deg", p.loop_search_window, 0.5, 180.0, "matcher orientation window for loops");
}

void describeGraph(ParameterTable& t, PsmSlamParams& p) {
  t.boolean("optimize_on_loop", p.optimize_on_loop, "optimise the pose graph after loop closures");
  t.integer("min_keyframes_between_optimizations", p.min_keyframes_between_optimizations, 0, 1000000,
            "new reference scans between optimisations at least");
  t.number("loop_loss_scale", p.graph.loop_loss_scale, 0.01, 1000.0, "σ: Cauchy loss on loop edges");
  t.number("outlier_chi2", p.graph.outlier_chi2, 0.0, 1e9, "loop edges above this χ² are deactivated");
  t.integer("max_iterations", p.graph.max_iterations, 1, 100000, "Ceres iterations at most");
  t.integer("max_outlier_rounds", p.graph.max_outlier_rounds, 0, 100, "re-solves after deactivating edges");
}

void describeRefinement(ParameterTable& t, GraphRefinementParams& p) {
  t.boolean("enabled", p.enabled, "at the end of a run, match overlapping reference scans pairwise into the graph");
  t.number("max_distance", p.max_distance, 0.0, 100.0, "m: pairs of reference scans at most this far apart ...");
  t.angle("max_heading_deg", p.max_heading, 0.0, 180.0, "... and this much turned");
  t.integer("max_pairs_per_scan", p.max_pairs_per_scan, 0, 1000, "nearest earlier reference scans matched per scan");
  t.number("max_error_index", p.max_error_index, 0.0, 10.0, "m: a refinement match's error index at most");
  t.number("min_overlap", p.min_overlap, 0.0, 1.0, "a refinement match's overlap at least");
  t.number("agree_translation", p.agree_translation, 0.0, 100.0, "m: a match this far from the graph's pose converged elsewhere");
  t.angle("agree_rotation_deg", p.agree_rotation, 0.0, 180.0, "the same for heading");
  t.boolean("online", p.online, "also after each loop closure, in the background (enabled only)");
}

void describeLocalization(ParameterTable& t, MapLocalizationParams& p) {
  t.boolean("temporary_mapping", p.temporary_mapping,
            "once placed, track by PSM SLAM over the fixed map with temporary reference scans");
  t.number("track_radius", p.track_radius, 0.0, 1000.0, "m: reference scans matched when tracking within");
  t.angle("track_heading_deg", p.track_heading, 0.0, 180.0, "the same for heading");
  t.integer("track_candidates", p.track_candidates, 1, 100, "tracking matches per scan at most");
  t.integer("lost_after_scans", p.lost_after_scans, 1, 100000, "scans without a match: lost, search globally");
  t.integer("lost_near_map_after_scans", p.lost_near_map_after_scans, 1, 100000,
            "scans near reference scans without a map match: lost");
  t.number("max_off_map_sigma", p.max_off_map_sigma, 0.0, 1000.0, "m: on new ground, lost beyond this position sigma");
  t.number("global_search_spacing", p.global_search_spacing, 0.0, 1000.0, "m: while lost, search again after moving this far");
  t.angle("global_search_turn_deg", p.global_search_turn, 0.0, 360.0, "... or turning this much");
  t.number("global_sequence_distance", p.global_sequence_distance, 0.0, 100.0,
           "m: scans seen while lost this near are searched with the scan");
  t.number("global_resolution", p.global_resolution, 0.01, 10.0, "m: grid of the global search");
  t.number("global_sigma", p.global_sigma, 0.001, 10.0, "m: spread of its likelihood field");
  t.number("global_region_radius", p.global_region_radius, 0.0, 100.0, "m: robot positions searched around reference poses");
  t.integer("global_points", p.global_points, 1, 100000, "readings it scores at most");
  t.number("global_min_score", p.global_min_score, 0.0, 1.0, "score the best pose needs at least");
  t.number("global_ambiguity_distance", p.global_ambiguity_distance, 0.0, 1000.0, "m: another pose this far away ...");
  t.number("global_score_margin", p.global_score_margin, 0.0, 1.0, "... scoring within this of the best ...");
  t.number("global_misfit_ratio", p.global_misfit_ratio, 1.0, 1000.0, "... and misfitting at most this times as much: no fix");
  t.number("global_min_overlap", p.global_min_overlap, 0.0, 1.0, "associated fraction of a global hit at least");
  t.number("global_fit_distance", p.global_fit_distance, 0.001, 10.0, "m: a reading this close to the map fits");
  t.number("global_min_fit", p.global_min_fit, 0.0, 1.0, "fraction of the scan the best hit fits at least");
  t.number("global_max_see_through", p.global_max_see_through, 0.0, 1.0, "fraction of rays through mapped walls at most");
  t.number("global_see_through_clearance", p.global_see_through_clearance, 0.0, 100.0,
           "m from either end of a ray not checked");
  t.number("doubt_max_fit", p.doubt_max_fit, 0.0, 1.0, "while tracked near the map, a scan fitting less searches globally");
  t.number("confirm_translation", p.confirm_translation, 0.0, 100.0, "m: two hits agree after the odometry");
  t.angle("confirm_rotation_deg", p.confirm_rotation, 0.0, 180.0, "the same for heading");
  t.number("confirm_sequence_length", p.confirm_sequence_length, 0.0, 1000.0,
           "m: a hit from scans seen along this much path needs no confirming search (0: always one)");
  t.number("tail_max_shift", p.tail_max_shift, 0.0, 1000.0, "m: a fix after a loss re-places the drifted scans before it ...");
  t.number("tail_shift_per_metre", p.tail_shift_per_metre, 0.0, 10.0, "... if it moves them this much more per metre at most ...");
  t.angle("tail_max_turn_deg", p.tail_max_turn, 0.0, 180.0, "... and turns them at most this ...");
  t.angle("tail_turn_per_metre_deg", p.tail_turn_per_metre, 0.0, 180.0, "... plus this per metre since the last map match");
}

}  // namespace

void describePsmSlamParams(ParameterTable& table, PsmSlamParams& p) {
  table.choice(
      "method", {"psm", "psm-c", "icp"}, [&p](const std::string& w) { return parseMatchMethod(w, p.method); },
      [&p] { return std::string(methodName(p.method)); }, "scan matcher");
  describePrediction(table.section("prediction", "motion between scans"), p);
  describeOdometry(table.section("odometry", "odometry pose-increment error model"), p.odometry.poses);
  describeMatches(table.section("matches", "which matches the filter takes"), p);
  describeReferences(table.section("reference_scans", "reference scans (keyframes)"), p);
  describeStationary(table.section("stationary", "a robot standing still"), p);
  describeLoops(table.section("loop_closure", "loop closures"), p);
  describeGraph(table.section("graph", "global pose-graph optimisation"), p);
  describeRefinement(
      table.section("refinement", "overlapping reference scans matched pairwise: after loop closures and at the end of a run"),
      p.refinement);
  describeMatcher(table.section("psm", "the polar scan matcher"), p.psm);
  describeLocalization(table.section("localization", "localisation in a stored map (--load-map, --mode localize)"),
                       p.localization);
}

}  // namespace polarslam
