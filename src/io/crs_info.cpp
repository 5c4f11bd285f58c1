#include "crs_info.h"

#include <cpl_conv.h>
#include <cpl_error.h>
#include <ogr_spatialref.h>

#include <cmath>
#include <memory>

#include "polysquare/core/error.h"

namespace polysquare::crs {

bool parse(const std::string& name, OGRSpatialReference& srs) {
  if (name.empty()) return false;
  const char* no_io[] = {"ALLOW_NETWORK_ACCESS=NO", "ALLOW_FILE_ACCESS=NO", nullptr};
  CPLPushErrorHandler(CPLQuietErrorHandler);
  const bool ok = srs.SetFromUserInput(name.c_str(), no_io) == OGRERR_NONE;
  CPLPopErrorHandler();
  srs.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);  // x = longitude / easting whatever the CRS says
  return ok;
}

namespace {

std::string owned(char* s) {
  std::string out = s ? s : "";
  CPLFree(s);
  return out;
}

}  // namespace

CrsInfo crs_info(const std::string& name) {
  CrsInfo info;
  OGRSpatialReference srs;
  if (!parse(name, srs)) return info;
  info.known = true;
  info.geographic = srs.IsGeographic();
  if (const char* n = srs.GetName()) info.name = n;
  CPLPushErrorHandler(CPLQuietErrorHandler);
  const char* code = srs.GetAuthorityCode(nullptr);
  if (!code) {
    srs.AutoIdentifyEPSG();
    code = srs.GetAuthorityCode(nullptr);
  }
  CPLPopErrorHandler();
  const char* authority = srs.GetAuthorityName(nullptr);
  if (code && authority && std::string(authority) == "EPSG") info.epsg = std::atoi(code);
  OGRErr err = OGRERR_NONE;
  info.semi_major = srs.GetSemiMajor(&err);
  info.semi_minor = srs.GetSemiMinor(&err);
  info.inverse_flattening = srs.GetInvFlattening(&err);
  char* wkt = nullptr;
  srs.exportToWkt(&wkt);
  info.wkt = owned(wkt);
  char* proj4 = nullptr;
  CPLPushErrorHandler(CPLQuietErrorHandler);
  srs.exportToProj4(&proj4);
  CPLPopErrorHandler();
  info.proj4 = owned(proj4);
  return info;
}

std::vector<Vec2> to_lonlat(const std::vector<Vec2>& points, const std::string& crs) {
  OGRSpatialReference source, target;
  if (!parse(crs, source)) throw InputError("the mesh's CRS \"" + crs.substr(0, 80) + "\" is not one PROJ knows");
  parse("EPSG:4326", target);
  std::unique_ptr<OGRCoordinateTransformation> transform(OGRCreateCoordinateTransformation(&source, &target));
  if (!transform) throw InputError("cannot transform from " + crs.substr(0, 80) + " to EPSG:4326");
  std::vector<double> x(points.size()), y(points.size());
  std::vector<int> ok(points.size(), 0);
  for (std::size_t i = 0; i < points.size(); ++i) x[i] = points[i].x, y[i] = points[i].y;
  if (!points.empty()) transform->Transform(points.size(), x.data(), y.data(), nullptr, nullptr, ok.data());
  std::vector<Vec2> out(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!ok[i] || !std::isfinite(x[i]) || !std::isfinite(y[i]))
      throw InputError("node " + std::to_string(i + 1) + " at " + at_text(points[i]) + " cannot be transformed from " +
                       crs.substr(0, 80) + " to EPSG:4326");
    out[i] = {x[i], y[i]};
  }
  return out;
}

}  // namespace polysquare::crs
