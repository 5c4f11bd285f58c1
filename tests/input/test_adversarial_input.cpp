// Issue 13, round two, at the library level: nesting understood, nothing dropped silently, options checked,
// refusals fast and plain (tests/data/adversarial/README.md lists the files and the promised outcomes).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "polysquare/core/error.h"
#include "polysquare/input/read_region.h"
#include "polysquare/input/split_features.h"
#include "polysquare/io/geojson.h"
#include "polysquare/pipeline/check_options.h"
#include "polysquare/pipeline/local_frame.h"
#include "polysquare/quality/quality.h"

using namespace polysquare;
namespace fs = std::filesystem;

namespace {
fs::path adversarial(const std::string& name) { return fs::path(POLYSQUARE_TEST_DATA_DIR) / "adversarial" / name; }
std::string refusal(const fs::path& path, const InputOptions& options = {}) {
  try {
    InputNotes notes;
    read_input(path, options, notes);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}
bool has_point(const std::vector<Vec2>& pts, Vec2 p) {
  for (Vec2 q : pts)
    if (q == p) return true;
  return false;
}
}  // namespace

// How fast: bench/adversarial_corpus.py (no wall-clock assertion in tests).
TEST(AdversarialInput, CombsAreRefusedWithTheirCrossing) {
  for (const char* f : {"comb_30000_crossing.geojson", "comb_30000_crossing_rotated.geojson"}) {
    const std::string what = refusal(adversarial(f));
    EXPECT_NE(what.find("ring 0 intersects itself at ("), std::string::npos) << what;
    EXPECT_NE(what.find(f), std::string::npos) << what;
  }
}

TEST(AdversarialInput, ARingInsideAHoleIsAnIsland) {
  InputNotes notes;
  const Region r = read_input(adversarial("hole_in_hole.geojson"), {}, notes);
  ASSERT_EQ(r.num_parts, 2);
  ASSERT_EQ(r.rings.size(), 3u);
  EXPECT_FALSE(r.rings[2].hole);
  EXPECT_EQ(r.rings[2].part, 1);
  EXPECT_NEAR(domain_area(r), 100.0 * 100 - 60.0 * 60 + 20.0 * 20, 1e-9);
  ASSERT_EQ(notes.warnings.size(), 1u);
  EXPECT_NE(notes.warnings[0].find("meshed as an island"), std::string::npos) << notes.warnings[0];
  // One level deeper (a ring inside the island, in the same Polygon) is refused with the place.
  const std::string deeper = R"({"type":"FeatureCollection","features":[{"type":"Feature","properties":{"role":"domain"},
    "geometry":{"type":"Polygon","coordinates":[[[0,0],[100,0],[100,100],[0,100],[0,0]],
    [[20,20],[20,80],[80,80],[80,20],[20,20]],[[30,30],[30,70],[70,70],[70,30],[30,30]],
    [[40,40],[40,60],[60,60],[60,40],[40,40]]]}}]})";
  Region d = parse_geojson(deeper, "deeper.geojson");
  try {
    validate_region(d);
    ADD_FAILURE() << "a ring two holes deep was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("deeper.geojson"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("ring 3 lies inside ring 2"), std::string::npos) << e.what();
  }
}

TEST(AdversarialInput, AFeatureStartingAlongTheBoundaryKeepsItsInsideLeg) {
  InputNotes notes;
  const Region r = read_input(adversarial("feature_along_boundary_then_inside.geojson"), {}, notes);
  ASSERT_EQ(r.features.size(), 1u);
  const auto& c = r.features[0].points;
  ASSERT_EQ(c.size(), 3u);
  EXPECT_EQ(c.front(), (Vec2{30, 0}));  // moved onto the boundary, where the stretch along it ends
  EXPECT_EQ(c[1], (Vec2{30, 60}));
  EXPECT_EQ(c.back(), (Vec2{70, 60}));
  EXPECT_TRUE(has_point(r.rings[0].points, Vec2{30, 0}));  // and that point is a ring vertex
  bool warned = false;
  for (const auto& w : notes.warnings) warned |= w.find("runs along the boundary") != std::string::npos;
  EXPECT_TRUE(warned);
}

TEST(AdversarialInput, FeaturePointsOutsideTheDomainAreRefusedOrDroppedWithRepair) {
  EXPECT_NE(refusal(adversarial("feature_point_outside.geojson")).find("feature point (150, 50) lies outside the domain"),
            std::string::npos);
  EXPECT_NE(refusal(adversarial("feature_point_in_hole.geojson")).find("feature point (50, 50) lies in a hole"),
            std::string::npos);
  InputOptions repair;
  repair.repair = true;
  InputNotes notes;
  const Region r = read_input(adversarial("feature_point_in_hole.geojson"), repair, notes);
  EXPECT_TRUE(r.feature_points.empty());
  ASSERT_EQ(notes.repairs.size(), 1u);
  EXPECT_NE(notes.repairs[0].find("dropped"), std::string::npos);
}

