// Stage 1 (input): feature curves cut at their crossings with each other and with the boundary, and clipped to
// the domain, so that afterwards curves meet each other and the boundary only at their end points.
#pragma once

#include <string>
#include <vector>

#include "polysquare/core/region.h"

namespace polysquare {

struct FeatureSplitOptions {
  double snap_relative = 1e-9;  ///< crossings closer than this (times the bounding-box diagonal) to an existing
                                ///< vertex use that vertex, so near-touching curves share one node
  bool clip_holes = false;      ///< drop pieces inside holes; otherwise a curve crossing a hole is an InputError
};

struct FeatureSplitStats {
  std::size_t crossings = 0;       ///< feature-feature and feature-boundary meeting points found
  std::size_t ring_vertices_added = 0;
  std::size_t pieces_dropped = 0;  ///< pieces outside the domain, inside a hole, or lying along the boundary
  std::size_t pieces_in_holes = 0; ///< of those, pieces inside a hole (clip_holes)
  std::size_t stretches_along_boundary = 0;  ///< stretches of a curve within the snap distance of a ring, left to
                                             ///< the ring (their neighbouring stretches are kept, ends on the ring)
  std::vector<std::string> warnings;  ///< one sentence per dropped stretch along the boundary, naming the file,
                                      ///< the feature and its two ends
};

/// Splits every feature curve at its crossings (the crossing point is computed once and inserted into both
/// curves, and into the ring when the other curve is a ring), drops pieces outside the domain, inside holes or
/// along the boundary, and keeps source_feature, name, kind and size on every piece; a closed curve with a size
/// is first added to region.size_areas, so its inside keeps the size after the cuts. Pieces are judged segment by segment: a stretch
/// of segments whose midpoints lie within the snap distance of a ring runs along the boundary and is dropped
/// (with a warning), and a stretch of the same curve that then leaves the boundary is kept, its end moved onto
/// the ring (inserted there as a vertex), so a curve that starts along the boundary is not lost whole. Rings must already be valid (validate_region).
/// Throws InputError naming the file, the feature and a coordinate when a feature has no piece in the domain.
FeatureSplitStats split_features(Region& region, const FeatureSplitOptions& options = {});

}  // namespace polysquare
