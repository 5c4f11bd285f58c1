// Local repair (design.md, "Failures are local"): a PPM subregion whose map fails is meshed by an unstructured
// patch on the nodes its mapped neighbours made, and only that subregion; the mesh keeps every invariant.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <set>
#include <string>

#include "polysquare/core/error.h"
#include "polysquare/fallback/patch.h"
#include "polysquare/input/read_region.h"
#include "polysquare/map/polysquare_map.h"
#include "polysquare/pipeline/invariants.h"
#include "polysquare/pipeline/mesh_region.h"
#include "polysquare/quality/quality.h"

using namespace polysquare;

namespace {
Region load(const std::string& name) { return read_region(std::string(POLYSQUARE_DATA_DIR) + "/cases/" + name + ".geojson"); }

// A square loop of side `side` with `per_side` given edges on each side (counter-clockwise), as a patch input.
PatchInput square_loop(double side, int per_side) {
  PatchInput in;
  PatchCurve c;
  c.closed = c.loop = true;
  const Vec2 corner[4] = {{0, 0}, {side, 0}, {side, side}, {0, side}};
  for (int s = 0; s < 4; ++s)
    for (int k = 0; k < per_side; ++k) {
      c.nodes.push_back(static_cast<std::int32_t>(in.nodes.size()));
      in.nodes.push_back(lerp(corner[s], corner[(s + 1) % 4], static_cast<double>(k) / per_side));
      in.kind.push_back(k == 0 ? NodeKind::corner : NodeKind::boundary);
      c.role.push_back(PatchEdgeRole::boundary);
      c.tag.push_back(0);
    }
  in.curves.push_back(c);
  return in;
}
}  // namespace

TEST(Patch, TakesExactlyTheGivenBoundaryNodes) {
  for (const auto& [per_side, method] : {std::pair{2, PatchMethod::split}, std::pair{4, PatchMethod::split},
                                         std::pair{8, PatchMethod::split}, std::pair{5, PatchMethod::matching},
                                         std::pair{7, PatchMethod::matching}}) {
    const PatchInput in = square_loop(8.0, per_side);
    PatchOptions o;
    o.size = 8.0 / per_side;
    o.method = method;
    const QuadMesh m = mesh_patch(in, o);
    const InvariantReport inv = check_invariants(m);
    EXPECT_TRUE(inv.ok()) << per_side << ": " << inv.first_problem;
    // The given nodes come first, unmoved, and are the whole boundary.
    for (std::size_t v = 0; v < in.nodes.size(); ++v) EXPECT_EQ(m.nodes[v], in.nodes[v]);
    EXPECT_EQ(m.boundary_edges.size(), in.nodes.size());
    const QualityReport q = compute_quality(m);
    EXPECT_EQ(q.inverted, 0u);
    EXPECT_GT(q.sj.min, 0.2) << per_side;
    double area = 0;
    for (const auto& x : m.quads) area += 0.5 * cross(m.nodes[x[2]] - m.nodes[x[0]], m.nodes[x[3]] - m.nodes[x[1]]);
    EXPECT_NEAR(area, 64.0, 1e-9);
  }
}

TEST(Patch, RefusesAnOddBoundary) {
  PatchInput in = square_loop(8.0, 4);
  // Drop one node: 15 edges cannot bound a quad mesh.
  in.curves[0].nodes.pop_back();
  in.curves[0].role.pop_back();
  in.curves[0].tag.pop_back();
  PatchOptions o;
  o.size = 2.0;
  EXPECT_THROW(mesh_patch(in, o), MeshingError);
}

