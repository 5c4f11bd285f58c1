// The last resort for parts no poly-square candidate meshes: triangles split into quads. It must hold every
// invariant of design.md on its own, and the pipeline must use it for exactly the parts that failed and say so.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <unordered_set>

#include "polysquare/core/error.h"
#include "polysquare/fallback/split_triangles.h"
#include "polysquare/input/read_region.h"
#include "polysquare/pipeline/invariants.h"
#include "polysquare/pipeline/mesh_region.h"
#include "polysquare/quality/quality.h"

using namespace polysquare;

namespace {
Region load(const std::string& name) { return read_region(std::string(POLYSQUARE_DATA_DIR) + "/cases/" + name + ".geojson"); }
}  // namespace

TEST(SplitTriangles, HoldsTheInvariantsOnACaseWithHolesAndFeatures) {
  for (const auto& [name, size] : {std::pair{"mechanical_part", 3.0}, std::pair{"letter_R", 2.0}, std::pair{"smile", 2.5}}) {
    const Region region = load(name);
    SplitOptions o;
    o.size = size;
    const QuadMesh m = split_triangles(region, split_into_parts(region)[0], o);
    EXPECT_TRUE(check_invariants(m).ok()) << name << ": " << check_invariants(m).first_problem;
    const QualityReport q = compute_quality(m);
    EXPECT_EQ(q.triangles, 0u);
    EXPECT_EQ(q.inverted, 0u);
    EXPECT_GT(q.sj.min, 0.2) << name;  // the worst quad corner is the worst triangle angle (>= 20.7 degrees but
                                       // input corners sharper than that)
    const DomainDistance d = domain_distance(m, region);
    EXPECT_LT(d.boundary_max_relative, 1e-9) << name;
    EXPECT_EQ(d.sharp_vertices_missing, 0u) << name;
    EXPECT_LT(d.feature_node_max_distance, 1e-9 * region.bounding_box().diagonal()) << name;
    if (!region.features.empty()) EXPECT_LT(d.feature_max_distance, 1e-9 * region.bounding_box().diagonal()) << name;
    // Element size: interior quads of about h, boundary ones as small as the input's vertex spacing makes them.
    double area = 0;
    for (const auto& x : m.quads) area += 0.5 * cross(m.nodes[x[2]] - m.nodes[x[0]], m.nodes[x[3]] - m.nodes[x[1]]);
    const double mean = area / static_cast<double>(m.quads.size()) / (size * size);
    EXPECT_GT(mean, 0.1) << name;
    EXPECT_LT(mean, 1.5) << name;
  }
}

TEST(SplitTriangles, RefusesAPartSmallerThanOneElement) {
  const Region region = load("letter_I");
  SplitOptions o;
  o.size = 200.0;
  EXPECT_THROW(split_triangles(region, split_into_parts(region)[0], o), MeshingError);
}

TEST(Pipeline, CoastlinePartsThatNoMapMeshesFallBackAndAreReported) {
  // delta_water at 600 m with one poly-square per part: the convoluted coastline parts fail to map, fall back
  // to split triangles, and every part above one element is in the mesh with its reason on record.
  const Region region = load("delta_water");
  MeshOptions o;
  o.size.h = 600.0;
  o.subregions.parts = 1;
  const MeshResult r = mesh_region(region, o);
  EXPECT_TRUE(check_invariants(r.mesh).ok()) << check_invariants(r.mesh).first_problem;
  std::size_t fallbacks = 0, kept = 0;
  for (const auto& part : r.report.candidates)
    for (const auto& c : part) {
      if (!c.chosen) {
        EXPECT_TRUE(c.error.has_value());  // every candidate not kept says why
        continue;
      }
      ++kept;
      if (c.fallback.has_value()) ++fallbacks;
    }
  EXPECT_EQ(kept + r.report.dropped_parts.size(), static_cast<std::size_t>(region.num_parts));
  EXPECT_GT(fallbacks, 0u);
  const DomainDistance d = domain_distance(r.mesh, r.region);
  EXPECT_LT(d.boundary_max_relative, 1e-9);
  // Quads below the SJ gate are only those the report names: accepted within --max-poor-fraction (summary
  // poor_quads) or lying in an input corner sharper than the gate (the chosen candidates' pinned quads).
  const QuadMetrics m = quad_metrics(r.mesh);
  const auto below = static_cast<std::size_t>(
      std::count_if(m.sj.begin(), m.sj.end(), [&](double s) { return s < o.gates.min_scaled_jacobian; }));
  std::size_t pinned = 0;
  for (const auto& part : r.report.candidates)
    for (const auto& c : part)
      if (c.chosen && c.pinned.has_value())
        pinned += c.pinned->quads_pinned_by_sharp_input;
  EXPECT_LE(below, r.report.summary.poor_quads + pinned);
}

