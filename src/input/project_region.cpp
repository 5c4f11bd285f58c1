#include "polysquare/input/project_region.h"

#include <cpl_error.h>
#include <ogr_geometry.h>
#include <ogr_spatialref.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <sstream>
#include <vector>

#include "io/crs_info.h"
#include "polysquare/core/error.h"

namespace polysquare {
namespace {

std::string units_of(const OGRSpatialReference& srs) {
  const char* name = nullptr;
  const double to_metre = srs.GetLinearUnits(&name);
  if (std::abs(to_metre - 1.0) < 1e-12) return "m";
  return name ? name : "";
}

// Coordinates that fit lon/lat ranges, span less than a continent and carry many decimals are probably degrees.
// Whole numbers (letters drawn on a grid, unit squares) are not: they are typical of planar test shapes.
bool looks_like_degrees(const Region& region, const Box2& box) {
  if (box.lo.x < -180 || box.hi.x > 360 || box.lo.y < -90 || box.hi.y > 90) return false;
  if (box.hi.x - box.lo.x > 30 || box.hi.y - box.lo.y > 30) return false;
  auto fine = [](const std::vector<Vec2>& pts) {
    for (Vec2 p : pts)
      if (std::abs(p.x * 1e4 - std::round(p.x * 1e4)) > 1e-6) return true;
    return false;
  };
  for (const Ring& r : region.rings)
    if (fine(r.points)) return true;
  for (const FeatureCurve& c : region.features)
    if (fine(c.points)) return true;
  return false;
}

std::string number_text(double v) {
  std::ostringstream os;
  os.precision(6);
  os << v;
  return os.str();
}

// Every longitude of the region (rings, curves, points, boundary segments), in degrees.
std::vector<double> longitudes(const Region& region, double to_degree) {
  std::vector<double> lon;
  auto add = [&](const std::vector<Vec2>& pts) {
    for (Vec2 p : pts) lon.push_back(p.x * to_degree);
  };
  for (const Ring& r : region.rings) add(r.points);
  for (const FeatureCurve& c : region.features) add(c.points);
  add(region.feature_points);
  for (const BoundarySegment& b : region.boundary_segments) add(b.line);
  return lon;
}

// A region split at the antimeridian (RFC 7946 asks for it) comes as polygon parts meeting along longitude 180:
// the parts with a vertex there are united (GEOS through OGR), with their western longitudes taken past 180 so
// the pieces are contiguous; said in a warning. Meshed as given, the parts would meet along the seam (refused) or
// be meshed apart with a wall between them. Attributes (name, size) of the first part united are kept.
void unite_antimeridian_parts(Region& region, double to_degree, InputNotes& notes) {
  std::vector<int> on_seam;
  for (int part = 0; part < region.num_parts; ++part) {
    bool seam = false;
    for (const Ring& r : region.rings)
      if (r.part == part)
        for (Vec2 p : r.points) seam |= p.x * to_degree == 180.0;
    if (seam) on_seam.push_back(part);
  }
  if (on_seam.size() < 2) return;
  OGRMultiPolygon pieces;
  const Ring* first = nullptr;
  for (int part : on_seam) {
    OGRPolygon poly;
    for (const Ring& r : region.rings) {
      if (r.part != part) continue;
      if (!first) first = &r;
      OGRLinearRing ring;
      for (Vec2 p : r.points) ring.addPoint(p.x * to_degree < 0 ? p.x + 360.0 / to_degree : p.x, p.y);
      ring.addPoint(ring.getX(0), ring.getY(0));
      poly.addRing(&ring);  // the readers give a part's outer ring first, then its holes
    }
    pieces.addGeometry(&poly);
  }
  CPLPushErrorHandler(CPLQuietErrorHandler);
  std::unique_ptr<OGRGeometry> united(pieces.UnionCascaded());
  CPLPopErrorHandler();
  if (!united) return;
  std::vector<const OGRPolygon*> polys;
  if (wkbFlatten(united->getGeometryType()) == wkbPolygon) polys.push_back(united->toPolygon());
  else if (wkbFlatten(united->getGeometryType()) == wkbMultiPolygon)
    for (const OGRPolygon* p : *united->toMultiPolygon()) polys.push_back(p);
  else return;
  if (polys.size() >= on_seam.size()) return;
  const Ring keep = *first;
  std::vector<Ring> rings;
  std::vector<int> renumber(static_cast<std::size_t>(region.num_parts), -1);
  int parts = 0;
  for (const Ring& r : region.rings) {
    if (std::find(on_seam.begin(), on_seam.end(), r.part) != on_seam.end()) continue;
    if (renumber[static_cast<std::size_t>(r.part)] < 0) renumber[static_cast<std::size_t>(r.part)] = parts++;
    rings.push_back(r);
    rings.back().part = renumber[static_cast<std::size_t>(r.part)];
  }
  for (const OGRPolygon* p : polys) {
    const int part = parts++;
    for (int k = 0; k <= p->getNumInteriorRings(); ++k) {
      const OGRLinearRing* lr = k == 0 ? p->getExteriorRing() : p->getInteriorRing(k - 1);
      Ring r = keep;
      r.part = part;
      r.hole = k > 0;
      r.points.clear();
      for (int i = 0; i + 1 < lr->getNumPoints(); ++i) r.points.push_back({lr->getX(i), lr->getY(i)});
      rings.push_back(std::move(r));
    }
  }
  notes.warnings.push_back(region.source + ": " + std::to_string(on_seam.size()) +
                           " polygon parts meet along the antimeridian (longitude 180 / -180): meshed as " +
                           std::to_string(polys.size()) + " part(s)");
  region.rings = std::move(rings);
  region.num_parts = parts;
}

// Messages about places of a projected region name them in the input's own coordinates.
class InputPlaces : public PlaceTextHook {
 public:
  InputPlaces(std::unique_ptr<OGRCoordinateTransformation> t) : transform_(std::move(t)) {}
  std::string text(Vec2 p) const override {
    double x = p.x, y = p.y;
    int ok = 0;
    if (!transform_->Transform(1, &x, &y, nullptr, nullptr, &ok) || !ok || !std::isfinite(x) || !std::isfinite(y))
      return plain_point_text(p) + " (in the meshing CRS)";
    return plain_point_text({x, y});
  }

