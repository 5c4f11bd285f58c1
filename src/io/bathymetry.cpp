#include "polysquare/io/bathymetry.h"

#include <gdal_priv.h>
#include <ogr_spatialref.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <mutex>
#include <sstream>

#include "crs_info.h"
#include "polysquare/core/error.h"

namespace polysquare {
namespace {

struct DatasetCloser {
  void operator()(GDALDataset* d) const { GDALClose(d); }
};
using Raster = std::unique_ptr<GDALDataset, DatasetCloser>;

std::string gdal_reason() {
  const char* m = CPLGetLastErrorMsg();
  return m && *m ? std::string(" (") + m + ")" : std::string();
}

// The raster opened, its band and its geotransform's inverse; InputError naming the file otherwise.
struct OpenRaster {
  Raster ds;
  GDALRasterBand* band = nullptr;
  std::array<double, 6> gt{}, inv{};
  int nx = 0, ny = 0;
};

OpenRaster open_raster(const std::string& name, const BathymetryOptions& options) {
  static std::once_flag once;
  std::call_once(once, [] { GDALAllRegister(); });
  OpenRaster r;
  CPLPushErrorHandler(CPLQuietErrorHandler);
  CPLErrorReset();
  r.ds.reset(static_cast<GDALDataset*>(GDALOpenEx(name.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY, nullptr, nullptr, nullptr)));
  CPLPopErrorHandler();
  if (!r.ds) throw InputError(name + ": cannot open the raster" + gdal_reason());
  if (options.band < 1 || options.band > r.ds->GetRasterCount())
    throw InputError(name + ": has no band " + std::to_string(options.band) + " (it has " +
                     std::to_string(r.ds->GetRasterCount()) + ")");
  r.band = r.ds->GetRasterBand(options.band);
  if (r.ds->GetGeoTransform(r.gt.data()) != CE_None || !GDALInvGeoTransform(r.gt.data(), r.inv.data()))
    throw InputError(name + ": the raster has no usable geotransform (where its cells lie is unknown)");
  r.nx = r.band->GetXSize();
  r.ny = r.band->GetYSize();
  return r;
}

std::string number(double v) {
  std::ostringstream os;
  os.precision(9);
  os << v;
  return os.str();
}

}  // namespace

std::vector<std::string> check_bathymetry(const std::filesystem::path& raster, const std::vector<Vec2>& domain,
                                          const std::string& domain_crs, const std::string& input_crs,
                                          const BathymetryOptions& options) {
  const std::string name = raster.string();
  std::vector<std::string> warnings;
  OpenRaster r = open_raster(name, options);
  const OGRSpatialReference* raster_srs = r.ds->GetSpatialRef();
  const bool raster_has_crs = raster_srs && !raster_srs->IsEmpty();
  // A region projected from its input's CRS (lon/lat to UTM) has nodes in metres: a raster naming no CRS cannot
  // be matched to them (its cells are most likely in the input's degrees).
  if (!raster_has_crs && !input_crs.empty() && input_crs != domain_crs)
    throw InputError(name + ": the raster names no CRS, and the region (in " + input_crs + ") is meshed in " +
                     domain_crs + ": give the raster its CRS (gdal_translate -a_srs " + input_crs + " " + name + " OUT.tif)");
  std::vector<Vec2> at = domain;
  OGRSpatialReference mesh_srs;
  if (raster_has_crs && crs::parse(domain_crs, mesh_srs)) {
    OGRSpatialReference target(*raster_srs);
    target.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
    if (!mesh_srs.IsSame(&target)) {
      CPLPushErrorHandler(CPLQuietErrorHandler);
      std::unique_ptr<OGRCoordinateTransformation> t(OGRCreateCoordinateTransformation(&mesh_srs, &target));
      CPLPopErrorHandler();
      if (!t) throw InputError(name + ": cannot transform the region's " + domain_crs + " into the raster's CRS");
      std::vector<double> x(at.size()), y(at.size());
      std::vector<int> ok(at.size(), 0);
      for (std::size_t i = 0; i < at.size(); ++i) x[i] = at[i].x, y[i] = at[i].y;
      if (!at.empty()) t->Transform(at.size(), x.data(), y.data(), nullptr, nullptr, ok.data());
      for (std::size_t i = 0; i < at.size(); ++i) {
        if (!ok[i] || !std::isfinite(x[i]) || !std::isfinite(y[i]))
          throw InputError(name + ": the domain's point " + at_text(domain[i]) + " (" + domain_crs +
                           ") cannot be transformed into the raster's CRS");
        at[i] = {x[i], y[i]};
      }
    }
  }
  // The domain's box in cells: every point within half a cell of the raster's edge (as sampling needs).
  double px_lo = INFINITY, px_hi = -INFINITY, py_lo = INFINITY, py_hi = -INFINITY;
  for (std::size_t i = 0; i < at.size(); ++i) {
    const double px = r.inv[0] + r.inv[1] * at[i].x + r.inv[2] * at[i].y;
    const double py = r.inv[3] + r.inv[4] * at[i].x + r.inv[5] * at[i].y;
    if (!(px >= -0.5 && py >= -0.5 && px <= r.nx + 0.5 && py <= r.ny + 0.5)) {
      const double x0 = r.gt[0], x1 = r.gt[0] + r.gt[1] * r.nx + r.gt[2] * r.ny;
      const double y0 = r.gt[3], y1 = r.gt[3] + r.gt[4] * r.nx + r.gt[5] * r.ny;
      throw InputError(name + ": the raster (x " + number(std::min(x0, x1)) + " .. " + number(std::max(x0, x1)) + ", y " +
                       number(std::min(y0, y1)) + " .. " + number(std::max(y0, y1)) +
                       (raster_has_crs ? std::string() : ", no CRS") + ") does not cover the domain: its point " +
                       plain_point_text(at[i]) + (at[i] == domain[i] ? std::string() : " in the raster's CRS") +
                       " lies outside");
    }
    px_lo = std::min(px_lo, px), px_hi = std::max(px_hi, px), py_lo = std::min(py_lo, py), py_hi = std::max(py_hi, py);
  }
  if (at.empty()) return warnings;
  // Cells under the domain's box: readable, and infinite values said (sampling leaves them out as no-data).
  const int i0 = std::clamp(static_cast<int>(std::floor(px_lo)) - 1, 0, r.nx - 1);
  const int i1 = std::clamp(static_cast<int>(std::ceil(px_hi)) + 1, 0, r.nx - 1);
  const int j0 = std::clamp(static_cast<int>(std::floor(py_lo)) - 1, 0, r.ny - 1);
  const int j1 = std::clamp(static_cast<int>(std::ceil(py_hi)) + 1, 0, r.ny - 1);
  const std::size_t w = static_cast<std::size_t>(i1 - i0 + 1);
  // A window of more than 10^8 cells (a domain of 100 km at 10 m cells) is not scanned: reading it would cost
  // more than the meshing; sampling still leaves infinite cells out.
  if (static_cast<double>(w) * (j1 - j0 + 1) > 1e8) return warnings;
  int has_nodata = 0;
  const double nodata = r.band->GetNoDataValue(&has_nodata);
  std::size_t infinite = 0, values = 0;
  std::pair<int, int> first{-1, -1};
  double first_value = 0;
  std::vector<double> row(w);
  // Row by row: a 10^8-cell window is read without holding it.
  for (int j = j0; j <= j1; ++j) {
    CPLPushErrorHandler(CPLQuietErrorHandler);
    CPLErrorReset();
    const CPLErr err = r.band->RasterIO(GF_Read, i0, j, static_cast<int>(w), 1, row.data(), static_cast<int>(w), 1,
                                        GDT_Float64, 0, 0);
    CPLPopErrorHandler();
    if (err != CE_None)
      throw InputError(name + ": reading the raster's row " + std::to_string(j) + " failed" + gdal_reason() +
                       " (a truncated or corrupt file?)");
    for (std::size_t i = 0; i < w; ++i) {
      if (std::isinf(row[i]) && infinite++ == 0) first = {i0 + static_cast<int>(i), j}, first_value = row[i];
      values += std::isfinite(row[i]) && !(has_nodata && row[i] == nodata);
    }
  }
  if (values == 0)
    throw InputError(name + ": no cell under the domain holds a value (columns " + std::to_string(i0) + " .. " +
                     std::to_string(i1) + ", rows " + std::to_string(j0) + " .. " + std::to_string(j1) +
                     " are all no-data or infinite)");
  if (infinite > 0)
    warnings.push_back(name + ": " + std::to_string(infinite) + " cell(s) under the domain hold an infinite value (the first " +
                       (first_value > 0 ? "+inf" : "-inf") + " at column " + std::to_string(first.first) + ", row " +
                       std::to_string(first.second) + "); they are taken as no-data");
  return warnings;
}

std::vector<double> sample_bathymetry(const std::filesystem::path& raster, const std::vector<Vec2>& nodes,
                                      const std::string& nodes_crs, const BathymetryOptions& options) {
  const std::string name = raster.string();
  OpenRaster r = open_raster(name, options);
  const Raster& ds = r.ds;
  GDALRasterBand* band = r.band;
  const std::array<double, 6>& inv = r.inv;
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
    CPLPushErrorHandler(CPLQuietErrorHandler);
    CPLErrorReset();
    const CPLErr err = band->RasterIO(GF_Read, i0, j0, wx, wy, v.data(), wx, wy, GDT_Float64, 0, 0);
    CPLPopErrorHandler();
    if (err != CE_None)
      throw InputError(name + ": reading the raster failed near node " + std::to_string(i + 1) + gdal_reason());
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
