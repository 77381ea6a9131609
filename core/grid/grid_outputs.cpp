#include "grid/grid_outputs.hpp"

#include <chrono>
#include <unordered_map>

#include "io/stopwatch.hpp"

namespace polarslam {
namespace {

std::vector<AnchoredScan> pairByUtime(const std::vector<LaserScan>& scans, const std::vector<ScanAnchors>& anchors) {
  std::unordered_map<int64_t, const LaserScan*> by_utime;
  for (const LaserScan& s : scans) by_utime[s.utime] = &s;
  std::vector<AnchoredScan> paired;
  for (const ScanAnchors& a : anchors) {
    const auto it = by_utime.find(a.utime);
    if (it != by_utime.end()) paired.push_back({*it->second, a});
  }
  return paired;
}

}  // namespace

RegeneratedGrid regenerateGrid(const std::vector<AnchoredScan>& scans, const FeatureMap& map,
                               const GridOutputOptions& options) {
  RegeneratedGrid out{OccupancyGrid(options.grid), {}, {}, {}, {}, 0.0, 0.0};
  std::vector<const ScanAnchors*> anchors;
  std::vector<const LaserScan*> laser;
  anchors.reserve(scans.size());
  laser.reserve(scans.size());
  for (const AnchoredScan& s : scans) {
    anchors.push_back(&s.anchors);
    laser.push_back(&s.scan);
    out.utimes.push_back(s.scan.utime);
  }
  auto start = std::chrono::steady_clock::now();
  out.poses = regeneratePoses(anchors, map, options.regeneration);
  out.summary = summarize(anchors, out.poses);
  out.regenerate_seconds = secondsSince(start);

  start = std::chrono::steady_clock::now();
  std::vector<Pose2> poses;
  poses.reserve(out.poses.size());
  for (const RegeneratedPose& p : out.poses) poses.push_back(p.pose);
  out.grid = buildGrid(laser, poses, options.grid);
  out.slice = out.grid.slice();
  out.build_seconds = secondsSince(start);
  return out;
}

GridPicture gridPictureOf(const RegeneratedGrid& result, const FeatureMap& map) {
  GridPicture picture;
  picture.title = "occupancy grid from regenerated poses";
  PlotSeries path{"regenerated poses", {}, seriesColor(0), 1.2, 0};
  PlotSeries chained{"chained (under-constrained)", {}, Rgb{230, 120, 0}, 0.0, 2.5};
  for (const RegeneratedPose& p : result.poses) {
    path.points.push_back(p.pose.translation());
    if (p.source != PoseSource::Regenerated) chained.points.push_back(p.pose.translation());
  }
  picture.paths.push_back(path);
  if (!chained.points.empty()) picture.paths.push_back(chained);
  PlotSeries corners{"map corners and points", {}, Rgb{200, 0, 0}, 0.0, 3.0};
  for (const MapFeature& f : map.features) {
    if (f.kind == MapFeatureKind::Line) {
      if ((f.endpoint_a - f.endpoint_b).norm() > 1e-6) picture.segments.push_back({f.endpoint_a, f.endpoint_b, Rgb{200, 0, 0}, 1.5});
    } else {
      corners.points.push_back(f.params.head<2>());
    }
  }
  if (!corners.points.empty()) picture.paths.push_back(corners);
  return picture;
}

nlohmann::json gridReportJson(const RegeneratedGrid& r, const GridFiles& files) {
  size_t occupied = 0, free = 0;
  for (int y = 0; y < r.slice.height; ++y)
    for (int x = 0; x < r.slice.width; ++x) {
      occupied += r.slice.occupied(x, y);
      free += r.slice.free(x, y);
    }
  return {{"scans", r.poses.size()},
          {"regenerated", r.summary.regenerated},
          {"chained", r.summary.chained},
          {"stored", r.summary.stored},
          {"anchors_rejected", r.summary.anchors_rejected},
          {"mean_pose_shift_m", r.summary.mean_shift},
          {"max_pose_shift_m", r.summary.max_shift},
          {"resolution_m", r.slice.resolution},
          {"width_cells", r.slice.width},
          {"height_cells", r.slice.height},
          {"origin", {r.slice.origin.x(), r.slice.origin.y()}},
          {"occupied_cells", occupied},
          {"free_cells", free},
          {"regenerate_s", r.regenerate_seconds},
          {"build_s", r.build_seconds},
          {"files", {files.bt, files.ot, files.pgm, files.yaml, files.png}}};
}

RegeneratedGrid writeGridOutputs(const std::string& out_dir, const AnchoredScanStore& store, const FeatureMap& map,
                                 nlohmann::json& report, const GridOutputOptions& options) {
  RegeneratedGrid result = regenerateGrid(store.scans(), map, options);
  const GridFiles files = writeGridFiles(out_dir, result.grid, result.slice, gridPictureOf(result, map));
  report["grid"] = gridReportJson(result, files);
  return result;
}

RegeneratedGrid writeGridOutputs(const std::string& out_dir, const std::vector<LaserScan>& scans,
                                 const std::vector<ScanAnchors>& anchors, const FeatureMap& map,
                                 nlohmann::json& report, const GridOutputOptions& options) {
  RegeneratedGrid result = regenerateGrid(pairByUtime(scans, anchors), map, options);
  const GridFiles files = writeGridFiles(out_dir, result.grid, result.slice, gridPictureOf(result, map));
  report["grid"] = gridReportJson(result, files);
  return result;
}

}  // namespace polarslam
