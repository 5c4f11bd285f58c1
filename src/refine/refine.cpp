#include "polysquare/refine/refine.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <unordered_map>
#include <vector>

namespace polysquare {
namespace {

// Interior angle (degrees, 0-360) of a counter-clockwise quad at the node whose outgoing edge is e_next and
// incoming edge reversed is e_prev.
double corner_angle_deg(Vec2 e_next, Vec2 e_prev) {
  double a = std::atan2(cross(e_next, e_prev), dot(e_next, e_prev)) * 180.0 / std::numbers::pi;
  return a < 0.0 ? a + 360.0 : a;
}

// The mesh around feature loops: each node's quads, how many boundary and feature edges it has, each curve's edges.
struct FeatureLoopIndex {
  std::vector<std::vector<std::int32_t>> quads_of;
  std::vector<int> curve_edges;
  std::vector<std::vector<std::array<std::int32_t, 2>>> edges_of;
};

FeatureLoopIndex feature_loop_index(const QuadMesh& mesh) {
  const std::size_t nn = mesh.nodes.size();
  FeatureLoopIndex ix;
  ix.quads_of.resize(nn);
  for (std::size_t q = 0; q < mesh.quads.size(); ++q)
    for (std::int32_t v : mesh.quads[q]) ix.quads_of[v].push_back(static_cast<std::int32_t>(q));
  ix.curve_edges.assign(nn, 0);
  for (const auto& e : mesh.boundary_edges) ix.curve_edges[e[0]]++, ix.curve_edges[e[1]]++;
  for (const auto& e : mesh.feature_edges) ix.curve_edges[e[0]]++, ix.curve_edges[e[1]]++;
  int curves = 0;
  for (auto c : mesh.feature_edge_curve) curves = std::max(curves, c + 1);
  ix.edges_of.resize(static_cast<std::size_t>(curves));
  for (std::size_t e = 0; e < mesh.feature_edges.size(); ++e)
    ix.edges_of[static_cast<std::size_t>(mesh.feature_edge_curve[e])].push_back(mesh.feature_edges[e]);
  return ix;
}

// Quads at v swept counter-clockwise from the edge towards `from` to the edge towards `to`: the side of the
// loop on the left of to -> v -> from... i.e. the fan between the two loop edges. Empty if the fan breaks.
std::vector<std::int32_t> fan(const QuadMesh& mesh, const FeatureLoopIndex& ix, std::int32_t v, std::int32_t from,
                              std::int32_t to) {
  auto at_of = [&](std::int32_t q) {
    const auto& quad = mesh.quads[static_cast<std::size_t>(q)];
    return static_cast<int>(std::find(quad.begin(), quad.end(), v) - quad.begin());
  };
  const auto& quads_of = ix.quads_of;
  std::vector<std::int32_t> out;
  std::int32_t dir = from;
  for (std::size_t guard = 0; guard <= quads_of[v].size(); ++guard) {
    std::int32_t found = -1;
    for (std::int32_t q : quads_of[v])
      if (mesh.quads[static_cast<std::size_t>(q)][(at_of(q) + 1) % 4] == dir) found = q;
    if (found < 0) return std::vector<std::int32_t>{};
    out.push_back(found);
    dir = mesh.quads[static_cast<std::size_t>(found)][(at_of(found) + 3) % 4];
    if (dir == to) return out;
  }
  return std::vector<std::int32_t>{};
}

// The loop as a cycle of nodes, each with exactly the two edges of this curve and no other curve edge; empty if
// the curve is not one such cycle.
std::vector<std::int32_t> simple_loop(const QuadMesh& mesh, const FeatureLoopIndex& ix,
                                      const std::vector<std::array<std::int32_t, 2>>& edges) {
  std::unordered_map<std::int32_t, std::vector<std::int32_t>> adj;
  for (const auto& e : edges) adj[e[0]].push_back(e[1]), adj[e[1]].push_back(e[0]);
  bool simple = true;
  for (const auto& [v, a] : adj)
    simple = simple && a.size() == 2 && ix.curve_edges[v] == 2 && mesh.node_kind[v] != NodeKind::boundary;
  if (!simple) return {};
  std::vector<std::int32_t> loop{edges[0][0]};
  for (std::int32_t prev = -1, v = edges[0][0];;) {
    const auto& a = adj[v];
    const std::int32_t next = a[0] != prev ? a[0] : a[1];
    if (next == loop.front()) break;
    loop.push_back(next);
    prev = v;
    v = next;
    if (loop.size() > edges.size()) break;
  }
  if (loop.size() != edges.size()) return {};  // more than one cycle
  return loop;
}

// The quads on each side of a loop, per loop node (side 0: left of the walk, the fan from next to prev; side 1:
// right, from prev to next), and whether a side has a loop node with one quad there and a corner flatter than
// loop_corner_deg.
struct LoopSides {
  std::array<std::vector<std::vector<std::int32_t>>, 2> side;
  std::array<bool, 2> flat{false, false};
};

std::optional<LoopSides> loop_sides(const QuadMesh& mesh, const FeatureLoopIndex& ix,
                                    const std::vector<std::int32_t>& loop, double loop_corner_deg) {
  const std::size_t n = loop.size();
  LoopSides ls;
  for (int s = 0; s < 2; ++s) {
    ls.side[s].resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      const std::int32_t v = loop[i], prev = loop[(i + n - 1) % n], next = loop[(i + 1) % n];
      ls.side[s][i] = s == 0 ? fan(mesh, ix, v, next, prev) : fan(mesh, ix, v, prev, next);
      if (ls.side[s][i].empty()) return std::nullopt;
      if (ls.side[s][i].size() == 1) {
        const Vec2 p = mesh.nodes[v];
        const double deg = corner_angle_deg(mesh.nodes[s == 0 ? next : prev] - p, mesh.nodes[s == 0 ? prev : next] - p);
        ls.flat[s] = ls.flat[s] || deg > loop_corner_deg;
      }
    }
  }
  return ls;
}

// Puts a layer of quads on side s of the loop (fans: that side's quads per loop node): copies of the loop nodes
// placed part of the way towards the centroids of the side's quads; shallower if a quad inverts. Only the side's
// quads and the new layer change, so only they are checked before the mesh is touched. False if every depth
// inverts one.
bool pillow_loop_side(QuadMesh& mesh, const std::vector<std::int32_t>& loop,
                      const std::vector<std::vector<std::int32_t>>& fans, int s) {
  const std::size_t n = loop.size();
  std::vector<Vec2> centroid(n);
  std::unordered_map<std::int32_t, std::int32_t> copy_of;  // loop node -> index into loop
  for (std::size_t i = 0; i < n; ++i) {
    Vec2 g{};
    for (std::int32_t q : fans[i])
      for (std::int32_t w : mesh.quads[static_cast<std::size_t>(q)]) g = g + 0.25 * mesh.nodes[w];
    centroid[i] = (1.0 / static_cast<double>(fans[i].size())) * g;
    copy_of[loop[i]] = static_cast<std::int32_t>(i);
  }
  std::vector<std::int32_t> changed;  // the side's quads, each once
  for (const auto& fan_quads : fans) changed.insert(changed.end(), fan_quads.begin(), fan_quads.end());
  std::sort(changed.begin(), changed.end());
  changed.erase(std::unique(changed.begin(), changed.end()), changed.end());
  for (double t : {0.5, 0.25, 0.1}) {
    std::vector<Vec2> copy(n);
    for (std::size_t i = 0; i < n; ++i) copy[i] = lerp(mesh.nodes[loop[i]], centroid[i], t);
    // A side quad sees every loop node of its own through the copies.
    auto moved = [&](std::int32_t v) {
      const auto it = copy_of.find(v);
      return it == copy_of.end() ? mesh.nodes[v] : copy[static_cast<std::size_t>(it->second)];
    };
    bool valid = true;
    for (std::size_t k = 0; k < changed.size() && valid; ++k) {
      const auto& q = mesh.quads[static_cast<std::size_t>(changed[k])];
      valid = quad_min_sj(moved(q[0]), moved(q[1]), moved(q[2]), moved(q[3])) > 0.0;
    }
    for (std::size_t i = 0; i < n && valid; ++i) {
      const std::size_t j = (i + 1) % n;
      const Vec2 a = mesh.nodes[loop[i]], b = mesh.nodes[loop[j]];
      valid = s == 0 ? quad_min_sj(a, b, copy[j], copy[i]) > 0.0 : quad_min_sj(b, a, copy[i], copy[j]) > 0.0;
    }
    if (!valid) continue;
    const auto first = static_cast<std::int32_t>(mesh.nodes.size());
    for (std::size_t i = 0; i < n; ++i) {
      mesh.nodes.push_back(copy[i]);
      mesh.node_kind.push_back(NodeKind::interior);
    }
    for (std::int32_t q : changed)
      for (auto& v : mesh.quads[static_cast<std::size_t>(q)]) {
        const auto it = copy_of.find(v);
        if (it != copy_of.end()) v = first + it->second;
      }
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t j = (i + 1) % n;
      const std::int32_t ci = first + static_cast<std::int32_t>(i), cj = first + static_cast<std::int32_t>(j);
      // The side's quad on edge i -> j: first of i's fan on the left side, first of j's fan on the right.
      const std::int32_t beside = s == 0 ? fans[i].front() : fans[j].front();
      mesh.quads.push_back(s == 0 ? std::array<std::int32_t, 4>{loop[i], loop[j], cj, ci}
                                  : std::array<std::int32_t, 4>{loop[j], loop[i], ci, cj});
      if (!mesh.quad_part.empty()) mesh.quad_part.push_back(mesh.quad_part[static_cast<std::size_t>(beside)]);
    }
    return true;
  }
  return false;
}

