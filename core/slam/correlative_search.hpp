#pragma once
// Global localisation by exhaustive correlative matching (Olson, "Real-time correlative scan
// matching", ICRA 2009) with the branch-and-bound of Hess et al., "Real-time loop closure in 2D
// LIDAR SLAM" (ICRA 2016, §V): every robot pose within `region_radius` of the map's reference
// poses, at every heading, is scored by how well a set of points (a scan, or several scans placed
// by odometry) lies on the map, and the best is found without scoring most of them.
//
// The map's points are rasterised once into a score grid: exp(-d²/2σ²) of the distance d to the
// nearest map point (a likelihood field, Thrun, Burgard & Fox, "Probabilistic Robotics", §6.4).
// Level k of the precomputed grids holds, per cell, the maximum of the score grid over the
// 2^k × 2^k cells from there on, so the score of a level-k node (2^k × 2^k translations at one
// heading) bounds the score of every translation in it: nodes below the best so far are pruned.
// Headings are branched on too (as translations are): a node also spans a group of headings, over
// which each point's cell moves within a few cells (the point's extent: in proportion to its range);
// per point, the largest of four windows of a level's grid (shifted by that motion) that together
// hold the node's translations and the motion bounds its score over the node. Far from the map's
// look-alikes most of the search space is pruned while whole groups of headings are still one node.
//
// The search returns the best pose of each place that scores within `rival_margin` of the best
// (places farther than `rival_distance` or `rival_heading` apart), best first, so that the caller
// can refuse an ambiguous answer (a look-alike corridor) or tell the places apart by other means.
//
//   CorrelativeMapSearch search(map_points, reference_positions, params);
//   CorrelativeSearchResult r = search.find(points_in_robot_frame, query);
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include "geometry/pose2.hpp"
#include "slam/large_pages.hpp"
#include "slam/map_fit_field.hpp"

namespace polarslam {

struct CorrelativeSearchParams {
  double resolution = 0.05;    ///< m per cell of the score grid and translation step
  double sigma = 0.1;          ///< m: the likelihood field's spread
  double region_radius = 1.5;  ///< m: robot positions searched around each reference pose
  int levels = 8;              ///< precomputed grids; the coarsest node spans 2^(levels-1) cells
  /// Largest grid, in cells of `resolution` (each cell takes levels + 1 bytes once built): a
  /// map spreading wider is refused (std::length_error).
  size_t max_cells = kMaxMapGridCells;
};

struct CorrelativeHit {
  Pose2 pose;
  double score = 0.0;
};

struct CorrelativeQuery {
  double min_score = 0.5;      ///< mean per-point score a pose needs (0..1)
  double rival_margin = 0.05;  ///< a rival scores at least best − this
  double rival_distance = 0.5;     ///< m
  double rival_heading = 0.5;      ///< rad
  /// The best place must score at least this (when above min_score): until a pose does, nodes below
  /// it are set aside rather than expanded, and taken up again, for the places within rival_margin
  /// of the best, only once one does. A search that finds nothing costs what a search from this
  /// score does; one that finds a place costs about what a search from the rivals' score does.
  double best_at_least = 0.0;
  /// Asked after each place is found, with the places so far (best first: the first time, the
  /// best alone): false ends the search with them (no rivals wanted, or the caller's verdict can no
  /// longer change). Places come in order of score, none better than one before it.
  std::function<bool(const std::vector<CorrelativeHit>& places)> go_on;
};

struct CorrelativeSearchResult {
  std::vector<CorrelativeHit> places;  ///< best first; the others within rival_margin of it
  size_t scored_nodes = 0;             ///< nodes and leaves scored (the work done)
};

class CorrelativeMapSearch {
 public:
  /// `map_points` in the map frame; robot positions are searched within region_radius of
  /// `reference_positions`. An empty map gives a search that finds nothing. Throws
  /// std::length_error when the grid would need more than params.max_cells.
  CorrelativeMapSearch(const std::vector<Vec2>& map_points, const std::vector<Vec2>& reference_positions,
                       CorrelativeSearchParams params);

  /// The best robot pose for `points` (robot frame), if any scores at least query.min_score.
  CorrelativeSearchResult find(const std::vector<Vec2>& points, const CorrelativeQuery& query) const;

