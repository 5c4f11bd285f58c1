// The `size` attribute of input features (issue 51): the size along a feature line, inside a domain polygon part
// or a closed feature, read from GeoJSON and through GDAL, kept through validation's cuts, and followed by the
// size field and the mesh.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <sys/wait.h>
#include <unistd.h>
#include <vector>

#include "polysquare/core/error.h"
#include "polysquare/input/read_region.h"
#include "polysquare/io/geojson.h"
#include "polysquare/pipeline/invariants.h"
#include "polysquare/pipeline/mesh_region.h"
#include "polysquare/size/size_field.h"

using namespace polysquare;
namespace fs = std::filesystem;

namespace {

// A FeatureCollection of a 2000 x 1000 box (its properties `domain_props`) and the features given as JSON text.
std::string box_with(const std::string& features, const std::string& domain_props = "") {
  return R"({"type": "FeatureCollection", "features": [{"type": "Feature", "properties": {"role": "domain")" +
         domain_props + R"(}, "geometry": {"type": "Polygon", "coordinates": [[[0, 0], [2000, 0], [2000, 1000], )" +
         R"([0, 1000], [0, 0]]]}})" + (features.empty() ? "" : ", " + features) + "]}";
}

std::string line(const std::string& props, Vec2 a, Vec2 b) {
  return R"({"type": "Feature", "properties": {"role": "feature")" + props +
         R"(}, "geometry": {"type": "LineString", "coordinates": [[)" + std::to_string(a.x) + ", " +
         std::to_string(a.y) + "], [" + std::to_string(b.x) + ", " + std::to_string(b.y) + "]]}}";
}

Region parsed(const std::string& text) {
  Region r = parse_geojson(text, "sizes.geojson");
  validate_region(r);
  return r;
}

SizeFieldOptions field_options(double size_min, double size_max, bool distance_term = true) {
  SizeFieldOptions o;
  o.size_min = size_min;
  o.size_max = size_max;
  o.distance_term = distance_term;
  return o;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

double distance_to_segment(Vec2 p, Vec2 a, Vec2 b) {
  const Vec2 d = b - a;
  const double t = std::clamp(dot(p - a, d) / dot(d, d), 0.0, 1.0);
  return distance(p, a + t * d);
}

// The edges of the quads with a node on the line a-b: along it (both nodes on it) and across it (one node on
// it); and the edges of the quads whose centroid lies farther than `far` from it.
struct LineEdges {
  std::vector<double> along, across, far_away;
};

LineEdges line_edges(const QuadMesh& m, Vec2 a, Vec2 b, double far) {
  LineEdges out;
  auto on_line = [&](Vec2 p) { return distance_to_segment(p, a, b) < 1e-6; };
  for (const auto& q : m.quads) {
    Vec2 centroid{0, 0};
    for (int k = 0; k < 4; ++k) centroid = centroid + 0.25 * m.nodes[static_cast<std::size_t>(q[k])];
    const bool far_quad = distance_to_segment(centroid, a, b) > far;
    for (int k = 0; k < 4; ++k) {
      const Vec2 p = m.nodes[static_cast<std::size_t>(q[k])], r = m.nodes[static_cast<std::size_t>(q[(k + 1) % 4])];
      if (far_quad) out.far_away.push_back(distance(p, r));
      else if (on_line(p) && on_line(r)) out.along.push_back(distance(p, r));
      else if (on_line(p) != on_line(r)) out.across.push_back(distance(p, r));
    }
  }
  return out;
}

LineEdges meshed_line_edges(double size, const SizeFieldOptions& field, double far) {
  const Vec2 a{200, 500}, b{1800, 500};
  const Region region = parsed(box_with(line(R"(, "size": )" + std::to_string(size), a, b)));
  MeshOptions o;
  o.size.field = field;
  const MeshResult r = mesh_region(region, o);
  const InvariantReport inv = check_invariants(r.mesh);
  EXPECT_TRUE(inv.ok()) << inv.first_problem;
  const LineEdges e = line_edges(r.mesh, a, b, far);
  std::printf("line of size %g in %zu quads: edges along it median %.1f (%zu), across it %.1f (%zu), of quads farther "
              "than %g %.1f (%zu)\n", size, r.mesh.quads.size(), median(e.along), e.along.size(), median(e.across),
              e.across.size(), far, median(e.far_away), e.far_away.size());
  return e;
}

struct CliRun {
  int code;
  std::string err;
};

CliRun run(const std::string& args) {
  const fs::path err = fs::temp_directory_path() / ("polysquare_size_attr_err_" + std::to_string(::getpid()));
  const int status = std::system((std::string(POLYSQUARE_CLI) + " " + args + " > /dev/null 2> " + err.string()).c_str());
  std::ifstream in(err);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  fs::remove(err);
  return {WEXITSTATUS(status), text};
}

fs::path written(const std::string& name, const std::string& text) {
  const fs::path p = fs::temp_directory_path() / (name + "_" + std::to_string(::getpid()) + ".geojson");
  std::ofstream(p) << text;
  return p;
}

}  // namespace

// The size attribute on a feature line: the field is s along it and grades away as s + grade * distance, larger
// than HMIN (the attribute takes its place there) while the unsized boundary keeps HMIN.
TEST(SizeAttribute, FeatureLineBoundsTheFieldAlongIt) {
  const Vec2 a{200, 500}, b{1800, 500};
  const Region region = parsed(box_with(line(R"(, "name": "levee", "size": 40)", a, b)));
  ASSERT_EQ(region.features.size(), 1u);
  EXPECT_EQ(region.features[0].size, 40.0);
  const SizeFieldResult f = make_size_field(region, field_options(10.0, 200.0));
  EXPECT_TRUE(f.warnings.empty());
  for (double x : {300.0, 1000.0, 1700.0}) {
    EXPECT_NEAR(f.field.at({x, 500.0}), 40.0, 0.15 * f.stats.cell) << x;      // s on the line, not HMIN
    EXPECT_LE(f.field.at({x, 650.0}), 40.0 + 0.15 * 150.0 + 1e-9) << x;       // s + grade * distance off it
  }
  EXPECT_NEAR(f.field.at({1000.0, 0.0}), 10.0, 0.15 * f.stats.cell);  // the boundary keeps HMIN
  EXPECT_GT(f.field.at({1000.0, 250.0}), 40.0);                       // between them, larger than both
}

// Meshed with the distance term off, so that only the line sets small sizes: the quads along it are its size
// across it and far larger away from it. Along the line their edges are a compromise with the far side of each
// structured subregion (as many quads along either side), so they are only bounded.
TEST(SizeAttribute, QuadsAlongAFeatureLineTakeItsSize) {
  const double s = 20.0;
  const LineEdges e = meshed_line_edges(s, field_options(10.0, 200.0, false), 350.0);
  ASSERT_GT(e.across.size(), 50u);
  ASSERT_GT(e.far_away.size(), 20u);
  EXPECT_GE(median(e.across), 0.7 * s);
  EXPECT_LE(median(e.across), 1.4 * s);
  EXPECT_LE(median(e.along), 2.0 * s);
  EXPECT_GT(median(e.far_away), 3.0 * s);  // the field there is at least 20 + 0.15 * 350 = 72.5
}

// With the distance term on and a size above HMIN, the line's quads take its size, not HMIN's, both ways.
TEST(SizeAttribute, FeatureLineSizeTakesHminsPlace) {
  const double s = 40.0;
  const LineEdges e = meshed_line_edges(s, field_options(20.0, 200.0), 350.0);
  ASSERT_GT(e.across.size(), 50u);
  for (const std::vector<double>* edges : {&e.along, &e.across}) {
    EXPECT_GE(median(*edges), 0.7 * s);
    EXPECT_LE(median(*edges), 1.4 * s);
  }
}

// A domain polygon part with a size: h <= size everywhere inside it, its own shore included (the size takes
// HMIN's place there); a part without one grades up from HMIN as before.
TEST(SizeAttribute, DomainPartBoundsTheFieldInside) {
  const std::string other = R"({"type": "Feature", "properties": {"role": "domain"}, "geometry": {"type": )"
                            R"("Polygon", "coordinates": [[[3000, 0], [5000, 0], [5000, 1000], [3000, 1000], [3000, 0]]]}})";
  const Region region = parsed(box_with(other, R"(, "size": 30)"));
  ASSERT_EQ(region.num_parts, 2);
  const SizeFieldResult f = make_size_field(region, field_options(10.0, 200.0));
  double sized_max = 0.0;
  for (int j = 0; j < f.field.ny(); ++j)
    for (int i = 0; i < f.field.nx(); ++i) {
      const Vec2 p = f.field.centre(i, j);
      if (p.x > 0 && p.x < 2000 && p.y > 0 && p.y < 1000) sized_max = std::max(sized_max, f.field.at(p));
    }
  EXPECT_LE(sized_max, 30.0 + 1e-9);
  EXPECT_NEAR(f.field.at({1000, 500}), 30.0, 1e-9);
  EXPECT_NEAR(f.field.at({1000, 0}), 30.0, 0.15 * f.stats.cell);
  EXPECT_NEAR(f.field.at({4000, 0}), 10.0, 0.15 * f.stats.cell);
  EXPECT_GT(f.field.at({4000, 500}), 60.0);
}

// Bad sizes are refused naming the file, the feature, its name and the value; null means none.
TEST(SizeAttribute, BadValuesAreRefusedByFeatureAndValue) {
  for (const std::string& bad : {std::string(R"("20")"), std::string("-5"), std::string("0"), std::string("true")}) {
    const std::string text = box_with(line(R"(, "name": "levee", "size": )" + bad, {200, 500}, {1800, 500}));
    try {
      parse_geojson(text, "sizes.geojson");
      ADD_FAILURE() << bad << " was taken";
    } catch (const InputError& e) {
      const std::string m = e.what();
      EXPECT_NE(m.find("sizes.geojson: feature 1"), std::string::npos) << m;
      EXPECT_NE(m.find("'levee'"), std::string::npos) << m;
      EXPECT_NE(m.find("size " + bad), std::string::npos) << m;
    }
  }
  EXPECT_THROW(parse_geojson(box_with("", R"(, "size": -1)"), "d.geojson"), InputError);
  EXPECT_EQ(parse_geojson(box_with(line(R"(, "size": null)", {200, 500}, {1800, 500})), "d.geojson").features[0].size,
            0.0);
}

// Through GDAL (--where makes read_input use it): numeric sizes are read, a text size field is refused naming the
// feature's FID and the value.
TEST(SizeAttribute, GdalReaderReadsAndRefusesSizes) {
  InputOptions gdal;
  gdal.where = "1=1";
  const fs::path good = written("size_attr_good", box_with(line(R"(, "size": 25.5)", {200, 500}, {1800, 500}), R"(, "size": 80)"));
  InputNotes notes;
  const Region r = read_input(good, gdal, notes);
  ASSERT_EQ(r.features.size(), 1u);
  EXPECT_EQ(r.features[0].size, 25.5);
  for (const Ring& ring : r.rings) EXPECT_EQ(ring.size, 80.0);
  const fs::path text = written("size_attr_text", box_with(line(R"(, "name": "levee", "size": "fine")", {200, 500}, {1800, 500})));
  try {
    read_input(text, gdal, notes);
    ADD_FAILURE() << "a text size was taken";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("FID 1"), std::string::npos) << m;
    EXPECT_NE(m.find("\"fine\""), std::string::npos) << m;
    EXPECT_NE(m.find("'levee'"), std::string::npos) << m;
  }
  fs::remove(good), fs::remove(text);
}

