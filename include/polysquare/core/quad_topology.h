// Connectivity of a quad mesh that several stages read: how many quads share each edge, node valences.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "polysquare/core/quad_mesh.h"

namespace polysquare {

/// Number of quads on every edge of the quads of `mesh` (triangles are not counted): one (edge_key, count) entry
/// per edge, sorted by key. One sorted array, not a hash map: at millions of quads the map's nodes and hashing
/// were a tenth of a run.
struct EdgeCounts {
  std::vector<std::pair<std::uint64_t, int>> edges;
  /// Quads on the edge with `key`; 0 when no quad has that edge.
  int count(std::uint64_t key) const;
  auto begin() const { return edges.begin(); }
  auto end() const { return edges.end(); }
  std::size_t size() const { return edges.size(); }
};
EdgeCounts quad_edge_counts(const QuadMesh& mesh);

struct NodeValences {
  std::vector<int> valence;               ///< #nodes: distinct quad edges at the node (0 for a node of no quad)
  std::vector<std::uint8_t> on_boundary;  ///< #nodes: 1 when the node is on an edge of one quad
};

/// Valences and boundary flags from the edge counts of quad_edge_counts(mesh).
NodeValences node_valences(const QuadMesh& mesh, const EdgeCounts& edge_counts);

/// The quads at each node, compressed: those of node v are quads[offset[v] .. offset[v + 1]), in quad order.
struct NodeQuads {
  std::vector<std::size_t> offset;  ///< #nodes + 1
  std::vector<std::int32_t> quads;
};
NodeQuads node_quads(const QuadMesh& mesh);

}  // namespace polysquare