  /// The best pose for `points` within ±`translation` and ±`rotation` of `pose`, every
  /// resolution step and heading step scored (a small window: places a scan where a search of
  /// several scans, placed by odometry, found the place).
  CorrelativeHit refine(const std::vector<Vec2>& points, const Pose2& pose, double translation, double rotation) const;
  /// Mean score of `points` (robot frame) with the robot at `pose`.
  double score(const std::vector<Vec2>& points, const Pose2& pose) const;
  /// The misfit (1 − score) the translation grid alone gives points on a straight wall: the grid
  /// pose nearest the true one is up to half a cell off across the wall, resolution²/12 squared on
  /// average, and 1 − exp(−d²/2σ²) ≈ d²/2σ². Scores closer to 1 than a few times this cannot be
  /// told apart by the search.
  double gridMisfit() const { return params_.resolution * params_.resolution / (24.0 * params_.sigma * params_.sigma); }
  /// The robot positions searched lie on origin() + resolution · (i, j).
  Vec2 origin() const { return origin_; }

 private:
  struct Node {
    int x = 0, y = 0;     ///< translation cell of the node's corner
    int level = 0;        ///< the node spans 2^level × 2^level translations
    int group = 0;        ///< index into the heading groups: the headings it spans
    int sum = 0;          ///< of the cell values its bound adds up
  };
  /// Headings [first, first + 2^level) of the search, and where each point lands over them: as
  /// cell offsets from the robot's cell, the lowest of each coordinate; `extent` is the farthest
  /// any point's cell moves beyond that as the heading varies over the group.
  struct HeadingGroup {
    int level = 0;
    int first = 0;
    int extent = 0;
    int min_dx = 0, min_dy = 0;            ///< the lowest cell offset of any point
    int max_reach_x = 0, max_reach_y = 0;  ///< the highest of a point's lowest cell plus its extent
    int children[2] = {-1, -1};
  };
  /// The groups of every level for a set of points: single headings first (group h is heading h),
  /// each level pairing the one below, up to one group of all. Each group's per-point cells lie
  /// in flat arrays (group g's at [g · points, (g + 1) · points)): a search builds thousands of
  /// groups, and one allocation per array rather than per group.
  struct HeadingGroups {
    std::vector<HeadingGroup> groups;
    size_t points = 0;
    std::vector<int> dx, dy;
    std::vector<std::ptrdiff_t> offsets;  ///< dy · width + dx: into a level's cells
    std::vector<int> extents;             ///< how far each point's cell moves over the group's headings
    const HeadingGroup& operator[](size_t g) const { return groups[g]; }
    size_t size() const { return groups.size(); }
  };
  /// Heading groups of every level for `points`; `headings` is the count.
  HeadingGroups headingGroups(const std::vector<Vec2>& points, int headings) const;
  int cellValue(int level, int x, int y) const;
  /// Upper bound of the score of every pose in the node (the exact score of a single pose), as the
  /// sum of the cell values (at most kScoreScale per point); once it falls short of a perfect sum by
  /// more than `max_deficit`, the points so far plus a perfect score for the rest (a looser bound,
  /// still short by more than `max_deficit`: the node is pruned either way).
  int nodeSum(const HeadingGroups& groups, int group, int level, int x, int y, int max_deficit) const;
  bool regionAllows(int level, int x, int y) const;
  double headingStep(double reach) const;
  Pose2 poseOf(int heading, int headings, int x, int y) const;

  /// Bits of a grid of blocks, row by row: a block in the region or not.
  struct RegionLevel {
    int width = 0, height = 0;
    std::vector<uint64_t> bits;
    size_t index(int x, int y) const { return static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x); }
    bool allows(int x, int y) const { return (bits[index(x, y) / 64] >> (index(x, y) % 64)) & 1U; }
  };
  /// The region's levels from its cells (1 where a translation is allowed), each level from the one
  /// below.
  void buildRegionLevels(LargePageVector<uint8_t> region);

  CorrelativeSearchParams params_;
  Vec2 origin_ = Vec2::Zero();
  int width_ = 0, height_ = 0;
  /// The score levels, one after the other: level k's cell y · width + x holds the maximum score
  /// over the window of 2^k × 2^k cells from there.
  LargePageVector<uint8_t> grids_;
  size_t cells_ = 0;
  int score_levels_ = 0;
  const uint8_t* scoreLevel(int k) const { return grids_.data() + static_cast<size_t>(k) * cells_; }
  std::vector<RegionLevel> region_;           ///< [level]: blocks of 2^level cells holding an allowed translation
};

}  // namespace polarslam
