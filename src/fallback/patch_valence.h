// Topological clean-up of an unstructured all-quad patch: local moves that bring the number of quads at each node
// towards what its angle asks for (four inside, about one per right angle on the patch's curves), so that a patch
// has few irregular nodes of its own and welds to its structured neighbours without new ones along the seam.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "polysquare/core/quad_mesh.h"

namespace polysquare::patch_valence {

/// Moves made by relax_valences, and the valence energy (sum over nodes of (quads - target)^2) before and after.
struct Moves {
  std::size_t flips = 0;      ///< interior edges turned to another diagonal of their two quads' hexagon
  std::size_t collapses = 0;  ///< quads collapsed along a diagonal (its two opposite nodes merged)
  double energy_before = 0.0;
  double energy_after = 0.0;
};

/// Quads of `mesh` that are folded (scaled Jacobian <= 0), and those below `poor`: how a move's result is judged.
std::pair<std::size_t, std::size_t> folded_and_poor(const QuadMesh& mesh, double poor);

/// Greedy moves on `mesh` (nodes below `given` are fixed: never removed, never moved), each lowering the valence
/// energy: the target of a free node is 4, of a given node its angle inside the patch over a right angle, or
/// `given_targets[v]` when that is not empty.
/// `kept_edges` (node pairs) are never flipped. A move is made only when every quad it creates keeps a positive
/// area at the current positions, and no quad gets a corner of three given nodes that is reflex or nearly flat.
/// Removed free nodes stay in `mesh.nodes` but in no quad; `mesh.quad_part`, when it has an entry per quad,
/// follows the quads (a turned quad keeps its entry). At most `max_moves` moves. Then up to `plateau_rounds`
/// rounds of moves that keep the energy, each followed by the greedy moves; the lowest energy reached is kept.
Moves relax_valences(QuadMesh& mesh, std::size_t given, const std::vector<std::array<std::int32_t, 2>>& kept_edges,
                     std::size_t max_moves, int plateau_rounds, const std::vector<double>& given_targets = {});

}  // namespace polysquare::patch_valence
