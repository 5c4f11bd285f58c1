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
/// the interpolation (the other cells' weights renormalised). Throws InputError naming the raster, the node and its
/// coordinate when a node lies outside the raster or only on no-data cells, and when the raster cannot be read.
std::vector<double> sample_bathymetry(const std::filesystem::path& raster, const std::vector<Vec2>& nodes,
                                      const std::string& nodes_crs, const BathymetryOptions& options = {});

}  // namespace polysquare
