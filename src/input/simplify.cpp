#include "polysquare/input/simplify.h"

#include "polysquare/input/chord_clearance.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <queue>
#include <set>
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

// Vertices with both neighbours whose input segments are shorter than max_segment, not locked.
std::vector<int> movable_vertices(const Pool& pool, const std::vector<Vec2>& input, const SimplifyOptions& options) {
  const int n = static_cast<int>(pool.p.size());
  std::vector<int> movable;
  for (int v = 0; v < n; ++v) {
    const int a = pool.prev[v], b = pool.next[v];
    if (pool.locked[v] || a < 0 || b < 0) continue;
    if (options.max_segment > 0.0 &&
        (distance(input[a], input[v]) >= options.max_segment || distance(input[v], input[b]) >= options.max_segment))
      continue;
    movable.push_back(v);
  }
  return movable;
}

// Distance to the input curve near v: the input segments within four vertices either side.
double distance_to_input_near(const Pool& pool, const std::vector<Vec2>& input, int v, Vec2 q) {
  double d = INFINITY;
  int i = v;
  for (int k = 0; k < 4 && pool.prev[i] >= 0; ++k) i = pool.prev[i];
  for (int k = 0; k < 8 && pool.next[i] >= 0; ++k, i = pool.next[i])
    d = std::min(d, point_segment_distance(q, input[i], input[pool.next[i]]));
  return d;
}

bool in_triangle(Vec2 q, Vec2 x, Vec2 y, Vec2 z) {
  const double o1 = orient2(x, y, q), o2 = orient2(y, z, q), o3 = orient2(z, x, q);
  return (o1 >= 0 && o2 >= 0 && o3 >= 0) || (o1 <= 0 && o2 <= 0 && o3 <= 0);
}

double segment_gap(Vec2 p, Vec2 q, Vec2 r, Vec2 t) {
  if (segments_touch(p, q, r, t)) return 0.0;
  return std::min({point_segment_distance(p, r, t), point_segment_distance(q, r, t), point_segment_distance(r, p, q),
                   point_segment_distance(t, p, q)});
}

// Segments within a few vertices along the same curve are its own bends, not another curve.
bool nearby_along_curve(const Pool& pool, int v, int s) {
  for (int k = 0, i = v, j = v; k < 4; ++k) {
    i = i >= 0 ? pool.prev[i] : -1;
    j = j >= 0 ? pool.next[j] : -1;
    if (i == s || j == s) return true;
  }
  return false;
}

// Whether v may move to c: its moved segments touch no other curve and sweep over no vertex. Two curves that do
// not touch still make slivers when they come close: a move may not bring the vertex's segments nearer another
// curve than `clear`, or nearer than they already were.
bool move_is_free(const Pool& pool, const Grid& grid, int v, Vec2 c, double clear) {
  const int a = pool.prev[v], b = pool.next[v];
  const Vec2 pa = pool.p[a], pv = pool.p[v], pb = pool.p[b];
  Box2 box;
  for (Vec2 q : {pa, pv, pb, c}) box.add(q);
  box.lo = box.lo - Vec2{clear, clear};
  box.hi = box.hi + Vec2{clear, clear};
  bool ok = true;
  std::unordered_set<int> checked;
  grid.for_cells(box.lo, box.hi, [&](long long k) {
    auto it = grid.cells.find(k);
    if (it == grid.cells.end() || !ok) return;
    for (int s : it->second) {
      if (!pool.alive[s] || pool.next[s] < 0 || !checked.insert(s).second) continue;
      if (s == a || s == v) continue;  // the two segments that move
      const int e = pool.next[s];
      const Vec2 ps = pool.p[s], pe = pool.p[e];
      if (e != a && segments_touch(pa, c, ps, pe)) { ok = false; return; }
      if (s != b && segments_touch(c, pb, ps, pe)) { ok = false; return; }
      for (int q : {s, e}) {
        if (q == a || q == v || q == b) continue;
        if (in_triangle(pool.p[q], pa, pv, c) || in_triangle(pool.p[q], pv, pb, c)) { ok = false; return; }
      }
      if (nearby_along_curve(pool, v, s)) continue;
      // The vertex itself (also where a curve ends on another, its segments touching that one at the end)...
      if (point_segment_distance(c, ps, pe) < std::min(clear, point_segment_distance(pv, ps, pe))) { ok = false; return; }
      // ... and its segments, unless they share an end point with that one.
      if (e != a && s != b &&
          std::min(segment_gap(pa, c, ps, pe), segment_gap(c, pb, ps, pe)) <
              std::min(clear, std::min(segment_gap(pa, pv, ps, pe), segment_gap(pv, pb, ps, pe)))) {
        ok = false;
        return;
      }
    }
  });
  return ok;
}

// Only zigzags move: a vertex turning by more than smooth_turn_deg one way next to one turning the other way.
// Turns the same way are the curve's own bends (a small island is all of them); smoothing would shrink it.
struct Zigzags {
  const Pool& pool;
  double min_turn;  // sine of smooth_turn_deg

