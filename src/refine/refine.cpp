#include "polysquare/refine/refine.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

namespace polysquare {
namespace {

// Interior angle (degrees, 0-360) of a counter-clockwise quad at the node whose outgoing edge is e_next and
// incoming edge reversed is e_prev.
double corner_angle_deg(Vec2 e_next, Vec2 e_prev) {
  double a = std::atan2(cross(e_next, e_prev), dot(e_next, e_prev)) * 180.0 / std::numbers::pi;
  return a < 0.0 ? a + 360.0 : a;
}

}  // namespace

RefineStats refine_flat_corners(QuadMesh& mesh, const RefineOptions& options) {
  RefineStats st;
  const std::size_t nn = mesh.nodes.size(), nq = mesh.quads.size();
  if (!options.enabled || mesh.node_kind.size() != nn) return st;
  std::vector<std::vector<std::int32_t>> quads_of(nn), nbrs(nn);
  for (std::size_t q = 0; q < nq; ++q)
    for (int k = 0; k < 4; ++k) {
      const std::int32_t v = mesh.quads[q][k], w = mesh.quads[q][(k + 1) % 4];
      quads_of[v].push_back(static_cast<std::int32_t>(q));
      nbrs[v].push_back(w);
      nbrs[w].push_back(v);
    }
  for (auto& n : nbrs) {
    std::sort(n.begin(), n.end());
    n.erase(std::unique(n.begin(), n.end()), n.end());
  }
  // Boundary neighbours of each node with the ring of the edge.
  std::vector<std::vector<std::pair<std::int32_t, std::int32_t>>> along(nn);
  for (std::size_t e = 0; e < mesh.boundary_edges.size(); ++e) {
    const auto [a, b] = mesh.boundary_edges[e];
    along[a].push_back({b, mesh.boundary_edge_ring[e]});
    along[b].push_back({a, mesh.boundary_edge_ring[e]});
  }
  auto ring_edge = [&](std::int32_t v, std::int32_t w) {
    for (auto [u, ring] : along[v])
      if (u == w) return ring;
    return -1;
  };

  std::vector<std::int32_t> merge_into(nn, -1);
  std::vector<std::uint8_t> quad_removed(nq, 0), touched(nn, 0);
  for (std::size_t v = 0; v < nn; ++v) {
    if (mesh.node_kind[v] != NodeKind::boundary || quads_of[v].size() != 1 || along[v].size() != 2) continue;
    const std::int32_t q = quads_of[v][0];
    const auto& quad = mesh.quads[static_cast<std::size_t>(q)];
    const int at = static_cast<int>(std::find(quad.begin(), quad.end(), static_cast<std::int32_t>(v)) - quad.begin());
    const std::int32_t a = quad[(at + 1) % 4], m = quad[(at + 2) % 4], b = quad[(at + 3) % 4];
    const Vec2 p = mesh.nodes[v];
    if (corner_angle_deg(mesh.nodes[a] - p, mesh.nodes[b] - p) <= options.flat_corner_deg) continue;
    st.flat_corners++;
    const std::int32_t ring = ring_edge(static_cast<std::int32_t>(v), a);
    // The template needs: a and b plain boundary nodes on the same ring as v, m an interior node that keeps at
    // least three quads, and a, b sharing no neighbour but v and m (else the merge would double an edge).
    if (ring < 0 || ring_edge(static_cast<std::int32_t>(v), b) != ring) continue;
    if (mesh.node_kind[a] != NodeKind::boundary || mesh.node_kind[b] != NodeKind::boundary) continue;
    if (mesh.node_kind[m] != NodeKind::interior || quads_of[m].size() < 4) continue;
    if (touched[v] || touched[a] || touched[b] || touched[m]) continue;
    std::vector<std::int32_t> common;
    std::set_intersection(nbrs[a].begin(), nbrs[a].end(), nbrs[b].begin(), nbrs[b].end(), std::back_inserter(common));
    if (common.size() != 2) continue;
    merge_into[a] = merge_into[b] = static_cast<std::int32_t>(v);
    quad_removed[static_cast<std::size_t>(q)] = 1;
    // Later collapses stay clear of every quad this one rewrites.
    for (std::int32_t x : {static_cast<std::int32_t>(v), a, b, m})
      for (std::int32_t qq : quads_of[x])
        for (std::int32_t y : mesh.quads[static_cast<std::size_t>(qq)]) touched[y] = 1;
    st.collapsed++;
  }
  if (st.collapsed == 0) return st;

  // Renumber: merged nodes disappear, the others keep their order.
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
    if (quad_removed[q]) continue;
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
  mesh = std::move(out);
  return st;
}

}  // namespace polysquare
