// Stage 4-6 for a partitioned part, the Piecewise Poly-square Map (FPPM Sec. 5.2): every subregion is cut out of
// the background triangulation and mapped to a poly-square in its own frame; one integer program quantizes all
// of them with equal element counts on both sides of every interface; the subregions' quads are stitched into one
// conforming mesh. Singularities appear where subregions meet, never elsewhere inside.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "polysquare/core/quad_mesh.h"
#include "polysquare/map/polysquare_map.h"
#include "polysquare/triangulate/background_triangulation.h"

namespace polysquare {

/// One subregion cut out of a partitioned triangulation.
struct Subregion {
  TriMesh mesh;  ///< its triangles; chains: its boundary loops cut into ring pieces and interfaces (listed in
                 ///< mesh.loops), then the pieces of feature curves inside it
  std::vector<std::int32_t> global_vertex;  ///< #mesh.vertices: vertex of the partitioned triangulation, or -1
                                            ///< for vertices added by splitting constrained interior edges
};

/// Cuts `tri` (rings and features as chains, no separator chains) into the subregions of `triangle_part`.
/// A boundary loop is cut wherever the neighbour across it changes (outside, another subregion, a feature on
/// the interface) and at every vertex where three or more curves meet, identically on both sides of each
/// interface. Throws MeshingError naming `name` when a subregion touches itself at a vertex or is enclosed by a
/// single neighbour (no junction to close its poly-square on). With `chain_ends` given, it receives for every vertex
/// of `tri` whether chains are cut there (a union of these subregions, cut later, has longer chains).
std::vector<Subregion> split_subregions(const TriMesh& tri, const std::vector<std::int32_t>& triangle_part, int parts,
                                        const std::string& name, std::vector<std::uint8_t>* chain_ends = nullptr);

/// Welds the nodes of several quad meshes that lie on shared sides: node i < side_nodes[m] of mesh m is merged
/// with any node of another mesh within `tolerance`; feature edges found twice are kept once. quad_part of the
/// result is the index of the mesh each quad came from.
QuadMesh stitch_quad_meshes(const std::vector<QuadMesh>& meshes, const std::vector<std::size_t>& side_nodes,
                            double tolerance);

/// Local repair by splitting (paper Sec. 5.3): every subregion whose map fails on its own (labelling,
/// deformation, quantization alone, snap) is cut into smaller subregions by a k-way partition of its triangles,
/// k from its side count (options.sides_per_split), and the new pieces are tested again, options.split_rounds
/// times; subregions that map keep their triangles. The partition clean-ups run after each round (feature loops
/// kept whole, cut-off pieces absorbed, enclosed parts merged), and a round whose partition cannot be cut into
/// subregions is undone. Returns the number of subregions; `triangle_part` is renumbered 0 .. count-1.
int split_unmappable_subregions(const TriMesh& tri, std::vector<std::int32_t>& triangle_part, int parts,
                                const PolysquareMapOptions& options, const std::string& name, SplitStats& stats);

/// Splits each listed subregion (subregion, its poly-square side count or 0) by a k-way partition of its
/// triangles, k = ceil(sides / options.sides_per_split) in [2, 8], unless its pieces would be smaller than 4 x 4
/// elements or the part would pass its cap (options.split_max_subregions, or its quads over
/// options.split_quads_per_subregion when that is more); then the partition clean-ups. Returns the new subregion
/// count and sets `split` to the number split (0 and the partition unchanged when the pieces cannot be cut into
/// subregions).
int split_listed_subregions(const TriMesh& tri, std::vector<std::int32_t>& triangle_part, int parts,
                            const std::vector<std::pair<int, int>>& listed, const PolysquareMapOptions& options,
                            const std::string& name, int& split);

/// The PPM of one partitioned part: split, per-subregion deformation and layout (in parallel), one joint
/// quantization, per-subregion snap and extraction (in parallel), stitching. quad_part = subregion. Fills the
/// timing and layout figures of `stats`. Throws MeshingError naming `name` and the subregion that failed.
QuadMesh map_piecewise(const TriMesh& tri, const std::vector<std::int32_t>& triangle_part, int parts,
                       const PolysquareMapOptions& options, const std::string& name, PartMapStats& stats);

}  // namespace polysquare
