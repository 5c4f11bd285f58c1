// Feature-aware partitioning (FPPM Sec. 3): energy terms on hand-checked graphs, balance, connectivity,
// feature attraction over METIS alone, determinism.
#include <gtest/gtest.h>

#include <cmath>
#include <deque>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <set>
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

namespace {
// Feature faces computed here independently of the library: components of triangles joined across non-feature
// edges, then a face enclosed by one other face (no ring edge, one neighbour) joins it, repeatedly.
struct Faces {
  std::vector<int> raw;         // raw component of each triangle
  std::vector<double> raw_area;
  std::vector<char> raw_ring;   // the component has a ring edge
  std::vector<int> merged;      // face of each raw component after the enclosed ones joined their neighbour
  int count = 0;                // faces after merging
};

Faces faces_of(const TriMesh& m) {
  std::map<std::pair<int, int>, std::vector<int>> by_edge;
  for (std::size_t t = 0; t < m.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const int a = m.triangles[t][k], b = m.triangles[t][(k + 1) % 3];
      by_edge[{std::min(a, b), std::max(a, b)}].push_back(static_cast<int>(t));
    }
  std::set<std::pair<int, int>> feature;
  for (const TriChain& ch : m.chains) {
    if (ch.kind != TriChain::Kind::feature) continue;
    const std::size_t n = ch.vertices.size();
    for (std::size_t i = 0; i + (ch.closed ? 0 : 1) < n; ++i) {
      const int a = ch.vertices[i], b = ch.vertices[(i + 1) % n];
      feature.insert({std::min(a, b), std::max(a, b)});
    }
  }
  Faces f;
  const std::size_t nt = m.triangles.size();
  std::vector<std::vector<int>> adj(nt);
  std::vector<std::pair<int, int>> feature_pairs;
  std::vector<int> ring_tris;
  for (const auto& [e, ts] : by_edge) {
    if (ts.size() == 1) ring_tris.push_back(ts[0]);
    else if (feature.count(e)) feature_pairs.push_back({ts[0], ts[1]});
    else { adj[ts[0]].push_back(ts[1]); adj[ts[1]].push_back(ts[0]); }
  }
  f.raw.assign(nt, -1);
  for (std::size_t s = 0; s < nt; ++s) {
    if (f.raw[s] >= 0) continue;
    const int c = static_cast<int>(f.raw_area.size());
    f.raw_area.push_back(0);
    std::deque<int> q{static_cast<int>(s)};
    f.raw[s] = c;
    while (!q.empty()) {
      const int t = q.front();
      q.pop_front();
      const auto& tr = m.triangles[t];
      f.raw_area[c] += 0.5 * orient2(m.vertices[tr[0]], m.vertices[tr[1]], m.vertices[tr[2]]);
      for (int n : adj[t])
        if (f.raw[n] < 0) { f.raw[n] = c; q.push_back(n); }
    }
  }
  const std::size_t nc = f.raw_area.size();
  f.raw_ring.assign(nc, 0);
  for (int t : ring_tris) f.raw_ring[f.raw[t]] = 1;
  f.merged.resize(nc);
  for (std::size_t c = 0; c < nc; ++c) f.merged[c] = static_cast<int>(c);
  auto root = [&](int c) { while (f.merged[c] != c) c = f.merged[c]; return c; };
  for (bool changed = true; changed;) {
    changed = false;
    std::map<int, std::set<int>> nbs;
    std::set<int> ring;
    for (std::size_t c = 0; c < nc; ++c)
      if (f.raw_ring[c]) ring.insert(root(static_cast<int>(c)));
    for (const auto& [a, b] : feature_pairs) {
      const int ra = root(f.raw[a]), rb = root(f.raw[b]);
      if (ra != rb) { nbs[ra].insert(rb); nbs[rb].insert(ra); }
    }
    for (const auto& [c, set] : nbs)
      if (!ring.count(c) && set.size() == 1 && root(c) == c && root(*set.begin()) == *set.begin()) {
        f.merged[c] = *set.begin();
        changed = true;
        break;  // one at a time: simple, and the order cannot matter for nested loops
      }
  }
  std::map<int, int> number;
  for (std::size_t c = 0; c < nc; ++c) number.emplace(root(static_cast<int>(c)), 0);
  for (auto& [r, id] : number) id = f.count++;
  for (std::size_t c = 0; c < nc; ++c) f.merged[c] = number[root(static_cast<int>(c))];
  return f;
}
}  // namespace

