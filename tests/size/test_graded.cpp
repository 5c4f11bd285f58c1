// Graded meshes (--size-min, --size-max, --grade, --across): the mesh follows its size field on a real coast and
// in a narrow channel, keeps every invariant, and bad field options are refused before meshing.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <sys/wait.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include "polysquare/core/error.h"
#include "polysquare/input/read_region.h"
#include "polysquare/pipeline/invariants.h"
#include "polysquare/pipeline/mesh_region.h"
#include "polysquare/pipeline/subregions.h"
#include "polysquare/quality/quality.h"

using namespace polysquare;
namespace fs = std::filesystem;

namespace {

MeshOptions graded(double size_min, double size_max, double grade = 0.15, double across = 0.0) {
  MeshOptions o;
  o.size.field.size_min = size_min;
  o.size.field.size_max = size_max;
  o.size.field.grade = grade;
  o.size.field.across = across;
  return o;
}

// The quads whose interior the segment a-b crosses (a segment through a node or along an edge counts the quads
// it passes through, not those it touches).
int quads_crossed(const QuadMesh& m, Vec2 a, Vec2 b) {
  int n = 0;
  for (const auto& q : m.quads) {
    // Clip a-b against the convex quad (Cyrus-Beck): a crossing of positive length is a crossing.
    double t0 = 0.0, t1 = 1.0;
    bool outside = false;
    for (int e = 0; e < 4 && !outside; ++e) {
      const Vec2 p = m.nodes[q[e]], r = m.nodes[q[(e + 1) % 4]];
      const double num = orient2(p, r, a), den = orient2(p, r, b) - num;  // inside: orient2 > 0
      if (std::abs(den) < 1e-15) {
        outside = num <= 0.0;
        continue;
      }
      const double t = -num / den;
      if (den > 0) t0 = std::max(t0, t);
      else t1 = std::min(t1, t);
      outside = t0 >= t1;
    }
    if (!outside && (t1 - t0) * distance(a, b) > 1e-6) ++n;
  }
  return n;
}

struct CliRun {
  int code;
  std::string err;
};

CliRun run(const std::string& args) {
  const fs::path err = fs::temp_directory_path() / ("polysquare_graded_err_" + std::to_string(::getpid()));
  const int status = std::system((std::string(POLYSQUARE_CLI) + " " + args + " > /dev/null 2> " + err.string()).c_str());
  std::ifstream in(err);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  fs::remove(err);
  return {WEXITSTATUS(status), text};
}

// A 2 km x 1 km basin with a channel of width w, 600 m long, from the middle of its upper side.
Region basin_with_channel(double w) {
  Region region;
  region.rings.push_back({{{0, 0}, {2000, 0}, {2000, 1000}, {1000 + w / 2, 1000}, {1000 + w / 2, 1600},
                           {1000 - w / 2, 1600}, {1000 - w / 2, 1000}, {0, 1000}},
                          0, false, -1, {}});
  region.num_parts = 1;
  region.source = "channel";
  return region;
}

}  // namespace

// The issue's coast: delta_water at 50 m at the shore, 1000 m offshore, gradient 0.15.
TEST(Graded, DeltaWaterFollowsItsSizeField) {
  const Region region = read_region(std::string(POLYSQUARE_DATA_DIR) + "/cases/delta_water.geojson");
  const MeshResult r = mesh_region(region, graded(50.0, 1000.0));
  const InvariantReport inv = check_invariants(r.mesh);
  EXPECT_TRUE(inv.ok()) << inv.first_problem;
  const QualityReport q = compute_quality(r.mesh);
  EXPECT_EQ(q.inverted, 0u);
  ASSERT_TRUE(r.report.size_field.has_value());
  const SizeFieldReport& f = *r.report.size_field;
  // Far fewer quads than the uniform mesh at the least size, and about what the field's integral said.
  const double uniform = domain_area(r.region) / (50.0 * 50.0);
  EXPECT_LT(static_cast<double>(r.mesh.quads.size()), uniform / 5.0);
  EXPECT_NEAR(static_cast<double>(r.mesh.quads.size()) / f.estimated_quads, 1.0, 0.25);
  // Semi-structured, and each quad near its size: sqrt(area) / h at the centroid.
  EXPECT_GE(q.regular_quad_fraction, 0.9);
  EXPECT_LE(1000.0 * static_cast<double>(q.interior_singularities) / static_cast<double>(r.mesh.quads.size()), 40.0);
  EXPECT_GE(f.size_ratio_median, 0.8);
  EXPECT_LE(f.size_ratio_median, 1.25);
  EXPECT_GE(f.size_ratio_p05, 0.5);  // 0.47 before transition rows
  EXPECT_LE(f.size_ratio_p95, 1.6);
  EXPECT_LE(f.neighbour_ratio_p99, 2.0);
  // Sizes really vary: the largest quads are many times the smallest.
  EXPECT_GT(f.max / f.min, 10.0);
}