// Around each node: its quads, its edge neighbours (sorted) and its boundary neighbours with the ring of the edge.
struct CornerIndex {
  std::vector<std::vector<std::int32_t>> quads_of, nbrs;
  std::vector<std::vector<std::pair<std::int32_t, std::int32_t>>> along;
  std::int32_t ring_edge(std::int32_t v, std::int32_t w) const {
    for (auto [u, ring] : along[v])
      if (u == w) return ring;
    return -1;
  }
};

CornerIndex corner_index(const QuadMesh& mesh) {
  const std::size_t nn = mesh.nodes.size(), nq = mesh.quads.size();
  CornerIndex ix;
  ix.quads_of.resize(nn);
  ix.nbrs.resize(nn);
  for (std::size_t q = 0; q < nq; ++q)
    for (int k = 0; k < 4; ++k) {
      const std::int32_t v = mesh.quads[q][k], w = mesh.quads[q][(k + 1) % 4];
      ix.quads_of[v].push_back(static_cast<std::int32_t>(q));
      ix.nbrs[v].push_back(w);
      ix.nbrs[w].push_back(v);
    }
  for (auto& n : ix.nbrs) {
    std::sort(n.begin(), n.end());
    n.erase(std::unique(n.begin(), n.end()), n.end());
  }
  ix.along.resize(nn);
  for (std::size_t e = 0; e < mesh.boundary_edges.size(); ++e) {
    const auto [a, b] = mesh.boundary_edges[e];
    ix.along[a].push_back({b, mesh.boundary_edge_ring[e]});
    ix.along[b].push_back({a, mesh.boundary_edge_ring[e]});
  }
  return ix;
}

