#include "polysquare/smooth/untangle.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include "polysquare/core/geometry.h"
#include "polysquare/core/quad_topology.h"

namespace polysquare {
namespace {

// A corner condition on one node: dot(n, v) + d >= 0 with |n| = 1, so that dot(n, v) + d is v's distance to
// the line on which the corner degenerates (positive on the convex side).
struct HalfPlane {
  Vec2 n;
  double d;
  double at(Vec2 v) const { return dot(n, v) + d; }
};

// The part of the convex polygon `poly` where h.at(v) >= t, into `out` (cleared first).
void clip(const std::vector<Vec2>& poly, const HalfPlane& h, double t, std::vector<Vec2>& out) {
  out.clear();
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const Vec2 a = poly[i], b = poly[(i + 1) % poly.size()];
    const double fa = h.at(a) - t, fb = h.at(b) - t;
    if (fa >= 0) out.push_back(a);
    if ((fa >= 0) != (fb >= 0)) out.push_back(lerp(a, b, fa / (fa - fb)));
  }
}

// The polygon of the points of `box` where every condition of hs is >= t, in `poly` (empty: none). `spare` is
// scratch: the bisection below clips about 30 times per node move, and allocating a vector per clip cost about
// two thirds as much again as the clipping (a star of 40 spikes: 91 -> 71 CPU seconds without it).
void kernel(const std::vector<HalfPlane>& hs, const std::vector<Vec2>& box, double t, std::vector<Vec2>& poly,
            std::vector<Vec2>& spare) {
  poly.assign(box.begin(), box.end());
  for (const HalfPlane& h : hs) {
    clip(poly, h, t, spare);
    poly.swap(spare);
    if (poly.empty()) break;
  }
}

Vec2 centroid(const std::vector<Vec2>& poly) {
  double area = 0.0;
  Vec2 c{};
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const Vec2 a = poly[i], b = poly[(i + 1) % poly.size()];
    const double w = cross(a, b);
    area += w;
    c = c + w * (a + b);
  }
  if (std::abs(area) < 1e-300) {
    Vec2 m{};
    for (Vec2 p : poly) m = m + p;
    return (1.0 / static_cast<double>(poly.size())) * m;
  }
  return (1.0 / (3.0 * area)) * c;
}

// The condition "corner (a, b, c) is convex" (orient2(a, b, c) > 0) on the one of its nodes at index `which`,
// in coordinates relative to `origin`; false when the other two coincide (no condition on that node).
bool corner_condition(Vec2 a, Vec2 b, Vec2 c, int which, HalfPlane& h) {
  // orient2 is linear in each argument: orient2(a, b, c) = cross(b - a, c - a).
  Vec2 p, q;  // the other two nodes, in the order that keeps the orientation: orient2(p, q, v)
  if (which == 0) { p = b; q = c; }
  else if (which == 1) { p = c; q = a; }
  else { p = a; q = b; }
  const Vec2 e = q - p;
  const double len = std::sqrt(dot(e, e));
  if (len <= 0.0) return false;
  // orient2(p, q, v) = cross(e, v - p): positive with v left of p -> q.
  h.n = Vec2{-e.y / len, e.x / len};
  h.d = -dot(h.n, p);
  return true;
}

double quad_sj(const QuadMesh& mesh, std::size_t q) {
  const auto& c = mesh.quads[q];
  return quad_min_sj(mesh.nodes[static_cast<std::size_t>(c[0])], mesh.nodes[static_cast<std::size_t>(c[1])],
                     mesh.nodes[static_cast<std::size_t>(c[2])], mesh.nodes[static_cast<std::size_t>(c[3])]);
}

// The movable nodes of folded quads and of the quads around those nodes.
std::vector<std::uint8_t> nodes_near_folded(const QuadMesh& mesh, const NodeQuads& at, double target_sj) {
  std::vector<std::uint8_t> todo(mesh.nodes.size(), 0);
  for (std::size_t q = 0; q < mesh.quads.size(); ++q) {
    if (quad_sj(mesh, q) >= target_sj) continue;
    for (auto v : mesh.quads[q])
      for (std::size_t k = at.offset[static_cast<std::size_t>(v)]; k < at.offset[static_cast<std::size_t>(v) + 1]; ++k)
        for (auto u : mesh.quads[static_cast<std::size_t>(at.quads[k])]) todo[static_cast<std::size_t>(u)] = 1;
  }
  return todo;
}

