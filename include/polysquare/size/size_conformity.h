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

/// sqrt(area) of quad `q` of `mesh` (0 for a quad of negative area), region units.
double quad_size(const QuadMesh& mesh, std::size_t q);

/// quad_size over the field at the quad's centroid (the mean of its four nodes): 1 where quad `q` has the size
/// `field` asks for, 2 where it is twice as large.
double quad_size_ratio(const QuadMesh& mesh, std::size_t q, const SizeField& field);

/// The conformity of `mesh` (quads only) to `field`.
SizeConformity size_conformity(const QuadMesh& mesh, const SizeField& field);

}  // namespace polysquare
