// GeoJSON reader for the region format of data/cases/PROVENANCE.md (features with "role": "domain" or "feature").
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "polysquare/core/region.h"

namespace polysquare {

/// Parses a FeatureCollection. Domain features (Polygon, MultiPolygon) become rings (one part per polygon);
/// feature features become curves (LineString, MultiLineString; Polygon = a closed loop per ring, inner rings
/// included) or feature points (Point, MultiPoint). A missing role means domain for polygons and feature
/// otherwise. Coordinates are taken as is; a third coordinate (z) is dropped, and features where it varies are
/// named in one sentence appended to `warnings`;
/// validate_region() checks them. Throws InputError naming `source_name`, the feature index and what is wrong.
Region parse_geojson(std::string_view text, const std::string& source_name,
                     std::vector<std::string>* warnings = nullptr);

}  // namespace polysquare
