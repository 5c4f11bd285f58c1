// polysquare command-line tool: parses options into the library's options structs, calls the library, reports.
// Exit codes: 0 success, 1 unexpected error, 2 bad input or options, 3 meshing failure (time limit and out of
// memory too).
#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <cstdio>
#include <exception>
#include <iostream>
#include <new>
#include <optional>

#include "mesh_command.h"
#include "polysquare/core/error.h"
#include "polysquare/core/version.h"
#include "polysquare/input/read_region.h"
#include "polysquare/io/atomic_file.h"
#include "polysquare/io/mesh_io.h"
#include "polysquare/io/render.h"
#include "polysquare/io/solver_files.h"
#include "polysquare/pipeline/invariants.h"
#include "polysquare/pipeline/report.h"
#include "polysquare/quality/quality.h"
#include "polysquare/driver/mpi_driver.h"

namespace {

using namespace polysquare;

void on_signal(int sig) {
  remove_pending_temporaries();
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}

// An exception no one catches (one thrown in a thread of a library): out of memory is said in one line and ends
// the run in exit 3; anything else is said and aborts, as before. The run's temporaries are removed either way.
[[noreturn]] void on_terminate() {
  remove_pending_temporaries();
  if (const std::exception_ptr p = std::current_exception()) {
    try {
      std::rethrow_exception(p);
    } catch (const std::bad_alloc&) {
      static const char line[] = "error: the run ran out of memory; nothing written\n";
      [[maybe_unused]] const ssize_t n = ::write(2, line, sizeof line - 1);
      ::_exit(3);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "error: unexpected failure: %s\n", e.what());
    } catch (...) {
    }
  }
  std::abort();
}

struct RenderArgs {
  std::string mesh, output, color = "sj", window, domain;
  int width = 1600;
};

int run_render(const RenderArgs& args) {
  RenderOptions ro;
  ro.color = parse_render_color(args.color);
  if (!args.window.empty()) ro.window = parse_window(args.window);
  ro.width_px = args.width;
  const std::string ext = lower_extension(args.output);
  if (ext != ".png" && ext != ".svg") throw InputError(args.output + ": pictures are .png or .svg");
  const QuadMesh mesh = read_mesh(args.mesh);
  std::optional<Region> region;
  if (!args.domain.empty()) region = read_region(args.domain);
  const RenderStats st = render_mesh(args.output, mesh, region ? &*region : nullptr, ro);
  std::cerr << "polysquare: " << st.quads_drawn << " quads drawn, " << st.singular_nodes_marked
            << " singular nodes marked" << (st.edges_drawn ? "" : ", quad edges hidden (too small to see)") << " -> "
            << args.output << " (" << st.width_px << " x " << st.height_px << ")\n";
  return 0;
}

struct QualityArgs {
  std::string mesh, domain;
  bool json = false, require_quads = false;
};

int run_quality(const QualityArgs& args) {
  const std::string& mesh_path = args.mesh;
  const bool require_quads = args.require_quads;
  const QuadMesh mesh = read_mesh(mesh_path);
  check_judgeable(mesh, mesh_path);
  const QuadMetrics metrics = quad_metrics(mesh);
  const QualityReport quality = compute_quality(mesh, metrics);
  const FiniteVolumeQuality fv = finite_volume_quality(mesh);
  // Shape figures cover quads only, so a mesh of triangles would otherwise read as SJ 0 and pass.
  if (quality.triangles > 0)
    std::cerr << (require_quads ? "error: " : "warning: ") << mesh_path << " has " << quality.triangles
              << " triangles beside " << quality.quads << " quads; quality figures cover the quads only\n";
  std::optional<DomainDistance> domain;
  if (!args.domain.empty()) domain = domain_distance(mesh, read_region(args.domain));
  // Quads that overlap pass every shape figure (each quad alone is fine): the mesh is judged, then refused.
  const QuadOverlaps overlaps = find_overlapping_quads(mesh);
  if (args.json) {
    nlohmann::json j = to_json(quality);
    j["overlapping_quad_pairs"] = overlaps.pairs;
    j["finite_volume"] = to_json(fv);
    if (domain) j["domain"] = to_json(*domain);
    std::cout << j.dump(2) << "\n";
  } else {
    std::cout << format_quality_text(quality, domain ? &*domain : nullptr) << "  overlapping quad pairs "
              << overlaps.pairs << "\n" << format_finite_volume_text(fv) << format_schism_text(quality.schism);
  }
  // An inverted or collapsed quad (scaled Jacobian <= 0) is not a mesh a solver takes: figures, then a refusal.
  if (quality.inverted > 0) {
    const auto first = static_cast<std::size_t>(
        std::find_if(metrics.sj.begin(), metrics.sj.end(), [](double v) { return !(v > 0); }) - metrics.sj.begin());
    Vec2 centre{0, 0};
    for (const auto v : mesh.quads[first]) centre = centre + 0.25 * mesh.nodes[static_cast<std::size_t>(v)];
    std::cerr << "error: " << mesh_path << ": " << quality.inverted
              << (quality.inverted == 1 ? " quad is" : " quads are") << " inverted or collapsed (scaled Jacobian <= 0), first quad "
              << first << " (counted from 0) at " << point_text(centre) << "\n";
    return 2;
  }
  if (overlaps.pairs) {
    std::cerr << "error: " << mesh_path << ": " << overlaps.pairs
              << (overlaps.pairs == 1 ? " pair of quads overlaps" : " pairs of quads overlap") << ", first quads "
              << overlaps.first_a << " and " << overlaps.first_b << " (counted from 0) at " << point_text(overlaps.at) << "\n";
    return 2;
  }
  return require_quads && quality.triangles > 0 ? 2 : 0;
}