TEST(AdversarialInput, InnerRingsOfAFeaturePolygonAreCurves) {
  InputNotes notes;
  const Region r = read_input(adversarial("feature_polygon_with_hole.geojson"), {}, notes);
  ASSERT_EQ(r.features.size(), 2u);
  EXPECT_TRUE(r.features[0].closed && r.features[1].closed);
  EXPECT_TRUE(has_point(r.features[1].points, Vec2{40, 40}));
}

TEST(AdversarialInput, VaryingZIsWarnedAbout) {
  InputNotes notes;
  read_input(adversarial("feature_varying_z.geojson"), {}, notes);
  ASSERT_EQ(notes.warnings.size(), 1u);
  EXPECT_NE(notes.warnings[0].find("feature 1 has"), std::string::npos) << notes.warnings[0];
  EXPECT_NE(notes.warnings[0].find("(z) varies"), std::string::npos) << notes.warnings[0];
}

TEST(AdversarialInput, MultiPolygonMessageSaysWhatIsWrong) {
  const std::string what = refusal(adversarial("multipolygon_not_array.geojson"));
  EXPECT_NE(what.find("MultiPolygon's coordinates must be an array of polygons, got 5"), std::string::npos) << what;
}

TEST(AdversarialInput, FarFromTheOriginRingsKeepTheirArea) {
  for (int e : {8, 10, 11}) {
    const fs::path p = adversarial("far_square_1e" + std::to_string(e) + ".geojson");
    InputNotes notes;
    const Region r = read_input(p, {}, notes);
    EXPECT_NEAR(domain_area(r), 10000.0, 1e-3) << p;
  }
}

TEST(MeshOptionsCheck, DefaultsPassAndEveryNaNIsRefusedByName) {
  MeshOptions ok;
  ok.size.h = 1;
  EXPECT_NO_THROW(check_mesh_options(ok));
  const double nan = std::nan("");
  struct Case {
    const char* flag;
    void (*set)(MeshOptions&, double);
  };
  const Case cases[] = {
      {"--size", [](MeshOptions& o, double v) { o.size.h = v; }},
      {"--min-sj", [](MeshOptions& o, double v) { o.gates.min_scaled_jacobian = v; }},
      {"--max-edge-ratio", [](MeshOptions& o, double v) { o.gates.max_edge_ratio = v; }},
      {"--max-poor-fraction", [](MeshOptions& o, double v) { o.gates.max_poor_fraction = v; }},
      {"--corner-angle", [](MeshOptions& o, double v) { o.curves.corner_threshold_deg = v; }},
      {"--simplify", [](MeshOptions& o, double v) { o.curves.simplify = v; }},
      {"--smooth-curves", [](MeshOptions& o, double v) { o.curves.smooth_curves = v; }},
      {"--min-island-width", [](MeshOptions& o, double v) { o.curves.min_island_width = v; }},
      {"--boundary-weight", [](MeshOptions& o, double v) { o.map.deform.boundary_weight = v; }},
      {"--feature-weight", [](MeshOptions& o, double v) { o.map.deform.feature_weight = v; }},
      {"--flat-corner-angle", [](MeshOptions& o, double v) { o.refine.flat_corner_deg = v; }},
      {"--loop-corner-angle", [](MeshOptions& o, double v) { o.refine.loop_corner_deg = v; }},
      {"--feature-tolerance", [](MeshOptions& o, double v) { o.gates.feature_tolerance = v; }},
      {"--agree-turns", [](MeshOptions& o, double v) { o.map.layout.agree_turn_elements = v; }},
  };
  for (const Case& c : cases)
    for (double v : {nan, -1.0}) {  // NaN compared false against every gate and disabled it
      MeshOptions o = ok;
      c.set(o, v);
      try {
        check_mesh_options(o);
        ADD_FAILURE() << c.flag << " " << v << " accepted";
      } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find(c.flag), std::string::npos) << e.what();
      }
    }
  MeshOptions o = ok;
  o.gates.max_edge_ratio = 0;
  EXPECT_THROW(check_mesh_options(o), InputError);
  o = ok;
  o.run.threads = 1'000'000'000;
  EXPECT_THROW(check_mesh_options(o), InputError);
  o = ok;
  o.size.max_quads = 0;
  EXPECT_THROW(check_mesh_options(o), InputError);
}

TEST(MeshOptionsCheck, SizeMessagesArePlainNumbers) {
  InputNotes notes;
  const Region r = read_input(adversarial("far_square_1e11.geojson"), {}, notes);
  MeshOptions o;
  o.size.h = 1e-150;
  try {
    check_mesh_size(r, o);
    ADD_FAILURE() << "1e-150 accepted";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("would need about 1e+304 quads"), std::string::npos) << what;
    EXPECT_LT(what.size(), 300u) << what;
  }
  o.size.h = 1e9;
  try {
    check_mesh_size(r, o);
    ADD_FAILURE() << "1e9 accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("(100 x 100)"), std::string::npos) << e.what();
  }
}

