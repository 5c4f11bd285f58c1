// Fallback of stages 4-6 for a polygon part that no poly-square candidate meshes (convoluted coastline parts):
// an unstructured all-quad mesh from a quality triangulation. Triangle pairs that make good quads are merged
// first; then every quad is split into four and every remaining triangle into three (corners, edge midpoints,
// centre). It holds every invariant (conforming, boundary and feature curves chains of edges, sharp vertices as
// nodes) but is not semi-structured. The pipeline reports every part meshed this way.
#pragma once

#include "polysquare/core/quad_mesh.h"
#include "polysquare/core/region.h"
#include <cstdint>
#include <unordered_map>
#include <utility>
#include <vector>

#include "polysquare/triangulate/background_triangulation.h"

namespace polysquare {

struct SplitOptions {
  double size = 1.0;                 ///< target quad edge length h (region units); must be set by the caller
  double max_size = 0.0;             ///< graded meshes: the largest size, which interior triangles may grow to
                                     ///< from `size` at the curves (0 = `size` throughout)
  double corner_threshold_deg = 30;  ///< input vertices turning by more than this become corner nodes
  double shape_bound = 0.125;        ///< CGAL shape bound of the triangulation (0.125 = 20.7 degrees minimum
                                     ///< angle; the worst quad corner is the worst triangle angle; tighter bounds
                                     ///< refine finely spaced coastlines far below h)
  std::size_t max_triangles = 20'000'000;  ///< refuse larger triangulations
  double pair_min_sj = 0.3;          ///< two triangles sharing an interior edge are first merged into a quad
                                     ///< whose worst corner is at least this (best first, greedy); the quad is
                                     ///< split into four. Cuts the singular nodes: a vertex keeps about four
                                     ///< cells instead of six. > 1 = no pairs (every triangle split in three)
};

/// The triangulation the fallback splits: curves at 2 h, interior edges up to 3.5 h (3.5 max_size when graded),
/// SplitOptions' shape bound.
TriangulationOptions split_triangulation_options(const SplitOptions& options);

/// The counter-clockwise quad made of triangle t of `tri` and its neighbour u across their shared edge
/// ({-1, -1, -1, -1} when they share no edge).
std::array<std::int32_t, 4> quad_of_pair(const TriMesh& tri, std::int32_t t, std::int32_t u);

/// Greedy matching of the triangles of `tri` into quads across interior edges that are not on a curve, best
/// worst-corner first, pairs below `min_sj` left out: partner triangle of each triangle (-1 if alone), pairs.
std::pair<std::vector<std::int32_t>, std::size_t> pair_triangles(const TriMesh& tri, double min_sj);

/// Splits the cells of `tri` into quads: triangle pairs (pair_triangles, min_sj = pair_min_sj) are merged
/// first, then every quad is cut into four and every other triangle into three at its edge midpoints and centre.
/// `out` already holds a node for every vertex of `tri` under the same index; `midpoint` gives the node already
/// made for an edge's middle (by edge_key: curve edges); every other edge gets a new interior node at its middle
/// and every cell an interior centre node. Appends the quads (counter-clockwise) with quad_part 0.
void split_cells(const TriMesh& tri, double pair_min_sj, QuadMesh& out,
                 std::unordered_map<std::uint64_t, std::int32_t>& midpoint);

/// Quad mesh of `part` from a triangulation with edges of about 2 h (each split in two; triangle pairs merged
/// into quads first, see SplitOptions::pair_min_sj), node kinds set for
/// smoothing (ring nodes boundary, feature nodes feature, sharp input vertices, curve ends and meetings corner).
/// Throws MeshingError for a part smaller than one element.
QuadMesh split_triangles(const Region& region, const RegionPart& part, const SplitOptions& options);

}  // namespace polysquare