namespace {
// A patch input as written by a delta_box run (400 m, 128 subregions) whose repairs failed: h, the nodes
// (x y kind), the curves (closed loop count, node indices, role tag per edge), the isolated points.
PatchInput read_patch(const std::string& name, double& h) {
  std::ifstream f(std::string(POLYSQUARE_DATA_DIR) + "/../tests/data/patches/" + name);
  PatchInput in;
  std::size_t n = 0;
  f >> h >> n;
  for (std::size_t i = 0; i < n; ++i) {
    Vec2 p;
    int kind = 0;
    f >> p.x >> p.y >> kind;
    in.nodes.push_back(p);
    in.kind.push_back(static_cast<NodeKind>(kind));
  }
  std::size_t curves = 0;
  f >> curves;
  for (std::size_t c = 0; c < curves; ++c) {
    PatchCurve cv;
    int closed = 0, loop = 0;
    std::size_t m = 0;
    f >> closed >> loop >> m;
    cv.closed = closed != 0;
    cv.loop = loop != 0;
    cv.nodes.resize(m);
    for (auto& v : cv.nodes) f >> v;
    for (std::size_t e = 0; e < (cv.closed ? m : m - 1); ++e) {
      int role = 0, tag = 0;
      f >> role >> tag;
      cv.role.push_back(static_cast<PatchEdgeRole>(role));
      cv.tag.push_back(tag);
    }
    in.curves.push_back(std::move(cv));
  }
  std::size_t points = 0;
  f >> points;
  in.points.resize(points);
  for (auto& v : in.points) f >> v;
  EXPECT_TRUE(f.good()) << name;
  return in;
}
}  // namespace

TEST(Patch, MatchingUnknotsTheTrianglesNoPerfectMatchingPairs) {
  // Two delta_box patches (shorelines and rivers inside, wedges between them narrower than h) whose first
  // triangulations have no perfect matching; the knots get centre vertices until one exists.
  for (const char* name : {"delta_box_400m_subregion45.txt", "delta_box_400m_subregion45_grown.txt"}) {
    double h = 0;
    const PatchInput in = read_patch(name, h);
    PatchOptions o;
    o.size = h;
    o.method = PatchMethod::matching;
    o.matching_repairs = 0;
    EXPECT_THROW(mesh_patch(in, o), MeshingError) << name << ": a perfect matching at once; the case is moot";
    o.matching_repairs = PatchOptions{}.matching_repairs;
    const QuadMesh m = mesh_patch(in, o);
    for (std::size_t v = 0; v < in.nodes.size(); ++v) EXPECT_EQ(m.nodes[v], in.nodes[v]) << name;
    // Its border is exactly the given loops: every loop edge is in one quad, every other edge in two.
    std::map<std::pair<std::int32_t, std::int32_t>, int> uses;
    for (const auto& q : m.quads)
      for (int k = 0; k < 4; ++k) uses[std::minmax(q[k], q[(k + 1) % 4])]++;
    std::set<std::pair<std::int32_t, std::int32_t>> border, loop_edges;
    for (const auto& [e, count] : uses)
      if (count == 1) border.insert(e);
    for (const PatchCurve& c : in.curves)
      for (std::size_t i = 0; c.loop && i < c.nodes.size(); ++i)
        loop_edges.insert(std::minmax(c.nodes[i], c.nodes[(i + 1) % c.nodes.size()]));
    EXPECT_EQ(border, loop_edges) << name;
    // And it covers the patch once: the signed quad areas add up to the area the loops enclose (folds left
    // to the mesh's smoothing would still add up; overlaps or gaps would not).
    double quads_area = 0, loops_area = 0;
    for (const auto& q : m.quads)
      quads_area += 0.5 * cross(m.nodes[q[2]] - m.nodes[q[0]], m.nodes[q[3]] - m.nodes[q[1]]);
    for (const PatchCurve& c : in.curves)
      for (std::size_t i = 0; c.loop && i < c.nodes.size(); ++i)
        loops_area += 0.5 * cross(in.nodes[c.nodes[i]], in.nodes[c.nodes[(i + 1) % c.nodes.size()]]);
    EXPECT_NEAR(quads_area, loops_area, 1e-9 * std::abs(loops_area)) << name;
    EXPECT_GT(m.quads.size(), loop_edges.size() / 4) << name;
  }
}

