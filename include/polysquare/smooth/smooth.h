// Stage 7 (global part): smoothing of the assembled quad mesh. Interior nodes move; boundary, feature and
// corner nodes stay exactly on their curves.
#pragma once

#include "polysquare/core/quad_mesh.h"

namespace polysquare {

struct SmoothOptions {
  int iterations = 40;   ///< Gauss-Seidel sweeps over the interior nodes
  double min_gain = 0.0; ///< a move is kept only if the worst corner of the incident quads improves by more than this
  int worst_sweeps = 10;  ///< sweeps of the pattern search that maximizes the worst corner around poor nodes
  double worst_threshold = 0.6;  ///< nodes whose incident quads have a corner scaled Jacobian below this are searched
};

struct SmoothStats {
  int sweeps = 0;
  std::size_t moves = 0;  ///< accepted node moves over all sweeps
};

/// Laplacian smoothing guarded by quality: each interior node moves to the mean of its edge neighbours only if
/// the smallest corner scaled Jacobian of its incident quads increases, so smoothing never makes the worst quad
/// around a node worse; then a pattern search maximizes that worst corner around the poor nodes.
/// Deterministic (fixed node order), independent of thread count.
SmoothStats smooth_quads(QuadMesh& mesh, const SmoothOptions& options);

/// Smallest corner scaled Jacobian of quad q (sin of the corner angle; negative when inverted).
double quad_min_corner_sj(const QuadMesh& mesh, std::size_t q);

}  // namespace polysquare