// The coastline sizes: both delta cases at h = 200 m hold every invariant, with features within 0.1 h.
// delta_box's shoreline and a river cross four times within 700 m near (276780, 3219350), at about 3 degrees:
// the slivers between those crossings are narrower than h, so one side of each is removed before meshing (and
// reported), and no quad is left pinned in a wedge: every quad passes the SJ gate.
TEST(Pipeline, DeltaCasesMeshAt200Metres) {
  for (const char* name : {"delta_water", "delta_box"}) {
    const Region region = load(name);
    MeshOptions o;
    o.size.h = 200.0;
    o.subregions.parts = 1;
    const MeshResult r = mesh_region(region, o);
    EXPECT_TRUE(check_invariants(r.mesh).ok()) << name << ": " << check_invariants(r.mesh).first_problem;
    const QualityReport q = compute_quality(r.mesh);
    EXPECT_EQ(q.inverted, 0u) << name;
    EXPECT_GE(q.sj.min, o.gates.min_scaled_jacobian) << name;
    for (const auto& part : r.report.candidates)
      for (const auto& c : part)
        if (c.chosen) EXPECT_FALSE(c.pinned.has_value()) << name;
    if (std::string(name) == "delta_box") {
      bool near_crossing = false;
      for (const auto& d : r.report.dropped_curves) {
        EXPECT_NE(d.kind, "hole");  // island loops narrower than h, and pieces of slivers
        EXPECT_LT(d.width, o.size.h);
        if (d.kind != "feature_piece") continue;
        EXPECT_LE(d.distance, o.size.h);
        near_crossing = near_crossing || std::hypot(d.at.x - 276780.0, d.at.y - 3219350.0) < 700.0;
      }
      EXPECT_TRUE(near_crossing);
    }
    DomainDistanceOptions measure;
    for (const auto& d : r.report.dropped_parts) measure.skip_parts.push_back(d.part);
    const DomainDistance d = domain_distance(r.mesh, r.region, measure);
    EXPECT_LT(d.boundary_max_relative, 1e-9) << name;
    // The shorelines were simplified to the size: the mesh boundary stays within h of the input.
    EXPECT_LE(domain_distance(r.mesh, region, measure).boundary_max_distance, o.size.h) << name;
    EXPECT_EQ(d.sharp_vertices_missing, 0u) << name;
    EXPECT_LT(d.feature_node_max_distance, 1e-9 * region.bounding_box().diagonal()) << name;
    EXPECT_LE(d.feature_max_distance, 0.1 * o.size.h) << name;
    if (!region.features.empty()) EXPECT_GT(r.mesh.feature_edges.size(), 0u) << name;
  }
}

TEST(SplitTriangles, PairsTrianglesIntoGoodQuadsAndSoHalvesTheSingularNodes) {
  const Region region = load("mechanical_part");
  const RegionPart part = split_into_parts(region)[0];
  SplitOptions o;
  o.size = 3.0;
  const TriMesh tri = triangulate_part(region, part, split_triangulation_options(o));
  const auto [partner, pairs] = pair_triangles(tri, o.pair_min_sj);
  std::unordered_set<std::uint64_t> curve;
  for (const TriChain& ch : tri.chains)
    for (std::size_t i = 0; i + 1 < ch.vertices.size() + (ch.closed ? 1 : 0); ++i)
      curve.insert(edge_key(ch.vertices[i], ch.vertices[(i + 1) % ch.vertices.size()]));
  std::size_t seen = 0;
  for (std::size_t t = 0; t < partner.size(); ++t) {
    if (partner[t] < 0) continue;
    ++seen;
    EXPECT_EQ(partner[static_cast<std::size_t>(partner[t])], static_cast<std::int32_t>(t));  // symmetric
    // The two share exactly one edge, and it is not on a boundary or feature curve.
    const auto& a = tri.triangles[t];
    const auto& b = tri.triangles[static_cast<std::size_t>(partner[t])];
    int shared = 0;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) shared += a[i] == b[j];
    EXPECT_EQ(shared, 2);
    for (int i = 0; i < 3; ++i) {
      const std::int32_t p = a[i], q = a[(i + 1) % 3];
      if (std::count(b.begin(), b.end(), p) && std::count(b.begin(), b.end(), q))
        EXPECT_FALSE(curve.count(edge_key(p, q))) << "merged across a curve";
    }
  }
  EXPECT_EQ(seen, 2 * pairs);
  EXPECT_GT(2 * pairs, tri.triangles.size() / 2);  // most triangles find a partner
  // Against splitting every triangle in three: far fewer interior singular nodes, invariants kept.
  const QuadMesh paired = split_triangles(region, part, o);
  o.pair_min_sj = 2.0;
  const QuadMesh alone = split_triangles(region, part, o);
  EXPECT_TRUE(check_invariants(paired).ok()) << check_invariants(paired).first_problem;
  EXPECT_LT(2 * compute_quality(paired).interior_singularities, compute_quality(alone).interior_singularities);
}
