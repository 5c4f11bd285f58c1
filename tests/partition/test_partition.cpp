// Feature-aware partitioning (FPPM Sec. 3): energy terms on hand-checked graphs, balance, connectivity,
// feature attraction over METIS alone, determinism.
#include <gtest/gtest.h>

#include <cmath>
#include <deque>
#include <map>
#include <numbers>

#include "polysquare/input/read_region.h"
#include "polysquare/partition/partition.h"

using namespace polysquare;

namespace {
// 2 x 2 unit squares, each split by its (i,j)-(i+1,j+1) diagonal: 8 triangles, vertex (i,j) = 3j + i.
TriMesh grid2x2() {
  TriMesh m;
  for (int j = 0; j <= 2; ++j)
    for (int i = 0; i <= 2; ++i) m.vertices.push_back({double(i), double(j)});
  for (int j = 0; j < 2; ++j)
    for (int i = 0; i < 2; ++i) {
      const int a = 3 * j + i, b = a + 1, c = a + 4, d = a + 3;
      m.triangles.push_back({a, b, c});  // lower right of the diagonal a-c
      m.triangles.push_back({a, c, d});  // upper left
    }
  return m;
}
const double kMeanEdge = (12.0 + 4.0 * std::sqrt(2.0)) / 16.0;

TriMesh triangulated(const std::string& name, double size) {
  const Region r = read_region(std::string(POLYSQUARE_DATA_DIR) + "/cases/" + name + ".geojson");
  TriangulationOptions o;
  o.boundary_edge = o.max_edge = size;
  return triangulate_part(r, split_into_parts(r)[0], o);
}

std::size_t components_of(const TriMesh& m, const std::vector<std::int32_t>& part, int p) {
  // Triangles sharing an edge and a part are connected.
  std::map<std::pair<int, int>, std::vector<int>> by_edge;
  for (std::size_t t = 0; t < m.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      int a = m.triangles[t][k], b = m.triangles[t][(k + 1) % 3];
      by_edge[{std::min(a, b), std::max(a, b)}].push_back(static_cast<int>(t));
    }
  std::vector<std::vector<int>> adj(m.triangles.size());
  for (const auto& [e, ts] : by_edge)
    if (ts.size() == 2) { adj[ts[0]].push_back(ts[1]); adj[ts[1]].push_back(ts[0]); }
  std::vector<char> seen(m.triangles.size(), 0);
  std::size_t comps = 0;
  for (std::size_t s = 0; s < m.triangles.size(); ++s) {
    if (seen[s] || part[s] != p) continue;
    ++comps;
    std::deque<int> q{static_cast<int>(s)};
    seen[s] = 1;
    while (!q.empty()) {
      const int t = q.front();
      q.pop_front();
      for (int n : adj[t])
        if (!seen[n] && part[n] == p) { seen[n] = 1; q.push_back(n); }
    }
  }
  return comps;
}
}  // namespace

TEST(PartitionEnergy, StraightSeparatorMeetingTheBoundaryAtRightAngles) {
  const TriMesh m = grid2x2();
  // Left column (x < 1) against right column: separator x = 1, two unit edges, straight, 90 degrees at the border.
  const std::vector<std::int32_t> part{0, 0, 1, 1, 0, 0, 1, 1};
  const PartitionEnergy e = partition_energy(m, part, PartitionOptions{});
  EXPECT_NEAR(e.separator_length, 2.0 / kMeanEdge * 100.0, 1e-9);
  EXPECT_NEAR(e.angle_deviation, 0.0, 1e-9);
  EXPECT_NEAR(e.feature_on_separators, 0.0, 1e-12);
}

TEST(PartitionEnergy, DiagonalSeparatorPaysFortyFiveDegreesAtBothEnds) {
  const TriMesh m = grid2x2();
  // Lower-right triangles against upper-left ones: separator along the diagonal (0,0)-(2,2).
  const std::vector<std::int32_t> part{0, 1, 0, 1, 0, 1, 0, 1};
  // Only the two triangles next to the diagonal in squares (0,0) and (1,1) matter; others share parts across
  // square edges, so their edges are separators too. Make it exact: squares off the diagonal go to one side.
  const std::vector<std::int32_t> diag{0, 1, 0, 0, 1, 1, 0, 1};
  const PartitionEnergy e = partition_energy(m, diag, PartitionOptions{});
  EXPECT_NEAR(e.separator_length, 2.0 * std::sqrt(2.0) / kMeanEdge * 100.0, 1e-9);
  // 45 degrees to each of the two boundary edges at (0,0) and at (2,2); straight at (1,1).
  EXPECT_NEAR(e.angle_deviation, 4.0 * (std::numbers::pi / 4) * 100.0, 1e-9);
  EXPECT_GT(partition_energy(m, part, PartitionOptions{}).separator_length, e.separator_length);
}

TEST(PartitionEnergy, FeatureEdgesOnSeparatorsCount) {
  TriMesh m = grid2x2();
  m.chains.push_back({TriChain::Kind::feature, 0, false, {1, 4, 7}, {1, 0, 1}});  // the line x = 1
  const std::vector<std::int32_t> part{0, 0, 1, 1, 0, 0, 1, 1};
  PartitionOptions o;
  const PartitionEnergy e = partition_energy(m, part, o);
  EXPECT_NEAR(e.feature_on_separators, e.separator_length, 1e-9);
  EXPECT_NEAR(e.energy, e.separator_length + o.lambda_angle * e.angle_deviation - o.lambda_feature * e.feature_on_separators, 1e-9);
}

class PartitionCases : public ::testing::TestWithParam<std::tuple<const char*, double, int>> {};

TEST_P(PartitionCases, BalancedConnectedDeterministic) {
  const auto [name, size, k] = GetParam();
  const TriMesh m = triangulated(name, size);
  PartitionOptions o;
  o.parts = k;
  const PartitionResult r = partition_triangles(m, o);
  ASSERT_EQ(r.triangle_part.size(), m.triangles.size());
  EXPECT_EQ(r.parts, k);
  EXPECT_LE(r.balance_max_over_avg, 1.0 + o.balance + 0.05) << name << " k=" << k;
  for (int p = 0; p < k; ++p) EXPECT_EQ(components_of(m, r.triangle_part, p), 1u) << name << " part " << p;
  EXPECT_LE(r.final.energy, r.metis.energy + 1e-9);  // the best state seen is kept
  EXPECT_EQ(partition_triangles(m, o).triangle_part, r.triangle_part);
}

INSTANTIATE_TEST_SUITE_P(Cases, PartitionCases,
                         ::testing::Combine(::testing::Values("rect_feature", "square_feature", "turtle_shell"),
                                            ::testing::Values(4.0), ::testing::Values(2, 4, 8)));

TEST(Partition, MetropolisHastingsLowersEnergyAndAttractsSeparatorsToFeatures) {
  // On rect_feature the feature lies at 35-40 % of the width: a 2-way cut through it breaks the 10 % balance
  // constraint, so the attraction is checked where the balance allows it (README reports rect_feature too).
  for (const char* name : {"turtle_shell", "square_feature"}) {
    const TriMesh m = triangulated(name, 4.0);
    PartitionOptions o;
    o.parts = 4;
    const PartitionResult r = partition_triangles(m, o);
    EXPECT_LT(r.final.energy, r.metis.energy) << name;
    EXPECT_GT(r.feature_fraction_final, r.feature_fraction_metis) << name;
    EXPECT_GT(r.mh_accepted, 0u);
  }
}
