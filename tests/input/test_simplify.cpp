// Topology-preserving simplification of curves finer than the target size.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "polysquare/core/error.h"
#include "polysquare/input/read_region.h"
#include "polysquare/input/simplify.h"
#include "polysquare/input/snap_points.h"

using namespace polysquare;

TEST(Simplify, CoastlineLosesVerticesKeepsValidityAndStaysClose) {
  const Region original = read_region(std::string(POLYSQUARE_DATA_DIR) + "/cases/delta_water.geojson");
  Region r = original;
  SimplifyOptions o;
  o.min_area = 100.0 * 100.0;  // (0.5 h)^2 at h = 200 m
  const SimplifyStats st = simplify_region(r, o);
  EXPECT_LT(st.vertices_after, st.vertices_before * 3 / 4);
  ASSERT_EQ(r.rings.size(), original.rings.size());
  for (const Ring& ring : r.rings) EXPECT_GE(ring.points.size(), 3u);
  // Still a valid region: no crossing or touching rings, holes inside their part.
  EXPECT_NO_THROW(validate_region(r));
  // Every surviving vertex is an original vertex.
  for (std::size_t k = 0; k < r.rings.size(); ++k)
    for (Vec2 p : r.rings[k].points)
      EXPECT_NE(std::find(original.rings[k].points.begin(), original.rings[k].points.end(), p), original.rings[k].points.end());
}

TEST(Simplify, ZeroAreaThresholdChangesNothingAndSharedVerticesStay) {
  Region r;
  r.source = "test";
  r.num_parts = 1;
  r.rings.push_back({{{0, 0}, {5, 0.001}, {10, 0}, {10, 10}, {0, 10}}, 0, false, 0});
  r.features.push_back({{{5, 0.001}, {5, 5}}, false, 1});
  Region same = r;
  EXPECT_EQ(simplify_region(same, {}).vertices_after, 7u);
  SimplifyOptions o;
  o.min_area = 1.0;
  simplify_region(r, o);
  // (5, 0.001) is nearly collinear but a feature ends there: it stays.
  EXPECT_EQ(r.rings[0].points.size(), 5u);
}

// Collinear vertices have a zero-area triangle and are removed first; the next vertex of a straight run lies on
// the line of the removed one's triangle but not on the triangle (a segment then), so it must not block the
// removal (it did: a square with 1,000 points per side kept all 4,000 and took 25-38 s to mesh into 100 quads).
TEST(Simplify, CollinearRunsGoDownToTheirCornersAndAPointOnTheRunStillBlocks) {
  Region r;
  r.source = "test";
  r.num_parts = 1;
  std::vector<Vec2> pts;
  for (int side = 0; side < 4; ++side)
    for (int k = 0; k < 100; ++k) {
      const double t = k / 100.0;
      const Vec2 corners[4] = {{0, 0}, {100, 0}, {100, 100}, {0, 100}};
      pts.push_back(corners[side] + t * (corners[(side + 1) % 4] - corners[side]));
    }
  r.rings.push_back({pts, 0, false, 0});
  SimplifyOptions o;
  o.min_area = 25.0;
  const SimplifyStats st = simplify_region(r, o);
  EXPECT_EQ(st.vertices_after, 4u);
  EXPECT_EQ(st.refused, 0u);
  ASSERT_EQ(r.rings[0].points.size(), 4u);
  for (Vec2 p : r.rings[0].points) EXPECT_TRUE((p.x == 0 || p.x == 100) && (p.y == 0 || p.y == 100)) << p.x << " " << p.y;
  // A vertex of another ring lying on the straight run between the kept ends still blocks the shortcut.
  Region h;
  h.source = "test";
  h.num_parts = 1;
  h.rings.push_back({{{0, 0}, {50, 0}, {100, 0}, {100, 100}, {0, 100}}, 0, false, 0});
  h.features.push_back({{{25, 0}, {25, 50}}, false, 1});  // its end lies on the segment from (0, 0) to (50, 0)
  SimplifyOptions ho;
  ho.min_area = 25.0;
  simplify_region(h, ho);
  EXPECT_NE(std::find(h.rings[0].points.begin(), h.rings[0].points.end(), Vec2{50, 0}), h.rings[0].points.end());
}

