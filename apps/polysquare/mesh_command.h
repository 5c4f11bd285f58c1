// `polysquare mesh`: its flags (mesh_flags.cpp) and the run (run_mesh.cpp): read, mesh, measure, write, report.
#pragma once

#include <CLI/CLI.hpp>

#include <cstddef>
#include <new>
#include <string>

#include "polysquare/driver/mpi_driver.h"
#include "polysquare/input/read_region.h"
#include "polysquare/pipeline/mesh_region.h"

namespace polysquare::cli {

struct MeshArgs {
  std::string input, output, report, picture, partition_picture, map = "ppm";
  bool binary = false, bend_interfaces = false;
  bool quiet = false, verbose = false;  ///< --quiet: errors and warnings only; --verbose: stage timings
  double time_limit = 0.0;  ///< --time-limit: seconds of wall time before the run ends in exit 3 (0 = none)
  double read_time_limit = 120.0;  ///< --read-time-limit: seconds reading the input may take (0 = none)
  double depth = 0.0;  ///< constant water depth (positive down) for solver files, when depth_given
  bool depth_given = false;
  std::string bathymetry, bathymetry_positive = "up";  ///< raster of elevations (up) or depths (down)
  std::string size_raster;        ///< --size-field: a raster of sizes (graded runs)
  std::string size_picture;       ///< --size-picture: a PNG of the size field (graded runs)
  std::string picture_color = "sj";  ///< --picture-color: what colours --picture's quads (size: graded runs)
  double per_wavelength = 0.0;    ///< --per-wavelength N: quads per M2 tidal wavelength, with --bathymetry
  std::string msh_version = "2.2", msh_features = "nodes";
  std::size_t pieces = 0;  ///< --pieces: .vtu pieces of a .pvtu output (0 = one per million quads)
  InputOptions input_options;
  MeshOptions options;
  const MpiDriver* mpi = nullptr;  ///< the processes of this run (mpirun); only rank 0 writes and reports
};

/// Adds the `mesh` subcommand to `app`, its flags bound to `args`.
CLI::App* add_mesh_command(CLI::App& app, MeshArgs& args);

/// std::bad_alloc met by a run, with what the run would have needed (the estimated quads) in what().
class OutOfMemory : public std::bad_alloc {
 public:
  explicit OutOfMemory(std::string message) : message_(std::move(message)) {}
  const char* what() const noexcept override { return message_.c_str(); }

 private:
  std::string message_;
};

/// Runs `polysquare mesh`; returns the exit code (errors are thrown: InputError, MeshingError, OutOfMemory).
int run_mesh(const MeshArgs& args);

}  // namespace polysquare::cli
