#include "map_saving.hpp"

#include "map/map_store.hpp"

namespace polarslam {

void LiveMapSaver::save(const PsmSlam& slam) const {
  PsmSlamEstimatorConfig config = config_;
  ParameterTable table;
  describePsmSlamEstimatorConfig(table, config);
  const StoredMap map = storedMapOf(slam.graph(), scans_.scans(), scans_.anchors(), table.yaml());
  const GraphGrid grid = buildGraphGrid(scans_, slam.graph(), gridOptions(config_.map));
  saveMap(dir_, map, &grid.grid);
}

}  // namespace polarslam
