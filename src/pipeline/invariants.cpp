#include "polysquare/pipeline/invariants.h"

#include <algorithm>
#include <unordered_map>
#include <unordered_set>

#include "polysquare/core/quad_topology.h"
#include "polysquare/smooth/smooth.h"

namespace polysquare {

InvariantReport check_invariants(const QuadMesh& mesh) {
  InvariantReport r;
  auto problem = [&](const std::string& text) {
    if (r.first_problem.empty()) r.first_problem = text;
  };
  std::unordered_map<std::uint64_t, int> edge_count;
  edge_count.reserve(mesh.quads.size() * 2);
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
    if (quad_min_corner_sj(mesh, q) <= 0.0) {
      r.inverted_quads++;
      const Vec2 p = mesh.nodes[quad[0]];
      problem("quad " + std::to_string(q) + " at (" + std::to_string(p.x) + ", " + std::to_string(p.y) +
              ") is inverted or has a flat corner");
    }
    for (int k = 0; k < 4; ++k) edge_count[edge_key(quad[k], quad[(k + 1) % 4])]++;
  }
  if (!mesh.triangles.empty()) problem(std::to_string(mesh.triangles.size()) + " triangles in an all-quad mesh");
  std::unordered_map<std::uint64_t, int> tagged;
  for (const auto& e : mesh.boundary_edges) tagged[edge_key(e[0], e[1])]++;
  for (const auto& [key, count] : edge_count) {
    if (count > 2) { r.non_manifold_edges++; problem("an edge is shared by " + std::to_string(count) + " quads"); }
    if (count == 1 && !tagged.count(key)) {
      r.untagged_boundary_edges++;
      // Where: a crack between pieces that do not share their nodes, or a boundary edge that lost its tag.
      const Vec2 a = mesh.nodes[static_cast<std::size_t>(key >> 32)], b = mesh.nodes[static_cast<std::size_t>(key & 0xffffffffu)];
      problem("a boundary edge from " + at_text(a) + " to " + at_text(b) + " is not on the input boundary");
    }
  }
  for (const auto& [key, count] : tagged) {
    auto it = edge_count.find(key);
    if (count != 1 || it == edge_count.end() || it->second != 1) {
      r.tagged_edges_not_boundary++;
      problem("a tagged boundary edge does not have exactly one quad");
    }
  }
  for (const auto& e : mesh.feature_edges)
    if (!edge_count.count(edge_key(e[0], e[1]))) {
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
      const int count = edge_count.at(key);
      out[q] |= count > 2 || (count == 1 && !tagged.count(key));
    }
  return out;
}

}  // namespace polysquare
