// Stage "assemble": the parts' meshes, in part order, as one mesh.
#include "pipeline/region_stages.h"

namespace polysquare::pipeline {
namespace {

// The part's background triangulation and its partition appended to the result's (for pictures).
void append_background(const PartMapResult& r, std::int32_t subregion_offset, MeshResult& out) {
  const auto voff = static_cast<std::int32_t>(out.background.vertices.size());
  out.background.vertices.insert(out.background.vertices.end(), r.background.vertices.begin(), r.background.vertices.end());
  for (auto t : r.background.triangles) out.background.triangles.push_back({t[0] + voff, t[1] + voff, t[2] + voff});
  for (TriChain ch : r.background.chains) {
    for (auto& v : ch.vertices) v += voff;
    out.background.chains.push_back(std::move(ch));
  }
  for (auto p : r.partition->triangle_part) out.background_part.push_back(p + subregion_offset);
}

// The part's mesh appended to `mesh`, its nodes and subregions numbered after those before it.
void append_mesh(const QuadMesh& m, std::int32_t subregion_offset, QuadMesh& mesh) {
  const auto offset = static_cast<std::int32_t>(mesh.nodes.size());
  auto shift = [offset](auto arr) { for (auto& v : arr) v += offset; return arr; };
  mesh.nodes.insert(mesh.nodes.end(), m.nodes.begin(), m.nodes.end());
  mesh.node_kind.insert(mesh.node_kind.end(), m.node_kind.begin(), m.node_kind.end());
  for (const auto& q : m.quads) mesh.quads.push_back(shift(q));
  for (auto p : m.quad_part) mesh.quad_part.push_back(p + subregion_offset);
  for (const auto& e : m.boundary_edges) mesh.boundary_edges.push_back(shift(e));
  mesh.boundary_edge_ring.insert(mesh.boundary_edge_ring.end(), m.boundary_edge_ring.begin(), m.boundary_edge_ring.end());
  for (const auto& e : m.feature_edges) mesh.feature_edges.push_back(shift(e));
  mesh.feature_edge_curve.insert(mesh.feature_edge_curve.end(), m.feature_edge_curve.begin(), m.feature_edge_curve.end());
}

}  // namespace

MeshResult assemble_parts(const std::vector<PartOutcome>& parts, const Region& region, bool keep_partition) {
  MeshResult out;
  out.mesh.crs = region.crs;
  out.mesh.units = region.units;
  std::int32_t subregion_offset = 0;
  for (const PartOutcome& p : parts) {
    const PartMapResult& r = *p.result;
    if (keep_partition && r.partition) append_background(r, subregion_offset, out);
    append_mesh(r.mesh, subregion_offset, out.mesh);
    subregion_offset += r.partition ? r.partition->parts : 1;
    out.parts.push_back(r.stats);
  }
  return out;
}

}  // namespace polysquare::pipeline
