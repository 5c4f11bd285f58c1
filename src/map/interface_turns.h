// PPM interfaces: the corners the two sides of an interface make where it turns.
#pragma once

#include <cstddef>
#include <optional>
#include <vector>

#include "polysquare/map/layout.h"
#include "polysquare/map/quantize.h"

namespace polysquare {

/// A break point where both sides of an interface make a convex corner: segments `segment_a` -> `segment_a_next`
/// of layout `a` and the two coupled segments of layout `b` meet there.
struct ConvexOnBothSides {
  std::size_t a = 0, b = 0;
  int segment_a_next = 0;  ///< the segment of layout a that starts at the corner
};

/// Where an interface turns at a break point both sides share, one side's corner must be convex and the other's
/// reflex (or both sides straight): two convex corners would make the two cells there share two sides (a node of
/// valence 2), which no snap or smoothing mends. Returns the first such corner over `layouts` (null entries are
/// left out), judging convexity by each loop's orientation (the sign of its total turn).
std::optional<ConvexOnBothSides> convex_on_both_sides(const std::vector<const Layout*>& layouts,
                                                      const std::vector<SegmentCoupling>& couplings);

}  // namespace polysquare