 private:
  std::unique_ptr<OGRCoordinateTransformation> transform_;
};

}  // namespace

LonRange longitude_range(const std::vector<double>& lon_degrees) {
  LonRange range;
  std::vector<double> lon;
  lon.reserve(lon_degrees.size());
  for (double l : lon_degrees)
    if (std::isfinite(l)) lon.push_back(l - 360.0 * std::floor(l / 360.0));  // into [0, 360)
  if (lon.empty()) return range;
  std::sort(lon.begin(), lon.end());
  lon.erase(std::unique(lon.begin(), lon.end()), lon.end());
  // The arc covering every longitude is the circle less its largest gap between neighbouring longitudes.
  double gap = 360.0 - (lon.back() - lon.front());
  double start = lon.front();
  for (std::size_t i = 1; i < lon.size(); ++i)
    if (lon[i] - lon[i - 1] > gap) gap = lon[i] - lon[i - 1], start = lon[i];
  range.width = 360.0 - gap;
  range.west = start > 180.0 ? start - 360.0 : start;  // [-180, 180]
  range.east = range.west + range.width;
  range.centre = range.west + 0.5 * range.width;
  if (range.centre >= 180.0) range.centre -= 360.0;
  range.crosses_antimeridian = range.east > 180.0;
  return range;
}

int utm_epsg(double lon, double lat) {
  // Clamped before the cast: a longitude far out of range (a broken file) must not overflow an int.
  const double lon_clamped = std::isfinite(lon) ? std::clamp(lon, -180.0, 360.0) : 0.0;
  const int zone = std::clamp(static_cast<int>(std::floor((lon_clamped + 180.0) / 6.0)) % 60 + 1, 1, 60);
  return (lat >= 0 ? 32600 : 32700) + zone;
}

namespace {

// The input's CRS, refused when PROJ does not know it (an EPSG code that does not exist, a typo: taking the
// coordinates as planar would mesh degrees, or feet, as metres without a word) or when it is not planar-able.
void parse_source_crs(const Region& region, OGRSpatialReference& source) {
  if (!crs::parse(region.crs, source))
    throw InputError(region.source + ": CRS \"" + region.crs.substr(0, 80) + "\" is not one PROJ knows" +
                     (region.crs.rfind("EPSG:", 0) == 0 ? " (no such EPSG code)" : std::string()) +
                     "; name a known CRS (ogr2ogr -a_srs EPSG:n) or none to mesh the coordinates as planar units");
  if (source.IsGeocentric())
    throw InputError(region.source + ": CRS " + region.crs.substr(0, 80) +
                     " is geocentric (x, y, z from the earth's centre); a planar region needs a geographic or projected "
                     "CRS (ogr2ogr -t_srs EPSG:4326 converts)");
  if (!source.IsGeographic() && !source.IsProjected())
    throw InputError(region.source + ": CRS " + region.crs.substr(0, 80) +
                     " is neither geographic nor projected; a planar region needs one of those");
}

// The UTM zone of a geographic region's centre (its longitude taken on the circle: a region across the
// antimeridian, 179.9 and -179.9, has its centre at 180, not at 0, which put it in zone 31); refused beyond UTM's
// latitudes and wider than half the earth.
std::string utm_zone_of(const Region& region, const OGRSpatialReference& source, const Box2& box, InputNotes& notes) {
  // The centre's longitude and latitude, in degrees, whatever the source's geographic unit. The longitude's
  // centre is taken on the circle: a region across the antimeridian (179.9 and -179.9) has its centre at 180,
  // not at 0 (which put it in zone 31, 180 degrees from its central meridian).
  const double to_degree = source.GetAngularUnits() / (M_PI / 180.0);
  const double lat_lo = box.lo.y * to_degree, lat_hi = box.hi.y * to_degree;
  // UTM covers 80 S to 84 N; past that (a cap reaching the pole) its zones do not hold the region.
  if (lat_hi > 84.0 || lat_lo < -80.0)
    throw InputError(region.source + ": the region reaches latitude " + number_text(lat_hi > 84.0 ? lat_hi : lat_lo) +
                     ", beyond " + (lat_hi > 84.0 ? "84 N" : "80 S") + " where UTM zones end; give --crs a polar "
                     "CRS (" + (lat_hi > 84.0 ? "EPSG:3413 or EPSG:3995" : "EPSG:3031") +
                     "), with no ring along latitude " + (lat_hi > 84.0 ? "90" : "-90") + ", which is one point");
  const LonRange lon = longitude_range(longitudes(region, to_degree));
  if (lon.width > 180.0)
    throw InputError(region.source + ": the region spans " + number_text(lon.width) +
                     " degrees of longitude (from " + number_text(lon.west) + " to " + number_text(lon.east) +
                     "), more than half the earth: no UTM zone holds it; give --crs a CRS for it");
  const std::string target_name = "EPSG:" + std::to_string(utm_epsg(lon.centre, 0.5 * (lat_lo + lat_hi)));
  if (lon.crosses_antimeridian)
    notes.warnings.push_back(region.source + ": the region crosses the antimeridian (longitudes " +
                             number_text(lon.west) + " to " + number_text(lon.east > 180.0 ? lon.east - 360.0 : lon.east) +
                             "); meshed in " + target_name + ", the UTM zone of its centre at longitude " +
                             number_text(lon.centre));
  return target_name;
}

// Longitude -180 written as 180 and parts meeting along it united (an RFC 7946 split); a cap drawn along latitude
// 90 (or -90) has those vertices taken as one point, the pole, said (else the ring repeated a point).
void mend_seam_and_poles(Region& region, double to_degree, InputNotes& notes) {
  auto at_pole = [&](Vec2 p) { return std::abs(p.y * to_degree) == 90.0; };
  // Longitude -180 is longitude 180: one value for both, so a region split at the antimeridian (RFC 7946) has
  // its two sides' points projected to the same bits.
  auto seam = [&](std::vector<Vec2>& pts) {
    for (Vec2& p : pts)
      if (p.x * to_degree == -180.0) p.x = 180.0 / to_degree;
  };
  for (Ring& r : region.rings) seam(r.points);
  for (FeatureCurve& c : region.features) seam(c.points);
  seam(region.feature_points);
  for (BoundarySegment& b : region.boundary_segments) seam(b.line);
  unite_antimeridian_parts(region, to_degree, notes);
  auto collapse = [&](std::vector<Vec2>& pts, bool closed, int feature) {
    std::vector<Vec2> kept;
    for (std::size_t i = 0; i < pts.size(); ++i)
      if (kept.empty() || !(at_pole(pts[i]) && at_pole(kept.back()) && pts[i].y == kept.back().y)) kept.push_back(pts[i]);
    while (closed && kept.size() > 1 && at_pole(kept.front()) && at_pole(kept.back()) && kept.front().y == kept.back().y)
      kept.pop_back();
    if (kept.size() == pts.size()) return;
    double pole = 90.0;
    for (Vec2 p : kept)
      if (at_pole(p)) {
        pole = p.y * to_degree;
        break;
      }
    notes.warnings.push_back(region.source + ": feature " + std::to_string(feature) + " runs along latitude " +
                             number_text(pole) +
                             ", which is one point (the pole): " + std::to_string(pts.size() - kept.size() + 1) +
                             " vertices there are taken as one");
    pts = std::move(kept);
  };
  for (Ring& r : region.rings) collapse(r.points, true, r.source_feature);
  for (FeatureCurve& c : region.features) collapse(c.points, c.closed, c.source_feature);
}

// Every point of the region through `transform`; a point it cannot take is refused, named.
void project_points(Region& region, OGRCoordinateTransformation& transform, const std::string& target_name) {
  auto project = [&](std::vector<Vec2>& pts, const std::string& what) {
    std::vector<double> x(pts.size()), y(pts.size());
    std::vector<int> ok(pts.size(), 0);
    for (std::size_t i = 0; i < pts.size(); ++i) x[i] = pts[i].x, y[i] = pts[i].y;
    if (!pts.empty()) transform.Transform(pts.size(), x.data(), y.data(), nullptr, nullptr, ok.data());
    for (std::size_t i = 0; i < pts.size(); ++i) {
      if (!ok[i] || !std::isfinite(x[i]) || !std::isfinite(y[i]))
        throw InputError(region.source + ": " + what + ": the point " + point_text(pts[i]) + " cannot be projected to " + target_name);
      pts[i] = {x[i], y[i]};
    }
  };
  for (Ring& r : region.rings) project(r.points, "feature " + std::to_string(r.source_feature));
  for (FeatureCurve& c : region.features) project(c.points, "feature " + std::to_string(c.source_feature));
  project(region.feature_points, "feature points");
  for (BoundarySegment& b : region.boundary_segments) project(b.line, "feature " + std::to_string(b.source_feature));
}

}  // namespace

void project_region(Region& region, const std::string& target_crs, InputNotes& notes) {
  const Box2 box = region.bounding_box();
  notes.input_crs = region.crs;
  if (region.crs.empty()) {
    if (!target_crs.empty())
      throw InputError(region.source + ": --crs " + target_crs +
                       " needs input that names its CRS; this input names none (ogr2ogr -a_srs sets one)");
    if (looks_like_degrees(region, box))
      notes.warnings.push_back(region.source + ": the input names no CRS but its coordinates look like longitude/latitude "
                               "degrees (from " + point_text(box.lo) + " to " + point_text(box.hi) +
                               "); they are meshed as planar units, so --size is in degrees too. Give the file a CRS "
                               "(a GeoJSON \"crs\" member, a .prj, or ogr2ogr -a_srs EPSG:4326) to mesh in metres");
    return;
  }
  OGRSpatialReference source;
  parse_source_crs(region, source);
  if (source.IsProjected() && target_crs.empty()) {
    region.units = units_of(source);
    if (region.units != "m")
      // Kept in the CRS's unit (the mesh is written in the input's CRS, as the user's other tools read it), and
      // said: --size, the report's lengths and areas are in that unit (the report's input.units names it).
      notes.warnings.push_back(region.source + ": the CRS " + region.crs.substr(0, 80) + " is in " + region.units +
                               " (" + number_text(source.GetLinearUnits()) + " m), so --size and the report's lengths are in " +
                               region.units + ", not metres (--crs EPSG:n meshes in a metric CRS)");
    return;
  }
  if (source.IsGeographic()) {
    // Geographic coordinates outside longitude [-180, 360] and latitude [-90, 90] are not positions on the earth.
    const double to_degree = source.GetAngularUnits() / (M_PI / 180.0);
    const Vec2 lo = to_degree * box.lo, hi = to_degree * box.hi;
    const bool lon_ok = lo.x >= -180.0 && hi.x <= 360.0, lat_ok = lo.y >= -90.0 && hi.y <= 90.0;
    if (!lon_ok || !lat_ok)
      throw InputError(region.source + ": its CRS " + region.crs.substr(0, 80) + " is geographic, but its coordinates run from " +
                       point_text(box.lo) + " to " + point_text(box.hi) + ", outside longitude -180..360 and latitude -90..90 " +
                       "degrees (planar coordinates with a wrong CRS? ogr2ogr -a_srs sets the right one)");
  }
  OGRSpatialReference target;
  std::string target_name = target_crs;
  if (target_name.empty() && source.IsGeographic()) {
    target_name = utm_zone_of(region, source, box, notes);
  }
  if (!crs::parse(target_name, target)) throw InputError("--crs " + target_name + ": not a CRS PROJ knows");
  if (!target.IsProjected()) throw InputError("--crs " + target_name + ": not a projected CRS (meshing needs planar coordinates)");
  std::unique_ptr<OGRCoordinateTransformation> transform(OGRCreateCoordinateTransformation(&source, &target));
  if (!transform)
    throw InputError(region.source + ": cannot transform from " + region.crs.substr(0, 80) + " to " + target_name);
  // A cap drawn in longitude/latitude runs along latitude 90 (or -90) from one longitude to another: on the earth
  // (and in a polar CRS) those vertices are one point, the pole. They are taken as one, said; else the ring
  // repeated a point.
  if (source.IsGeographic()) mend_seam_and_poles(region, source.GetAngularUnits() / (M_PI / 180.0), notes);
  project_points(region, *transform, target_name);
  region.crs = target_name;
  region.units = units_of(target);
  notes.reprojected = true;
}

std::unique_ptr<PlaceTextHook> input_place_text(const Region& region, const InputNotes& notes) {
  if (!notes.reprojected) return nullptr;
  OGRSpatialReference meshed, input;
  if (!crs::parse(region.crs, meshed) || !crs::parse(notes.input_crs, input)) return nullptr;
  CPLPushErrorHandler(CPLQuietErrorHandler);
  std::unique_ptr<OGRCoordinateTransformation> t(OGRCreateCoordinateTransformation(&meshed, &input));
  CPLPopErrorHandler();
  if (!t) return nullptr;
  return std::make_unique<InputPlaces>(std::move(t));
}

}  // namespace polysquare
