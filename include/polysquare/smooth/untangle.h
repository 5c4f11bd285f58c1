// Untangling of folded quads by moving free nodes (part of stage 7, and of the patches that repair failed
// subregions). Every corner's signed area is linear in each of its three nodes, so for one node the positions
// where all corners of its quads are convex form a convex polygon (the kernel). A node of a folded quad moves to
// the point of that polygon farthest from its edges (the largest inscribed circle's centre); where the kernel is
// empty, to the point where the worst corner is least folded. A move is kept only if it lifts the worst corner
// around the node and leaves no more of its quads below the target: lifting the worst corner alone may fold a
// neighbouring quad, and the tangle spreads.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "polysquare/core/quad_mesh.h"

namespace polysquare {

struct UntangleOptions {
  int sweeps = 20;           ///< sweeps over the nodes of folded quads (and their neighbours), at most
  double target_sj = 0.05;   ///< quads whose worst corner scaled Jacobian is below this count as folded here
};

struct UntangleStats {
  std::size_t folded_before = 0;  ///< quads below target_sj before
  std::size_t folded_after = 0;   ///< and after
  std::size_t moves = 0;          ///< node moves made
};

/// Moves the nodes with movable[v] != 0 (one entry per node) of quads whose worst corner is below
/// options.target_sj, and the movable nodes next to them. Deterministic (fixed node order).
UntangleStats untangle_quads(QuadMesh& mesh, const std::vector<std::uint8_t>& movable, const UntangleOptions& options);

}  // namespace polysquare
