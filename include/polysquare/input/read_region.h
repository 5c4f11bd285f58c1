// Stage 1: input. Reads a region file and validates it; every rejection names the file, feature and coordinate.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "polysquare/core/region.h"

namespace polysquare {

struct InputOptions {
  double max_abs_coordinate = 1e15;  ///< larger coordinates are rejected (precision of the geometry would be lost)
  bool repair = false;  ///< fix what a user would want fixed instead of refusing: make invalid polygons valid
                        ///< (GEOS through GDAL), drop repeated consecutive points, clip feature curves that
                        ///< cross a hole (each repair is reported)
};

/// Checks and normalizes a parsed region: finite coordinates below max_abs_coordinate; duplicate consecutive
/// points removed; rings with at least 3 distinct points and non-zero area; no ring crossing or touching itself
/// or another ring; holes inside their outer ring; parts not inside one another; outer rings counter-clockwise
/// and holes clockwise; feature curves with 2 distinct points, inside or on the domain, not crossing each other.
/// Throws InputError naming region.source, the feature index and a coordinate.
/// With options.repair, each repair made is appended to `repairs` (a sentence naming the feature and coordinate).
void validate_region(Region& region, const InputOptions& options = {}, std::vector<std::string>* repairs = nullptr);

/// Reads `path` (GeoJSON: .geojson or .json) and validates it. Throws InputError on any problem.
Region read_region(const std::filesystem::path& path, const InputOptions& options = {},
                   std::vector<std::string>* repairs = nullptr);

}  // namespace polysquare
