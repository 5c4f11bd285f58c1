// Feature curves are cut at crossings and clipped to the domain; afterwards they meet only at end points.
#include <gtest/gtest.h>

#include <algorithm>

#include "polysquare/core/error.h"
#include "polysquare/input/read_region.h"
#include "polysquare/input/split_features.h"

using namespace polysquare;

namespace {
Region square_with(std::vector<FeatureCurve> features) {
  Region r;
  r.source = "test";
  r.num_parts = 1;
  r.rings.push_back({{{0, 0}, {10, 0}, {10, 10}, {0, 10}}, 0, false, 0});
  r.features = std::move(features);
  return r;
}
bool has_point(const std::vector<Vec2>& pts, Vec2 p) { return std::find(pts.begin(), pts.end(), p) != pts.end(); }

}  // namespace

TEST(SplitFeatures, CrossingCurvesBecomeFourPiecesSharingTheCrossing) {
  Region r = square_with({{{{2, 2}, {8, 8}}, false, 1}, {{{2, 8}, {8, 2}}, false, 2}});
  const FeatureSplitStats st = split_features(r);
  EXPECT_EQ(r.features.size(), 4u);
  EXPECT_GE(st.crossings, 1u);
  for (const FeatureCurve& c : r.features) {
    EXPECT_TRUE(c.points.front() == (Vec2{5, 5}) || c.points.back() == (Vec2{5, 5}));
    EXPECT_TRUE(c.source_feature == 1 || c.source_feature == 2);
  }
}

TEST(SplitFeatures, CurveCrossingTheBoundaryIsClippedAndTheRingGainsTheVertex) {
  Region r = square_with({{{{5, 5}, {15, 5}}, false, 1}});
  split_features(r);
  ASSERT_EQ(r.features.size(), 1u);
  EXPECT_EQ(r.features[0].points.back(), (Vec2{10, 5}));
  EXPECT_TRUE(has_point(r.rings[0].points, {10, 5}));
  EXPECT_EQ(r.rings[0].points.size(), 5u);
}

TEST(SplitFeatures, UntouchedLoopStaysClosedAndOutsideCurveIsRefused) {
  Region r = square_with({{{{3, 3}, {6, 3}, {6, 6}, {3, 6}}, true, 1}});
  split_features(r);
  ASSERT_EQ(r.features.size(), 1u);
  EXPECT_TRUE(r.features[0].closed);
  Region outside = square_with({{{{20, 20}, {30, 30}}, false, 7}});
  try {
    split_features(outside);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("feature 7"), std::string::npos) << e.what();
  }
}

TEST(SplitFeatures, CurveAlongTheBoundaryIsDropped) {
  Region r = square_with({{{{0, 2}, {0, 8}}, false, 1}, {{{1, 1}, {2, 2}}, false, 2}});
  const FeatureSplitStats st = split_features(r);
  EXPECT_EQ(r.features.size(), 1u);
  EXPECT_GE(st.pieces_dropped, 1u);
}

TEST(SplitFeatures, DeltaBoxCurvesMeetOnlyAtEndPoints) {
  const Region r = read_region(std::string(POLYSQUARE_DATA_DIR) + "/cases/delta_box.geojson");
  ASSERT_GT(r.features.size(), 72u);
  std::vector<std::array<Vec2, 2>> segs;
  for (const FeatureCurve& c : r.features)
    for (std::size_t i = 0; i + 1 < c.points.size() + (c.closed ? 1 : 0); ++i)
      segs.push_back({c.points[i], c.points[(i + 1) % c.points.size()]});
  const auto& ring = r.rings[0].points;
  for (std::size_t i = 0; i < ring.size(); ++i) segs.push_back({ring[i], ring[(i + 1) % ring.size()]});
  std::size_t crossings = 0;
  for (std::size_t i = 0; i < segs.size(); ++i)
    for (std::size_t j = i + 1; j < segs.size(); ++j)
      crossings += segments_cross(segs[i][0], segs[i][1], segs[j][0], segs[j][1]);
  EXPECT_EQ(crossings, 0u);
  // Every curve end point on the boundary is a ring vertex.
  for (const FeatureCurve& c : r.features)
    for (Vec2 e : {c.points.front(), c.points.back()})
      for (std::size_t i = 0; i < ring.size(); ++i)
        if (point_segment_distance(e, ring[i], ring[(i + 1) % ring.size()]) < 1e-6) EXPECT_TRUE(has_point(ring, e));
}
