#include "polysquare/input/split_features.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>

#include <CGAL/box_intersection_d.h>

#include "polysquare/core/error.h"

namespace polysquare {
namespace {

// Stretches of feature curves along the boundary named one by one in the warnings; the rest are counted.
constexpr std::size_t kStretchWarnings = 20;

// One straight piece of a ring (owner >= 0) or of a feature curve (owner = -1 - feature index).
struct Piece {
  Vec2 a, b;
  int owner, index;
};

int sgn(double v) { return (v > 0) - (v < 0); }

// Crossing or touching point of two segments; parameters along each in [0, 1]. Collinear overlaps report the
// overlap's end points through the touching tests.
bool meet(const Piece& s, const Piece& t, Vec2& at, double& ts, double& tt) {
  const double d1 = orient2(s.a, s.b, t.a), d2 = orient2(s.a, s.b, t.b);
  const double d3 = orient2(t.a, t.b, s.a), d4 = orient2(t.a, t.b, s.b);
  auto param = [](Vec2 p, Vec2 q, Vec2 r) {
    const Vec2 d = q - p;
    const double l2 = dot(d, d);
    return l2 > 0 ? std::clamp(dot(r - p, d) / l2, 0.0, 1.0) : 0.0;
  };
  if (sgn(d1) * sgn(d2) < 0 && sgn(d3) * sgn(d4) < 0) {
    ts = d3 / (d3 - d4);
    at = lerp(s.a, s.b, ts);
    tt = param(t.a, t.b, at);
    return true;
  }
  auto on = [](Vec2 p, Vec2 q, Vec2 r) {
    return std::min(p.x, q.x) <= r.x && r.x <= std::max(p.x, q.x) && std::min(p.y, q.y) <= r.y && r.y <= std::max(p.y, q.y);
  };
  if (d1 == 0 && on(s.a, s.b, t.a)) { at = t.a; ts = param(s.a, s.b, at); tt = 0; return true; }
  if (d2 == 0 && on(s.a, s.b, t.b)) { at = t.b; ts = param(s.a, s.b, at); tt = 1; return true; }
  if (d3 == 0 && on(t.a, t.b, s.a)) { at = s.a; ts = 0; tt = param(t.a, t.b, at); return true; }
  if (d4 == 0 && on(t.a, t.b, s.b)) { at = s.b; ts = 1; tt = param(t.a, t.b, at); return true; }
  return false;
}

bool in_domain(const Region& region, Vec2 p) {
  // Even-odd over all rings: inside an outer ring and not inside its holes (parts do not overlap).
  bool inside = false;
  for (const Ring& r : region.rings)
    if (point_in_ring(p, r.points)) inside = !inside;
  return inside;
}

bool inside_an_outer_ring(const Region& region, Vec2 p) {
  for (const Ring& r : region.rings)
    if (!r.hole && point_in_ring(p, r.points)) return true;
  return false;
}

std::string pt_len(double v) {
  std::ostringstream os;
  os.precision(3);
  os << v;
  return os.str();
}

// Points to insert: per (owner, segment index), parameter -> point.
using Inserts = std::map<std::pair<int, int>, std::vector<std::pair<double, Vec2>>>;

// Every segment of the rings and of the feature curves, sorted by their least x.
std::vector<Piece> collect_pieces(const Region& region) {
  std::vector<Piece> pieces;
  for (std::size_t r = 0; r < region.rings.size(); ++r) {
    const auto& p = region.rings[r].points;
    for (std::size_t i = 0; i < p.size(); ++i) pieces.push_back({p[i], p[(i + 1) % p.size()], static_cast<int>(r), static_cast<int>(i)});
  }
  for (std::size_t f = 0; f < region.features.size(); ++f) {
    const auto& c = region.features[f];
    const std::size_t m = c.closed ? c.points.size() : c.points.size() - 1;
    for (std::size_t i = 0; i < m; ++i)
      pieces.push_back({c.points[i], c.points[(i + 1) % c.points.size()], -1 - static_cast<int>(f), static_cast<int>(i)});
  }
  std::sort(pieces.begin(), pieces.end(), [](const Piece& s, const Piece& t) { return std::min(s.a.x, s.b.x) < std::min(t.a.x, t.b.x); });
  return pieces;
}

// Candidate pairs (a feature piece and any other piece whose boxes meet) from CGAL's box intersection, then
// taken in the order of the pieces sorted by x. A sweep over x alone compared every pair of ring segments
// sharing an x range (a comb with 30,000 teeth along x: minutes).
std::vector<std::pair<std::size_t, std::size_t>> candidate_pairs(const std::vector<Piece>& pieces) {
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  using Box = CGAL::Box_intersection_d::Box_with_info_d<double, 2, std::size_t, CGAL::Box_intersection_d::ID_EXPLICIT>;
  std::vector<Box> all, curves;
  for (std::size_t i = 0; i < pieces.size(); ++i) {
    double lo[2] = {std::min(pieces[i].a.x, pieces[i].b.x), std::min(pieces[i].a.y, pieces[i].b.y)};
    double hi[2] = {std::max(pieces[i].a.x, pieces[i].b.x), std::max(pieces[i].a.y, pieces[i].b.y)};
    all.emplace_back(lo, hi, i);
    if (pieces[i].owner < 0) curves.push_back(all.back());
  }
  CGAL::box_intersection_d<CGAL::Sequential_tag>(
      curves.begin(), curves.end(), all.begin(), all.end(),
      [&](const Box& c, const Box& b) {
        const std::size_t i = std::min(c.info(), b.info()), j = std::max(c.info(), b.info());
        if (i != j && pieces[i].owner != pieces[j].owner) pairs.emplace_back(i, j);
      },
      std::ptrdiff_t(10), CGAL::Box_intersection_d::CLOSED, CGAL::Box_intersection_d::BIPARTITE);
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  return pairs;
}

// Each crossing point is computed once and given to both owners, so the two curves share the exact same
// coordinate.
Inserts crossing_points(const std::vector<Piece>& pieces, double tol, FeatureSplitStats& stats) {
  Inserts inserts;
  for (const auto& [i, j] : candidate_pairs(pieces)) {
    const Piece &s = pieces[i], &t = pieces[j];
    Vec2 at;
    double ts = 0, tt = 0;
    if (!meet(s, t, at, ts, tt)) continue;
    // Snap to an existing end point of either segment.
    for (Vec2 e : {s.a, s.b, t.a, t.b})
      if (distance(at, e) <= tol) at = e;
    inserts[{s.owner, s.index}].push_back({ts, at});
    inserts[{t.owner, t.index}].push_back({tt, at});
    ++stats.crossings;
  }
  return inserts;
}

// A polyline with its crossing points inserted in order along each segment (sorts the owner's lists in place).
std::vector<Vec2> with_inserts(Inserts& inserts, int owner, const std::vector<Vec2>& pts, bool closed) {
  std::vector<Vec2> out;
  const std::size_t m = closed ? pts.size() : pts.size() - 1;
  auto push = [&](Vec2 p) { if (out.empty() || !(out.back() == p)) out.push_back(p); };
  for (std::size_t i = 0; i < pts.size(); ++i) {
    push(pts[i]);
    if (i >= m) continue;
    auto it = inserts.find({owner, static_cast<int>(i)});
    if (it == inserts.end()) continue;
    auto& list = it->second;
    std::sort(list.begin(), list.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
    for (const auto& item : list)
      if (!(item.second == pts[(i + 1) % pts.size()])) push(item.second);
  }
  if (closed && out.size() > 1 && out.front() == out.back()) out.pop_back();
  return out;
}

void insert_into_rings(Region& region, Inserts& inserts, FeatureSplitStats& stats) {
  for (std::size_t r = 0; r < region.rings.size(); ++r) {
    const std::size_t before = region.rings[r].points.size();
    region.rings[r].points = with_inserts(inserts, static_cast<int>(r), region.rings[r].points, true);
    stats.ring_vertices_added += region.rings[r].points.size() - before;
  }
}

// Which segments of each (rebuilt) curve run along a ring: their midpoint within tol of it (candidate ring
// segments from CGAL's box intersection, boxes grown by tol).
std::vector<std::vector<std::uint8_t>> segments_along_rings(const Region& region,
                                                            const std::vector<std::vector<Vec2>>& rebuilt, double tol) {
  const std::size_t nf = region.features.size();
  std::vector<std::vector<std::uint8_t>> along(nf);
  for (std::size_t f = 0; f < nf; ++f) along[f].assign(rebuilt[f].size(), 0);
  using Box = CGAL::Box_intersection_d::Box_with_info_d<double, 2, std::pair<std::int64_t, std::int64_t>,
                                                         CGAL::Box_intersection_d::ID_EXPLICIT>;
  auto box = [](Vec2 a, Vec2 b, double grow, std::int64_t i, std::int64_t j) {
    double lo[2] = {std::min(a.x, b.x) - grow, std::min(a.y, b.y) - grow};
    double hi[2] = {std::max(a.x, b.x) + grow, std::max(a.y, b.y) + grow};
    return Box(lo, hi, {i, j});
  };
  std::vector<Box> ring_boxes, curve_boxes;
  for (std::size_t r = 0; r < region.rings.size(); ++r) {
    const auto& p = region.rings[r].points;
    for (std::size_t i = 0; i < p.size(); ++i)
      ring_boxes.push_back(box(p[i], p[(i + 1) % p.size()], 0.0, static_cast<std::int64_t>(r), static_cast<std::int64_t>(i)));
  }
  for (std::size_t f = 0; f < nf; ++f) {
    const auto& p = rebuilt[f];
    const std::size_t m = region.features[f].closed ? p.size() : p.size() - 1;
    for (std::size_t i = 0; i < m; ++i)
      curve_boxes.push_back(box(p[i], p[(i + 1) % p.size()], tol, static_cast<std::int64_t>(f), static_cast<std::int64_t>(i)));
  }
  CGAL::box_intersection_d<CGAL::Sequential_tag>(
      ring_boxes.begin(), ring_boxes.end(), curve_boxes.begin(), curve_boxes.end(),
      [&](const Box& rb, const Box& cb) {
        const auto& rp = region.rings[static_cast<std::size_t>(rb.info().first)].points;
        const auto ri = static_cast<std::size_t>(rb.info().second);
        const auto& p = rebuilt[static_cast<std::size_t>(cb.info().first)];
        const auto i = static_cast<std::size_t>(cb.info().second);
        const Vec2 mid = lerp(p[i], p[(i + 1) % p.size()], 0.5);
        if (point_segment_distance(mid, rp[ri], rp[(ri + 1) % rp.size()]) <= tol)
          along[static_cast<std::size_t>(cb.info().first)][i] = 1;
      });
  return along;
}

// p moved onto the nearest ring segment; a point inside a segment is recorded in ring_inserts.
Vec2 onto_ring(const Region& region, Inserts& ring_inserts, Vec2 p) {
  double best = INFINITY;
  int br = -1, bi = -1;
  double bt = 0;
  for (std::size_t r = 0; r < region.rings.size(); ++r) {
    const auto& q = region.rings[r].points;
    for (std::size_t i = 0; i < q.size(); ++i) {
      const Vec2 a = q[i], b = q[(i + 1) % q.size()];
      const double d = point_segment_distance(p, a, b);
      if (d < best) {
        const Vec2 e = b - a;
        best = d, br = static_cast<int>(r), bi = static_cast<int>(i);
        bt = dot(e, e) > 0 ? std::clamp(dot(p - a, e) / dot(e, e), 0.0, 1.0) : 0.0;
      }
    }
  }
  const auto& q = region.rings[static_cast<std::size_t>(br)].points;
  const Vec2 a = q[static_cast<std::size_t>(bi)], b = q[(static_cast<std::size_t>(bi) + 1) % q.size()];
  const Vec2 at = bt <= 0 ? a : bt >= 1 ? b : lerp(a, b, bt);
  if (!(at == a) && !(at == b)) ring_inserts[{br, bi}].push_back({bt, at});
  return at;
}

// Which points of a curve are crossing points (the curve is cut at every point where it meets something else).
std::vector<std::uint8_t> cut_points(const Inserts& inserts, int owner, const std::vector<Vec2>& pts) {
  std::vector<std::pair<double, double>> crossing;
  for (const auto& [key, list] : inserts)
    if (key.first == owner)
      for (const auto& item : list) crossing.emplace_back(item.second.x, item.second.y);
  std::sort(crossing.begin(), crossing.end());
  std::vector<std::uint8_t> cut(pts.size());
  for (std::size_t i = 0; i < pts.size(); ++i)
    cut[i] = std::binary_search(crossing.begin(), crossing.end(), std::make_pair(pts[i].x, pts[i].y));
  return cut;
}

struct Stretch {
  std::vector<Vec2> points;
  bool along = false, snap_front = false, snap_back = false;
};

struct Stretches {
  std::vector<Stretch> parts;
  bool closed_kept = false;  ///< a closed curve kept whole
};

// Pieces between cuts, each split further where its segments start or stop running along the boundary.
Stretches split_into_stretches(const std::vector<Vec2>& pts, bool closed, const std::vector<std::uint8_t>& cut,
                               const std::vector<std::uint8_t>& along) {
  Stretches result;
  auto& parts = result.parts;
  const bool any_cut = std::find(cut.begin(), cut.end(), 1) != cut.end();
  const std::size_t n = pts.size(), steps = closed ? n : n - 1;
  std::size_t nalong = 0;
  for (std::size_t i = 0; i < steps; ++i) nalong += along[i];
  if (closed && !any_cut && (nalong == 0 || nalong == steps)) {
    parts.push_back({pts, nalong == steps});
    result.closed_kept = nalong == 0;
    return result;
  }
  // Start at a cut (or where running along the boundary changes) for closed curves so pieces do not wrap.
  std::size_t start = 0;
  if (closed && any_cut) start = static_cast<std::size_t>(std::find(cut.begin(), cut.end(), 1) - cut.begin());
  else if (closed)
    while (along[start] == along[(start + n - 1) % n]) ++start;
  Stretch cur{{pts[start]}, along[start] != 0};
  for (std::size_t k = 1; k <= steps; ++k) {
    const std::size_t i = (start + k) % n;
    cur.points.push_back(pts[i]);
    const bool next_along = k < steps && along[i] != 0;
    const bool change = k < steps && next_along != cur.along && !cut[i];
    if (cut[i] || k == steps || change) {
      parts.push_back(cur);
      cur = {{pts[i]}, next_along};
      if (change) parts.back().snap_back = !parts.back().along, cur.snap_front = !next_along;
    }
  }
  return result;
}

// The curve's stretches that lie inside the domain and off the boundary, appended to out; the others are
// counted and named in warnings.
void keep_stretches_in_domain(const Region& region, const FeatureCurve& c, const std::string& name, Stretches stretches,
                              double tol, const FeatureSplitOptions& options, Inserts& ring_inserts,
                              std::vector<FeatureCurve>& out, FeatureSplitStats& stats) {
  bool kept = false, on_boundary = false;
  for (auto& piece : stretches.parts) {
    if (piece.points.size() < 2) continue;
    if (piece.along) {
      on_boundary = true;
      ++stats.pieces_dropped;
      ++stats.stretches_along_boundary;
      if (stats.stretches_along_boundary <= kStretchWarnings)
        stats.warnings.push_back(name + ": the stretch from " + point_text(piece.points.front()) + " to " +
                                 point_text(piece.points.back()) + " runs along the boundary (within " + pt_len(tol) +
                                 ") and is left to it");
      continue;
    }
    const Vec2 probe = lerp(piece.points[0], piece.points[1], 0.5);
    if (!in_domain(region, probe)) {
      ++stats.pieces_dropped;
      const bool in_hole = inside_an_outer_ring(region, probe);
      if (in_hole) {
        if (!options.clip_holes)
          throw InputError(name + " crosses a hole at " + point_text(piece.points.front()) + " (--repair clips it)");
        ++stats.pieces_in_holes;
      }
      stats.warnings.push_back(name + ": a piece from " + point_text(piece.points.front()) + " to " + point_text(piece.points.back()) +
                               (in_hole ? " lies in a hole and is left out" : " lies outside the domain and is left out"));
      continue;
    }
    if (piece.snap_front) piece.points.front() = onto_ring(region, ring_inserts, piece.points.front());
    if (piece.snap_back) piece.points.back() = onto_ring(region, ring_inserts, piece.points.back());
    if (piece.points.size() == 2 && piece.points[0] == piece.points[1]) continue;
    out.push_back({std::move(piece.points), stretches.closed_kept, c.source_feature, c.name, c.kind, c.size});
    kept = true;
  }
  if (!kept && !on_boundary)  // a curve lying along the boundary is already in the mesh
    throw InputError(name + " lies outside the domain, at " + point_text(lerp(c.points[0], c.points[1], 0.5)));
}

// The insides of closed curves with a size, which their pieces no longer enclose once cut (each kept once, so
// splitting twice adds nothing).
void keep_size_areas(Region& region) {
  for (const FeatureCurve& c : region.features) {
    if (!c.closed || c.size <= 0.0) continue;
    const bool known = std::any_of(region.size_areas.begin(), region.size_areas.end(),
                                   [&](const Ring& r) { return r.points == c.points && r.size == c.size; });
    if (!known) region.size_areas.push_back({c.points, -1, false, c.source_feature, c.name, c.size});
  }
}

}  // namespace

FeatureSplitStats split_features(Region& region, const FeatureSplitOptions& options) {
  FeatureSplitStats stats;
  if (region.features.empty()) return stats;
  keep_size_areas(region);
  const double tol = options.snap_relative * region.bounding_box().diagonal();

  Inserts inserts = crossing_points(collect_pieces(region), tol, stats);
  insert_into_rings(region, inserts, stats);
  // Every curve with its crossing points inserted, and which of its segments run along a ring.
  const std::size_t nf = region.features.size();
  std::vector<std::vector<Vec2>> rebuilt(nf);
  for (std::size_t f = 0; f < nf; ++f) {
    const FeatureCurve& c = region.features[f];
    rebuilt[f] = with_inserts(inserts, -1 - static_cast<int>(f), c.points, c.closed);
  }
  const std::vector<std::vector<std::uint8_t>> along = segments_along_rings(region, rebuilt, tol);
  // Ends of kept stretches next to a stretch along the boundary, moved onto the nearest ring segment.
  Inserts ring_inserts;
  std::vector<FeatureCurve> out;
  for (std::size_t f = 0; f < nf; ++f) {
    const FeatureCurve& c = region.features[f];
    const std::string name = region.source + ": feature " + std::to_string(c.source_feature) + " (curve " + std::to_string(f) + ")";
    const std::vector<std::uint8_t> cut = cut_points(inserts, -1 - static_cast<int>(f), rebuilt[f]);
    keep_stretches_in_domain(region, c, name, split_into_stretches(rebuilt[f], c.closed, cut, along[f]), tol, options,
                             ring_inserts, out, stats);
  }
  if (!ring_inserts.empty()) insert_into_rings(region, ring_inserts, stats);
  // Only the stretches' warnings are capped (pieces left outside are each named), so count them, not all.
  if (stats.stretches_along_boundary > kStretchWarnings)
    stats.warnings.push_back(region.source + ": ... and " +
                             std::to_string(stats.stretches_along_boundary - kStretchWarnings) +
                             " more stretches of feature curves along the boundary");
  region.features = std::move(out);
  return stats;
}

}  // namespace polysquare
