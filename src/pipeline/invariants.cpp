#include "polysquare/pipeline/invariants.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <unordered_map>
#include <unordered_set>

#include "polysquare/core/quad_topology.h"
#include "polysquare/smooth/smooth.h"

namespace polysquare {

namespace {

// Sign of orient2(a, b, c), exact: the floating-point value where its error bound (Shewchuk's ccwerrboundA) says
// the sign is sure, CGAL's exact predicate otherwise. Touching quads put vertices exactly on each other's edges,
// where a rounded sign would turn a shared edge into an overlap.
int orientation(Vec2 a, Vec2 b, Vec2 c) {
  const double bx = b.x - a.x, by = b.y - a.y, cx = c.x - a.x, cy = c.y - a.y;
  // Shared nodes, answered without the exact predicate: a difference of doubles is zero only when they are equal.
  if ((bx == 0.0 || cy == 0.0) && (by == 0.0 || cx == 0.0)) return 0;
  if (b == c) return 0;
  const double l = bx * cy, r = by * cx, det = l - r;
  const double bound = 3.3306690738754716e-16 * (std::abs(l) + std::abs(r));
  if (det > bound) return 1;
  if (det < -bound) return -1;
  using K = CGAL::Exact_predicates_inexact_constructions_kernel;
  return static_cast<int>(CGAL::orientation(K::Point_2(a.x, a.y), K::Point_2(b.x, b.y), K::Point_2(c.x, c.y)));
}

using Triangle = std::array<Vec2, 3>;  // counter-clockwise, positive area

// The quad's interior as the interiors of at most two counter-clockwise triangles (up to the diagonal): split
// along a diagonal that lies inside it (from the reflex corner of a non-convex quad); triangles of zero area
// have no interior and are left out. A self-crossing quad is split along 0-2, each half turned counter-clockwise.
int quad_triangles(const std::array<Vec2, 4>& p, std::array<Triangle, 2>& out) {
  const int o012 = orientation(p[0], p[1], p[2]), o023 = orientation(p[0], p[2], p[3]);
  const int o123 = orientation(p[1], p[2], p[3]), o130 = orientation(p[1], p[3], p[0]);
  std::array<Triangle, 2> t{Triangle{p[0], p[1], p[2]}, Triangle{p[0], p[2], p[3]}};
  std::array<int, 2> o{o012, o023};
  if (o012 * o023 < 0 && o123 * o130 >= 0) {
    t = {Triangle{p[1], p[2], p[3]}, Triangle{p[1], p[3], p[0]}};
    o = {o123, o130};
  }
  int n = 0;
  for (int k = 0; k < 2; ++k) {
    if (o[k] == 0) continue;
    out[n] = t[k];
    if (o[k] < 0) std::swap(out[n][1], out[n][2]);
    ++n;
  }
  return n;
}

// Interiors of two counter-clockwise triangles intersect unless the line of an edge of one has the whole other
// triangle on its outer side or on it (separating axis test: for convex polygons an edge line always separates).
bool interiors_intersect(const Triangle& t, const Triangle& u) {
  auto separates = [](const Triangle& a, const Triangle& b) {
    for (int e = 0; e < 3; ++e) {
      const Vec2 p = a[e], q = a[(e + 1) % 3];
      if (orientation(p, q, b[0]) <= 0 && orientation(p, q, b[1]) <= 0 && orientation(p, q, b[2]) <= 0) return true;
    }
    return false;
  };
  return !separates(t, u) && !separates(u, t);
}

// A point inside both triangles: the mean of the corners of their intersection (t clipped by u's half-planes).
Vec2 common_point(const Triangle& t, const Triangle& u) {
  std::vector<Vec2> poly(t.begin(), t.end());
  for (int e = 0; e < 3 && !poly.empty(); ++e) {
    const Vec2 a = u[e], b = u[(e + 1) % 3];
    std::vector<Vec2> next;
    for (std::size_t i = 0; i < poly.size(); ++i) {
      const Vec2 p = poly[i], q = poly[(i + 1) % poly.size()];
      const double dp = orient2(a, b, p), dq = orient2(a, b, q);
      if (dp >= 0) next.push_back(p);
      if ((dp >= 0) != (dq >= 0)) next.push_back(lerp(p, q, dp / (dp - dq)));
    }
    poly = std::move(next);
  }
  Vec2 c{};
  for (Vec2 p : poly) c = c + (1.0 / static_cast<double>(poly.size())) * p;
  return poly.empty() ? t[0] : c;
}

// Box2::add's fmin/fmax are library calls; a NaN here makes a box that is not finite, which callers skip.
Box2 quad_box(const QuadMesh& mesh, std::size_t q) {
  const auto& v = mesh.quads[q];
  const Vec2 a = mesh.nodes[static_cast<std::size_t>(v[0])], b = mesh.nodes[static_cast<std::size_t>(v[1])],
             c = mesh.nodes[static_cast<std::size_t>(v[2])], d = mesh.nodes[static_cast<std::size_t>(v[3])];
  Box2 box;
  box.lo = {std::min(std::min(a.x, b.x), std::min(c.x, d.x)), std::min(std::min(a.y, b.y), std::min(c.y, d.y))};
  box.hi = {std::max(std::max(a.x, b.x), std::max(c.x, d.x)), std::max(std::max(a.y, b.y), std::max(c.y, d.y))};
  if (!(std::isfinite(box.lo.x) && std::isfinite(box.lo.y) && std::isfinite(box.hi.x) && std::isfinite(box.hi.y)))
    box = Box2{};
  return box;
}

// What the pair test reads of one quad, computed once per grid cell.
struct QuadShape {
  std::uint32_t q = 0;
  Box2 box;
  std::array<Vec2, 4> p;            // counter-clockwise when convex (a clockwise convex quad is turned)
  std::array<std::int32_t, 4> v{};  // its nodes, in the order of p
  bool complete = false;            // the fields below are set (complete_shape)
  bool convex = false;              // every corner strictly convex
  int triangles = 0;                // otherwise: its interior as triangles
  std::array<Triangle, 2> t;
};

// The rest of the shape of s.q (its box is there already): only for quads whose box meets another's.
void complete_shape(const QuadMesh& mesh, QuadShape& s) {
  s.v = mesh.quads[s.q];
  for (int k = 0; k < 4; ++k) s.p[k] = mesh.nodes[static_cast<std::size_t>(s.v[k])];
  int turns = 0;
  for (int k = 0; k < 4; ++k) turns += orientation(s.p[(k + 3) % 4], s.p[k], s.p[(k + 1) % 4]);
  if (turns == -4) {
    std::reverse(s.p.begin(), s.p.end());
    std::reverse(s.v.begin(), s.v.end());
  }
  s.convex = turns == 4 || turns == -4;
  if (!s.convex) s.triangles = quad_triangles(s.p, s.t);
  s.complete = true;
}

// Whether the line of an edge of convex a has all of convex b on its outer side or on it.
bool separates(const QuadShape& a, const QuadShape& b) {
  for (int e = 0; e < 4; ++e) {
    const Vec2 p = a.p[e], q = a.p[(e + 1) % 4];
    bool all_out = true;
    for (int k = 0; k < 4 && all_out; ++k) all_out = orientation(p, q, b.p[k]) <= 0;
    if (all_out) return true;
  }
  return false;
}

bool shapes_overlap(const QuadShape& a, const QuadShape& b) {
  if (a.convex && b.convex) {
    // Neighbours across an edge (one runs it forward, the other backward) lie on either side of its line.
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j)
        if (a.v[i] == b.v[(j + 1) % 4] && a.v[(i + 1) % 4] == b.v[j]) return false;
    return !separates(a, b) && !separates(b, a);
  }
  std::array<Triangle, 2> ta = a.t, tb = b.t;
  int na = a.triangles, nb = b.triangles;
  if (a.convex) na = quad_triangles(a.p, ta);
  if (b.convex) nb = quad_triangles(b.p, tb);
  for (int i = 0; i < na; ++i)
    for (int j = 0; j < nb; ++j)
      if (interiors_intersect(ta[i], tb[j])) return true;
  return false;
}



std::array<Vec2, 4> quad_points(const QuadMesh& mesh, std::size_t q) {
  std::array<Vec2, 4> p;
  for (int k = 0; k < 4; ++k) p[k] = mesh.nodes[static_cast<std::size_t>(mesh.quads[q][k])];
  return p;
}

// The quads' bounding boxes on a grid: each quad listed in every cell its box meets (counting sort: offsets per
// cell in `start`, then the entries). Cells are about the mean quad extent (a quad's box then meets about four
// cells), no more cells than quads (a sparse region, a coast in a large bounding box, widens them).
struct QuadGrid {
  Box2 all;
  double cell = 0.0;
  std::size_t nx = 0, ny = 0;
  std::vector<std::uint32_t> start, in_cell;
  void cell_of(Vec2 p, std::size_t& ix, std::size_t& iy) const {
    ix = std::min(nx - 1, static_cast<std::size_t>(std::max(0.0, std::floor((p.x - all.lo.x) / cell))));
    iy = std::min(ny - 1, static_cast<std::size_t>(std::max(0.0, std::floor((p.y - all.lo.y) / cell))));
  }
  // Calls f(c) for every cell c that quad q's box meets.
  template <typename F>
  void for_cells(const QuadMesh& mesh, std::size_t q, F&& f) const {
    const Box2 b = quad_box(mesh, q);
    std::size_t x0, y0, x1, y1;
    cell_of(b.lo, x0, y0);
    cell_of(b.hi, x1, y1);
    for (std::size_t iy = y0; iy <= y1; ++iy)
      for (std::size_t ix = x0; ix <= x1; ++ix) f(iy * nx + ix);
  }
};

// The grid of the quads with finite coordinates; false when fewer than two have them.
bool quad_grid(const QuadMesh& mesh, QuadGrid& g) {
  const std::size_t n = mesh.quads.size();
  double extent_sum = 0.0;
  std::size_t finite = 0;
  std::vector<std::uint8_t> usable(n, 0);
  for (std::size_t q = 0; q < n; ++q) {
    const Box2 b = quad_box(mesh, q);
    if (!(b.lo.x <= b.hi.x)) continue;  // a non-finite coordinate
    usable[q] = 1;
    g.all.add(b.lo);
    g.all.add(b.hi);
    extent_sum += (b.hi.x - b.lo.x) + (b.hi.y - b.lo.y);
    ++finite;
  }
  if (finite < 2) return false;
  const double w = g.all.hi.x - g.all.lo.x, h = g.all.hi.y - g.all.lo.y;
  g.cell = std::max(0.75 * extent_sum / static_cast<double>(finite), std::sqrt(w * h / static_cast<double>(finite)));
  if (!(g.cell > 0.0)) g.cell = std::max({w, h, 1.0});
  const auto cells_along = [&](double len) {
    return static_cast<std::size_t>(std::min(std::floor(len / g.cell), static_cast<double>(finite))) + 1;
  };
  g.nx = cells_along(w);
  g.ny = cells_along(h);
  const std::size_t nx = g.nx, ny = g.ny;
  g.start.assign(nx * ny + 1, 0);
  std::size_t entries = 0;
  for (std::size_t q = 0; q < n; ++q)
    if (usable[q]) g.for_cells(mesh, q, [&](std::size_t c) { ++g.start[c + 1]; ++entries; });
  if (entries >= std::numeric_limits<std::uint32_t>::max())
    throw std::length_error("overlap check: too many grid entries (" + std::to_string(entries) + ")");
  for (std::size_t c = 0; c < nx * ny; ++c) g.start[c + 1] += g.start[c];
  std::vector<std::uint32_t> fill(g.start.begin(), g.start.end() - 1);
  g.in_cell.resize(entries);
  for (std::size_t q = 0; q < n; ++q)
    if (usable[q]) g.for_cells(mesh, q, [&](std::size_t c) { g.in_cell[fill[c]++] = static_cast<std::uint32_t>(q); });
  return true;
}

// Overlapping pairs: how many, and the first (a < b) in (a, b) order.
struct Overlaps {
  std::size_t pairs = 0;
  std::uint32_t a = std::numeric_limits<std::uint32_t>::max(), b = 0;
  std::vector<std::uint32_t> quads;  // of every pair, in the order found
  static Overlaps reduce(Overlaps x, const Overlaps& y) {
    x.pairs += y.pairs;
    x.quads.insert(x.quads.end(), y.quads.begin(), y.quads.end());
    if (y.pairs && (y.a < x.a || (y.a == x.a && y.b < x.b))) { x.a = y.a; x.b = y.b; }
    return x;
  }
};

// Pairs whose boxes overlap with positive area (interiors of boxes that only touch cannot meet), each tested
// once: in the cell holding the lower-left corner of the two boxes' intersection. Those of cell c into acc;
// `shapes` is scratch.
void overlaps_in_cell(const QuadMesh& mesh, const QuadGrid& g, std::size_t c, std::vector<QuadShape>& shapes,
                      Overlaps& acc) {
  const std::size_t m = g.start[c + 1] - g.start[c];
  if (m < 2) return;
  shapes.resize(m);
  for (std::size_t i = 0; i < m; ++i) {
    shapes[i].q = g.in_cell[g.start[c] + i];
    shapes[i].box = quad_box(mesh, shapes[i].q);
    shapes[i].complete = false;
  }
  for (std::size_t i = 0; i < m; ++i)
    for (std::size_t j = i + 1; j < m; ++j) {
      const Box2 &p = shapes[i].box, &r = shapes[j].box;
      if (!(p.lo.x < r.hi.x && r.lo.x < p.hi.x && p.lo.y < r.hi.y && r.lo.y < p.hi.y)) continue;
      std::size_t ix, iy;
      g.cell_of({std::max(p.lo.x, r.lo.x), std::max(p.lo.y, r.lo.y)}, ix, iy);
      if (iy * g.nx + ix != c) continue;
      if (!shapes[i].complete) complete_shape(mesh, shapes[i]);
      if (!shapes[j].complete) complete_shape(mesh, shapes[j]);
      if (!shapes_overlap(shapes[i], shapes[j])) continue;
      Overlaps one;
      one.pairs = 1;
      one.a = std::min(shapes[i].q, shapes[j].q);
      one.b = std::max(shapes[i].q, shapes[j].q);
      one.quads = {one.a, one.b};
      acc = Overlaps::reduce(acc, one);
    }
}

}  // namespace

