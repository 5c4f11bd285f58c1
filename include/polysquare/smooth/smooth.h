// Stage 7 (global part): smoothing of the assembled quad mesh. Interior nodes move in the plane; boundary and
// feature nodes slide along their input curve (so they stay exactly on it); corner nodes never move.
#pragma once

#include "polysquare/core/quad_mesh.h"
#include "polysquare/core/region.h"
#include "polysquare/smooth/untangle.h"

namespace polysquare {

struct SmoothOptions {
  UntangleOptions untangle;      ///< first, the interior nodes of folded quads are untangled (untangle.h)
  int iterations = 10;           ///< Gauss-Seidel sweeps of guarded Laplacian smoothing of interior nodes (at most;
                                 ///< more change SJ min by < 0.005 on the bundled cases)
  double converged_fraction = 0.01;  ///< stop the sweeps when no node moves by more than this fraction of an edge
  int worst_sweeps = 10;         ///< sweeps of the pattern search that maximizes the worst corner around poor nodes
  double worst_threshold = 0.9;  ///< nodes whose incident quads have a corner scaled Jacobian below this are searched
  bool slide_on_curves = true;   ///< let boundary and feature nodes slide along their input curve in the search
  double feature_tolerance = 0;  ///< largest distance (region units) between a feature curve and the mesh edge
                                 ///< joining two of its nodes: slides never exceed it, and nodes beside a longer
                                 ///< chord move to even it out. 0 = unbounded. The pipeline sets it from
                                 ///< MeshOptions::feature_tolerance.
  double feature_repair_min_sj = 0.3;  ///< a node evening out a chord may not push the worst corner around it
                                       ///< below this (or below its current value, if lower)
};

struct SmoothStats {
  UntangleStats untangle;
  int sweeps = 0;
  std::size_t moves = 0;        ///< accepted interior moves over all sweeps
  std::size_t curve_moves = 0;  ///< accepted moves of boundary and feature nodes along their curves
};

/// Laplacian smoothing guarded by quality: each interior node moves to the mean of its edge neighbours only if
/// the smallest corner scaled Jacobian of its incident quads increases. Then a derivative-free pattern search
/// maximizes that worst corner around the poor nodes: in the plane for interior nodes and, when `region` is
/// given and slide_on_curves is set, along the input ring or feature curve for boundary and feature nodes
/// (positions interpolated on the input polyline, between the node's curve neighbours). No move makes the worst
/// quad around a node worse. Deterministic (fixed node order), independent of the thread count. With `only`
/// (#nodes), just the nodes flagged there move (a mesh changed in a few places is smoothed there).
SmoothStats smooth_quads(QuadMesh& mesh, const SmoothOptions& options, const Region* region = nullptr,
                         const std::vector<std::uint8_t>* only = nullptr);

/// Smallest corner scaled Jacobian of quad q (sin of the corner angle; negative when inverted).
double quad_min_corner_sj(const QuadMesh& mesh, std::size_t q);

}  // namespace polysquare