TEST(Patch, NoQuadLeftFoldedOnTheDeltaBoxPatches) {
  // The same patches, by either construction: slivers along nearly straight runs of given nodes, doublets (a
  // free node in two quads) and quads of given nodes paired into a non-convex quad are all mended inside the
  // patch, so no quad is left folded for the mesh's smoothing.
  for (const char* name : {"delta_box_400m_subregion45.txt", "delta_box_400m_subregion45_grown.txt"})
    for (PatchMethod method : {PatchMethod::automatic, PatchMethod::matching}) {
      double h = 0;
      const PatchInput in = read_patch(name, h);
      PatchOptions o;
      o.size = h;
      o.method = method;
      const QuadMesh m = mesh_patch(in, o);
      std::vector<int> quads_at(m.nodes.size(), 0);
      for (const auto& q : m.quads) {
        EXPECT_GT(quad_min_sj(m.nodes[q[0]], m.nodes[q[1]], m.nodes[q[2]], m.nodes[q[3]]), 0.0)
            << name << " method " << int(method) << ": quad at " << at_text(m.nodes[q[0]]);
        for (auto v : q) quads_at[static_cast<std::size_t>(v)]++;
      }
      for (std::size_t v = in.nodes.size(); v < m.nodes.size(); ++v)
        EXPECT_GE(quads_at[v], 3) << name << ": free node at " << at_text(m.nodes[v]);
    }
}

TEST(LocalRepair, ASubregionMadeToFailIsPatchedAndOnlyIt) {
  // letter_M in 4 subregions, subregion 1 forced to a patch: the other three stay mapped, the patch welds to
  // their interface nodes, and the mesh holds every invariant with the boundary exactly on the input.
  const Region region = load("letter_M");
  MeshOptions o;
  o.size.h = 2.0;
  o.subregions.parts = 4;
  o.map.patch_subregions = {1};
  const MeshResult r = mesh_region(region, o);
  EXPECT_TRUE(check_invariants(r.mesh).ok()) << check_invariants(r.mesh).first_problem;
  ASSERT_EQ(r.parts.size(), 1u);
  const auto& subs = r.parts[0].subregions;
  ASSERT_EQ(subs.size(), 4u);
  std::size_t patch_quads = 0;
  for (const SubregionStats& s : subs) {
    EXPECT_EQ(s.mapped, s.subregion != 1) << s.subregion;
    if (!s.mapped) patch_quads += s.quads;
  }
  EXPECT_GT(patch_quads, 0u);
  const double fraction = r.report.summary.structured_fraction;
  EXPECT_GT(fraction, 0.3);
  EXPECT_LT(fraction, 1.0);
  EXPECT_EQ(r.report.summary.unstructured_subregions, 1u);
  const QualityReport q = compute_quality(r.mesh);
  EXPECT_EQ(q.inverted, 0u);
  EXPECT_GT(q.sj.min, 0.2);
  const DomainDistance d = domain_distance(r.mesh, r.region);
  EXPECT_LT(d.boundary_max_relative, 1e-9);
  EXPECT_EQ(d.sharp_vertices_missing, 0u);
}

TEST(LocalRepair, AGrownPatchTakesInOneNeighbourFirst) {
  // letter_M in 4 subregions, subregion 0 (two neighbours) a patch that must grow (as after a failed build): it
  // takes in the one neighbour that lets it build, the smallest, not both; the last subregion keeps its map.
  const Region region = load("letter_M");
  PolysquareMapOptions o;
  o.size = 2.0;
  o.partition.parts = 4;
  o.patch_subregions = {0};
  o.grown_patches = {0};
  const PartMapResult r = map_part(region, split_into_parts(region)[0], o);
  ASSERT_EQ(r.stats.subregions.size(), 4u);
  int patched = 0, taken_in = 0;
  for (const SubregionStats& s : r.stats.subregions) {
    patched += !s.mapped;
    taken_in += s.reason.find("meshed in the patch of subregion") != std::string::npos;
  }
  EXPECT_EQ(patched, 2);
  EXPECT_EQ(taken_in, 1);
  QuadMesh m = r.mesh;
  EXPECT_TRUE(check_invariants(m).ok()) << check_invariants(m).first_problem;
}

