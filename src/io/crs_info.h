// What the solver writers need to know about a CRS name, through GDAL/OSR (internal to io/).
#pragma once

#include <string>
#include <vector>

#include "polysquare/core/geometry.h"

class OGRSpatialReference;

namespace polysquare::crs {

/// Parses a CRS name into `srs` with no file or network access (the name may come from an untrusted file) and
/// traditional GIS axis order (x = longitude / easting). False when PROJ does not know it (or it is empty).
bool parse(const std::string& name, OGRSpatialReference& srs);

struct CrsInfo {
  bool known = false;       ///< the name parsed as a CRS PROJ knows
  bool geographic = false;  ///< longitude/latitude
  int epsg = 0;             ///< EPSG code, 0 when none is identified
  std::string name, wkt, proj4;
  double semi_major = 6378137.0, semi_minor = 6356752.314245, inverse_flattening = 298.257223563;  ///< WGS 84 unless known
};

/// Interprets an "EPSG:n" code, URN, WKT or PROJ string without file or network access (the name may come from an
/// untrusted input file). An empty or unknown name gives known = false.
CrsInfo crs_info(const std::string& name);

/// `points` in `crs` transformed to EPSG:4326 longitude/latitude in degrees (x = longitude). Throws InputError
/// when the CRS is unknown or a point cannot be transformed.
std::vector<Vec2> to_lonlat(const std::vector<Vec2>& points, const std::string& crs);

}  // namespace polysquare::crs
