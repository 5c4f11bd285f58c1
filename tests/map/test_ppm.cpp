// Piecewise Poly-square Map (paper Sec. 5.2): interval assignment across interfaces on hand-made layouts, the
// cutting of a partitioned triangulation into subregions, and conforming stitched meshes on the real cases.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <set>

#include "polysquare/core/error.h"
#include "polysquare/input/read_region.h"
#include "polysquare/map/piecewise_map.h"
#include "polysquare/map/quantize.h"
#include "polysquare/partition/partition.h"
#include "polysquare/pipeline/invariants.h"
#include "polysquare/pipeline/mesh_region.h"
#include "polysquare/quality/quality.h"
#include "polysquare/size/size_field.h"

using namespace polysquare;

namespace {

// A layout with its deformed positions (taken as given).
struct RectLayout {
  Layout layout;
  std::vector<Vec2> deformed;
};

// The layout of one axis-parallel polygon (counter-clockwise, a break point at every vertex).
RectLayout polygon(const std::vector<Vec2>& ring) {
  RectLayout r;
  r.deformed = ring;
  const int n = static_cast<int>(ring.size());
  for (int i = 0; i < n; ++i) {
    r.layout.break_vertex.push_back(i);
    r.layout.break_is_corner.push_back(1);
    r.layout.vertex_break.push_back(i);
  }
  for (int i = 0; i < n; ++i) {
    const Vec2 d = ring[(i + 1) % n] - ring[i];
    LayoutSegment s;
    s.chain = 0;
    s.first = i;
    s.count = 1;
    s.label = std::abs(d.x) > std::abs(d.y) ? (d.x > 0 ? 0 : 2) : (d.y > 0 ? 1 : 3);
    s.break_a = i;
    s.break_b = (i + 1) % n;
    s.target = norm(d);
    r.layout.segments.push_back(s);
  }
  return r;
}

// A rectangle layout from its four corners (counter-clockwise from bottom-left), with extra straight break
// points on its right side (heights in `right_breaks`).
RectLayout rectangle(Vec2 lo, Vec2 hi, const std::vector<double>& right_breaks = {}) {
  std::vector<Vec2> ring{lo, {hi.x, lo.y}};
  for (double y : right_breaks) ring.push_back({hi.x, y});
  ring.push_back(hi);
  ring.push_back({lo.x, hi.y});
  return polygon(ring);
}

// The area of a triangulation.
double triangulated_area(const TriMesh& tri) {
  double area = 0.0;
  for (const auto& t : tri.triangles) area += 0.5 * orient2(tri.vertices[t[0]], tri.vertices[t[1]], tri.vertices[t[2]]);
  return area;
}

}  // namespace

TEST(InterfaceQuantization, TJunctionCountsAgreeAcrossSubregions) {
  // A (left, 4.3 x 6.2) has its right side split at the T-junction where the separator between B (top right)
  // and C (bottom right) meets it. Each subregion is in its own frame; the targets disagree across every interface
  // (2.4 vs 3.6 below, 3.8 vs 2.6 above), so only the coupling can make the counts equal.
  RectLayout A = rectangle({0, 0}, {4.3, 6.2}, {2.4});
  RectLayout B = rectangle({0, 0}, {5.1, 2.6});  // its left side (segment 3, -Y) faces A's upper right piece
  RectLayout C = rectangle({0, 0}, {5.4, 3.6});  // its left side faces A's lower piece, its top faces B's bottom
  auto seg_len = [](const Layout& l, int k) {
    const auto a = l.lattice[l.segments[k].break_a], b = l.lattice[l.segments[k].break_b];
    return std::llabs(b[0] - a[0]) + std::llabs(b[1] - a[1]);
  };
  {  // Alone, each rectangle keeps its own counts: the interfaces disagree.
    RectLayout a = A, c = C;
    quantize_layout(a.layout, a.deformed, QuantizeOptions{}, "A");
    quantize_layout(c.layout, c.deformed, QuantizeOptions{}, "C");
    EXPECT_NE(seg_len(a.layout, 1), seg_len(c.layout, 3));
  }
  // A: 0 bottom, 1 right lower, 2 right upper, 3 top, 4 left. B and C: 0 bottom, 1 right, 2 top, 3 left.
  const std::vector<SegmentCoupling> couplings{{0, 1, 2, 3}, {0, 2, 1, 3}, {1, 0, 2, 2}};
  const QuantizeStats st = quantize_layouts({&A.layout, &B.layout, &C.layout}, {&A.deformed, &B.deformed, &C.deformed},
                                            couplings, QuantizeOptions{}, "T");
  for (const RectLayout* r : {&A, &B, &C}) EXPECT_EQ(check_layout(r->layout), "");
  EXPECT_EQ(seg_len(A.layout, 1), seg_len(C.layout, 3));
  EXPECT_EQ(seg_len(A.layout, 2), seg_len(B.layout, 3));
  EXPECT_EQ(seg_len(B.layout, 0), seg_len(C.layout, 2));
  // Every rectangle closes: opposite sides equal, A's left side the sum of its two right pieces.
  EXPECT_EQ(seg_len(A.layout, 4), seg_len(A.layout, 1) + seg_len(A.layout, 2));
  EXPECT_EQ(seg_len(B.layout, 1), seg_len(B.layout, 3));
  EXPECT_EQ(seg_len(C.layout, 1), seg_len(C.layout, 3));
  // Counts stay near the targets: each within one element of the nearer of its two targets' range.
  EXPECT_GE(seg_len(A.layout, 1), 2);
  EXPECT_LE(seg_len(A.layout, 1), 4);
  EXPECT_GE(seg_len(A.layout, 2), 2);
  EXPECT_LE(seg_len(A.layout, 2), 4);
  EXPECT_EQ(seg_len(A.layout, 0), 4);  // 4.3, uncoupled
  EXPECT_LT(st.max_relative_deviation, 0.5);
}