// Cut at crossings, every piece keeps its curve's size; a closed feature cut by a line keeps its inside's size
// in the region's size areas, and the field follows both.
TEST(SizeAttribute, SizesSurviveFeatureSplitting) {
  const std::string closed = R"({"type": "Feature", "properties": {"role": "feature", "size": 15}, "geometry": )"
                             R"({"type": "Polygon", "coordinates": [[[1200, 300], [1600, 300], [1600, 700], )"
                             R"([1200, 700], [1200, 300]]]}})";
  const Region region = parsed(box_with(line(R"(, "size": 25)", {200, 500}, {1800, 500}) + ", " +
                                        line("", {1000, 100}, {1000, 900}) + ", " + closed));
  auto pieces_of_size = [&](double size) {
    return std::count_if(region.features.begin(), region.features.end(), [&](const FeatureCurve& c) { return c.size == size; });
  };
  const auto sized25 = pieces_of_size(25.0), sized15 = pieces_of_size(15.0), unsized = pieces_of_size(0.0);
  EXPECT_EQ(sized25 + sized15 + unsized, static_cast<std::ptrdiff_t>(region.features.size()));
  EXPECT_GE(sized25, 4);  // cut by the vertical line and by the square's two sides
  EXPECT_GE(sized15, 2);  // the square, cut by the long line
  EXPECT_EQ(unsized, 2);  // the vertical line, cut by the long one
  ASSERT_EQ(region.size_areas.size(), 1u);
  EXPECT_EQ(region.size_areas[0].size, 15.0);
  const SizeFieldResult f = make_size_field(region, field_options(10.0, 200.0));
  EXPECT_LE(f.field.at({1400, 400}), 15.0 + 1e-9);                      // inside the square
  EXPECT_NEAR(f.field.at({400, 500}), 25.0, 0.15 * f.stats.cell);       // along the long line, off the square
  EXPECT_NEAR(f.field.at({1000, 800}), 10.0, 0.15 * f.stats.cell);      // the unsized line keeps HMIN
}

