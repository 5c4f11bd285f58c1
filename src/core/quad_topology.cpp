#include "polysquare/core/quad_topology.h"

namespace polysquare {

std::unordered_map<std::uint64_t, int> quad_edge_counts(const QuadMesh& mesh) {
  std::unordered_map<std::uint64_t, int> counts;
  counts.reserve(mesh.quads.size() * 2);
  for (const auto& q : mesh.quads)
    for (std::size_t k = 0; k < 4; ++k) counts[edge_key(q[k], q[(k + 1) % 4])]++;
  return counts;
}

NodeValences node_valences(const QuadMesh& mesh, const std::unordered_map<std::uint64_t, int>& edge_counts) {
  NodeValences out;
  out.valence.assign(mesh.nodes.size(), 0);
  out.on_boundary.assign(mesh.nodes.size(), 0);
  for (const auto& [key, count] : edge_counts) {
    const auto a = static_cast<std::size_t>(key >> 32), b = static_cast<std::size_t>(key & 0xffffffffu);
    out.valence[a]++;
    out.valence[b]++;
    if (count == 1) out.on_boundary[a] = out.on_boundary[b] = 1;
  }
  return out;
}

NodeQuads node_quads(const QuadMesh& mesh) {
  NodeQuads n;
  n.offset.assign(mesh.nodes.size() + 1, 0);
  for (const auto& q : mesh.quads)
    for (auto v : q) n.offset[static_cast<std::size_t>(v) + 1]++;
  for (std::size_t i = 0; i + 1 < n.offset.size(); ++i) n.offset[i + 1] += n.offset[i];
  n.quads.resize(n.offset.back());
  std::vector<std::size_t> fill(n.offset.begin(), n.offset.end() - 1);
  for (std::size_t q = 0; q < mesh.quads.size(); ++q)
    for (auto v : mesh.quads[q]) n.quads[fill[static_cast<std::size_t>(v)]++] = static_cast<std::int32_t>(q);
  return n;
}

}  // namespace polysquare