TEST(InterfaceQuantization, DisagreeingMapsShareTheInterfaceLength) {
  // Two subregions' maps disagree on their interface by a factor of two: A (4 x 8) sees it 8 long, B (4 x 16) 16.
  // Each side's own relative deviation would put the count at the shorter target and squeeze B to half its
  // length; the shared count lies between, within 1.5 of both targets in ratio.
  RectLayout A = rectangle({0, 0}, {4, 8}), B = rectangle({0, 0}, {4, 16});
  // A's right side (1, +Y) against B's left side (3, -Y).
  quantize_layouts({&A.layout, &B.layout}, {&A.deformed, &B.deformed}, {{0, 1, 1, 3}}, QuantizeOptions{}, "AB");
  const auto len = [](const Layout& l, int k) {
    const auto a = l.lattice[l.segments[k].break_a], b = l.lattice[l.segments[k].break_b];
    return std::llabs(b[0] - a[0]) + std::llabs(b[1] - a[1]);
  };
  ASSERT_EQ(len(A.layout, 1), len(B.layout, 3));
  const double n = static_cast<double>(len(A.layout, 1));
  EXPECT_LE(n / 8.0, 1.5);
  EXPECT_GE(n / 16.0, 1.0 / 1.5);
  EXPECT_EQ(len(A.layout, 3), len(A.layout, 1));  // both close as rectangles
  EXPECT_EQ(len(B.layout, 1), len(B.layout, 3));
}

TEST(InterfaceQuantization, CouplingsPropagateThroughSubregions) {
  // A wants 1 x 3 elements; its bottom is coupled to B's right side and its right side to B's left side. B is a
  // rectangle (left = right), so A must come out square: counts travel across subregions, not just one interface.
  RectLayout A = rectangle({0, 0}, {1, 3}), B = rectangle({0, 0}, {2, 2});
  QuantizeOptions o;
  const std::vector<SegmentCoupling> couplings{{0, 0, 1, 1}, {0, 1, 1, 3}};
  quantize_layouts({&A.layout, &B.layout}, {&A.deformed, &B.deformed}, couplings, o, "square");
  const auto len = [](const Layout& l, int k) {
    const auto a = l.lattice[l.segments[k].break_a], b = l.lattice[l.segments[k].break_b];
    return std::llabs(b[0] - a[0]) + std::llabs(b[1] - a[1]);
  };
  EXPECT_EQ(len(A.layout, 0), len(A.layout, 1));
  EXPECT_EQ(check_layout(A.layout), "");
}

TEST(InterfaceQuantization, ElasticCouplingsNameTheOnesThatCannotAgree) {
  // C's right side is split in two pieces whose counts add up to its left side; coupling A's bottom both to C's
  // left side and to C's lower right piece leaves the upper piece no element: no integer program satisfies both.
  // The elastic program still solves, honours one coupling, and names the other (and only it) as broken.
  RectLayout A = rectangle({0, 0}, {3, 2}), C = rectangle({0, 0}, {2, 3}, {1.5});
  // A: 0 bottom, 1 right, 2 top, 3 left. C: 0 bottom, 1 right lower, 2 right upper, 3 top, 4 left.
  const std::vector<SegmentCoupling> couplings{{0, 0, 1, 4}, {0, 0, 1, 1}, {0, 1, 1, 0}};
  const auto len = [](const Layout& l, int k) {
    const auto a = l.lattice[l.segments[k].break_a], b = l.lattice[l.segments[k].break_b];
    return std::llabs(b[0] - a[0]) + std::llabs(b[1] - a[1]);
  };
  {
    RectLayout a = A, c = C;
    EXPECT_THROW(quantize_layouts({&a.layout, &c.layout}, {&a.deformed, &c.deformed}, couplings, QuantizeOptions{}, "AC"),
                 MeshingError);
  }
  std::vector<std::size_t> broken;
  quantize_layouts({&A.layout, &C.layout}, {&A.deformed, &C.deformed}, couplings, QuantizeOptions{}, "AC", {}, &broken);
  ASSERT_EQ(broken.size(), 1u);
  EXPECT_TRUE(broken[0] == 0 || broken[0] == 1) << broken[0];
  EXPECT_EQ(check_layout(A.layout), "");
  EXPECT_EQ(check_layout(C.layout), "");
  for (std::size_t c = 0; c < couplings.size(); ++c) {
    const Layout& la = couplings[c].layout_a == 0 ? A.layout : C.layout;
    const Layout& lb = couplings[c].layout_b == 0 ? A.layout : C.layout;
    if (c == broken[0]) EXPECT_NE(len(la, couplings[c].segment_a), len(lb, couplings[c].segment_b));
    else EXPECT_EQ(len(la, couplings[c].segment_a), len(lb, couplings[c].segment_b)) << c;
  }
  // Couplings that can agree are all honoured and none is named.
  RectLayout B = rectangle({0, 0}, {3, 2}), D = rectangle({0, 0}, {2, 3}, {1.5});
  quantize_layouts({&B.layout, &D.layout}, {&B.deformed, &D.deformed}, {{0, 0, 1, 4}, {0, 1, 1, 0}}, QuantizeOptions{},
                   "BD", {}, &broken);
  EXPECT_TRUE(broken.empty());
  EXPECT_EQ(len(B.layout, 0), len(D.layout, 4));
}

