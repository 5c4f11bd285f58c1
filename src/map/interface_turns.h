// PPM interfaces: the corners the two sides of an interface make where it turns.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
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

/// One mapped subregion as agree_feature_interface_turns sees it (null layout: not mapped).
struct InterfaceSide {
  Layout* layout = nullptr;
  const TriMesh* mesh = nullptr;
  const std::vector<Vec2>* deformed = nullptr;       ///< the deformed vertices its layout was built from
  const std::vector<std::int32_t>* global_vertex = nullptr;  ///< #mesh vertices: shared vertex, or -1
  std::string name;
};

/// Where a feature curve is the interface of two mapped subregions, each labels it alone, and at a break point
/// where one side turns and the other goes straight the node gets three or five quads (most interior singular
/// nodes of a coast's maps). Along each such interface, mismatches of opposite sign are paired like brackets
/// (the nearest first) and one side's labels between the two are turned a quarter: that side's corner moves
/// to, or cancels with, the other's, and every turn inside the stretch and the loop's total turn stay. Of the
/// two sides, the one left with fewer corners is changed (then the shorter stretch); a stretch longer than
/// `max_length` deformed elements is left alone. Returns the number of pairs agreed (the changed layouts' sides
/// are rebuilt).
std::size_t agree_feature_interface_turns(std::vector<InterfaceSide>& sides, double max_length);

}  // namespace polysquare