TEST(Simplify, ReportsHowFarTheRemovedVerticesLie) {
  // A square whose bottom side has a bump 0.3 high at x = 4 and 0.1 high at x = 7: with a threshold above both
  // triangles' areas both go, and the largest distance is the higher bump's, measured to the new bottom side.
  Region r;
  r.source = "test";
  r.num_parts = 1;
  r.rings.push_back({{{0, 0}, {4, 0.3}, {7, 0.1}, {10, 0}, {10, 10}, {0, 10}}, 0, false, 0});
  SimplifyOptions o;
  o.min_area = 2.0;
  const SimplifyStats st = simplify_region(r, o);
  ASSERT_EQ(r.rings[0].points.size(), 4u);
  EXPECT_NEAR(st.max_distance, 0.3, 1e-12);
  Region kept = r;
  EXPECT_EQ(simplify_region(kept, {}).max_distance, 0.0);
}

TEST(Simplify, KeepsEveryInputVertexWithinTheDistanceBound) {
  // The same bumps with a bound of 0.2: the 0.1 bump may go, the 0.3 one may not (neither alone nor after it).
  Region r;
  r.source = "test";
  r.num_parts = 1;
  r.rings.push_back({{{0, 0}, {4, 0.3}, {7, 0.1}, {10, 0}, {10, 10}, {0, 10}}, 0, false, 0});
  SimplifyOptions o;
  o.min_area = 2.0;
  o.max_distance = 0.2;
  const SimplifyStats st = simplify_region(r, o);
  EXPECT_NE(std::find(r.rings[0].points.begin(), r.rings[0].points.end(), Vec2{4, 0.3}), r.rings[0].points.end());
  EXPECT_LE(st.max_distance, 0.2);
  EXPECT_EQ(r.rings[0].points.size(), 5u);
}

namespace {
std::size_t corners_over(const Region& r, double degrees) {
  std::size_t n = 0;
  auto count = [&](const std::vector<Vec2>& p, bool closed) {
    const std::size_t m = p.size();
    for (std::size_t i = 0; i < m; ++i) {
      if (!closed && (i == 0 || i + 1 == m)) continue;
      const Vec2 u = p[i] - p[(i + m - 1) % m], w = p[(i + 1) % m] - p[i];
      n += std::abs(std::atan2(cross(u, w), dot(u, w))) > degrees * 3.14159265358979323846 / 180.0;
    }
  };
  for (const Ring& ring : r.rings) count(ring.points, true);
  for (const FeatureCurve& c : r.features) count(c.points, c.closed);
  return n;
}
double farthest_from(const std::vector<Vec2>& from, const std::vector<Vec2>& line, bool closed) {
  double worst = 0.0;
  for (Vec2 q : from) {
    double d = INFINITY;
    for (std::size_t i = 0; i + 1 < line.size() + (closed ? 1 : 0); ++i)
      d = std::min(d, point_segment_distance(q, line[i], line[(i + 1) % line.size()]));
    worst = std::max(worst, d);
  }
  return worst;
}
}  // namespace