TEST(InterfaceQuantization, LayoutsThatCannotCloseAloneAreNamedBeforeTheJointProgram) {
  // Two coupled rectangles that agree, and two layouts that no quantization makes valid: a rectangle whose top
  // side is labelled +X like its bottom (x(left) > x(right) > x(left): no solution at all), and an L-shape whose
  // notch reads -X, +X, -X along one line (two of its sides overlap however it is separated). The error names
  // those two, by their index in the call, with why each fails alone; the others then quantize together.
  RectLayout A = rectangle({0, 0}, {3, 2}), B = rectangle({0, 0}, {2, 2});
  RectLayout bad_labels = rectangle({0, 0}, {4, 3});
  bad_labels.layout.segments[2].label = 0;
  RectLayout notch;
  notch.deformed = {{0, 0}, {4.2, 0}, {4.2, 2.1}, {2.1, 2.1}, {2.1, 5.9}, {0, 5.9}};
  const int labels[6] = {0, 1, 2, 0, 2, 3};
  for (int i = 0; i < 6; ++i) {
    notch.layout.break_vertex.push_back(i);
    notch.layout.break_is_corner.push_back(1);
    notch.layout.vertex_break.push_back(i);
    LayoutSegment s;
    s.chain = 0, s.first = i, s.count = 1, s.label = labels[i];
    s.break_a = i, s.break_b = (i + 1) % 6;
    s.target = distance(notch.deformed[static_cast<std::size_t>(i)], notch.deformed[static_cast<std::size_t>((i + 1) % 6)]);
    notch.layout.segments.push_back(s);
  }
  try {
    quantize_layouts({&A.layout, &bad_labels.layout, &B.layout, &notch.layout},
                     {&A.deformed, &bad_labels.deformed, &B.deformed, &notch.deformed}, {{0, 1, 2, 3}}, QuantizeOptions{},
                     "four");
    ADD_FAILURE() << "a joint program with two layouts that cannot close was solved";
  } catch (const LayoutsCannotClose& e) {
    EXPECT_EQ(e.layouts, (std::vector<std::size_t>{1, 3}));
    ASSERT_EQ(e.reasons.size(), 2u);
    EXPECT_NE(e.reasons[1].find("overlapping"), std::string::npos) << e.reasons[1];
    EXPECT_NE(std::string(e.what()).find("four"), std::string::npos) << e.what();
  }
  quantize_layouts({&A.layout, &B.layout}, {&A.deformed, &B.deformed}, {{0, 1, 1, 3}}, QuantizeOptions{}, "two");
  EXPECT_EQ(check_layout(A.layout), "");
  EXPECT_EQ(check_layout(B.layout), "");
  const auto len = [](const Layout& l, int k) {
    const auto a = l.lattice[l.segments[k].break_a], b = l.lattice[l.segments[k].break_b];
    return std::llabs(b[0] - a[0]) + std::llabs(b[1] - a[1]);
  };
  EXPECT_EQ(len(A.layout, 1), len(B.layout, 3));
}

namespace {
Region load(const std::string& name) {
  return read_region(std::string(POLYSQUARE_DATA_DIR) + "/cases/" + name + ".geojson");
}

TriMesh background(const Region& region, double h) {
  const auto parts = split_into_parts(region);
  TriangulationOptions t;
  t.boundary_edge = h;
  t.max_edge = 4 * h;
  return triangulate_part(region, parts.front(), t);
}

// The background triangulation of a case and its k-way partition.
struct Partitioned {
  TriMesh tri;
  std::vector<std::int32_t> triangle_part;
};

Partitioned partitioned(const char* name, double h, int k) {
  Partitioned p;
  p.tri = background(load(name), h);
  PartitionOptions po;
  po.parts = k;
  p.triangle_part = partition_triangles(p.tri, po).triangle_part;
  return p;
}
}  // namespace

