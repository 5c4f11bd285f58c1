// Stage 8 (first template): adaptive singularity refinement (paper Sec. 5.3). A poly-square corner that the map
// put on a smooth stretch of the boundary leaves a boundary node with a single quad whose corner there is nearly
// flat (a disc meshed as one poly-square has four). The paper's triangle patch with the thinnest strip, one
// element, reduces to collapsing that quad along its diagonal: the corner node stays on the curve, its two
// boundary neighbours merge into it, and the node across becomes an interior valence-3 singularity whose three
// quads smoothing opens to about 120 degrees.
#pragma once

#include <cstddef>

#include "polysquare/core/quad_mesh.h"

namespace polysquare {

struct RefineOptions {
  bool enabled = true;             ///< apply the template (the map's raw corners are kept when false)
  double flat_corner_deg = 135.0;  ///< a boundary node with one quad whose angle there exceeds this is collapsed
                                   ///< (sin 135 = SJ 0.71: flatter corners are worse than the valence-3 node
                                   ///< the template leaves)
  double loop_corner_deg = 150.0;  ///< a closed feature loop is pillowed where a single-quad corner on one side is
                                   ///< flatter than this (sin 150 = SJ 0.5): the layer leaves eight singular
                                   ///< nodes, more than a corner of SJ 0.5 to 0.7 is worth; 180 = off
};

struct RefineStats {
  std::size_t flat_corners = 0;   ///< boundary nodes with one quad and an angle above the threshold
  std::size_t collapsed = 0;      ///< of those, collapsed (the others had a neighbourhood the template cannot take)
  std::size_t feature_loops = 0;  ///< closed feature loops with a flat single-quad corner on one side
  std::size_t pillowed = 0;       ///< of those, pillowed (the others would have inverted a quad)
};

/// Collapses the quads at flattened boundary corners of `mesh` in place (nodes renumbered, tags and quad_part
/// kept consistent). Only boundary nodes of kind `boundary` (never input corners) on one ring qualify; a quad
/// whose collapse would join two nodes that already share a neighbour, or touch a collapse already made, is left.
/// Deterministic: candidates in node order.
RefineStats refine_flat_corners(QuadMesh& mesh, const RefineOptions& options);

/// Second template, for closed feature loops (smile's eyes, mechanical_part's circle). A poly-square puts four
/// corners on a loop; on a round loop each leaves a node with one quad on one side, flat there (150 degrees on
/// smile's eyes, so SJ 0.5), and the boundary collapse cannot be used because the loop nodes carry quads on both
/// sides. Pillowing that side inserts a layer of quads along the whole loop: every loop node gets a copy on that
/// side, the side's quads use the copies, and each loop edge gets a new quad between the node pairs. The flat
/// corner then has two quads, its copy becomes an interior valence-3 node (the loop node valence 5): eight
/// singularities per loop, no new node on the curve, conforming because the layer is closed. Only loops whose
/// nodes carry no other curve edge qualify; a loop whose layer would invert a quad is left as it was.
/// Deterministic: loops in curve order, new nodes and quads appended.
RefineStats pillow_feature_loops(QuadMesh& mesh, const RefineOptions& options);

}  // namespace polysquare