TEST(PartitionFaces, RectFeatureTwoWaysIsTheFeature) {
  // The feature of rect_feature crosses the rectangle: two faces, and with k = 2 each is one part, so the only
  // separator is the feature (METIS alone cannot cut there under the 10 % balance).
  const TriMesh m = triangulated("rect_feature", 4.0);
  PartitionOptions o;
  o.parts = 2;
  const PartitionResult r = partition_triangles(m, o);
  EXPECT_EQ(r.faces, 2);
  EXPECT_EQ(r.parts, 2);
  EXPECT_NEAR(r.feature_fraction_final, 1.0, 1e-12);
  EXPECT_NEAR(r.balance_max_over_avg, 1.0, 1e-12);  // one part per face: each is its face's mean
}

TEST(PartitionFaces, DeltaBoxPartsStayInsideFeatureFaces) {
  // delta_box: shorelines and rivers cross the box and close around islands. Every part lies in one face (an
  // island face, enclosed by one other face, belongs to that face), every face gets a part, deterministic.
  const TriMesh m = triangulated("delta_box", 1500.0);
  const Faces f = faces_of(m);
  ASSERT_GT(f.count, 3);
  for (double min_area : {0.0, 16.0 * 200.0 * 200.0}) {
    PartitionOptions o;
    o.parts = 24;
    o.min_face_area = min_area;
    const PartitionResult r = partition_triangles(m, o);
    ASSERT_EQ(r.triangle_part.size(), m.triangles.size());
    EXPECT_GE(r.parts, std::max(24, r.faces));
    std::map<int, std::set<int>> faces_of_part, parts_of_face;
    std::map<int, std::set<int>> large_ring_faces_of_part;  // raw faces that touch the ring and are >= min_area
    for (std::size_t t = 0; t < m.triangles.size(); ++t) {
      const int p = r.triangle_part[t], c = f.raw[t];
      faces_of_part[p].insert(f.merged[c]);
      parts_of_face[f.merged[c]].insert(p);
      if (f.raw_ring[c] && f.raw_area[c] >= min_area) large_ring_faces_of_part[p].insert(c);
    }
    for (const auto& [p, set] : large_ring_faces_of_part)
      EXPECT_EQ(set.size(), 1u) << "part " << p << " crosses a feature between two faces, min_face_area " << min_area;
    for (int p = 0; p < r.parts; ++p) EXPECT_EQ(components_of(m, r.triangle_part, p), 1u) << "part " << p;
    if (min_area == 0.0) {
      // Only the enclosed faces merge: the faces computed here are exactly the library's.
      EXPECT_EQ(r.faces, f.count);
      for (const auto& [p, set] : faces_of_part) EXPECT_EQ(set.size(), 1u) << "part " << p << " spans faces";
      EXPECT_EQ(static_cast<int>(parts_of_face.size()), f.count);  // every face holds a part
    } else {
      EXPECT_LT(r.faces, f.count);  // slivers between the ring and short shorelines merged
    }
    EXPECT_EQ(partition_triangles(m, o).triangle_part, r.triangle_part);
  }
}

TEST(PartitionPicture, AnEmptyBackgroundGivesABoundedPictureThatSaysSo) {
  // When every part was meshed without a partition the picture had a box from +inf to -inf (height -2^31).
  const std::filesystem::path path = std::filesystem::temp_directory_path() / "polysquare_empty_partition.svg";
  write_partition_svg(path, TriMesh{}, PartitionResult{});
  std::ifstream in(path);
  const std::string svg((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(svg.find("height=\"40\""), std::string::npos) << svg;
  EXPECT_NE(svg.find("no partition"), std::string::npos) << svg;
  std::filesystem::remove(path);
}
