#include "polysquare/fallback/patch.h"
#include "polysquare/smooth/untangle.h"

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_face_base_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <set>
#include <string>
#include <unordered_map>
#include <unordered_set>

#include "polysquare/core/error.h"
#include "fallback/patch_valence.h"
#include "fallback/perfect_matching.h"
#include "polysquare/fallback/split_triangles.h"

namespace polysquare {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
struct NodeId {
  std::int32_t v = -1;  // -1 until set: tells a new CDT vertex from one already there
  operator std::int32_t() const { return v; }
  NodeId& operator=(std::int32_t x) { v = x; return *this; }
};
using Vb = CGAL::Triangulation_vertex_base_with_info_2<NodeId, K>;
using Fb = CGAL::Constrained_triangulation_face_base_2<K>;
using Tds = CGAL::Triangulation_data_structure_2<Vb, Fb>;
using CDT = CGAL::Constrained_Delaunay_triangulation_2<K, Tds, CGAL::Exact_predicates_tag>;

// Buckets of segments on a square grid, for "is this point at least r away from every segment" queries.
struct SegmentGrid {
  double cell;
  std::unordered_map<std::uint64_t, std::vector<std::pair<Vec2, Vec2>>> buckets;
  std::uint64_t key(long long i, long long j) const {
    return (static_cast<std::uint64_t>(i) << 32) ^ static_cast<std::uint64_t>(j & 0xffffffffLL);
  }
  void add(Vec2 a, Vec2 b) {
    const long long i0 = static_cast<long long>(std::floor(std::min(a.x, b.x) / cell));
    const long long i1 = static_cast<long long>(std::floor(std::max(a.x, b.x) / cell));
    const long long j0 = static_cast<long long>(std::floor(std::min(a.y, b.y) / cell));
    const long long j1 = static_cast<long long>(std::floor(std::max(a.y, b.y) / cell));
    for (long long i = i0; i <= i1; ++i)
      for (long long j = j0; j <= j1; ++j) buckets[key(i, j)].push_back({a, b});
  }
  // No segment within r of p: checks the cells around p out to r (3 x 3 up to r = cell).
  bool clear_of(Vec2 p, double r) const {
    const long long i = static_cast<long long>(std::floor(p.x / cell));
    const long long j = static_cast<long long>(std::floor(p.y / cell));
    const long long ring = std::max(1LL, static_cast<long long>(std::ceil(r / cell)));
    for (long long di = -ring; di <= ring; ++di)
      for (long long dj = -ring; dj <= ring; ++dj) {
        auto it = buckets.find(key(i + di, j + dj));
        if (it == buckets.end()) continue;
        for (const auto& [a, b] : it->second)
          if (point_segment_distance(p, a, b) < r) return false;
      }
    return true;
  }
};


// The loops of a patch as polygons, for inside tests (even-odd over all loops).
std::vector<std::vector<Vec2>> loop_polygons(const PatchInput& in) {
  std::vector<std::vector<Vec2>> loops;
  for (const PatchCurve& c : in.curves)
    if (c.loop) {
      loops.emplace_back();
      for (std::int32_t v : c.nodes) loops.back().push_back(in.nodes[static_cast<std::size_t>(v)]);
    }
  return loops;
}

bool inside_loops(const std::vector<std::vector<Vec2>>& loops, Vec2 p) {
  bool in_region = false;
  for (const auto& l : loops) in_region ^= point_in_ring(p, l);
  return in_region;
}

// The coarsest of the nested triangular lattices of spacing 2^k (k <= kMaxLatticeLevel) that point (i, j) of the
// finest one belongs to: rows j divisible by 2^k, every 2^k-th point of a row, alternate rows shifted by half.
constexpr int kMaxLatticeLevel = 8;
int lattice_level(long long i, long long j) {
  int k = 0;
  while (k < kMaxLatticeLevel) {
    const long long step = 1LL << (k + 1), half = 1LL << k;
    if (j % step != 0) break;
    const long long shift = (j / step) % 2 != 0 ? half : 0;
    if (((i - shift) % step + step) % step != 0) break;
    ++k;
  }
  return k;
}

// Interior vertices: a triangular lattice of `spacing` inside the loops, `clearance` from every segment. Graded (`field` given;
// `spacing` stands for the field's `least` size): a point stays where the coarsest lattice it belongs to is no
// coarser than the field asks there, so the spacing doubles in steps towards coarse sizes, and its clearance
// grows with it.
std::vector<Vec2> lattice_points(const std::vector<std::vector<Vec2>>& loops, const SegmentGrid& grid, double spacing,
                                 double clearance, Vec2 offset = {}, const SizeField* field = nullptr,
                                 double least = 1.0) {
  Box2 box;
  for (const auto& l : loops)
    for (Vec2 p : l) box.add(p);
  std::vector<Vec2> out;
  const double dy = spacing * std::sqrt(3.0) / 2.0;
  for (long long j = 0; box.lo.y + static_cast<double>(j) * dy <= box.hi.y; ++j)
    for (long long i = 0;; ++i) {
      const Vec2 p{box.lo.x + offset.x + (static_cast<double>(i) + 0.5 * static_cast<double>(j % 2)) * spacing,
                   box.lo.y + offset.y + static_cast<double>(j) * dy};
      if (p.x > box.hi.x) break;
      double scale = 1.0;
      if (field) {
        const int wanted = std::clamp(static_cast<int>(std::floor(std::log2(field->at(p) / least))), 0, kMaxLatticeLevel);
        if (lattice_level(i, j) < wanted) continue;
        scale = static_cast<double>(1LL << wanted);
      }
      if (inside_loops(loops, p) && grid.clear_of(p, scale * clearance)) out.push_back(p);
    }
  return out;
}

// Boundary and feature edges of the output, from the given curves' roles.
void tag_curve_edges(const PatchInput& in, QuadMesh& out) {
  for (const PatchCurve& c : in.curves) {
    const int n = static_cast<int>(c.nodes.size());
    for (int i = 0; i < (c.closed ? n : n - 1); ++i) {
      const std::array<std::int32_t, 2> e{c.nodes[i], c.nodes[(i + 1) % n]};
      if (c.role[i] == PatchEdgeRole::boundary) {
        out.boundary_edges.push_back(e);
        out.boundary_edge_ring.push_back(c.tag[i]);
      } else if (c.role[i] == PatchEdgeRole::feature) {
        out.feature_edges.push_back(e);
        out.feature_edge_curve.push_back(c.tag[i]);
      }
    }
  }
}

// The angle of quad q at its corner k, counter-clockwise from the next node's edge to the previous one's, in
// [0, 2 pi): above pi the corner is reflex (the quad folded there).
double corner_angle(const QuadMesh& out, const std::array<std::int32_t, 4>& q, int k) {
  const Vec2 p = out.nodes[static_cast<std::size_t>(q[k])], next = out.nodes[static_cast<std::size_t>(q[(k + 1) % 4])] - p,
             prev = out.nodes[static_cast<std::size_t>(q[(k + 3) % 4])] - p;
  const double angle = std::atan2(cross(next, prev), dot(next, prev));
  return angle < 0 ? angle + 2.0 * std::acos(-1.0) : angle;
}

// Replaces each quad with a corner at a given node above `limit` (radians) by an inner quad and four quads around
// it (its edges, shared with its neighbours, stay as they are), so that the node gets two corners there. With
// `single_only`, only corners of nodes in one quad count. Returns the number of quads replaced.
std::size_t inset_wide_given_corners(const PatchInput& in, double limit, bool single_only, QuadMesh& out) {
  std::vector<int> quads_at(out.nodes.size(), 0);
  for (const auto& q : out.quads)
    for (std::int32_t v : q) quads_at[static_cast<std::size_t>(v)]++;
  const std::size_t nq = out.quads.size();
  std::size_t replaced = 0;
  for (std::size_t i = 0; i < nq; ++i) {
    const auto q = out.quads[i];
    bool wide = false;
    for (int k = 0; k < 4 && !wide; ++k) {
      const auto v = static_cast<std::size_t>(q[k]);
      if (v >= in.nodes.size() || (single_only && quads_at[v] != 1)) continue;
      wide = corner_angle(out, q, k) > limit;
    }
    if (!wide) continue;
    ++replaced;
    Vec2 centre{};
    for (std::int32_t v : q) centre = centre + 0.25 * out.nodes[static_cast<std::size_t>(v)];
    std::array<std::int32_t, 4> inner{};
    for (int k = 0; k < 4; ++k) {
      inner[k] = static_cast<std::int32_t>(out.nodes.size());
      out.nodes.push_back(lerp(out.nodes[static_cast<std::size_t>(q[k])], centre, 0.5));
      out.node_kind.push_back(NodeKind::interior);
    }
    out.quads[i] = inner;
    for (int k = 0; k < 4; ++k) out.quads.push_back({q[k], q[(k + 1) % 4], inner[(k + 1) % 4], inner[k]});
  }
  return replaced;
}

// A free node in exactly two quads that share both its edges (a doublet: its two corners add up to a full turn,
// so one of them is reflex wherever it moves) is removed and its two quads merged into one; merged quads can
// leave new doublets, so this repeats. Free nodes left in no quad are dropped (the given ones keep their indices).
void collapse_doublets(const PatchInput& in, QuadMesh& out) {
  for (bool changed = true; changed;) {
    changed = false;
    std::vector<std::vector<std::int32_t>> quads_at(out.nodes.size());
    for (std::size_t i = 0; i < out.quads.size(); ++i)
      for (std::int32_t v : out.quads[i]) quads_at[static_cast<std::size_t>(v)].push_back(static_cast<std::int32_t>(i));
    std::vector<std::uint8_t> gone(out.quads.size(), 0);
    for (std::size_t v = in.nodes.size(); v < out.nodes.size(); ++v) {
      if (quads_at[v].size() != 2) continue;
      const auto ia = static_cast<std::size_t>(quads_at[v][0]), ib = static_cast<std::size_t>(quads_at[v][1]);
      if (gone[ia] || gone[ib]) continue;
      auto rotate_to = [&](std::array<std::int32_t, 4> q) {  // q with v first
        while (static_cast<std::size_t>(q[0]) != v) std::rotate(q.begin(), q.begin() + 1, q.end());
        return q;
      };
      const auto a = rotate_to(out.quads[ia]), b = rotate_to(out.quads[ib]);
      // a = (v, p, x, r), b = (v, r, y, p): the two quads meet along v-p and v-r.
      if (a[1] != b[3] || a[3] != b[1] || a[2] == b[2]) continue;
      out.quads[ia] = {a[1], a[2], a[3], b[2]};
      gone[ib] = 1;
      changed = true;
    }
    if (!changed) break;
    std::size_t kept = 0;
    for (std::size_t i = 0; i < out.quads.size(); ++i)
      if (!gone[i]) out.quads[kept++] = out.quads[i];
    out.quads.resize(kept);
  }
  std::vector<std::uint8_t> used(out.nodes.size(), 0);
  for (const auto& q : out.quads)
    for (std::int32_t v : q) used[static_cast<std::size_t>(v)] = 1;
  std::vector<std::int32_t> index(out.nodes.size(), -1);
  std::size_t kept = 0;
  for (std::size_t v = 0; v < out.nodes.size(); ++v) {
    if (v >= in.nodes.size() && !used[v]) continue;
    index[v] = static_cast<std::int32_t>(kept);
    out.nodes[kept] = out.nodes[v];
    out.node_kind[kept] = out.node_kind[v];
    ++kept;
  }
  if (kept == out.nodes.size()) return;
  out.nodes.resize(kept);
  out.node_kind.resize(kept);
  for (auto& q : out.quads)
    for (std::int32_t& v : q) v = index[static_cast<std::size_t>(v)];
}

// A given node in one quad only keeps the whole angle of the patch there as that quad's corner: on a straight
// stretch that corner is flat (scaled Jacobian 0) whatever the smoothing does, since the given nodes are fixed,
// so such corners above options.inset_angle_deg are split first. Then plain Laplacian sweeps over the nodes after
// the given ones (a triangulation that hugs a convoluted boundary can give quads that start folded) and the
// untangler; a quad still flat or reflex at a given node (no move of the free nodes can open it: two triangles of given
// nodes paired into a non-convex quad) is split the same way and untangled again. Last, the check that every
// given node is used and, with refuse_folded, that no quad is folded.
void smooth_patch(const PatchInput& in, const PatchOptions& options, QuadMesh& out) {
  const double pi = std::acos(-1.0);
  inset_wide_given_corners(in, options.inset_angle_deg * pi / 180.0, true, out);
  out.quad_part.assign(out.quads.size(), 0);
  std::vector<std::vector<std::int32_t>> adj(out.nodes.size());
  for (const auto& q : out.quads)
    for (int k = 0; k < 4; ++k) {
      adj[static_cast<std::size_t>(q[k])].push_back(q[(k + 1) % 4]);
      adj[static_cast<std::size_t>(q[(k + 1) % 4])].push_back(q[k]);
    }
  for (std::size_t v = 0; v < in.nodes.size(); ++v)
    if (adj[v].empty()) throw MeshingError("patch: node at " + at_text(out.nodes[v]) + " is in no quad");
  for (int sweep = 0; sweep < options.untangle_sweeps; ++sweep)
    for (std::size_t v = in.nodes.size(); v < out.nodes.size(); ++v) {
      if (adj[v].empty()) continue;
      Vec2 c{};
      for (std::int32_t u : adj[v]) c = c + out.nodes[static_cast<std::size_t>(u)];
      out.nodes[v] = (1.0 / static_cast<double>(adj[v].size())) * c;
    }
  auto free_nodes = [&] {
    std::vector<std::uint8_t> movable(out.nodes.size(), 0);
    std::fill(movable.begin() + static_cast<std::ptrdiff_t>(in.nodes.size()), movable.end(), std::uint8_t{1});
    return movable;
  };
  UntangleStats untangled = untangle_quads(out, free_nodes(), options.untangle);
  if (untangled.folded_after > 0 && inset_wide_given_corners(in, pi * 179.0 / 180.0, false, out) > 0) {
    out.quad_part.assign(out.quads.size(), 0);
    untangle_quads(out, free_nodes(), options.untangle);
  }
  if (!options.refuse_folded) return;
  for (const auto& q : out.quads) {
    const Vec2 a = out.nodes[static_cast<std::size_t>(q[0])], b = out.nodes[static_cast<std::size_t>(q[1])];
    const Vec2 c = out.nodes[static_cast<std::size_t>(q[2])], d = out.nodes[static_cast<std::size_t>(q[3])];
    if (quad_min_sj(a, b, c, d) <= 0.0)
      throw MeshingError("patch: a quad at " + at_text(a) + " stays folded (the boundary is too convoluted there)");
  }
}

// Either construction leaves many irregular nodes (about one in three quads touches a triangle's centre or a coarse
// vertex, and a wide corner split by smooth_patch adds four). Local moves lower them first (patch_valence.h); the
// relaxed patch is kept unless it ends with more folded or poor quads than the one without the moves.
void finish_patch(const PatchInput& in, const PatchOptions& options, QuadMesh& out) {
  collapse_doublets(in, out);
  if (!options.relax_valences) return smooth_patch(in, options, out);
  std::vector<std::array<std::int32_t, 2>> kept;
  for (const PatchCurve& c : in.curves) {
    const std::size_t n = c.nodes.size();
    for (std::size_t i = 0; i + 1 < n + (c.closed ? 1 : 0); ++i) kept.push_back({c.nodes[i], c.nodes[(i + 1) % n]});
  }
  QuadMesh relaxed = out;
  const patch_valence::Moves moves = patch_valence::relax_valences(relaxed, in.nodes.size(), kept, options.max_valence_moves,
                                                                         options.valence_plateau_rounds);
  if (moves.flips + moves.collapses == 0) return smooth_patch(in, options, out);
  try {
    collapse_doublets(in, relaxed);
    smooth_patch(in, options, relaxed);
  } catch (const MeshingError&) {
    return smooth_patch(in, options, out);
  }
  try {
    smooth_patch(in, options, out);
  } catch (const MeshingError&) {
    out = std::move(relaxed);  // refused folded without the moves, not with them
    return;
  }
  const auto before = patch_valence::folded_and_poor(out, options.pair_min_sj);
  const auto after = patch_valence::folded_and_poor(relaxed, options.pair_min_sj);
  if (after.first <= before.first && after.second <= before.second) out = std::move(relaxed);
}

std::size_t folded_quads(const QuadMesh& m) { return patch_valence::folded_and_poor(m, 0.0).first; }

// A CDT whose vertices carry the index of their node; inserting a node where another one is already is an error.
struct IndexedCdt {
  CDT cdt;
  std::vector<CDT::Vertex_handle> handle;
  const std::vector<Vec2>& nodes;
  explicit IndexedCdt(const std::vector<Vec2>& n) : handle(n.size()), nodes(n) {}
  CDT::Vertex_handle vertex(std::int32_t v) {
    if (handle[static_cast<std::size_t>(v)] == CDT::Vertex_handle()) {
      const Vec2 p = nodes[static_cast<std::size_t>(v)];
      CDT::Vertex_handle vh = cdt.insert(K::Point_2(p.x, p.y));
      if (vh->info() >= 0 && vh->info() != v) throw MeshingError("patch: two given nodes coincide at " + at_text(p));
      vh->info() = v;
      handle[static_cast<std::size_t>(v)] = vh;
    }
    return handle[static_cast<std::size_t>(v)];
  }
  std::unordered_set<std::uint64_t> loop_edges;  // node pairs of the loops: crossing one toggles inside/outside

