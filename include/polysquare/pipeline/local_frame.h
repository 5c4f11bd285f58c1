// Meshing far from the origin: the region is moved next to the origin before meshing and the mesh moved back.
#pragma once

#include <cstdint>

#include "polysquare/core/geometry.h"
#include "polysquare/core/quad_mesh.h"
#include "polysquare/core/region.h"

namespace polysquare {

/// Where to put the origin of a local frame for `region`: (0, 0) when the region lies within 1e4 of its bounding-box
/// diagonals of the origin (projected coastlines: UTM coordinates of millions of metres around domains of
/// kilometres), else its bounding-box centre rounded to a multiple of a power of two no smaller than the diagonal,
/// so that subtracting it is exact for every coordinate of the region. With it, a region 1e11 from the origin
/// keeps 16 significant digits relative to its own size: orientation and area tests, triangulation and
/// snapping then see the same numbers as next to the origin (a 100 m square 1e11 away lost its area and its
/// constrained segments). The remaining limit is the output: coordinates written back carry their absolute
/// rounding, about 1e-16 of their magnitude (1.5e-5 at 1e11).
Vec2 local_origin(const Region& region);

/// Adds `offset` to every point of the region (rings, feature curves, feature points).
void translate(Region& region, Vec2 offset);
/// Adds `offset` to every node of the mesh.
void translate(QuadMesh& mesh, Vec2 offset);

/// The index of the first quad of `mesh` with a corner that does not turn strictly counter-clockwise (a fold
/// or a collapse), -1 when none: run on a mesh moved back from a local frame, it finds quads that the rounding
/// of far coordinates bent out of shape (corner tests on coordinate differences, which are exact for nearby
/// nodes whatever their magnitude).
std::int64_t first_folded_quad(const QuadMesh& mesh);

}  // namespace polysquare
