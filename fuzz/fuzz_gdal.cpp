// libFuzzer target: vector input through GDAL/OGR (read_input: every layer read, the CRS projected, points snapped
// and the region validated, as `polysquare mesh` does) must reject bad input with InputError, never crash, hang or
// trip a sanitizer in our code.
//
// The first byte picks the format (low 3 bits) and the ways the file is read (bits 3-5); the rest is the file:
//   0 GeoPackage, 1 Shapefile, 2 GeoJSON through OGR (--where), 3 KML, 4 GML, 5 FlatGeobuf, 6 DXF, 7 GeoJSON
//   through OGR with --domain-layer;
//   Shapefile: three little-endian uint32 lengths of the .shp, .shx and .dbf that follow, the rest is the .prj;
//   bit 3: the file is also read as a --features file, bit 4: also as a --boundary file, bit 5: --repair.
// Files live in /vsimem/ (GDAL's memory file system) and are removed after each input. Network access is pointed
// at a closed loopback port (GML may name remote schemas).
//
// GDAL 3.6.2's DXF driver does not return from some files (ogrinfo neither: outside the project; `mesh` bounds it
// with --read-time-limit, tests/data/adversarial/dxf_gdal_loops.dxf). A DXF input is first read by GDAL alone in
// a child process; one GDAL cannot read within kGdalAloneSeconds is skipped, so the fuzzer keeps looking at
// what is ours instead of stopping at that driver.
#include <cpl_conv.h>
#include <cpl_error.h>
#include <cpl_vsi.h>
#include <gdal.h>
#include <ogr_api.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>

#include "polysquare/core/error.h"
#include "polysquare/input/read_region.h"

namespace {

const char* const dir = "/vsimem/fuzz";

void put(const std::string& path, const std::uint8_t* data, std::size_t size) {
  // VSIFileFromMemBuffer does not copy; the written file must own its bytes, so write through VSIF.
  VSILFILE* f = VSIFOpenL(path.c_str(), "wb");
  if (!f) return;
  if (size) VSIFWriteL(data, 1, size, f);
  VSIFCloseL(f);
}

constexpr int kGdalAloneSeconds = 2;

// Whether GDAL alone opens `path` and reads every feature of every layer within kGdalAloneSeconds (in a child
// process, so a driver that never returns can be killed). True when that cannot be tried.
bool gdal_reads_in_time(const std::string& path) {
  const pid_t pid = fork();
  if (pid < 0) return true;
  if (pid == 0) {
    GDALAllRegister();
    if (GDALDatasetH ds = GDALOpenEx(path.c_str(), GDAL_OF_VECTOR | GDAL_OF_READONLY, nullptr, nullptr, nullptr)) {
      for (int l = 0; l < GDALDatasetGetLayerCount(ds); ++l) {
        OGRLayerH layer = GDALDatasetGetLayer(ds, l);
        OGR_L_ResetReading(layer);
        while (OGRFeatureH f = OGR_L_GetNextFeature(layer)) OGR_F_Destroy(f);
      }
      GDALClose(ds);
    }
    _exit(0);
  }
  for (int waited = 0; waited < kGdalAloneSeconds * 100; ++waited) {
    if (waitpid(pid, nullptr, WNOHANG) == pid) return true;
    usleep(10000);
  }
  kill(pid, SIGKILL);
  waitpid(pid, nullptr, 0);
  return false;
}

std::uint32_t u32(const std::uint8_t* p) {
  return static_cast<std::uint32_t>(p[0]) | static_cast<std::uint32_t>(p[1]) << 8 | static_cast<std::uint32_t>(p[2]) << 16 |
         static_cast<std::uint32_t>(p[3]) << 24;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  CPLSetErrorHandler(CPLQuietErrorHandler);
  CPLSetConfigOption("GDAL_HTTP_PROXY", "127.0.0.1:9");
  CPLSetConfigOption("GDAL_HTTP_TIMEOUT", "1");
  CPLSetConfigOption("GML_DOWNLOAD_WFS_SCHEMA", "NO");
  CPLSetConfigOption("GDAL_DISABLE_READDIR_ON_OPEN", "EMPTY_DIR");
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::uint8_t mode = data[0];
  const std::uint8_t* body = data + 1;
  std::size_t rest = size - 1;
  static const char* const extensions[] = {".gpkg", ".shp", ".geojson", ".kml", ".gml", ".fgb", ".dxf", ".json"};
  const int format = mode & 7;
  const std::string path = std::string(dir) + "/in" + extensions[format];
  VSIMkdir(dir, 0755);
  if (format == 1) {
    if (rest < 12) return 0;
    std::size_t len[3] = {u32(body), u32(body + 4), u32(body + 8)};
    body += 12;
    rest -= 12;
    const char* const sidecars[] = {".shp", ".shx", ".dbf"};
    for (int k = 0; k < 3; ++k) {
      len[k] = std::min(len[k], rest);
      put(std::string(dir) + "/in" + sidecars[k], body, len[k]);
      body += len[k];
      rest -= len[k];
    }
    put(std::string(dir) + "/in.prj", body, rest);
  } else {
    put(path, body, rest);
  }
  if (format == 6 && !gdal_reads_in_time(path)) {
    VSIRmdirRecursive(dir);
    return 0;
  }
  polysquare::InputOptions options;
  if (format == 2) options.where = "1 = 1";
  if (format == 7) options.domain_layer = "in";
  if (mode & 0x08) options.feature_files.push_back(path);
  if (mode & 0x10) options.boundary_files.push_back(path);
  options.repair = (mode & 0x20) != 0;
  try {
    polysquare::InputNotes notes;
    polysquare::read_input(path, options, notes);
  } catch (const polysquare::InputError&) {
  }
  VSIRmdirRecursive(dir);
  return 0;
}
