// GeoJSON reader for the region format of data/cases/PROVENANCE.md (features with "role": "domain" or "feature").
#pragma once

#include <string>
#include <string_view>

#include "polysquare/core/region.h"

namespace polysquare {

/// Parses a FeatureCollection. Domain features (Polygon, MultiPolygon) become rings (one part per polygon);
/// feature features become curves (LineString, MultiLineString; Polygon = closed loop) or feature points (Point,
/// MultiPoint). A missing role means domain for polygons and feature otherwise. Coordinates are taken as is;
/// validate_region() checks them. Throws InputError naming `source_name`, the feature index and what is wrong.
Region parse_geojson(std::string_view text, const std::string& source_name);

}  // namespace polysquare