  // Adds interior points (new indices from all_positions.size()), then returns the triangles inside the loops
  // (a flood fill from the outside that toggles at loop edges: no point-in-polygon test on thin triangles);
  // throws when a constraint was cut (curves crossing), which shows as a vertex CGAL created itself.
  std::vector<std::array<std::int32_t, 3>> triangles(const std::vector<Vec2>& extra, std::vector<Vec2>& all_positions) {
    for (const Vec2& p : extra) {
      CDT::Vertex_handle vh = cdt.insert(K::Point_2(p.x, p.y));
      if (vh->info() >= 0) continue;
      vh->info() = static_cast<std::int32_t>(all_positions.size());
      all_positions.push_back(p);
    }
    for (auto vh = cdt.finite_vertices_begin(); vh != cdt.finite_vertices_end(); ++vh)
      if (vh->info() < 0) throw MeshingError("patch: curves cross near " + at_text({vh->point().x(), vh->point().y()}));
    if (cdt.dimension() < 2) throw MeshingError("patch: its given nodes are collinear");
    std::unordered_map<const void*, int> level;
    std::vector<CDT::Face_handle> stack{cdt.infinite_face()};
    level[&*cdt.infinite_face()] = 0;
    while (!stack.empty()) {
      const CDT::Face_handle f = stack.back();
      stack.pop_back();
      const int l = level[&*f];
      for (int i = 0; i < 3; ++i) {
        const CDT::Face_handle g = f->neighbor(i);
        if (level.count(&*g)) continue;
        const CDT::Vertex_handle a = f->vertex(CDT::cw(i)), b = f->vertex(CDT::ccw(i));
        const bool crosses = !cdt.is_infinite(a) && !cdt.is_infinite(b) &&
                             loop_edges.count(edge_key(a->info().v, b->info().v));
        level[&*g] = l + (crosses ? 1 : 0);
        stack.push_back(g);
      }
    }
    std::vector<std::array<std::int32_t, 3>> out;
    for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f)
      if (level[&*f] % 2 == 1) out.push_back({f->vertex(0)->info().v, f->vertex(1)->info().v, f->vertex(2)->info().v});
    return out;
  }
};

