#include "polysquare/io/bathymetry.h"

#include <gdal_priv.h>
#include <ogr_spatialref.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>

#include "crs_info.h"
#include "polysquare/core/error.h"

namespace polysquare {
namespace {

struct DatasetCloser {
  void operator()(GDALDataset* d) const { GDALClose(d); }
};

}  // namespace

std::vector<double> sample_bathymetry(const std::filesystem::path& raster, const std::vector<Vec2>& nodes,
                                      const std::string& nodes_crs, const BathymetryOptions& options) {
  const std::string name = raster.string();
  GDALAllRegister();
  CPLPushErrorHandler(CPLQuietErrorHandler);
  std::unique_ptr<GDALDataset, DatasetCloser> ds(
      static_cast<GDALDataset*>(GDALOpenEx(name.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY, nullptr, nullptr, nullptr)));
  CPLPopErrorHandler();
  if (!ds) throw InputError(name + ": cannot open the bathymetry raster (" + CPLGetLastErrorMsg() + ")");
  if (options.band < 1 || options.band > ds->GetRasterCount())
    throw InputError(name + ": has no band " + std::to_string(options.band));
  GDALRasterBand* band = ds->GetRasterBand(options.band);
  std::array<double, 6> gt{}, inv{};
  if (ds->GetGeoTransform(gt.data()) != CE_None || !GDALInvGeoTransform(gt.data(), inv.data()))
    throw InputError(name + ": the raster has no usable geotransform");
  int has_nodata = 0;
  const double nodata = band->GetNoDataValue(&has_nodata);
  const int nx = band->GetXSize(), ny = band->GetYSize();

  // Nodes into the raster's CRS, when both name one.
  std::vector<Vec2> at = nodes;
  const OGRSpatialReference* raster_srs = ds->GetSpatialRef();
  OGRSpatialReference mesh_srs;
  if (raster_srs && !raster_srs->IsEmpty() && crs::parse(nodes_crs, mesh_srs)) {
    OGRSpatialReference target(*raster_srs);
    target.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
    if (!mesh_srs.IsSame(&target)) {
      std::unique_ptr<OGRCoordinateTransformation> t(OGRCreateCoordinateTransformation(&mesh_srs, &target));
      if (!t) throw InputError(name + ": cannot transform the mesh's " + nodes_crs + " into the raster's CRS");
      std::vector<double> x(at.size()), y(at.size());
      std::vector<int> ok(at.size(), 0);
      for (std::size_t i = 0; i < at.size(); ++i) x[i] = at[i].x, y[i] = at[i].y;
      if (!at.empty()) t->Transform(at.size(), x.data(), y.data(), nullptr, nullptr, ok.data());
      for (std::size_t i = 0; i < at.size(); ++i) {
        if (!ok[i]) throw InputError(name + ": node " + std::to_string(i + 1) + " at " + at_text(nodes[i]) +
                                     " cannot be transformed into the raster's CRS");
        at[i] = {x[i], y[i]};
      }
    }
  }

  std::vector<double> depth(nodes.size());
  for (std::size_t i = 0; i < at.size(); ++i) {
    // Pixel coordinates, then relative to cell centres.
    const double px = inv[0] + inv[1] * at[i].x + inv[2] * at[i].y - 0.5;
    const double py = inv[3] + inv[4] * at[i].x + inv[5] * at[i].y - 0.5;
    if (!(px >= -1.0 && py >= -1.0 && px <= nx && py <= ny) || !std::isfinite(px) || !std::isfinite(py))
      throw InputError(name + ": node " + std::to_string(i + 1) + " at " + at_text(nodes[i]) + " lies outside the raster");
    const double cx = std::clamp(px, 0.0, static_cast<double>(nx - 1)), cy = std::clamp(py, 0.0, static_cast<double>(ny - 1));
    const int i0 = std::min(static_cast<int>(std::floor(cx)), std::max(nx - 2, 0));
    const int j0 = std::min(static_cast<int>(std::floor(cy)), std::max(ny - 2, 0));
    const int wx = std::min(2, nx - i0), wy = std::min(2, ny - j0);
    std::array<double, 4> v{};
    if (band->RasterIO(GF_Read, i0, j0, wx, wy, v.data(), wx, wy, GDT_Float64, 0, 0) != CE_None)
      throw InputError(name + ": reading the raster failed near node " + std::to_string(i + 1));
    const double fx = wx == 2 ? cx - i0 : 0.0, fy = wy == 2 ? cy - j0 : 0.0;
    double sum = 0, weight = 0;
    for (int b = 0; b < wy; ++b)
      for (int a = 0; a < wx; ++a) {
        const double value = v[static_cast<std::size_t>(b * wx + a)];
        if ((has_nodata && value == nodata) || !std::isfinite(value)) continue;
        const double w = (a ? fx : 1 - fx) * (b ? fy : 1 - fy);
        sum += w * value;
        weight += w;
      }
    if (!(weight > 1e-12))
      throw InputError(name + ": node " + std::to_string(i + 1) + " at " + at_text(nodes[i]) + " lies on no-data cells");
    const double value = sum / weight;
    depth[i] = options.positive_down ? value : -value;
  }
  return depth;
}

}  // namespace polysquare
