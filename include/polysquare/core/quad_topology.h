// Connectivity of a quad mesh that several stages read: how many quads share each edge, node valences.
#pragma once

#include <cstdint>
#include <unordered_map>
#include <vector>

#include "polysquare/core/quad_mesh.h"

namespace polysquare {

/// Number of quads on every edge of the quads of `mesh`, keyed by edge_key (triangles are not counted).
std::unordered_map<std::uint64_t, int> quad_edge_counts(const QuadMesh& mesh);

struct NodeValences {
  std::vector<int> valence;               ///< #nodes: distinct quad edges at the node (0 for a node of no quad)
  std::vector<std::uint8_t> on_boundary;  ///< #nodes: 1 when the node is on an edge of one quad
};

/// Valences and boundary flags from the edge counts of quad_edge_counts(mesh).
NodeValences node_valences(const QuadMesh& mesh, const std::unordered_map<std::uint64_t, int>& edge_counts);

/// The quads at each node, compressed: those of node v are quads[offset[v] .. offset[v + 1]), in quad order.
struct NodeQuads {
  std::vector<std::size_t> offset;  ///< #nodes + 1
  std::vector<std::int32_t> quads;
};
NodeQuads node_quads(const QuadMesh& mesh);

}  // namespace polysquare