TEST(LocalRepair, APatchBesideAGrownPatchSharesItsNodes) {
  // A square in 9 subregions; one patch grows over a neighbour while another patch borders it. The union has one
  // chain where the other patch has one per member of the union: both must cut it at the junction of the three
  // subregions and count it alike, or their nodes differ there (a crack).
  Region region;
  region.rings.push_back({{{0, 0}, {60, 0}, {60, 60}, {0, 60}}, 0, false, 0, ""});
  region.num_parts = 1;
  region.source = "square";
  int unions = 0;
  for (int grown = 0; grown < 9; ++grown)
    for (int other = 0; other < 9; ++other) {
      if (other == grown) continue;
      PolysquareMapOptions o;
      o.size = 3.0;
      o.partition.parts = 9;
      o.patch_subregions = {grown, other};
      o.grown_patches = {grown};
      const PartMapResult r = map_part(region, split_into_parts(region)[0], o);
      bool taken_in = false;
      for (const SubregionStats& st : r.stats.subregions)
        taken_in = taken_in || st.reason.find("meshed in the patch of subregion") != std::string::npos;
      unions += taken_in;
      // Before smoothing a patch may hold flat quads; what must hold is the topology: every edge in two quads or
      // on the boundary.
      const InvariantReport inv = check_invariants(r.mesh);
      EXPECT_EQ(inv.non_manifold_edges, 0u) << grown << " grown, " << other << " patched";
      EXPECT_EQ(inv.untagged_boundary_edges, 0u) << grown << " grown, " << other << " patched";
    }
  EXPECT_GT(unions, 0);
}

TEST(LocalRepair, AnUnrepairedMeshIsFullyStructured) {
  // The same case without a forced patch: every subregion mapped, structured fraction 1.
  const Region region = load("letter_M");
  MeshOptions o;
  o.size.h = 2.0;
  o.subregions.parts = 4;
  const MeshResult r = mesh_region(region, o);
  EXPECT_DOUBLE_EQ(r.report.summary.structured_fraction, 1.0);
  EXPECT_EQ(r.report.summary.unstructured_subregions, 0u);
}

TEST(LocalRepair, TheReportSaysWhereACandidatesTimeWent) {
  // letter_M in 4 subregions, subregion 1 forced to a patch: the chosen candidate's stage times are each >= 0 and
  // add up to no more than its wall time; its part was mapped jointly at least once; its interior singular nodes
  // are all placed.
  const Region region = load("letter_M");
  MeshOptions o;
  o.size.h = 2.0;
  o.subregions.parts = 4;
  o.map.patch_subregions = {1};
  const MeshResult r = mesh_region(region, o);
  bool found = false;
  for (const auto& c : r.report.candidates[0]) {
    if (!c.chosen) continue;
    found = true;
    ASSERT_TRUE(c.stage_seconds.has_value());
    const CandidateSecondsReport& st = *c.stage_seconds;
    double sum = 0.0;
    for (double s : {st.map, st.repair_maps, st.refine, st.smooth, st.local_patches, st.relax_valences, st.measure}) {
      EXPECT_GE(s, 0.0);
      sum += s;
    }
    EXPECT_LE(sum, c.seconds + 1e-6);
    EXPECT_GE(st.map_of.joint_maps, 1);
    EXPECT_LE(st.map_of.joint_maps_seconds, st.map + 1e-6);
    // Every interior singular node is counted once, by where it is.
    ASSERT_TRUE(c.interior_singularities_at.has_value());
    const SingularitiesAtReport& at = *c.interior_singularities_at;
    EXPECT_EQ(at.maps + at.subregion_patches + at.local_patches, c.measures.value().interior_singularities);
  }
  EXPECT_TRUE(found);
  EXPECT_GE(r.report.parts[0].joint_maps, 1);
}

