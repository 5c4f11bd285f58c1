// Graded PPM: the transition row that joins two counts of one interface (map/piecewise_map.cpp).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "polysquare/core/geometry.h"
#include "polysquare/core/quad_mesh.h"

namespace polysquare {

/// The first `side_nodes` nodes of `mesh` that lie on the polyline `line` (within `tolerance`), in order along it.
std::vector<std::int32_t> nodes_along(const QuadMesh& mesh, std::size_t side_nodes, const std::vector<Vec2>& line,
                                      double tolerance);

/// Replaces the row of `coarse` quads that have an edge on `line` (its n interface edges) by a transition row
/// onto `top`, the finer side's n + 2t nodes along the same line (positions and kinds, in order along it, ends
/// equal to coarse's): n quads keep one edge on each side and t fans (two top edges, none below, spread evenly)
/// take the rest, each fan leaving its middle top node with valence 3 and its bottom node with valence 5.
/// coarse's nodes on the line give way to top's, kept among its first `side_nodes` (updated) so that stitching
/// merges them with the finer side's. `in_row` (#quads of coarse, kept in step) marks quads of earlier rows,
/// which a row may not take again but at an end of the line (a corner quad of two rows): there the row leaves
/// that quad out, and the quad's node on the line moves onto the finer side's next node. Throws MeshingError
/// saying why when the quads along the line are no row.
void replace_with_transition_row(QuadMesh& coarse, std::size_t& side_nodes, std::vector<std::uint8_t>& in_row,
                                 const std::vector<Vec2>& line, const std::vector<Vec2>& top,
                                 const std::vector<NodeKind>& top_kind, double tolerance);

}  // namespace polysquare
