// libFuzzer target: the global search (core/slam/correlative_search), whose bounds read four
// windows per point from grids of several levels, near and beyond the grid's edges. The input
// bytes make a small map (points and reference positions within ±6.4 m, 5 cm apart; a byte of -128
// is a NaN), the grid's parameters, a scan (robot frame) and a query. Beyond memory errors and UB,
// a finding is a place that scores below the query's minimum, comes after a better one or beyond
// the number asked for, or a score outside [0, 1]. (A place's score is not compared with score()
// at its pose: a reading that lies on a cell boundary may land in either cell, depending on the
// order of the additions.)
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <vector>

#include "slam/correlative_search.hpp"

namespace {

class Bytes {
 public:
  Bytes(const uint8_t* data, size_t size) : data_(data), size_(size) {}
  uint8_t next() { return at_ < size_ ? data_[at_++] : 0; }
  double unit() { return next() / 255.0; }
  /// A coordinate in [−6.4, 6.35] m; -128 is a NaN.
  double coordinate() {
    const int8_t raw = static_cast<int8_t>(next());
    return raw == -128 ? std::numeric_limits<double>::quiet_NaN() : 0.05 * raw;
  }
  std::vector<polarslam::Vec2> points(size_t most) {
    std::vector<polarslam::Vec2> out(next() % (most + 1));
    for (polarslam::Vec2& p : out) p = {coordinate(), coordinate()};
    return out;
  }

 private:
  const uint8_t* data_;
  size_t size_, at_ = 0;
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace polarslam;
  Bytes in(data, size);
  CorrelativeSearchParams params;
  params.levels = 1 + in.next() % 9;
  params.resolution = 0.1 + 0.2 * in.unit();  // grids of at most about 200 x 200 cells: fast runs
  params.sigma = 0.02 + 0.3 * in.unit();
  params.region_radius = 2.0 * in.unit();
  const std::vector<Vec2> map = in.points(96), references = in.points(8);
  CorrelativeQuery query;
  query.min_score = in.unit();
  query.rival_margin = 0.3 * in.unit();
  query.rival_distance = 2.0 * in.unit();
  query.rival_heading = 3.2 * in.unit();
  query.best_at_least = in.unit();
  // Every caller ends the search after a few places (two rivals make it ambiguous): without that, a
  // query with rivals 0 m apart reports every pose within the margin, and checking each node
  // against tens of thousands of places found takes minutes.
  const size_t most_places = 1 + in.next() % 8;
  query.go_on = [most_places](const std::vector<CorrelativeHit>& places) { return places.size() < most_places; };
  const std::vector<Vec2> scan = in.points(48);

  const CorrelativeMapSearch search(map, references, params);
  const CorrelativeSearchResult found = search.find(scan, query);
  if (found.places.size() > most_places) std::abort();
  for (size_t i = 0; i < found.places.size(); ++i) {
    const CorrelativeHit& place = found.places[i];
    if (place.score + 1e-12 < query.min_score || place.score > 1.0 + 1e-12) std::abort();
    if (i > 0 && place.score > found.places[i - 1].score + 1e-12) std::abort();
  }
  const Pose2 start = found.places.empty() ? Pose2(in.coordinate(), in.coordinate(), 6.3 * in.unit()) : found.places.front().pose;
  const CorrelativeHit refined = search.refine(scan, start, 0.5 * in.unit(), 0.5 * in.unit());
  if (!(refined.score >= 0.0 && refined.score <= 1.0 + 1e-12)) std::abort();
  return 0;
}
