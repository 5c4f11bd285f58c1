// Stage 1 (input): near-coincident points snapped at read time, so that a curve ending a rounding error away
// from the boundary or another curve (typical after reprojection) meets it exactly instead of failing the
// triangulation later.
#pragma once

#include <string>
#include <vector>

#include "polysquare/core/region.h"

namespace polysquare {

struct SnapStats {
  std::size_t to_vertex = 0;    ///< points moved onto an existing vertex
  std::size_t to_segment = 0;   ///< points moved onto a segment (the point is inserted into that ring or curve)
  double largest_move = 0.0;    ///< in region units
};

/// Moves every end point of an open feature curve, and every feature point, that lies within
/// `relative` x (bounding-box diagonal of the rings) of a ring or of another feature curve but not on it: onto
/// the nearest vertex there when one is that close, else onto the nearest point of the nearest segment, which is
/// inserted into that ring or curve so both share the exact coordinate. One sentence per move (naming the file,
/// the feature, the coordinate and the distance) is appended to `notes`.
SnapStats snap_near_coincident(Region& region, double relative, std::vector<std::string>* notes);

}  // namespace polysquare