TEST(Subregions, EveryInterfaceIsCutIdenticallyOnBothSides) {
  for (const auto& [name, h, k] : {std::make_tuple("pentagon", 3.0, 4), std::make_tuple("letter_M", 2.0, 6),
                                   std::make_tuple("rect_feature", 3.0, 4)}) {
    const auto [tri, triangle_part] = partitioned(name, h, k);
    const std::vector<Subregion> subs = split_subregions(tri, triangle_part, k, name);
    ASSERT_EQ(subs.size(), static_cast<std::size_t>(k));
    std::size_t triangles = 0;
    // Interface pieces by their global vertex sequence: each must appear once from each side, reversed.
    std::map<std::vector<std::int32_t>, int> pieces;
    for (std::size_t p = 0; p < subs.size(); ++p) {
      const Subregion& s = subs[p];
      triangles += s.mesh.triangles.size();
      for (const auto& loop : s.mesh.loops)
        for (std::size_t i = 0; i < loop.size(); ++i) {  // consecutive chains of a loop join end to start
          const auto& a = s.mesh.chains[static_cast<std::size_t>(loop[i])];
          const auto& b = s.mesh.chains[static_cast<std::size_t>(loop[(i + 1) % loop.size()])];
          EXPECT_EQ(a.vertices.back(), b.vertices.front()) << name;
        }
      for (const TriChain& ch : s.mesh.chains) {
        if (ch.interface < 0) continue;
        std::vector<std::int32_t> g;
        for (auto v : ch.vertices) g.push_back(s.global_vertex[static_cast<std::size_t>(v)]);
        std::vector<std::int32_t> r(g.rbegin(), g.rend());
        if (auto it = pieces.find(r); it != pieces.end()) {
          EXPECT_EQ(it->second, ch.interface) << name;  // the neighbour named is the other side
          pieces.erase(it);
        } else {
          pieces.emplace(g, static_cast<int>(p));
        }
      }
    }
    EXPECT_TRUE(pieces.empty()) << name << ": " << pieces.size() << " interface pieces without a partner";
    // Triangles are only added by splitting constrained interior edges, never lost.
    EXPECT_GE(triangles, tri.triangles.size()) << name;
  }
}

TEST(PartitionRepair, FeaturePiecesAndCornerEndsAreSettledInOnePass) {
  for (const auto& [name, h, k] : {std::make_tuple("rect_feature", 3.0, 4), std::make_tuple("square_feature", 3.0, 4),
                                   std::make_tuple("letter_R", 2.0, 5)}) {
    auto [tri, tp] = partitioned(name, h, k);
    absorb_pieces_cut_off_by_features(tri, tp);
    snap_separator_ends_to_corners(tri, tp, 30.0);
    // A second pass finds nothing left to move, and every part still has triangles.
    std::vector<std::int32_t> again = tp;
    EXPECT_EQ(absorb_pieces_cut_off_by_features(tri, again), 0u) << name;
    EXPECT_EQ(again, tp);
    EXPECT_EQ(std::set<std::int32_t>(tp.begin(), tp.end()).size(), static_cast<std::size_t>(k)) << name;
  }
}

TEST(PartitionRepair, TheSubregionCapGrowsWithThePartsQuads) {
  // rect_feature at h = 3 in 4 subregions; subregion 0 listed with 24 sides is split in two. A cap of 4
  // subregions blocks that split, unless the part's quads over split_quads_per_subregion allow more.
  const auto [tri, tp] = partitioned("rect_feature", 3.0, 4);
  const double area = triangulated_area(tri);
  PolysquareMapOptions o;
  o.size = 3.0;
  o.split_max_subregions = 4;
  o.split_quads_per_subregion = static_cast<std::size_t>(area / 9.0) + 1;  // one subregion's worth: the cap stays 4
  std::vector<std::int32_t> capped = tp;
  int split = -1;
  EXPECT_EQ(split_listed_subregions(tri, capped, 4, {{0, 24}}, o, "rect_feature", split), 4);
  EXPECT_EQ(split, 0);
  EXPECT_EQ(capped, tp);
  o.split_quads_per_subregion = static_cast<std::size_t>(area / 9.0 / 8.0);  // the part holds 8 of them
  std::vector<std::int32_t> grown = tp;
  EXPECT_EQ(split_listed_subregions(tri, grown, 4, {{0, 24}}, o, "rect_feature", split), 5);
  EXPECT_EQ(split, 1);
  EXPECT_EQ(std::set<std::int32_t>(grown.begin(), grown.end()).size(), 5u);
}

