#include "polysquare/input/snap_points.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>

namespace polysquare {
namespace {

constexpr int kPoint = 1 << 30;  // owner of an isolated feature point (no ring or curve)

// A straight piece of a ring (owner >= 0) or of a feature curve (owner = -1 - feature index).
struct Seg {
  Vec2 a, b;
  int owner, index;
};

// A point that may be snapped: an end point of an open curve or an isolated feature point.
struct Query {
  Vec2 p;
  int owner;          // its own curve (never snapped onto), or kPoint
  std::size_t which;  // curve index or feature point index
  bool front;         // which end of the curve
  double seg_d = INFINITY, vertex_d = INFINITY;
  Vec2 vertex{};
  int seg = -1;       // index into the segment list
  int vertex_seg = -1;  // the segment whose end point `vertex` is
};

std::vector<Seg> segments(const Region& region) {
  std::vector<Seg> out;
  for (std::size_t r = 0; r < region.rings.size(); ++r) {
    const auto& p = region.rings[r].points;
    for (std::size_t i = 0; i < p.size(); ++i) out.push_back({p[i], p[(i + 1) % p.size()], static_cast<int>(r), static_cast<int>(i)});
  }
  for (std::size_t f = 0; f < region.features.size(); ++f) {
    const auto& c = region.features[f];
    const std::size_t m = c.closed ? c.points.size() : c.points.size() - 1;
    for (std::size_t i = 0; i < m && c.points.size() >= 2; ++i)
      out.push_back({c.points[i], c.points[(i + 1) % c.points.size()], -1 - static_cast<int>(f), static_cast<int>(i)});
  }
  return out;
}

// The end points of the open curves and the isolated feature points, each to be snapped.
std::vector<Query> snap_queries(const Region& region) {
  std::vector<Query> queries;
  for (std::size_t f = 0; f < region.features.size(); ++f) {
    const auto& c = region.features[f];
    if (c.closed || c.points.size() < 2) continue;
    // Non-finite coordinates are refused by validation later; here they would only upset the sort.
    if (!std::isfinite(c.points.front().x + c.points.front().y + c.points.back().x + c.points.back().y)) continue;
    queries.push_back({c.points.front(), -1 - static_cast<int>(f), f, true});
    queries.push_back({c.points.back(), -1 - static_cast<int>(f), f, false});
  }
  for (std::size_t k = 0; k < region.feature_points.size(); ++k)
    if (std::isfinite(region.feature_points[k].x + region.feature_points[k].y)) queries.push_back({region.feature_points[k], kPoint, k, false});
  return queries;
}

// For every query, the nearest segment and vertex of another ring or curve within tol.
void find_nearest(std::vector<Query>& queries, const std::vector<Seg>& segs, double tol) {
  std::vector<std::size_t> by_x(queries.size());
  for (std::size_t i = 0; i < by_x.size(); ++i) by_x[i] = i;
  std::sort(by_x.begin(), by_x.end(), [&](std::size_t i, std::size_t j) { return queries[i].p.x < queries[j].p.x; });
  // Queries whose x lies in [lo, hi]: a binary search, then a scan of that slice.
  auto in_x_range = [&](double lo, double hi, auto visit) {
    auto it = std::lower_bound(by_x.begin(), by_x.end(), lo, [&](std::size_t i, double v) { return queries[i].p.x < v; });
    for (; it != by_x.end() && queries[*it].p.x <= hi; ++it) visit(queries[*it]);
  };
  for (std::size_t s = 0; s < segs.size(); ++s) {
    const Seg& g = segs[s];
    in_x_range(std::min(g.a.x, g.b.x) - tol, std::max(g.a.x, g.b.x) + tol, [&](Query& q) {
      if (q.owner == g.owner) return;
      if (q.p.y < std::min(g.a.y, g.b.y) - tol || q.p.y > std::max(g.a.y, g.b.y) + tol) return;
      const double d = point_segment_distance(q.p, g.a, g.b);
      if (d < q.seg_d) { q.seg_d = d; q.seg = static_cast<int>(s); }
      for (Vec2 v : {g.a, g.b}) {
        const double dv = distance(q.p, v);
        if (dv < q.vertex_d) { q.vertex_d = dv; q.vertex = v; q.vertex_seg = static_cast<int>(s); }
      }
    });
  }
}

// Points inserted per (owner, segment index): parameter along the segment and the point.
using Inserts = std::map<std::pair<int, int>, std::vector<std::pair<double, Vec2>>>;

// Where q goes on g: the vertex, or its foot on the segment, recorded in inserts. Two points snapping to the same
// place share one inserted vertex.
Vec2 snap_target(const Query& q, const Seg& g, bool onto_vertex, double tol, Inserts& inserts) {
  if (onto_vertex) return q.vertex;
  const Vec2 d = g.b - g.a;
  const double t = std::clamp(dot(q.p - g.a, d) / dot(d, d), 0.0, 1.0);
  const Vec2 to = lerp(g.a, g.b, t);
  auto& list = inserts[{g.owner, g.index}];
  auto same = std::find_if(list.begin(), list.end(), [&](const auto& e) { return distance(e.second, to) <= tol; });
  if (same != list.end()) return same->second;
  list.push_back({t, to});
  return to;
}

// The query's point (a feature point or a curve's end) moved to `to`.
void move_point(Region& region, const Query& q, Vec2 to) {
  if (q.owner == kPoint) {
    region.feature_points[q.which] = to;
    return;
  }
  auto& pts = region.features[q.which].points;
  (q.front ? pts.front() : pts.back()) = to;
  // Snapped onto the point next to it along its own curve (a shared vertex there): the end is that point, once.
  if (pts.size() > 2 && q.front && pts[0] == pts[1]) pts.erase(pts.begin());
  if (pts.size() > 2 && !q.front && pts[pts.size() - 1] == pts[pts.size() - 2]) pts.pop_back();
}

std::string snap_note(const Region& region, const Query& q, const Seg& g, bool onto_vertex, double moved, Vec2 to) {
  const std::string what =
      q.owner == kPoint ? "feature point " + std::to_string(q.which)
                        : "feature " + std::to_string(region.features[q.which].source_feature) + " (curve " +
                              std::to_string(q.which) + "): " + (q.front ? "first" : "last") + " point";
  const std::string onto =
      g.owner >= 0 ? "ring " + std::to_string(g.owner) + " (feature " +
                         std::to_string(region.rings[static_cast<std::size_t>(g.owner)].source_feature) + ")"
                   : "feature curve " + std::to_string(-1 - g.owner);
  std::ostringstream d;
  d.precision(3);
  d << moved;
  return region.source + ": " + what + " " + point_text(q.p) + " snapped " + d.str() + " onto " +
         (onto_vertex ? "a vertex of " : "") + onto + " at " + point_text(to);
}

// Inserted points go into their ring or curve in order along each segment.
void insert_snapped_points(Region& region, Inserts& inserts) {
  auto rebuild = [&](int owner, std::vector<Vec2>& pts, bool closed) {
    std::vector<Vec2> out;
    const std::size_t m = closed ? pts.size() : pts.size() - 1;
    for (std::size_t i = 0; i < pts.size(); ++i) {
      out.push_back(pts[i]);
      auto it = inserts.find({owner, static_cast<int>(i)});
      if (i >= m || it == inserts.end()) continue;
      std::sort(it->second.begin(), it->second.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
      for (const auto& [t, p] : it->second)
        if (!(p == out.back()) && !(p == pts[(i + 1) % pts.size()])) out.push_back(p);
    }
    pts = std::move(out);
  };
  for (std::size_t r = 0; r < region.rings.size(); ++r) rebuild(static_cast<int>(r), region.rings[r].points, true);
  for (std::size_t f = 0; f < region.features.size(); ++f)
    if (region.features[f].points.size() >= 2)
      rebuild(-1 - static_cast<int>(f), region.features[f].points, region.features[f].closed);
}

// A two-point curve whose end snapped onto its other end (a stub shorter than the tolerance) is no curve: it
// goes, and is said (a zero-length constraint crashed the triangulation).
void drop_collapsed_stubs(Region& region, std::vector<std::string>* notes) {
  for (std::size_t f = region.features.size(); f-- > 0;) {
    const auto& pts = region.features[f].points;
    if (region.features[f].closed || pts.size() != 2 || !(pts[0] == pts[1])) continue;
    if (notes)
      notes->push_back(region.source + ": feature " + std::to_string(region.features[f].source_feature) + " (curve " +
                       std::to_string(f) + "): a piece shorter than the snap distance at " + point_text(pts[0]) +
                       " collapsed onto a point and is left out");
    region.features.erase(region.features.begin() + static_cast<std::ptrdiff_t>(f));
  }
}

// One pass: finds for every query the nearest vertex and segment of another ring or curve within tol, moves it,
// and inserts the points moved onto a segment interior into that ring or curve. Returns the moves made.
std::size_t snap_pass(Region& region, double tol, SnapStats& stats, std::vector<std::string>* notes) {
  std::vector<Query> queries = snap_queries(region);
  if (queries.empty()) return 0;
  const std::vector<Seg> segs = segments(region);
  find_nearest(queries, segs, tol);
  Inserts inserts;
  std::size_t moves = 0;
  for (Query& q : queries) {
    // A vertex that close wins (even when the point is on a segment: it would leave a tiny edge); a point far from
    // everything, or exactly on a segment, stays.
    const bool onto_vertex = q.vertex_d > 0.0 && q.vertex_d <= tol;
    if (q.seg < 0 || (!onto_vertex && (q.seg_d == 0.0 || q.seg_d > tol))) continue;
    const Seg& g = segs[static_cast<std::size_t>(onto_vertex ? q.vertex_seg : q.seg)];
    const Vec2 to = snap_target(q, g, onto_vertex, tol, inserts);
    const double moved = distance(q.p, to);
    move_point(region, q, to);
    ++moves;
    ++(onto_vertex ? stats.to_vertex : stats.to_segment);
    stats.largest_move = std::max(stats.largest_move, moved);
    if (notes) notes->push_back(snap_note(region, q, g, onto_vertex, moved, to));
  }
  if (!inserts.empty()) insert_snapped_points(region, inserts);
  drop_collapsed_stubs(region, notes);
  return moves;
}

}  // namespace

SnapStats snap_near_coincident(Region& region, double relative, std::vector<std::string>* notes) {
  SnapStats stats;
  const double tol = relative * region.bounding_box().diagonal();
  if (!(tol > 0.0) || !std::isfinite(tol)) return stats;
  // A point may have snapped onto an end point that itself moved in the same pass: a second pass joins them
  // again. Each pass only moves points that are not exactly on something, so this ends.
  for (int pass = 0; pass < 3 && snap_pass(region, tol, stats, notes) > 0; ++pass) {
  }
  return stats;
}

}  // namespace polysquare
