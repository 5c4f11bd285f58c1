// How closely a mesh follows its size field: each quad's size (the square root of its area) over the field at
// its centroid, and how much the size jumps between neighbouring quads.
#pragma once

#include <cstddef>

#include "polysquare/core/quad_mesh.h"
#include "polysquare/size/size_field.h"

namespace polysquare {

struct SizeConformity {
  double median = 0.0, p05 = 0.0, p95 = 0.0;  ///< of sqrt(quad area) / h(centroid) over the quads
  double neighbour_p99 = 0.0;                 ///< of max(a, b) / min(a, b), a and b the sizes of two quads
  double neighbour_max = 0.0;                 ///< sharing an edge, over the interior edges
  std::size_t quads = 0;
};

/// The conformity of `mesh` (quads only) to `field`.
SizeConformity size_conformity(const QuadMesh& mesh, const SizeField& field);

}  // namespace polysquare
