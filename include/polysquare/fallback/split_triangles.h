// Fallback of stages 4-6 for a polygon part that no poly-square candidate meshes (convoluted coastline parts):
// an unstructured all-quad mesh made by splitting every triangle of a quality triangulation into three quads
// (corner, two edge midpoints, centroid). It holds every invariant (conforming, boundary and feature curves
// chains of edges, sharp vertices as nodes) but is not semi-structured: interior nodes have the triangulation's
// valences. The pipeline reports every part meshed this way.
#pragma once

#include "polysquare/core/quad_mesh.h"
#include "polysquare/core/region.h"
#include "polysquare/triangulate/background_triangulation.h"

namespace polysquare {

struct SplitOptions {
  double size = 1.0;                 ///< target quad edge length h (region units); must be set by the caller
  double corner_threshold_deg = 30;  ///< input vertices turning by more than this become corner nodes
  double shape_bound = 0.125;        ///< CGAL shape bound of the triangulation (0.125 = 20.7 degrees minimum
                                     ///< angle; the worst quad corner is the worst triangle angle; tighter bounds
                                     ///< refine finely spaced coastlines far below h)
  std::size_t max_triangles = 20'000'000;  ///< refuse larger triangulations
};

/// Quad mesh of `part` from a triangulation with edges of about 2 h (each split in two), node kinds set for
/// smoothing (ring nodes boundary, feature nodes feature, sharp input vertices, curve ends and meetings corner).
/// Throws MeshingError for a part smaller than one element.
QuadMesh split_triangles(const Region& region, const RegionPart& part, const SplitOptions& options);

}  // namespace polysquare