  int turn(int v) const {
    if (v < 0) return 0;
    const int a = pool.prev[v], b = pool.next[v];
    if (a < 0 || b < 0) return 0;
    const Vec2 u = pool.p[v] - pool.p[a], w = pool.p[b] - pool.p[v];
    const double c = cross(u, w);
    if (!(std::abs(c) > min_turn * std::hypot(u.x, u.y) * std::hypot(w.x, w.y))) return 0;
    return c > 0.0 ? 1 : -1;
  }
  bool at(int v) const {
    if (v < 0) return false;
    const int t = turn(v);
    return t != 0 && (turn(pool.prev[v]) == -t || turn(pool.next[v]) == -t);
  }
};

// Zigzagging vertices in a stretch finer than max_segment (both segments at a vertex shorter) move towards the mean
// of their neighbours, a few passes, each move kept only if the vertex stays within smooth_distance of the input
// curve and the moved segments touch no other curve, sweep over no vertex and close in on none. A shoreline digitised in steps finer
// than the size (45-degree turns every 120 m at 200 m) then turns gently, and its steps stop being corners.
void smooth_fine_stretches(Pool& pool, Grid& grid, const std::vector<Vec2>& input, const SimplifyOptions& options) {
  const std::vector<int> movable = movable_vertices(pool, input, options);
  const Zigzags zigzag{pool, std::sin(options.smooth_turn_deg * 3.14159265358979323846 / 180.0)};
  const double still = 1e-3 * options.smooth_distance;
  for (int pass = 0; pass < 30; ++pass) {
    int moved = 0;
    for (int v : movable) {
      if (!zigzag.at(v) && !zigzag.at(pool.prev[v]) && !zigzag.at(pool.next[v])) continue;
      const Vec2 p = pool.p[v];
      const Vec2 step = 0.25 * (pool.p[pool.prev[v]] + pool.p[pool.next[v]] - 2.0 * p);
      const Vec2 c = p + step;
      if (distance(c, p) < still || distance_to_input_near(pool, input, v, c) > options.smooth_distance) continue;
      // Vertices also slide along the curve as it straightens; one that slid farther than max_distance from
      // its own input position would leave that input vertex beyond the bound once its neighbours are removed.
      if (options.max_distance > 0.0 && distance(c, input[v]) > options.max_distance) continue;
      if (!move_is_free(pool, grid, v, c, options.smooth_distance)) continue;
      pool.p[v] = c;
      grid.add(pool, pool.prev[v]);  // old cells keep stale entries: checks read the current positions
      grid.add(pool, v);
      ++moved;
    }
    if (moved == 0) break;
  }
}

// A polyline's place in the pool: its vertices are consecutive from first.
struct Line { int first; bool closed; int size; };

// The rings, then the feature curves, in one pool; the open lines' end vertices are locked.
std::vector<Line> pool_lines(const Region& region, Pool& pool) {
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
  return lines;
}

// Points shared by several polylines (a feature ending on a ring, curves meeting) stay.
void lock_shared_points(const Region& region, Pool& pool) {
  std::vector<std::pair<std::pair<double, double>, int>> keys;
  for (std::size_t v = 0; v < pool.p.size(); ++v) keys.push_back({{pool.p[v].x, pool.p[v].y}, static_cast<int>(v)});
  std::sort(keys.begin(), keys.end());
  for (std::size_t i = 1; i < keys.size(); ++i)
    if (keys[i].first == keys[i - 1].first) pool.locked[keys[i].second] = pool.locked[keys[i - 1].second] = 1;
  for (const Vec2 q : region.feature_points)
    for (std::size_t v = 0; v < pool.p.size(); ++v)
      if (pool.p[v] == q) pool.locked[v] = 1;
}

// A grid of the alive segments, its cells twice their mean length (at least a billionth of the box's diagonal).
Grid grid_of_alive_segments(const Pool& pool, const Box2& box, std::size_t segments) {
  double alive_len = 0.0;
  for (std::size_t v = 0; v < pool.p.size(); ++v)
    if (pool.alive[v] && pool.next[v] >= 0) alive_len += distance(pool.p[v], pool.p[pool.next[v]]);
  Grid grid{std::max(2.0 * alive_len / static_cast<double>(std::max<std::size_t>(1, segments)), box.diagonal() * 1e-9),
            box.lo, {}};
  for (std::size_t v = 0; v < pool.p.size(); ++v)
    if (pool.alive[v] && pool.next[v] >= 0) grid.add(pool, static_cast<int>(v));
  return grid;
}

// Whether the shortcut from v's previous to its next vertex touches no other segment and cuts off no vertex.
bool shortcut_is_free(const Pool& pool, const Grid& grid, int v) {
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
      // No other vertex inside (or on) the triangle that the shortcut cuts off. When a, v, b are collinear
      // the triangle is the segment from a to b: every point of its line has three zero orientations, so only
      // those within the three points' box are on it (the next vertex of a straight run is not, and once counted it
      // kept every collinear vertex: a square with 1,000 points per side went to the map with all 4,000).
      for (int q : {s, e}) {
        if (q == a || q == v || q == b) continue;
        const Vec2 pq = pool.p[q];
        const double o1 = orient2(pa, pv, pq), o2 = orient2(pv, pb, pq), o3 = orient2(pb, pa, pq);
        if (o1 == 0 && o2 == 0 && o3 == 0 &&
            !(std::min({pa.x, pv.x, pb.x}) <= pq.x && pq.x <= std::max({pa.x, pv.x, pb.x}) &&
              std::min({pa.y, pv.y, pb.y}) <= pq.y && pq.y <= std::max({pa.y, pv.y, pb.y})))
          continue;
        if ((o1 >= 0 && o2 >= 0 && o3 >= 0) || (o1 <= 0 && o2 <= 0 && o3 <= 0)) { ok = false; return; }
      }
    }
  });
  return ok;
}

