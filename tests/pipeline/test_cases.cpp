// The invariants of design.md on the bundled cases this slice supports (one poly-square per part), and the
// quality figures the slice must reach against Gmsh 4.8.4 (data/cases/PROVENANCE.md).
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>

#include <string>

#include "polysquare/core/error.h"
#include "polysquare/input/read_region.h"
#include "polysquare/pipeline/invariants.h"
#include "polysquare/pipeline/mesh_region.h"
#include "polysquare/quality/quality.h"
#include "polysquare/refine/refine.h"

using namespace polysquare;

namespace {

struct Case {
  const char* name;
  double size;
  double sj_floor;  // the figure to reach (Gmsh's SJ min from data/cases/PROVENANCE.md where we meet it; see README otherwise)
  std::size_t gmsh_interior_singularities;  // data/cases/PROVENANCE.md; the issue's bound is a quarter of it
};

Region load(const std::string& name) { return read_region(std::string(POLYSQUARE_DATA_DIR) + "/cases/" + name + ".geojson"); }

MeshResult mesh(const Region& r, double size, int threads = 0) {
  MeshOptions o;
  o.size.h = size;
  o.run.threads = threads;
  return mesh_region(r, o);
}

// One poly-square per part, without the stage 8 templates and without the quality gate: the map's raw corners.
MeshOptions raw_single_map(double size) {
  MeshOptions o;
  o.size.h = size;
  o.subregions.parts = 1;
  o.gates.min_scaled_jacobian = 0.0;
  o.local_patch.mend_below_sj = 0.0;  // the raw map: no local patch mends its valid quads
  o.refine.enabled = false;
  o.curves.simplify = 0.0;  // the input's own curves
  return o;
}

}  // namespace

class SlicedCase : public ::testing::TestWithParam<Case> {};

TEST_P(SlicedCase, HoldsEveryInvariant) {
  const Case c = GetParam();
  const Region region = load(c.name);
  const MeshResult result = mesh(region, c.size);
  const QuadMesh& m = result.mesh;
  // 1-3: all quads, conforming, no inverted element, tags consistent.
  const InvariantReport inv = check_invariants(m);
  EXPECT_TRUE(inv.ok()) << inv.first_problem;
  const QualityReport q = compute_quality(m);
  EXPECT_EQ(q.triangles, 0u);
  EXPECT_EQ(q.inverted, 0u);
  EXPECT_EQ(q.non_manifold_edges, 0u);
  EXPECT_EQ(q.boundary_edges, m.boundary_edges.size());
  // Poly-square maps put singularities on the boundary or where subregions meet: at most a quarter of Gmsh's.
  EXPECT_LE(4 * q.interior_singularities, c.gmsh_interior_singularities) << c.name;
  // 4: boundary fidelity, sharp vertices are nodes, area preserved.
  // against the curves the mesh was made for (simplified to the size), and within h of the input
  const DomainDistance d = domain_distance(m, result.region);
  EXPECT_LT(d.boundary_max_relative, 1e-9);
  EXPECT_LE(domain_distance(m, region).boundary_max_distance, c.size) << c.name;
  EXPECT_EQ(d.sharp_vertices_missing, 0u);
  // Where every input vertex is a node the mesh covers the region exactly; on curved rings the chords between
  // boundary nodes cut the curve, and the report gives the change.
  std::size_t ring_vertices = 0;
  for (const Ring& ring : region.rings) ring_vertices += ring.points.size();
  EXPECT_LT(std::abs(d.area_relative_change), d.sharp_vertices_total == ring_vertices ? 1e-9 : 1e-2);
  // 5: feature nodes on the curves.
  EXPECT_LT(d.feature_node_max_distance, 1e-9 * region.bounding_box().diagonal());
  if (!region.features.empty()) EXPECT_GT(m.feature_edges.size(), 0u);
  // Feature curves lie on mesh edges: no point of a feature polyline farther than 0.1 h from the mesh edges.
  EXPECT_LE(d.feature_max_distance, 0.1 * c.size) << c.name;
  // Gmsh's SJ min, or the quality gate where Gmsh's lies below it (mechanical_part: 0.18), so that the floor can fail.
  EXPECT_GT(q.sj.min, std::max(c.sj_floor, MeshOptions{}.gates.min_scaled_jacobian)) << c.name;
  EXPECT_LT(q.edge_ratio.max, 10.0) << c.name;  // no collapsed edge hiding behind good angles
  // Element size follows the requested size: mean quad area within 40% of h^2.
  double area = 0;
  for (const auto& x : m.quads) area += 0.5 * cross(m.nodes[x[2]] - m.nodes[x[0]], m.nodes[x[3]] - m.nodes[x[1]]);
  EXPECT_NEAR(area / static_cast<double>(m.quads.size()) / (c.size * c.size), 1.0, 0.4) << c.name;
}

