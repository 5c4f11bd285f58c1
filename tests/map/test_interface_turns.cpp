// The corners the two sides of a PPM interface make where it turns (map/interface_turns.h).
#include <gtest/gtest.h>

#include "map/interface_turns.h"

using namespace polysquare;

namespace {

// A closed loop of segments with these labels (0 +X, 1 +Y, 2 -X, 3 -Y), break point k from segment k-1 to k.
Layout loop_of(const std::vector<int>& labels) {
  Layout l;
  const int n = static_cast<int>(labels.size());
  l.break_vertex.resize(static_cast<std::size_t>(n));
  for (int k = 0; k < n; ++k) {
    l.break_vertex[static_cast<std::size_t>(k)] = k;
    LayoutSegment s;
    s.label = labels[static_cast<std::size_t>(k)];
    s.break_a = k;
    s.break_b = (k + 1) % n;
    s.count = 1;
    l.segments.push_back(s);
  }
  return l;
}

}  // namespace

TEST(InterfaceTurns, TwoConvexCornersOnOneInterfaceCornerAreFound) {
  // Subregion A is a square traversed counter-clockwise; its first two sides (+X then +Y: a convex corner) are an
  // interface with B, which traverses them the other way round as its own first two sides.
  const Layout a = loop_of({0, 1, 2, 3});
  const std::vector<SegmentCoupling> couplings = {{0, 0, 1, 1}, {0, 1, 1, 0}};
  // B a square too: its sides there also turn left, convex on its counter-clockwise loop. No mesh has that.
  const Layout b_square = loop_of({0, 1, 2, 3});
  const auto found = convex_on_both_sides({&a, &b_square}, couplings);
  ASSERT_TRUE(found.has_value());
  EXPECT_EQ(found->a, 0u);
  EXPECT_EQ(found->b, 1u);
  EXPECT_EQ(found->segment_a_next, 1);
  // B an L wrapping round A's corner (-Y then -X there: a right turn, reflex on its counter-clockwise loop): fine.
  const Layout b_l = loop_of({3, 2, 3, 0, 1, 2});
  EXPECT_FALSE(convex_on_both_sides({&a, &b_l}, couplings).has_value());
  // Both sides straight through the break point (A's two sides in line): nothing to judge either.
  const Layout a_straight = loop_of({0, 0, 1, 2, 3});
  const Layout b_straight = loop_of({2, 2, 3, 0, 1});
  EXPECT_FALSE(convex_on_both_sides({&a_straight, &b_straight}, couplings).has_value());
  // A left-out (failed) subregion is not judged.
  EXPECT_FALSE(convex_on_both_sides({&a, nullptr}, couplings).has_value());
}
