// Water depth at mesh nodes from a bathymetry raster (any raster GDAL reads: GeoTIFF, NetCDF, ASCII grid, ...).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "polysquare/core/geometry.h"

namespace polysquare {

struct BathymetryOptions {
  bool positive_down = false;  ///< false: the raster holds elevations, positive up (GEBCO, DEMs), depth = -value;
                               ///< true: it holds depths, positive down
  int band = 1;                ///< raster band (1-based)
};

/// #nodes depths (positive down) at `nodes`, bilinear between the centres of the raster's cells (clamped to the
/// outermost centres within half a cell of the raster's edge). Nodes given in `nodes_crs` are transformed into the
/// raster's CRS when both are known; otherwise coordinates are taken as they are. A no-data cell is left out of
/// the interpolation (the other cells' weights renormalised), and so is an infinite cell (check_bathymetry says so). Throws InputError naming the raster, the node and its
/// coordinate when a node lies outside the raster or only on no-data cells, and when the raster cannot be read.
std::vector<double> sample_bathymetry(const std::filesystem::path& raster, const std::vector<Vec2>& nodes,
                                      const std::string& nodes_crs, const BathymetryOptions& options = {});

/// Opens `raster` and checks it before meshing: readable (a corrupt or truncated file is refused naming it), the
/// band present, a geotransform, a CRS when the region was projected from its input's CRS (`input_crs` differs from
/// `domain_crs`: a lon/lat region is meshed in UTM metres, and a raster without CRS cannot be placed), and every point of
/// `domain` (the rings' vertices, in `domain_crs`) within half a cell of the raster. Returns warnings: cells under the
/// domain's box holding an infinite value (sampling takes them as no-data). Throws InputError naming the file.
std::vector<std::string> check_bathymetry(const std::filesystem::path& raster, const std::vector<Vec2>& domain,
                                          const std::string& domain_crs, const std::string& input_crs,
                                          const BathymetryOptions& options = {});

}  // namespace polysquare