INSTANTIATE_TEST_SUITE_P(Cases, SlicedCase,
                         // Gmsh 4.8.4 SJ min and interior singularities from data/cases/PROVENANCE.md (rect_feature has no Gmsh
                         // figure: dam_channel's).
                         ::testing::Values(Case{"letter_I", 2.0, 0.99, 58}, Case{"pentagon", 3.0, 0.70, 100},
                                           Case{"letter_M", 2.0, 0.71, 177}, Case{"square_feature", 3.0, 0.34, 219},
                                           Case{"triangle", 3.0, 0.71, 101},
                                           Case{"dam_channel", 2.0, 0.67, 508}, Case{"rect_feature", 3.0, 0.67, 508},
                                           Case{"mechanical_part", 3.0, 0.18, 319}, Case{"letter_R", 2.0, 0.62, 152},
                                           Case{"key", 2.0, 0.68, 184}, Case{"turtle_shell", 2.5, 0.70, 108},
                                           Case{"smile", 2.5, 0.66, 221}),
                         [](const auto& info) { return std::string(info.param.name); });

// The smoother is what keeps smile's eye loops within tolerance: unbounded, it lengthens the chords next to the
// loops' poly-square corners (a smaller inscribed angle there) and leaves the curve 0.3 h away. (Without the loop
// template, which takes those corners away.)
TEST(Pipeline, FeatureToleranceBoundsTheChordsAlongFeatures) {
  const Region r = load("smile");
  MeshOptions o = raw_single_map(2.5);
  o.gates.feature_tolerance = 0.0;
  auto feature_distance = [&] {
    const MeshResult res = mesh_region(r, o);
    return domain_distance(res.mesh, res.region).feature_max_distance;
  };
  const double loose = feature_distance();
  EXPECT_GT(loose, 0.15 * o.size.h);
  o.gates.feature_tolerance = 0.05;
  const double tight = feature_distance();
  EXPECT_LE(tight, 0.05 * o.size.h);
}

TEST(Pipeline, LetterIIsAPerfectStructuredGrid) {
  const QuadMesh m = mesh(load("letter_I"), 2.0).mesh;
  const QualityReport q = compute_quality(m);
  EXPECT_GE(q.sj.min, 0.99);
  EXPECT_EQ(q.interior_singularities, 0u);
  EXPECT_EQ(q.singularities, 4u);  // the four corners (valence 2)
}

TEST(Pipeline, OutputIsIndependentOfTheThreadCount) {
  const Region r = load("letter_M");
  const QuadMesh a = mesh(r, 2.0, 1).mesh, b = mesh(r, 2.0, 2).mesh;
  ASSERT_EQ(a.nodes.size(), b.nodes.size());
  ASSERT_EQ(a.quads, b.quads);
  for (std::size_t i = 0; i < a.nodes.size(); ++i) ASSERT_TRUE(a.nodes[i] == b.nodes[i]) << i;
}

TEST(Pipeline, BadSizesAreInputErrors) {
  const Region r = load("letter_I");
  EXPECT_THROW(mesh(r, 0.0), InputError);
  EXPECT_THROW(mesh(r, -1.0), InputError);
  EXPECT_THROW(mesh(r, 1000.0), InputError);  // larger than the region
  MeshOptions o;
  o.size.h = 0.01;
  o.size.max_quads = 1000;
  EXPECT_THROW(mesh_region(r, o), InputError);  // would need ~14 million quads
}

TEST(Pipeline, PartsSmallerThanOneElementAreLeftOutAndReported) {
  // A 40 x 20 rectangle and a 1 x 1 islet at h = 2: the islet cannot hold a quad.
  const auto path = std::filesystem::temp_directory_path() / "polysquare_islet.geojson";
  {
    std::ofstream f(path);
    f << R"({"type":"FeatureCollection","features":[)"
      << R"({"type":"Feature","properties":{},"geometry":{"type":"MultiPolygon","coordinates":[)"
      << R"([[[0,0],[40,0],[40,20],[0,20],[0,0]]],[[[50,5],[51,5],[51,6],[50,6],[50,5]]]]}}]})";
  }
  const Region r = read_region(path.string());
  MeshOptions o;
  o.size.h = 2.0;
  const MeshResult res = mesh_region(r, o);
  ASSERT_EQ(res.report.dropped_parts.size(), 1u);
  EXPECT_NEAR(res.report.dropped_parts[0].area, 1.0, 1e-12);
  EXPECT_EQ(res.mesh.quads.size(), 200u);  // 20 x 10 on the rectangle
  // Measured without the islet, the mesh covers the rest exactly and misses no sharp vertex; with it, the
  // islet's four corners are missing and its area is lost.
  const DomainDistance with_islet = domain_distance(res.mesh, r);
  EXPECT_EQ(with_islet.sharp_vertices_missing, 4u);
  const DomainDistance without = domain_distance(res.mesh, r, {30.0, {res.report.dropped_parts[0].part}});
  EXPECT_EQ(without.sharp_vertices_missing, 0u);
  EXPECT_LT(std::abs(without.area_relative_change), 1e-12);
  o.curves.drop_small_parts = false;
  EXPECT_THROW(mesh_region(r, o), MeshingError);
  std::filesystem::remove(path);
}

