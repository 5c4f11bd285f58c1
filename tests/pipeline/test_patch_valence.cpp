// Topological clean-up of unstructured quads (fallback/patch_valence.h, refine/relax_valences.h): moves that lower
// the valence energy.
#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "fallback/patch_valence.h"
#include "polysquare/core/geometry.h"
#include "polysquare/refine/relax_valences.h"

using namespace polysquare;

namespace {
// An n x n grid of unit quads; the boundary nodes come first (counter-clockwise from (0, 0)), then the interior
// ones, so that the given nodes are exactly the boundary.
QuadMesh grid(int n, std::size_t& given) {
  QuadMesh m;
  std::vector<std::int32_t> id((n + 1) * (n + 1), -1);
  auto at = [&](int i, int j) -> std::int32_t& { return id[static_cast<std::size_t>(j * (n + 1) + i)]; };
  auto add = [&](int i, int j) {
    at(i, j) = static_cast<std::int32_t>(m.nodes.size());
    m.nodes.push_back({static_cast<double>(i), static_cast<double>(j)});
    m.node_kind.push_back(NodeKind::interior);
  };
  for (int i = 0; i < n; ++i) add(i, 0);
  for (int j = 0; j < n; ++j) add(n, j);
  for (int i = n; i > 0; --i) add(i, n);
  for (int j = n; j > 0; --j) add(0, j);
  given = m.nodes.size();
  for (int j = 1; j < n; ++j)
    for (int i = 1; i < n; ++i) add(i, j);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) m.quads.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)});
  return m;
}

std::vector<int> valences(const QuadMesh& m) {
  std::vector<int> v(m.nodes.size(), 0);
  for (const auto& q : m.quads)
    for (auto x : q) v[static_cast<std::size_t>(x)]++;
  return v;
}
}  // namespace

TEST(PatchValence, AnEdgeTurnedInAGridIsTurnedBack) {
  std::size_t given = 0;
  QuadMesh m = grid(4, given);
  const QuadMesh regular = m;
  // Quads 5 = (1,1)-(2,2) and 6 = (2,1)-(3,2) share the vertical edge x = 2; turning it to another diagonal of
  // their hexagon leaves two nodes of 3 quads and two of 5.
  const auto q1 = m.quads[5], q2 = m.quads[6];  // q1 = (a0, b, c, a1), q2 = (b, d, e, c): shared edge b-c
  m.quads[5] = {q1[0], q1[1], q2[1], q1[3]};
  m.quads[6] = {q2[1], q2[2], q2[3], q1[3]};
  const std::vector<int> turned = valences(m);
  EXPECT_EQ(std::count(turned.begin() + static_cast<std::ptrdiff_t>(given), turned.end(), 4), 5);

  const patch_valence::Moves moves = patch_valence::relax_valences(m, given, {}, 1000, 0);
  EXPECT_GT(moves.energy_before, 3.9);
  EXPECT_NEAR(moves.energy_after, 0.0, 1e-9);
  EXPECT_GE(moves.flips, 1u);
  const std::vector<int> after = valences(m);
  for (std::size_t v = given; v < after.size(); ++v) EXPECT_EQ(after[v], 4) << "node " << v;
  // The given nodes are where they were, and the quads cover the square once.
  for (std::size_t v = 0; v < given; ++v) EXPECT_EQ(m.nodes[v], regular.nodes[v]);
  double area = 0;
  for (const auto& q : m.quads) area += 0.5 * cross(m.nodes[q[2]] - m.nodes[q[0]], m.nodes[q[3]] - m.nodes[q[1]]);
  EXPECT_NEAR(area, 16.0, 1e-9);
}

TEST(PatchValence, TwoNodesOfThreeQuadsAcrossAQuadAreMerged) {
  // A quad inserted into a grid by splitting a node (its two opposite corners of 3 quads each): collapsing it
  // along that diagonal merges them into one node of 4 quads.
  std::size_t given = 0;
  QuadMesh m = grid(4, given);
  // Split the centre node c = (2, 2): its left quads keep c, its right ones take a new node c2, and the quad
  // (c, down, c2, up) opens between them, with `down` = (2, 1) and `up` = (2, 3).
  auto find = [&](double x, double y) {
    for (std::size_t v = 0; v < m.nodes.size(); ++v)
      if (m.nodes[v].x == x && m.nodes[v].y == y) return static_cast<std::int32_t>(v);
    return -1;
  };
  const std::int32_t c = find(2, 2), down = find(2, 1), up = find(2, 3);
  const auto c2 = static_cast<std::int32_t>(m.nodes.size());
  m.nodes.push_back({2.2, 2.0});
  m.node_kind.push_back(NodeKind::interior);
  m.nodes[static_cast<std::size_t>(c)] = {1.8, 2.0};
  for (auto& q : m.quads) {
    double cx = 0;
    for (auto v : q) cx += 0.25 * m.nodes[static_cast<std::size_t>(v)].x;
    if (cx > 2.0)
      for (auto& v : q)
        if (v == c) v = c2;
  }
  m.quads.push_back({c, down, c2, up});
  const std::vector<int> split = valences(m);
  ASSERT_EQ(split[static_cast<std::size_t>(c)], 3);
  ASSERT_EQ(split[static_cast<std::size_t>(c2)], 3);

  const patch_valence::Moves moves = patch_valence::relax_valences(m, given, {}, 1000, 0);
  EXPECT_EQ(moves.collapses, 1u);
  EXPECT_NEAR(moves.energy_after, 0.0, 1e-9);
  EXPECT_EQ(m.quads.size(), 16u);
  const std::vector<int> after = valences(m);
  for (std::size_t v = given; v < after.size(); ++v)
    if (after[v] > 0) EXPECT_EQ(after[v], 4) << "node " << v;
}