// Transition rows: where neighbouring subregions want counts far apart, rows of fans join them, so the quads along
// a shore keep the shore's size instead of the far side's. On the estuary (100 m at the shore, 800 m offshore) the
// smallest quads come nearer their size than with every row keeping its count (--transition-cost 0), and the mesh
// stays semi-structured.
TEST(Graded, TransitionRowsBringQuadsNearerTheirSize) {
  const Region region = read_region(std::string(POLYSQUARE_DATA_DIR) + "/cases/estuary.geojson");
  MeshOptions without = graded(100.0, 800.0);
  without.map.quantize.transition_cost = 0.0;
  const MeshResult a = mesh_region(region, graded(100.0, 800.0)), b = mesh_region(region, without);
  auto rows = [](const MeshResult& r) {
    std::size_t n = 0;
    for (const PartReport& p : r.report.parts) n += p.transition_rows;
    return n;
  };
  EXPECT_GT(rows(a), 0u);
  EXPECT_EQ(rows(b), 0u);
  for (const MeshResult* r : {&a, &b}) EXPECT_TRUE(check_invariants(r->mesh).ok());
  ASSERT_TRUE(a.report.size_field && b.report.size_field);
  EXPECT_GE(a.report.size_field->size_ratio_p05, 0.5);
  EXPECT_GT(a.report.size_field->size_ratio_p05, b.report.size_field->size_ratio_p05 + 0.03);
  EXPECT_GT(a.report.size_field->size_ratio_median, b.report.size_field->size_ratio_median);
  const QualityReport q = compute_quality(a.mesh);
  EXPECT_GE(q.regular_quad_fraction, 0.9);
  EXPECT_LE(1000.0 * static_cast<double>(q.interior_singularities) / static_cast<double>(a.mesh.quads.size()), 40.0);
}

// A 2 km x 1 km basin with a 30 m wide, 600 m long channel: --across 3 puts at least three quads across the
// channel everywhere along it, while the basin grades up to 100 m.
TEST(Graded, AcrossPutsQuadsAcrossANarrowChannel) {
  const double w = 30.0;
  const Region region = basin_with_channel(w);
  const MeshResult r = mesh_region(region, graded(5.0, 100.0, 0.15, 3.0));
  EXPECT_TRUE(check_invariants(r.mesh).ok());
  // Sections across the channel every 50 m, away from its mouth and its end.
  int fewest = 1 << 30;
  for (double y = 1100.0; y <= 1500.0; y += 50.0)
    fewest = std::min(fewest, quads_crossed(r.mesh, {1000 - w / 2 - 1e-3, y + 0.37}, {1000 + w / 2 + 1e-3, y + 0.37}));
  EXPECT_GE(fewest, 3);
  // Without --across, the distance term alone would give the channel size 5 m quads at the walls anyway; the
  // point of the field is the basin: far fewer quads than 5 m throughout.
  EXPECT_LT(static_cast<double>(r.mesh.quads.size()), 2000.0 * 1000.0 / 25.0 / 5.0);
}

// The singular nodes a grading needs go as G^2, so a gentler gradient takes larger subregions (a quarter of the
// gradient: 16 times the quads), and a steeper one no smaller than at the reference.
TEST(Graded, GentlerGradientsTakeLargerSubregions) {
  const SubregionOptions o;
  EXPECT_DOUBLE_EQ(graded_subregion_quads(o, o.graded_reference_grade), o.graded_quads_per_subregion);
  EXPECT_NEAR(graded_subregion_quads(o, o.graded_reference_grade / 4.0), 16.0 * o.graded_quads_per_subregion, 1e-9);
  EXPECT_DOUBLE_EQ(graded_subregion_quads(o, 2.0 * o.graded_reference_grade), o.graded_quads_per_subregion);
}

