// Graded PPM's transition rows (map/transition_rows.h): a coarse row along an interface replaced by fans onto
// the finer side's nodes, checked on a small grid where every count is known.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>

#include "map/transition_rows.h"
#include "polysquare/core/error.h"

namespace polysquare {
namespace {

// cols x rows unit squares, counter-clockwise; the top line y = rows is the interface.
QuadMesh grid(int cols, int rows) {
  QuadMesh m;
  for (int j = 0; j <= rows; ++j)
    for (int i = 0; i <= cols; ++i) m.nodes.push_back({double(i), double(j)});
  m.node_kind.assign(m.nodes.size(), NodeKind::interior);
  auto at = [&](int i, int j) { return j * (cols + 1) + i; };
  for (int j = 0; j < rows; ++j)
    for (int i = 0; i < cols; ++i) m.quads.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)});
  return m;
}

double signed_area(const QuadMesh& m, const std::array<std::int32_t, 4>& q) {
  double a = 0.0;
  for (int k = 0; k < 4; ++k) a += cross(m.nodes[q[k]], m.nodes[q[(k + 1) % 4]]);
  return 0.5 * a;
}

std::vector<Vec2> top_nodes(int edges, double width, double y) {
  std::vector<Vec2> top;
  for (int i = 0; i <= edges; ++i) top.push_back({width * i / edges, y});
  return top;
}

TEST(TransitionRows, FansJoinTwoCountsOfOneInterface) {
  for (int fine : {5, 7, 9}) {
    QuadMesh m = grid(3, 2);
    std::size_t side_nodes = m.nodes.size();
    std::vector<std::uint8_t> in_row(m.quads.size(), 0);
    const std::vector<Vec2> line{{0, 2}, {3, 2}}, top = top_nodes(fine, 3.0, 2.0);
    replace_with_transition_row(m, side_nodes, in_row, line, top, std::vector<NodeKind>(top.size(), NodeKind::interior), 1e-9);
    const int fans = (fine - 3) / 2;
    EXPECT_EQ(m.quads.size(), 6u - 3u + 3u + static_cast<std::size_t>(fans)) << fine;
    EXPECT_EQ(m.nodes.size(), 12u - 2u + static_cast<std::size_t>(fine - 1));
    EXPECT_EQ(side_nodes, m.nodes.size());  // every node was a side node here
    double area = 0.0;
    for (const auto& q : m.quads) {
      EXPECT_GT(signed_area(m, q), 0.0);  // counter-clockwise kept, no fold
      area += signed_area(m, q);
    }
    EXPECT_NEAR(area, 6.0, 1e-12);
    // Every edge of the mesh is used once (on its border) or twice; the top line holds exactly the fine nodes.
    std::map<std::pair<int, int>, int> uses;
    for (const auto& q : m.quads)
      for (int k = 0; k < 4; ++k) ++uses[{std::min(q[k], q[(k + 1) % 4]), std::max(q[k], q[(k + 1) % 4])}];
    int top_edges = 0;
    for (const auto& [e, n] : uses) {
      EXPECT_LE(n, 2);
      if (m.nodes[e.first].y == 2.0 && m.nodes[e.second].y == 2.0) {
        ++top_edges;
        EXPECT_EQ(n, 1);
      }
    }
    EXPECT_EQ(top_edges, fine);
    EXPECT_EQ(nodes_along(m, side_nodes, line, 1e-9).size(), static_cast<std::size_t>(fine + 1));
    // A second row may not take the same quads again.
    EXPECT_THROW(replace_with_transition_row(m, side_nodes, in_row, line, top_nodes(fine + 2, 3.0, 2.0),
                                             std::vector<NodeKind>(fine + 3, NodeKind::interior), 1e-9),
                 MeshingError);
  }
}

TEST(TransitionRows, RefusesCountsARowCannotJoin) {
  const std::vector<Vec2> line{{0, 2}, {3, 2}};
  for (int fine : {3, 4, 6, 2}) {  // equal, odd differences, fewer
    QuadMesh m = grid(3, 2);
    std::size_t side_nodes = m.nodes.size();
    std::vector<std::uint8_t> in_row(m.quads.size(), 0);
    const std::vector<Vec2> top = top_nodes(fine, 3.0, 2.0);
    EXPECT_THROW(replace_with_transition_row(m, side_nodes, in_row, line, top,
                                             std::vector<NodeKind>(top.size(), NodeKind::interior), 1e-9),
                 MeshingError) << fine;
    EXPECT_EQ(m.quads.size(), 6u);  // left as it was
  }
}

TEST(TransitionRows, TwoRowsMeetAtACornerQuad) {
  // A 4 x 4 grid with a row onto 6 nodes along its top, then one onto 6 along its right side, traversed either
  // way: the corner quad is the top row's, so the right row leaves it out (its node at (4, 3) slides up onto the
  // finer side's (4, 10/3)) and fans the other three edges onto five.
  for (const bool upwards : {true, false}) {
    QuadMesh m = grid(4, 4);
    std::size_t side_nodes = m.nodes.size();
    std::vector<std::uint8_t> in_row(m.quads.size(), 0);
    const std::vector<Vec2> top_line{{0, 4}, {4, 4}}, top = top_nodes(6, 4.0, 4.0);
    replace_with_transition_row(m, side_nodes, in_row, top_line, top, std::vector<NodeKind>(7, NodeKind::interior), 1e-9);
    std::vector<Vec2> right_line{{4, 0}, {4, 4}}, right;
    for (int i = 0; i <= 6; ++i) right.push_back({4.0, 4.0 * i / 6});
    if (!upwards) {
      std::reverse(right_line.begin(), right_line.end());
      std::reverse(right.begin(), right.end());
    }
    replace_with_transition_row(m, side_nodes, in_row, right_line, right, std::vector<NodeKind>(7, NodeKind::interior), 1e-9);
    double area = 0.0;
    for (const auto& q : m.quads) {
      EXPECT_GT(signed_area(m, q), 0.0) << upwards;
      area += signed_area(m, q);
    }
    EXPECT_NEAR(area, 16.0, 1e-12);
    std::map<std::pair<int, int>, int> uses;
    for (const auto& q : m.quads)
      for (int k = 0; k < 4; ++k) ++uses[{std::min(q[k], q[(k + 1) % 4]), std::max(q[k], q[(k + 1) % 4])}];
    int top_edges = 0, right_edges = 0;
    for (const auto& [e, n] : uses) {
      EXPECT_LE(n, 2);
      if (m.nodes[e.first].y == 4.0 && m.nodes[e.second].y == 4.0) ++top_edges;
      if (m.nodes[e.first].x == 4.0 && m.nodes[e.second].x == 4.0) ++right_edges;
    }
    EXPECT_EQ(top_edges, 6);
    EXPECT_EQ(right_edges, 6);
    EXPECT_EQ(nodes_along(m, side_nodes, {{4, 0}, {4, 4}}, 1e-9).size(), 7u);
  }
}

}  // namespace
}  // namespace polysquare