// delta_box's shorelines are traced in steps of about 120 m turning 45 or 90 degrees at nearly every vertex: at
// 200 m each surviving step would be a corner of the poly-square. Smoothing first leaves a fraction of them,
// keeps the region valid, and every input vertex within the size of its curve.
TEST(Simplify, SmoothingTakesTheStepsOutOfATracedShorelineAndStaysWithinTheSize) {
  const Region original = read_region(std::string(POLYSQUARE_DATA_DIR) + "/cases/delta_box.geojson");
  SimplifyOptions o;
  o.min_area = 100.0 * 100.0;
  o.max_distance = o.max_segment = 200.0;
  Region plain = original;
  simplify_region(plain, o);
  o.smooth_distance = 100.0;
  Region smooth = original;
  const SimplifyStats st = simplify_region(smooth, o);
  const std::size_t before = corners_over(plain, 30.0), after = corners_over(smooth, 30.0);
  EXPECT_GT(before, 1000u);
  EXPECT_LT(after, before * 3 / 4) << before << " -> " << after;
  EXPECT_NO_THROW(validate_region(smooth));
  ASSERT_EQ(smooth.features.size(), original.features.size());
  double worst = 0.0;
  for (std::size_t k = 0; k < original.features.size(); ++k)
    worst = std::max(worst, farthest_from(original.features[k].points, smooth.features[k].points, smooth.features[k].closed));
  EXPECT_LE(worst, 200.0);
  EXPECT_GE(st.max_distance, worst - 1e-9);  // the report bounds it (each vertex to the segment that replaced it)
  EXPECT_LE(st.max_distance, 200.0);
}

// Smoothing moves zigzags only. A finely sampled circle turns gently everywhere, and a small octagonal island
// (an islet at the size) turns one way at every vertex: smoothing would only shrink them, so they keep their
// input points.
TEST(Simplify, SmoothingLeavesArcsAndSmallIslandsAlone) {
  Region r;
  r.source = "test";
  r.num_parts = 1;
  std::vector<Vec2> circle, octagon;
  for (int k = 0; k < 160; ++k) circle.push_back({40.0 * std::cos(k * 2 * M_PI / 160), 40.0 * std::sin(k * 2 * M_PI / 160)});
  for (int k = 0; k < 8; ++k) octagon.push_back({2.0 * std::cos(k * 2 * M_PI / 8), 2.0 * std::sin(k * 2 * M_PI / 8)});
  r.rings.push_back({circle, 0, false, 0});
  r.rings.push_back({octagon, 0, true, 1});
  SimplifyOptions o;
  o.min_area = 1e-6;
  o.max_distance = o.max_segment = 2.5;
  o.smooth_distance = 1.25;
  simplify_region(r, o);
  ASSERT_EQ(r.rings[1].points.size(), 8u);
  for (Vec2 p : r.rings[0].points) EXPECT_NE(std::find(circle.begin(), circle.end(), p), circle.end()) << p.x << " " << p.y;
  for (Vec2 p : r.rings[1].points) EXPECT_NE(std::find(octagon.begin(), octagon.end(), p), octagon.end()) << p.x << " " << p.y;
  // A zigzag along a straight shore (steps of 1 turning 45 degrees each way) does move, within the bound.
  Region z;
  z.source = "test";
  z.num_parts = 1;
  std::vector<Vec2> saw{{0, 0}};
  for (int k = 1; k <= 20; ++k) saw.push_back({static_cast<double>(k), k % 2 ? 0.5 : 0.0});
  saw.push_back({20, 10});
  saw.push_back({0, 10});
  z.rings.push_back({saw, 0, false, 0});
  SimplifyOptions zo = o;
  zo.min_area = 1e-6;
  const SimplifyStats st = simplify_region(z, zo);
  std::size_t moved = 0;
  for (Vec2 p : z.rings[0].points) moved += std::find(saw.begin(), saw.end(), p) == saw.end();
  EXPECT_GT(moved, 10u);
  EXPECT_LE(st.max_distance, 2.5);
  EXPECT_NO_THROW(validate_region(z));
}

