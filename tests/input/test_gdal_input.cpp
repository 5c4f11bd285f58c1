// GDAL/OGR input (Shapefile, GeoPackage, GeoJSON through OGR), CRS handling and read-time snapping.
// Inputs are made at test time from data/cases with ogr2ogr (gdal-bin), an independent writer.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>

#include <unistd.h>

#include "polysquare/core/error.h"
#include "polysquare/input/project_region.h"
#include "polysquare/input/read_gdal.h"
#include "polysquare/input/read_region.h"
#include "polysquare/pipeline/mesh_region.h"

namespace fs = std::filesystem;
using namespace polysquare;

namespace {

const std::string kCases = std::string(POLYSQUARE_DATA_DIR) + "/cases/";

// A fresh directory per test, so tests can run in parallel.
fs::path scratch(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("polysquare_gdal_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

void ogr2ogr(const std::string& args) {
  const std::string cmd = "ogr2ogr " + args + " 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
}

double area(const Region& r) {
  double a = 0;
  for (const Ring& ring : r.rings)
    for (std::size_t i = 0; i < ring.points.size(); ++i) a += 0.5 * cross(ring.points[i], ring.points[(i + 1) % ring.points.size()]);
  return a;
}

// Same rings, curves and points, vertex by vertex within tol, every ring from the same first point (Shapefile
// writers turn outer rings clockwise keeping the first point; the reader turns them back keeping it, so the
// mesh is the one of the file converted).
void expect_same_region(const Region& a, const Region& b, double tol) {
  ASSERT_EQ(a.rings.size(), b.rings.size());
  ASSERT_EQ(a.features.size(), b.features.size());
  ASSERT_EQ(a.feature_points.size(), b.feature_points.size());
  EXPECT_EQ(a.num_parts, b.num_parts);
  EXPECT_EQ(a.crs, b.crs);
  EXPECT_EQ(a.units, b.units);
  double worst = 0;
  for (std::size_t r = 0; r < a.rings.size(); ++r) {
    ASSERT_EQ(a.rings[r].points.size(), b.rings[r].points.size()) << "ring " << r;
    EXPECT_EQ(a.rings[r].hole, b.rings[r].hole);
    const auto &p = a.rings[r].points, &q = b.rings[r].points;
    for (std::size_t i = 0; i < p.size(); ++i) worst = std::max(worst, distance(p[i], q[i]));
  }
  for (std::size_t f = 0; f < a.features.size(); ++f) {
    ASSERT_EQ(a.features[f].points.size(), b.features[f].points.size()) << "curve " << f;
    EXPECT_EQ(a.features[f].closed, b.features[f].closed);
    for (std::size_t i = 0; i < a.features[f].points.size(); ++i)
      worst = std::max(worst, distance(a.features[f].points[i], b.features[f].points[i]));
  }
  EXPECT_LE(worst, tol);
  EXPECT_NEAR(area(a), area(b), 1e-9 * std::abs(area(a)));
}

}  // namespace

TEST(GdalInput, GeoPackageShapefilesAndOgrGeoJsonGiveTheNativeRegion) {
  const fs::path dir = scratch("formats");
  const std::string src = kCases + "delta_box.geojson";
  const Region native = read_region(src);
  ASSERT_EQ(native.crs, "EPSG:32616");
  ASSERT_GT(native.features.size(), 50u);

  ogr2ogr("-f GPKG " + (dir / "db.gpkg").string() + " " + src + " -nln domain -where \"role='domain'\"");
  ogr2ogr("-f GPKG -update " + (dir / "db.gpkg").string() + " " + src + " -nln features -where \"role='feature'\"");
  ogr2ogr((dir / "domain.shp").string() + " " + src + " -where \"role='domain'\"");
  ogr2ogr((dir / "features.shp").string() + " " + src + " -where \"role='feature'\" -nlt LINESTRING");

  InputNotes notes;
  expect_same_region(read_input(dir / "db.gpkg", {}, notes), native, 0.0);
  EXPECT_EQ(gdal_layer_names(dir / "db.gpkg"), (std::vector<std::string>{"domain", "features"}));

  InputOptions two_files;
  two_files.feature_files = {dir / "features.shp"};
  expect_same_region(read_input(dir / "domain.shp", two_files, notes), native, 0.0);

  // The same GeoJSON through OGR (a filter sends it there) and natively.
  InputOptions filtered;
  filtered.where = "role IN ('domain', 'feature')";
  expect_same_region(read_input(src, filtered, notes), native, 0.0);

  // Layers chosen by name give the same region whatever their role attributes say.
  InputOptions layers;
  layers.domain_layer = "domain";
  layers.feature_layers = {"features"};
  expect_same_region(read_input(dir / "db.gpkg", layers, notes), native, 0.0);

  // Other formats GDAL writes and reads back: FlatGeobuf and GML keep the UTM coordinates, KML is lon/lat by
  // definition and comes back through the UTM projection.
  // Without the spatial index FlatGeobuf keeps the features in order (with it, in Hilbert order).
  ogr2ogr("-f FlatGeobuf -nlt GEOMETRY -lco SPATIAL_INDEX=NO " + (dir / "db.fgb").string() + " " + src);
  ogr2ogr("-f GML " + (dir / "db.gml").string() + " " + src);
  ogr2ogr("-f KML " + (dir / "db.kml").string() + " " + src);
  expect_same_region(read_input(dir / "db.fgb", {}, notes), native, 0.0);
  expect_same_region(read_input(dir / "db.gml", {}, notes), native, 1e-6);
  expect_same_region(read_input(dir / "db.kml", {}, notes), native, 1e-4);

  // A filter keeps only the rivers: fewer curves, same domain.
  InputOptions rivers;
  rivers.where = "role = 'domain' OR kind = 'river'";
  const Region r = read_input(dir / "db.gpkg", rivers, notes);
  EXPECT_EQ(r.rings.size(), native.rings.size());
  EXPECT_GT(r.features.size(), 0u);
  EXPECT_LT(r.features.size(), native.features.size());
  fs::remove_all(dir);
}

TEST(GdalInput, LonLatInputIsProjectedToTheUtmZoneOfItsCentre) {
  const fs::path dir = scratch("lonlat");
  const std::string src = kCases + "delta_box.geojson";
  const Region native = read_region(src);
  ogr2ogr("-f GeoJSON -t_srs EPSG:4326 -lco COORDINATE_PRECISION=12 " + (dir / "ll.geojson").string() + " " + src);
  ogr2ogr("-f GPKG -t_srs EPSG:4326 " + (dir / "ll.gpkg").string() + " " + src);
  for (const fs::path& file : {dir / "ll.geojson", dir / "ll.gpkg"}) {
    InputNotes notes;
    const Region r = read_input(file, {}, notes);
    EXPECT_TRUE(notes.reprojected) << file;
    EXPECT_NE(notes.input_crs.find(file.extension() == ".gpkg" ? "4326" : "CRS84"), std::string::npos) << notes.input_crs;
    EXPECT_EQ(r.crs, "EPSG:32616");  // the box is at 89.3 W: zone 16
    EXPECT_EQ(r.units, "m");
    // Back where the UTM file has it: 1e-12 degrees of rounding is about 1e-7 m.
    expect_same_region(r, native, 1e-4);
  }
  // An explicit --crs wins: zone 15 is a different plane, with the same area within the scale error.
  InputOptions zone15;
  zone15.crs = "EPSG:32615";
  InputNotes notes;
  const Region r15 = read_input(dir / "ll.gpkg", zone15, notes);
  EXPECT_EQ(r15.crs, "EPSG:32615");
  EXPECT_GT(distance(r15.rings[0].points[0], native.rings[0].points[0]), 1e4);
  EXPECT_NEAR(area(r15), area(native), 1e-2 * area(native));  // 3.7 degrees off zone 15's meridian: +0.3 %
  zone15.crs = "EPSG:4326";  // not projected
  EXPECT_THROW(read_input(dir / "ll.gpkg", zone15, notes), InputError);

  EXPECT_EQ(utm_epsg(-89.3, 29.1), 32616);
  EXPECT_EQ(utm_epsg(10.7, 59.9), 32632);
  EXPECT_EQ(utm_epsg(151.2, -33.9), 32756);
  EXPECT_EQ(utm_epsg(180.0, 0.0), 32601);
  fs::remove_all(dir);
}

TEST(GdalInput, LonLatDeltaBoxMeshesAt200Metres) {
  const fs::path dir = scratch("mesh");
  ogr2ogr("-f GeoJSON -t_srs EPSG:4326 " + (dir / "ll.geojson").string() + " " + kCases + "delta_box.geojson");
  const Region region = read_region(dir / "ll.geojson");
  ASSERT_EQ(region.crs, "EPSG:32616");
  MeshOptions options;
  options.size.h = 200;          // metres; in degrees this size was refused as larger than the region
  options.subregions.parts = 1;  // one candidate (about a minute): the default search takes many minutes on this part
  const MeshResult result = mesh_region(region, options);
  EXPECT_GT(result.mesh.quads.size(), 30000u);  // about 1.7e9 m^2 / 200^2 = 42,000 elements of h^2
  EXPECT_EQ(result.mesh.crs, "EPSG:32616");
  EXPECT_EQ(result.report.input.crs, "EPSG:32616");
  fs::remove_all(dir);
}

TEST(GdalInput, DegreeLookingCoordinatesWithoutCrsAreWarnedAbout) {
  const fs::path dir = scratch("degrees");
  ogr2ogr("-f GeoJSON -t_srs EPSG:4326 -lco RFC7946=YES " + (dir / "ll.geojson").string() + " " + kCases +
          "delta_box.geojson");
  InputNotes notes;
  const Region r = read_input(dir / "ll.geojson", {}, notes);  // RFC 7946 writes no "crs" member
  EXPECT_TRUE(r.crs.empty());
  EXPECT_FALSE(notes.reprojected);
  ASSERT_EQ(notes.warnings.size(), 1u);
  EXPECT_NE(notes.warnings[0].find("degrees"), std::string::npos) << notes.warnings[0];
  EXPECT_NE(notes.warnings[0].find("-89.5"), std::string::npos) << notes.warnings[0];
  // OGR would assume WGS 84 for the same file; both readers agree that it names no CRS.
  InputOptions through_ogr;
  through_ogr.where = "1 = 1";
  InputNotes ogr_notes;
  expect_same_region(read_input(dir / "ll.geojson", through_ogr, ogr_notes), r, 0.0);
  EXPECT_EQ(ogr_notes.warnings.size(), 1u);
  // Planar shapes in whole units are not mistaken for degrees.
  for (const char* name : {"letter_M", "square_feature", "smile", "dam_channel"}) {
    InputNotes planar;
    read_input(kCases + name + ".geojson", {}, planar);
    EXPECT_TRUE(planar.warnings.empty()) << name;
  }
  InputOptions crs;
  crs.crs = "EPSG:32616";
  EXPECT_THROW(read_input(dir / "ll.geojson", crs, notes), InputError);  // nothing to reproject from
  fs::remove_all(dir);
}

TEST(GdalInput, GeographicCrsWithCoordinatesOffTheEarthIsRefused) {
  // A UTM region labelled EPSG:4326 (and a fuzzed file with x = 3e35): refused with the file and the range, not
  // projected to some UTM zone (before: an int overflow picking the zone).
  const fs::path dir = scratch("offearth");
  for (const char* x : {"3e35", "284000"}) {
    const fs::path file = dir / (std::string("off_") + x + ".geojson");
    std::ofstream(file) << R"({"type": "FeatureCollection", "crs": {"type": "name", "properties": {"name": "EPSG:4326"}},
      "features": [{"type": "Feature", "properties": {}, "geometry": {"type": "Polygon", "coordinates": [[[)"
                        << x << R"(, 10], [)" << x << R"(, 11], [10, 11], [10, 10], [)" << x << R"(, 10]]]}}]})";
    InputNotes notes;
    try {
      read_input(file, {}, notes);
      ADD_FAILURE() << x << ": accepted";
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(file.filename().string()), std::string::npos) << what;
      EXPECT_NE(what.find("outside longitude"), std::string::npos) << what;
    }
  }
  EXPECT_EQ(utm_epsg(3e35, 10.0), 32631);  // clamped to 360 degrees, which is 0
  EXPECT_EQ(utm_epsg(-1e300, -5.0), 32701);
  fs::remove_all(dir);
}

TEST(GdalInput, NearCoincidentPointsAreSnappedAndReported) {
  const fs::path dir = scratch("snap");
  const fs::path file = dir / "near.geojson";
  // Curve 1 ends 1e-7 inside the right edge (tolerance 1e-9 x 1414 = 1.4e-6), curve 2 ends 1e-7 off curve 1's
  // interior, curve 3 ends 1.4e-7 from the corner (0, 1000), and a feature point sits 1e-7 from curve 1's start.
  std::ofstream(file) << R"({"type": "FeatureCollection", "features": [
{"type": "Feature", "properties": {"role": "domain"}, "geometry": {"type": "Polygon", "coordinates": [[[0,0],[1000,0],[1000,1000],[0,1000],[0,0]]]}},
{"type": "Feature", "properties": {}, "geometry": {"type": "LineString", "coordinates": [[300,500],[999.9999999,500]]}},
{"type": "Feature", "properties": {}, "geometry": {"type": "LineString", "coordinates": [[600,100],[600,499.9999999]]}},
{"type": "Feature", "properties": {}, "geometry": {"type": "LineString", "coordinates": [[200,800],[0.0000001,999.9999999]]}},
{"type": "Feature", "properties": {}, "geometry": {"type": "Point", "coordinates": [300.0000001, 500]}}
]})";
  InputNotes notes;
  const Region r = read_input(file, {}, notes);
  std::string all;
  for (const std::string& n : notes.snaps) all += n + "\n";
  ASSERT_EQ(notes.snaps.size(), 4u) << all;
  EXPECT_NE(notes.snaps[0].find("feature 1"), std::string::npos) << notes.snaps[0];
  EXPECT_NE(notes.snaps[0].find("(999.9999999, 500)"), std::string::npos) << notes.snaps[0];
  EXPECT_NE(notes.snaps[0].find("onto ring 0"), std::string::npos) << notes.snaps[0];
  // The right edge now has the curve's end as a vertex, and curve 2 meets curve 1 at a shared node.
  auto has = [](const std::vector<Vec2>& pts, Vec2 p) { return std::find(pts.begin(), pts.end(), p) != pts.end(); };
  EXPECT_TRUE(has(r.rings[0].points, Vec2{1000, 500}));
  EXPECT_TRUE(has(r.rings[0].points, Vec2{0, 1000}));
  EXPECT_EQ(r.rings[0].points.size(), 5u);
  // Curve 1 is cut where curve 2 now ends: three curve ends share one point next to (600, 500).
  std::map<std::pair<double, double>, int> ends;
  for (const FeatureCurve& c : r.features)
    for (Vec2 p : {c.points.front(), c.points.back()})
      if (distance(p, {600, 500}) < 1e-6) ++ends[{p.x, p.y}];
  ASSERT_EQ(ends.size(), 1u);
  EXPECT_EQ(ends.begin()->second, 3);
  ASSERT_EQ(r.feature_points.size(), 1u);
  EXPECT_TRUE(r.feature_points[0] == (Vec2{300, 500}));
  // The snapped region meshes; its curves end on mesh nodes on the boundary.
  MeshOptions options;
  options.size.h = 50;
  const MeshResult result = mesh_region(r, options);
  EXPECT_GT(result.mesh.quads.size(), 100u);
  bool node_at_end = false;
  for (Vec2 p : result.mesh.nodes) node_at_end |= p == Vec2{1000, 500};
  EXPECT_TRUE(node_at_end);
  // Points farther than the tolerance are left alone.
  InputOptions tight;
  tight.snap_relative = 1e-12;
  InputNotes none;
  read_input(file, tight, none);
  EXPECT_TRUE(none.snaps.empty());
  fs::remove_all(dir);
}

TEST(GdalInput, BadInputNamesFileLayerAndFeature) {
  const fs::path dir = scratch("bad");
  const std::string src = kCases + "delta_box.geojson";
  ogr2ogr("-f GPKG " + (dir / "db.gpkg").string() + " " + src + " -nln domain -where \"role='domain'\"");
  ogr2ogr("-f GPKG -update " + (dir / "db.gpkg").string() + " " + src + " -nln features -where \"role='feature'\"");
  auto message = [](const fs::path& p, const InputOptions& o) {
    InputNotes notes;
    try {
      read_input(p, o, notes);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message(dir / "missing.shp", {}).find("missing.shp"), std::string::npos);
  InputOptions o;
  o.domain_layer = "coast";
  const std::string no_layer = message(dir / "db.gpkg", o);
  EXPECT_NE(no_layer.find("'coast'"), std::string::npos) << no_layer;
  EXPECT_NE(no_layer.find("'features'"), std::string::npos) << no_layer;  // lists what there is
  o.domain_layer = "features";  // lines cannot be a domain
  const std::string lines = message(dir / "db.gpkg", o);
  EXPECT_NE(lines.find("layer 'features', FID 1"), std::string::npos) << lines;
  o = {};
  o.where = "no_such_column = 3";
  EXPECT_NE(message(dir / "db.gpkg", o).find("--where"), std::string::npos);
  o = {};
  o.feature_layers = {"levees"};
  EXPECT_NE(message(dir / "db.gpkg", o).find("'levees'"), std::string::npos);
  // Validation's message, for input read through OGR, also names the layer and FID of the feature.
  ogr2ogr("-f GPKG " + (dir / "bad.gpkg").string() + " " + std::string(POLYSQUARE_TEST_DATA_DIR) +
          "/bad/self_intersection.geojson -nln crossing");
  const std::string crossing = message(dir / "bad.gpkg", {});
  EXPECT_NE(crossing.find("intersects itself at ("), std::string::npos) << crossing;
  EXPECT_NE(crossing.find("bad.gpkg, layer 'crossing', FID 1"), std::string::npos) << crossing;
  fs::remove_all(dir);
}

// Issue 52: the longitudes' arc is taken on the circle, so a region across the antimeridian gets the UTM zone of
// its own centre (180), not of the mean of -180 .. 180 (0, zone 31).
TEST(GdalInput, LongitudeRangeIsTakenOnTheCircle) {
  const LonRange across = longitude_range({179.9, -179.9, 180.0});
  EXPECT_NEAR(across.width, 0.2, 1e-9);
  EXPECT_NEAR(across.west, 179.9, 1e-9);
  EXPECT_TRUE(across.crosses_antimeridian);
  EXPECT_EQ(utm_epsg(across.centre, -17.0), 32701);
  const LonRange greenwich = longitude_range({-0.1, 0.1});
  EXPECT_NEAR(greenwich.width, 0.2, 1e-9);
  EXPECT_NEAR(greenwich.centre, 0.0, 1e-9);
  EXPECT_FALSE(greenwich.crosses_antimeridian);
  const LonRange east360 = longitude_range({179.9, 180.1});  // longitudes past 180 as some files write them
  EXPECT_NEAR(east360.width, 0.2, 1e-9);
  EXPECT_TRUE(std::abs(east360.centre) == 180.0 || std::abs(east360.centre) < 1e-9 || east360.centre == -180.0);
  EXPECT_NEAR(longitude_range({-100, 0, 100}).width, 200.0, 1e-9);
  EXPECT_NEAR(longitude_range({10, 12}).centre, 11.0, 1e-9);
}

// Issue 52: messages about a projected lon/lat region name places in lon/lat, the coordinates of the user's file.
TEST(GdalInput, PlacesInMessagesAreInTheInputsCoordinates) {
  Region region;
  region.source = "bay";
  region.crs = "EPSG:4326";
  region.rings.push_back({{{-122.5, 37.7}, {-122.45, 37.7}, {-122.45, 37.7}, {-122.4, 37.7}, {-122.4, 37.8}, {-122.5, 37.8}}, 0, false, 0, "", 0.0});
  region.num_parts = 1;
  InputNotes notes;
  project_region(region, "", notes);
  ASSERT_TRUE(notes.reprojected);
  const std::unique_ptr<PlaceTextHook> places = input_place_text(region, notes);
  ASSERT_TRUE(places);
  const Vec2 p = region.rings[0].points[1];
  EXPECT_EQ(point_text(p).substr(0, 2), "(5");  // UTM metres without the hook
  {
    const ScopedPlaceText scoped(places.get());
    EXPECT_EQ(point_text(p), "(-122.45, 37.7)");
    try {
      validate_region(region);
      ADD_FAILURE() << "a repeated point must be refused";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("repeats the point (-122.45, 37.7)"), std::string::npos) << e.what();
    }
  }
  EXPECT_EQ(point_text(p).substr(0, 2), "(5");  // the hook ends with its scope
}
