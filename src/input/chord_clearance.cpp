#include "polysquare/input/chord_clearance.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <set>
#include <unordered_map>
#include <utility>

namespace polysquare {

namespace {

struct Segment {
  Vec2 a, b;
  int ring = -1;      // -1 for a feature curve's segment
  std::size_t index = 0;  // segment index in its ring (from vertex index to index + 1)
};

// Every ring and feature segment in a uniform grid of cell `cell`, for the segments near a window's hull.
class SegmentGrid {
 public:
  SegmentGrid(const Region& region, double cell) : cell_(cell) {
    for (std::size_t r = 0; r < region.rings.size(); ++r) {
      const auto& p = region.rings[r].points;
      for (std::size_t i = 0; i < p.size(); ++i) add({p[i], p[(i + 1) % p.size()], static_cast<int>(r), i});
    }
    for (const FeatureCurve& f : region.features) {
      const std::size_t n = f.closed ? f.points.size() : f.points.size() - 1;
      for (std::size_t i = 0; i < n; ++i) add({f.points[i], f.points[(i + 1) % f.points.size()], -1, i});
    }
    seen_.assign(segments_.size(), 0);
  }
  const Segment& operator[](std::size_t s) const { return segments_[s]; }
  // Calls f(segment index) once for every segment whose box meets `box`.
  template <class F>
  void near(const Box2& box, F&& f) {
    ++stamp_;
    const auto [x0, y0] = cell_of(box.lo);
    const auto [x1, y1] = cell_of(box.hi);
    for (std::int64_t y = y0; y <= y1; ++y)
      for (std::int64_t x = x0; x <= x1; ++x) {
        const auto it = cells_.find(key(x, y));
        if (it == cells_.end()) continue;
        for (std::uint32_t s : it->second)
          if (seen_[s] != stamp_) {
            seen_[s] = stamp_;
            f(s);
          }
      }
  }