QuadOverlaps find_overlapping_quads(const QuadMesh& mesh) {
  QuadOverlaps result;
  const std::size_t n = mesh.quads.size();
  if (n < 2) return result;
  QuadGrid g;
  if (!quad_grid(mesh, g)) return result;
  const Overlaps found = oneapi::tbb::parallel_reduce(
      oneapi::tbb::blocked_range<std::size_t>(0, g.nx * g.ny, 1024), Overlaps{},
      [&](const oneapi::tbb::blocked_range<std::size_t>& range, Overlaps acc) {
        std::vector<QuadShape> shapes;
        for (std::size_t c = range.begin(); c < range.end(); ++c) overlaps_in_cell(mesh, g, c, shapes, acc);
        return acc;
      },
      Overlaps::reduce);
  result.pairs = found.pairs;
  result.quads = found.quads;
  std::sort(result.quads.begin(), result.quads.end());
  result.quads.erase(std::unique(result.quads.begin(), result.quads.end()), result.quads.end());
  if (found.pairs) {
    result.first_a = found.a;
    result.first_b = found.b;
    std::array<Triangle, 2> ta, tb;
    const int na = quad_triangles(quad_points(mesh, found.a), ta), nb = quad_triangles(quad_points(mesh, found.b), tb);
    for (int i = 0; i < na; ++i)
      for (int j = 0; j < nb; ++j)
        if (interiors_intersect(ta[i], tb[j])) { result.at = common_point(ta[i], tb[j]); i = na; break; }
  }
  return result;
}

