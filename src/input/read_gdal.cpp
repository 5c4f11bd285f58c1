#include "polysquare/input/read_gdal.h"

#include <cpl_error.h>
#include <gdal_priv.h>
#include <ogr_spatialref.h>
#include <ogrsf_frmts.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <memory>
#include <mutex>
#include <sstream>

#include "polysquare/core/error.h"

namespace polysquare {
namespace {

struct DatasetCloser {
  void operator()(GDALDataset* ds) const { GDALClose(ds); }
};
using Dataset = std::unique_ptr<GDALDataset, DatasetCloser>;

// GDAL's default handler prints to stderr; its messages are folded into our errors instead.
struct QuietErrors {
  QuietErrors() { CPLPushErrorHandler(CPLQuietErrorHandler); CPLErrorReset(); }
  ~QuietErrors() { CPLPopErrorHandler(); }
};

std::string gdal_message() {
  const char* m = CPLGetLastErrorMsg();
  return m && *m ? std::string(": ") + m : std::string();
}

Dataset open_vector(const std::filesystem::path& path) {
  static std::once_flag once;
  std::call_once(once, [] { GDALAllRegister(); });
  // NATIVE_DATA keeps the GeoJSON collection's own members, to see whether it has a "crs" member at all.
  const char* open_options[] = {"NATIVE_DATA=YES", nullptr};
  Dataset ds(static_cast<GDALDataset*>(
      GDALOpenEx(path.c_str(), GDAL_OF_VECTOR | GDAL_OF_READONLY, nullptr, open_options, nullptr)));
  if (!ds)
    throw InputError(path.string() + ": not a vector dataset GDAL can read (Shapefile, GeoPackage, GeoJSON, KML, GML, "
                     "DXF, FlatGeobuf, ...)" + gdal_message());
  if (ds->GetLayerCount() == 0) throw InputError(path.string() + ": no vector layer");
  return ds;
}

// The layer's CRS, or null when it has none. GDAL's GeoJSON driver assumes WGS 84 when the file has no "crs"
// member; the native reader takes such a file as planar, and both readers must agree.
const OGRSpatialReference* layer_srs(GDALDataset& ds, OGRLayer& layer) {
  const OGRSpatialReference* srs = layer.GetSpatialRef();
  if (!srs || !EQUAL(ds.GetDriverName(), "GeoJSON")) return srs;
  const char* native = layer.GetMetadataItem("NATIVE_DATA", "NATIVE_DATA");
  const nlohmann::json members = nlohmann::json::parse(native ? native : "{}", nullptr, false);
  return members.is_object() && members.contains("crs") ? srs : nullptr;
}

std::string crs_name(const OGRSpatialReference& srs) {
  const char* auth = srs.GetAuthorityName(nullptr);
  const char* code = srs.GetAuthorityCode(nullptr);
  if (auth && code && EQUAL(auth, "EPSG")) return std::string("EPSG:") + code;
  OGRSpatialReference copy(srs);
  if (copy.AutoIdentifyEPSG() == OGRERR_NONE && copy.GetAuthorityCode(nullptr))
    return std::string("EPSG:") + copy.GetAuthorityCode(nullptr);
  char* wkt = nullptr;
  const char* wkt_options[] = {"FORMAT=WKT2_2019", nullptr};
  srs.exportToWkt(&wkt, wkt_options);
  std::string out = wkt ? wkt : "";
  CPLFree(wkt);
  return out;
}

// Where one feature came from, and the region being filled.
struct Reader {
  Region& region;
  std::vector<std::string>& names;
  std::string where;  // "FILE, layer 'L', FID n", for messages
  int source = -1;
  const OGRCoordinateTransformation* transform = nullptr;
  std::string name, kind;  // the feature's `name` and `kind` attributes (empty when absent)
  double size = 0.0;       // its `size` attribute (0 when absent)
  const char* size_unused_on = nullptr;  // what took no size: "points", "boundary segments"
  // ESRI Shapefile stores outer rings clockwise and holes counter-clockwise: a writer turns rings of the other
  // orientation (GeoJSON's) around, keeping the first point. Such rings are turned back keeping it too, so the
  // ring has its original order and start, and the mesh is the one of the file it was converted from.
  bool clockwise_outer_rings = false;
  // The third coordinates read (polysquare meshes in 2D: varying z is dropped with a warning, as for GeoJSON).
  mutable double z_min = INFINITY, z_max = -INFINITY;
  std::string curved;  // the first curved geometry linearized ("CurvePolygon"), empty when none

