// The invariants every output mesh must hold (design.md), checked before anything is written.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "polysquare/core/quad_mesh.h"

namespace polysquare {

struct InvariantReport {
  std::size_t degenerate_quads = 0;     ///< repeated node or zero area
  std::size_t inverted_quads = 0;       ///< some corner with scaled Jacobian <= 0
  std::size_t non_manifold_edges = 0;   ///< edges with more than two quads
  std::size_t untagged_boundary_edges = 0;  ///< edges with one quad that are not tagged boundary edges
  std::size_t tagged_edges_not_boundary = 0; ///< tagged boundary edges that do not have exactly one quad
  std::size_t feature_edges_not_in_mesh = 0; ///< tagged feature edges that are not edges of any quad
  std::string first_problem;            ///< description of the first violation (empty when valid)
  bool ok() const { return first_problem.empty(); }
};

/// Checks invariants 1-3 of design.md and the consistency of the curve tags (boundary edges are exactly the
/// edges with one quad; feature edges are quad edges).
InvariantReport check_invariants(const QuadMesh& mesh);

/// #quads: 1 for a quad with an edge that no other quad shares and that is not a tagged boundary edge (a crack
/// between pieces that do not share their nodes), or an edge shared by more than two quads. The repair rounds
/// mesh the subregions of these quads again, as they do for folded ones.
std::vector<std::uint8_t> quads_beside_cracks(const QuadMesh& mesh);

}  // namespace polysquare
