// Local repair of a PPM subregion that no poly-square maps: an unstructured all-quad patch whose boundary nodes
// are given (the neighbours' interface nodes, the subregion's ring and feature pieces), so that it welds into the
// structured mesh around it. The patch is the split-triangle construction of split_triangles.h on a constrained
// Delaunay triangulation of every other boundary node: each constrained edge of that triangulation spans two
// given edges, and its midpoint is the given node between them.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "polysquare/core/quad_mesh.h"
#include "polysquare/size/size_field.h"
#include "polysquare/smooth/untangle.h"

namespace polysquare {

/// What a curve edge of a patch is in the output mesh.
enum class PatchEdgeRole : std::uint8_t {
  none,      ///< an interface with another subregion: untagged, interior nodes
  boundary,  ///< on an input ring: a boundary edge tagged with its ring
  feature,   ///< on a feature curve: a feature edge tagged with its curve
};

/// A chain of given nodes. Loops bound the patch (outer loops counter-clockwise, holes clockwise, the patch on
/// their left); other curves are feature curves inside it. Between two anchors (nodes shared by two curves, and
/// the ends of open curves) every curve must have an even number of edges, and every closed curve in all.
struct PatchCurve {
  std::vector<std::int32_t> nodes;     ///< node indices in order; closed curves do not repeat the first
  bool closed = false;
  bool loop = false;                   ///< a boundary loop of the patch (closed)
  std::vector<PatchEdgeRole> role;     ///< #edges role of edge i (nodes i -> i+1)
  std::vector<std::int32_t> tag;       ///< #edges ring or feature index of edge i (ignored for none)
};

struct PatchInput {
  std::vector<Vec2> nodes;             ///< every given node
  std::vector<NodeKind> kind;          ///< #nodes kind in the output mesh
  std::vector<PatchCurve> curves;
  std::vector<std::int32_t> points;    ///< isolated nodes inside the patch that must be mesh nodes
};

/// How a patch is built from its given nodes.
enum class PatchMethod : std::uint8_t {
  automatic,  ///< split, and matching where the split's coarse edges cannot follow the boundary
  split,      ///< every other given node a vertex of a coarse triangulation, every cell split into quads
  matching,   ///< a triangulation of the given nodes, triangles paired by a maximum-weight perfect matching
};

struct PatchOptions {
  PatchMethod method = PatchMethod::automatic;
  int matching_attempts = 8;   ///< matching: interior lattices (shifted) tried before giving up
  int matching_repairs = 8;    ///< matching: times the triangles left unmatched get a centre vertex, per lattice
  double size = 1.0;           ///< target quad edge length h; interior triangle vertices are 2 h apart
  std::shared_ptr<const SizeField> size_field;  ///< graded meshes: the interior vertices' spacing follows this
                                                ///< field (at least `size`, doubling in steps); null = uniform
  double pair_min_sj = 0.3;    ///< triangle pairs merged first when their quad's worst corner reaches this
  bool refuse_folded = false;  ///< throw when a quad is still folded after the sweeps (else the mesh's smoothing
                               ///< and invariant check decide)
  double inset_angle_deg = 150.0;  ///< a given node in one quad whose angle there exceeds this gets two quads
                                   ///< (that quad is replaced by an inner quad and four around it)
  int untangle_sweeps = 30;    ///< plain Laplacian sweeps over the interior nodes, before the untangler
  UntangleOptions untangle;    ///< then the untangler (untangle.h) on the interior nodes
  bool relax_valences = true;  ///< then local moves (edge flips, quad collapses) towards four quads at an interior
                               ///< node and one per right angle on a curve, kept unless more quads end folded or poor
  std::size_t max_valence_moves = 100000;  ///< at most this many of those moves
  int valence_plateau_rounds = 40;  ///< rounds of moves that keep the valence energy (irregular nodes wander until
                                    ///< they meet one they cancel with), each followed by the improving moves
};

/// The all-quad patch. Its first in.nodes.size() nodes are the given nodes, in order (all of them used), then
/// the interior ones; curve edges are tagged by role. Throws MeshingError when the parity rule above does not
/// hold or when a curve crosses another (the triangulation could not keep a constrained edge).
QuadMesh mesh_patch(const PatchInput& in, const PatchOptions& options);

}  // namespace polysquare
