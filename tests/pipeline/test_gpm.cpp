// Global Poly-square Map over a feature-aware partition (paper Sec. 5.1): separators are chains of the one
// global map, so the subregions' meshes are conforming by construction.
#include <gtest/gtest.h>

#include <set>

#include "polysquare/input/read_region.h"
#include "polysquare/pipeline/invariants.h"
#include "polysquare/pipeline/mesh_region.h"
#include "polysquare/quality/quality.h"

using namespace polysquare;

namespace {
MeshResult gpm(const char* name, double size, int parts, int threads = 0) {
  MeshOptions o;
  o.size.h = size;
  o.subregions.parts = parts;
  o.run.threads = threads;
  o.run.keep_partition = true;
  o.map.composition = MapComposition::gpm;
  o.refine.enabled = false;  // these tests are about the map: the corner template would add interior nodes,
  o.local_patch.mend_below_sj = 0.0;  // and so would local patches mending valid quads
  return mesh_region(read_region(std::string(POLYSQUARE_DATA_DIR) + "/cases/" + name + ".geojson"), o);
}
}  // namespace

class GpmCase : public ::testing::TestWithParam<std::tuple<const char*, double, int>> {};

TEST_P(GpmCase, SubregionsAreStitchedConformingly) {
  const auto [name, size, parts] = GetParam();
  const MeshResult r = gpm(name, size, parts);
  const InvariantReport inv = check_invariants(r.mesh);
  EXPECT_TRUE(inv.ok()) << inv.first_problem;
  const QualityReport q = compute_quality(r.mesh);
  EXPECT_EQ(q.interior_singularities, 0u);  // GPM keeps every singularity on the boundary
  EXPECT_EQ(q.non_manifold_edges, 0u);
  // Every subregion has quads, and separators are not reported as user features.
  const std::set<std::int32_t> used(r.mesh.quad_part.begin(), r.mesh.quad_part.end());
  EXPECT_EQ(used.size(), static_cast<std::size_t>(parts)) << name;
  const Region region = read_region(std::string(POLYSQUARE_DATA_DIR) + "/cases/" + name + ".geojson");
  EXPECT_LT(domain_distance(r.mesh, r.region).feature_node_max_distance, 1e-9 * region.bounding_box().diagonal());
  ASSERT_EQ(r.background_part.size(), r.background.triangles.size());
  EXPECT_EQ(r.report.partition.size(), 1u);
}

INSTANTIATE_TEST_SUITE_P(Cases, GpmCase,
                         ::testing::Values(std::make_tuple("pentagon", 3.0, 4), std::make_tuple("letter_R", 2.0, 4),
                                           std::make_tuple("rect_feature", 3.0, 2), std::make_tuple("dam_channel", 2.0, 2)));

TEST(Gpm, IndependentOfTheThreadCount) {
  const QuadMesh a = gpm("pentagon", 3.0, 4, 1).mesh, b = gpm("pentagon", 3.0, 4, 2).mesh;
  ASSERT_EQ(a.quads, b.quads);
  ASSERT_EQ(a.quad_part, b.quad_part);
  for (std::size_t i = 0; i < a.nodes.size(); ++i) ASSERT_TRUE(a.nodes[i] == b.nodes[i]);
}

TEST(Gpm, FailedPartitionFallsBackToOnePolySquareAndSaysSo) {
  // key's 2-way partition leaves a subregion that cannot close as a poly-square in the global frame.
  const MeshResult r = gpm("key", 2.0, 2);
  EXPECT_TRUE(check_invariants(r.mesh).ok());
  // The report lists both candidates of part 0: the failed 2-way GPM with its error, then the kept fallback.
  const auto& tried = r.report.candidates[0];
  ASSERT_EQ(tried.size(), 2u);
  EXPECT_EQ(tried[0].subregions, 2);
  EXPECT_NE(tried[0].error.value_or("").find("key"), std::string::npos);
  EXPECT_EQ(tried[1].subregions, 1);
  EXPECT_TRUE(tried[1].chosen);
  EXPECT_EQ(std::set<std::int32_t>(r.mesh.quad_part.begin(), r.mesh.quad_part.end()).size(), 1u);
}