// Two failed subregions side by side are both patched; their shared interface must get one count from both. Each
// patch's own least size gave each side its own count (a crack and overlapping quads along the interface: 53 pairs
// on a graded delta_box, which sent the whole coast to the unstructured fallback). The basin and channel of the
// test above, every subregion a patch, no repair round to hide a crack: the patches must stitch as they are.
TEST(Graded, NeighbouringPatchesTakeOneCountOnTheirInterface) {
  const double w = 30.0;
  const Region region = basin_with_channel(w);
  MeshOptions o = graded(5.0, 100.0, 0.15, 3.0);
  o.subregions.parts = 6;
  o.map.patch_subregions = {0, 1, 2, 3, 4, 5};
  o.repair.rounds = 0;
  o.repair.split_fallback = false;
  MeshResult r;
  ASSERT_NO_THROW(r = mesh_region(region, o));
  const InvariantReport inv = check_invariants(r.mesh);
  EXPECT_TRUE(inv.ok()) << inv.first_problem;
  EXPECT_GE(std::set<std::int32_t>(r.mesh.quad_part.begin(), r.mesh.quad_part.end()).size(), 6u);
}

// Bad field options: exit 2, one error line naming the flag, no file.
TEST(Graded, BadFieldOptionsAreRefusedByName) {
  const fs::path out = fs::temp_directory_path() / ("polysquare_graded_" + std::to_string(::getpid()) + ".msh");
  const std::string in = std::string(POLYSQUARE_DATA_DIR) + "/cases/estuary.geojson";
  const std::vector<std::pair<std::string, std::string>> cases{
      {"--size-min 0 --size-max 100", "--size-min"},
      {"--size-min -5 --size-max 100", "--size-min"},
      {"--size-min 200 --size-max 100", "--size-max"},
      {"--size-min 50 --size-max 500 --grade nan", "--grade"},
      {"--size-min 50 --size-max 500 --grade 0", "--grade"},
      {"--size-min 50 --size-max 500 --across -1", "--across"},
      {"--size-min 50", "--size-max"},
      {"--size 50 --size-min 50 --size-max 500", "--size"},
      {"--size-min 1 --size-max 2 --max-quads 1000", "--max-quads"},
  };
  for (const auto& [flags, named] : cases) {
    const CliRun r = run("mesh " + in + " " + flags + " -o " + out.string());
    EXPECT_EQ(r.code, 2) << flags << ": " << r.err;
    EXPECT_NE(r.err.find(named), std::string::npos) << flags << ": " << r.err;
    EXPECT_FALSE(fs::exists(out)) << flags;
  }
}

namespace {

// An ESRI ASCII grid (GDAL's AAIGrid) of `value` over [x0, x0 + n cell] x [y0, y0 + m cell], and a rectangle
// domain inside it as GeoJSON: the inputs of the raster terms.
fs::path constant_grid(const std::string& name, double value, double x0, double y0, int n, int m, double cell) {
  const fs::path p = fs::temp_directory_path() / (name + "_" + std::to_string(::getpid()) + ".asc");
  std::ofstream out(p);
  out << "ncols " << n << "\nnrows " << m << "\nxllcorner " << x0 << "\nyllcorner " << y0 << "\ncellsize " << cell
      << "\nNODATA_value -9999\n";
  for (int j = 0; j < m; ++j) {
    for (int i = 0; i < n; ++i) out << value << (i + 1 < n ? " " : "\n");
  }
  return p;
}

fs::path rectangle_geojson(const std::string& name, double x0, double y0, double w, double h) {
  const fs::path p = fs::temp_directory_path() / (name + "_" + std::to_string(::getpid()) + ".geojson");
  std::ofstream out(p);
  out.precision(12);
  out << R"({"type": "FeatureCollection", "features": [{"type": "Feature", "properties": {"role": "domain"}, )"
      << R"("geometry": {"type": "Polygon", "coordinates": [[)" << "[" << x0 << ", " << y0 << "], [" << x0 + w << ", "
      << y0 << "], [" << x0 + w << ", " << y0 + h << "], [" << x0 << ", " << y0 + h << "], [" << x0 << ", " << y0
      << "]]]}}]}\n";
  return p;
}

double field_max_of_run(const std::string& args, int& code) {
  const fs::path report = fs::temp_directory_path() / ("polysquare_graded_r_" + std::to_string(::getpid()) + ".json");
  const fs::path mesh = fs::temp_directory_path() / ("polysquare_graded_m_" + std::to_string(::getpid()) + ".msh");
  code = run("mesh " + args + " -o " + mesh.string() + " --report " + report.string()).code;
  std::ifstream in(report);
  const nlohmann::json r = code == 0 ? nlohmann::json::parse(in) : nlohmann::json();
  fs::remove(report), fs::remove(mesh);
  return code == 0 ? r["size_field"]["max"].get<double>() : 0.0;
}

}  // namespace