// Ears (triangles with one edge off the curves) must pair with their one neighbour, and their tip keeps a
// single quad: a triangle that is the neighbour of two ears, and an ear on a smooth stretch of a loop (its tip
// turns by less than 60 degrees, so its one quad would be nearly flat there), get a vertex at their centre.
void break_ears(IndexedCdt& idx, TriMesh& tri, const std::unordered_set<std::uint64_t>& curve_edge,
                const std::unordered_map<std::uint64_t, std::int32_t>& midpoint = {}) {
  for (int round = 0; round < 4; ++round) {
    std::vector<int> free_edges(tri.triangles.size(), 0);
    std::vector<std::array<std::int32_t, 2>> pairs;
    for (const auto& [key, owner] : edge_owners(tri))
      if (owner[1] >= 0 && !curve_edge.count(key)) {
        free_edges[static_cast<std::size_t>(owner[0])]++;
        free_edges[static_cast<std::size_t>(owner[1])]++;
        pairs.push_back(owner);
      }
    std::vector<int> ears_next(tri.triangles.size(), 0);
    for (const auto& o : pairs) {
      if (free_edges[static_cast<std::size_t>(o[0])] == 1) ears_next[static_cast<std::size_t>(o[1])]++;
      if (free_edges[static_cast<std::size_t>(o[1])] == 1) ears_next[static_cast<std::size_t>(o[0])]++;
    }
    std::vector<Vec2> centres;
    for (std::size_t t = 0; t < tri.triangles.size(); ++t) {
      const auto& v = tri.triangles[t];
      // An ear on a smooth stretch of a loop (its tip turns by less than 60 degrees) would leave its tip with a
      // single, nearly flat quad: a vertex at its centre lets the tip take two quads.
      bool flat_ear = false;
      for (int k = 0; k < 3 && free_edges[t] == 1; ++k) {
        std::int32_t a = v[(k + 2) % 3];
        const std::int32_t tip = v[k];
        std::int32_t b = v[(k + 1) % 3];
        if (!idx.loop_edges.count(edge_key(a, tip)) || !idx.loop_edges.count(edge_key(tip, b))) continue;
        // Split construction: the tip's quad has its corner between the midpoints of the two edges.
        if (auto it = midpoint.find(edge_key(a, tip)); it != midpoint.end()) a = it->second;
        if (auto it = midpoint.find(edge_key(tip, b)); it != midpoint.end()) b = it->second;
        flat_ear = dot(tri.vertices[a] - tri.vertices[tip], tri.vertices[b] - tri.vertices[tip]) <
                   -0.5 * distance(tri.vertices[a], tri.vertices[tip]) * distance(tri.vertices[b], tri.vertices[tip]);
      }
      if (ears_next[t] >= 2 || flat_ear) {
        centres.push_back((1.0 / 3.0) * (tri.vertices[v[0]] + tri.vertices[v[1]] + tri.vertices[v[2]]));
      }
    }
    if (centres.empty()) break;
    std::sort(centres.begin(), centres.end(), [](Vec2 a, Vec2 b) { return a.x != b.x ? a.x < b.x : a.y < b.y; });
    tri.triangles = idx.triangles(centres, tri.vertices);
  }
}