TEST(LocalRepair, NewCoastsHoldTheInvariantsAndTheSummaryAccountsForEveryQuad) {
  // Two coasts nobody tuned the mesher to (GSHHG, data/cases/PROVENANCE.md), one poly-square per part at 400 m:
  // every invariant holds, the boundary lies on the input, and the summary's structured fraction matches the
  // quads listed under `unstructured` (patches and whole-part fallbacks), each with its place.
  for (const char* name : {"fjord_coast", "estuary"}) {
    const Region region = load(name);
    MeshOptions o;
    o.size.h = 400.0;
    o.subregions.parts = 1;
    const MeshResult r = mesh_region(region, o);
    EXPECT_TRUE(check_invariants(r.mesh).ok()) << name << ": " << check_invariants(r.mesh).first_problem;
    EXPECT_EQ(compute_quality(r.mesh).inverted, 0u) << name;
    DomainDistanceOptions measure;
    for (const auto& d : r.report.dropped_parts) measure.skip_parts.push_back(d.part);
    const DomainDistance d = domain_distance(r.mesh, r.region, measure);
    EXPECT_LT(d.boundary_max_relative, 1e-9) << name;
    EXPECT_EQ(d.sharp_vertices_missing, 0u) << name;
    const auto& summary = r.report.summary;
    EXPECT_EQ(summary.quads, r.mesh.quads.size()) << name;
    double unstructured = 0;
    for (const auto& u : r.report.unstructured) {
      unstructured += u.quads;
      EXPECT_TRUE(std::isfinite(u.at.x) && std::isfinite(u.at.y));
    }
    // Quads that local patches made inside mapped subregions count as unstructured too.
    unstructured += summary.local_patch_quads;
    EXPECT_NEAR(summary.structured_fraction, 1.0 - unstructured / static_cast<double>(r.mesh.quads.size()),
                0.02) << name;
    EXPECT_EQ(summary.unstructured_subregions, r.report.unstructured.size()) << name;
  }
}

// fjord_coast at 400 m in 4 subregions under an SJ gate of 0.5 (so "far outside", below 0.25, occurs), local
// patches off and every poor quad accepted: what decides a subregion's fate is its map's quads alone.
static MeshOptions fjord_under_a_high_gate() {
  MeshOptions o;
  o.size.h = 400.0;
  o.subregions.parts = 4;
  o.gates.min_scaled_jacobian = 0.5;
  o.gates.max_poor_fraction = 1.0;
  o.local_patch.enabled = false;
  return o;
}

TEST(LocalRepair, ALargeMapKeepsItsMapForValidQuadsFarOutsideTheGates) {
  // fjord_coast at 400 m in 4 subregions, under an SJ gate of 0.5 (so "far outside", below 0.25, occurs) with
  // local patches off and every poor quad accepted: a map above keep_map_above_quads keeps its quads and
  // reports them as poor; below it, the same quads cost their subregion its map (meshed again as a patch).
  // Degenerate quads (below the untangling's target) cost a map of any size, under another reason.
  const Region region = load("fjord_coast");
  auto run = [&](std::size_t keep_above) {
    MeshOptions o = fjord_under_a_high_gate();
    o.repair.keep_map_above_quads = keep_above;
    return mesh_region(region, o);
  };
  auto demoted_for_quads = [](const MeshResult& r) {
    std::size_t n = 0;
    for (const auto& u : r.report.unstructured)
      n += u.reason.value_or("").find("near-degenerate") != std::string::npos;
    return n;
  };
  const MeshResult keep = run(0), demote = run(std::numeric_limits<std::size_t>::max());
  EXPECT_GT(demoted_for_quads(demote), 0u);
  EXPECT_EQ(demoted_for_quads(keep), 0u);
  EXPECT_GT(keep.report.summary.structured_fraction,
            demote.report.summary.structured_fraction);
  EXPECT_GT(keep.report.summary.poor_quads, 0u);
  EXPECT_TRUE(check_invariants(keep.mesh).ok()) << check_invariants(keep.mesh).first_problem;
}