// Sizes outside [size_min, size_max] are said, naming the feature; the CLI says them, and says that uniform
// runs do not follow sizes at all.
TEST(SizeAttribute, ClippedAndUnusedSizesAreSaid) {
  const Region region = parsed(box_with(line(R"(, "name": "levee", "size": 5)", {200, 500}, {1800, 500})));
  const SizeFieldResult f = make_size_field(region, field_options(20.0, 200.0));
  ASSERT_EQ(f.warnings.size(), 1u);
  EXPECT_NE(f.warnings[0].find("feature 1 ('levee')"), std::string::npos) << f.warnings[0];
  EXPECT_NE(f.warnings[0].find("below --size-min 20"), std::string::npos) << f.warnings[0];
  EXPECT_NEAR(f.field.at({1000, 500}), 20.0, 1e-9);  // raised to HMIN
  const fs::path in = written("size_attr_cli", box_with(line(R"(, "name": "levee", "size": 5)", {200, 500}, {1800, 500})));
  const fs::path out = fs::temp_directory_path() / ("size_attr_cli_" + std::to_string(::getpid()) + ".msh");
  const CliRun uniform = run("mesh " + in.string() + " --size 100 -o " + out.string());
  EXPECT_EQ(uniform.code, 0) << uniform.err;
  EXPECT_NE(uniform.err.find("size attributes"), std::string::npos) << uniform.err;
  const CliRun graded = run("mesh " + in.string() + " --size-min 50 --size-max 200 -o " + out.string());
  EXPECT_EQ(graded.code, 0) << graded.err;
  EXPECT_NE(graded.err.find("'levee'"), std::string::npos) << graded.err;
  EXPECT_NE(graded.err.find("below --size-min"), std::string::npos) << graded.err;
  fs::remove(in), fs::remove(out);
}
