// Stage 1 (input): vector datasets read through GDAL/OGR (Shapefile, GeoPackage, GeoJSON, KML, GML, DXF,
// FlatGeobuf, anything else GDAL opens as vector data).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "polysquare/core/region.h"
#include "polysquare/input/read_region.h"

namespace polysquare {

/// How a layer's geometries get their role when no `role` attribute says it.
enum class LayerRole {
  by_geometry,  ///< polygons are the domain, lines and points are features (as for GeoJSON)
  feature,      ///< everything is a feature (polygons become closed feature curves): --features files
  boundary,     ///< every line is a named boundary segment (BoundarySegment): --boundary files
};

/// Appends the geometries of the selected layers of `path` to `region` (not validated, not projected).
/// A layer is selected by options.domain_layer / options.feature_layers (see InputOptions), and its features by
/// options.where. A string `role` attribute ("domain", "feature" or "boundary") overrides `default_role`, except in a layer
/// named by --domain-layer or --feature-layer, whose role is the option's, and in a --boundary file (every line
/// is a boundary segment). String attributes `name` and `kind` go to the ring, curve or segment read. Curved geometries are linearized
/// (said in notes.warnings, naming the first feature and counting the others), Z and M are dropped (varying z said,
/// as the GeoJSON reader says it). A layer without a geometry column (an attribute table) is skipped with a warning,
/// refused when --domain-layer or --feature-layer names it; a feature without geometry is refused naming its FID. Every geometry gets source_feature = feature_names.size() at the time it is read, and
/// feature_names gets "FILE, layer 'L', FID n" for it.
/// CRS: the first layer with a spatial reference sets region.crs (when still empty, e.g. "EPSG:32616", else
/// WKT); later layers in another CRS are transformed into it. A Shapefile whose .prj GDAL cannot read is refused
/// naming the .prj; a local engineering CRS (GeoPackage srs_id -1) is no CRS (planar units); GeoPackage's undefined
/// geographic CRS (srs_id 0) is taken as WGS 84 with a warning. GeoJSON without a "crs" member has no CRS, as
/// for the native reader (GDAL would assume WGS 84). Throws InputError naming the file, layer and feature.
void read_gdal(const std::filesystem::path& path, LayerRole default_role, const InputOptions& options, Region& region,
               std::vector<std::string>& feature_names, InputNotes& notes);

/// The names of every vector layer GDAL finds in `path` (for messages and tests). Throws InputError.
std::vector<std::string> gdal_layer_names(const std::filesystem::path& path);

}  // namespace polysquare
