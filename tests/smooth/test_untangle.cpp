// The untangler opens folded quads by moving free nodes only, and leaves a mesh without folds as it is.
#include <gtest/gtest.h>

#include "polysquare/core/geometry.h"
#include "polysquare/smooth/untangle.h"

using namespace polysquare;

namespace {
// An n x n grid of unit quads; nodes on its border are not movable.
QuadMesh grid(int n, std::vector<std::uint8_t>& movable) {
  QuadMesh m;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      m.nodes.push_back({double(i), double(j)});
      const bool border = i == 0 || j == 0 || i == n || j == n;
      m.node_kind.push_back(border ? NodeKind::boundary : NodeKind::interior);
      movable.push_back(border ? 0 : 1);
    }
  auto id = [&](int i, int j) { return static_cast<std::int32_t>(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) m.quads.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
  return m;
}
double worst_sj(const QuadMesh& m) {
  double w = 1.0;
  for (const auto& q : m.quads) w = std::min(w, quad_min_sj(m.nodes[q[0]], m.nodes[q[1]], m.nodes[q[2]], m.nodes[q[3]]));
  return w;
}
}  // namespace

TEST(Untangle, FoldedGridIsOpenedAndItsBorderStays) {
  std::vector<std::uint8_t> movable;
  QuadMesh m = grid(5, movable);
  // Two interior nodes thrown across their neighbours, one past the border's first row of nodes.
  m.nodes[7] = {3.6, 2.7};
  m.nodes[15] = {0.4, 1.9};
  m.nodes[26] = {2.2, 2.1};
  const std::vector<Vec2> before = m.nodes;
  ASSERT_LE(worst_sj(m), 0.0);
  const UntangleStats st = untangle_quads(m, movable, UntangleOptions{});
  EXPECT_GT(st.folded_before, 0u);
  EXPECT_EQ(st.folded_after, 0u);
  EXPECT_GT(worst_sj(m), UntangleOptions{}.target_sj);
  for (std::size_t v = 0; v < m.nodes.size(); ++v)
    if (!movable[v]) EXPECT_EQ(m.nodes[v], before[v]) << v;
}

TEST(Untangle, NothingMovesWithoutAFold) {
  std::vector<std::uint8_t> movable;
  QuadMesh m = grid(4, movable);
  m.nodes[6] = {1.3, 0.8};  // skewed, not folded
  const std::vector<Vec2> before = m.nodes;
  const UntangleStats st = untangle_quads(m, movable, UntangleOptions{});
  EXPECT_EQ(st.folded_before, 0u);
  EXPECT_EQ(st.moves, 0u);
  EXPECT_EQ(m.nodes, before);
}

TEST(Untangle, AFoldNoFreeNodeCanOpenStays) {
  // A quad folded at a node whose only neighbours are fixed: the untangler reports it, and moves nothing fixed.
  std::vector<std::uint8_t> movable;
  QuadMesh m = grid(2, movable);
  m.nodes[4] = {0.1, 0.1};  // the one interior node, pushed towards a fixed corner
  movable[4] = 0;
  ASSERT_LE(worst_sj(m), UntangleOptions{}.target_sj);
  const UntangleStats st = untangle_quads(m, movable, UntangleOptions{});
  EXPECT_EQ(st.folded_after, st.folded_before);
  EXPECT_EQ(m.nodes[4], (Vec2{0.1, 0.1}));
}
