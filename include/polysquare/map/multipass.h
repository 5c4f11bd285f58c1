// The paper's multi-pass PPM deformation (Sec. 5, Algorithm 1): the subregions of a partitioned part are deformed
// towards poly-squares together instead of each alone. Each subregion's deformation chart is the subregion with a
// buffer of k rings of its neighbours' triangles; the chart's outer ring stays where the last pass left it, so
// that what one subregion does to an interface its neighbours see in the next pass. Subregions of one colour (no
// two adjacent) are deformed in parallel, the colours in turn, each chart re-oriented first, until no vertex
// moves more than a tolerance in a pass.
#pragma once

#include <cstdint>
#include <vector>

#include "polysquare/core/geometry.h"
#include "polysquare/map/deform.h"
#include "polysquare/triangulate/background_triangulation.h"

namespace polysquare {

struct MultipassOptions {
  int max_passes = 0;        ///< passes over all colours at most; 0 = off (every subregion deformed alone)
  int buffer_rings = 2;      ///< k: rings of neighbouring triangles in each subregion's deformation chart
  double tolerance = 1e-2;   ///< stop after a pass in which no vertex moved more than this (elements; paper: T)
};

struct MultipassStats {
  int passes = 0;          ///< passes made
  int colours = 0;         ///< groups of non-adjacent subregions
  double last_move = 0.0;  ///< largest vertex move of the last pass (elements)
  double seconds = 0.0;
};

/// Positions of every vertex of `tri` (lattice units: input coordinates / size, one frame for the part) after the
/// multi-pass deformation of the subregions `triangle_part` (0 .. parts-1) of `tri`: every subregion's boundary
/// and the features inside it are pulled to the axes of its own frame (deform.h's energy with `deform`'s weights),
/// its chart's outer ring fixed. Deterministic for any thread count.
std::vector<Vec2> multipass_deform(const TriMesh& tri, const std::vector<std::int32_t>& triangle_part, int parts,
                                   double size, const MultipassOptions& options, const DeformOptions& deform,
                                   MultipassStats& stats);

}  // namespace polysquare
