// Stage 1 (input): geographic coordinates projected to a metric CRS before meshing (never mesh in degrees).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "polysquare/core/region.h"
#include "polysquare/input/read_region.h"

namespace polysquare {

/// Interprets region.crs (an "EPSG:n" code, URN, WKT or PROJ string; no file or network access). Geographic
/// input is projected to `target_crs` when given, else to the WGS 84 UTM zone of its centre (EPSG:326zz north,
/// 327zz south; the longitude's centre taken on the circle, so across the antimeridian too, said in a warning;
/// refused past 84 N / 80 S, where UTM ends, and for regions wider than 180 degrees of longitude); projected input is projected only when `target_crs` is given. Afterwards
/// region.crs names the CRS of the coordinates and region.units its linear unit ("m" for metres).
/// notes.input_crs keeps the CRS read. Input without a CRS is left as it is; when its coordinates look like
/// lon/lat degrees, a sentence is added to notes.warnings. Throws InputError when a coordinate cannot be
/// projected, when target_crs is not a projected CRS, when target_crs is given for input without a CRS, when
/// region.crs is not one PROJ knows (an EPSG code that does not exist), or geocentric.
void project_region(Region& region, const std::string& target_crs, InputNotes& notes);

/// The hook that writes places of a region projected by project_region (notes.reprojected) in the input's
/// own coordinates (notes.input_crs), for messages (ScopedPlaceText); nullptr when it was not projected.
std::unique_ptr<PlaceTextHook> input_place_text(const Region& region, const InputNotes& notes);

/// The arc of longitudes a region covers, taken on the circle (a region across the antimeridian, at 179.9 and
/// -179.9, covers 0.2 degrees around 180, not 359.8 around 0).
struct LonRange {
  double west = 0, east = 0;   ///< degrees; west in [-180, 180), east = west + width (above 180 across the antimeridian)
  double width = 0;            ///< degrees, 0 .. 360
  double centre = 0;           ///< degrees, in [-180, 180)
  bool crosses_antimeridian = false;
};
/// The smallest arc holding every longitude (degrees, any range; non-finite ones ignored).
LonRange longitude_range(const std::vector<double>& lon_degrees);

/// EPSG code of the WGS 84 UTM zone containing (lon, lat) in degrees (standard 6-degree zones).
int utm_epsg(double lon, double lat);

}  // namespace polysquare
