#include "scanmatch/beam_geometry.hpp"

#include <algorithm>
#include <cmath>
#include <mutex>

namespace polarslam {

std::shared_ptr<const BeamGeometry> beamGeometry(size_t size, double angle_min, double angle_increment) {
  // A handful of geometries is alive at a time (one per sensor, plus decimated copies).
  constexpr size_t kCacheSize = 16;
  static std::mutex mutex;
  static std::vector<std::shared_ptr<const BeamGeometry>> cache;
  std::lock_guard lock(mutex);
  for (const auto& g : cache)
    if (g->size == size && g->angle_min == angle_min && g->angle_increment == angle_increment) return g;
  auto g = std::make_shared<BeamGeometry>();
  g->size = size;
  g->angle_min = angle_min;
  g->angle_increment = angle_increment;
  g->cos_table.resize(size);
  g->sin_table.resize(size);
  for (size_t i = 0; i < size; ++i) {
    g->cos_table[i] = std::cos(g->bearing(i));
    g->sin_table[i] = std::sin(g->bearing(i));
  }
  g->cos_float.assign(g->cos_table.begin(), g->cos_table.end());
  g->sin_float.assign(g->sin_table.begin(), g->sin_table.end());
  g->centre_cos = static_cast<float>(std::cos(g->centre()));
  g->centre_sin = static_cast<float>(std::sin(g->centre()));
  if (cache.size() == kCacheSize) cache.erase(cache.begin());
  cache.push_back(g);
  return g;
}

}  // namespace polarslam
