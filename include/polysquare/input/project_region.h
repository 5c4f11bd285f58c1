// Stage 1 (input): geographic coordinates projected to a metric CRS before meshing (never mesh in degrees).
#pragma once

#include <string>

#include "polysquare/core/region.h"
#include "polysquare/input/read_region.h"

namespace polysquare {

/// Interprets region.crs (an "EPSG:n" code, URN, WKT or PROJ string; no file or network access). Geographic
/// input is projected to `target_crs` when given, else to the WGS 84 UTM zone of the centre of its bounding box
/// (EPSG:326zz north, 327zz south); projected input is projected only when `target_crs` is given. Afterwards
/// region.crs names the CRS of the coordinates and region.units its linear unit ("m" for metres).
/// notes.input_crs keeps the CRS read. Input without a CRS is left as it is; when its coordinates look like
/// lon/lat degrees, a sentence is added to notes.warnings. Throws InputError when a coordinate cannot be
/// projected, when target_crs is not a projected CRS, or when target_crs is given for input without a CRS.
void project_region(Region& region, const std::string& target_crs, InputNotes& notes);

/// EPSG code of the WGS 84 UTM zone containing (lon, lat) in degrees (standard 6-degree zones).
int utm_epsg(double lon, double lat);

}  // namespace polysquare