// The corner at `at` between from and to, in degrees (180 at an open line's end).
double opening(const Pool& pool, int from, int at, int to) {
  if (from < 0 || to < 0) return 180.0;
  const Vec2 u = pool.p[from] - pool.p[at], w = pool.p[to] - pool.p[at];
  return std::abs(std::atan2(cross(u, w), dot(u, w))) * 180.0 / 3.14159265358979323846;
}

// Removals only move a vertex's neighbours apart: once the shortcut is too long, it stays too long.
// A vertex crowding its neighbour goes even past max_segment, unless the shortcut leaves a spike (a corner
// below 20 degrees at a or b) where there was none.
bool shortcut_too_long(const Pool& pool, int a, int v, int b, const SimplifyOptions& options) {
  const bool crowded = std::min(distance(pool.p[a], pool.p[v]), distance(pool.p[v], pool.p[b])) < options.crowded_fraction * options.max_segment &&
                       opening(pool, pool.prev[a], a, b) >= 20.0 && opening(pool, a, b, pool.next[b]) >= 20.0;
  return options.max_segment > 0.0 && !crowded && distance(pool.p[a], pool.p[b]) > options.max_segment;
}

// Every input vertex the new segment a-b replaces (those removed before between a and b, and v) stays
// within max_distance of it; the line's vertices are consecutive in the pool.
bool replaced_input_stays_close(const Pool& pool, const Line& line, const std::vector<Vec2>& input, int a, int b,
                                double max_distance) {
  bool close = true;
  for (int i = a;;) {
    i = i + 1 < line.first + line.size ? i + 1 : line.first;
    if (i == b) break;
    close = close && point_segment_distance(input[i], pool.p[a], pool.p[b]) <= max_distance;
  }
  return close;
}

// Removes vertices, smallest triangle area first, while the area is below min_area and the shortcut is free,
// short enough and close to the input.
void remove_small_triangles(Pool& pool, Grid& grid, const Box2& box, std::size_t nseg, const std::vector<Line>& lines,
                            const std::vector<Vec2>& input, const SimplifyOptions& options, SimplifyStats& stats) {
  // Segments lengthen as vertices go, and a segment is listed in every cell of its box: with cells sized for the
  // input (0.5 m along a 1.2M-vertex ring), shortcuts of the target size spanned thousands of cells each, and the
  // grid grew to 5 GB in 90 s. So the grid is rebuilt, its cells sized for the segments then alive, each time
  // their count halves (linear in all: n + n/2 + ...). Only the speed changes: any cell size finds every segment.
  std::size_t segments = nseg, rebuilt_at = nseg;
  auto area = [&](int v) { return 0.5 * std::abs(orient2(pool.p[pool.prev[v]], pool.p[v], pool.p[pool.next[v]])); };
  using Entry = std::pair<double, int>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<>> heap;
  std::vector<double> current(pool.p.size(), INFINITY);
  for (std::size_t v = 0; v < pool.p.size(); ++v)
    if (!pool.locked[v]) heap.push({current[v] = area(static_cast<int>(v)), static_cast<int>(v)});
  std::vector<int> line_size(lines.size());
  for (std::size_t l = 0; l < lines.size(); ++l) line_size[l] = lines[l].size;

  while (!heap.empty()) {
    const auto [a_val, v] = heap.top();
    heap.pop();
    if (a_val != current[v] || !pool.alive[v] || pool.locked[v]) continue;
    if (a_val >= options.min_area) break;
    const int l = pool.line[v];
    if (line_size[l] <= (lines[l].closed ? 4 : 2)) continue;
    if (!shortcut_is_free(pool, grid, v)) { ++stats.refused; pool.locked[v] = 1; continue; }
    const int a = pool.prev[v], b = pool.next[v];
    if (shortcut_too_long(pool, a, v, b, options)) {
      pool.locked[v] = 1;
      continue;
    }
    if (options.max_distance > 0.0 &&
        !replaced_input_stays_close(pool, lines[static_cast<std::size_t>(l)], input, a, b, options.max_distance)) {
      pool.locked[v] = 1;
      continue;
    }
    pool.alive[v] = 0;
    pool.next[a] = b;
    pool.prev[b] = a;
    grid.add(pool, a);
    --line_size[l];
    if (--segments * 2 <= rebuilt_at && segments >= 64) {
      grid = grid_of_alive_segments(pool, box, segments);
      rebuilt_at = segments;
    }
    for (int w : {a, b})
      if (!pool.locked[w] && pool.prev[w] >= 0 && pool.next[w] >= 0) heap.push({current[w] = area(w), w});
  }
}

// How far the input moved: every input vertex's distance to the kept segment that replaced it (a kept vertex
// counts too: smoothing may have moved it).
double max_input_distance(const Pool& pool, const std::vector<Line>& lines, const std::vector<Vec2>& input) {
  double max_distance = 0.0;
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
      for (int i = from; i <= to; ++i)
        max_distance = std::max(max_distance, point_segment_distance(input[line.first + i % line.size], pa, pb));
    }
  }
  return max_distance;
}