  void note_z(double z) const {
    z_min = std::fmin(z_min, z);
    z_max = std::fmax(z_max, z);
  }

  [[noreturn]] void fail(const std::string& what) const { throw InputError(where + ": " + what); }

  // The `size` attribute: a quad size in region units, 0 when absent or null. A text field, or a size that is not
  // a positive finite number, is refused: a size taken wrongly would grade the whole mesh without a word.
  void read_size(OGRFeature& feature, int field) {
    if (field < 0 || !feature.IsFieldSetAndNotNull(field)) return;
    const std::string of = name.empty() ? std::string() : " of '" + name + "'";
    const OGRFieldType type = feature.GetFieldDefnRef(field)->GetType();
    if (type != OFTReal && type != OFTInteger && type != OFTInteger64)
      fail("size \"" + std::string(feature.GetFieldAsString(field)).substr(0, 80) + "\"" + of +
           " is not a number (the size field holds " + OGRFieldDefn::GetFieldTypeName(type) + "; give it a numeric type)");
    size = feature.GetFieldAsDouble(field);
    if (!(std::isfinite(size) && size > 0.0))
      fail("size " + std::string(feature.GetFieldAsString(field)) + of +
           " is not a positive number (the quad size, in the region's units)");
  }

  std::vector<Vec2> points(const OGRSimpleCurve& curve) const {
    std::vector<Vec2> out(static_cast<std::size_t>(curve.getNumPoints()));
    std::vector<double> x(out.size()), y(out.size());
    for (std::size_t i = 0; i < out.size(); ++i) {
      x[i] = curve.getX(static_cast<int>(i));
      y[i] = curve.getY(static_cast<int>(i));
      if (curve.Is3D()) note_z(curve.getZ(static_cast<int>(i)));
    }
    to_region_crs(x, y);
    for (std::size_t i = 0; i < out.size(); ++i) out[i] = {x[i], y[i]};
    return out;
  }

  void to_region_crs(std::vector<double>& x, std::vector<double>& y) const {
    if (!transform || x.empty()) return;
    std::vector<int> ok(x.size(), 0);
    const_cast<OGRCoordinateTransformation*>(transform)->Transform(x.size(), x.data(), y.data(), nullptr, ok.data());
    for (std::size_t i = 0; i < x.size(); ++i)
      if (!ok[i]) fail("cannot transform the point " + point_text({x[i], y[i]}) + " into the region's CRS");
  }

  // As for GeoJSON: a ring repeats its first point at the end; the repeat is dropped here.
  std::vector<Vec2> ring(const OGRLinearRing& r, int index) const {
    std::vector<Vec2> pts = points(r);
    if (pts.size() < 4)
      fail("ring " + std::to_string(index) + " has " + std::to_string(pts.size()) +
           " positions; a closed ring needs at least 4");
    if (!(pts.front() == pts.back()))
      fail("ring " + std::to_string(index) + " is not closed: first point " + point_text(pts.front()) + " differs from last point " +
           point_text(pts.back()));
    pts.pop_back();
    if (clockwise_outer_rings && (ring_signed_area(pts) < 0) == (index == 0)) std::reverse(pts.begin() + 1, pts.end());
    return pts;
  }

