// The untangler opens folded quads by moving free nodes only, and leaves a mesh without folds as it is.
#include <gtest/gtest.h>

#include <cmath>

#include "polysquare/core/geometry.h"
#include "polysquare/smooth/smooth.h"
#include "polysquare/smooth/untangle.h"

using namespace polysquare;

namespace {
// An nx x ny grid of quads `stretch` wide and 1 high (ny = nx when not given); nodes on its border are not movable.
QuadMesh grid(int nx, std::vector<std::uint8_t>& movable, int ny = -1, double stretch = 1.0) {
  if (ny < 0) ny = nx;
  QuadMesh m;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) {
      m.nodes.push_back({stretch * i, double(j)});
      const bool border = i == 0 || j == 0 || i == nx || j == ny;
      m.node_kind.push_back(border ? NodeKind::boundary : NodeKind::interior);
      movable.push_back(border ? 0 : 1);
    }
  auto id = [&](int i, int j) { return static_cast<std::int32_t>(j * (nx + 1) + i); };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) m.quads.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
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

namespace {
std::size_t below(const QuadMesh& m, double t) {
  std::size_t n = 0;
  for (const auto& q : m.quads) n += quad_min_sj(m.nodes[q[0]], m.nodes[q[1]], m.nodes[q[2]], m.nodes[q[3]]) < t;
  return n;
}
// A 16 x 10 grid of quads 20 times longer than wide (a map's cells along a long thin subregion), its middle row
// of nodes pressed to 0.05 above the row below, then its interior nodes thrown up to 0.3 of a cell each way (a
// reproducible linear congruential stream): many quads folded at once, next to each other, as a snap past its
// limits leaves them.
QuadMesh scrambled_grid(unsigned seed, std::vector<std::uint8_t>& movable) {
  const int nx = 16, ny = 10;
  const double stretch = 20.0, jitter = 0.3;
  QuadMesh m = grid(nx, movable, ny, stretch);
  unsigned x = seed * 2654435761u + 12345u;
  auto uniform = [&] {
    x = x * 1664525u + 1013904223u;
    return static_cast<double>(x >> 8) / static_cast<double>(1u << 24) * 2.0 - 1.0;
  };
  for (std::size_t v = 0; v < m.nodes.size(); ++v) {
    if (!movable[v]) continue;
    if (static_cast<int>(v) / (nx + 1) == ny / 2) m.nodes[v].y = ny / 2 - 1 + 0.05;
    m.nodes[v] = m.nodes[v] + Vec2{jitter * stretch * uniform(), jitter * uniform()};
  }
  return m;
}
}  // namespace

// Lifting the worst corner around a node may fold another of its quads; the tangle must shrink, never spread:
// on delta_water at 40 m the untangler once turned 837 quads below the target into 3,508 (on these grids it made
// a quarter of them worse).
TEST(Untangle, ATangleNeverSpreads) {
  std::size_t tangled = 0, left = 0;
  for (unsigned seed = 0; seed < 100; ++seed) {
    std::vector<std::uint8_t> movable;
    QuadMesh m = scrambled_grid(seed, movable);
    const double t = UntangleOptions{}.target_sj;
    const std::size_t before = below(m, t);
    const UntangleStats st = untangle_quads(m, movable, UntangleOptions{});
    EXPECT_EQ(st.folded_before, before) << "seed " << seed;
    EXPECT_EQ(st.folded_after, below(m, t)) << "seed " << seed;
    EXPECT_LE(st.folded_after, before) << "seed " << seed;
    tangled += before;
    left += st.folded_after;
  }
  EXPECT_GT(tangled, 1000u);
  EXPECT_LT(left, tangled / 4);  // it still opens most of what it is given
}

// The guarded smoothing (untangler, averaging, pattern search) never leaves more folded quads than it found.
TEST(Smooth, FoldedQuadsNeverMultiply) {
  std::size_t tangled = 0, left = 0;
  for (unsigned seed = 0; seed < 50; ++seed) {
    std::vector<std::uint8_t> movable;
    QuadMesh m = scrambled_grid(seed, movable);
    const std::size_t before = below(m, 1e-300);
    smooth_quads(m, SmoothOptions{}, nullptr);
    const std::size_t after = below(m, 1e-300);
    EXPECT_LE(after, before) << "seed " << seed;
    tangled += before;
    left += after;
  }
  EXPECT_GT(tangled, 500u);
  EXPECT_LT(left, tangled / 4);
}

// With a node mask, only the flagged nodes move: the pipeline smooths again only near the quads a local patch or a
// valence move changed, and the rest of the part must keep the positions its first smoothing gave it.
TEST(Smooth, OnlyTheFlaggedNodesMove) {
  std::vector<std::uint8_t> movable;
  QuadMesh m = grid(8, movable);
  // Every interior node pushed off the grid; those in the left half (i < 4) are flagged.
  for (std::size_t v = 0; v < m.nodes.size(); ++v)
    if (movable[v]) m.nodes[v] = m.nodes[v] + Vec2{0.3 * std::sin(1.7 * double(v)), 0.3 * std::cos(2.3 * double(v))};
  std::vector<std::uint8_t> only(m.nodes.size(), 0);
  for (std::size_t v = 0; v < m.nodes.size(); ++v) only[v] = v % 9 < 4;
  const QuadMesh before = m;
  const SmoothStats st = smooth_quads(m, SmoothOptions{}, nullptr, &only);
  std::size_t flagged_moved = 0;
  for (std::size_t v = 0; v < m.nodes.size(); ++v) {
    if (!only[v] || !movable[v]) {
      EXPECT_EQ(m.nodes[v].x, before.nodes[v].x) << "node " << v;
      EXPECT_EQ(m.nodes[v].y, before.nodes[v].y) << "node " << v;
    } else {
      flagged_moved += !(m.nodes[v] == before.nodes[v]);
    }
  }
  EXPECT_GT(st.moves, 0u);
  EXPECT_GE(flagged_moved, 10u);  // of the 21 flagged interior nodes
  // The flagged half got better where the mask let it: its worst corner rose.
  auto worst_in_left = [](const QuadMesh& g) {
    double w = 1.0;
    for (std::size_t q = 0; q < g.quads.size(); ++q)
      if (q % 8 < 3) w = std::min(w, quad_min_sj(g.nodes[g.quads[q][0]], g.nodes[g.quads[q][1]], g.nodes[g.quads[q][2]], g.nodes[g.quads[q][3]]));
    return w;
  };
  EXPECT_GT(worst_in_left(m), worst_in_left(before));
}
