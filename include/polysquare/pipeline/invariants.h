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
  std::size_t overlapping_quad_pairs = 0;    ///< pairs of quads whose interiors intersect (find_overlapping_quads)
  std::string first_problem;            ///< description of the first violation (empty when valid)
  bool ok() const { return first_problem.empty(); }
};

/// Checks invariants 1-3 and 7 (no two quads overlap) of design.md and the consistency of the curve tags (boundary
/// edges are exactly the edges with one quad; feature edges are quad edges). The area half of invariant 7 needs the
/// region and is not checked here: with no overlap, no inverted quad and every edge in one or two quads, the quads'
/// area equals the area the mesh's boundary edges enclose (term by term), so only a comparison with the region
/// adds anything.
InvariantReport check_invariants(const QuadMesh& mesh);

struct QuadOverlaps {
  std::size_t pairs = 0;  ///< pairs of quads whose interiors intersect
  std::int64_t first_a = -1, first_b = -1;  ///< the pair with the lowest indices (first_a < first_b), -1 when none
  Vec2 at{};                                ///< a point inside both quads of that pair
  std::vector<std::uint32_t> quads;         ///< every quad of some pair, ascending
};
/// Pairs of quads of `mesh` whose interiors intersect: quads that share nodes or edges and only touch are not
/// counted, two quads on the same place with different nodes are. Exact orientation tests (CGAL's filtered
/// predicate where the floating-point sign is uncertain) on each quad split into two triangles along a diagonal
/// inside it; candidates from a uniform grid of about the mean quad extent, so linear on average; parallel
/// (oneTBB); the result does not depend on the thread count. Quads with a non-finite coordinate are left out.
QuadOverlaps find_overlapping_quads(const QuadMesh& mesh);

/// #quads: 1 for a quad with an edge that no other quad shares and that is not a tagged boundary edge (a crack
/// between pieces that do not share their nodes), or an edge shared by more than two quads. The repair rounds
/// mesh the subregions of these quads again, as they do for folded ones.
std::vector<std::uint8_t> quads_beside_cracks(const QuadMesh& mesh);

}  // namespace polysquare
