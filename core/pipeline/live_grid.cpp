#include "pipeline/live_grid.hpp"

#include <stdexcept>

#include "map/map_store.hpp"

namespace polarslam {
namespace {

BuiltGrid buildFromAnchors(const std::vector<AnchoredScan>& scans, const FeatureMap& map,
                           const GridOutputOptions& options) {
  RegeneratedGrid r = regenerateGrid(scans, map, options);
  GridPicture picture = gridPictureOf(r, map);
  return {std::move(r.grid),   std::move(r.slice), std::move(picture), static_cast<int>(scans.size()),
          std::move(r.utimes), std::move(r.poses), r.summary,          r.regenerate_seconds,
          r.build_seconds};
}

BuiltGrid buildFromGraph(const GraphScanStore& store, const PoseGraph& graph, const GridOptions& options) {
  GraphGrid g = buildGraphGrid(store, graph, options);
  GridPicture picture = graphGridPicture(g, graph);
  return {std::move(g.grid), std::move(g.slice), std::move(picture), static_cast<int>(store.size()), {}, {}, {}, 0.0,
          g.build_seconds};
}

}  // namespace

LiveGrid::LiveGrid(LiveGridOptions options)
    : options_(std::move(options)), anchored_(options_.store), graph_scans_(options_.psm_map.all_scans) {
  if (options_.load_map.empty()) return;
  if (options_.source != GridSource::PsmGraph) throw std::invalid_argument("a saved map goes with the PSM SLAM graph");
  const StoredMap map = loadMap(options_.load_map);
  for (const MapReferenceScan& s : map.scans) graph_scans_.addStored(s.scan, s.anchor);
  setPoseGraph(map.graph);
}

void LiveGrid::addScan(LaserScan scan) {
  if (options_.source == GridSource::EkfAnchors) anchored_.addScan(std::move(scan));
  else graph_scans_.addScan(std::move(scan));
}

void LiveGrid::addScanAnchors(ScanAnchors anchors) { anchored_.addAnchors(std::move(anchors)); }

void LiveGrid::setFeatureMap(FeatureMap map) {
  map_ = std::move(map);
  ++maps_and_graphs_;
}

void LiveGrid::addAnchoredPose(const AnchoredPose& pose) { graph_scans_.addAnchor(pose); }

void LiveGrid::setPoseGraph(PoseGraph graph) {
  graph_ = std::move(graph);
  ++maps_and_graphs_;
}

size_t LiveGrid::storedScans() const {
  return options_.source == GridSource::EkfAnchors ? anchored_.size() : graph_scans_.size();
}

uint64_t LiveGrid::version() const {
  const uint64_t store = options_.source == GridSource::EkfAnchors ? anchored_.version() : graph_scans_.version();
  return store + maps_and_graphs_;
}

std::function<BuiltGrid()> LiveGrid::build() {
  snapshot_version_ = version();
  if (options_.source == GridSource::EkfAnchors)
    return [scans = anchored_.scans(), map = map_, options = options_.ekf] { return buildFromAnchors(scans, map, options); };
  return [store = graph_scans_, graph = graph_, options = gridOptions(options_.psm_map)] {
    return buildFromGraph(store, graph, options);
  };
}

LiveGridCounts LiveGrid::counts() const {
  LiveGridCounts c;
  c.scans_stored = static_cast<int64_t>(storedScans());
  if (options_.source == GridSource::EkfAnchors) {
    const ScanStoreStatistics& s = anchored_.statistics();
    c.scans_received = s.scans_received;
    c.anchors_received = s.anchors_received;
    c.unpaired_dropped = s.unpaired_dropped;
    c.store_bytes = static_cast<int64_t>(anchored_.memoryBytes());
  } else {
    const GraphScanStoreStatistics& s = graph_scans_.statistics();
    c.scans_received = s.scans_received;
    c.anchors_received = s.anchors_received;
    c.unpaired_dropped = s.unpaired_dropped;
  }
  return c;
}

}  // namespace polarslam
