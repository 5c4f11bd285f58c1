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

namespace {

// A 4 x 4 square above (a) or below (b) the x axis, its side on the axis a feature interface with the other one
// through vertices at x = 0 .. 4, the rest of its loop a ring piece. `interface_labels`: the labels of its four
// interface edges in its own direction of travel; breaks at every vertex but the middle one (x = 2).
struct Side {
  TriMesh mesh;
  std::vector<Vec2> deformed;
  std::vector<std::int32_t> global;
  Layout layout;
};

Side square_side(bool above, const std::vector<int>& interface_labels) {
  Side s;
  const double y = above ? 4.0 : -4.0;
  for (int i = 0; i <= 4; ++i) s.mesh.vertices.push_back({above ? double(i) : double(4 - i), 0.0});
  s.mesh.vertices.push_back({above ? 4.0 : 0.0, y});
  s.mesh.vertices.push_back({above ? 0.0 : 4.0, y});
  TriChain interface;
  interface.kind = TriChain::Kind::feature;
  interface.interface = above ? 1 : 0;
  interface.vertices = {0, 1, 2, 3, 4};
  TriChain ring;
  ring.vertices = {4, 5, 6, 0};
  s.mesh.chains = {interface, ring};
  s.mesh.loops = {{0, 1}};
  s.deformed = s.mesh.vertices;
  for (int i = 0; i <= 4; ++i) s.global.push_back(above ? i : 4 - i);
  s.global.push_back(-1);
  s.global.push_back(-1);
  // Counter-clockwise: a goes +X along the axis, then +Y, -X, -Y; b -X along it, then -Y, +X, +Y.
  s.layout.chain_labels = {interface_labels, above ? std::vector<int>{1, 2, 3} : std::vector<int>{3, 0, 1}};
  s.layout.break_vertex = {0, 1, 3, 4, 5, 6};
  s.layout.break_is_corner.assign(6, 0);
  add_straight_breaks(s.layout, s.mesh, s.deformed, std::vector<std::uint8_t>(7, 0), above ? "a" : "b");
  return s;
}

int quads_at(const Side& s, int x) {  // quads the side's layout puts at the interface vertex at x (1, 2 or 3)
  std::int32_t v = -1;
  for (std::size_t i = 0; i < s.global.size(); ++i)
    if (s.global[i] == x) v = static_cast<std::int32_t>(i);
  const std::int32_t b = s.layout.vertex_break[static_cast<std::size_t>(v)];
  int in = -1, out = -1;
  for (std::size_t k = 0; k < s.layout.segments.size(); ++k) {
    if (s.layout.segments[k].break_b == b) in = s.layout.segments[k].label;
    if (s.layout.segments[k].break_a == b) out = s.layout.segments[k].label;
  }
  const int turn = ((out - in) % 4 + 4) % 4;  // both loops counter-clockwise: a left turn is convex
  return turn == 0 ? 2 : turn == 1 ? 1 : 3;
}

}  // namespace

TEST(InterfaceTurns, OneSidedTurnsOnAFeatureInterfaceAreAgreedPairwise) {
  // a steps up at x = 1 (convex) and back at x = 3 (reflex); b goes straight through both: nodes of 3 and 5 quads.
  Side a = square_side(true, {0, 1, 1, 0});
  Side b = square_side(false, {2, 2, 2, 2});
  ASSERT_EQ(quads_at(a, 1) + quads_at(b, 1), 3);
  ASSERT_EQ(quads_at(a, 3) + quads_at(b, 3), 5);
  auto sides_of = [](Side& a, Side& b) {
    return std::vector<InterfaceSide>{{&a.layout, &a.mesh, &a.deformed, &a.global, "a"},
                                      {&b.layout, &b.mesh, &b.deformed, &b.global, "b"}};
  };
  // A stretch longer than allowed is left alone.
  std::vector<InterfaceSide> sides = sides_of(a, b);
  EXPECT_EQ(agree_feature_interface_turns(sides, 1.5), 0u);
  EXPECT_EQ(quads_at(a, 1) + quads_at(b, 1), 3);
  // Within reach: of flattening a's step (4 corners left) and raising one on b (6), a's step goes.
  sides = sides_of(a, b);
  EXPECT_EQ(agree_feature_interface_turns(sides, 4.0), 1u);
  EXPECT_EQ(quads_at(a, 1), 2);
  EXPECT_EQ(quads_at(a, 3), 2);
  EXPECT_EQ(quads_at(b, 1), 2);
  EXPECT_EQ(quads_at(b, 3), 2);
  // a's loop still closes: its turns add up to one full left turn.
  int sum = 0;
  for (std::size_t k = 0; k < a.layout.segments.size(); ++k)
    for (std::size_t l = 0; l < a.layout.segments.size(); ++l)
      if (a.layout.segments[l].break_a == a.layout.segments[k].break_b) {
        const int t = ((a.layout.segments[l].label - a.layout.segments[k].label) % 4 + 4) % 4;
        sum += t == 1 ? 1 : t == 3 ? -1 : 0;
      }
  EXPECT_EQ(sum, 4);
}