TEST(PatchValence, KeptEdgesAreNeverTurned) {
  std::size_t given = 0;
  QuadMesh m = grid(4, given);
  const auto q1 = m.quads[5], q2 = m.quads[6];
  m.quads[5] = {q1[0], q1[1], q2[1], q1[3]};
  m.quads[6] = {q2[1], q2[2], q2[3], q1[3]};
  const QuadMesh turned = m;
  // The edge the repair would turn is one to keep (a feature curve's, say): every other move makes the energy
  // no lower than this arrangement allows, and that edge is still there.
  const std::int32_t a = q1[3], b = q2[1];
  const patch_valence::Moves moves = patch_valence::relax_valences(m, given, {{a, b}}, 1000, 0);
  EXPECT_GT(moves.energy_after, 0.0);
  bool kept = false;
  for (const auto& q : m.quads)
    for (int k = 0; k < 4; ++k) kept = kept || (std::minmax(q[k], q[(k + 1) % 4]) == std::minmax(a, b));
  EXPECT_TRUE(kept);
}

TEST(RelaxValences, AFlaggedRegionIsMadeRegularAcrossItsSeamAndTheRestStays) {
  // A 6 x 6 grid whose 2 x 2 centre (x and y in [2, 4]) is flagged unstructured, with the edge x = 3, y in [2, 3]
  // turned: two nodes on the flagged region's border get 5 quads (their quads outside count), one on the
  // border and the centre get 3. Only the flagged quads may change; the result is a regular grid again.
  std::size_t given = 0;
  QuadMesh m = grid(6, given);
  m.node_kind.assign(m.nodes.size(), NodeKind::interior);
  for (std::size_t v = 0; v < given; ++v) m.node_kind[v] = NodeKind::boundary;
  m.quad_part.resize(m.quads.size());
  for (std::size_t q = 0; q < m.quads.size(); ++q) m.quad_part[q] = static_cast<std::int32_t>(q);
  std::vector<std::uint8_t> region(m.quads.size(), 0);
  for (int j = 2; j < 4; ++j)
    for (int i = 2; i < 4; ++i) region[static_cast<std::size_t>(j * 6 + i)] = 1;
  const auto q1 = m.quads[2 * 6 + 2], q2 = m.quads[2 * 6 + 3];  // (a0, b, c, a1) and (b, d, e, c)
  m.quads[2 * 6 + 2] = {q1[0], q1[1], q2[1], q1[3]};
  m.quads[2 * 6 + 3] = {q2[1], q2[2], q2[3], q1[3]};
  const QuadMesh turned = m;
  auto interior_irregular = [](const QuadMesh& x) {
    const std::vector<int> v = valences(x);
    std::size_t n = 0;
    for (std::size_t i = 0; i < v.size(); ++i) n += x.node_kind[i] == NodeKind::interior && v[i] != 4;
    return n;
  };
  ASSERT_EQ(interior_irregular(turned), 4u);

  std::vector<std::size_t> origin;
  const RelaxValencesStats st = relax_region_valences(m, region, RelaxValencesOptions{}, SmoothOptions{}, origin);
  EXPECT_TRUE(st.kept);
  EXPECT_EQ(st.region_quads, 4u);
  EXPECT_LT(st.energy_after, st.energy_before);
  EXPECT_EQ(interior_irregular(m), 0u);
  ASSERT_EQ(origin.size(), m.quads.size());
  // Quads outside the region come first, as they were; each quad carries the per-quad data of its origin.
  for (std::size_t q = 0; q < m.quads.size(); ++q) {
    EXPECT_EQ(m.quad_part[q], static_cast<std::int32_t>(origin[q]));
    if (region[origin[q]]) continue;
    for (int k = 0; k < 4; ++k) EXPECT_EQ(m.nodes[m.quads[q][k]], turned.nodes[turned.quads[origin[q]][k]]);
  }
  double area = 0;
  for (const auto& q : m.quads) area += 0.5 * cross(m.nodes[q[2]] - m.nodes[q[0]], m.nodes[q[3]] - m.nodes[q[1]]);
  EXPECT_NEAR(area, 36.0, 1e-9);
  for (const auto& q : m.quads)
    EXPECT_GT(quad_min_sj(m.nodes[q[0]], m.nodes[q[1]], m.nodes[q[2]], m.nodes[q[3]]), 0.5);
}

TEST(RelaxValences, NothingFlaggedChangesNothing) {
  std::size_t given = 0;
  QuadMesh m = grid(3, given);
  m.node_kind.assign(m.nodes.size(), NodeKind::interior);
  const QuadMesh was = m;
  std::vector<std::size_t> origin;
  const RelaxValencesStats st = relax_region_valences(m, std::vector<std::uint8_t>(m.quads.size(), 0),
                                                      RelaxValencesOptions{}, SmoothOptions{}, origin);
  EXPECT_FALSE(st.kept);
  EXPECT_TRUE(origin.empty());
  EXPECT_EQ(m.quads, was.quads);
  EXPECT_EQ(m.nodes.size(), was.nodes.size());
}
