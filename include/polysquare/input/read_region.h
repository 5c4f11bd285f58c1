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
  // Files read through GDAL/OGR (every layer of every file, unless selected below).
  std::vector<std::filesystem::path> feature_files;  ///< more datasets whose layers give feature curves (--features)
  std::vector<std::filesystem::path> boundary_files;  ///< datasets whose lines are named boundary segments (--boundary)
  std::string domain_layer;                 ///< only this layer gives the domain (--domain-layer); empty: roles
  std::vector<std::string> feature_layers;  ///< only these layers give features (--feature-layer); empty: roles
  std::string where;                        ///< OGR SQL attribute filter on every layer read (--where)
  std::string crs;  ///< projected CRS to mesh geographic input in (--crs "EPSG:n"); empty: UTM zone of the centre
  double snap_relative = 1e-9;  ///< end points and feature points this close (times the bounding-box diagonal)
                                ///< to a vertex or a curve are moved onto it (reported)
  double boundary_snap_relative = 1e-6;  ///< a boundary segment's points this close (times the bounding-box
                                         ///< diagonal) to a ring lie on it; its end points this close to a ring
                                         ///< vertex are that vertex
};

/// What reading changed or doubts, for the CLI and the report (one sentence each, naming file and coordinate).
struct InputNotes {
  std::vector<std::string> repairs;   ///< fixes made because of InputOptions::repair
  std::vector<std::string> snaps;     ///< near-coincident points moved onto a vertex or curve
  std::vector<std::string> warnings;  ///< e.g. coordinates that look like degrees in input without a CRS
  std::string input_crs;              ///< CRS of the file as read ("EPSG:4326"); empty when it names none
  bool reprojected = false;           ///< coordinates were projected from input_crs to Region::crs
};

/// Checks and normalizes a parsed region: finite coordinates below max_abs_coordinate; duplicate consecutive
/// points removed; rings with at least 3 distinct points and non-zero area; no ring crossing or touching itself
/// or another ring; holes inside their outer ring; parts not inside one another; outer rings counter-clockwise
/// and holes clockwise; feature curves with 2 distinct points, inside or on the domain, not crossing each other.
/// Boundary segments are placed on their rings (place_boundary_segments).
/// Throws InputError naming region.source, the feature index and a coordinate.
/// With options.repair, each repair made is appended to `repairs` (a sentence naming the feature and coordinate).
/// A hole inside another hole of its polygon becomes a polygon part of its own (an island in a lake), said in
/// `warnings`, which also get the stretches of feature curves left to the boundary (split_features); feature
/// points outside the domain or in a hole are refused (dropped and listed in `repairs` with options.repair).
void validate_region(Region& region, const InputOptions& options = {}, std::vector<std::string>* repairs = nullptr,
                     std::vector<std::string>* warnings = nullptr);

/// Reads `path` and options.feature_files, projects geographic coordinates (project_region), snaps
/// near-coincident points (snap_near_coincident) and validates the result. GeoJSON (.geojson, .json) is parsed
/// natively unless layers or a filter are selected; every other format, and the feature files, go through
/// GDAL/OGR (read_gdal). Both paths feed the same projection, snapping and validation. Throws InputError.
Region read_input(const std::filesystem::path& path, const InputOptions& options, InputNotes& notes);

/// read_input, keeping only the repairs.
Region read_region(const std::filesystem::path& path, const InputOptions& options = {},
                   std::vector<std::string>* repairs = nullptr);

}  // namespace polysquare