// A line's surviving vertices in order.
std::vector<Vec2> surviving_points(const Pool& pool, const Line& line) {
  std::vector<Vec2> out;
  int start = line.first;
  while (!pool.alive[start]) ++start;  // closed lines: any survivor; open lines keep their first vertex
  int v = start;
  do {
    out.push_back(pool.p[v]);
    v = pool.next[v];
  } while (v >= 0 && v != start);
  return out;
}

}  // namespace

SimplifyStats simplify_region(Region& region, const SimplifyOptions& options) {
  SimplifyStats stats;
  Pool pool;
  const std::vector<Line> lines = pool_lines(region, pool);
  stats.vertices_before = pool.p.size();
  if (!(options.min_area > 0.0)) { stats.vertices_after = stats.vertices_before; return stats; }
  lock_shared_points(region, pool);
  Box2 box;
  std::size_t nseg = 0;
  for (std::size_t v = 0; v < pool.p.size(); ++v) {
    box.add(pool.p[v]);
    if (pool.next[v] >= 0) ++nseg;
  }
  Grid grid = grid_of_alive_segments(pool, box, nseg);

  // The input positions: distances are measured to them, also after smoothing has moved the vertices.
  const std::vector<Vec2> input = pool.p;
  if (options.smooth_distance > 0.0) smooth_fine_stretches(pool, grid, input, options);
  remove_small_triangles(pool, grid, box, nseg, lines, input, options, stats);
  stats.max_distance = max_input_distance(pool, lines, input);
  // Write the surviving vertices back in order.
  for (std::size_t r = 0; r < region.rings.size(); ++r) region.rings[r].points = surviving_points(pool, lines[r]);
  for (std::size_t f = 0; f < region.features.size(); ++f) region.features[f].points = surviving_points(pool, lines[region.rings.size() + f]);
  for (const Ring& r : region.rings) stats.vertices_after += r.points.size();
  for (const FeatureCurve& f : region.features) stats.vertices_after += f.points.size();
  // Coarsened to the size, a ring concave towards another curve closer than a chord's sagitta (an island in a
  // hole, a part beside another) would be met by mesh edges that cross that curve: the meshes would overlap.
  const double reach = options.chord_reach < 0.0 ? options.max_segment : options.chord_reach;
  if (reach > 0.0) stats.chord_pins = pin_chords_clear_of_curves(region, reach).size();
  return stats;
}

}  // namespace polysquare

namespace polysquare {
namespace {

// The arrangement of the region's curves as a planar graph: nodes where feature pieces end (on rings, on each
// other or free), edges the open feature pieces and the ring arcs between such nodes. Faces are traced with
// each face on the left of its half-edges.
struct Arrangement {
  struct Edge {
    std::vector<Vec2> points;  // from node a to node b
    int a = -1, b = -1;
    int feature = -1;          // index into Region::features, or -1 for a ring arc
    bool domain_left = false;  // ring arcs: the domain lies on the left going a -> b
  };
  std::vector<Edge> edges;
  std::vector<std::vector<int>> out;  // per node: half-edges leaving it (2 e: a -> b, 2 e + 1: b -> a), by angle

