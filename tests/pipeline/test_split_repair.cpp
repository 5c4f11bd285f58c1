// Local repair by splitting (paper Sec. 5.3) and the partition clean-up that keeps subregions simple loops.
#include <gtest/gtest.h>

#include <map>
#include <numeric>
#include <set>

#include "polysquare/input/read_region.h"
#include "polysquare/partition/partition.h"
#include "polysquare/pipeline/invariants.h"
#include "polysquare/pipeline/mesh_region.h"
#include "polysquare/quality/quality.h"

using namespace polysquare;

namespace {

// A grid of n x n unit cells, each cut into two triangles; cell (i, j) holds triangles 2 (j n + i) and +1.
TriMesh grid(int n) {
  TriMesh m;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) m.vertices.push_back({static_cast<double>(i), static_cast<double>(j)});
  auto v = [&](int i, int j) { return static_cast<std::int32_t>(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      m.triangles.push_back({v(i, j), v(i + 1, j), v(i + 1, j + 1)});
      m.triangles.push_back({v(i, j), v(i + 1, j + 1), v(i, j + 1)});
    }
  return m;
}

// Fans of each part around each vertex (triangles joined through the edges at the vertex they share).
std::size_t most_fans(const TriMesh& m, const std::vector<std::int32_t>& part) {
  std::size_t worst = 0;
  for (std::size_t v = 0; v < m.vertices.size(); ++v) {
    std::vector<std::int32_t> around;
    for (std::size_t t = 0; t < m.triangles.size(); ++t)
      for (std::int32_t w : m.triangles[t])
        if (w == static_cast<std::int32_t>(v)) around.push_back(static_cast<std::int32_t>(t));
    std::vector<int> root(around.size());
    std::iota(root.begin(), root.end(), 0);
    auto find = [&](int a) { while (root[a] != a) a = root[a]; return a; };
    for (std::size_t a = 0; a < around.size(); ++a)
      for (std::size_t b = a + 1; b < around.size(); ++b) {
        if (part[around[a]] != part[around[b]]) continue;
        int shared = 0;
        for (std::int32_t x : m.triangles[around[a]])
          for (std::int32_t y : m.triangles[around[b]]) shared += x == y;
        if (shared == 2) root[find(static_cast<int>(a))] = find(static_cast<int>(b));
      }
    std::map<std::int32_t, std::set<int>> fans;
    for (std::size_t a = 0; a < around.size(); ++a) fans[part[around[a]]].insert(find(static_cast<int>(a)));
    for (const auto& [p, f] : fans) worst = std::max(worst, f.size());
  }
  return worst;
}

}  // namespace

TEST(SplitRepair, PinchedPartsMeetEveryVertexInOneFan) {
  // 4 x 4 cells; part 0 is the cells (1,1) and (2,2), which meet only at the vertex (2,2), joined by a path of
  // cells round the outside; part 1 is cell (2,1), part 2 the rest. Part 0 touches itself at (2,2).
  const TriMesh m = grid(4);
  std::vector<std::int32_t> part(m.triangles.size(), 2);
  auto set_cell = [&](int i, int j, std::int32_t p) { part[2 * (j * 4 + i)] = part[2 * (j * 4 + i) + 1] = p; };
  for (auto [i, j] : std::vector<std::pair<int, int>>{{1, 1}, {2, 2}, {3, 2}, {3, 1}, {3, 0}, {2, 0}, {1, 0}}) set_cell(i, j, 0);
  set_cell(2, 1, 1);
  ASSERT_EQ(most_fans(m, part), 2u);
  const std::size_t moved = separate_pinched_parts(m, part);
  EXPECT_GT(moved, 0u);
  EXPECT_EQ(most_fans(m, part), 1u);
  EXPECT_GT(std::count(part.begin(), part.end(), 0), 0);
}

TEST(SplitRepair, SubregionsThatFailAloneAreSplitIntoPiecesThatMap) {
  // estuary (GSHHG) at 400 m: some subregions of the automatic partition cannot be mapped alone; their pieces
  // after a k-way split can, and the mesh holds every invariant.
  const Region region = read_region(std::string(POLYSQUARE_DATA_DIR) + "/cases/estuary.geojson");
  MeshOptions o;
  o.size.h = 400.0;  // automatic subregion counts
  const MeshResult r = mesh_region(region, o);
  EXPECT_TRUE(check_invariants(r.mesh).ok()) << check_invariants(r.mesh).first_problem;
  int split = 0, mapped = 0;
  for (const auto& part : r.report.candidates)
    for (const auto& c : part)
      if (c.split.has_value()) {
        split += c.split->subregions_split;
        mapped += c.split->pieces_mapped;
      }
  EXPECT_GT(split, 0);
  EXPECT_GT(mapped, 0);
  // Splitting loses no more than a little structure (since the elastic joint quantization the unsplit mesh of this
  // case is as structured; since zigzags are smoothed, 0.9905 split against 0.9939 unsplit).
  MeshOptions no_split = o;
  no_split.map.split_rounds = 0;
  no_split.map.joint_split_rounds = 0;
  const MeshResult u = mesh_region(region, no_split);
  const double unsplit = u.report.summary.structured_fraction;
  EXPECT_GE(r.report.summary.structured_fraction, unsplit - 0.01);
  // Splitting only what fails in the joint map (counts a snap cannot reach) runs, and never loses structure
  // (since local patches repair poor quads in place, the unsplit mesh of this case is already 0.99 structured).
  MeshOptions joint_only = no_split;
  joint_only.map.joint_split_rounds = 2;
  const MeshResult j = mesh_region(region, joint_only);
  EXPECT_GE(j.report.summary.structured_fraction, unsplit - 0.01);
  int joint = 0;
  for (const auto& part : j.report.candidates)
    for (const auto& c : part)
      if (c.split.has_value()) joint += c.split->after_joint_map;
  EXPECT_GT(joint, 0);
}
