#include "polysquare/fallback/split_triangles.h"

#include <string>
#include <unordered_map>

#include "polysquare/core/error.h"

namespace polysquare {

QuadMesh split_triangles(const Region& region, const RegionPart& part, const SplitOptions& options) {
  const double area = part_area(region, part);
  if (area < options.size * options.size)
    throw MeshingError((region.source.empty() ? std::string("region") : region.source) + ": part " +
                       std::to_string(part.part) + " has area " + std::to_string(area) +
                       ", less than one element; remove it from the input or use a smaller size");
  TriangulationOptions topt;
  topt.boundary_edge = 2.0 * options.size;
  // CGAL bounds the longest edge: with 4 h the mean triangle is about 2.5 h^2, three quads of about h^2.
  topt.max_edge = 4.0 * options.size;
  topt.shape_bound = options.shape_bound;
  topt.max_triangles = options.max_triangles;
  topt.split_constrained_edges = false;  // corner ears are fine here: nothing is straightened
  const TriMesh tri = triangulate_part(region, part, topt);

  QuadMesh out;
  const std::size_t nv = tri.vertices.size();
  out.nodes = tri.vertices;
  out.node_kind.assign(nv, NodeKind::interior);
  for (const TriChain& ch : tri.chains) {
    const NodeKind kind = ch.kind == TriChain::Kind::ring ? NodeKind::boundary : NodeKind::feature;
    // A ring wins over a feature touching it: boundary nodes slide on the boundary.
    for (const std::int32_t v : ch.vertices)
      if (out.node_kind[v] != NodeKind::boundary) out.node_kind[v] = kind;
  }
  const std::vector<std::uint8_t> corner = corner_vertices(tri, tri.vertices, options.corner_threshold_deg);
  for (std::size_t v = 0; v < nv; ++v)
    if (corner[v]) out.node_kind[v] = NodeKind::corner;

  // One midpoint node per triangle edge, of the kind of the curve the edge lies on (interior otherwise).
  std::unordered_map<std::uint64_t, std::int32_t> midpoint;
  auto mid = [&](std::int32_t a, std::int32_t b, NodeKind kind) {
    auto [it, inserted] = midpoint.try_emplace(edge_key(a, b), static_cast<std::int32_t>(out.nodes.size()));
    if (inserted) {
      out.nodes.push_back(0.5 * (tri.vertices[a] + tri.vertices[b]));
      out.node_kind.push_back(kind);
    } else if (kind != NodeKind::interior) {
      out.node_kind[static_cast<std::size_t>(it->second)] = kind;
    }
    return it->second;
  };
  for (const TriChain& ch : tri.chains) {
    const int n = static_cast<int>(ch.vertices.size());
    const int m = ch.closed ? n : n - 1;
    const bool ring = ch.kind == TriChain::Kind::ring;
    for (int i = 0; i < m; ++i) {
      const std::int32_t a = ch.vertices[i], b = ch.vertices[(i + 1) % n];
      const std::int32_t c = mid(a, b, ring ? NodeKind::boundary : NodeKind::feature);
      auto& edges = ring ? out.boundary_edges : out.feature_edges;
      auto& tags = ring ? out.boundary_edge_ring : out.feature_edge_curve;
      edges.push_back({a, c});
      edges.push_back({c, b});
      tags.push_back(ch.index);
      tags.push_back(ch.index);
    }
  }
  for (const auto& t : tri.triangles) {
    const std::int32_t g = static_cast<std::int32_t>(out.nodes.size());
    out.nodes.push_back((1.0 / 3.0) * (tri.vertices[t[0]] + tri.vertices[t[1]] + tri.vertices[t[2]]));
    out.node_kind.push_back(NodeKind::interior);
    const std::int32_t m01 = mid(t[0], t[1], NodeKind::interior), m12 = mid(t[1], t[2], NodeKind::interior),
                       m20 = mid(t[2], t[0], NodeKind::interior);
    out.quads.push_back({t[0], m01, g, m20});
    out.quads.push_back({t[1], m12, g, m01});
    out.quads.push_back({t[2], m20, g, m12});
  }
  out.quad_part.assign(out.quads.size(), 0);
  return out;
}

}  // namespace polysquare