// The collapses of flat boundary corners: the nodes merged into another (merge_into) and the quads removed.
struct CornerCollapses {
  std::vector<std::int32_t> merge_into;
  std::vector<std::uint8_t> quad_removed;
};

CornerCollapses plan_corner_collapses(const QuadMesh& mesh, const CornerIndex& ix, double flat_corner_deg,
                                      RefineStats& st) {
  const std::size_t nn = mesh.nodes.size(), nq = mesh.quads.size();
  CornerCollapses cc{std::vector<std::int32_t>(nn, -1), std::vector<std::uint8_t>(nq, 0)};
  std::vector<std::uint8_t> touched(nn, 0);
  for (std::size_t v = 0; v < nn; ++v) {
    if (mesh.node_kind[v] != NodeKind::boundary || ix.quads_of[v].size() != 1 || ix.along[v].size() != 2) continue;
    const std::int32_t q = ix.quads_of[v][0];
    const auto& quad = mesh.quads[static_cast<std::size_t>(q)];
    const int at = static_cast<int>(std::find(quad.begin(), quad.end(), static_cast<std::int32_t>(v)) - quad.begin());
    const std::int32_t a = quad[(at + 1) % 4], m = quad[(at + 2) % 4], b = quad[(at + 3) % 4];
    const Vec2 p = mesh.nodes[v];
    if (corner_angle_deg(mesh.nodes[a] - p, mesh.nodes[b] - p) <= flat_corner_deg) continue;
    st.flat_corners++;
    const std::int32_t ring = ix.ring_edge(static_cast<std::int32_t>(v), a);
    // The template needs: a and b plain boundary nodes on the same ring as v, m an interior node that keeps at
    // least three quads, and a, b sharing no neighbour but v and m (else the merge would double an edge).
    if (ring < 0 || ix.ring_edge(static_cast<std::int32_t>(v), b) != ring) continue;
    if (mesh.node_kind[a] != NodeKind::boundary || mesh.node_kind[b] != NodeKind::boundary) continue;
    if (mesh.node_kind[m] != NodeKind::interior || ix.quads_of[m].size() < 4) continue;
    if (touched[v] || touched[a] || touched[b] || touched[m]) continue;
    std::vector<std::int32_t> common;
    std::set_intersection(ix.nbrs[a].begin(), ix.nbrs[a].end(), ix.nbrs[b].begin(), ix.nbrs[b].end(),
                          std::back_inserter(common));
    if (common.size() != 2) continue;
    cc.merge_into[a] = cc.merge_into[b] = static_cast<std::int32_t>(v);
    cc.quad_removed[static_cast<std::size_t>(q)] = 1;
    // Later collapses stay clear of every quad this one rewrites.
    for (std::int32_t x : {static_cast<std::int32_t>(v), a, b, m})
      for (std::int32_t qq : ix.quads_of[x])
        for (std::int32_t y : mesh.quads[static_cast<std::size_t>(qq)]) touched[y] = 1;
    st.collapsed++;
  }
  return cc;
}

