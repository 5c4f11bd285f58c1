// Stage 8 (local repair of a finished quad mesh, paper Sec. 5.3's patch templates applied where distortion is
// high): the quads around a cluster of poor or folded quads are cut out of the mesh and the hole is meshed again
// by an unstructured patch (fallback/patch.h) on exactly the nodes of its boundary loop, so the rest of the
// subregion keeps its mapped quads. Without it, one poor quad next to a sharp coastline vertex turned a whole
// mapped subregion of hundreds of quads into an unstructured patch.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "polysquare/core/quad_mesh.h"
#include "polysquare/size/size_field.h"

namespace polysquare {

struct LocalPatchOptions {
  bool enabled = true;          ///< false: poor quads are left to the coarser repairs (whole subregions as patches)
  double size = 1.0;            ///< target quad edge length h (patch interior vertices follow it)
  std::shared_ptr<const SizeField> size_field;  ///< graded meshes: patch interiors follow this field from `size`
                                                ///< up (PatchOptions::size_field); null = uniform
  int max_rings = 3;            ///< rings of quads grown around a cluster, one at a time, until its patch builds
  /// Rings grown before the first patch is tried: 0 tries the flagged quads alone first (a whole subregion cut
  /// out of a finished mesh), 1 never does (a poor quad's own corners are usually what a patch must move).
  int min_rings = 1;
  /// A region may enclose holes (islands, quads left out) and is then patched with them; false: it grows until
  /// it is a disk.
  bool holes = false;
  /// Feature curves and feature points inside a region are kept as curves and points of its patch (a whole
  /// subregion crossed by a feature); false: the region grows until no feature edge is inside.
  bool inner_features = false;
  std::size_t max_quads = 300;  ///< a region grown past this many quads is left to the caller's coarser repair
  /// Growth goes on while the patch's worst corner (scaled Jacobian, before smoothing) is below this; the best
  /// patch of all rings tried is kept.
  double target_sj = 0.3;
  /// Valid quads that pass the caller's gates but have a corner below this are mended too (flagged 2 in
  /// remesh_poor_quads), a patch kept only where its worst corner beats theirs; 0 = off.
  double mend_below_sj = 0.3;
  /// A second pass for quads still poor after the first pass and smoothing, before their subregion is demoted
  /// to a patch (a patch that builds may still hold a corner under the gate): larger regions, more rings.
  int second_rings = 6;
  std::size_t second_max_quads = 1200;
  /// The last resort for quads still folded when every coarser repair has run (instead of refusing the part):
  /// the same growth, further.
  int wide_rings = 12;
  std::size_t wide_max_quads = 5000;
};

struct LocalPatchStats {
  std::size_t clusters = 0;       ///< clusters of flagged quads (quads sharing a node belong to one)
  std::size_t patched = 0;        ///< clusters whose region was meshed again
  std::size_t quads_removed = 0;  ///< quads cut out of the mesh
  std::size_t quads_added = 0;    ///< patch quads that replaced them
};

/// Meshes again the neighbourhood of every cluster of quads flagged in `poor` (#quads; 1 = poor or folded, 2 = valid,
/// mended only when the patch's worst corner beats the cluster's): the cluster grows by rings
/// of edge-neighbours, never across a feature edge, until it is a disk without feature or boundary edges inside
/// and the patch on its boundary loop builds with no folded quad (the split and the matching construction are
/// both tried, the one with the better worst corner kept). Nodes outside the regions and every tagged edge keep
/// their indices' meaning (nodes are renumbered, tags follow); patch quads take the subregion (quad_part) that
/// held most of their region. `unstructured` (#quads, in/out; empty = none) flags quads made by patches: it is
/// carried as they are (any value) for the quads that stay and set to 1 for the new ones. Deterministic: clusters
/// in quad order.
LocalPatchStats remesh_poor_quads(QuadMesh& mesh, const std::vector<std::uint8_t>& poor, const LocalPatchOptions& options,
                                  std::vector<std::uint8_t>& unstructured);

/// The same for given regions instead of clusters: the quads q with region[q] >= 0 (#quads or shorter) holding
/// one index form one cluster, whatever they touch (a whole subregion cut out of a finished mesh, each apart from
/// its neighbours); clusters in index order. The patch quads take the subregion that held most of their region.
LocalPatchStats remesh_regions(QuadMesh& mesh, const std::vector<std::int32_t>& region, const LocalPatchOptions& options,
                               std::vector<std::uint8_t>& unstructured);

}  // namespace polysquare
