// Stage 1 (input, optional): simplification of curves far finer than the target size (coastlines), keeping the
// topology: no ring or curve may come to cross or touch another, and shared vertices are kept.
#pragma once

#include <cstddef>

#include "polysquare/core/region.h"

namespace polysquare {

struct SimplifyOptions {
  double min_area = 0.0;  ///< Visvalingam-Whyatt: vertices whose triangle with their neighbours has an area below
                          ///< this are removed, smallest first (region units squared); 0 disables
  double max_distance = 0.0;  ///< a removal is skipped when an input vertex it replaces would lie farther than
                              ///< this from the new segment (region units); 0 = no bound
  double max_segment = 0.0;   ///< a removal is skipped when the new segment would be longer than this (region
                              ///< units): curves are coarsened to the target size, never beyond it, so smooth
                              ///< arcs keep turning gently; 0 = no bound. A vertex closer than a tenth of it
                              ///< to a neighbour is removed all the same (the shortcut is then at most 1.1 times
                              ///< this): two mesh nodes that close leave an edge ratio no mesh can avoid
};

struct SimplifyStats {
  std::size_t vertices_before = 0, vertices_after = 0;
  std::size_t refused = 0;  ///< removals refused because the shortcut would cross or cover other geometry
  double max_distance = 0.0;  ///< largest distance of a removed vertex from the simplified curve (region units)
};

/// Simplifies every ring and feature curve in place. Ring vertices where a feature ends, feature end points,
/// and enough vertices to keep each ring a triangle are never removed. A removal is refused when the new
/// segment would cross or touch another segment, or when the removed triangle would cover another vertex.
SimplifyStats simplify_region(Region& region, const SimplifyOptions& options);

}  // namespace polysquare