namespace {

// The quad edges grouped by their lower node (a counting sort), each group sorted: how many quads share an edge,
// and every edge in node order. A hash map of edge keys took 32 s and most of 2 GB on 17M quads.
class EdgeTable {
 public:
  explicit EdgeTable(std::size_t nodes) : start_(nodes + 1, 0) {}
  template <class ForEachEdge>
  void build(ForEachEdge&& for_each_edge) {
    for_each_edge([&](std::int32_t a, std::int32_t b) { ++start_[static_cast<std::size_t>(std::min(a, b)) + 1]; });
    for (std::size_t v = 1; v < start_.size(); ++v) start_[v] += start_[v - 1];
    upper_.resize(start_.back());
    std::vector<std::size_t> fill(start_.begin(), start_.end() - 1);
    for_each_edge([&](std::int32_t a, std::int32_t b) { upper_[fill[static_cast<std::size_t>(std::min(a, b))]++] = std::max(a, b); });
    for (std::size_t v = 0; v + 1 < start_.size(); ++v) std::sort(upper_.begin() + start_[v], upper_.begin() + start_[v + 1]);
  }
  /// How many times the edge (a, b) was listed (0 for nodes out of range).
  std::size_t count(std::int32_t a, std::int32_t b) const {
    const auto lo = static_cast<std::size_t>(std::min(a, b));
    if (std::min(a, b) < 0 || lo + 1 >= start_.size()) return 0;
    const auto first = upper_.begin() + static_cast<std::ptrdiff_t>(start_[lo]);
    const auto last = upper_.begin() + static_cast<std::ptrdiff_t>(start_[lo + 1]);
    const auto range = std::equal_range(first, last, std::max(a, b));
    return static_cast<std::size_t>(range.second - range.first);
  }
  /// f(a, b, count) for every distinct edge, a < b, in node order.
  template <class F>
  void for_each(F&& f) const {
    for (std::size_t v = 0; v + 1 < start_.size(); ++v)
      for (std::size_t i = start_[v]; i < start_[v + 1];) {
        std::size_t j = i + 1;
        while (j < start_[v + 1] && upper_[j] == upper_[i]) ++j;
        f(static_cast<std::int32_t>(v), upper_[i], j - i);
        i = j;
      }
  }