// Issue 52: a size whose quads --max-quads allows but the machine's memory cannot hold is refused with what it
// would need; an unknown amount of memory (0) refuses nothing.
TEST(MeshOptionsCheck, SizesBeyondTheAvailableMemoryAreRefused) {
  try {
    check_quad_memory(1e9, 21.7e9, "sea.geojson: --size 0.0316");
    ADD_FAILURE() << "1e9 quads in 21.7 GB accepted";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("sea.geojson: --size 0.0316 would need about 1e+09 quads", 0), 0u) << what;
    EXPECT_NE(what.find(std::to_string(static_cast<int>(kBytesPerQuad)) + " GB of memory"), std::string::npos) << what;
    EXPECT_NE(what.find("21.7 GB this machine has available"), std::string::npos) << what;
    EXPECT_NE(what.find("--max-quads"), std::string::npos) << what;
  }
  EXPECT_NO_THROW(check_quad_memory(1e6, 21.7e9, "sea.geojson: --size 1"));
  EXPECT_NO_THROW(check_quad_memory(1e9, 0.0, "sea.geojson: --size 0.0316"));
  const double available = available_memory_bytes();
  EXPECT_GT(available, 1e6);  // /proc/meminfo read (this suite runs on Linux)
  // check_mesh_size asks the machine: a square of 1e12 quads, allowed by max_quads, needs more than it has.
  Region r;
  r.source = "square.geojson";
  r.rings.push_back(Ring{{{0, 0}, {1e6, 0}, {1e6, 1e6}, {0, 1e6}}});
  MeshOptions o;
  o.size.h = 1.0;
  o.size.max_quads = 2'000'000'000'000;
  if (1e12 * kBytesPerQuad <= available) GTEST_SKIP() << "this machine holds 1e12 quads";
  try {
    check_mesh_size(r, o);
    ADD_FAILURE() << "1e12 quads accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("square.geojson: --size 1 would need about 1e+12 quads"), std::string::npos)
        << e.what();
  }
}

TEST(LocalFrame, FarRegionsMoveExactlyAndNearOnesStay) {
  InputNotes notes;
  const Region far = read_input(adversarial("far_smile_1e11.geojson"), {}, notes);
  const Vec2 o = local_origin(far);
  EXPECT_EQ(o.x, 1e11);  // the centre rounded to a multiple of 256 (the power of two above the diagonal, 141)
  EXPECT_EQ(o.y, 1e11);
  Region local = far;
  translate(local, {-o.x, -o.y});
  const Box2 box = local.bounding_box();
  EXPECT_LE(std::max(std::abs(box.lo.x), std::abs(box.hi.x)), 50.0);
  translate(local, o);
  for (std::size_t r = 0; r < far.rings.size(); ++r)
    for (std::size_t i = 0; i < far.rings[r].points.size(); ++i)
      ASSERT_EQ(local.rings[r].points[i], far.rings[r].points[i]) << "ring " << r << " point " << i;  // exact
  const Region near = read_input(fs::path(POLYSQUARE_DATA_DIR) / "cases" / "smile.geojson", {}, notes);
  EXPECT_EQ(local_origin(near).x, 0.0);
  EXPECT_EQ(local_origin(near).y, 0.0);
}

TEST(AdversarialInput, StretchesAlongTheBoundaryAreCountedApartFromOtherWarnings) {
  // Three curves leave the domain (each named), then 25 lie along its bottom side: 20 are named and "5 more"
  // counted. The cap counted every warning, so the pieces outside took three of the stretches' places.
  std::string features;
  for (int i = 0; i < 3; ++i)
    features += R"(,{"type":"Feature","properties":{"role":"feature"},"geometry":{"type":"LineString","coordinates":[[)" +
                std::to_string(20 + 20 * i) + ",50],[" + std::to_string(20 + 20 * i) + ",150]]}}";
  for (int i = 0; i < 25; ++i)
    features += R"(,{"type":"Feature","properties":{"role":"feature"},"geometry":{"type":"LineString","coordinates":[[)" +
                std::to_string(2 + 3 * i) + ",0],[" + std::to_string(3 + 3 * i) + ",0]]}}";
  Region r = parse_geojson(R"({"type":"FeatureCollection","features":[{"type":"Feature","properties":{"role":"domain"},
    "geometry":{"type":"Polygon","coordinates":[[[0,0],[100,0],[100,100],[0,100],[0,0]]]}})" + features + "]}",
                           "stretches.geojson");
  const FeatureSplitStats stats = split_features(r);
  EXPECT_EQ(stats.stretches_along_boundary, 25u);
  std::size_t named = 0, outside = 0, more = 0;
  for (const std::string& w : stats.warnings) {
    named += w.find("runs along the boundary") != std::string::npos;
    outside += w.find("lies outside the domain") != std::string::npos;
    more += w.find("... and 5 more stretches") != std::string::npos;
  }
  EXPECT_EQ(named, 20u);
  EXPECT_EQ(outside, 3u);
  EXPECT_EQ(more, 1u);
}
