// Foldover-free maps with a fixed boundary (stage 5, the snap's last resort): the interior vertices of a
// triangulation whose constrained vertices already sit on their targets are moved until no triangle is
// inverted, by minimizing a regularized distortion energy (Garanzha, Kaporin, Kudryavtseva, Protais, Ray,
// Sokolov, "Foldover-free maps in 50 lines of code", ACM TOG 40(4), 2021): every triangle's energy is finite
// whatever its orientation, and the regularization shrinks as the inverted triangles unfold.
#pragma once

#include <cstdint>
#include <vector>

#include "polysquare/map/deform.h"

namespace polysquare {

/// Moves the vertices v with movable[v] != 0 so that every triangle of `problem` has a positive signed area,
/// measured against its rest shape. Returns whether it got there; `x` is changed either way.
bool untangle_triangles(const DeformProblem& problem, const std::vector<std::uint8_t>& movable, std::vector<Vec2>& x);

}  // namespace polysquare