 private:
  std::vector<std::size_t> start_;
  std::vector<std::int32_t> upper_;
};

}  // namespace

InvariantReport check_invariants(const QuadMesh& mesh) {
  InvariantReport r;
  auto problem = [&](const std::string& text) {
    if (r.first_problem.empty()) r.first_problem = text;
  };
  std::vector<std::uint8_t> counted(mesh.quads.size(), 0);  // degenerate quads' edges are not counted
  for (std::size_t q = 0; q < mesh.quads.size(); ++q) {
    const auto& quad = mesh.quads[q];
    bool degenerate = false;
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) degenerate |= quad[i] == quad[j];
    if (degenerate) {
      r.degenerate_quads++;
      problem("quad " + std::to_string(q) + " repeats a node");
      continue;
    }
    counted[q] = 1;
    if (!(quad_min_corner_sj(mesh, q) > 0.0)) {  // NaN too: a non-finite node is no valid corner
      r.inverted_quads++;
      const Vec2 p = mesh.nodes[quad[0]];
      problem("quad " + std::to_string(q) + " at (" + std::to_string(p.x) + ", " + std::to_string(p.y) +
              ") is inverted or has a flat corner");
    }
  }
  EdgeTable edges(mesh.nodes.size());
  edges.build([&](auto&& add) {
    for (std::size_t q = 0; q < mesh.quads.size(); ++q)
      if (counted[q])
        for (int k = 0; k < 4; ++k) add(mesh.quads[q][k], mesh.quads[q][(k + 1) % 4]);
  });
  // Overlaps before the edge counts: two parts meshed over each other is the cause, their cracks the symptom.
  const QuadOverlaps overlaps = find_overlapping_quads(mesh);
  r.overlapping_quad_pairs = overlaps.pairs;
  if (overlaps.pairs)
    problem(std::to_string(overlaps.pairs) + (overlaps.pairs == 1 ? " pair of quads overlaps" : " pairs of quads overlap") +
            ", first quads " + std::to_string(overlaps.first_a) + " and " + std::to_string(overlaps.first_b) + " at " +
            at_text(overlaps.at));
  if (!mesh.triangles.empty()) problem(std::to_string(mesh.triangles.size()) + " triangles in an all-quad mesh");
  EdgeTable tagged(mesh.nodes.size());
  tagged.build([&](auto&& add) {
    for (const auto& e : mesh.boundary_edges)
      if (std::min(e[0], e[1]) >= 0 && static_cast<std::size_t>(std::max(e[0], e[1])) < mesh.nodes.size()) add(e[0], e[1]);
  });
  edges.for_each([&](std::int32_t a, std::int32_t b, std::size_t count) {
    if (count > 2) { r.non_manifold_edges++; problem("an edge is shared by " + std::to_string(count) + " quads"); }
    if (count == 1 && !tagged.count(a, b)) {
      r.untagged_boundary_edges++;
      // Where: a crack between pieces that do not share their nodes, or a boundary edge that lost its tag.
      problem("a boundary edge from " + at_text(mesh.nodes[static_cast<std::size_t>(a)]) + " to " +
              at_text(mesh.nodes[static_cast<std::size_t>(b)]) + " is not on the input boundary");
    }
  });
  std::size_t valid_tags = 0;
  tagged.for_each([&](std::int32_t a, std::int32_t b, std::size_t count) {
    valid_tags += count;
    if (count != 1 || edges.count(a, b) != 1) {
      r.tagged_edges_not_boundary++;
      problem("a tagged boundary edge does not have exactly one quad");
    }
  });
  if (valid_tags != mesh.boundary_edges.size()) {
    r.tagged_edges_not_boundary += mesh.boundary_edges.size() - valid_tags;
    problem("a tagged boundary edge names a node that does not exist");
  }
  for (const auto& e : mesh.feature_edges)
    if (!edges.count(e[0], e[1])) {
      r.feature_edges_not_in_mesh++;
      problem("a feature edge is not an edge of the mesh");
    }
  return r;
}

std::vector<std::uint8_t> quads_beside_cracks(const QuadMesh& mesh) {
  const auto edge_count = quad_edge_counts(mesh);
  std::unordered_set<std::uint64_t> tagged;
  for (const auto& e : mesh.boundary_edges) tagged.insert(edge_key(e[0], e[1]));
  std::vector<std::uint8_t> out(mesh.quads.size(), 0);
  for (std::size_t q = 0; q < mesh.quads.size(); ++q)
    for (int k = 0; k < 4; ++k) {
      const std::uint64_t key = edge_key(mesh.quads[q][k], mesh.quads[q][(k + 1) % 4]);
      const int count = edge_count.count(key);
      out[q] |= count > 2 || (count == 1 && !tagged.count(key));
    }
  return out;
}

}  // namespace polysquare