TEST(NarrowIslands, InscribedWidthOfKnownShapes) {
  // A 4 x 1 rectangle holds a disk of diameter 1; an L of two 1-wide arms one touching both outer walls and the
  // inner corner (centre (c, c), c = sqrt 2 (1 - c)); a 3-4-5 right triangle its incircle, diameter 3 + 4 - 5.
  EXPECT_NEAR(inscribed_width({{0, 0}, {4, 0}, {4, 1}, {0, 1}}, 1e-4), 1.0, 1e-3);
  EXPECT_NEAR(inscribed_width({{0, 0}, {5, 0}, {5, 1}, {1, 1}, {1, 5}, {0, 5}}, 1e-4),
              2.0 * std::sqrt(2.0) / (1.0 + std::sqrt(2.0)), 1e-3);
  EXPECT_NEAR(inscribed_width({{0, 0}, {4, 0}, {0, 3}}, 1e-4), 2.0, 1e-3);
  // Clockwise rings give the same answer; the early stop returns as soon as `enough` is reached.
  EXPECT_NEAR(inscribed_width({{0, 1}, {4, 1}, {4, 0}, {0, 0}}, 1e-4), 1.0, 1e-3);
  EXPECT_GE(inscribed_width({{0, 0}, {40, 0}, {40, 40}, {0, 40}}, 1e-4, 2.0), 2.0);
  // Narrower than `enough`: within enough / 10, below it, whatever the tolerance asked (a 100,000 x 1 channel).
  const double channel = inscribed_width({{0, 0}, {1e5, 0}, {1e5, 1}, {0, 1}}, 1e-4, 2.0);
  EXPECT_LT(channel, 2.0);
  EXPECT_NEAR(channel, 1.0, 0.2);
}

TEST(NarrowIslands, NarrowHolesAndLoopsGoWideOnesAndTouchedOnesStay) {
  Region r;
  r.source = "test";
  r.num_parts = 1;
  r.rings.push_back({{{0, 0}, {100, 0}, {100, 100}, {0, 100}}, 0, false, 0});
  r.rings.push_back({{{10, 10}, {10, 10.8}, {30, 10.8}, {30, 10}}, 0, true, 1});  // 0.8 wide: goes
  r.rings.push_back({{{50, 50}, {50, 55}, {55, 55}, {55, 50}}, 0, true, 2});      // 5 wide: stays
  r.rings.push_back({{{70, 10}, {70, 10.5}, {90, 10.5}, {90, 10}}, 0, true, 3});  // narrow, but a feature ends on it
  r.features.push_back({{{70, 10.5}, {70, 40}}, false, 4});
  r.features.push_back({{{10, 80}, {30, 80}, {30, 80.9}, {10, 80.9}}, true, 5});  // narrow loop: goes
  r.features.push_back({{{60, 80}, {80, 80}, {80, 90}, {60, 90}}, true, 6});      // wide loop: stays
  r.features.push_back({{{10, 60}, {30, 60}, {30, 60.5}, {10, 60.5}}, true, 7});  // narrow, holds a feature point
  r.feature_points.push_back({20, 60.25});
  const std::vector<DroppedCurve> d = drop_narrow_islands(r, 1.0);
  ASSERT_EQ(d.size(), 2u);
  EXPECT_EQ(d[0].kind, DroppedCurve::Kind::hole);
  EXPECT_EQ(d[0].source_feature, 1);
  EXPECT_NEAR(d[0].width, 0.8, 0.02);
  EXPECT_NEAR(d[0].area, 16.0, 1e-9);
  EXPECT_EQ(d[1].kind, DroppedCurve::Kind::feature_loop);
  EXPECT_EQ(d[1].source_feature, 5);
  ASSERT_EQ(r.rings.size(), 3u);
  EXPECT_EQ(r.rings[1].source_feature, 2);
  EXPECT_EQ(r.rings[2].source_feature, 3);
  ASSERT_EQ(r.features.size(), 3u);
  EXPECT_EQ(r.features[1].source_feature, 6);
  EXPECT_NO_THROW(validate_region(r));
  // A zero width removes nothing.
  Region same = r;
  EXPECT_TRUE(drop_narrow_islands(same, 0.0).empty());
  EXPECT_EQ(same.rings.size(), 3u);
}

