// Named groups of a mesh for the writers: the domain surfaces, the boundary (rings split into named segments) and
// the feature curves, with the names the input gave (`name` attributes) and generated names where it gave none.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "polysquare/core/quad_mesh.h"
#include "polysquare/core/region.h"

namespace polysquare {

/// Quads of one named domain (a physical surface).
struct SurfaceGroup {
  std::string name;                  ///< the domain's `name`, or "domain" when the input names none
  int tag = 1;                       ///< physical tag
  std::vector<std::int32_t> quads;   ///< quad indices
};

/// A named set of mesh edges along the boundary or a feature (a physical curve, a gr3 boundary, a nodestring).
struct CurveGroup {
  std::string name;
  int tag = 0;                       ///< physical tag
  std::string kind;                  ///< boundary: "open", "land" or the input's kind; features: the input's kind
  int ring = -1;                     ///< boundary groups: the ring (rest-of-ring groups and segments); -1 features
  bool segment = false;              ///< a named boundary segment (BoundarySegment); false: the rest of a ring
  bool island = false;               ///< the whole rim of a hole (no segment on it): a closed island boundary
  /// Boundary groups: node chains along the boundary with the domain on their left (for a ring without segments
  /// one closed chain, its first node repeated at the end). Empty for feature groups.
  std::vector<std::vector<std::int32_t>> chains;
  std::vector<std::array<std::int32_t, 2>> edges;  ///< every edge of the group
};

struct MeshGroups {
  std::vector<SurfaceGroup> surfaces;   ///< one per distinct domain name, first tag 1
  std::vector<CurveGroup> rings;        ///< one per ring the mesh has, in ring order: the part of the ring that
                                        ///< no segment covers, named "boundary_ring_<r>", kind "land" (may be empty)
  std::vector<CurveGroup> features;     ///< one per distinct feature name (curves of one name merged), in order of
                                        ///< their first curve; unnamed curves "feature_<c>"
  std::vector<CurveGroup> segments;     ///< one per distinct segment name (segments of one name merged), in input
                                        ///< order; unnamed ones "segment_<s>"
  std::vector<std::string> warnings;    ///< e.g. a segment end point that is not a mesh node (nearest node used)
  bool empty() const { return surfaces.empty(); }
};

/// Groups of `mesh` with the names of `region` (the region it conforms to: MeshResult::region). Tags: the first
/// surface 1, rings 2, 3, ... in ring order, then the feature groups, then the segment groups, then the other
/// surfaces; so the tags of rings and features do not depend on segments, names or the MSH feature mode, and a
/// region without names or segments gets the groups and tags polysquare always wrote. Without a region, every
/// ring and curve gets its generated name. A segment end point is found as the node of its ring's boundary loop
/// at that position (the nearest one, with a warning, when none is exactly there); the segment is the loop from
/// its start node forward to its end node.
MeshGroups mesh_groups(const QuadMesh& mesh, const Region* region = nullptr);

/// The name of boundary segment `s`'s group: its `name`, or "segment_<s>" when the input gives none (segments of
/// one name are one group).
std::string segment_group_name(const Region& region, std::size_t s);

/// The names of the open boundary groups (kind "open": a segment group's kind is its first segment's), in the
/// order mesh_groups lists them; before meshing, so that their companion files (.pli) can be checked.
std::vector<std::string> open_segment_names(const Region& region);

/// One line for the CLI, "  groups: channel (1), 1 boundary ring(s) (2), dam_lower (3), inflow (5, open)\n":
/// domains, named features and segments with their tags, the rings (hundreds on a coast) as a tag range.
std::string format_groups_text(const MeshGroups& groups);

}  // namespace polysquare
