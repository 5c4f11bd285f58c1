// Stage 6: quad extraction. The quantized poly-square is a union of unit lattice squares; every lattice node is
// mapped back through the inverse of the (piecewise linear) deformation.
#pragma once

#include <string>
#include <vector>

#include "polysquare/core/quad_mesh.h"
#include "polysquare/map/layout.h"
#include "polysquare/triangulate/background_triangulation.h"

namespace polysquare {

/// Builds the quads of one part. `snapped` is the deformation after its boundary and feature vertices were moved
/// onto the quantized poly-square (lattice units); `original` the input coordinates of the same vertices.
/// Nodes on a side of the poly-square are interpolated along the chain, so they lie on the input polyline; break
/// points map exactly to their input vertex. Boundary edges carry their ring index, feature edges their curve
/// index; separator nodes are interior and separator edges untagged. quad_part is the part (from
/// `triangle_part`, #triangles, when given) of the triangle holding the quad's centre. Throws MeshingError
/// naming `part_name` if a lattice node cannot be located in the deformed mesh. `side_nodes`, when given, gets
/// the number of leading nodes that lie on the sides (the rest are interior lattice nodes).
QuadMesh extract_quads(const TriMesh& mesh, const std::vector<Vec2>& original, const std::vector<Vec2>& snapped,
                       const Layout& layout, const std::string& part_name,
                       const std::vector<std::int32_t>* triangle_part = nullptr, std::size_t* side_nodes = nullptr);

/// Target positions of every chain vertex on the quantized poly-square: break points on their lattice point,
/// the vertices between them spread along the side in proportion to their deformed arc length (input arc length
/// on interfaces, so that both subregions sharing one agree).
/// `mask` gets 1 for every vertex that received a target.
void polysquare_targets(const TriMesh& mesh, const std::vector<Vec2>& original, const std::vector<Vec2>& deformed,
                        const Layout& layout, std::vector<Vec2>& targets, std::vector<std::uint8_t>& mask);

/// n + 1 points along the polyline `place` at equal steps of the arc length of `measure` (the same polyline, or
/// its deformed image, vertex for vertex); the first and last are exactly place's ends. The two subregions sharing
/// an interface call it on the same input polyline, so they create the same nodes.
std::vector<Vec2> spread_along(const std::vector<Vec2>& measure, const std::vector<Vec2>& place, long long n);

}  // namespace polysquare