// Anchors: nodes on two curves, ends of open curves. They must be coarse vertices; every other node of a curve
// alternates between coarse vertex and midpoint.
std::vector<std::uint8_t> split_anchors(const PatchInput& in) {
  const auto nn = static_cast<std::int32_t>(in.nodes.size());
  std::vector<int> uses(static_cast<std::size_t>(nn), 0);
  for (const PatchCurve& c : in.curves)
    for (std::int32_t v : c.nodes) uses[static_cast<std::size_t>(v)]++;
  std::vector<std::uint8_t> anchor(static_cast<std::size_t>(nn), 0);
  for (std::size_t v = 0; v < uses.size(); ++v) anchor[v] = uses[v] > 1;
  for (const PatchCurve& c : in.curves)
    if (!c.closed) {
      anchor[static_cast<std::size_t>(c.nodes.front())] = 1;
      anchor[static_cast<std::size_t>(c.nodes.back())] = 1;
    }
  return anchor;
}

// The position on curve c of its first coarse vertex: its first anchor, else on a closed curve without one the
// phase that makes more sharp turns coarse vertices (a sharp turn at a midpoint folds the quad there).
int coarse_start(const PatchInput& in, const PatchCurve& c, const std::vector<std::uint8_t>& anchor) {
  const int n = static_cast<int>(c.nodes.size());
  int start = -1;
  if (c.closed)
    for (int i = 0; i < n && start < 0; ++i)
      if (anchor[static_cast<std::size_t>(c.nodes[i])]) start = i;
  if (start < 0 && c.closed) {
    int sharp[2] = {0, 0};
    for (int i = 0; i < n; ++i) {
      const Vec2 a = in.nodes[static_cast<std::size_t>(c.nodes[(i + n - 1) % n])];
      const Vec2 b = in.nodes[static_cast<std::size_t>(c.nodes[i])];
      const Vec2 d = in.nodes[static_cast<std::size_t>(c.nodes[(i + 1) % n])];
      if (sharp_turn(a, b, d, 30.0)) sharp[i % 2]++;
    }
    start = sharp[1] > sharp[0] ? 1 : 0;
  }
  return std::max(start, 0);
}

