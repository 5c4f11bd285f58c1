// Stage 1 (input): named boundary segments (lines with role "boundary") placed on the rings they lie on.
#pragma once

#include <cstddef>
#include <vector>

#include "polysquare/core/region.h"

namespace polysquare {

/// Places every Region::boundary_segments line on the ring it lies on: every point of the line and the middle of
/// every line segment must be within `tolerance` (region units) of one ring, else InputError naming the file, the
/// input feature and the point farthest from the boundary (a line inside the domain is told to be a feature).
/// The end points are snapped to a ring vertex within `tolerance` or inserted into the ring (projected onto its
/// nearest edge), set as BoundarySegment::start/end in ring order (the arc from start forward along the ring is
/// the one the line covers; a closed line covers the whole ring, start == end) and appended to
/// Region::feature_points, so simplification keeps them and the mesher makes them nodes. Segments of one ring
/// that overlap are an InputError. Rings must be validated and oriented (outer counter-clockwise).
void place_boundary_segments(Region& region, double tolerance);

/// The vertices of `segment` on its ring, in ring order: indices into rings[segment.ring].points from the start
/// vertex forward to the end vertex (both included; the whole ring, start repeated at the end, when start ==
/// end). Empty when an end point is not a vertex of the ring.
std::vector<std::size_t> segment_ring_vertices(const Region& region, const BoundarySegment& segment);

}  // namespace polysquare