  // A line with role "boundary": a named piece of a ring, placed on it by validation.
  void add_boundary(const OGRGeometry& g) {
    if (g.IsEmpty()) return;
    if (g.hasCurveGeometry()) {
      std::unique_ptr<OGRGeometry> linear(g.getLinearGeometry());
      if (!linear) fail("cannot linearize a " + std::string(g.getGeometryName()));
      if (curved.empty()) curved = g.getGeometryName();
      add_boundary(*linear);
      return;
    }
    switch (wkbFlatten(g.getGeometryType())) {
      case wkbLineString: {
        size_unused_on = "boundary segments";
        BoundarySegment b;
        b.name = name;
        b.kind = kind;
        b.source_feature = source;
        b.line = points(*g.toLineString());
        region.boundary_segments.push_back(std::move(b));
        return;
      }
      case wkbMultiLineString:
      case wkbGeometryCollection:
        for (const OGRGeometry* part : *g.toGeometryCollection()) add_boundary(*part);
        return;
      default:
        fail("a boundary segment must be a line lying on the domain boundary, got " + std::string(g.getGeometryName()));
    }
  }

  void add(const OGRGeometry& g, bool domain) {
    if (g.IsEmpty()) return;
    if (g.hasCurveGeometry()) {  // arcs (GML, DXF, GeoPackage) become polylines at GDAL's default step, said
      std::unique_ptr<OGRGeometry> linear(g.getLinearGeometry());
      if (!linear) fail("cannot linearize a " + std::string(g.getGeometryName()));
      if (curved.empty()) curved = g.getGeometryName();
      add(*linear, domain);
      return;
    }
    switch (wkbFlatten(g.getGeometryType())) {
      case wkbPolygon: {
        const auto& poly = *g.toPolygon();
        if (domain) {
          const int part = region.num_parts++;
          for (int k = 0; k <= poly.getNumInteriorRings(); ++k) {
            const OGRLinearRing* r = k == 0 ? poly.getExteriorRing() : poly.getInteriorRing(k - 1);
            region.rings.push_back({ring(*r, k), part, k > 0, source, name, size});
          }
        } else {  // a polygon feature is a closed curve along each of its rings, as for GeoJSON
          for (int k = 0; k <= poly.getNumInteriorRings(); ++k)
            region.features.push_back({ring(k == 0 ? *poly.getExteriorRing() : *poly.getInteriorRing(k - 1), k), true,
                                       source, name, kind, size});
        }
        return;
      }
      case wkbLineString:
      case wkbLinearRing:
        if (domain) fail("a domain must be a polygon, got a line string (give it the role \"feature\")");
        if (wkbFlatten(g.getGeometryType()) == wkbLinearRing)
          region.features.push_back({ring(*g.toLinearRing(), 0), true, source, name, kind, size});
        else
          region.features.push_back({points(*g.toLineString()), false, source, name, kind, size});
        return;
      case wkbPoint: {
        if (domain) fail("a domain must be a polygon, got a point");
        size_unused_on = "points";
        std::vector<double> x{g.toPoint()->getX()}, y{g.toPoint()->getY()};
        if (g.Is3D()) note_z(g.toPoint()->getZ());
        to_region_crs(x, y);
        region.feature_points.push_back({x[0], y[0]});
        return;
      }
      case wkbMultiPolygon:
      case wkbMultiLineString:
      case wkbMultiPoint:
      case wkbGeometryCollection:
        for (const OGRGeometry* part : *g.toGeometryCollection()) add(*part, domain);
        return;
      default:
        fail("unsupported geometry " + std::string(g.getGeometryName()) +
             " (expected polygons for the domain, lines and points for features)");
    }
  }
};

bool contains(const std::vector<std::string>& names, const std::string& name) {
  return std::find(names.begin(), names.end(), name) != names.end();
}

}  // namespace

std::vector<std::string> gdal_layer_names(const std::filesystem::path& path) {
  QuietErrors quiet;
  Dataset ds = open_vector(path);
  std::vector<std::string> names;
  for (OGRLayer* layer : ds->GetLayers()) names.push_back(layer->GetName());
  return names;
}

namespace {

// Which role a layer's geometries take: forced by a layer option, else the attribute or the default.
enum class Mode { skip, by_attribute, domain, feature, boundary };

Mode layer_mode(const std::string& name, LayerRole default_role, const InputOptions& options) {
  if (default_role == LayerRole::boundary) return Mode::boundary;
  if (name == options.domain_layer && default_role == LayerRole::by_geometry) return Mode::domain;
  if (contains(options.feature_layers, name)) return Mode::feature;
  if (!options.feature_layers.empty() && (default_role == LayerRole::feature || !options.domain_layer.empty()))
    return Mode::skip;
  if (!options.domain_layer.empty()) return Mode::feature;
  return Mode::by_attribute;
}

// The layer's CRS as it is meant: none for planar units, WGS 84 (in `wgs84`) for GeoPackage's undefined
// geographic one.
const OGRSpatialReference* defined_srs(GDALDataset& ds, OGRLayer& layer, const std::filesystem::path& path,
                                       InputNotes& notes, OGRSpatialReference& wgs84) {
  const std::string file = path.string(), name = layer.GetName();
  const OGRSpatialReference* srs = layer_srs(ds, layer);
  // A Shapefile whose .prj GDAL cannot read comes without a CRS: refused, not meshed as planar units (a lon/lat
  // file would be meshed in degrees without a word).
  if (!srs && EQUAL(ds.GetDriverName(), "ESRI Shapefile"))
    for (const char* ext : {".prj", ".PRJ"})
      if (std::filesystem::path prj = std::filesystem::path(path).replace_extension(ext); std::filesystem::exists(prj))
        throw InputError(prj.string() + ": GDAL cannot read the CRS in it; correct it (ogr2ogr -a_srs EPSG:n writes "
                         "one) or remove it to mesh the coordinates as planar units");
  // GeoPackage's undefined CRSs: srs_id -1 (Cartesian) is planar units, as no CRS; srs_id 0 (geographic, datum
  // unknown) is taken as WGS 84 longitude/latitude, said.
  if (srs && srs->IsLocal()) {
    const char* n = srs->GetName();
    if (!n || std::string(n) != "Undefined Cartesian SRS")
      notes.warnings.push_back(file + ", layer '" + name + "' is in a local engineering CRS" +
                               (n ? " '" + std::string(n) + "'" : std::string()) + ": its coordinates are meshed as planar units");
    srs = nullptr;
  } else if (srs && srs->IsGeographic() && srs->GetName() && std::string(srs->GetName()) == "Undefined geographic SRS") {
    wgs84.importFromEPSG(4326);
    notes.warnings.push_back(file + ", layer '" + name + "' has an undefined geographic CRS (GeoPackage srs_id 0): "
                             "its longitudes and latitudes are taken as WGS 84 (EPSG:4326; ogr2ogr -a_srs sets the right one)");
    srs = &wgs84;
  }
  return srs;
}

// The transform from the layer's CRS to the region's (null when they agree or either has none); the first layer
// with a CRS gives the region its CRS.
std::unique_ptr<OGRCoordinateTransformation> to_region_srs(const OGRSpatialReference* srs, const std::string& where,
                                                           Region& region, OGRSpatialReference& region_srs,
                                                           bool& have_region_srs, InputNotes& notes) {
  std::unique_ptr<OGRCoordinateTransformation> transform;
  if (srs) {
    OGRSpatialReference layer_srs_gis(*srs);
    layer_srs_gis.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
    if (!have_region_srs && region.rings.empty() && region.features.empty() && region.feature_points.empty()) {
      region_srs = layer_srs_gis;
      have_region_srs = true;
      region.crs = crs_name(layer_srs_gis);
    } else if (!have_region_srs) {
      notes.warnings.push_back(where + " is in " + crs_name(layer_srs_gis) +
                               " but what was read before names no CRS; its coordinates are taken as they are");
    } else if (!layer_srs_gis.IsSame(&region_srs)) {
      transform.reset(OGRCreateCoordinateTransformation(&layer_srs_gis, &region_srs));
      if (!transform)
        throw InputError(where + ": cannot transform from " + crs_name(layer_srs_gis) + " to " +
                         region.crs + gdal_message());
    }
  }
  return transform;
}

struct LayerSource {
  std::string where;      // "file, layer 'name'"
  bool shapefile = false; // outer rings clockwise
};

// Every feature of `layer` read into `region` in its role, with the layer's warnings (varying z, arcs).
void read_layer(OGRLayer& layer, Mode mode, LayerRole default_role, const LayerSource& source,
                OGRCoordinateTransformation* transform, Region& region, std::vector<std::string>& feature_names,
                InputNotes& notes) {
  const int role_field = layer.GetLayerDefn()->GetFieldIndex("role");
  const int name_field = layer.GetLayerDefn()->GetFieldIndex("name");
  const int kind_field = layer.GetLayerDefn()->GetFieldIndex("kind");
  const int size_field = layer.GetLayerDefn()->GetFieldIndex("size");
  CPLErrorReset();
  layer.ResetReading();
  std::size_t varying_z = 0, curved = 0;
  std::string first_varying_z, first_curved;
  for (auto& feature : layer) {
    Reader reader{region, feature_names,
                  source.where + ", FID " + std::to_string(feature->GetFID()),
                  static_cast<int>(feature_names.size()), transform};
    reader.clockwise_outer_rings = source.shapefile;
    feature_names.push_back(reader.where);
    if (name_field >= 0 && feature->IsFieldSetAndNotNull(name_field)) reader.name = feature->GetFieldAsString(name_field);
    if (kind_field >= 0 && feature->IsFieldSetAndNotNull(kind_field)) reader.kind = feature->GetFieldAsString(kind_field);
    reader.read_size(*feature, size_field);
    const OGRGeometry* g = feature->GetGeometryRef();
    if (!g)
      reader.fail("the feature has no geometry (a row without a shape: delete it, or leave it out with --where)");
    std::string role = mode == Mode::boundary ? "boundary"
                       : mode == Mode::domain ? "domain"
                       : mode == Mode::feature ? "feature"
                                               : "";
    if (mode == Mode::by_attribute && role_field >= 0 && feature->IsFieldSetAndNotNull(role_field))
      role = feature->GetFieldAsString(role_field);
    if (role.empty()) {
      const OGRwkbGeometryType t = wkbFlatten(g->getGeometryType());
      const bool polygon = t == wkbPolygon || t == wkbMultiPolygon || t == wkbCurvePolygon || t == wkbMultiSurface;
      role = default_role == LayerRole::by_geometry && polygon ? "domain" : "feature";
    }
    if (role == "boundary") reader.add_boundary(*g);
    else if (role == "domain" || role == "feature") reader.add(*g, role == "domain");
    else reader.fail("unknown role \"" + role + "\" (expected \"domain\", \"feature\" or \"boundary\")");
    if (reader.z_min < reader.z_max && varying_z++ == 0) first_varying_z = "FID " + std::to_string(feature->GetFID());
    if (!reader.curved.empty() && curved++ == 0)
      first_curved = "FID " + std::to_string(feature->GetFID()) + " (a " + reader.curved + ")";
    if (reader.size > 0.0 && reader.size_unused_on)
      notes.warnings.push_back(reader.where + ": its size is not used (sizes hold inside domain polygons and along "
                               "feature lines and polygons, not on " + std::string(reader.size_unused_on) + ")");
  }
  if (varying_z > 0)
    notes.warnings.push_back(source.where + ": " + first_varying_z +
                             (varying_z > 1 ? " and " + std::to_string(varying_z - 1) + " more features have" : std::string(" has")) +
                             " positions whose third coordinate (z) varies; the mesh is 2D and z is dropped");
  if (curved > 0)
    notes.warnings.push_back(source.where + ": " + first_curved +
                             (curved > 1 ? " and " + std::to_string(curved - 1) + " more curved geometries are" : std::string(" is")) +
                             " linearized: arcs become straight segments at GDAL's default step (4 degrees of arc)");
}

}  // namespace

void read_gdal(const std::filesystem::path& path, LayerRole default_role, const InputOptions& options, Region& region,
               std::vector<std::string>& feature_names, InputNotes& notes) {
  QuietErrors quiet;
  const std::string file = path.string();
  Dataset ds = open_vector(path);
  std::vector<std::string> layer_names;
  for (OGRLayer* layer : ds->GetLayers()) layer_names.push_back(layer->GetName());
  auto list = [&] {
    std::string s;
    for (const std::string& n : layer_names) s += (s.empty() ? "'" : ", '") + n + "'";
    return s;
  };
  // A --domain-layer belongs to the main input; --feature-layer names may be in any file, checked by the caller.
  if (default_role == LayerRole::by_geometry && !options.domain_layer.empty() && !contains(layer_names, options.domain_layer))
    throw InputError(file + ": no layer '" + options.domain_layer + "' (--domain-layer); its layers are " + list());

  OGRSpatialReference region_srs;
  region_srs.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  bool have_region_srs = false;
  if (!region.crs.empty()) {
    const char* no_io[] = {"ALLOW_NETWORK_ACCESS=NO", "ALLOW_FILE_ACCESS=NO", nullptr};
    have_region_srs = region_srs.SetFromUserInput(region.crs.c_str(), no_io) == OGRERR_NONE;
  }
  for (OGRLayer* layer : ds->GetLayers()) {
    const std::string name = layer->GetName();
    const Mode mode = layer_mode(name, default_role, options);
    if (mode == Mode::skip) continue;

    if (!options.where.empty() && layer->SetAttributeFilter(options.where.c_str()) != OGRERR_NONE)
      throw InputError(file + ", layer '" + name + "': --where \"" + options.where + "\" is not a valid filter here" +
                       gdal_message());
    // An attribute table (a GeoPackage table without a geometry column) has no shapes to mesh: skipped with a
    // warning, refused when an option names it.
    if (layer->GetLayerDefn()->GetGeomFieldCount() == 0) {
      const bool named = name == options.domain_layer || contains(options.feature_layers, name);
      if (named)
        throw InputError(file + ", layer '" + name + "' has no geometry column (an attribute table); " +
                         (name == options.domain_layer ? "--domain-layer" : "--feature-layer") +
                         " needs a layer of shapes; the layers are " + list());
      notes.warnings.push_back(file + ", layer '" + name + "' has no geometry column (an attribute table): skipped");
      continue;
    }
    OGRSpatialReference wgs84;
    const OGRSpatialReference* srs = defined_srs(*ds, *layer, path, notes, wgs84);
    const std::unique_ptr<OGRCoordinateTransformation> transform =
        to_region_srs(srs, file + ", layer '" + name + "'", region, region_srs, have_region_srs, notes);
    read_layer(*layer, mode, default_role, LayerSource{file + ", layer '" + name + "'", EQUAL(ds->GetDriverName(), "ESRI Shapefile")},
               transform.get(), region, feature_names, notes);
    // Some drivers (GeoPackage) only run the filter while reading and then stop early without a feature.
    if (CPLGetLastErrorType() == CE_Failure)
      throw InputError(file + ", layer '" + name + "': reading failed" +
                       (options.where.empty() ? std::string() : " (--where \"" + options.where + "\")") + gdal_message());
  }
}

}  // namespace polysquare