// The curves' edges in pairs: each pair a coarse edge a - b with the given node m between, its curve, and each
// curve's chain of coarse vertices.
struct CoarseCurves {
  struct Edge {
    std::int32_t a, m, b;
  };
  std::vector<Edge> edges;
  std::vector<const PatchCurve*> curve;  // the curve of each coarse edge
  std::vector<TriChain> chains;
};

CoarseCurves coarse_curves(const PatchInput& in) {
  const std::vector<std::uint8_t> anchor = split_anchors(in);
  CoarseCurves cc;
  for (const PatchCurve& c : in.curves) {
    const int n = static_cast<int>(c.nodes.size());
    const int edges = c.closed ? n : n - 1;
    const int start = coarse_start(in, c, anchor);
    if (edges % 2 != 0)
      throw MeshingError("patch: a curve of " + std::to_string(edges) + " edges near " +
                         at_text(in.nodes[static_cast<std::size_t>(c.nodes.front())]) + " cannot be split in pairs");
    TriChain ch;
    ch.kind = c.loop ? TriChain::Kind::ring : TriChain::Kind::feature;
    ch.closed = c.closed;
    for (int e = 0; e < edges; e += 2) {
      const std::int32_t a = c.nodes[(start + e) % n], m = c.nodes[(start + e + 1) % n];
      const std::int32_t b = c.nodes[(start + e + 2) % n];
      if (anchor[static_cast<std::size_t>(m)])
        throw MeshingError("patch: an anchor node at " + at_text(in.nodes[static_cast<std::size_t>(m)]) +
                           " falls between two coarse vertices (odd count between anchors)");
      if (a == b) throw MeshingError("patch: a closed curve of two edges at " + at_text(in.nodes[static_cast<std::size_t>(a)]));
      cc.edges.push_back({a, m, b});
      cc.curve.push_back(&c);
      ch.vertices.push_back(a);
    }
    if (!c.closed) ch.vertices.push_back(c.nodes.back());
    cc.chains.push_back(std::move(ch));
  }
  return cc;
}

