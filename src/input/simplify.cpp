#include "polysquare/input/simplify.h"

#include <algorithm>
#include <cmath>
#include <queue>
#include <unordered_map>
#include <unordered_set>

namespace polysquare {
namespace {

// All polylines in one vertex pool with next/prev links, so removals anywhere update a shared segment grid.
struct Pool {
  std::vector<Vec2> p;
  std::vector<int> prev, next, line;
  std::vector<std::uint8_t> alive, locked;
};

struct Grid {
  double cell;
  Vec2 origin;
  std::unordered_map<long long, std::vector<int>> cells;  // cell -> segment start vertices (segment a -> next[a])
  long long key(long long i, long long j) const { return (i << 32) ^ (j & 0xffffffffLL); }
  std::pair<long long, long long> index(Vec2 q) const {
    return {static_cast<long long>(std::floor((q.x - origin.x) / cell)), static_cast<long long>(std::floor((q.y - origin.y) / cell))};
  }
  template <typename F>
  void for_cells(Vec2 a, Vec2 b, F f) const {
    const auto [i0, j0] = index({std::min(a.x, b.x), std::min(a.y, b.y)});
    const auto [i1, j1] = index({std::max(a.x, b.x), std::max(a.y, b.y)});
    for (long long i = i0; i <= i1; ++i)
      for (long long j = j0; j <= j1; ++j) f(key(i, j));
  }
  void add(const Pool& pool, int a) {
    for_cells(pool.p[a], pool.p[pool.next[a]], [&](long long k) { cells[k].push_back(a); });
  }
};

int sgn(double v) { return (v > 0) - (v < 0); }

bool segments_touch(Vec2 a, Vec2 b, Vec2 c, Vec2 d) {
  const int d1 = sgn(orient2(a, b, c)), d2 = sgn(orient2(a, b, d)), d3 = sgn(orient2(c, d, a)), d4 = sgn(orient2(c, d, b));
  if (d1 * d2 < 0 && d3 * d4 < 0) return true;
  auto on = [](Vec2 p, Vec2 q, Vec2 r) {
    return std::min(p.x, q.x) <= r.x && r.x <= std::max(p.x, q.x) && std::min(p.y, q.y) <= r.y && r.y <= std::max(p.y, q.y);
  };
  return (d1 == 0 && on(a, b, c)) || (d2 == 0 && on(a, b, d)) || (d3 == 0 && on(c, d, a)) || (d4 == 0 && on(c, d, b));
}

}  // namespace

SimplifyStats simplify_region(Region& region, const SimplifyOptions& options) {
  SimplifyStats stats;
  Pool pool;
  struct Line { int first; bool closed; int size; };
  std::vector<Line> lines;
  auto add_line = [&](const std::vector<Vec2>& pts, bool closed) {
    const int first = static_cast<int>(pool.p.size()), n = static_cast<int>(pts.size());
    for (int i = 0; i < n; ++i) {
      pool.p.push_back(pts[i]);
      pool.prev.push_back(i > 0 ? first + i - 1 : (closed ? first + n - 1 : -1));
      pool.next.push_back(i + 1 < n ? first + i + 1 : (closed ? first : -1));
      pool.line.push_back(static_cast<int>(lines.size()));
      pool.alive.push_back(1);
      pool.locked.push_back(!closed && (i == 0 || i == n - 1));
    }
    lines.push_back({first, closed, n});
  };
  for (const Ring& r : region.rings) add_line(r.points, true);
  for (const FeatureCurve& f : region.features) add_line(f.points, f.closed);
  stats.vertices_before = pool.p.size();
  if (!(options.min_area > 0.0)) { stats.vertices_after = stats.vertices_before; return stats; }
  // Points shared by several polylines (a feature ending on a ring, curves meeting) stay.
  {
    std::unordered_map<long long, int> seen;
    std::vector<std::pair<std::pair<double, double>, int>> keys;
    for (std::size_t v = 0; v < pool.p.size(); ++v) keys.push_back({{pool.p[v].x, pool.p[v].y}, static_cast<int>(v)});
    std::sort(keys.begin(), keys.end());
    for (std::size_t i = 1; i < keys.size(); ++i)
      if (keys[i].first == keys[i - 1].first) pool.locked[keys[i].second] = pool.locked[keys[i - 1].second] = 1;
    for (const Vec2 q : region.feature_points)
      for (std::size_t v = 0; v < pool.p.size(); ++v)
        if (pool.p[v] == q) pool.locked[v] = 1;
  }
  Box2 box;
  double len = 0.0;
  std::size_t nseg = 0;
  for (std::size_t v = 0; v < pool.p.size(); ++v) {
    box.add(pool.p[v]);
    if (pool.next[v] >= 0) { len += distance(pool.p[v], pool.p[pool.next[v]]); ++nseg; }
  }
  Grid grid{std::max(2.0 * len / std::max<std::size_t>(1, nseg), box.diagonal() * 1e-9), box.lo, {}};
  for (std::size_t v = 0; v < pool.p.size(); ++v)
    if (pool.next[v] >= 0) grid.add(pool, static_cast<int>(v));

  auto area = [&](int v) { return 0.5 * std::abs(orient2(pool.p[pool.prev[v]], pool.p[v], pool.p[pool.next[v]])); };
  using Entry = std::pair<double, int>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<>> heap;
  std::vector<double> current(pool.p.size(), INFINITY);
  for (std::size_t v = 0; v < pool.p.size(); ++v)
    if (!pool.locked[v]) heap.push({current[v] = area(static_cast<int>(v)), static_cast<int>(v)});
  std::vector<int> line_size(lines.size());
  for (std::size_t l = 0; l < lines.size(); ++l) line_size[l] = lines[l].size;

  auto shortcut_is_free = [&](int v) {
    const int a = pool.prev[v], b = pool.next[v];
    const Vec2 pa = pool.p[a], pv = pool.p[v], pb = pool.p[b];
    bool ok = true;
    std::unordered_set<int> checked;
    Box2 tri;
    tri.add(pa); tri.add(pv); tri.add(pb);
    grid.for_cells(tri.lo, tri.hi, [&](long long k) {
      auto it = grid.cells.find(k);
      if (it == grid.cells.end() || !ok) return;
      for (int s : it->second) {
        if (!pool.alive[s] || pool.next[s] < 0 || !checked.insert(s).second) continue;
        const int e = pool.next[s];
        if (s == a || s == v) continue;  // the two segments being replaced
        const Vec2 ps = pool.p[s], pe = pool.p[e];
        // The new segment may share only its own end points with the segments next to it.
        const bool shares = s == b || e == a;
        if (!shares && segments_touch(pa, pb, ps, pe)) { ok = false; return; }
        // No other vertex inside (or on) the triangle that the shortcut cuts off.
        for (int q : {s, e}) {
          if (q == a || q == v || q == b) continue;
          const Vec2 pq = pool.p[q];
          const double o1 = orient2(pa, pv, pq), o2 = orient2(pv, pb, pq), o3 = orient2(pb, pa, pq);
          if ((o1 >= 0 && o2 >= 0 && o3 >= 0) || (o1 <= 0 && o2 <= 0 && o3 <= 0)) { ok = false; return; }
        }
      }
    });
    return ok;
  };

  while (!heap.empty()) {
    const auto [a_val, v] = heap.top();
    heap.pop();
    if (a_val != current[v] || !pool.alive[v] || pool.locked[v]) continue;
    if (a_val >= options.min_area) break;
    const int l = pool.line[v];
    if (line_size[l] <= (lines[l].closed ? 4 : 2)) continue;
    if (!shortcut_is_free(v)) { ++stats.refused; pool.locked[v] = 1; continue; }
    const int a = pool.prev[v], b = pool.next[v];
    // Removals only move a vertex's neighbours apart: once the shortcut is too long, it stays too long.
    // A vertex crowding its neighbour goes even past max_segment, unless the shortcut leaves a spike (a corner
    // below 20 degrees at a or b) where there was none.
    auto opening = [&](int from, int at, int to) {
      if (from < 0 || to < 0) return 180.0;
      const Vec2 u = pool.p[from] - pool.p[at], w = pool.p[to] - pool.p[at];
      return std::abs(std::atan2(cross(u, w), dot(u, w))) * 180.0 / 3.14159265358979323846;
    };
    const bool crowded = std::min(distance(pool.p[a], pool.p[v]), distance(pool.p[v], pool.p[b])) < 0.1 * options.max_segment &&
                         opening(pool.prev[a], a, b) >= 20.0 && opening(a, b, pool.next[b]) >= 20.0;
    if (options.max_segment > 0.0 && !crowded && distance(pool.p[a], pool.p[b]) > options.max_segment) {
      pool.locked[v] = 1;
      continue;
    }
    if (options.max_distance > 0.0) {
      // Every input vertex the new segment replaces (those removed before between a and b, and v) stays
      // within max_distance of it; the line's vertices are consecutive in the pool.
      const Line& line = lines[static_cast<std::size_t>(l)];
      bool close = true;
      for (int i = a;;) {
        i = i + 1 < line.first + line.size ? i + 1 : line.first;
        if (i == b) break;
        close = close && point_segment_distance(pool.p[i], pool.p[a], pool.p[b]) <= options.max_distance;
      }
      if (!close) { pool.locked[v] = 1; continue; }
    }
    pool.alive[v] = 0;
    pool.next[a] = b;
    pool.prev[b] = a;
    grid.add(pool, a);
    --line_size[l];
    for (int w : {a, b})
      if (!pool.locked[w] && pool.prev[w] >= 0 && pool.next[w] >= 0) heap.push({current[w] = area(w), w});
  }
  // How far the input moved: every removed vertex's distance to the kept segment that replaced it.
  for (const Line& line : lines) {
    std::vector<int> kept;
    for (int i = 0; i < line.size; ++i)
      if (pool.alive[line.first + i]) kept.push_back(i);
    if (kept.empty()) continue;
    for (std::size_t k = 0; k < kept.size(); ++k) {
      const bool last = k + 1 == kept.size();
      if (last && !line.closed) break;
      const int from = kept[k], to = last ? kept[0] + line.size : kept[k + 1];
      const Vec2 pa = pool.p[line.first + from], pb = pool.p[line.first + to % line.size];
      for (int i = from + 1; i < to; ++i)
        stats.max_distance = std::max(stats.max_distance, point_segment_distance(pool.p[line.first + i % line.size], pa, pb));
    }
  }
  // Write the surviving vertices back in order.
  auto collect = [&](const Line& line) {
    std::vector<Vec2> out;
    int start = line.first;
    while (!pool.alive[start]) ++start;  // closed lines: any survivor; open lines keep their first vertex
    int v = start;
    do {
      out.push_back(pool.p[v]);
      v = pool.next[v];
    } while (v >= 0 && v != start);
    return out;
  };
  for (std::size_t r = 0; r < region.rings.size(); ++r) region.rings[r].points = collect(lines[r]);
  for (std::size_t f = 0; f < region.features.size(); ++f) region.features[f].points = collect(lines[region.rings.size() + f]);
  for (const Ring& r : region.rings) stats.vertices_after += r.points.size();
  for (const FeatureCurve& f : region.features) stats.vertices_after += f.points.size();
  return stats;
}

}  // namespace polysquare