// The conditions of the three corners of each quad that move with v, in coordinates relative to v, into hs; lo
// and hi bound v's quads.
void corner_conditions(const QuadMesh& mesh, const NodeQuads& at, std::size_t v, std::vector<HalfPlane>& hs, Vec2& lo,
                       Vec2& hi) {
  const Vec2 origin = mesh.nodes[v];
  hs.clear();
  lo = Vec2{0, 0};
  hi = Vec2{0, 0};
  for (std::size_t k = at.offset[v]; k < at.offset[v + 1]; ++k) {
    const auto& quad = mesh.quads[static_cast<std::size_t>(at.quads[k])];
    int i = 0;
    while (static_cast<std::size_t>(quad[i]) != v) ++i;
    std::array<Vec2, 4> p;
    for (int c = 0; c < 4; ++c) {
      p[c] = mesh.nodes[static_cast<std::size_t>(quad[c])] - origin;
      lo = Vec2{std::min(lo.x, p[c].x), std::min(lo.y, p[c].y)};
      hi = Vec2{std::max(hi.x, p[c].x), std::max(hi.y, p[c].y)};
    }
    for (int c = 3; c <= 5; ++c) {  // corners i - 1, i, i + 1; v at index 2, 1, 0 of (prev, corner, next)
      const int corner = (i + c) % 4;
      HalfPlane h;
      if (corner_condition(p[(corner + 3) % 4], p[corner], p[(corner + 1) % 4], 5 - c, h)) hs.push_back(h);
    }
  }
}

// A place (relative to v) whose worst condition beats v's own (`worst`, at the origin), within the box lo - hi;
// nothing when there is none.
std::optional<Vec2> kernel_place(const std::vector<HalfPlane>& hs, Vec2 lo, Vec2 hi, double worst) {
  const std::vector<Vec2> box{lo, Vec2{hi.x, lo.y}, hi, Vec2{lo.x, hi.y}};
  const double span = std::max(hi.x - lo.x, hi.y - lo.y);
  if (span <= 0.0) return std::nullopt;
  // Bisection for the largest t with a non-empty kernel {v : every condition >= t}; v itself has t = worst.
  std::vector<Vec2> poly, spare;
  poly.reserve(hs.size() + 4), spare.reserve(hs.size() + 4);  // a convex polygon gains at most a vertex per clip
  double t_lo = worst, t_hi = span;
  for (int it = 0; it < 40 && t_hi - t_lo > 1e-9 * span; ++it) {
    const double t = 0.5 * (t_lo + t_hi);
    kernel(hs, box, t, poly, spare);
    (poly.empty() ? t_hi : t_lo) = t;
  }
  if (t_lo <= worst + 1e-9 * span) return std::nullopt;  // no better place
  // The centre of the kernel a little inside the best level, so that v is not pushed against one corner.
  const double t = t_lo > 0.0 ? 0.5 * t_lo : t_lo - 1e-6 * span;
  kernel(hs, box, std::max(t, worst), poly, spare);
  if (poly.empty()) return std::nullopt;
  Vec2 best = centroid(poly);
  double best_worst = INFINITY;
  for (const HalfPlane& h : hs) best_worst = std::min(best_worst, h.at(best));
  if (!(best_worst > worst)) return std::nullopt;
  return best;
}

// Moves node v to the best place its corner conditions allow (hs: scratch); false when it stays.
bool untangle_node(QuadMesh& mesh, const NodeQuads& at, std::size_t v, double target_sj, std::vector<HalfPlane>& hs) {
  const Vec2 origin = mesh.nodes[v];
  Vec2 lo, hi;
  corner_conditions(mesh, at, v, hs, lo, hi);
  if (hs.empty()) return false;
  // Quads around v below the target: a move that leaves more of them is refused even when it lifts the worst
  // corner (lifting one folded corner by folding another's quad spreads the tangle).
  auto below_around = [&] {
    std::size_t below = 0;
    for (std::size_t k = at.offset[v]; k < at.offset[v + 1]; ++k)
      below += quad_sj(mesh, static_cast<std::size_t>(at.quads[k])) < target_sj;
    return below;
  };
  const std::size_t below_before = below_around();
  double worst = INFINITY;
  for (const HalfPlane& h : hs) worst = std::min(worst, h.at(Vec2{0, 0}));
  const std::optional<Vec2> best = kernel_place(hs, lo, hi, worst);
  if (!best) return false;
  mesh.nodes[v] = origin + *best;
  if (below_around() > below_before) {
    mesh.nodes[v] = origin;
    return false;
  }
  return true;
}

}  // namespace

UntangleStats untangle_quads(QuadMesh& mesh, const std::vector<std::uint8_t>& movable, const UntangleOptions& options) {
  UntangleStats stats;
  const std::size_t nn = mesh.nodes.size();
  const NodeQuads at = node_quads(mesh);
  auto count_folded = [&] {
    std::size_t n = 0;
    for (std::size_t q = 0; q < mesh.quads.size(); ++q) n += quad_sj(mesh, q) < options.target_sj;
    return n;
  };
  stats.folded_before = count_folded();
  stats.folded_after = stats.folded_before;
  if (stats.folded_before == 0) return stats;

  std::vector<HalfPlane> hs;
  for (int sweep = 0; sweep < options.sweeps && stats.folded_after > 0; ++sweep) {
    // The nodes near folded quads, in node order.
    const std::vector<std::uint8_t> todo = nodes_near_folded(mesh, at, options.target_sj);
    std::size_t moved = 0;
    for (std::size_t v = 0; v < nn; ++v) {
      if (!todo[v] || !movable[v] || at.offset[v] == at.offset[v + 1]) continue;
      moved += untangle_node(mesh, at, v, options.target_sj, hs);
    }
    stats.moves += moved;
    stats.folded_after = count_folded();
    if (moved == 0) break;
  }
  return stats;
}

}  // namespace polysquare
