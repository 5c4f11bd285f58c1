// The output of the pipeline, and what the readers of other tools' meshes return.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "polysquare/core/geometry.h"

namespace polysquare {

/// Kind of a mesh node, from the most constrained to the least.
enum class NodeKind : std::uint8_t {
  interior = 0,
  boundary = 1,  ///< on an input ring
  feature = 2,   ///< on a feature curve (not on the boundary)
  corner = 3,    ///< an input vertex kept as a node: sharp boundary vertex, feature end or intersection
};

/// A 2D mesh in flat arrays (no per-element heap objects), counter-clockwise quads.
/// polysquare writes quads only; `triangles` holds what readers find in other tools' meshes.
struct QuadMesh {
  std::vector<Vec2> nodes;                          ///< #nodes positions
  std::vector<std::array<std::int32_t, 4>> quads;   ///< #quads by 4 node indices, counter-clockwise
  std::vector<std::array<std::int32_t, 3>> triangles;  ///< #triangles by 3 node indices (other tools only)
  std::vector<std::int32_t> quad_part;              ///< #quads subregion index (empty or all 0 for one part)
  std::vector<NodeKind> node_kind;                  ///< #nodes kind (may be empty for meshes read from files)

  /// Tagged curve edges: boundary edges carry the input ring index, feature edges the feature curve index.
  std::vector<std::array<std::int32_t, 2>> boundary_edges;
  std::vector<std::int32_t> boundary_edge_ring;
  std::vector<std::array<std::int32_t, 2>> feature_edges;
  std::vector<std::int32_t> feature_edge_curve;

  std::string crs;    ///< carried from the region
  std::string units;  ///< carried from the region

  std::size_t num_nodes() const { return nodes.size(); }
  std::size_t num_quads() const { return quads.size(); }
};

}  // namespace polysquare
