#include "polysquare/input/split_features.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>

#include "polysquare/core/error.h"

namespace polysquare {
namespace {

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

double distance_to_rings(const Region& region, Vec2 p) {
  double d = INFINITY;
  for (const Ring& r : region.rings)
    for (std::size_t i = 0; i < r.points.size(); ++i)
      d = std::min(d, point_segment_distance(p, r.points[i], r.points[(i + 1) % r.points.size()]));
  return d;
}

std::string pt(Vec2 p) {
  std::ostringstream os;
  os.precision(12);
  os << "(" << p.x << ", " << p.y << ")";
  return os.str();
}

}  // namespace

FeatureSplitStats split_features(Region& region, const FeatureSplitOptions& options) {
  FeatureSplitStats stats;
  if (region.features.empty()) return stats;
  const double tol = options.snap_relative * region.bounding_box().diagonal();

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
  // Points to insert: per (owner, segment index), parameter -> point. Each crossing point is computed once and
  // given to both owners, so the two curves share the exact same coordinate.
  std::map<std::pair<int, int>, std::vector<std::pair<double, Vec2>>> inserts;
  std::sort(pieces.begin(), pieces.end(), [](const Piece& s, const Piece& t) { return std::min(s.a.x, s.b.x) < std::min(t.a.x, t.b.x); });
  for (std::size_t i = 0; i < pieces.size(); ++i) {
    const double maxx = std::max(pieces[i].a.x, pieces[i].b.x);
    for (std::size_t j = i + 1; j < pieces.size() && std::min(pieces[j].a.x, pieces[j].b.x) <= maxx; ++j) {
      const Piece &s = pieces[i], &t = pieces[j];
      if (s.owner >= 0 && t.owner >= 0) continue;  // ring-ring contacts were refused by validation
      if (s.owner == t.owner) continue;            // a curve's own segments: self-crossings are not split
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
  }
  // A polyline with its crossing points inserted in order along each segment.
  auto rebuild = [&](int owner, const std::vector<Vec2>& pts, bool closed) {
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
  };
  for (std::size_t r = 0; r < region.rings.size(); ++r) {
    const std::size_t before = region.rings[r].points.size();
    region.rings[r].points = rebuild(static_cast<int>(r), region.rings[r].points, true);
    stats.ring_vertices_added += region.rings[r].points.size() - before;
  }
  std::vector<FeatureCurve> out;
  for (std::size_t f = 0; f < region.features.size(); ++f) {
    const FeatureCurve& c = region.features[f];
    const int owner = -1 - static_cast<int>(f);
    const std::vector<Vec2> pts = rebuild(owner, c.points, c.closed);
    // The curve is cut at every point where it meets something else.
    std::vector<std::pair<double, double>> crossing;
    for (const auto& [key, list] : inserts)
      if (key.first == owner)
        for (const auto& item : list) crossing.emplace_back(item.second.x, item.second.y);
    std::sort(crossing.begin(), crossing.end());
    std::vector<std::uint8_t> cut(pts.size());
    for (std::size_t i = 0; i < pts.size(); ++i)
      cut[i] = std::binary_search(crossing.begin(), crossing.end(), std::make_pair(pts[i].x, pts[i].y));
    std::vector<std::vector<Vec2>> parts;
    bool closed_kept = false;
    const bool any_cut = std::find(cut.begin(), cut.end(), 1) != cut.end();
    if (c.closed && !any_cut) {
      parts.push_back(pts);
      closed_kept = true;
    } else {
      // Start at a cut for closed curves so pieces do not wrap around.
      std::size_t start = 0;
      if (c.closed) start = static_cast<std::size_t>(std::find(cut.begin(), cut.end(), 1) - cut.begin());
      const std::size_t n = pts.size(), steps = c.closed ? n : n - 1;
      std::vector<Vec2> cur{pts[start]};
      for (std::size_t k = 1; k <= steps; ++k) {
        const std::size_t i = (start + k) % n;
        cur.push_back(pts[i]);
        if (cut[i] || k == steps) {
          parts.push_back(cur);
          cur = {pts[i]};
        }
      }
    }
    bool kept = false, on_boundary = false;
    for (auto& piece : parts) {
      if (piece.size() < 2) continue;
      const Vec2 probe = lerp(piece[0], piece[1], 0.5);
      const bool along_boundary = distance_to_rings(region, probe) <= tol;
      if (along_boundary || !in_domain(region, probe)) {
        on_boundary |= along_boundary;
        ++stats.pieces_dropped;
        const bool in_hole = !along_boundary && inside_an_outer_ring(region, probe);
        if (in_hole) {
          if (!options.clip_holes)
            throw InputError(region.source + ": feature " + std::to_string(c.source_feature) + " (curve " + std::to_string(f) +
                             ") crosses a hole at " + pt(piece.front()) + " (--repair clips it)");
          ++stats.pieces_in_holes;
        }
        stats.dropped.push_back(region.source + ": feature " + std::to_string(c.source_feature) + " (curve " +
                                std::to_string(f) + "): a piece from " + pt(piece.front()) + " to " + pt(piece.back()) +
                                (along_boundary ? " lies along the boundary and is meshed as boundary"
                                 : in_hole      ? " lies in a hole and is left out"
                                                : " lies outside the domain and is left out"));
        continue;
      }
      out.push_back({std::move(piece), closed_kept, c.source_feature, c.name, c.kind});
      kept = true;
    }
    if (!kept && !on_boundary)  // a curve lying along the boundary is already in the mesh
      throw InputError(region.source + ": feature " + std::to_string(c.source_feature) + " (curve " + std::to_string(f) +
                       ") lies outside the domain, at " + pt(lerp(c.points[0], c.points[1], 0.5)));
  }
  region.features = std::move(out);
  return stats;
}

}  // namespace polysquare
