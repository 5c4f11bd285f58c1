// pin_chords_clear_of_curves (issue 13, class 1): ring vertices become mesh nodes where a boundary chord could
// cross another curve, and only there; with them, the close-ring cases of tests/data/adversarial mesh without
// overlapping quads.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "polysquare/input/chord_clearance.h"
#include "polysquare/input/read_region.h"
#include "polysquare/input/simplify.h"
#include "polysquare/pipeline/invariants.h"
#include "polysquare/pipeline/mesh_region.h"

using namespace polysquare;

namespace {

std::string adversarial(const std::string& name) { return std::string(POLYSQUARE_TEST_DATA_DIR) + "/adversarial/" + name; }

// The curves as mesh_region simplifies them at `size` (default options), pins left out.
Region simplified(const std::string& name, double size) {
  Region region = read_region(adversarial(name + ".geojson"));
  SimplifyOptions so;
  so.min_area = (0.5 * size) * (0.5 * size);
  so.max_distance = size;
  so.max_segment = size;
  so.chord_reach = 0.0;
  simplify_region(region, so);
  return region;
}

bool on_ring(const Region& region, std::size_t r, Vec2 p) {
  for (Vec2 q : region.rings[r].points)
    if (q == p) return true;
  return false;
}

}  // namespace

TEST(ChordClearance, ConvexRingsFacingEachOtherAndStraightRingsGetNoPin) {
  Region disks = simplified("parts_two_disks_gap_0_05", 2.0);
  EXPECT_TRUE(pin_chords_clear_of_curves(disks, 4.0).empty());
  Region square;
  square.rings.push_back({{{0, 0}, {10, 0}, {10, 10}, {0, 10}}, 0, false, -1, ""});
  square.num_parts = 1;
  EXPECT_TRUE(pin_chords_clear_of_curves(square, 4.0).empty());
  EXPECT_TRUE(square.feature_points.empty());
}

TEST(ChordClearance, OnlyTheConcaveRingFacingAnotherIsPinned) {
  for (const char* name : {"island_in_hole_gap_0_05", "island_in_hole_gap_0_01"}) {
    SCOPED_TRACE(name);
    Region region = simplified(name, 2.0);
    ASSERT_EQ(region.rings.size(), 3u);  // square, its circular hole, the island
    const std::size_t before = region.feature_points.size();
    const std::vector<Vec2> pins = pin_chords_clear_of_curves(region, 4.0);
    EXPECT_EQ(region.feature_points.size(), before + pins.size());
    ASSERT_FALSE(pins.empty());
    // Every pin is a vertex of the hole (its chords cut into the island); the island's chords cut into itself.
    for (Vec2 p : pins) EXPECT_TRUE(on_ring(region, 1, p)) << point_text(p);
    EXPECT_LE(pins.size(), region.rings[1].points.size());
  }
  Region notch = simplified("parts_disk_in_notch_gap_0_05", 2.0);
  const std::vector<Vec2> pins = pin_chords_clear_of_curves(notch, 4.0);
  ASSERT_FALSE(pins.empty());
  for (Vec2 p : pins) {
    EXPECT_TRUE(on_ring(notch, 0, p)) << point_text(p);
    EXPECT_LT(std::hypot(p.x, p.y - 20.0), 10.0 + 1e-9);  // on the notch's arc, not on the square's sides
  }
}

TEST(ChordClearance, SimplificationPinsAndTheCloseRingsMeshWithoutOverlap) {
  for (const char* name : {"island_in_hole_gap_0_05", "island_in_hole_gap_0_01", "parts_disk_in_notch_gap_0_05"}) {
    SCOPED_TRACE(name);
    // simplify_region pins by itself (chord_reach defaults to twice max_segment), as mesh_region calls it.
    Region region = read_region(adversarial(std::string(name) + ".geojson"));
    SimplifyOptions so;
    so.min_area = 1.0;
    so.max_distance = so.max_segment = 2.0;
    EXPECT_GT(simplify_region(region, so).chord_pins, 0u);
    MeshOptions options;
    options.size.h = 2.0;
    // Before the pins these meshes had 9 to 33 overlapping quad pairs and mesh_region refused them.
    const MeshResult result = mesh_region(read_region(adversarial(std::string(name) + ".geojson")), options);
    EXPECT_EQ(find_overlapping_quads(result.mesh).pairs, 0u);
    EXPECT_TRUE(check_invariants(result.mesh).ok()) << check_invariants(result.mesh).first_problem;
  }
}