TEST(Pipeline, PillowingAFeatureLoopSplitsItsFlatCorners) {
  // mechanical_part's circle gets four poly-square corners, each a node with one quad inside the circle.
  const Region region = load("mechanical_part");
  MeshOptions o = raw_single_map(3.0);
  const MeshResult raw = mesh_region(region, o);
  QuadMesh m = raw.mesh;
  const std::size_t loop_edges = m.feature_edges.size();
  const RefineStats st = pillow_feature_loops(m, RefineOptions{});
  EXPECT_EQ(st.feature_loops, 1u);
  ASSERT_EQ(st.pillowed, 1u);
  // One closed layer: a new node and a new quad per loop edge, the curve's nodes and edges untouched.
  EXPECT_EQ(m.quads.size(), raw.mesh.quads.size() + loop_edges);
  EXPECT_EQ(m.nodes.size(), raw.mesh.nodes.size() + loop_edges);
  EXPECT_EQ(m.feature_edges, raw.mesh.feature_edges);
  EXPECT_TRUE(check_invariants(m).ok()) << check_invariants(m).first_problem;
  // Each of the four corners: the loop node goes to valence 5 and its copy is a valence-3 node.
  EXPECT_EQ(compute_quality(m).interior_singularities, compute_quality(raw.mesh).interior_singularities + 8);
  std::vector<int> quads_at(m.nodes.size(), 0);
  for (const auto& q : m.quads)
    for (auto v : q) quads_at[v]++;
  for (const auto& e : m.feature_edges)
    for (auto v : e) EXPECT_GE(quads_at[v], 4) << "a loop node kept a single quad on one side";
  // A loop whose flattest single-quad corner is under loop_corner_deg keeps its corners (and no eight
  // singular nodes): the circle's are near 170 degrees.
  RefineOptions flatter_only;
  flatter_only.loop_corner_deg = 179.0;
  QuadMesh kept = raw.mesh;
  const RefineStats none = pillow_feature_loops(kept, flatter_only);
  EXPECT_EQ(none.feature_loops, 0u);
  EXPECT_EQ(kept.quads, raw.mesh.quads);
  // Through the pipeline (smoothing included) the worst quad, at those corners, improves.
  o.refine.enabled = true;
  const MeshResult refined = mesh_region(region, o);
  EXPECT_EQ(refined.report.candidates[0][0].feature_loops_pillowed, std::optional<std::size_t>(1));
  EXPECT_LT(compute_quality(raw.mesh).sj.min, 0.45);
  EXPECT_GT(compute_quality(refined.mesh).sj.min, 0.75);
}

TEST(Pipeline, FlatCornerTemplateRaisesTheWorstQuadOnDiscs) {
  // A disc meshed as one poly-square has four corners on its smooth rim; collapsing the quad at each (paper
  // Sec. 5.3, thinnest triangle patch) trades a near-180-degree corner for an interior valence-3 node.
  const Region region = load("turtle_shell");
  MeshOptions o = raw_single_map(2.5);
  const MeshResult raw = mesh_region(region, o);
  o.refine.enabled = true;
  const MeshResult refined = mesh_region(region, o);
  const QualityReport a = compute_quality(raw.mesh), b = compute_quality(refined.mesh);
  EXPECT_EQ(refined.report.candidates[0][0].flat_corners_collapsed, std::optional<std::size_t>(4));
  EXPECT_EQ(a.interior_singularities, 0u);
  EXPECT_EQ(b.interior_singularities, 4u);
  EXPECT_EQ(raw.mesh.quads.size() - refined.mesh.quads.size(), 4u);
  EXPECT_LT(a.sj.min, 0.3);
  EXPECT_GT(b.sj.min, 0.6);
  EXPECT_TRUE(check_invariants(refined.mesh).ok());
  const DomainDistance d = domain_distance(refined.mesh, refined.region);
  EXPECT_LT(d.boundary_max_relative, 1e-9);
  EXPECT_LT(d.feature_node_max_distance, 1e-9 * region.bounding_box().diagonal());
}
