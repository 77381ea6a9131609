#include "laser/segmentation.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <utility>

namespace polarslam {
namespace {

/// What separates a segment from the one before it.
enum class Link : uint8_t { Split, Hint, Break };

struct Piece {
  int first, last;
  Link link;
};

double distanceToChord(const Vec2& a, const Vec2& b, const Vec2& p) {
  const Vec2 ab = b - a;
  const double len = ab.norm();
  if (len < 1e-12) return (p - a).norm();
  return std::abs(ab.x() * (p.y() - a.y()) - ab.y() * (p.x() - a.x())) / len;
}

double distanceToLine(const PolarLine& line, const Vec2& p) {
  return std::abs(std::cos(line.alpha) * p.x() + std::sin(line.alpha) * p.y() - line.d);
}

/// Adaptive breakpoint detector (Borges & Aldon 2004): consecutive readings farther apart than
/// a wall seen at incidence 90° − λ would place them belong to different objects. The distance
/// limit is r·sin Δφ / sin(λ − Δφ) + k·σ; the factor is cached for the usual constant Δφ.
class BreakDetector {
 public:
  BreakDetector(double range_sigma, const SegmentationParams& p)
      : lambda_(p.break_angle), allowance_(p.break_sigmas * range_sigma) {}

  bool isBreak(const PolarReadings& r, size_t i) {
    const double dphi = r.bearing[i] - r.bearing[i - 1];
    if (dphi != cached_dphi_) {
      cached_dphi_ = dphi;
      factor_ = std::sin(dphi) / std::sin(std::max(lambda_ - dphi, deg2rad(1.0)));
    }
    const double limit = r.range[i - 1] * factor_ + allowance_;
    return (r.point(i) - r.point(i - 1)).squaredNorm() > limit * limit;
  }

