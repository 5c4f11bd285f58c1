#include "polysquare/input/project_region.h"

#include <cpl_error.h>
#include <ogr_spatialref.h>

#include <cmath>
#include <memory>
#include <sstream>

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

}  // namespace

int utm_epsg(double lon, double lat) {
  // Clamped before the cast: a longitude far out of range (a broken file) must not overflow an int.
  const double lon_clamped = std::isfinite(lon) ? std::clamp(lon, -180.0, 360.0) : 0.0;
  const int zone = std::clamp(static_cast<int>(std::floor((lon_clamped + 180.0) / 6.0)) % 60 + 1, 1, 60);
  return (lat >= 0 ? 32600 : 32700) + zone;
}

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
  if (!crs::parse(region.crs, source)) {
    notes.warnings.push_back(region.source + ": CRS \"" + region.crs.substr(0, 80) +
                             "\" is not one PROJ knows; coordinates are taken as planar");
    return;
  }
  if (!source.IsGeographic() && !source.IsProjected())
    throw InputError(region.source + ": CRS " + region.crs.substr(0, 80) +
                     " is neither geographic nor projected; a planar region needs one of those");
  if (source.IsProjected() && target_crs.empty()) {
    region.units = units_of(source);
    if (region.units != "m")
      notes.warnings.push_back(region.source + ": the CRS's unit is " + region.units + ", so --size is in " +
                               region.units + " (--crs EPSG:n reprojects to a metric CRS)");
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
  if (target_name.empty()) {
    // The centre's longitude and latitude, in degrees, whatever the source's geographic unit.
    const Vec2 c = 0.5 * (box.lo + box.hi);
    const double to_degree = source.GetAngularUnits() / (M_PI / 180.0);
    target_name = "EPSG:" + std::to_string(utm_epsg(c.x * to_degree, c.y * to_degree));
  }
  if (!crs::parse(target_name, target)) throw InputError("--crs " + target_name + ": not a CRS PROJ knows");
  if (!target.IsProjected()) throw InputError("--crs " + target_name + ": not a projected CRS (meshing needs planar coordinates)");
  std::unique_ptr<OGRCoordinateTransformation> transform(OGRCreateCoordinateTransformation(&source, &target));
  if (!transform)
    throw InputError(region.source + ": cannot transform from " + region.crs.substr(0, 80) + " to " + target_name);
  auto project = [&](std::vector<Vec2>& pts, const std::string& what) {
    std::vector<double> x(pts.size()), y(pts.size());
    std::vector<int> ok(pts.size(), 0);
    for (std::size_t i = 0; i < pts.size(); ++i) x[i] = pts[i].x, y[i] = pts[i].y;
    if (!pts.empty()) transform->Transform(pts.size(), x.data(), y.data(), nullptr, nullptr, ok.data());
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
  region.crs = target_name;
  region.units = units_of(target);
  notes.reprojected = true;
}

}  // namespace polysquare
