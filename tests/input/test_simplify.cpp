// Topology-preserving simplification of curves finer than the target size.
#include <gtest/gtest.h>

#include "polysquare/core/error.h"
#include "polysquare/input/read_region.h"
#include "polysquare/input/simplify.h"

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
