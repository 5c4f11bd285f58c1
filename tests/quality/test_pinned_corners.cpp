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
