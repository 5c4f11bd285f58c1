// SCHISM's quad checks (quality.h, SchismQuadQuality): angle ratio = smallest / largest interior angle, aspect
// ratio = longest / shortest side, as xmgredit5 and fix_bad_quads.f90 define them. Constructed quads whose angles
// and sides are known by hand, then real meshes re-measured here by another formula (the law of cosines), and the
// figures in `polysquare quality` and the mesh report.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "polysquare/io/mesh_io.h"
#include "polysquare/quality/quality.h"

using namespace polysquare;
namespace fs = std::filesystem;

namespace {

constexpr double pi = std::numbers::pi;

QuadMesh one_quad(std::array<Vec2, 4> corners) {
  QuadMesh m;
  m.nodes.assign(corners.begin(), corners.end());
  m.quads = {{0, 1, 2, 3}};
  return m;
}

// A parallelogram with sides a (along x) and b, at the angle `angle` (radians) between them at the first node.
QuadMesh parallelogram(double a, double b, double angle) {
  const Vec2 side{b * std::cos(angle), b * std::sin(angle)};
  return one_quad({Vec2{0, 0}, Vec2{a, 0}, Vec2{a + side.x, side.y}, side});
}

std::string read_text(const fs::path& p) {
  std::ifstream f(p);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

// Interior angles from side lengths and diagonals alone (law of cosines), a formula the library does not use.
double angle_ratio_by_cosines(const QuadMesh& m, const std::array<std::int32_t, 4>& q) {
  double lo = INFINITY, hi = 0;
  for (int k = 0; k < 4; ++k) {
    const Vec2 p = m.nodes[q[k]], a = m.nodes[q[(k + 1) % 4]], b = m.nodes[q[(k + 3) % 4]];
    const double la = distance(p, a), lb = distance(p, b), d = distance(a, b);
    const double angle = std::acos(std::clamp((la * la + lb * lb - d * d) / (2 * la * lb), -1.0, 1.0));
    lo = std::min(lo, angle);
    hi = std::max(hi, angle);
  }
  return lo / hi;
}

}  // namespace

TEST(SchismQuadChecks, RectangleHasAngleRatioOneAndItsSideRatio) {
  const SchismQuadQuality q = schism_quad_quality(one_quad({Vec2{0, 0}, Vec2{4, 0}, Vec2{4, 1}, Vec2{0, 1}}));
  EXPECT_NEAR(q.angle_ratio.min, 1.0, 1e-12);  // four right angles
  EXPECT_NEAR(q.aspect_ratio.max, 4.0, 1e-12);  // sides 4 and 1
  EXPECT_EQ(q.failing, 0u);
  // The same rectangle fails an aspect ratio cutoff of 3, not the angle ratio.
  const SchismQuadQuality strict = schism_quad_quality(one_quad({Vec2{0, 0}, Vec2{4, 0}, Vec2{4, 1}, Vec2{0, 1}}), 0.5, 3.0);
  EXPECT_EQ(strict.aspect_ratio_above, 1u);
  EXPECT_EQ(strict.angle_ratio_below, 0u);
  EXPECT_EQ(strict.failing, 1u);
}

TEST(SchismQuadChecks, ParallelogramsGiveTheirAcuteOverObtuseAngle) {
  // 60 and 120 degrees: ratio 1/2, exactly SCHISM's example cutoff (not below it); sides 3 and 1.
  const SchismQuadQuality q60 = schism_quad_quality(parallelogram(3, 1, pi / 3));
  EXPECT_NEAR(q60.angle_ratio.min, 0.5, 1e-12);
  EXPECT_NEAR(q60.aspect_ratio.max, 3.0, 1e-12);
  // 45 and 135 degrees: ratio 1/3, below 0.5, so SCHISM would split it; sides 2 and 2 * 6.
  const SchismQuadQuality q45 = schism_quad_quality(parallelogram(2, 12, pi / 4));
  EXPECT_NEAR(q45.angle_ratio.min, 1.0 / 3.0, 1e-12);
  EXPECT_NEAR(q45.aspect_ratio.max, 6.0, 1e-12);
  EXPECT_EQ(q45.angle_ratio_below, 1u);
  EXPECT_EQ(q45.aspect_ratio_above, 1u);
  EXPECT_EQ(q45.failing, 1u);  // one quad, failing both checks
  EXPECT_EQ(q45.non_convex, 0u);
}

TEST(SchismQuadChecks, RightTrapezoid) {
  // (0,0) 90, (3,0) 45, (2,1) 135, (0,1) 90 degrees: ratio 45 / 135; sides 3, sqrt 2, 2, 1: aspect ratio 3.
  const QuadMesh m = one_quad({Vec2{0, 0}, Vec2{3, 0}, Vec2{2, 1}, Vec2{0, 1}});
  EXPECT_NEAR(schism_angle_ratios(m)[0], 1.0 / 3.0, 1e-12);
  EXPECT_NEAR(schism_quad_quality(m).aspect_ratio.max, 3.0, 1e-12);
}

TEST(SchismQuadChecks, FiguresDoNotDependOnPlaceSizeRotationOrFirstNode) {
  const std::array<Vec2, 4> kite{Vec2{0, 0}, Vec2{2, -1}, Vec2{5, 0}, Vec2{2, 1}};
  const double expected = schism_angle_ratios(one_quad(kite))[0];
  // The kite's angles: 2 atan(1/2) at (0,0), 2 atan(1/3) at (5,0), the rest of 360 split at (2, +-1).
  const double a0 = 2 * std::atan(0.5), a2 = 2 * std::atan(1.0 / 3.0), a1 = (2 * pi - a0 - a2) / 2;
  EXPECT_NEAR(expected, a2 / a1, 1e-12);
  const double turn = 0.7, scale = 1e3;
  for (int start = 0; start < 4; ++start) {
    std::array<Vec2, 4> moved;
    for (int k = 0; k < 4; ++k) {
      const Vec2 p = kite[static_cast<std::size_t>((k + start) % 4)];
      moved[static_cast<std::size_t>(k)] = Vec2{scale * (std::cos(turn) * p.x - std::sin(turn) * p.y) + 5e5,
                                                scale * (std::sin(turn) * p.x + std::cos(turn) * p.y) - 3e6};
    }
    const SchismQuadQuality q = schism_quad_quality(one_quad(moved));
    EXPECT_NEAR(q.angle_ratio.min, expected, 1e-9) << start;
    EXPECT_NEAR(q.aspect_ratio.max, std::sqrt(10.0) / std::sqrt(5.0), 1e-9) << start;  // sides sqrt 5, sqrt 10
  }
}

TEST(SchismQuadChecks, ConcaveAndClockwiseQuadsHaveAngleRatioZero) {
  // A dart: the corner at (1, 1) is reflex (its interior angle is above 180 degrees).
  const QuadMesh dart = one_quad({Vec2{0, 0}, Vec2{3, 1}, Vec2{0, 2}, Vec2{1, 1}});
  const SchismQuadQuality d = schism_quad_quality(dart);
  EXPECT_EQ(d.angle_ratio.min, 0.0);
  EXPECT_EQ(d.non_convex, 1u);
  EXPECT_EQ(d.failing, 1u);
  // The unit square walked clockwise is inverted.
  EXPECT_EQ(schism_angle_ratios(one_quad({Vec2{0, 0}, Vec2{0, 1}, Vec2{1, 1}, Vec2{1, 0}}))[0], 0.0);
  // A zero-length side.
  EXPECT_EQ(schism_angle_ratios(one_quad({Vec2{0, 0}, Vec2{1, 0}, Vec2{1, 0}, Vec2{0, 1}}))[0], 0.0);
}

TEST(SchismQuadChecks, MeshFiguresCountAndPlaceTheWorstQuads) {
  // A unit square, a 45-degree parallelogram (ratio 1/3) to its right and a 6 x 1 rectangle above them.
  QuadMesh m;
  m.nodes = {{0, 0}, {1, 0}, {1, 1}, {0, 1}, {3, 0}, {4, 1}, {2, 1}, {6, 1}, {6, 2}, {0, 2}};
  // The square; (1,0) (3,0) (4,1) (2,1): sides 2 and sqrt 2 at 45 degrees; (0,1) (6,1) (6,2) (0,2).
  m.quads = {{0, 1, 2, 3}, {1, 4, 5, 6}, {3, 7, 8, 9}};
  const SchismQuadQuality q = schism_quad_quality(m);
  EXPECT_NEAR(q.angle_ratio.min, 1.0 / 3.0, 1e-12);
  EXPECT_NEAR(q.angle_ratio.max, 1.0, 1e-12);
  EXPECT_NEAR(q.angle_ratio.avg, (1.0 + 1.0 / 3.0 + 1.0) / 3.0, 1e-12);
  EXPECT_NEAR(q.aspect_ratio.max, 6.0, 1e-12);
  EXPECT_NEAR(q.aspect_ratio.min, 1.0, 1e-12);
  EXPECT_EQ(q.angle_ratio_below, 1u);
  EXPECT_EQ(q.aspect_ratio_above, 1u);
  EXPECT_EQ(q.failing, 2u);
  EXPECT_NEAR(q.angle_ratio_worst_at.x, 2.5, 1e-12);  // mean of the parallelogram's nodes
  EXPECT_NEAR(q.angle_ratio_worst_at.y, 0.5, 1e-12);
  EXPECT_NEAR(q.aspect_ratio_worst_at.x, 3.0, 1e-12);  // the rectangle's centre
  EXPECT_NEAR(q.aspect_ratio_worst_at.y, 1.5, 1e-12);
  // compute_quality carries them, and the JSON and text say them.
  const QualityReport report = compute_quality(m);
  EXPECT_EQ(report.schism.failing, 2u);
  const nlohmann::json j = to_json(report)["schism"];
  EXPECT_NEAR(j["angle_ratio"]["min"].get<double>(), 1.0 / 3.0, 1e-12);
  EXPECT_EQ(j["failing"].get<int>(), 2);
  EXPECT_NE(format_schism_text(q).find("2 quads fail"), std::string::npos) << format_schism_text(q);
}

TEST(SchismQuadChecks, GmshLetterRMeasuredAgainByTheLawOfCosines) {
  // A mesh made by another tool (Gmsh 4.8.4, letter_R; its 4 triangles are left out).
  const QuadMesh m = read_mesh(std::string(POLYSQUARE_TEST_DATA_DIR) + "/gmsh/letter_R_msh22_ascii.msh");
  const SchismQuadQuality q = schism_quad_quality(m);
  const QualityReport report = compute_quality(m);
  ASSERT_EQ(report.inverted, 0u);  // every quad convex, so the law of cosines gives its interior angles
  double lo = INFINITY, sum = 0;
  std::size_t below = 0;
  for (const auto& quad : m.quads) {
    const double r = angle_ratio_by_cosines(m, quad);
    lo = std::min(lo, r);
    sum += r;
    below += r < 0.5;
  }
  EXPECT_NEAR(q.angle_ratio.min, lo, 1e-9);
  EXPECT_NEAR(q.angle_ratio.avg, sum / static_cast<double>(m.quads.size()), 1e-9);
  EXPECT_EQ(q.angle_ratio_below, below);
  EXPECT_EQ(q.angle_ratio.count, 1036u);
  EXPECT_EQ(q.non_convex, 0u);
  // The aspect ratio is the edge ratio; the equiangle skew s bounds the angles within 90 (1 -+ s) degrees.
  EXPECT_DOUBLE_EQ(q.aspect_ratio.max, report.edge_ratio.max);
  EXPECT_GE(q.angle_ratio.min, (1 - report.skew.max) / (1 + report.skew.max) - 1e-12);
  EXPECT_LT(q.angle_ratio.min, 1.0);
}

TEST(SchismQuadChecks, CliQualityAndReportGiveTheSchismFigures) {
  // dam_channel meshed by polysquare at the README's size, then judged by `polysquare quality` from the file.
  const fs::path dir = fs::temp_directory_path() / ("polysquare_schism_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string cli = POLYSQUARE_CLI;
  const std::string mesh_cmd = cli + " mesh " + POLYSQUARE_DATA_DIR + "/cases/dam_channel.geojson --size 2 -o " +
                               (dir / "m.msh").string() + " --report " + (dir / "r.json").string() + " > " +
                               (dir / "mesh.txt").string() + " 2>&1";
  ASSERT_EQ(std::system(mesh_cmd.c_str()), 0) << read_text(dir / "mesh.txt");
  EXPECT_NE(read_text(dir / "mesh.txt").find("SCHISM quad checks: angle ratio"), std::string::npos);
  const std::string json_cmd = cli + " quality " + (dir / "m.msh").string() + " --json > " + (dir / "q.json").string();
  ASSERT_EQ(std::system(json_cmd.c_str()), 0);
  const std::string text_cmd = cli + " quality " + (dir / "m.msh").string() + " > " + (dir / "q.txt").string();
  ASSERT_EQ(std::system(text_cmd.c_str()), 0);
  const nlohmann::json report = nlohmann::json::parse(read_text(dir / "r.json"))["quality"]["schism"];
  const nlohmann::json judged = nlohmann::json::parse(read_text(dir / "q.json"))["schism"];
  const std::string text = read_text(dir / "q.txt");
  // The text line follows the D-Flow FM line.
  const auto fv_at = text.find("finite volume (D-Flow FM"), schism_at = text.find("SCHISM quad checks");
  ASSERT_NE(schism_at, std::string::npos) << text;
  EXPECT_LT(fv_at, schism_at);
  // Re-measured from the file by the law of cosines (the report was measured before writing, the file keeps
  // 17 digits, so the figures agree to rounding).
  const QuadMesh m = read_mesh(dir / "m.msh");
  double lo = INFINITY;
  for (const auto& quad : m.quads) lo = std::min(lo, angle_ratio_by_cosines(m, quad));
  EXPECT_NEAR(report["angle_ratio"]["min"].get<double>(), lo, 1e-9);
  EXPECT_NEAR(judged["angle_ratio"]["min"].get<double>(), lo, 1e-9);
  EXPECT_NEAR(judged["aspect_ratio"]["max"].get<double>(), report["aspect_ratio"]["max"].get<double>(), 1e-9);
  EXPECT_EQ(judged["failing"], report["failing"]);
  EXPECT_EQ(report["non_convex"].get<int>(), 0);
  EXPECT_DOUBLE_EQ(report["angle_ratio_limit"].get<double>(), 0.5);
  EXPECT_DOUBLE_EQ(report["aspect_ratio_limit"].get<double>(), 5.0);
  fs::remove_all(dir);
}