// --size-field: the field never exceeds the raster's sizes; --per-wavelength: N quads per M2 wavelength over
// a constant depth of 4 m (lambda = 44,712 s * sqrt(9.81 * 4) = 280,085 m); bad raster values are refused.
TEST(Graded, RasterAndWavelengthTermsBoundTheField) {
  const fs::path domain = rectangle_geojson("graded_rect", 1000.0, 2000.0, 2000.0, 1000.0);
  const fs::path sizes = constant_grid("graded_sizes", 40.0, 900.0, 1900.0, 44, 24, 50.0);
  const fs::path depth = constant_grid("graded_depth", 4.0, 900.0, 1900.0, 44, 24, 50.0);
  const fs::path bad = constant_grid("graded_bad", -3.0, 900.0, 1900.0, 44, 24, 50.0);
  int code = 0;
  const std::string graded = domain.string() + " --size-min 10 --size-max 200 --grade 0.15";
  const double plain = field_max_of_run(graded, code);
  ASSERT_EQ(code, 0);
  EXPECT_GT(plain, 60.0);  // the distance term alone grows past 60 m inside the rectangle
  EXPECT_NEAR(field_max_of_run(graded + " --size-field " + sizes.string(), code), 40.0, 1e-6);
  EXPECT_EQ(code, 0);
  const double lambda = 44712.0 * std::sqrt(9.81 * 4.0);
  EXPECT_NEAR(field_max_of_run(graded + " --bathymetry " + depth.string() + " --bathymetry-positive down "
                               "--per-wavelength " + std::to_string(lambda / 30.0), code), 30.0, 1e-3);
  EXPECT_EQ(code, 0);
  const fs::path out = fs::temp_directory_path() / ("polysquare_graded_bad_" + std::to_string(::getpid()) + ".msh");
  const CliRun r = run("mesh " + graded + " --size-field " + bad.string() + " -o " + out.string());
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("--size-field"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("not a positive number"), std::string::npos) << r.err;
  const CliRun w = run("mesh " + graded + " --per-wavelength 10 -o " + out.string());
  EXPECT_EQ(w.code, 2);
  EXPECT_NE(w.err.find("--bathymetry"), std::string::npos) << w.err;
  EXPECT_FALSE(fs::exists(out));
  for (const fs::path& p : {domain, sizes, depth, bad}) fs::remove(p);
}

// --size-picture: a PNG of the field of a graded run, refused (exit 2, no file) without grading.
TEST(Graded, SizePictureDrawsTheField) {
  const std::string in = std::string(POLYSQUARE_DATA_DIR) + "/cases/estuary.geojson";
  const fs::path dir = fs::temp_directory_path() / ("polysquare_graded_pic_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const CliRun r = run("mesh " + in + " --size-min 100 --size-max 800 -o " + (dir / "m.msh").string() +
                       " --size-picture " + (dir / "field.png").string());
  ASSERT_EQ(r.code, 0) << r.err;
  std::ifstream png(dir / "field.png", std::ios::binary);
  std::string head(8, '\0');
  png.read(head.data(), 8);
  EXPECT_EQ(head, std::string("\x89PNG\r\n\x1a\n", 8));
  EXPECT_GT(fs::file_size(dir / "field.png"), 10000u);
  const CliRun u = run("mesh " + in + " --size 200 -o " + (dir / "u.msh").string() + " --size-picture " +
                       (dir / "u.png").string());
  EXPECT_EQ(u.code, 2);
  EXPECT_NE(u.err.find("--size-picture"), std::string::npos) << u.err;
  EXPECT_FALSE(fs::exists(dir / "u.png"));
  EXPECT_FALSE(fs::exists(dir / "u.msh"));
  fs::remove_all(dir);
}