TEST(PartitionRepair, AGradedPartsCapCountsItsQuadsByTheField) {
  // The same split on a graded run, the field at twice the size everywhere: the part holds a quarter of the
  // quads, so a cap that the size's count would lift to 8 stays at 4; the graded figure per subregion lifts it.
  const auto [tri, tp] = partitioned("rect_feature", 3.0, 4);
  const double area = triangulated_area(tri);
  PolysquareMapOptions o;
  o.size = 3.0;
  o.size_field = std::make_shared<const SizeField>(Vec2{-1e4, -1e4}, 2e4, 2, 2, std::vector<double>(4, 6.0));
  o.split_max_subregions = 4;
  o.split_quads_per_subregion = static_cast<std::size_t>(area / 9.0 / 8.0);  // uniform: 8 subregions' worth
  o.split_graded_quads_per_subregion = static_cast<std::size_t>(area / 9.0 / 8.0) + 1;  // by the field: 2
  std::vector<std::int32_t> capped = tp;
  int split = -1;
  EXPECT_EQ(split_listed_subregions(tri, capped, 4, {{0, 24}}, o, "rect_feature", split), 4);
  EXPECT_EQ(split, 0);
  o.split_graded_quads_per_subregion = static_cast<std::size_t>(area / 36.0 / 8.0);  // by the field: 8
  std::vector<std::int32_t> grown = tp;
  EXPECT_EQ(split_listed_subregions(tri, grown, 4, {{0, 24}}, o, "rect_feature", split), 5);
  EXPECT_EQ(split, 1);
}

namespace {
MeshResult ppm(const char* name, double size, int parts, int threads = 0) {
  MeshOptions o;
  o.size.h = size;
  o.subregions.parts = parts;
  o.run.threads = threads;
  return mesh_region(load(name), o);
}
}  // namespace

class PpmCase : public ::testing::TestWithParam<std::tuple<const char*, double, int, std::size_t>> {};

TEST_P(PpmCase, SubregionsAreStitchedConformingly) {
  const auto [name, size, parts, gmsh_singularities] = GetParam();
  const MeshResult r = ppm(name, size, parts);
  // The requested partition was kept (no fallback to one poly-square): every subregion has quads.
  const std::set<std::int32_t> used(r.mesh.quad_part.begin(), r.mesh.quad_part.end());
  EXPECT_EQ(used.size(), static_cast<std::size_t>(parts)) << name;
  const InvariantReport inv = check_invariants(r.mesh);
  EXPECT_TRUE(inv.ok()) << inv.first_problem;
  const QualityReport q = compute_quality(r.mesh);
  EXPECT_EQ(q.non_manifold_edges, 0u);
  EXPECT_GT(q.sj.min, 0.2) << name;
  EXPECT_LE(4 * q.interior_singularities, gmsh_singularities) << name;  // the issue's bound: a quarter of Gmsh's
  const Region region = load(name);
  const DomainDistance d = domain_distance(r.mesh, r.region);  // the simplified curves (invariant 4)
  EXPECT_LT(d.boundary_max_relative, 1e-9);
  EXPECT_EQ(d.sharp_vertices_missing, 0u);
  EXPECT_LT(d.feature_node_max_distance, 1e-9 * region.bounding_box().diagonal());
  EXPECT_LT(d.feature_max_distance, 0.1 * size) << name;
}

INSTANTIATE_TEST_SUITE_P(Cases, PpmCase,
                         ::testing::Values(std::make_tuple("triangle", 3.0, 3, 101), std::make_tuple("pentagon", 3.0, 5, 100),
                                           std::make_tuple("letter_M", 2.0, 8, 177), std::make_tuple("letter_R", 2.0, 3, 152),
                                           // subregion 1 of letter_R's 8-way partition needs the Tutte snap
                                           std::make_tuple("letter_R", 2.0, 8, 152),
                                           std::make_tuple("key", 2.0, 4, 184), std::make_tuple("dam_channel", 2.0, 4, 508)));

TEST(Ppm, IndependentOfTheThreadCount) {
  const QuadMesh a = ppm("letter_M", 2.0, 8, 1).mesh, b = ppm("letter_M", 2.0, 8, 2).mesh;
  ASSERT_EQ(a.quads, b.quads);
  ASSERT_EQ(a.quad_part, b.quad_part);
  ASSERT_EQ(a.nodes.size(), b.nodes.size());
  for (std::size_t i = 0; i < a.nodes.size(); ++i) ASSERT_TRUE(a.nodes[i] == b.nodes[i]) << i;
}

TEST(PartitionRepair, APartEnclosedByAnotherIsMergedIntoIt) {
  // pentagon: a disc of triangles around the centre is part 1 (enclosed by part 0), a wedge touching the
  // boundary is part 2 (kept), everything else part 0.
  auto [tri, tp] = partitioned("pentagon", 3.0, 2);
  Box2 box;
  for (Vec2 p : tri.vertices) box.add(p);
  const Vec2 c = 0.5 * (box.lo + box.hi);
  const double r = 0.15 * box.diagonal();
  for (std::size_t t = 0; t < tri.triangles.size(); ++t) {
    const auto& tr = tri.triangles[t];
    const Vec2 m = (1.0 / 3.0) * (tri.vertices[tr[0]] + tri.vertices[tr[1]] + tri.vertices[tr[2]]);
    tp[t] = distance(m, c) < r ? 1 : (m.x > box.hi.x - 0.2 * (box.hi.x - box.lo.x) ? 2 : 0);
  }
  const std::size_t disc = static_cast<std::size_t>(std::count(tp.begin(), tp.end(), 1));
  ASSERT_GT(disc, 0u);
  EXPECT_EQ(merge_enclosed_parts(tri, tp), 2);
  EXPECT_EQ(std::count(tp.begin(), tp.end(), 2), 0);  // renumbered: the wedge is now part 1
  EXPECT_GT(std::count(tp.begin(), tp.end(), 1), 0);
  EXPECT_EQ(std::set<std::int32_t>(tp.begin(), tp.end()).size(), 2u);
}