TEST(LocalRepair, APatchCrossedByFeaturesGetsEvenCountsFromItsMappedNeighbours) {
  // A square with three wavy feature curves from its left side to 95 % of its width, in 9 subregions; each
  // subregion in turn is forced to a patch. The features end on the patches' loops and cut them into runs
  // between anchors, each of which must get an even count: the joint quantization gives the mapped neighbours
  // such counts, so the patch is built on its own (before, subregion 6's patch had to take in 3 neighbours).
  Region region;
  region.rings.push_back({{{0, 0}, {120, 0}, {120, 120}, {0, 120}}, 0, false, 0, ""});
  region.num_parts = 1;
  for (double y0 : {23.0, 52.0, 91.0}) {
    FeatureCurve f;
    for (int i = 0; i <= 19; ++i) f.points.push_back({5.0 * i, y0 + 3.0 * std::sin(0.37 * i + y0)});
    f.source_feature = 1;
    region.features.push_back(f);
  }
  region.source = "three_features";
  for (int s = 0; s < 9; ++s) {
    MeshOptions o;
    o.size.h = 3.0;
    o.subregions.parts = 9;
    o.map.patch_subregions = {s};
    const MeshResult r = mesh_region(region, o);
    ASSERT_EQ(r.parts.size(), 1u);
    const InvariantReport inv = check_invariants(r.mesh);
    EXPECT_TRUE(inv.ok()) << s << ": " << inv.first_problem;
    EXPECT_GT(r.report.summary.structured_fraction, 0.5) << s;
    const auto& subs = r.parts[0].subregions;
    ASSERT_FALSE(subs.empty()) << s << ": the part fell back as a whole";
    std::size_t unmapped = 0;
    for (const SubregionStats& sr : subs) unmapped += !sr.mapped;
    EXPECT_EQ(unmapped, 1u) << s << ": the patch took in its neighbours";
    const DomainDistance d = domain_distance(r.mesh, r.region);
    EXPECT_LT(d.feature_max_distance, 0.1 * o.size.h) << s;
  }
}

TEST(LocalRepair, QuadsBesideACrackAreFlaggedForRepair) {
  // Two unit squares side by side whose shared side has its own nodes on each side: a crack. Stitched (one pair
  // of nodes), nothing is flagged; the outer sides are tagged boundary edges either way.
  QuadMesh m;
  m.nodes = {{0, 0}, {1, 0}, {1, 1}, {0, 1}, {1, 0}, {2, 0}, {2, 1}, {1, 1}};
  m.quads = {{0, 1, 2, 3}, {4, 5, 6, 7}};
  m.boundary_edges = {{0, 1}, {2, 3}, {3, 0}, {4, 5}, {5, 6}, {6, 7}};
  const std::vector<std::uint8_t> cracked = quads_beside_cracks(m);
  EXPECT_EQ(cracked, (std::vector<std::uint8_t>{1, 1}));
  EXPECT_FALSE(check_invariants(m).ok());
  EXPECT_NE(check_invariants(m).first_problem.find("(1.000000, 0.000000)"), std::string::npos) << check_invariants(m).first_problem;
  m.quads[1] = {1, 5, 6, 2};
  m.boundary_edges = {{0, 1}, {2, 3}, {3, 0}, {1, 5}, {5, 6}, {6, 2}};
  EXPECT_EQ(quads_beside_cracks(m), (std::vector<std::uint8_t>{0, 0}));
  EXPECT_TRUE(check_invariants(m).ok()) << check_invariants(m).first_problem;
}