// Split construction: every other given node is a vertex of a coarse constrained triangulation (interior vertices
// 2 h apart), the nodes between are the midpoints of its curve edges, and every cell is split into quads.
QuadMesh split_patch(const PatchInput& in, const PatchOptions& options) {
  const double h = options.size;
  CoarseCurves cc = coarse_curves(in);
  const auto& coarse = cc.edges;
  const auto loops = loop_polygons(in);
  SegmentGrid grid{2.0 * h, {}};
  for (const CoarseCurves::Edge& e : coarse) {
    grid.add(in.nodes[static_cast<std::size_t>(e.a)], in.nodes[static_cast<std::size_t>(e.m)]);
    grid.add(in.nodes[static_cast<std::size_t>(e.m)], in.nodes[static_cast<std::size_t>(e.b)]);
  }
  IndexedCdt idx(in.nodes);
  for (std::size_t k = 0; k < coarse.size(); ++k) {
    const CoarseCurves::Edge& e = coarse[k];
    idx.cdt.insert_constraint(idx.vertex(e.a), idx.vertex(e.b));
    if (cc.curve[k]->loop) idx.loop_edges.insert(edge_key(e.a, e.b));
  }
  for (std::int32_t v : in.points) idx.vertex(v);
  TriMesh tri;
  tri.vertices = in.nodes;
  tri.triangles = idx.triangles(lattice_points(loops, grid, 2.0 * h, 1.2 * h, {}, options.size_field.get(), h), tri.vertices);
  std::unordered_set<std::uint64_t> coarse_edges;
  std::unordered_map<std::uint64_t, std::int32_t> coarse_midpoint;
  for (const CoarseCurves::Edge& e : coarse) {
    coarse_edges.insert(edge_key(e.a, e.b));
    coarse_midpoint[edge_key(e.a, e.b)] = e.m;
  }
  break_ears(idx, tri, coarse_edges, coarse_midpoint);
  tri.chains = std::move(cc.chains);

  QuadMesh out;
  out.nodes = tri.vertices;
  out.node_kind = in.kind;
  out.node_kind.resize(out.nodes.size(), NodeKind::interior);
  // Every coarse edge must be an edge of the triangulation, with the given node as its midpoint.
  const auto owners = edge_owners(tri);
  std::unordered_map<std::uint64_t, std::int32_t> midpoint;
  for (const CoarseCurves::Edge& e : coarse) {
    if (!owners.count(edge_key(e.a, e.b)))
      throw MeshingError("patch: the curve edge near " + at_text(in.nodes[static_cast<std::size_t>(e.m)]) +
                         " is not kept by the triangulation (curves too close)");
    midpoint[edge_key(e.a, e.b)] = e.m;
  }
  tag_curve_edges(in, out);
  split_cells(tri, options.pair_min_sj, out, midpoint);
  finish_patch(in, options, out);
  return out;
}