TEST(Ppm, BentInterfacesShareTheirBreakPointsAndStitch) {
  // With a cheap label change the labelling bends interfaces; each side then takes the other's break points,
  // so the stitched mesh stays conforming. Straight interfaces give fewer break points on the same partition.
  for (const auto& [name, h, k] : {std::make_tuple("letter_R", 2.0, 3), std::make_tuple("pentagon", 3.0, 5)}) {
    auto [tri, tp] = partitioned(name, h, k);
    PolysquareMapOptions o;
    o.size = h;
    o.layout.interface_change_cost = 0.5;
    PartMapStats straight, bent;
    map_piecewise(tri, tp, k, o, name, straight);
    o.layout.straight_interfaces = false;
    const QuadMesh m = map_piecewise(tri, tp, k, o, name, bent);
    EXPECT_GT(bent.break_points, straight.break_points) << name;
    // Conforming: no edge in three quads, and the only edges in one quad are the tagged ring edges (a node
    // missing on one side of an interface would leave untagged open edges there).
    const QualityReport q = compute_quality(m);
    EXPECT_EQ(q.non_manifold_edges, 0u) << name;
    EXPECT_EQ(q.boundary_edges, m.boundary_edges.size()) << name;
  }
}

TEST(InterfaceQuantization, EachLayoutAloneIsQuantizedOncePerRun) {
  // With a memo (the pipeline sets one per run), a layout met again (a later joint map, a re-solve, a repair
  // round) takes its quantization alone from it: the same joint result, and the same refusal of layouts that
  // cannot close, without solving them again; a layout that differs (here one side's target) is solved anew.
  RectLayout A = rectangle({0, 0}, {4.3, 6.2}, {2.4}), B = rectangle({0, 0}, {5.1, 2.6}), C = rectangle({0, 0}, {5.4, 3.6});
  const std::vector<SegmentCoupling> couplings{{0, 1, 2, 3}, {0, 2, 1, 3}, {1, 0, 2, 2}};
  auto solve = [&](const QuantizeOptions& o, RectLayout a, RectLayout b, RectLayout c) {
    quantize_layouts({&a.layout, &b.layout, &c.layout}, {&a.deformed, &b.deformed, &c.deformed}, couplings, o, "T");
    return std::vector<std::vector<std::array<long long, 2>>>{a.layout.lattice, b.layout.lattice, c.layout.lattice};
  };
  QuantizeOptions with_memo;
  with_memo.memo = std::make_shared<QuantizeMemo>();
  const auto plain = solve(QuantizeOptions{}, A, B, C);
  EXPECT_EQ(solve(with_memo, A, B, C), plain);
  EXPECT_EQ(with_memo.memo->hits(), 0u);
  EXPECT_EQ(solve(with_memo, A, B, C), plain);
  EXPECT_EQ(with_memo.memo->hits(), 1u);  // the whole joint quantization, met again
  RectLayout longer = B;
  longer.layout.segments[1].target += 0.5;
  EXPECT_EQ(solve(with_memo, A, longer, C), solve(QuantizeOptions{}, A, longer, C));
  EXPECT_EQ(with_memo.memo->hits(), 3u);  // a new joint program: A and C alone again; the changed B solved

  // A layout whose labels contradict each other is refused again from the memo, with the same reason.
  RectLayout bad = rectangle({0, 0}, {4, 3});
  bad.layout.segments[2].label = 0;
  std::vector<std::string> reasons;
  for (int run = 0; run < 2; ++run) {
    RectLayout a = A, b = bad;
    try {
      quantize_layouts({&a.layout, &b.layout}, {&a.deformed, &b.deformed}, {{0, 0, 1, 0}}, with_memo, "bad");
      ADD_FAILURE() << "a layout with contradictory labels was quantized";
    } catch (const LayoutsCannotClose& e) {
      EXPECT_EQ(e.layouts, std::vector<std::size_t>{1});
      reasons.push_back(e.reasons.at(0));
    }
  }
  ASSERT_EQ(reasons.size(), 2u);
  EXPECT_EQ(reasons[0], reasons[1]);
  // The first run's A belongs to another part (its messages name the part), so it is solved anew; the second
  // run replays the first's refusal.
  EXPECT_EQ(with_memo.memo->hits(), 3u + 1u);
}

