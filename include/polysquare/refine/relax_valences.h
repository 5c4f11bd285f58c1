// Stage 8, after the local patches: the unstructured quads of a finished mesh (subregion patches, local patches)
// are cleaned up together with the nodes they share with mapped quads. Each patch was built alone, with targets
// for its boundary nodes guessed from their angles; here a node on a seam counts its quads on both sides, so the
// moves of fallback/patch_valence.h (edge turns, quad collapses) can make it regular, and irregular nodes of
// neighbouring patches can meet and cancel.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "polysquare/core/quad_mesh.h"
#include "polysquare/smooth/smooth.h"

namespace polysquare {

struct RelaxValencesOptions {
  bool enabled = true;
  int plateau_rounds = 40;         ///< rounds of energy-neutral moves (fallback/patch.h's valence_plateau_rounds);
                                   ///< a piece the smoothing cannot follow then is tried with the improving moves only
  std::size_t max_moves = 200000;  ///< at most this many moves per piece
  int laplacian_sweeps = 10;       ///< plain Laplacian sweeps over a moved piece's free nodes, then the mesh's
                                   ///< smoothing (the caller's SmoothOptions)
  double poor_sj = 0.2;            ///< a piece is kept unless more of its quads end folded or with a corner below
                                   ///< this (the pipeline sets it from MeshOptions::min_scaled_jacobian)
};

struct RelaxValencesStats {
  std::size_t region_quads = 0;   ///< unstructured quads looked at
  std::size_t flips = 0, collapses = 0;  ///< moves in the pieces kept
  double energy_before = 0.0, energy_after = 0.0;  ///< sum of (quads - target)^2 over the pieces' nodes
  bool kept = false;              ///< some piece was kept (the mesh changed)
  std::size_t first_kept_quad = 0;  ///< when kept: the kept pieces' quads are mesh.quads from this index on
};

/// Moves on the quads flagged in `region` (#quads), in pieces (flagged quads sharing a node), each kept or not on
/// its own. Only nodes whose quads are all flagged and that are neither on the boundary nor on a feature move or
/// disappear; every other node keeps its place and aims at its share of a regular node (its angle over a right
/// angle, less the quads it keeps outside the piece). When something is kept, the quads outside kept pieces come
/// first, in their order, then each kept piece's: `origin` (#new quads) gives for each quad the index whose
/// per-quad data it takes (quad_part is carried here); nodes no quad uses any more are removed. Deterministic,
/// whatever the thread count.
RelaxValencesStats relax_region_valences(QuadMesh& mesh, const std::vector<std::uint8_t>& region,
                                         const RelaxValencesOptions& options, const SmoothOptions& smooth,
                                         std::vector<std::size_t>& origin);

}  // namespace polysquare