CLI::App* add_quality_command(CLI::App& app, QualityArgs& args) {
  auto* cmd = app.add_subcommand("quality", "report the quality of a mesh (MSH 2.2/4.1, VTU)");
  cmd->add_option("mesh", args.mesh, "mesh file")->required();
  cmd->add_option("--domain", args.domain, "input region, to measure boundary and feature distances");
  cmd->add_flag("--json", args.json, "print JSON");
  cmd->add_flag("--require-quads", args.require_quads, "exit 2 if the mesh has triangles");
  return cmd;
}

CLI::App* add_render_command(CLI::App& app, RenderArgs& args) {
  auto* cmd = app.add_subcommand("render", "draw a mesh (MSH, VTU) as a PNG or SVG picture");
  cmd->add_option("mesh", args.mesh, "mesh file")->required();
  cmd->add_option("-o,--output", args.output, "picture: .png (any size) or .svg (small meshes)")->required();
  cmd->add_option("--color", args.color,
                  "quad colours: sj (scaled Jacobian), skew, part (subregion) or singularities (plain, valence "
                  "marks only)")
      ->check(CLI::IsMember({"sj", "skew", "part", "singularities"}))->capture_default_str();
  cmd->add_option("--window", args.window, "x0,y0,x1,y1: the part of the plane to draw (mesh units)");
  cmd->add_option("--width", args.width, "picture width in pixels, colour bar included")
      ->check(CLI::Range(300, 16000))->capture_default_str();
  cmd->add_option("--domain", args.domain, "input region to draw under the mesh (thin dashed lines)");
  return cmd;
}

// The exit code of an error: 2 bad input or options, 3 meshing failure, 1 anything else. Not an error every
// process meets alike (those are InputError and MeshingError): the others may be waiting for this one, so it is
// printed by whichever process met it and ends the whole job.
int exit_on_error(const MpiDriver& mpi) {
  try {
    throw;
  } catch (const InputError& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 2;
  } catch (const MeshingError& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 3;
  } catch (const std::bad_alloc& e) {
    // Out of memory: this process may have met it alone while the others wait on it, so it speaks and ends the
    // job. What it held, outputs' temporaries included, was freed on the way here.
    remove_pending_temporaries();
    const bool said = dynamic_cast<const cli::OutOfMemory*>(&e) != nullptr;
    if (mpi.rank() != 0) {
      std::cerr.rdbuf(std::clog.rdbuf());
      std::cerr.clear();
    }
    std::cerr << "error: " << (mpi.rank() != 0 ? "rank " + std::to_string(mpi.rank()) + ": " : std::string())
              << (said ? e.what() : "the run ran out of memory; nothing written") << "\n";
    mpi.abort(3);
    return 3;
  } catch (const std::exception& e) {
    if (mpi.rank() != 0) {
      std::cerr.rdbuf(std::clog.rdbuf());
      std::cerr.clear();
      std::cerr << "error: rank " << mpi.rank() << ": " << e.what() << "\n";
    } else {
      std::cerr << "error: " << e.what() << "\n";
    }
    mpi.abort(1);
    return 1;
  }
}

}  // namespace

int main(int argc, char** argv) {
  // Under mpirun every process runs this same command; the driver starts MPI (else it does nothing).
  const MpiDriver mpi(argc, argv);
  if (mpi.rank() != 0) std::cerr.rdbuf(nullptr);  // rank 0 speaks for all: they meet the same warnings
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  std::set_terminate(on_terminate);
  spdlog::set_level(spdlog::level::warn);

  CLI::App app{"polysquare: feature-aligned semi-structured quad meshes of 2D regions"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("polysquare ") + library_version() +
                                        (MpiDriver::built_with_mpi() ? " (mpirun -np P: Open MPI)" : " (one process: built without MPI)"));
  cli::MeshArgs mesh;
  QualityArgs quality;
  RenderArgs render;
  CLI::App* cmd_mesh = cli::add_mesh_command(app, mesh);
  CLI::App* cmd_quality = add_quality_command(app, quality);
  CLI::App* cmd_render = add_render_command(app, render);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    std::cerr << "error: " << e.what() << "\n";
    return 2;
  }
  mesh.depth_given = cmd_mesh->count("--depth") > 0;
  mesh.mpi = &mpi;
  if (mpi.rank() != 0) {
    mesh.quiet = true;
    spdlog::set_level(spdlog::level::off);
  }
  try {
    if (*cmd_mesh) return cli::run_mesh(mesh);
    if (*cmd_render) return run_render(render);
    if (*cmd_quality) return run_quality(quality);
  } catch (...) {
    return exit_on_error(mpi);
  }
  return 1;
}