TEST(InterfaceQuantization, AJointQuantizationSolvedAgainStartsFromTheSeparationsItEndedWith) {
  // U (6 x 4, a notch 2 wide and 3 deep from the top) closes alone without a separation; coupled to R (3 x 2),
  // its right side gets 3 elements, and the notch 3 deep would reach its bottom: the joint program needs a
  // separation that U alone does not. The layouts keep it, and a second solve of the same layouts starts from
  // it: with no separation rounds allowed it is valid at once, where fresh copies are not. (Programs this small
  // reuse separations only when told to: reuse_separations_sides 0.)
  const RectLayout U = polygon({{0, 0}, {6, 0}, {6, 4}, {4, 4}, {4, 1}, {2, 1}, {2, 4}, {0, 4}});
  const RectLayout R = rectangle({0, 0}, {3, 2});
  const std::vector<SegmentCoupling> couplings{{0, 1, 1, 3}};
  QuantizeOptions reuse;
  reuse.reuse_separations_sides = 0;
  RectLayout u = U, r = R;
  RectLayout by_default_u = U, by_default_r = R;
  quantize_layouts({&by_default_u.layout, &by_default_r.layout}, {&by_default_u.deformed, &by_default_r.deformed},
                   couplings, QuantizeOptions{}, "UR");
  EXPECT_TRUE(by_default_u.layout.separations.empty());
  quantize_layouts({&u.layout, &r.layout}, {&u.deformed, &r.deformed}, couplings, reuse, "UR");
  EXPECT_EQ(u.layout.lattice, by_default_u.layout.lattice);
  ASSERT_EQ(check_layout(u.layout), "");
  const auto right = [](const Layout& l) { return l.lattice[2][1] - l.lattice[1][1]; };
  ASSERT_EQ(right(u.layout), 3);  // the coupled count: the notch is 2 deep at most
  ASSERT_FALSE(u.layout.separations.empty());
  RectLayout alone = U;
  quantize_layout(alone.layout, alone.deformed, QuantizeOptions{}, "U");
  EXPECT_EQ(right(alone.layout), 4);  // alone, the notch keeps its 3 (no separation needed)
  EXPECT_TRUE(alone.layout.separations.empty());

  QuantizeOptions no_rounds = reuse;
  no_rounds.max_separation_rounds = 0;
  const auto first = u.layout.lattice;
  quantize_layouts({&u.layout, &r.layout}, {&u.deformed, &r.deformed}, couplings, no_rounds, "UR");
  EXPECT_EQ(check_layout(u.layout), "");
  EXPECT_EQ(u.layout.lattice, first);
  RectLayout fresh_u = U, fresh_r = R;
  quantize_layouts({&fresh_u.layout, &fresh_r.layout}, {&fresh_u.deformed, &fresh_r.deformed}, couplings, no_rounds, "UR");
  EXPECT_NE(check_layout(fresh_u.layout), "");  // the first solve alone leaves the notch on the bottom
}

TEST(InterfaceQuantization, ALayoutMetAgainInAnotherMapStartsFromItsSeparations) {
  // A new map of the part (a split round, a repair round) makes new layouts, most of them the same as before but
  // without separations of their own: through the memo, the same U starts from the separation its last joint
  // program ended with (U and R of the test above), and with no rounds allowed it is valid at once; with a
  // memo that never met U it is not.
  const RectLayout U = polygon({{0, 0}, {6, 0}, {6, 4}, {4, 4}, {4, 1}, {2, 1}, {2, 4}, {0, 4}});
  const RectLayout R = rectangle({0, 0}, {3, 2});
  const std::vector<SegmentCoupling> couplings{{0, 1, 1, 3}};
  QuantizeOptions reuse;
  reuse.reuse_separations_sides = 0;
  reuse.memo = std::make_shared<QuantizeMemo>();
  RectLayout u = U, r = R;
  quantize_layouts({&u.layout, &r.layout}, {&u.deformed, &r.deformed}, couplings, reuse, "UR");
  ASSERT_EQ(check_layout(u.layout), "");
  ASSERT_FALSE(u.layout.separations.empty());
  QuantizeOptions no_rounds = reuse;
  no_rounds.max_separation_rounds = 0;
  RectLayout again_u = U, again_r = R;
  ASSERT_TRUE(again_u.layout.separations.empty());
  quantize_layouts({&again_u.layout, &again_r.layout}, {&again_u.deformed, &again_r.deformed}, couplings, no_rounds, "UR");
  EXPECT_EQ(check_layout(again_u.layout), "");
  EXPECT_EQ(again_u.layout.lattice, u.layout.lattice);
  no_rounds.memo = std::make_shared<QuantizeMemo>();
  RectLayout new_u = U, new_r = R;
  quantize_layouts({&new_u.layout, &new_r.layout}, {&new_u.deformed, &new_r.deformed}, couplings, no_rounds, "UR");
  EXPECT_NE(check_layout(new_u.layout), "");
}