TEST(NarrowFaces, ARiverCrossingAShorelineTwiceCloseByLosesOnePieceOfTheSliver) {
  // Pieces as validation leaves them: a shoreline along y = 50 and a river crossing it at x = 50 and x = 52,
  // between the crossings 0.3 above it: the sliver between them is far narrower than 1.
  Region r;
  r.source = "test";
  r.num_parts = 1;
  r.rings.push_back({{{0, 0}, {100, 0}, {100, 100}, {0, 100}}, 0, false, 0});
  r.rings[0].points = {{0, 0}, {50, 0}, {100, 0}, {100, 50}, {100, 100}, {52, 100}, {0, 100}, {0, 50}};
  r.features.push_back({{{0, 50}, {50, 50}}, false, 1});
  r.features.push_back({{{50, 50}, {52, 50}}, false, 1});
  r.features.push_back({{{52, 50}, {100, 50}}, false, 1});
  r.features.push_back({{{50, 0}, {50, 50}}, false, 2});
  r.features.push_back({{{50, 50}, {51, 50.3}, {52, 50}}, false, 2});
  r.features.push_back({{{52, 50}, {52, 100}}, false, 2});
  ASSERT_NO_THROW(validate_region(r));
  const std::size_t before = r.features.size();
  Region wide = r;
  EXPECT_TRUE(collapse_narrow_faces(wide, 0.2).empty());  // the sliver is 0.3 high at most: wider than 0.2
  const std::vector<DroppedCurve> d = collapse_narrow_faces(r, 1.0);
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].kind, DroppedCurve::Kind::feature_piece);
  EXPECT_LT(d[0].width, 0.3);
  EXPECT_NEAR(d[0].area, 0.3, 1e-9);  // the triangle (50, 50), (51, 50.3), (52, 50)
  EXPECT_LE(d[0].distance, 0.3);
  ASSERT_EQ(r.features.size(), before - 1);
  // The piece that went is one side of the sliver; the large faces around it kept all their pieces.
  for (const FeatureCurve& c : r.features) EXPECT_GE(c.points.size(), 2u);
  EXPECT_NO_THROW(validate_region(r));
  EXPECT_TRUE(collapse_narrow_faces(r, 1.0).empty());
}

TEST(NarrowFaces, DeltaBoxSliversGoAndNothingNarrowIsLeft) {
  Region r = read_region(std::string(POLYSQUARE_DATA_DIR) + "/cases/delta_box.geojson");
  const std::size_t before = r.features.size();
  const std::vector<DroppedCurve> d = collapse_narrow_faces(r, 200.0);
  EXPECT_GE(d.size(), 3u);  // the shoreline/river crossings within a fraction of 200 m of each other
  EXPECT_EQ(r.features.size(), before - d.size());
  for (const DroppedCurve& c : d) {
    EXPECT_LT(c.width, 200.0);
    EXPECT_LE(c.distance, 200.0);
  }
  EXPECT_NO_THROW(validate_region(r));
  EXPECT_TRUE(collapse_narrow_faces(r, 200.0).empty());
}

TEST(NarrowIslands, DeltaBoxIslandLoopsNarrowerThanTheSizeGo) {
  // delta_box's islands are closed shoreline features; at 200 m a dozen of them hold no 200 m disk.
  Region r = read_region(std::string(POLYSQUARE_DATA_DIR) + "/cases/delta_box.geojson");
  std::size_t loops = 0;
  for (const FeatureCurve& c : r.features) loops += c.closed;
  const std::vector<DroppedCurve> d = drop_narrow_islands(r, 200.0);
  EXPECT_GE(d.size(), 10u);
  for (const DroppedCurve& c : d) {
    EXPECT_EQ(c.kind, DroppedCurve::Kind::feature_loop);
    EXPECT_LT(c.width, 200.0);
  }
  std::size_t left = 0;
  for (const FeatureCurve& c : r.features) left += c.closed;
  EXPECT_EQ(left, loops - d.size());
  EXPECT_GT(left, 0u);  // the wider islands stay
  EXPECT_NO_THROW(validate_region(r));
  EXPECT_TRUE(drop_narrow_islands(r, 200.0).empty());
}