  explicit Arrangement(const Region& region) {
    std::map<std::pair<double, double>, int> node_of;
    auto node = [&](Vec2 p) { return node_of.try_emplace({p.x, p.y}, static_cast<int>(node_of.size())).first->second; };
    for (std::size_t f = 0; f < region.features.size(); ++f) {
      const FeatureCurve& c = region.features[f];
      if (c.closed || c.points.size() < 2) continue;
      edges.push_back({c.points, node(c.points.front()), node(c.points.back()), static_cast<int>(f), false});
    }
    for (const Ring& r : region.rings) {
      const std::size_t n = r.points.size();
      std::vector<std::size_t> at;
      for (std::size_t i = 0; i < n; ++i)
        if (node_of.count({r.points[i].x, r.points[i].y})) at.push_back(i);
      for (std::size_t k = 0; k < at.size(); ++k) {
        Edge e;
        for (std::size_t i = at[k];; i = (i + 1) % n) {
          e.points.push_back(r.points[i]);
          if (e.points.size() > 1 && i == at[(k + 1) % at.size()]) break;
        }
        e.a = node(e.points.front());
        e.b = node(e.points.back());
        e.domain_left = true;  // outer rings counter-clockwise, holes clockwise: the domain is on the left
        edges.push_back(std::move(e));
      }
    }
    out.assign(node_of.size(), {});
    for (std::size_t e = 0; e < edges.size(); ++e) {
      out[static_cast<std::size_t>(edges[e].a)].push_back(static_cast<int>(2 * e));
      out[static_cast<std::size_t>(edges[e].b)].push_back(static_cast<int>(2 * e + 1));
    }
    for (auto& o : out)
      std::sort(o.begin(), o.end(), [&](int h, int g) { return angle(h) < angle(g); });
  }
  Vec2 first_step(int h) const {
    const auto& p = edges[static_cast<std::size_t>(h / 2)].points;
    return h % 2 == 0 ? p[1] - p[0] : p[p.size() - 2] - p.back();
  }
  double angle(int h) const {
    const Vec2 d = first_step(h);
    return std::atan2(d.y, d.x);
  }
  int head(int h) const { const Edge& e = edges[static_cast<std::size_t>(h / 2)]; return h % 2 == 0 ? e.b : e.a; }
  // The half-edge after h on the face to its left: at h's head, the next one clockwise from h's reverse.
  int next(int h) const {
    const auto& o = out[static_cast<std::size_t>(head(h))];
    const auto it = std::find(o.begin(), o.end(), h ^ 1);
    const std::size_t i = static_cast<std::size_t>(it - o.begin());
    return o[(i + o.size() - 1) % o.size()];
  }
  // The points of half-edge h in its direction, without its last point.
  void append(int h, std::vector<Vec2>& poly) const {
    const auto& p = edges[static_cast<std::size_t>(h / 2)].points;
    if (h % 2 == 0) poly.insert(poly.end(), p.begin(), p.end() - 1);
    else poly.insert(poly.end(), p.rbegin(), p.rend() - 1);
  }
};

double polyline_distance(Vec2 q, const std::vector<Vec2>& line) {
  double d = INFINITY;
  for (std::size_t i = 0; i + 1 < line.size(); ++i) d = std::min(d, point_segment_distance(q, line[i], line[i + 1]));
  return d;
}

}  // namespace

std::vector<DroppedCurve> collapse_narrow_faces(Region& region, double min_width) {
  std::vector<DroppedCurve> dropped;
  if (!(min_width > 0.0)) return dropped;
  // Each removal changes the faces around it: trace them again until no narrow face can be opened.
  for (bool again = true; again;) {
    again = false;
    const Arrangement g(region);
    std::vector<int> face_of(2 * g.edges.size(), -1);
    std::vector<std::vector<int>> faces;
    for (std::size_t h0 = 0; h0 < face_of.size(); ++h0) {
      if (face_of[h0] >= 0) continue;
      std::vector<int> cycle;
      for (int h = static_cast<int>(h0); face_of[static_cast<std::size_t>(h)] < 0; h = g.next(h)) {
        face_of[static_cast<std::size_t>(h)] = static_cast<int>(faces.size());
        cycle.push_back(h);
      }
      faces.push_back(std::move(cycle));
    }
    struct Best { int feature = -1; double distance = INFINITY, width = 0, area = 0; };
    Best best;
    for (std::size_t f = 0; f < faces.size(); ++f) {
      const std::vector<int>& cycle = faces[f];
      bool inside = false, feature = false;
      for (int h : cycle) {
        const auto& e = g.edges[static_cast<std::size_t>(h / 2)];
        if (e.feature < 0) inside = inside || e.domain_left == (h % 2 == 0);
        feature = feature || e.feature >= 0;
      }
      std::vector<Vec2> poly;
      for (int h : cycle) g.append(h, poly);
      const double area = ring_signed_area(poly);
      // Bounded faces only (the face on the left of a counter-clockwise cycle); faces with a ring arc must have
      // the domain on their side; faces of features alone lie inside the domain already.
      if (!feature || !(area > 0.0) || (!inside && std::any_of(cycle.begin(), cycle.end(), [&](int h) {
            return g.edges[static_cast<std::size_t>(h / 2)].feature < 0; })))
        continue;
      // Wide faces go first (most of them); then a face with another curve or a feature point inside is not a
      // simple sliver. Points outside the face's box are not tested against its ring.
      const double width = inscribed_width(poly, 0.01 * min_width, min_width);
      if (width >= min_width) continue;
      Box2 box;
      for (Vec2 p : poly) box.add(p);
      auto in_face = [&](Vec2 p) { return box.contains(p) && point_in_ring(p, poly); };
      bool holds = false;
      for (Vec2 p : region.feature_points) holds = holds || in_face(p);
      for (const FeatureCurve& c : region.features)
        if (c.closed && !c.points.empty()) holds = holds || in_face(c.points.front());
      for (const Ring& r : region.rings)
        if (r.hole) holds = holds || in_face(r.points.front());
      std::vector<std::uint8_t> on_face(g.edges.size(), 0);
      for (int h : cycle) on_face[static_cast<std::size_t>(h / 2)] = 1;
      for (std::size_t e = 0; e < g.edges.size() && !holds; ++e)
        if (!on_face[e]) holds = in_face(0.5 * (g.edges[e].points[0] + g.edges[e].points[1]));
      if (holds) continue;
      for (int h : cycle) {
        const auto& e = g.edges[static_cast<std::size_t>(h / 2)];
        if (e.feature < 0 || face_of[static_cast<std::size_t>(h ^ 1)] == static_cast<int>(f)) continue;
        // How far the piece lies from the rest of the face's boundary.
        std::vector<Vec2> rest;
        const auto i = static_cast<std::size_t>(std::find(cycle.begin(), cycle.end(), h) - cycle.begin());
        for (std::size_t k = 1; k < cycle.size(); ++k) g.append(cycle[(i + k) % cycle.size()], rest);
        rest.push_back(e.points[h % 2 == 0 ? 0 : e.points.size() - 1]);
        double d = 0.0;  // over its vertices and points along its segments (a straight piece has only its ends)
        for (std::size_t k = 0; k + 1 < e.points.size(); ++k)
          for (double t : {0.0, 0.25, 0.5, 0.75, 1.0}) d = std::max(d, polyline_distance(lerp(e.points[k], e.points[k + 1], t), rest));
        if (d <= min_width && d < best.distance) best = {e.feature, d, width, area};
      }
    }
    if (best.feature < 0) break;
    const FeatureCurve& c = region.features[static_cast<std::size_t>(best.feature)];
    dropped.push_back({DroppedCurve::Kind::feature_piece, c.source_feature, best.width, best.area, best.distance, c.points.front()});
    region.features.erase(region.features.begin() + best.feature);
    again = true;
  }
  return dropped;
}

namespace {

// The closest point to q on a polyline: segment index, parameter along it, the point.
struct Foot {
  std::size_t segment = 0;
  double t = 0.0;
  Vec2 at{};
  double distance = INFINITY;
};
Foot closest_on(Vec2 q, const std::vector<Vec2>& line) {
  Foot best;
  for (std::size_t i = 0; i + 1 < line.size(); ++i) {
    const Vec2 d = line[i + 1] - line[i];
    const double len2 = dot(d, d);
    const double t = len2 > 0.0 ? std::clamp(dot(q - line[i], d) / len2, 0.0, 1.0) : 0.0;
    const Vec2 at = line[i] + t * d;
    const double dist = distance(q, at);
    if (dist < best.distance) best = {i, t, at, dist};
  }
  return best;
}

// A curve leaving a meeting point: a feature piece (forward from its first point or backward from its last) or
// a ring walked one way from one of its vertices.
struct Dart {
  bool ring = false;
  int index = -1;      // feature or ring
  bool reversed = false;  // feature: walked from its last point; ring: walked against its order
  std::size_t vertex = 0;  // ring: the meeting vertex
};

std::vector<Vec2> dart_points(const Region& region, const Dart& d, double max_length) {
  std::vector<Vec2> out;
  if (!d.ring) {
    out = region.features[static_cast<std::size_t>(d.index)].points;
    if (d.reversed) std::reverse(out.begin(), out.end());
    return out;
  }
  const auto& p = region.rings[static_cast<std::size_t>(d.index)].points;
  const std::size_t n = p.size();
  double length = 0.0;
  for (std::size_t k = 0; k <= n && length <= max_length; ++k) {
    out.push_back(p[(d.vertex + (d.reversed ? n - k % n : k)) % n]);
    if (out.size() > 1) length += distance(out[out.size() - 2], out.back());
  }
  return out;
}

double polyline_length(const std::vector<Vec2>& line) {
  double l = 0.0;
  for (std::size_t i = 0; i + 1 < line.size(); ++i) l += distance(line[i], line[i + 1]);
  return l;
}

// Direction in which a polyline leaves its first point, read at `reach` along it (short first segments of a
// finely drawn curve say little about where it goes).
Vec2 leaving_direction(const std::vector<Vec2>& line, double reach) {
  for (std::size_t i = 1; i < line.size(); ++i)
    if (distance(line[0], line[i]) >= reach || i + 1 == line.size()) return line[i] - line[0];
  return {0, 0};
}

// Meeting points: ends of open feature pieces, with every curve leaving them.
std::map<std::pair<double, double>, std::vector<Dart>> meeting_points(const Region& region) {
  std::map<std::pair<double, double>, std::vector<Dart>> at;
  for (std::size_t f = 0; f < region.features.size(); ++f) {
    const FeatureCurve& c = region.features[f];
    if (c.closed || c.points.size() < 2) continue;
    at[{c.points.front().x, c.points.front().y}].push_back({false, static_cast<int>(f), false, 0});
    at[{c.points.back().x, c.points.back().y}].push_back({false, static_cast<int>(f), true, 0});
  }
  for (std::size_t r = 0; r < region.rings.size(); ++r)
    for (std::size_t i = 0; i < region.rings[r].points.size(); ++i) {
      const Vec2 p = region.rings[r].points[i];
      if (auto it = at.find({p.x, p.y}); it != at.end()) {
        it->second.push_back({true, static_cast<int>(r), false, i});
        it->second.push_back({true, static_cast<int>(r), true, i});
      }
    }
  return at;
}

// The first vertex of `from` at least min_width from `to` (from's stretch before it goes).
std::size_t first_away(const std::vector<Vec2>& from, const std::vector<Vec2>& to, double min_width) {
  std::size_t k = 1;
  while (k < from.size() && closest_on(from[k], to).distance < min_width) ++k;
  return k;
}

double prefix_length(const std::vector<Vec2>& line, std::size_t k) {
  return polyline_length(std::vector<Vec2>(line.begin(), line.begin() + static_cast<std::ptrdiff_t>(k + 1)));
}

// The region with B (points bp) starting at the foot on A (points ap) instead of at its k first vertices; the
// foot becomes a vertex of A (a feature is cut there: curves meet only at their ends).
Region with_wedge_opened(const Region& region, const Dart& a, const Dart& b, const std::vector<Vec2>& ap,
                         const std::vector<Vec2>& bp, std::size_t k, const Foot& foot) {
  Region next = region;
  // B now starts at the foot.
  std::vector<Vec2> nb{foot.at};
  nb.insert(nb.end(), bp.begin() + static_cast<std::ptrdiff_t>(k), bp.end());
  if (b.reversed) std::reverse(nb.begin(), nb.end());
  next.features[static_cast<std::size_t>(b.index)].points = nb;
  const bool at_vertex = foot.t == 0.0 || foot.t == 1.0;
  const std::size_t vertex = foot.segment + (foot.t == 1.0 ? 1 : 0);
  if (!a.ring) {
    FeatureCurve& fa = next.features[static_cast<std::size_t>(a.index)];
    std::vector<Vec2> first(ap.begin(), ap.begin() + static_cast<std::ptrdiff_t>(at_vertex ? vertex + 1 : foot.segment + 1));
    if (!at_vertex) first.push_back(foot.at);
    std::vector<Vec2> second{foot.at};
    second.insert(second.end(), ap.begin() + static_cast<std::ptrdiff_t>(at_vertex ? vertex + 1 : foot.segment + 1), ap.end());
    if (a.reversed) {
      std::reverse(first.begin(), first.end());
      std::reverse(second.begin(), second.end());
    }
    FeatureCurve other = fa;
    fa.points = std::move(first);
    other.points = std::move(second);
    next.features.push_back(std::move(other));
  } else if (!at_vertex) {
    auto& rp = next.rings[static_cast<std::size_t>(a.index)].points;
    const std::size_t n = rp.size();
    // Walked forward the foot lies after ring vertex (v0 + segment); walked backward, before (v0 - segment).
    const std::size_t after = a.reversed ? (a.vertex + n - foot.segment - 1) % n : (a.vertex + foot.segment) % n;
    rp.insert(rp.begin() + static_cast<std::ptrdiff_t>(after + 1), foot.at);
  }
  return next;
}

// Whether the link from p0 to p1 touches anything but its own two ends.
bool link_touches_others(const Region& region, Vec2 p0, Vec2 p1) {
  bool crosses = false;
  auto test = [&](Vec2 u, Vec2 v) {
    if (u == p0 || v == p0 || u == p1 || v == p1) return;
    crosses = crosses || segments_touch(p0, p1, u, v);
  };
  for (const Ring& r : region.rings)
    for (std::size_t i = 0; i < r.points.size() && !crosses; ++i) test(r.points[i], r.points[(i + 1) % r.points.size()]);
  for (const FeatureCurve& c : region.features)
    for (std::size_t i = 0; i + (c.closed ? 0 : 1) < c.points.size() && !crosses; ++i)
      test(c.points[i], c.points[(i + 1) % c.points.size()]);
  for (Vec2 q : region.feature_points) crosses = crosses || point_segment_distance(q, p0, p1) == 0.0;
  return crosses;
}

// Feature B (points bp, leaving in direction db) against curve A at the same meeting point: when they leave
// within max_angle of each other, B's stretch beside A goes and B starts at A where it is min_width away.
// Returns whether region changed.
bool open_wedge(Region& region, const Dart& a, const Dart& b, const std::vector<Vec2>& bp, Vec2 db, double min_width,
                double cos_max, std::vector<DroppedCurve>& done) {
  const std::vector<Vec2> ap = dart_points(region, a, polyline_length(bp) + 2.0 * min_width);
  const Vec2 da = leaving_direction(ap, 0.25 * min_width);
  const double la = std::hypot(da.x, da.y), lb = std::hypot(db.x, db.y);
  if (!(la > 0.0 && lb > 0.0) || dot(da, db) < cos_max * la * lb) return false;
  const std::size_t k = first_away(bp, ap, min_width);
  if (k >= bp.size()) return false;  // B stays beside A to its end: a narrow face, not a wedge
  // Of two features, the one that loses the shorter stretch leaves the other (a river leaves the
  // shoreline it runs along); ties go by index.
  if (!a.ring) {
    const std::vector<Vec2> whole_a = dart_points(region, a, 0.0);
    const std::size_t ka = first_away(whole_a, bp, min_width);
    if (ka < whole_a.size() &&
        (prefix_length(whole_a, ka) < prefix_length(bp, k) ||
         (prefix_length(whole_a, ka) == prefix_length(bp, k) && a.index < b.index)))
      return false;
  }
  double stretch = 0.0;
  for (std::size_t i = 1; i < k; ++i) stretch = std::max(stretch, closest_on(bp[i], ap).distance);
  const Foot foot = closest_on(bp[k], ap);
  if (foot.segment == 0 && foot.t == 0.0) return false;
  if (!a.ring && foot.segment + 2 == ap.size() && foot.t == 1.0) return false;  // A's far end: no room
  Region next = with_wedge_opened(region, a, b, ap, bp, k, foot);
  if (link_touches_others(next, foot.at, bp[k])) return false;
  const double opening = std::acos(std::min(1.0, dot(da, db) / (la * lb)));
  done.push_back({DroppedCurve::Kind::wedge_stretch, region.features[static_cast<std::size_t>(b.index)].source_feature,
                  2.0 * min_width * std::sin(0.5 * opening), 0.0, stretch, bp.front()});
  region = std::move(next);
  return true;
}

}  // namespace

std::vector<DroppedCurve> open_narrow_wedges(Region& region, double min_width, double max_angle_deg) {
  std::vector<DroppedCurve> done;
  if (!(min_width > 0.0)) return done;
  const double cos_max = std::cos(max_angle_deg * M_PI / 180.0);
  for (int round = 0; round < 10000; ++round) {
    const auto at = meeting_points(region);
    bool changed = false;
    for (const auto& [key, darts] : at) {
      for (std::size_t b = 0; b < darts.size() && !changed; ++b) {
        if (darts[b].ring) continue;
        const std::vector<Vec2> bp = dart_points(region, darts[b], 0.0);
        const Vec2 db = leaving_direction(bp, 0.25 * min_width);
        for (std::size_t a = 0; a < darts.size() && !changed; ++a) {
          if (a == b || (darts[a].ring == darts[b].ring && darts[a].index == darts[b].index)) continue;
          changed = open_wedge(region, darts[a], darts[b], bp, db, min_width, cos_max, done);
        }
      }
      if (changed) break;
    }
    if (!changed) break;
  }
  return done;
}

double inscribed_width(const std::vector<Vec2>& ring, double tolerance, double enough) {
  // Best-first search over square cells (the largest-inscribed-circle search): a cell's centre is at distance d
  // from the ring (negative outside), and no point of the cell is farther than d + half its diagonal, so cells
  // that cannot beat the best centre by more than the tolerance are dropped.
  Box2 box;
  for (Vec2 p : ring) box.add(p);
  const double w = box.hi.x - box.lo.x, h = box.hi.y - box.lo.y, cell = std::min(w, h);
  if (ring.size() < 3 || !(cell > 0.0)) return 0.0;
  auto signed_distance = [&](Vec2 p) {
    double d = INFINITY;
    for (std::size_t i = 0, j = ring.size() - 1; i < ring.size(); j = i++) d = std::min(d, point_segment_distance(p, ring[j], ring[i]));
    return point_in_ring(p, ring) ? d : -d;
  };
  struct Cell {
    Vec2 c;
    double half, d, potential;
    bool operator<(const Cell& o) const { return potential < o.potential; }
  };
  auto make = [&](Vec2 c, double half) {
    const double d = signed_distance(c);
    return Cell{c, half, d, d + half * std::sqrt(2.0)};
  };
  std::priority_queue<Cell> queue;
  for (double x = box.lo.x; x < box.hi.x; x += cell)
    for (double y = box.lo.y; y < box.hi.y; y += cell) queue.push(make({x + 0.5 * cell, y + 0.5 * cell}, 0.5 * cell));
  double best = std::max(0.0, make(0.5 * (box.lo + box.hi), 0.0).d);
  while (!queue.empty()) {
    const Cell c = queue.top();
    queue.pop();
    best = std::max(best, c.d);
    if (enough > 0.0 && 2.0 * best >= enough) break;
    // A cell that cannot hold a disk of diameter `enough` cannot change the answer to "is it that wide", only
    // the width reported: that is refined to a tenth of `enough` (a long channel at 1 % of it took 30 s).
    const double tol = enough > 0.0 && 2.0 * c.potential < enough ? std::max(tolerance, 0.1 * enough) : tolerance;
    if (c.potential - best <= 0.5 * tol) continue;
    const double q = 0.5 * c.half;
    for (Vec2 off : {Vec2{-q, -q}, Vec2{q, -q}, Vec2{-q, q}, Vec2{q, q}}) queue.push(make(c.c + off, q));
  }
  return 2.0 * best;
}

std::vector<DroppedCurve> drop_narrow_islands(Region& region, double min_width) {
  std::vector<DroppedCurve> dropped;
  if (!(min_width > 0.0)) return dropped;
  // Points used by more than one polyline (a feature ending on a hole, two loops touching) and feature points
  // keep their rings and loops: removing one would cut a curve loose.
  std::map<std::pair<double, double>, int> uses;  // exact point -> polylines through it
  auto key = [](Vec2 p) { return std::pair<double, double>{p.x, p.y}; };
  auto count_line = [&](const std::vector<Vec2>& pts) {
    std::set<std::pair<double, double>> mine;
    for (Vec2 p : pts) mine.insert(key(p));
    for (const auto& k : mine) uses[k]++;
  };
  for (const Ring& r : region.rings) count_line(r.points);
  for (const FeatureCurve& f : region.features) count_line(f.points);
  for (Vec2 p : region.feature_points) uses[key(p)] += 2;
  auto isolated = [&](const std::vector<Vec2>& pts) {
    for (Vec2 p : pts)
      if (uses[key(p)] > 1) return false;
    for (Vec2 p : region.feature_points)
      if (point_in_ring(p, pts)) return false;
    return true;
  };
  auto narrow = [&](const std::vector<Vec2>& pts, bool feature, int source) {
    if (!isolated(pts)) return false;
    const double width = inscribed_width(pts, 0.01 * min_width, min_width);
    if (width >= min_width) return false;
    dropped.push_back({feature ? DroppedCurve::Kind::feature_loop : DroppedCurve::Kind::hole, source, width,
                       std::abs(ring_signed_area(pts)), 0.0, pts.front()});
    return true;
  };
  std::vector<Ring> rings;
  std::vector<int> new_index(region.rings.size(), -1);  // boundary segments follow their ring
  for (std::size_t k = 0; k < region.rings.size(); ++k) {
    Ring& r = region.rings[k];
    if (r.hole && narrow(r.points, false, r.source_feature)) continue;
    new_index[k] = static_cast<int>(rings.size());
    rings.push_back(std::move(r));
  }
  region.rings = std::move(rings);
  for (BoundarySegment& b : region.boundary_segments)
    if (b.ring >= 0) b.ring = new_index[static_cast<std::size_t>(b.ring)];
  std::vector<FeatureCurve> features;
  for (FeatureCurve& f : region.features)
    if (!(f.closed && narrow(f.points, true, f.source_feature))) features.push_back(std::move(f));
  region.features = std::move(features);
  return dropped;
}

}  // namespace polysquare
