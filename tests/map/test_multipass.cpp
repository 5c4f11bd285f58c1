// The multi-pass PPM deformation (paper Algorithm 1, map/multipass.h) on partitioned real cases: charts deform
// without inverting a triangle of the part, every subregion's ring pieces end closer to the axes of its own frame,
// the result does not depend on the thread count, and the pipeline's meshes from it keep the invariants.
#include <gtest/gtest.h>

#include <oneapi/tbb/global_control.h>

#include <cmath>
#include <set>

#include "polysquare/input/read_region.h"
#include "polysquare/map/multipass.h"
#include "polysquare/map/polysquare_map.h"
#include "polysquare/partition/partition.h"
#include "polysquare/pipeline/invariants.h"
#include "polysquare/pipeline/mesh_region.h"
#include "polysquare/quality/quality.h"

using namespace polysquare;

namespace {

Region load(const std::string& name) { return read_region(std::string(POLYSQUARE_DATA_DIR) + "/cases/" + name + ".geojson"); }

struct Partitioned {
  TriMesh tri;
  std::vector<std::int32_t> triangle_part;
  int parts = 0;
};

Partitioned partitioned(const char* name, double h, int k) {
  const Region region = load(name);
  TriangulationOptions t;
  t.boundary_edge = h;
  t.max_edge = 4 * h;
  Partitioned p;
  p.tri = triangulate_part(region, split_into_parts(region).front(), t);
  PartitionOptions po;
  po.parts = k;
  const PartitionResult r = partition_triangles(p.tri, po);
  p.triangle_part = r.triangle_part;
  p.parts = r.parts;
  return p;
}

// Over every subregion, the ring edges' distance from the axes of the subregion's best frame (eq. 11's energy,
// sum of len * (1 - cos 4 phi) / 8 at its optimal rotation).
double ring_misalignment(const Partitioned& p, const std::vector<Vec2>& x) {
  const auto owners = edge_owners(p.tri);
  double total = 0.0;
  for (int s = 0; s < p.parts; ++s) {
    std::vector<std::array<std::int32_t, 2>> ring;
    for (const auto& [key, o] : owners)
      if (o[1] < 0 && p.triangle_part[static_cast<std::size_t>(o[0])] == s) {
        const auto& t = p.tri.triangles[static_cast<std::size_t>(o[0])];
        for (int k = 0; k < 3; ++k)
          if (edge_key(t[k], t[(k + 1) % 3]) == key) ring.push_back({t[k], t[(k + 1) % 3]});
      }
    const double theta = preorientation_angle(x, ring);
    for (const auto& e : ring) {
      const Vec2 d = x[static_cast<std::size_t>(e[1])] - x[static_cast<std::size_t>(e[0])];
      const double phi = std::atan2(d.y, d.x) + theta;
      total += norm(d) * (1.0 - std::cos(4.0 * phi)) / 8.0;
    }
  }
  return total;
}

}  // namespace

TEST(Multipass, ChartsAlignEverySubregionsRingsWithoutInvertingTheirTriangles) {
  const double h = 2.0;
  const Partitioned p = partitioned("letter_M", h, 6);
  MultipassOptions o;
  o.max_passes = 4;
  MultipassStats st;
  const std::vector<Vec2> x = multipass_deform(p.tri, p.triangle_part, p.parts, h, o, DeformOptions{}, st);
  ASSERT_EQ(x.size(), p.tri.vertices.size());
  EXPECT_GE(st.colours, 2);  // neighbours' charts overlap: one colour cannot hold them all
  EXPECT_GE(st.passes, 1);
  EXPECT_GT(min_signed_area(p.tri.triangles, x), 0.0);
  std::vector<Vec2> start(p.tri.vertices.size());
  for (std::size_t v = 0; v < start.size(); ++v) start[v] = (1.0 / h) * p.tri.vertices[v];
  // letter_M's rings are axis-parallel but for its slanted strokes: those must come much closer to the axes.
  const double before = ring_misalignment(p, start), after = ring_misalignment(p, x);
  EXPECT_GT(before, 1.0);
  EXPECT_LT(after, 0.5 * before);
}

TEST(Multipass, IndependentOfTheThreadCount) {
  const Partitioned p = partitioned("pentagon", 3.0, 5);
  MultipassOptions o;
  o.max_passes = 3;
  auto run = [&](int threads) {
    oneapi::tbb::global_control limit(oneapi::tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
    MultipassStats st;
    return multipass_deform(p.tri, p.triangle_part, p.parts, 3.0, o, DeformOptions{}, st);
  };
  const std::vector<Vec2> a = run(1), b = run(2);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) ASSERT_TRUE(a[i] == b[i]) << i;
}

TEST(Multipass, MeshesFromItKeepTheInvariants) {
  MeshOptions o;
  o.size.h = 2.0;
  o.subregions.parts = 8;
  o.map.multipass.max_passes = 4;
  const MeshResult r = mesh_region(load("letter_M"), o);
  const std::set<std::int32_t> used(r.mesh.quad_part.begin(), r.mesh.quad_part.end());
  EXPECT_EQ(used.size(), 8u);  // the requested partition was kept
  const InvariantReport inv = check_invariants(r.mesh);
  EXPECT_TRUE(inv.ok()) << inv.first_problem;
  const QualityReport q = compute_quality(r.mesh);
  EXPECT_GT(q.sj.min, 0.2);
  ASSERT_EQ(r.parts.size(), 1u);
  EXPECT_GE(r.parts[0].multipass.passes, 1);
  for (const SubregionStats& s : r.parts[0].subregions) EXPECT_TRUE(s.mapped) << s.subregion << ": " << s.reason;
}