TEST(Patch, ValenceMovesLeaveFewerIrregularNodes) {
  // The delta_box patches and a square, each built with and without the valence moves: with them, fewer free
  // nodes sit in other than four quads, fewer given nodes in more or fewer quads than their angle asks for, and
  // no quad is folded or poorer than before.
  auto irregular = [](const PatchInput& in, const QuadMesh& m) {
    std::vector<int> quads_at(m.nodes.size(), 0);
    for (const auto& q : m.quads)
      for (auto v : q) quads_at[static_cast<std::size_t>(v)]++;
    std::size_t count = 0;
    for (std::size_t v = in.nodes.size(); v < m.nodes.size(); ++v) count += quads_at[v] != 4;
    return count;
  };
  std::size_t with = 0, without = 0;
  std::vector<std::pair<std::string, PatchInput>> inputs;
  std::vector<double> sizes;
  for (const char* name : {"delta_box_400m_subregion45.txt", "delta_box_400m_subregion45_grown.txt"}) {
    double h = 0;
    inputs.push_back({name, read_patch(name, h)});
    sizes.push_back(h);
  }
  inputs.push_back({"square", square_loop(8.0, 12)});
  sizes.push_back(8.0 / 12);
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    const auto& [name, in] = inputs[i];
    PatchOptions o;
    o.size = sizes[i];
    o.relax_valences = false;
    const QuadMesh plain = mesh_patch(in, o);
    o.relax_valences = true;
    const QuadMesh relaxed = mesh_patch(in, o);
    const std::size_t a = irregular(in, plain), b = irregular(in, relaxed);
    EXPECT_LE(b, a) << name;
    without += a;
    with += b;
    for (std::size_t v = 0; v < in.nodes.size(); ++v) EXPECT_EQ(relaxed.nodes[v], in.nodes[v]) << name;
    auto worst = [](const QuadMesh& m) {
      double w = 1.0;
      for (const auto& q : m.quads) w = std::min(w, quad_min_sj(m.nodes[q[0]], m.nodes[q[1]], m.nodes[q[2]], m.nodes[q[3]]));
      return w;
    };
    EXPECT_GT(worst(relaxed), 0.0) << name;
    double quads_area = 0, plain_area = 0;
    for (const auto& q : relaxed.quads)
      quads_area += 0.5 * cross(relaxed.nodes[q[2]] - relaxed.nodes[q[0]], relaxed.nodes[q[3]] - relaxed.nodes[q[1]]);
    for (const auto& q : plain.quads)
      plain_area += 0.5 * cross(plain.nodes[q[2]] - plain.nodes[q[0]], plain.nodes[q[3]] - plain.nodes[q[1]]);
    EXPECT_NEAR(quads_area, plain_area, 1e-6 * std::abs(plain_area)) << name;
  }
  std::cout << "free nodes not in four quads: " << without << " without the moves, " << with << " with them\n";
  EXPECT_LT(static_cast<double>(with), 0.8 * static_cast<double>(without));
}

TEST(LocalRepair, ARepairRoundPatchesItsSubregionsInPlaceWithoutMappingAgain) {
  // fjord_coast at 400 m in 4 subregions under an SJ gate of 0.5, local patches off and no map kept for its size:
  // the first round demotes subregions for their near-degenerate quads. In place, the next round cuts those
  // subregions out of the finished mesh and patches them there (no second map of the part); mapped again, the
  // part gets the same patches. Both meshes hold every invariant with the boundary on the input, and the same
  // subregions are patches.
  const Region region = load("fjord_coast");
  auto run = [&](bool in_place) {
    MeshOptions o = fjord_under_a_high_gate();
    o.repair.keep_map_above_quads = std::numeric_limits<std::size_t>::max();
    o.repair.in_place = in_place;
    return mesh_region(region, o);
  };
  const MeshResult in_place = run(true), mapped_again = run(false);
  auto chosen = [](const MeshResult& r) {
    for (const auto& c : r.report.candidates[0])
      if (c.chosen) return c;
    return CandidateReport();
  };
  auto patched = [](const MeshResult& r) {
    std::set<int> s;
    for (const SubregionStats& sr : r.parts[0].subregions)
      if (!sr.mapped) {
        s.insert(sr.subregion);
        EXPECT_NE(sr.reason.find("meshed again as a patch"), std::string::npos) << sr.reason;
      }
    return s;
  };
  const CandidateReport a = chosen(in_place), b = chosen(mapped_again);
  ASSERT_TRUE(a.chosen && a.repair_rounds && a.stage_seconds);
  ASSERT_TRUE(b.chosen && b.stage_seconds);
  ASSERT_GE(a.repair_rounds->size(), 2u);
  EXPECT_FALSE(a.repair_rounds->at(0).remeshed.empty());
  EXPECT_EQ(a.stage_seconds->repair_maps, 0.0);
  EXPECT_GT(a.stage_seconds->repair_patches, 0.0);
  EXPECT_GT(b.stage_seconds->repair_maps, 0.0);
  EXPECT_EQ(b.stage_seconds->repair_patches, 0.0);
  EXPECT_EQ(patched(in_place), patched(mapped_again));
  for (const int s : a.repair_rounds->at(0).remeshed) EXPECT_TRUE(patched(in_place).count(s)) << s;
  for (const MeshResult* r : {&in_place, &mapped_again}) {
    EXPECT_TRUE(check_invariants(r->mesh).ok()) << check_invariants(r->mesh).first_problem;
    EXPECT_EQ(compute_quality(r->mesh).inverted, 0u);
    DomainDistanceOptions measure;
    for (const auto& d : r->report.dropped_parts) measure.skip_parts.push_back(d.part);
    const DomainDistance d = domain_distance(r->mesh, r->region, measure);
    EXPECT_LT(d.boundary_max_relative, 1e-9);
    EXPECT_EQ(d.sharp_vertices_missing, 0u);
  }
  // The quads the summary counts are the mesh's, patches included.
  EXPECT_EQ(in_place.report.summary.quads, in_place.mesh.quads.size());
}