 private:
  double lambda_, allowance_;
  double cached_dphi_ = -1.0, factor_ = 0.0;
};

/// How each reading is separated from the previous one (entry 0 is a Break).
std::vector<Link> readingLinks(const PolarReadings& r, std::span<const int> beam_index, std::span<const double> hints,
                               double range_sigma, const SegmentationParams& p) {
  const int n = static_cast<int>(r.size());
  std::vector<Link> link(static_cast<size_t>(n), Link::Split);
  if (n > 0) link[0] = Link::Break;
  BreakDetector breaks(range_sigma, p);
  for (int i = 1; i < n; ++i) {
    const int gap = beam_index[static_cast<size_t>(i)] - beam_index[static_cast<size_t>(i - 1)] - 1;
    if (gap > p.max_gap_beams || breaks.isBreak(r, static_cast<size_t>(i))) link[static_cast<size_t>(i)] = Link::Break;
  }
  for (double h : hints) {
    if (!std::isfinite(h)) continue;
    const auto it = std::lower_bound(r.bearing.begin(), r.bearing.end(), h);
    const auto i = static_cast<size_t>(it - r.bearing.begin());
    if (i > 0 && i < r.size() && link[i] == Link::Split) link[i] = Link::Hint;
  }
  return link;
}

/// Iterative end-point fit: splits [first, last] at the reading farthest from the chord while
/// that distance exceeds the threshold. Explicit stack: no recursion depth limit.
void splitPiece(const PolarReadings& r, const Piece& piece, double threshold, std::vector<Piece>& out) {
  std::vector<std::pair<int, int>> stack{{piece.first, piece.last}};
  bool first_out = true;
  while (!stack.empty()) {
    const auto [a, b] = stack.back();
    stack.pop_back();
    int farthest = -1;
    double max_distance = threshold;
    const Vec2 pa = r.point(static_cast<size_t>(a)), pb = r.point(static_cast<size_t>(b));
    for (int i = a + 1; i < b; ++i) {
      const double dist = distanceToChord(pa, pb, r.point(static_cast<size_t>(i)));
      if (dist > max_distance) {
        max_distance = dist;
        farthest = i;
      }
    }
    if (farthest < 0) {
      out.push_back({a, b, first_out ? piece.link : Link::Split});
      first_out = false;
      continue;
    }
    stack.push_back({farthest + 1, b});  // right half after the left one
    stack.push_back({a, farthest});
  }
}

double maxDistanceToFit(const PolarReadings& r, int first, int last, PolarLine* fitted = nullptr) {
  const PolarLine line = fitLineTotalLeastSquares(r.sub(static_cast<size_t>(first), static_cast<size_t>(last - first + 1)));
  if (fitted) *fitted = line;
  if (!std::isfinite(line.d)) return 0.0;
  double worst = 0.0;
  for (int i = first; i <= last; ++i) worst = std::max(worst, distanceToLine(line, r.point(static_cast<size_t>(i))));
  return worst;
}

/// Merges neighbours split apart (Link::Split) whose union still fits one line; true if any.
bool mergeCollinear(const PolarReadings& r, double threshold, std::vector<Piece>& segments) {
  std::vector<Piece> merged;
  for (const Piece& s : segments) {
    if (!merged.empty() && s.link == Link::Split && maxDistanceToFit(r, merged.back().first, s.last) <= threshold) {
      merged.back().last = s.last;
      continue;
    }
    merged.push_back(s);
  }
  const bool changed = merged.size() != segments.size();
  segments = std::move(merged);
  return changed;
}

/// Moves the readings at each junction made by splitting to the neighbour whose line they are
/// closer to. A segment may shrink to two readings (then it is too short to be kept as a line,
/// and its neighbours may merge across it).
void refineJunctions(const PolarReadings& r, std::vector<Piece>& segments) {
  constexpr int kKeep = 2;
  for (size_t k = 1; k < segments.size(); ++k) {
    Piece& a = segments[k - 1];
    Piece& b = segments[k];
    if (b.link != Link::Split || a.last + 1 != b.first) continue;  // hinted junctions stay put
    if (a.last - a.first + 1 < 2 || b.last - b.first + 1 < 2) continue;
    PolarLine la, lb;
    maxDistanceToFit(r, a.first, a.last, &la);
    maxDistanceToFit(r, b.first, b.last, &lb);
    if (!std::isfinite(la.d) || !std::isfinite(lb.d)) continue;
    auto closer_to_b = [&](int i) {
      const Vec2 p = r.point(static_cast<size_t>(i));
      return distanceToLine(lb, p) < distanceToLine(la, p);
    };
    while (a.last - a.first + 1 > kKeep && closer_to_b(a.last)) {
      --a.last;
      --b.first;
    }
    while (b.last - b.first + 1 > kKeep && !closer_to_b(b.first)) {
      ++a.last;
      ++b.first;
    }
  }
}

bool isLine(const PolarReadings& r, const Piece& s, const SegmentationParams& p) {
  if (s.last - s.first + 1 < p.min_line_points) return false;
  return (r.point(static_cast<size_t>(s.last)) - r.point(static_cast<size_t>(s.first))).norm() >= p.min_line_length;
}

bool perpendicular(const PolarReadings& r, const Piece& a, const Piece& b, double tolerance) {
  const PolarLine la = fitLineTotalLeastSquares(r.sub(static_cast<size_t>(a.first), static_cast<size_t>(a.last - a.first + 1)));
  const PolarLine lb = fitLineTotalLeastSquares(r.sub(static_cast<size_t>(b.first), static_cast<size_t>(b.last - b.first + 1)));
  const double angle = std::abs(wrapAngle(la.alpha - lb.alpha));
  return std::abs(angle - std::numbers::pi / 2.0) <= tolerance;
}

}  // namespace

Segmentation segmentReadings(const PolarReadings& r, std::span<const int> beam_index,
                             std::span<const double> break_bearings, double range_sigma, const SegmentationParams& p) {
  Segmentation result;
  const int n = static_cast<int>(std::min(r.size(), beam_index.size()));
  if (n < 2) return result;
  const std::vector<Link> links = readingLinks(r, beam_index, break_bearings, range_sigma, p);
  const double threshold = p.split_distance + p.split_sigmas * range_sigma;

  // Pieces between breaks and hints, each split and merged on its own.
  std::vector<Piece> segments;
  for (int first = 0; first < n;) {
    int last = first;
    while (last + 1 < n && links[static_cast<size_t>(last + 1)] == Link::Split) ++last;
    std::vector<Piece> piece_segments;
    splitPiece(r, {first, last, links[static_cast<size_t>(first)]}, threshold, piece_segments);
    // A split next to a corner can leave the apex reading on the wrong side, which then blocks
    // merging the pieces of a straight wall: settle the junctions, merge, and repeat.
    for (int round = 0; round < 3; ++round) {
      refineJunctions(r, piece_segments);
      if (!mergeCollinear(r, threshold, piece_segments)) break;
    }
    segments.insert(segments.end(), piece_segments.begin(), piece_segments.end());
    first = last + 1;
  }

  // Keep the lines; corner candidates are kept neighbours with no range break between them and
  // at most two readings lost in between (a mixed reading at the apex).
  int previous_kept = -1;
  bool broken_since = true;
  for (size_t k = 0; k < segments.size(); ++k) {
    const Piece& s = segments[k];
    if (s.link == Link::Break) broken_since = true;
    if (!isLine(r, s, p)) continue;
    result.lines.push_back({s.first, s.last});
    const int kept = static_cast<int>(result.lines.size()) - 1;
    if (previous_kept >= 0 && !broken_since) {
      const Piece a{result.lines[static_cast<size_t>(previous_kept)].first,
                    result.lines[static_cast<size_t>(previous_kept)].last, Link::Split};
      if (s.first - a.last - 1 <= 2 && perpendicular(r, a, s, p.corner_tolerance))
        result.corners.push_back({previous_kept, kept});
    }
    previous_kept = kept;
    broken_since = false;
  }
  return result;
}

}  // namespace polarslam
