#include "slam/psm_slam_params.hpp"

#include <yaml-cpp/yaml.h>

#include <functional>
#include <map>
#include <stdexcept>

namespace polarslam {
namespace {

using Setter = std::function<void(const YAML::Node&)>;

template <typename T>
Setter set(T& field) {
  return [&field](const YAML::Node& node) { field = node.as<T>(); };
}

std::map<std::string, Setter> psmSetters(PsmParams& p) {
  return {
      {"max_range", set(p.max_range)},
      {"min_valid_points", set(p.min_valid_points)},
      {"decimation", set(p.decimation)},
      {"search_window", set(p.search_window)},
      {"initial_search_window", set(p.initial_search_window)},
      {"max_error", set(p.max_error)},
      {"max_iterations", set(p.max_iterations)},
      {"covariance", [&p](const YAML::Node& n) {
         if (!parseCovarianceModel(n.as<std::string>(), p.covariance))
           throw std::runtime_error("psm.covariance must be 'heuristic' or 'wls'");
       }},
  };
}

std::map<std::string, Setter> slamSetters(PsmSlamParams& p) {
  return {
      {"method", [&p](const YAML::Node& n) {
         if (!parseMatchMethod(n.as<std::string>(), p.method))
           throw std::runtime_error("method must be 'psm', 'psm-c' or 'icp'");
       }},
      {"time_noise_xy", set(p.time_noise_xy)},
      {"time_noise_theta", set(p.time_noise_theta)},
      {"match_cov_scale", set(p.match_cov_scale)},
      {"odometry_check_translation", set(p.odometry_check_translation)},
      {"odometry_check_rotation", set(p.odometry_check_rotation)},
      {"min_match_sigma_xy", set(p.min_match_sigma_xy)},
      {"min_match_sigma_theta", set(p.min_match_sigma_theta)},
      {"max_error_index", set(p.max_error_index)},
      {"min_overlap", set(p.min_overlap)},
      {"chi2_gate", set(p.chi2_gate)},
      {"max_odometry_fault_translation", set(p.max_odometry_fault_translation)},
      {"max_odometry_fault_rotation", set(p.max_odometry_fault_rotation)},
      {"keyframe_distance", set(p.keyframe_distance)},
      {"keyframe_angle", set(p.keyframe_angle)},
      {"keyframe_min_overlap", set(p.keyframe_min_overlap)},
      {"reuse_fraction", set(p.reuse_fraction)},
      {"max_filter_keyframes", set(p.max_filter_keyframes)},
      {"filter_window", set(p.filter_window)},
      {"skeleton_spacing", set(p.skeleton_spacing)},
      {"skeleton_heading", set(p.skeleton_heading)},
      {"odometry_k_distance", set(p.odometry.poses.k_distance)},
      {"odometry_k_heading_per_rad", set(p.odometry.poses.k_heading_per_rad)},
      {"odometry_k_heading_per_m", set(p.odometry.poses.k_heading_per_m)},

      {"stationary_odometry_translation", set(p.stationary_odometry_translation)},
      {"stationary_odometry_rotation", set(p.stationary_odometry_rotation)},
      {"stationary_match_translation", set(p.stationary_match_translation)},
      {"stationary_match_rotation", set(p.stationary_match_rotation)},
      {"loop_search_radius", set(p.loop_search_radius)},
      {"loop_max_heading_difference", set(p.loop_max_heading_difference)},
      {"loop_candidate_sigmas", set(p.loop_candidate_sigmas)},
      {"loop_min_keyframe_gap", set(p.loop_min_keyframe_gap)},
      {"max_candidates_per_scan", set(p.max_candidates_per_scan)},
      {"loop_max_error_index", set(p.loop_max_error_index)},
      {"loop_min_overlap", set(p.loop_min_overlap)},
      {"loop_guess_spacing", set(p.loop_guess_spacing)},
      {"loop_max_guesses", set(p.loop_max_guesses)},
      {"loop_ambiguity_distance", set(p.loop_ambiguity_distance)},
      {"loop_ambiguity_ratio", set(p.loop_ambiguity_ratio)},
      {"loop_ambiguity_heading", set(p.loop_ambiguity_heading)},
      {"loop_search_window", set(p.loop_search_window)},
      {"loop_chi2_gate", set(p.loop_chi2_gate)},
      {"loop_confirm_sigma", set(p.loop_confirm_sigma)},
      {"loop_confirm_scans", set(p.loop_confirm_scans)},
      {"loop_confirm_translation", set(p.loop_confirm_translation)},
      {"loop_confirm_rotation", set(p.loop_confirm_rotation)},
      {"loop_confirmed_chi2_gate", set(p.loop_confirmed_chi2_gate)},
      {"optimize_on_loop", set(p.optimize_on_loop)},
      {"min_keyframes_between_optimizations", set(p.min_keyframes_between_optimizations)},
      {"loop_loss_scale", set(p.graph.loop_loss_scale)},
      {"outlier_chi2", set(p.graph.outlier_chi2)},
  };
}

void apply(const YAML::Node& map, std::map<std::string, Setter> setters, const std::string& prefix) {
  for (const auto& item : map) {
    const std::string key = item.first.as<std::string>();
    const auto it = setters.find(key);
    if (it == setters.end()) throw std::runtime_error("unknown PSM SLAM parameter '" + prefix + key + "'");
    try {
      it->second(item.second);
    } catch (const YAML::Exception& e) {
      throw std::runtime_error("PSM SLAM parameter '" + prefix + key + "': " + e.what());
    }
  }
}

}  // namespace

PsmSlamParams loadPsmSlamParams(const std::string& yaml_path, const std::set<std::string>& other_keys) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(yaml_path);
  } catch (const YAML::Exception& e) {
    throw std::runtime_error(yaml_path + ": " + e.what());
  }
  PsmSlamParams params;
  if (!root || root.IsNull()) return params;
  if (!root.IsMap()) throw std::runtime_error(yaml_path + ": expected a map of parameters");
  YAML::Node top = YAML::Clone(root);
  if (root["psm"]) {
    if (!root["psm"].IsMap()) throw std::runtime_error(yaml_path + ": 'psm' must be a map");
    apply(root["psm"], psmSetters(params.psm), "psm.");
    top.remove("psm");
  }
  for (const std::string& key : other_keys) top.remove(key);
  try {
    apply(top, slamSetters(params), "");
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(yaml_path + ": " + e.what());
  }
  return params;
}

}  // namespace polarslam