TEST(NarrowWedges, ARiverLeavingAShorelineAtFiveDegreesLeavesItWhereTheyAreTheSizeApart) {
  // A shoreline along y = 50 and a river leaving it at (50, 50) at about 5 degrees, 1.8 above it at x = 70,
  // then turning north at x = 75 to the boundary: at size 5 the wedge between them holds no quad.
  Region r;
  r.source = "test";
  r.num_parts = 1;
  r.rings.push_back({{{0, 0}, {100, 0}, {100, 50}, {100, 100}, {75, 100}, {0, 100}, {0, 50}}, 0, false, 0});
  r.features.push_back({{{0, 50}, {50, 50}}, false, 1});
  r.features.push_back({{{50, 50}, {100, 50}}, false, 1});
  r.features.push_back({{{50, 50}, {60, 50.9}, {70, 51.8}, {75, 60}, {75, 100}}, false, 2});
  ASSERT_NO_THROW(validate_region(r));
  Region wide = r;
  EXPECT_TRUE(open_narrow_wedges(wide, 5.0, 3.0).empty());  // 5 degrees is not below 3
  const std::vector<DroppedCurve> d = open_narrow_wedges(r, 5.0);
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].kind, DroppedCurve::Kind::wedge_stretch);
  EXPECT_EQ(d[0].source_feature, 2);
  EXPECT_NEAR(d[0].distance, 1.8, 1e-9);  // the farthest removed vertex from the shoreline
  // The river now leaves the shoreline at the foot of (75, 60), straight north; the shoreline is cut there.
  ASSERT_EQ(r.features.size(), 4u);
  EXPECT_EQ(r.features[2].points.front(), (Vec2{75, 50}));
  EXPECT_EQ(r.features[2].points[1], (Vec2{75, 60}));
  EXPECT_EQ(r.features[1].points.back(), (Vec2{75, 50}));
  EXPECT_EQ(r.features[3].points.front(), (Vec2{75, 50}));
  EXPECT_EQ(r.features[3].points.back(), (Vec2{100, 50}));
  EXPECT_NO_THROW(validate_region(r));
  EXPECT_TRUE(open_narrow_wedges(r, 5.0).empty());
}

TEST(SnapNearCoincident, AStubThatSnapsOntoItsOtherEndGoesAndIsSaid) {
  // A curve along y = 60 in two pieces meeting at (30, 60), and a 0.5-long stub from (30.4, 60.3) to that node: with
  // a snap distance of 1 its free end snaps onto the node, the stub has no length left and is left out, said in a
  // note (a zero-length constraint crashed the triangulation of delta_box at 2000 m).
  Region r;
  r.source = "test";
  r.num_parts = 1;
  r.rings.push_back({{{0, 0}, {100, 0}, {100, 60}, {100, 100}, {0, 100}, {0, 60}}, 0, false, 0});
  r.features.push_back({{{0, 60}, {30, 60}}, false, 1});
  r.features.push_back({{{30, 60}, {100, 60}}, false, 1});
  r.features.push_back({{{30.4, 60.3}, {30, 60}}, false, 2});
  std::vector<std::string> notes;
  snap_near_coincident(r, 1.0 / r.bounding_box().diagonal(), &notes);
  ASSERT_EQ(r.features.size(), 2u);
  for (const FeatureCurve& c : r.features)
    for (std::size_t i = 0; i + 1 < c.points.size(); ++i) EXPECT_FALSE(c.points[i] == c.points[i + 1]);
  bool said = false;
  for (const std::string& n : notes) said = said || n.find("feature 2") != std::string::npos && n.find("left out") != std::string::npos;
  EXPECT_TRUE(said);
  EXPECT_NO_THROW(validate_region(r));
}
