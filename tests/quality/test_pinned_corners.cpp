// Quads pinned by sharp input corners: an acute corner between two input curves at an input corner node is what
// the input dictates, and only such quads are left out of the quality gates.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "polysquare/quality/quality.h"

using namespace polysquare;

namespace {
// One quad with a corner of `deg` degrees at node 0 (edges 0-1 and 3-0 along the boundary), and a square beside it.
QuadMesh wedge(double deg) {
  const double a = deg * std::numbers::pi / 180.0;
  QuadMesh m;
  m.nodes = {{0, 0}, {2, 0}, {2 + std::cos(a), std::sin(a)}, {2 * std::cos(a), 2 * std::sin(a)}, {3, 0}};
  m.quads = {{0, 1, 2, 3}};
  m.node_kind = {NodeKind::corner, NodeKind::boundary, NodeKind::interior, NodeKind::boundary, NodeKind::boundary};
  m.boundary_edges = {{0, 1}, {3, 0}};
  m.boundary_edge_ring = {0, 0};
  return m;
}
}  // namespace

TEST(PinnedCorners, OnlyAcuteInputCornersBetweenTwoCurvesBelowTheGate) {
  QuadMesh m = wedge(10.0);  // sin 10 deg = 0.17
  EXPECT_EQ(quads_pinned_by_sharp_input(m, 0.2), std::vector<std::uint8_t>{1});
  EXPECT_EQ(quads_pinned_by_sharp_input(m, 0.1), std::vector<std::uint8_t>{0});  // above the gate anyway
  m.node_kind[0] = NodeKind::boundary;  // a corner the mesher made, not the input
  EXPECT_EQ(quads_pinned_by_sharp_input(m, 0.2), std::vector<std::uint8_t>{0});
  m = wedge(10.0);
  m.boundary_edges.pop_back();  // one side is not on a curve: another quad could share the angle
  m.boundary_edge_ring.pop_back();
  EXPECT_EQ(quads_pinned_by_sharp_input(m, 0.2), std::vector<std::uint8_t>{0});
  m = wedge(170.0);  // obtuse and flat: sin 170 deg = 0.17, but two quads could split it
  EXPECT_EQ(quads_pinned_by_sharp_input(m, 0.2), std::vector<std::uint8_t>{0});
}

TEST(PinnedCorners, QuadsInsideAThinWedgeWithinReachOfItsTip) {
  // Two curves leave node 0 three degrees apart (a river meeting a shoreline); a strip of quads spans the gap,
  // and one quad lies outside the wedge, below the first curve.
  const double a = 3.0 * std::numbers::pi / 180.0;
  QuadMesh m;
  m.nodes.push_back({0, 0});
  m.node_kind.push_back(NodeKind::corner);
  for (int i = 1; i <= 6; ++i) {
    m.nodes.push_back({static_cast<double>(i), 0.0});                   // a_i = node 2i - 1
    m.nodes.push_back({i * std::cos(a), i * std::sin(a)});              // b_i = node 2i
    m.node_kind.insert(m.node_kind.end(), {NodeKind::feature, NodeKind::boundary});
  }
  auto A = [](int i) { return 2 * i - 1; };
  auto B = [](int i) { return 2 * i; };
  m.nodes.push_back({1.03, 0.027});  // beyond the chord a1 b1: the tip quad is convex
  m.node_kind.push_back(NodeKind::interior);
  const std::int32_t c = static_cast<std::int32_t>(m.nodes.size()) - 1;
  m.quads.push_back({0, A(1), c, B(1)});
  for (int i = 1; i < 6; ++i) m.quads.push_back({A(i), A(i + 1), B(i + 1), B(i)});
  m.nodes.push_back({0.2, -1});
  m.nodes.push_back({1, -1});
  m.node_kind.insert(m.node_kind.end(), {NodeKind::interior, NodeKind::interior});
  m.quads.push_back({0, c + 1, c + 2, A(1)});
  m.feature_edges.push_back({0, A(1)});
  m.boundary_edges.push_back({0, B(1)});
  for (int i = 1; i < 6; ++i) {
    m.feature_edges.push_back({A(i), A(i + 1)});
    m.boundary_edges.push_back({B(i), B(i + 1)});
  }
  m.feature_edge_curve.assign(m.feature_edges.size(), 0);
  m.boundary_edge_ring.assign(m.boundary_edges.size(), 0);
  // Without reach only the tip quad (its 3-degree corner); with reach 3 also the strip quads centred at x = 1.5
  // and 2.5; never the quad outside the wedge, nor any when the wedge is wider than asin(below).
  EXPECT_EQ(quads_pinned_by_sharp_input(m, 0.2), (std::vector<std::uint8_t>{1, 0, 0, 0, 0, 0, 0}));
  EXPECT_EQ(quads_pinned_by_sharp_input(m, 0.2, 3.0), (std::vector<std::uint8_t>{1, 1, 1, 0, 0, 0, 0}));
  EXPECT_EQ(quads_pinned_by_sharp_input(m, 0.02, 3.0), (std::vector<std::uint8_t>(7, 0)));
}
