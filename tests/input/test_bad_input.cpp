// Every file of the bad-input corpus is rejected with an InputError that names the file and the problem.
#include <gtest/gtest.h>

#include <string>

#include "polysquare/core/error.h"
#include "polysquare/input/read_region.h"

using namespace polysquare;

struct BadCase {
  const char* file;
  const char* fragment;  // must appear in the message
};

class BadInput : public ::testing::TestWithParam<BadCase> {};

TEST_P(BadInput, IsRejectedWithAClearMessage) {
  const BadCase c = GetParam();
  const std::string path = std::string(POLYSQUARE_TEST_DATA_DIR) + "/bad/" + c.file;
  try {
    read_region(path);
    FAIL() << c.file << " was accepted";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(c.file), std::string::npos) << msg;
    EXPECT_NE(msg.find(c.fragment), std::string::npos) << msg;
  }
}

INSTANTIATE_TEST_SUITE_P(
    Corpus, BadInput,
    ::testing::Values(BadCase{"unclosed_ring.geojson", "not closed: first point (0.000000, 0.000000)"},
                      BadCase{"bowtie.geojson", "intersects itself at (5, 5)"},
                      BadCase{"self_intersection.geojson", "intersects itself"},
                      BadCase{"nan.geojson", "not valid JSON"},
                      BadCase{"infinite.geojson", "number overflow"},
                      BadCase{"huge.geojson", "coordinate beyond"},
                      BadCase{"hole_outside.geojson", "ring 1 is a hole outside its polygon, at (2"},
                      BadCase{"empty_collection.geojson", "no domain"},
                      BadCase{"feature_outside.geojson", "feature 1 (curve 0) lies outside the domain, at (25, 25)"},
                      BadCase{"truncated.geojson", "not valid JSON"},
                      BadCase{"wrong_type.geojson", "feature 0: a domain must be a Polygon or MultiPolygon, got Circle"},
                      BadCase{"zero_area.geojson", "zero area"},
                      BadCase{"overlapping_parts.geojson", "meets ring"},
                      BadCase{"binary_garbage.geojson", "not valid JSON"},
                      BadCase{"no_domain.geojson", "no domain"},
                      BadCase{"not_numbers.geojson", "feature 0: a position must be an array of at least two numbers"},
                      BadCase{"duplicate_points.geojson", "repeats the point (10, 0)"},
                      BadCase{"feature_crossing_hole.geojson", "feature 1 (curve 0) crosses a hole at (8, 10)"},
                      BadCase{"hole_touching_part.geojson", "meets ring"},
                      BadCase{"hole_crossing_part.geojson", "meets ring 0 at (20, 10)"}),
    [](const auto& info) {
      std::string n = info.param.file;
      return n.substr(0, n.find('.'));
    });

TEST(ReadRegion, EveryBundledCaseReadsWithNormalizedOrientation) {
  for (const char* name : {"letter_I", "letter_M", "letter_R", "pentagon", "triangle", "square_feature", "rect_feature",
                           "smile", "turtle_shell", "mechanical_part", "dam_channel", "key", "delta_water"}) {
    const Region r = read_region(std::string(POLYSQUARE_DATA_DIR) + "/cases/" + name + ".geojson");
    ASSERT_GT(r.rings.size(), 0u) << name;
    for (const Ring& ring : r.rings) {
      double a = 0;
      for (std::size_t i = 0; i < ring.points.size(); ++i) a += cross(ring.points[i], ring.points[(i + 1) % ring.points.size()]);
      EXPECT_EQ(a > 0, !ring.hole) << name;  // outer counter-clockwise, holes clockwise
    }
  }
}

TEST(ReadRegion, HoleAndPartCounts) {
  auto holes = [](const Region& r) { int n = 0; for (const Ring& x : r.rings) n += x.hole; return n; };
  const std::string d = std::string(POLYSQUARE_DATA_DIR) + "/cases/";
  EXPECT_EQ(holes(read_region(d + "letter_R.geojson")), 1);
  EXPECT_EQ(holes(read_region(d + "key.geojson")), 1);
  EXPECT_EQ(holes(read_region(d + "mechanical_part.geojson")), 2);
  EXPECT_EQ(read_region(d + "delta_water.geojson").num_parts, 11);
  EXPECT_EQ(read_region(d + "delta_water.geojson").crs, "EPSG:32616");
}

TEST(ReadRegion, UnsupportedExtensionAndMissingFile) {
  EXPECT_THROW(read_region("region.shp"), InputError);
  EXPECT_THROW(read_region(std::string(POLYSQUARE_TEST_DATA_DIR) + "/bad/does_not_exist.geojson"), InputError);
}

TEST(Repair, DropsRepeatedPointsAndClipsFeaturesInHolesAndSaysSo) {
  InputOptions o;
  o.repair = true;
  std::vector<std::string> repairs;
  const Region a = read_region(std::string(POLYSQUARE_TEST_DATA_DIR) + "/bad/duplicate_points.geojson", o, &repairs);
  EXPECT_EQ(a.rings[0].points.size(), 4u);
  ASSERT_EQ(repairs.size(), 1u);
  EXPECT_NE(repairs[0].find("(10, 0)"), std::string::npos) << repairs[0];
  repairs.clear();
  const Region b = read_region(std::string(POLYSQUARE_TEST_DATA_DIR) + "/bad/feature_crossing_hole.geojson", o, &repairs);
  EXPECT_EQ(b.features.size(), 2u);  // the pieces left and right of the hole
  ASSERT_EQ(repairs.size(), 1u);
  // A hole crossing its outer ring is made valid (GEOS): one polygon whose outer ring has a notch.
  repairs.clear();
  const Region c = read_region(std::string(POLYSQUARE_TEST_DATA_DIR) + "/bad/hole_crossing_part.geojson", o, &repairs);
  EXPECT_EQ(c.num_parts, 1);
  EXPECT_EQ(c.rings.size(), 1u);
  double area = 0;
  for (std::size_t i = 0; i < c.rings[0].points.size(); ++i)
    area += 0.5 * cross(c.rings[0].points[i], c.rings[0].points[(i + 1) % c.rings[0].points.size()]);
  EXPECT_NEAR(area, 400.0 - 25.0, 1e-9);
  ASSERT_EQ(repairs.size(), 1u);
  // What repair cannot fix is still refused: a bow-tie becomes two triangles that touch at one point, and NaN.
  EXPECT_THROW(read_region(std::string(POLYSQUARE_TEST_DATA_DIR) + "/bad/bowtie.geojson", o), InputError);
  EXPECT_THROW(read_region(std::string(POLYSQUARE_TEST_DATA_DIR) + "/bad/nan.geojson", o), InputError);
}

TEST(FuzzRegressions, ReadWithoutCrashing) {
  // Found by fuzzing: each must read cleanly or be refused with InputError, fast.
  const std::string dir = std::string(POLYSQUARE_TEST_DATA_DIR) + "/fuzz-regressions/";
  const Region r = read_region(dir + "crs_long_digit_run.geojson");
  EXPECT_TRUE(r.crs.empty() || r.crs.size() <= 200);
  EXPECT_THROW(read_region(dir + "json_nested_66_levels.geojson"), InputError);
}