// Matching construction: a constrained triangulation of the given nodes themselves (interior vertices h apart),
// whose triangles are paired into quads by a maximum-weight perfect matching (LEMON) over the edges that are
// on no curve, weighted by the quad's worst corner. No edge skips a given node, so a convoluted boundary cannot
// make two curve edges cross. Pairs that would make a folded quad are kept at a tiny weight, so they are used
// only where no perfect matching exists without them (the untangling sweeps and the mesh's checks judge them).
QuadMesh matched_patch_once(const PatchInput& in, const PatchOptions& options, Vec2 offset, int repairs) {
  const double h = options.size;
  const auto loops = loop_polygons(in);
  SegmentGrid grid{h, {}};
  IndexedCdt idx(in.nodes);
  std::unordered_set<std::uint64_t> curve_edge;
  for (const PatchCurve& c : in.curves) {
    const int n = static_cast<int>(c.nodes.size());
    for (int i = 0; i < (c.closed ? n : n - 1); ++i) {
      const std::int32_t a = c.nodes[i], b = c.nodes[(i + 1) % n];
      grid.add(in.nodes[static_cast<std::size_t>(a)], in.nodes[static_cast<std::size_t>(b)]);
      idx.cdt.insert_constraint(idx.vertex(a), idx.vertex(b));
      curve_edge.insert(edge_key(a, b));
      if (c.loop) idx.loop_edges.insert(edge_key(a, b));
    }
  }
  for (std::int32_t v : in.points) idx.vertex(v);
  TriMesh tri;
  tri.vertices = in.nodes;
  tri.triangles = idx.triangles(lattice_points(loops, grid, h, 0.6 * h, offset, options.size_field.get(), h), tri.vertices);
  break_ears(idx, tri, curve_edge);
  if (tri.triangles.size() % 2 != 0)
    throw MeshingError("patch: an odd number of triangles near " + at_text(in.nodes.front()) + " cannot pair into quads");
  std::vector<std::array<int, 2>> sorted_edges;
  std::vector<int> matched;
  // A triangulation can hold a knot no perfect matching resolves (a narrow wedge between two curves, triangles
  // hanging off one neighbour): the triangles a maximum matching leaves alone get a vertex at their centre, which
  // re-triangulates the knot, and the matching is tried again.
  for (int round = 0;; ++round) {
    std::vector<std::array<int, 2>> edges;
    std::vector<double> weights;
    for (const auto& [key, owner] : edge_owners(tri)) {
      if (owner[1] < 0 || curve_edge.count(key)) continue;
      const std::int32_t t = std::min(owner[0], owner[1]), u = std::max(owner[0], owner[1]);
      const auto q = quad_of_pair(tri, t, u);
      const double sj = quad_min_sj(tri.vertices[q[0]], tri.vertices[q[1]], tri.vertices[q[2]], tri.vertices[q[3]]);
      // Every pair counts (a perfect matching first), better quads more; a folded one only where nothing else
      // pairs, left to the untangling sweeps and the mesh's checks.
      edges.push_back({t, u});
      weights.push_back(sj > 0.0 ? 1.0 + sj : 0.01);
    }
    // Edges in a fixed order (the hash map's is not), so the matching does not depend on it.
    std::vector<std::size_t> order(edges.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return edges[a] < edges[b]; });
    sorted_edges.clear();
    std::vector<double> sorted_weights;
    for (std::size_t i : order) {
      sorted_edges.push_back(edges[i]);
      sorted_weights.push_back(weights[i]);
    }
    const int count = static_cast<int>(tri.triangles.size());
    if (lemon_bridge::max_weight_perfect_matching(count, sorted_edges, sorted_weights, matched)) break;
    const std::vector<int> alone = lemon_bridge::unmatched_nodes(count, sorted_edges);
    if (round >= repairs || alone.empty())
      throw MeshingError("patch: the triangles near " + at_text(in.nodes.front()) + " cannot all pair into quads (" +
                         std::to_string(alone.size()) + " left alone" +
                         (alone.empty() ? std::string()
                                        : ", the first at " + at_text(tri.vertices[static_cast<std::size_t>(tri.triangles[static_cast<std::size_t>(alone.front())][0])])) +
                         ")");
    // The knot is wider than the triangles left alone: their neighbours get a centre vertex too, and the rings
    // beyond them in later rounds.
    std::set<int> knot(alone.begin(), alone.end());
    for (int ring = 0; ring <= round / 2; ++ring) {
      std::set<int> grown = knot;
      for (const auto& e : sorted_edges)
        if (knot.count(e[0]) || knot.count(e[1])) {
          grown.insert(e[0]);
          grown.insert(e[1]);
        }
      knot = std::move(grown);
    }
    std::vector<Vec2> centres;
    for (int t : knot) {
      const auto& v = tri.triangles[static_cast<std::size_t>(t)];
      centres.push_back((1.0 / 3.0) * (tri.vertices[v[0]] + tri.vertices[v[1]] + tri.vertices[v[2]]));
    }
    tri.triangles = idx.triangles(centres, tri.vertices);
  }
  QuadMesh out;
  out.nodes = tri.vertices;
  out.node_kind = in.kind;
  out.node_kind.resize(out.nodes.size(), NodeKind::interior);
  for (int e : matched) out.quads.push_back(quad_of_pair(tri, sorted_edges[static_cast<std::size_t>(e)][0],
                                                      sorted_edges[static_cast<std::size_t>(e)][1]));
  tag_curve_edges(in, out);
  finish_patch(in, options, out);
  return out;
}