TEST(Patch, GradedPatchesFollowTheirSizeField) {
  // A 64 x 64 square under a field from 2 at x = 0 to 18 at x = 64, its given nodes graded as graded neighbours
  // make them (32 edges on the left side, 4 on the right, 9 along the others at x = 8 (9^(k/9) - 1)): the
  // interior vertices thin out towards the coarse side (lattices of spacing 2^k h), so the quads there are larger
  // and fewer in all; without the field they are the finest size everywhere.
  PatchInput in;
  {
    PatchCurve c;
    c.closed = c.loop = true;
    std::vector<Vec2> ring;
    for (int k = 0; k < 9; ++k) ring.push_back({8.0 * (std::pow(9.0, k / 9.0) - 1.0), 0.0});
    for (int k = 0; k < 4; ++k) ring.push_back({64.0, 16.0 * k});
    for (int k = 9; k > 0; --k) ring.push_back({8.0 * (std::pow(9.0, k / 9.0) - 1.0), 64.0});
    for (int k = 32; k > 0; --k) ring.push_back({0.0, 2.0 * k});
    for (std::size_t v = 0; v < ring.size(); ++v) {
      c.nodes.push_back(static_cast<std::int32_t>(v));
      in.nodes.push_back(ring[v]);
      in.kind.push_back(v == 0 || v == 9 || v == 13 || v == 22 ? NodeKind::corner : NodeKind::boundary);
      c.role.push_back(PatchEdgeRole::boundary);
      c.tag.push_back(0);
    }
    in.curves.push_back(c);
  }
  std::vector<double> h;
  const int n = 17;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) h.push_back(2.0 + 0.25 * 4.0 * i);
  const auto field = std::make_shared<const SizeField>(Vec2{0.0, 0.0}, 4.0, n, n, h);
  for (const PatchMethod method : {PatchMethod::split, PatchMethod::matching}) {
    auto mean_sizes = [&](bool graded, std::size_t& quads) {
      PatchOptions o;
      o.size = 2.0;
      o.method = method;
      if (graded) o.size_field = field;
      const QuadMesh m = mesh_patch(in, o);
      const InvariantReport inv = check_invariants(m);
      EXPECT_TRUE(inv.ok()) << inv.first_problem;
      EXPECT_EQ(compute_quality(m).inverted, 0u);
      quads = m.quads.size();
      double fine = 0, coarse = 0;
      int nf = 0, nc = 0;
      for (const auto& x : m.quads) {
        const Vec2 c = 0.25 * (m.nodes[x[0]] + m.nodes[x[1]] + m.nodes[x[2]] + m.nodes[x[3]]);
        const double s = std::sqrt(0.5 * std::abs(cross(m.nodes[x[2]] - m.nodes[x[0]], m.nodes[x[3]] - m.nodes[x[1]])));
        if (c.x < 16.0 && c.y > 8.0 && c.y < 56.0) { fine += s; ++nf; }
        if (c.x > 40.0 && c.y > 8.0 && c.y < 56.0) { coarse += s; ++nc; }
      }
      return std::pair{nf ? fine / nf : 0.0, nc ? coarse / nc : 0.0};
    };
    std::size_t uniform_quads = 0, graded_quads = 0;
    const auto [uf, uc] = mean_sizes(false, uniform_quads);
    const auto [gf, gc] = mean_sizes(true, graded_quads);
    EXPECT_LT(uc, 1.5 * uf) << "uniform";
    EXPECT_GT(gc, 2.0 * gf) << "graded: the coarse side's quads";
    EXPECT_LT(2 * graded_quads, uniform_quads);
  }
}