TEST(InterfaceQuantization, AJointQuantizationMetAgainIsReplayed) {
  // The repair rounds and the candidates quantize the same subregions again: with a memo the second time gives
  // the first's lattices, broken couplings (elastic) and refusal, without a solve; the elastic and the strict
  // program of the same layouts are two programs.
  RectLayout A = rectangle({0, 0}, {3, 2}), C = rectangle({0, 0}, {2, 3}, {1.5});
  const std::vector<SegmentCoupling> couplings{{0, 0, 1, 4}, {0, 0, 1, 1}, {0, 1, 1, 0}};  // cannot all agree
  QuantizeOptions with_memo;
  with_memo.memo = std::make_shared<QuantizeMemo>();
  std::vector<std::vector<std::array<long long, 2>>> lattices[2];
  std::vector<std::size_t> broken[2];
  for (int run = 0; run < 2; ++run) {
    RectLayout a = A, c = C;
    quantize_layouts({&a.layout, &c.layout}, {&a.deformed, &c.deformed}, couplings, with_memo, "AC", {}, &broken[run]);
    lattices[run] = {a.layout.lattice, c.layout.lattice};
  }
  EXPECT_EQ(with_memo.memo->hits(), 1u);
  EXPECT_EQ(lattices[1], lattices[0]);
  ASSERT_EQ(broken[0].size(), 1u);
  EXPECT_EQ(broken[1], broken[0]);
  std::string refusals[2];
  for (std::string& refusal : refusals) {
    RectLayout a = A, c = C;
    try {
      quantize_layouts({&a.layout, &c.layout}, {&a.deformed, &c.deformed}, couplings, with_memo, "AC");
      ADD_FAILURE() << "couplings that cannot agree were quantized";
    } catch (const MeshingError& e) {
      refusal = e.what();
    }
  }
  EXPECT_FALSE(refusals[0].empty());
  EXPECT_EQ(refusals[1], refusals[0]);
  // The strict program: its layouts alone from the elastic one's solve (2), then itself replayed (1).
  EXPECT_EQ(with_memo.memo->hits(), 4u);
}

TEST(InterfaceQuantization, AMapMetAgainSolvesOnlyWhatChangedAndItsNeighbours) {
  // Four 2 x 2 squares in a row, each right side coupled to the next one's left: one height for all, 2. A later
  // map replaces the last one by a 2 x 20 rectangle. The whole program would now give the row a larger height (2
  // is far below the band of the tall one's sides); solved locally (the new layout and its neighbour, their
  // side towards the rest taking the count it had), the row keeps 2, every layout is valid and the untouched ones
  // keep their lattices.
  std::vector<RectLayout> row(4, rectangle({0, 0}, {2, 2}));
  std::vector<SegmentCoupling> couplings;
  for (std::size_t i = 0; i + 1 < row.size(); ++i) couplings.push_back({i, 1, i + 1, 3});
  const auto height = [](const Layout& l) { return l.lattice[2][1] - l.lattice[1][1]; };
  auto quantize = [&](std::vector<RectLayout>& rs, const QuantizeOptions& o) {
    std::vector<Layout*> layouts;
    std::vector<const std::vector<Vec2>*> deformed;
    for (RectLayout& r : rs) layouts.push_back(&r.layout), deformed.push_back(&r.deformed);
    quantize_layouts(layouts, deformed, couplings, o, "row");
  };
  QuantizeOptions o;
  o.reuse_separations_sides = 0;  // these small programs count as large ones
  o.localize_max_fraction = 0.5;  // the piece: 2 of the 4 layouts
  o.memo = std::make_shared<QuantizeMemo>();
  std::vector<RectLayout> first = row;
  quantize(first, o);
  for (const RectLayout& r : first) ASSERT_EQ(height(r.layout), 2);

  std::vector<RectLayout> second = row;
  second.back() = rectangle({0, 0}, {2, 20});
  std::vector<RectLayout> whole = second;
  quantize(second, o);
  for (std::size_t i = 0; i < second.size(); ++i) {
    EXPECT_EQ(height(second[i].layout), 2) << i;
    EXPECT_EQ(check_layout(second[i].layout), "") << i;
    if (i + 2 < second.size()) EXPECT_EQ(second[i].layout.lattice, first[i].layout.lattice) << i;
  }
  // The whole program: without localizing, or with a piece above the default fraction (0.3) of the sides.
  QuantizeOptions all = o;
  all.localize_rings = -1;
  QuantizeOptions capped = o;
  capped.localize_max_fraction = QuantizeOptions{}.localize_max_fraction;
  for (const QuantizeOptions& w : {all, capped}) {
    QuantizeOptions fresh = w;
    fresh.memo = std::make_shared<QuantizeMemo>();
    first = row;
    quantize(first, fresh);
    std::vector<RectLayout> again = whole;
    quantize(again, fresh);
    for (const RectLayout& r : again) {
      EXPECT_GT(height(r.layout), 2);
      EXPECT_EQ(height(r.layout), height(again.front().layout));
    }
  }
}