// The mesh with the collapses made: merged nodes disappear, the others keep their order.
QuadMesh collapsed_mesh(const QuadMesh& mesh, const CornerCollapses& cc) {
  const std::size_t nn = mesh.nodes.size(), nq = mesh.quads.size();
  const auto& merge_into = cc.merge_into;
  std::vector<std::int32_t> index(nn, -1);
  std::int32_t next = 0;
  for (std::size_t v = 0; v < nn; ++v)
    if (merge_into[v] < 0) index[v] = next++;
  auto map = [&](std::int32_t v) { return index[merge_into[v] < 0 ? v : merge_into[v]]; };
  QuadMesh out;
  out.crs = mesh.crs;
  out.units = mesh.units;
  for (std::size_t v = 0; v < nn; ++v)
    if (merge_into[v] < 0) {
      out.nodes.push_back(mesh.nodes[v]);
      out.node_kind.push_back(mesh.node_kind[v]);
    }
  for (std::size_t q = 0; q < nq; ++q) {
    if (cc.quad_removed[q]) continue;
    const auto& quad = mesh.quads[q];
    out.quads.push_back({map(quad[0]), map(quad[1]), map(quad[2]), map(quad[3])});
    if (!mesh.quad_part.empty()) out.quad_part.push_back(mesh.quad_part[q]);
  }
  auto copy_edges = [&](const std::vector<std::array<std::int32_t, 2>>& edges, const std::vector<std::int32_t>& tags,
                        std::vector<std::array<std::int32_t, 2>>& to, std::vector<std::int32_t>& to_tags) {
    for (std::size_t e = 0; e < edges.size(); ++e) {
      const std::int32_t a = map(edges[e][0]), b = map(edges[e][1]);
      if (a == b) continue;  // the two boundary edges of a collapsed corner
      to.push_back({a, b});
      to_tags.push_back(tags[e]);
    }
  };
  copy_edges(mesh.boundary_edges, mesh.boundary_edge_ring, out.boundary_edges, out.boundary_edge_ring);
  copy_edges(mesh.feature_edges, mesh.feature_edge_curve, out.feature_edges, out.feature_edge_curve);
  return out;
}

}  // namespace

RefineStats refine_flat_corners(QuadMesh& mesh, const RefineOptions& options) {
  RefineStats st;
  const std::size_t nn = mesh.nodes.size();
  if (!options.enabled || mesh.node_kind.size() != nn) return st;
  const CornerCollapses cc = plan_corner_collapses(mesh, corner_index(mesh), options.flat_corner_deg, st);
  if (st.collapsed == 0) return st;
  mesh = collapsed_mesh(mesh, cc);
  return st;
}

RefineStats pillow_feature_loops(QuadMesh& mesh, const RefineOptions& options) {
  RefineStats st;
  const std::size_t nn = mesh.nodes.size();
  if (!options.enabled || mesh.node_kind.size() != nn || mesh.feature_edges.empty()) return st;
  const FeatureLoopIndex ix = feature_loop_index(mesh);
  for (const auto& edges : ix.edges_of) {
    if (edges.size() < 3) continue;
    const std::vector<std::int32_t> loop = simple_loop(mesh, ix, edges);
    if (loop.empty()) continue;
    const std::optional<LoopSides> sides = loop_sides(mesh, ix, loop, options.loop_corner_deg);
    if (!sides || !(sides->flat[0] || sides->flat[1])) continue;
    st.feature_loops++;
    const int s = sides->flat[0] ? 0 : 1;  // one side: the inside of a round loop (its corners are convex there)
    if (pillow_loop_side(mesh, loop, sides->side[s], s)) st.pillowed++;
  }
  return st;
}

}  // namespace polysquare