// A triangulation has no perfect matching into unfolded quads now and then (two ears sharing their only
// neighbour): the interior lattice is shifted and the matching tried again.
QuadMesh matched_patch(const PatchInput& in, const PatchOptions& options) {
  const double h = options.size;
  const int attempts = std::max(1, options.matching_attempts);
  // Shifts along the golden-ratio sequence cover the lattice cell evenly.
  auto offset = [&](int attempt) {
    return Vec2{std::fmod(attempt * 0.618034, 1.0) * h, std::fmod(attempt * 0.381966, 1.0) * h * 0.866};
  };
  for (int attempt = 0;; ++attempt) {
    try {
      return matched_patch_once(in, options, offset(attempt), 0);
    } catch (const MeshingError&) {
      if (attempt + 1 >= attempts && options.matching_repairs <= 0) throw;
      if (attempt + 1 >= attempts) break;
    }
  }
  // No lattice gives a perfect matching: the same lattices with their knots repaired by centre vertices. Those
  // pairs are the poorer ones, so the patch with the fewest folded quads left after untangling is kept.
  std::optional<QuadMesh> best;
  std::size_t best_folded = 0;
  std::string last_error;
  for (int attempt = 0; attempt < attempts; ++attempt) {
    try {
      QuadMesh m = matched_patch_once(in, options, offset(attempt), options.matching_repairs);
      const std::size_t folded = folded_quads(m);
      if (!best || folded < best_folded) {
        best = std::move(m);
        best_folded = folded;
      }
      if (best_folded == 0) break;
    } catch (const MeshingError& e) {
      last_error = e.what();
    }
  }
  if (!best) throw MeshingError(last_error);
  return std::move(*best);
}

}  // namespace

QuadMesh mesh_patch(const PatchInput& in, const PatchOptions& options) {
  // A loop of four nodes and nothing inside is one quad.
  if (in.curves.size() == 1 && in.curves[0].loop && in.curves[0].nodes.size() == 4 && in.points.empty()) {
    QuadMesh out;
    out.nodes = in.nodes;
    out.node_kind = in.kind;
    const auto& v = in.curves[0].nodes;
    out.quads.push_back({v[0], v[1], v[2], v[3]});
    tag_curve_edges(in, out);
    finish_patch(in, options, out);
    return out;
  }
  // The split construction gives the more regular quads (about four at a vertex); where its coarse edges cannot
  // follow the boundary, the matching construction works on the given edges themselves.
  if (options.method == PatchMethod::split) return split_patch(in, options);
  if (options.method == PatchMethod::matching) return matched_patch(in, options);
  QuadMesh split;
  try {
    split = split_patch(in, options);
  } catch (const MeshingError& split_error) {
    try {
      return matched_patch(in, options);
    } catch (const MeshingError& e) {
      throw MeshingError(std::string(split_error.what()) + "; " + e.what());
    }
  }
  // A split patch with a quad left folded (a sliver of the coarse triangulation along a nearly straight run of
  // given nodes) gives way to a matched one that has fewer.
  const std::size_t split_folded = folded_quads(split);
  if (split_folded == 0) return split;
  try {
    QuadMesh matched = matched_patch(in, options);
    if (folded_quads(matched) < split_folded) return matched;
  } catch (const MeshingError&) {
  }
  return split;
}

}  // namespace polysquare