 private:
  std::pair<std::int64_t, std::int64_t> cell_of(Vec2 p) const {
    return {static_cast<std::int64_t>(std::floor(p.x / cell_)), static_cast<std::int64_t>(std::floor(p.y / cell_))};
  }
  static std::uint64_t key(std::int64_t x, std::int64_t y) {
    return (static_cast<std::uint64_t>(x) << 32) ^ static_cast<std::uint64_t>(y & 0xffffffff);
  }
  void add(const Segment& s) {
    Box2 b;
    b.add(s.a);
    b.add(s.b);
    const auto [x0, y0] = cell_of(b.lo);
    const auto [x1, y1] = cell_of(b.hi);
    for (std::int64_t y = y0; y <= y1; ++y)
      for (std::int64_t x = x0; x <= x1; ++x) cells_[key(x, y)].push_back(static_cast<std::uint32_t>(segments_.size()));
    segments_.push_back(s);
  }
  double cell_;
  std::vector<Segment> segments_;
  std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> cells_;
  std::vector<std::uint32_t> seen_;
  std::uint32_t stamp_ = 0;
};

// Convex hull, counter-clockwise, strictly convex corners only (Andrew's monotone chain).
std::vector<Vec2> convex_hull(std::vector<Vec2> p) {
  std::sort(p.begin(), p.end(), [](Vec2 a, Vec2 b) { return a.x < b.x || (a.x == b.x && a.y < b.y); });
  if (p.size() < 3) return p;
  std::vector<Vec2> h(2 * p.size());
  std::size_t k = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    while (k >= 2 && orient2(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  for (std::size_t i = p.size() - 1, t = k + 1; i-- > 0;) {
    while (k >= t && orient2(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  h.resize(k - 1);
  return h;
}

// Whether segment [a, b] meets the interior of the convex counter-clockwise polygon h (3 or more corners): no
// edge line of h has the segment on its outer side, and the segment's line has corners of h on both sides.
bool enters(const std::vector<Vec2>& h, Vec2 a, Vec2 b) {
  for (std::size_t i = 0; i < h.size(); ++i) {
    const Vec2 p = h[i], q = h[(i + 1) % h.size()];
    if (orient2(p, q, a) <= 0 && orient2(p, q, b) <= 0) return false;
  }
  bool left = false, right = false;
  for (Vec2 c : h) {
    const double o = orient2(a, b, c);
    left = left || o > 0;
    right = right || o < 0;
  }
  return left && right;
}

}  // namespace

std::vector<Vec2> pin_chords_clear_of_curves(Region& region, double reach) {
  std::vector<Vec2> added;
  if (!(reach > 0.0)) return added;
  SegmentGrid grid(region, reach);
  // Ring vertices that are mesh nodes already: feature points, feature ends, points where rings meet. A chord
  // cannot span them, so the greedy walk starts again there.
  std::set<std::pair<double, double>> pinned;
  for (Vec2 p : region.feature_points) pinned.insert({p.x, p.y});
  for (const FeatureCurve& f : region.features)
    if (!f.closed && !f.points.empty()) {
      pinned.insert({f.points.front().x, f.points.front().y});
      pinned.insert({f.points.back().x, f.points.back().y});
    }
  {
    std::set<std::pair<double, double>> seen;
    for (const Ring& ring : region.rings) {
      std::set<std::pair<double, double>> own;
      for (Vec2 p : ring.points) own.insert({p.x, p.y});
      for (const auto& p : own)
        if (!seen.insert(p).second) pinned.insert(p);
    }
  }

  for (std::size_t r = 0; r < region.rings.size(); ++r) {
    const std::vector<Vec2>& pts = region.rings[r].points;
    const std::size_t n = pts.size();
    if (n < 3) continue;
    // The ring walked twice from vertex 0 (positions 0 .. 2n), so windows may wrap; arc[t] = length up to t.
    std::vector<double> arc(2 * n + 1, 0.0);
    for (std::size_t t = 1; t <= 2 * n; ++t) arc[t] = arc[t - 1] + distance(pts[(t - 1) % n], pts[t % n]);
    auto is_pin = [&](std::size_t t) { return pinned.count({pts[t % n].x, pts[t % n].y}) > 0; };
    // Chords that span vertex t - 1 and end on the segment from t - 1 to t run between the points reach before
    // t - 1 (or the last pin, `floor`) and reach after it: whether another curve enters the hull of that stretch.
    auto dirty = [&](std::size_t t, std::size_t floor) {
      const double a0 = std::max(arc[floor], arc[t - 1] - reach), a1 = std::min(arc[t], arc[t - 1] + reach);
      std::size_t k = t - 1;
      while (k > floor && arc[k] > a0) --k;  // the segment from k to k + 1 holds a0
      // The point at arc a on a segment; its end points exactly (a segment of another curve starting there must
      // not seem to enter the hull by a rounding of lerp).
      auto at = [&](std::size_t seg, double a) {
        const double len = arc[seg + 1] - arc[seg], u = len > 0.0 ? (a - arc[seg]) / len : 0.0;
        return u <= 0.0 ? pts[seg % n] : u >= 1.0 ? pts[(seg + 1) % n] : lerp(pts[seg % n], pts[(seg + 1) % n], u);
      };
      std::vector<Vec2> window{at(k, a0)};
      for (std::size_t v = k + 1; v <= t - 1; ++v) window.push_back(pts[v % n]);
      window.push_back(at(t - 1, a1));
      Box2 box;
      for (Vec2 p : window) box.add(p);
      const std::vector<Vec2> hull = convex_hull(window);
      if (hull.size() < 3) return false;
      bool found = false;
      grid.near(box, [&](std::uint32_t s) {
        if (found) return;
        const Segment& seg = grid[s];
        // The stretch's own segments (positions k .. t - 1) bound the hull; the rest of a partly covered one runs
        // on along its line, away from the hull. Every other segment is another curve.
        if (seg.ring == static_cast<int>(r) && (seg.index + n - k % n) % n < t - k) return;
        found = enters(hull, seg.a, seg.b);
      });
      return found;
    };
    // First pass, no new pins: is any window dirty? Its position before the end becomes the first pin.
    std::size_t first = 2 * n;
    std::size_t last_pin = 0;
    for (std::size_t t = 1; t <= n && first == 2 * n; ++t)
      if (is_pin(t - 1)) last_pin = t - 1;
    for (std::size_t t = n + 1; t <= 2 * n && first == 2 * n; ++t) {
      if (is_pin(t - 1)) last_pin = t - 1;
      if (dirty(t, std::max(last_pin, t - n))) first = t - 1;
    }
    if (first == 2 * n) continue;
    // Greedy from that pin once round the ring: a window that turns dirty pins the position before its end.
    std::vector<std::size_t> pins;
    std::size_t floor = first - n;  // the same vertex as `first`, one turn earlier
    if (!is_pin(floor)) pins.push_back(floor % n);
    for (std::size_t t = floor + 1; t <= first; ++t) {
      if (is_pin(t - 1)) floor = t - 1;
      if (t - 1 > floor && dirty(t, floor)) {
        floor = t - 1;
        pins.push_back(floor % n);
      }
    }
    for (std::size_t v : pins) {
      pinned.insert({pts[v].x, pts[v].y});
      region.feature_points.push_back(pts[v]);
      added.push_back(pts[v]);
    }
  }
  return added;
}

}  // namespace polysquare
