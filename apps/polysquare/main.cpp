// polysquare command-line tool: parses options into the library's options structs, calls the library, reports.
// Exit codes: 0 success, 1 unexpected error, 2 bad input or options, 3 meshing failure.
#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <sstream>

#include "polysquare/core/error.h"
#include "polysquare/core/version.h"
#include "polysquare/input/read_region.h"
#include "polysquare/io/atomic_file.h"
#include "polysquare/io/bathymetry.h"
#include "polysquare/io/mesh_io.h"
#include "polysquare/io/render.h"
#include "polysquare/io/solver_files.h"
#include "polysquare/io/svg.h"
#include "polysquare/partition/partition.h"
#include "polysquare/pipeline/check_options.h"
#include "polysquare/pipeline/invariants.h"
#include "polysquare/pipeline/local_frame.h"
#include "polysquare/pipeline/mesh_region.h"
#include "polysquare/pipeline/report.h"
#include "polysquare/quality/quality.h"
#include "terminal_progress.h"
#include "polysquare/driver/mpi_driver.h"
#include "time_limit.h"

namespace {

namespace fs = std::filesystem;
using namespace polysquare;

void on_signal(int sig) {
  remove_pending_temporaries();
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}

struct MeshArgs {
  std::string input, output, report, picture, partition_picture, map = "ppm";
  bool binary = false, bend_interfaces = false;
  bool quiet = false, verbose = false;  ///< --quiet: errors and warnings only; --verbose: stage timings
  double time_limit = 0.0;  ///< --time-limit: seconds of wall time before the run ends in exit 3 (0 = none)
  double read_time_limit = 120.0;  ///< --read-time-limit: seconds reading the input may take (0 = none)
  double depth = 0.0;  ///< constant water depth (positive down) for solver files, when depth_given
  bool depth_given = false;
  std::string bathymetry, bathymetry_positive = "up";  ///< raster of elevations (up) or depths (down)
  std::string msh_version = "2.2", msh_features = "nodes";
  std::size_t pieces = 0;  ///< --pieces: .vtu pieces of a .pvtu output (0 = one per million quads)
  InputOptions input_options;
  MeshOptions options;
  const MpiDriver* mpi = nullptr;  ///< the processes of this run (mpirun); only rank 0 writes and reports
};

// --picture: PNG, or SVG when the mesh is small enough for one (else a PNG beside it, with a warning).
void write_picture(const fs::path& picture, const QuadMesh& mesh, const Region& region) {
  RenderOptions ro;
  fs::path to = picture;
  if (lower_extension(picture) == ".svg" && mesh.quads.size() > ro.svg_max_quads) {
    to.replace_extension(".png");
    std::cerr << "warning: " << mesh.quads.size() << " quads are too many for an SVG picture (limit "
              << ro.svg_max_quads << "); wrote " << to.string() << " instead\n";
  }
  render_mesh(to, mesh, &region, ro);
}

// Every output is checked before any work (format, directory, writability, distinct, not an input): a refusal
// takes milliseconds, not a meshing run.
void check_outputs(const MeshArgs& args) {
  check_output_path(args.output);
  std::vector<std::pair<fs::path, std::string>> outputs{{args.output, "-o"}}, inputs{{args.input, "input"}};
  if (lower_extension(args.output) == ".gr3")
    outputs.push_back({fs::path(args.output).replace_extension(".ll"), "the .ll companion of -o"});
  // A .pvtu's pieces: those asked for, or the first (their number follows the mesh); the others are checked
  // when they are written, before anything is committed.
  if (lower_extension(args.output) == ".pvtu")
    for (std::size_t k = 0; k < std::max<std::size_t>(args.pieces, 1); ++k) {
      const fs::path piece = pvtu_piece_path(args.output, k);
      check_output_file(piece, "a piece of -o", {".vtu"});
      outputs.push_back({piece, "a piece of -o"});
    }
  auto optional = [&](const std::string& path, const char* what, const char* ext) {
    if (path.empty()) return;
    check_output_file(path, what, {ext});
    outputs.push_back({path, what});
  };
  optional(args.report, "--report", ".json");
  if (!args.picture.empty()) {
    check_output_file(args.picture, "--picture", {".png", ".svg"});
    outputs.push_back({args.picture, "--picture"});
  }
  optional(args.partition_picture, "--partition-picture", ".svg");
  for (const auto& f : args.input_options.feature_files) inputs.push_back({f, "--features file"});
  if (!args.bathymetry.empty()) inputs.push_back({args.bathymetry, "--bathymetry raster"});
  check_distinct_files(outputs, inputs);
}

// A .pvtu meshed by several processes: each writes its own pieces (write_pvtu's piece_rank), and all commit
// them only when every process wrote its share. Every process calls agree() once, also when its part failed
// (the destructor says so for it), so none waits for another that has stopped.
class PieceAgreement {
 public:
  explicit PieceAgreement(const WorkSharing* sharing) : sharing_(sharing) {}
  ~PieceAgreement() {
    if (sharing_ && !agreed_) {
      try {
        agree("stopped before writing its pieces");
      } catch (...) {
      }
    }
  }
  PieceAgreement(const PieceAgreement&) = delete;
  PieceAgreement& operator=(const PieceAgreement&) = delete;
  /// `mine` empty: this process wrote its pieces. Returns the first other process's failure, or empty.
  std::string agree(const std::string& mine) {
    agreed_ = true;
    if (!sharing_) return {};
    const int n = sharing_->processes();
    std::vector<std::string> status(static_cast<std::size_t>(n));
    std::vector<int> owner(static_cast<std::size_t>(n));
    for (int r = 0; r < n; ++r) owner[static_cast<std::size_t>(r)] = r;
    status[static_cast<std::size_t>(sharing_->rank())] = mine;
    sharing_->all_gather(status, owner, "pvtu pieces");
    for (int r = 0; r < n; ++r)
      if (r != sharing_->rank() && !status[static_cast<std::size_t>(r)].empty())
        return "process " + std::to_string(r) + ": " + status[static_cast<std::size_t>(r)];
    return {};
  }

 private:
  const WorkSharing* sharing_;
  bool agreed_ = false;
};

int run_mesh(const MeshArgs& args) {
  check_mesh_options(args.options);
  if (args.depth_given && !std::isfinite(args.depth))
    throw InputError("--depth must be a finite number, got " + short_number(args.depth));
  if (!(std::isfinite(args.time_limit) && args.time_limit >= 0))
    throw InputError("--time-limit must be a finite number of seconds >= 0 (0 = none), got " + short_number(args.time_limit));
  if (!(std::isfinite(args.read_time_limit) && args.read_time_limit >= 0))
    throw InputError("--read-time-limit must be a finite number of seconds >= 0 (0 = none), got " +
                     short_number(args.read_time_limit));
  check_outputs(args);  // before minutes of meshing
  const std::string out_ext = lower_extension(args.output);
  if (args.pieces > 0 && out_ext != ".pvtu")
    throw InputError("--pieces writes a parallel VTK file: -o must end in .pvtu, not " + args.output);
  if ((args.depth_given || !args.bathymetry.empty()) && (out_ext == ".msh" || out_ext == ".vtu" || out_ext == ".pvtu"))
    std::cerr << "warning: depths are written to .gr3, .nc and .2dm files only, not to " << args.output << "\n";
  if (args.depth_given && !args.bathymetry.empty()) throw InputError("--depth and --bathymetry exclude each other");
  if (!args.bathymetry.empty() && !fs::is_regular_file(args.bathymetry))
    throw InputError(args.bathymetry + ": the bathymetry raster does not exist");
  // Progress on a terminal (never in a pipe or under CI), stage timings with --verbose; quiet: warnings only.
  cli::TerminalProgress shown(args.quiet ? cli::Verbosity::quiet : args.verbose ? cli::Verbosity::verbose : cli::Verbosity::normal);
  cli::TimeLimit limit(args.time_limit, args.read_time_limit, args.input, shown.callback());
  ProgressReporter progress(limit.callback());
  std::ostringstream discarded;
  std::ostream& info = args.quiet ? discarded : std::cerr;
  InputNotes notes;
  progress.start("read input");
  const Region region = read_input(args.input, args.input_options, notes);
  progress.finish("read input");
  // Each kind of note: the first few, then one line with the count (all of them are in the report).
  auto summarise = [](const std::vector<std::string>& lines, const char* prefix, const char* what) {
    for (std::size_t i = 0; i < lines.size() && i < 5; ++i) std::cerr << "warning: " << prefix << lines[i] << "\n";
    if (lines.size() > 5) std::cerr << "warning: ... and " << lines.size() - 5 << " more " << what << " (see the report)\n";
  };
  summarise(notes.repairs, "repaired: ", "repairs");
  summarise(notes.warnings, "", "input warnings");
  summarise(notes.snaps, "", "snapped points");
  if (notes.reprojected) info << "input in " << notes.input_crs << ", meshed in " << region.crs << " (--size in metres)\n";
  MeshOptions options = args.options;
  check_mesh_size(region, options);
  {
    // The figure to choose --size from, before minutes of meshing: quads of size h cover about area / h^2.
    const Box2 box = region.bounding_box();
    const double area = domain_area(region);
    info << "region " << short_number(box.hi.x - box.lo.x) << " x " << short_number(box.hi.y - box.lo.y)
         << ", area " << short_number(area) << ": --size " << short_number(options.size) << " gives about "
         << static_cast<long long>(std::llround(area / (options.size * options.size)))
         << " quads (area / size^2; half the size, four times as many)\n";
  }
  options.keep_partition = !args.partition_picture.empty();
  options.map.composition = args.map == "gpm" ? MapComposition::gpm : MapComposition::ppm;
  options.map.layout.straight_interfaces = !args.bend_interfaces;
  // Far from the origin (1e8 .. 1e11 around a small domain) the region is meshed in a local frame and the mesh
  // moved back before writing; figures are measured in the local frame, places printed in the input's.
  const Vec2 origin = local_origin(region);
  const bool moved = origin.x != 0 || origin.y != 0;
  Region local = region;
  if (moved) {
    translate(local, {-origin.x, -origin.y});
    std::cerr << "meshed relative to (" << short_number(origin.x) << ", " << short_number(origin.y)
              << "), " << short_number(std::max(std::abs(origin.x), std::abs(origin.y)) / region.bounding_box().diagonal())
              << " times the domain's size away from the origin; written back in the input's coordinates\n";
  }
  auto place = [&](const nlohmann::json& at) {
    return "(" + short_number(at[0].get<double>() + origin.x) + ", " + short_number(at[1].get<double>() + origin.y) + ")";
  };
  options.progress = limit.callback();
  if (args.mpi && args.mpi->active()) {
    // The processes of one machine share its cores (0 = all cores between them).
    options.map.sharing = args.mpi->sharing();
    if (options.threads == 0) options.threads = args.mpi->threads_per_process();
  }
  MeshResult result;
  try {
    result = mesh_region(local, options);
  } catch (const MeshingError& e) {
    if (!moved) throw;
    throw MeshingError(std::string(e.what()) + " (places relative to (" + short_number(origin.x) + ", " +
                       short_number(origin.y) + "))");
  }
  if (moved) result.report["input"]["local_origin"] = {origin.x, origin.y};
  // Every process holds the mesh; rank 0 measures and writes it, but for the pieces of a .pvtu, which each
  // process writes its share of.
  const bool pieces_by_process = args.mpi && args.mpi->active() && out_ext == ".pvtu";
  const std::size_t pieces =
      args.pieces > 0 ? args.pieces
                      : std::max<std::size_t>(pvtu_pieces(result.mesh, 0), pieces_by_process ? static_cast<std::size_t>(args.mpi->processes()) : 1);
  PieceAgreement agreement(pieces_by_process ? args.mpi->sharing().get() : nullptr);
  if (args.mpi && args.mpi->rank() != 0) {
    if (!pieces_by_process) return 0;
    std::string failed;
    OutputBatch batch;
    try {
      translate(result.mesh, origin);
      MeshWriteOptions write;
      write.pieces = pieces;
      write.piece_rank = static_cast<std::size_t>(args.mpi->rank());
      write.piece_processes = static_cast<std::size_t>(args.mpi->processes());
      write_mesh(args.output, result.mesh, write);
    } catch (const std::exception& e) {
      failed = e.what();
    }
    // Rank 0 says what failed, here or there; this process commits only when all wrote their share.
    const bool others_wrote = agreement.agree(failed).empty();
    if (failed.empty() && others_wrote) batch.commit();
    return 0;
  }
  if (args.mpi && args.mpi->active()) result.report["summary"]["processes"] = args.mpi->processes();
  progress.start("quality");
  QualityReport quality = compute_quality(result.mesh);
  quality.schism.angle_ratio_worst_at = quality.schism.angle_ratio_worst_at + origin;
  quality.schism.aspect_ratio_worst_at = quality.schism.aspect_ratio_worst_at + origin;
  DomainDistanceOptions measure{args.options.corner_threshold_deg, {}};
  for (const auto& d : result.report["dropped_parts"]) measure.skip_parts.push_back(d["part"].get<int>());
  // The mesh covers the (simplified) domain it conforms to, less the parts left out as too small, up to the
  // chords along curves: a larger change is said, never silent.
  if (const double change = area_relative_mismatch(result.mesh, result.region, measure.skip_parts);
      !(std::abs(change) <= 0.01))
    std::cerr << "warning: the mesh's area differs from the domain's by " << short_number(100 * change)
              << " % (more than 1 %: chords of coarse curves, or a region read wrongly)\n";
  DomainDistance domain = domain_distance(result.mesh, local, measure);
  // Places in the input's frame, as every other place the CLI prints.
  auto to_input_frame = [&](DomainDistance& d) {
    d.feature_max_at = d.feature_max_at + origin;
    d.feature_node_max_at = d.feature_node_max_at + origin;
  };
  to_input_frame(domain);
  FiniteVolumeQuality fv = finite_volume_quality(result.mesh);
  fv.orthogonality_worst_at = fv.orthogonality_worst_at + origin;
  fv.smoothness_worst_at = fv.smoothness_worst_at + origin;
  // Against the simplified curves too, which the mesh conforms to (the input distance includes the simplification).
  std::optional<DomainDistance> simplified;
  if (result.report["simplify"]["vertices_after"] != result.report["simplify"]["vertices_before"] ||
      !result.report["dropped_curves"].empty())
  {
    simplified = domain_distance(result.mesh, result.region, measure);
    to_input_frame(*simplified);
  }
  add_quality_to_report(result.report, quality, fv, domain, args.options.size, simplified ? &*simplified : nullptr);
  result.report["input"]["repairs"] = notes.repairs;
  result.report["input"]["snapped"] = notes.snaps;
  result.report["input"]["warnings"] = notes.warnings;
  result.report["input"]["input_crs"] = notes.input_crs;
  // Named groups (domains, ring pieces, features, boundary segments) from the region the mesh conforms to.
  MeshGroups groups = mesh_groups(result.mesh, &result.region);
  result.report["groups"] = to_json(groups);
  result.report["input"]["boundary_segments"] = region.boundary_segments.size();
  for (const std::string& w : groups.warnings) std::cerr << "warning: " << w << "\n";
  const std::string group_summary = format_groups_text(groups);
  progress.finish("quality");
  limit.stop();  // the outputs are committed whole or not at all, never cut off between two renames
  progress.start("write");
  // Outputs are written only after the whole mesh passed its checks, and committed together: each goes to a
  // synced temporary, and all are renamed onto their targets only when every one was written.
  translate(result.mesh, origin);
  if (const std::int64_t q = moved ? first_folded_quad(result.mesh) : -1; q >= 0) {
    const auto& quad = result.mesh.quads[static_cast<std::size_t>(q)];
    throw MeshingError("written back in the input's coordinates, " + short_number(std::max(std::abs(origin.x), std::abs(origin.y))) +
                       " from the origin, quad " + std::to_string(q) + " at " + point_text(result.mesh.nodes[static_cast<std::size_t>(quad[0])]) +
                       " folds: coordinates there are too coarse for --size " + short_number(args.options.size) +
                       "; use a larger size or move the input nearer the origin");
  }
  OutputBatch batch;
  MeshWriteOptions write{args.binary,
                               args.msh_features == "lines" ? MshFeatures::lines
                               : args.msh_features == "none" ? MshFeatures::none : MshFeatures::nodes,
                               args.msh_version == "4.1" ? MshVersion::v4_1 : MshVersion::v2_2,
                               !args.bathymetry.empty()
                                   ? sample_bathymetry(args.bathymetry, result.mesh.nodes, result.mesh.crs,
                                                       {args.bathymetry_positive == "down"})
                               : args.depth_given ? std::vector<double>(result.mesh.nodes.size(), args.depth)
                                                  : std::vector<double>{},
                               notes.input_crs,
                               std::move(groups)};
  write.pieces = pieces;
  if (pieces_by_process) write.piece_processes = static_cast<std::size_t>(args.mpi->processes());
  write_mesh(args.output, result.mesh, write);
  if (!args.report.empty())
    write_file_atomically(args.report, [&](std::ostream& os) { os << report_text(result.report); }, false);
  if (!args.picture.empty()) write_picture(args.picture, result.mesh, region);
  if (!args.partition_picture.empty()) {
    PartitionResult partition;
    partition.triangle_part = result.background_part;
    write_partition_svg(args.partition_picture, result.background, partition);
  }
  if (const std::string other = agreement.agree(""); !other.empty())
    throw InputError(args.output + ": a process could not write its pieces (" + other + ")");
  batch.commit();
  progress.finish("write");
  if (out_ext == ".nc" && fv.orthogonality_above > 0)
    std::cerr << "warning: " << fv.orthogonality_above << " of " << fv.interior_edges
              << " interior edges have a D-Flow FM orthogonality above " << fv.orthogonality_limit
              << ", which D-Flow FM refuses; the worst, " << fv.orthogonality.max << ", at "
              << at_text(fv.orthogonality_worst_at) << "\n";
  // Parts left out as smaller than one element: the first few by place, then one line for the rest.
  const auto& dropped = result.report["dropped_parts"];
  for (std::size_t i = 0; i < dropped.size() && i < 3; ++i)
    std::cerr << "warning: part " << dropped[i]["part"] << " left out: its area " << dropped[i]["area"]
              << " is less than one element, at " << place(dropped[i]["at"]) << "\n";
  if (dropped.size() > 3) {
    double area = 0;
    for (const auto& d : dropped) area += d["area"].get<double>();
    std::cerr << "warning: " << dropped.size() << " parts smaller than one element left out in all (total area "
              << short_number(area) << "); the report's dropped_parts lists each\n";
  }
  if (const auto& curves = result.report["dropped_curves"]; !curves.empty()) {
    std::map<std::string, std::size_t> kinds;
    const nlohmann::json* widest = &curves.front();
    for (const auto& d : curves) {
      kinds[d["kind"].get<std::string>()]++;
      if (d["width"].get<double>() > (*widest)["width"].get<double>()) widest = &d;
    }
    std::cerr << "warning: " << curves.size() << " curves around regions narrower than the size left out (";
    for (const auto& [kind, n] : kinds) std::cerr << (kind == kinds.begin()->first ? "" : ", ") << n << " " << kind;
    std::cerr << "; the widest " << (*widest)["width"] << " at " << place((*widest)["at"])
              << "; the report's dropped_curves lists them; --min-island-width 0 keeps them)\n";
  }
  std::size_t patches = 0, patch_quads = 0;
  for (const auto& u : result.report["unstructured"])
    if (u["meshed_by"] == "patch" && ++patches <= 5)
      std::cerr << "warning: part " << u["part"] << ": subregion " << u["subregion"] << " at " << place(u["at"])
                << " is an unstructured patch of " << u["quads"] << " quads: "
                << u["reason"].get<std::string>() << "\n";
    else if (u["meshed_by"] == "patch")
      patch_quads += u["quads"].get<std::size_t>();
  if (patches > 5)
    std::cerr << "warning: ... and " << patches - 5 << " more unstructured patches (" << patch_quads
              << " quads; the report's unstructured lists each)\n";
  if (const auto& simp = result.report["simplify"]; simp["vertices_after"] != simp["vertices_before"])
    info << "simplified curves finer than the size: " << simp["vertices_before"] << " -> " << simp["vertices_after"]
              << " vertices, largest distance moved " << simp["max_distance"] << " (" << simp["max_distance_over_size"]
              << " of the size), area change " << simp["area_change"] << " (--simplify 0 keeps them)\n";
  info << "structured fraction " << result.report["summary"]["structured_fraction"] << " ("
            << result.report["summary"]["unstructured_subregions"] << " of " << result.report["summary"]["subregions"]
            << " subregions unstructured)\n";
  // Which candidate each part kept, and why the explicitly requested one was not kept.
  for (const auto& part : result.report["candidates"]) {
    const bool explicit_parts = args.options.parts > 0;
    for (const auto& c : part) {
      if (c.contains("chosen") && c.contains("quads_pinned_by_sharp_input"))
        std::cerr << "warning: part " << c["part"] << ": " << c["quads_pinned_by_sharp_input"]
                  << " quads lie in input corners sharper than the --min-sj gate and are left out of it (scaled "
                     "Jacobian min "
                  << c["pinned_min_scaled_jacobian"] << " at " << place(c["pinned_worst_at"])
                  << "; the others' min is " << c["unpinned_min_scaled_jacobian"] << ")\n";
      if (c.contains("chosen") && c.contains("poor_quads")) {
        const auto& first = c["poor_quads"]["first"][0];
        std::cerr << "warning: part " << c["part"] << ": " << c["poor_quads"]["count"]
                  << " quads stay outside --min-sj or --max-edge-ratio after local repair (within --max-poor-fraction); "
                     "the first at "
                  << place(first["at"]) << " (scaled Jacobian " << first["scaled_jacobian"] << ", edge ratio "
                  << first["edge_ratio"] << "); the report's candidates list them\n";
      }
      if (c.contains("chosen") && c.contains("fallback")) {
        std::cerr << "warning: part " << c["part"] << ": none of " << part.size() - 1
                  << " poly-square candidates meshed it; meshed unstructured by splitting triangles into quads ("
                  << c["interior_singularities"] << " interior singularities, scaled Jacobian min "
                  << c["min_scaled_jacobian"] << "); the report's candidates say why each failed\n";
      } else if (c.contains("chosen")) {
        if (part.size() > 1 && !explicit_parts)
          info << "part " << c["part"] << ": " << c["subregions"] << " subregion(s) kept of " << part.size()
                    << " candidates (scaled Jacobian min " << c["min_scaled_jacobian"] << ")\n";
      } else if (explicit_parts && c.contains("error") && c["subregions"].get<int>() == args.options.parts) {
        std::cerr << "warning: part " << c["part"] << " meshed as one poly-square: " << c["error"].get<std::string>() << "\n";
      }
    }
  }
  if (!args.quiet)
    std::cout << "polysquare: " << result.mesh.quads.size() << " quads, " << result.mesh.nodes.size() << " nodes -> "
            << args.output << "\n"
            << group_summary << format_quality_text(quality, &domain)
            << (simplified ? "  against the simplified curves the mesh follows: boundary distance max " +
                                 short_number(simplified->boundary_max_distance) + ", feature distance to mesh edges max " +
                                 short_number(simplified->feature_max_distance) + ", feature nodes off curves max " +
                                 short_number(simplified->feature_node_max_distance) + "\n"
                           : std::string())
            << format_finite_volume_text(fv) << format_schism_text(quality.schism)
            << (result.report["summary"].value("sj_below_0_3_pinned", std::size_t{0}) > 0
                    ? "  of the quads below scaled Jacobian 0.3, " + result.report["summary"]["sj_below_0_3_pinned"].dump() +
                          " lie in input corners or wedges sharper than 17.5 degrees; the others are a fraction " +
                          short_number(result.report["summary"]["sj_below_0_3_unpinned_fraction"].get<double>()) + "\n"
                    : std::string());
  return 0;
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

int run_quality(const std::string& mesh_path, const std::string& domain_path, bool json, bool require_quads) {
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
  if (!domain_path.empty()) domain = domain_distance(mesh, read_region(domain_path));
  // Quads that overlap pass every shape figure (each quad alone is fine): the mesh is judged, then refused.
  const QuadOverlaps overlaps = find_overlapping_quads(mesh);
  if (json) {
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

}  // namespace

int main(int argc, char** argv) {
  // Under mpirun every process runs this same command; the driver starts MPI (else it does nothing).
  const MpiDriver mpi(argc, argv);
  if (mpi.rank() != 0) std::cerr.rdbuf(nullptr);  // rank 0 speaks for all: they meet the same warnings
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  spdlog::set_level(spdlog::level::warn);

  CLI::App app{"polysquare: feature-aligned semi-structured quad meshes of 2D regions"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("polysquare ") + library_version() +
                                        (MpiDriver::built_with_mpi() ? " (mpirun -np P: Open MPI)" : " (one process: built without MPI)"));

  MeshArgs mesh;
  auto* cmd_mesh = app.add_subcommand("mesh", "mesh a region (GeoJSON) into all quadrilaterals");
  cmd_mesh->add_option("input", mesh.input,
                       "input region: GeoJSON, or any vector dataset GDAL reads (.shp, .gpkg, .kml, .gml, .dxf, .fgb); "
                       "every layer, roles from a 'role' attribute or the geometry type")->required();
  cmd_mesh->add_option("--features", mesh.input_options.feature_files,
                       "more vector datasets whose layers are feature curves (repeatable)");
  cmd_mesh->add_option("--boundary", mesh.input_options.boundary_files,
                       "vector datasets whose lines lie on the domain boundary and split it into named segments "
                       "(attributes 'name', 'kind': open, land, ...; repeatable)");
  cmd_mesh->add_option("--domain-layer", mesh.input_options.domain_layer,
                       "the input layer that is the domain (the other layers give features)");
  cmd_mesh->add_option("--feature-layer", mesh.input_options.feature_layers,
                       "a layer that gives feature curves (repeatable; other feature layers are then skipped)");
  cmd_mesh->add_option("--where", mesh.input_options.where, "OGR SQL attribute filter applied to every layer read");
  cmd_mesh->add_option("--crs", mesh.input_options.crs,
                       "projected CRS to mesh geographic input in, e.g. EPSG:32615 (default: UTM zone of the centre)");
  cmd_mesh->add_option("--size", mesh.options.size, "target quad edge length h, in region units (metres for geographic input)")->required();
  cmd_mesh->add_option("-o,--output", mesh.output, "output mesh (.msh Gmsh, .vtu VTK, .pvtu VTK in pieces, .gr3 SCHISM hgrid, .nc D-Flow FM UGRID net file, .2dm SMS, .exo Exodus II)")->required();
  cmd_mesh->add_option("--depth", mesh.depth,
                       "constant water depth, positive down, for .gr3 (depth column), .nc (mesh2d_node_z = -depth) "
                       "and .2dm files");
  cmd_mesh->add_option("--bathymetry", mesh.bathymetry,
                       "raster GDAL reads (GeoTIFF, netCDF, ASCII grid, ...) sampled bilinearly at the nodes, in the "
                       "raster's CRS, for the depths of .gr3, .nc and .2dm files");
  cmd_mesh->add_option("--bathymetry-positive", mesh.bathymetry_positive,
                       "up: the raster holds elevations (depth = -value, as GEBCO and DEMs); down: it holds depths")
      ->check(CLI::IsMember({"up", "down"}))->capture_default_str();
  cmd_mesh->add_option("--report", mesh.report, "write a JSON report (options, timings, counts, quality)");
  cmd_mesh->add_option("--picture", mesh.picture,
                       "write a picture of the mesh coloured by scaled Jacobian: .png, or .svg for small meshes");
  cmd_mesh->add_option("--parts", mesh.options.parts,
                       "subregions per polygon part (1 = one poly-square per part, 0 = try several counts and keep the best mesh)")
      ->capture_default_str()->check(CLI::NonNegativeNumber);
  cmd_mesh->add_option("--split-rounds", mesh.options.map.split_rounds,
                       "times a subregion whose map fails alone is split into smaller ones before meshing (0 = patch it)")
      ->capture_default_str()->check(CLI::Range(0, 8));
  cmd_mesh->add_option("--agree-turns", mesh.options.map.layout.agree_turn_elements,
                       "PPM: where a feature between two subregions turns on one side only, turn one side's labels a "
                       "quarter over stretches of at most this many elements so both sides agree (0 = off)")
      ->capture_default_str();
  cmd_mesh->add_option("--multipass", mesh.options.map.multipass.max_passes,
                       "PPM: deform the subregions together in at most this many passes over charts with buffer zones "
                       "(the paper's Algorithm 1) instead of each alone (0)")
      ->capture_default_str()->check(CLI::Range(0, 100));
  cmd_mesh->add_option("--map", mesh.map,
                       "how subregions are mapped: ppm (a poly-square per subregion, singularities where they meet) or "
                       "gpm (one global poly-square, separators as its sides)")
      ->check(CLI::IsMember({"ppm", "gpm"}))->capture_default_str();
  cmd_mesh->add_option("--partition-picture", mesh.partition_picture,
                       "write an SVG of the background triangulation coloured by subregion, separators and features");
  cmd_mesh->add_option("--threads", mesh.options.threads, "worker threads (0 = all cores); output does not depend on it")
      ->check(CLI::NonNegativeNumber);
  cmd_mesh->add_option("--seed", mesh.options.seed, "seed of randomized stages");
  cmd_mesh->add_flag("--bend-interfaces", mesh.bend_interfaces,
                     "PPM: let interfaces between subregions bend (both sides share every break point) instead of "
                     "keeping each one straight");
  cmd_mesh->add_option("--corner-angle", mesh.options.corner_threshold_deg,
                       "input vertices turning by more than this (degrees) become mesh nodes")
      ->capture_default_str();
  cmd_mesh->add_option("--simplify", mesh.options.simplify,
                       "simplify curves finer than the size first: drop vertices whose triangle area < (F*size)^2, each within size of the result (0 = off: the mesh follows every input vertex)")
      ->capture_default_str();
  cmd_mesh->add_option("--smooth-curves", mesh.options.smooth_curves,
                       "with --simplify: smooth stretches of curve finer than the size first, each vertex within F*size of the input, so that digitisation steps are not corners (0 = off)")
      ->capture_default_str();
  cmd_mesh->add_option("--min-island-width", mesh.options.min_island_width,
                       "with --simplify: leave out (and report) holes, closed feature curves and feature pieces around regions narrower than F*size (0 keeps them)")
      ->capture_default_str();
  cmd_mesh->add_option("--max-quads", mesh.options.max_quads, "refuse sizes that need more quads than this")
      ->check(CLI::PositiveNumber)->capture_default_str();  // "-5" would otherwise wrap around to 2^64 - 5
  cmd_mesh->add_option("--min-sj", mesh.options.min_scaled_jacobian,
                       "refuse a mesh with quads whose scaled Jacobian is below this (see --max-poor-fraction; 0 accepts any valid mesh)")
      ->capture_default_str();
  cmd_mesh->add_option("--max-edge-ratio", mesh.options.max_edge_ratio,
                       "refuse a mesh with quads whose longest / shortest edge exceeds this (see --max-poor-fraction)")->capture_default_str();
  cmd_mesh->add_option("--max-poor-fraction", mesh.options.max_poor_fraction,
                       "accept (and report) a mesh whose quads outside --min-sj or --max-edge-ratio, after local repair, are at most this fraction of a part's quads (0 = every quad must pass)")
      ->capture_default_str();
  cmd_mesh->add_option("--boundary-weight", mesh.options.map.deform.boundary_weight,
                       "lambda of the boundary alignment term (paper eq. 9)")->capture_default_str();
  cmd_mesh->add_option("--feature-weight", mesh.options.map.deform.feature_weight,
                       "weight of the feature alignment term (paper eq. 10)")->capture_default_str();
  cmd_mesh->add_option("--flat-corner-angle", mesh.options.refine.flat_corner_deg,
                       "collapse the quad at a boundary node whose single corner there is flatter than this (degrees), "
                       "leaving an interior valence-3 node; 180 = off")
      ->capture_default_str();
  cmd_mesh->add_option("--loop-corner-angle", mesh.options.refine.loop_corner_deg,
                       "add a layer of quads inside a closed feature curve whose single corner there is flatter than "
                       "this (degrees), leaving eight singular nodes; 180 = off")
      ->capture_default_str();
  cmd_mesh->add_option("--feature-tolerance", mesh.options.feature_tolerance,
                       "largest distance between a feature curve and the mesh edges along it, as a fraction of the size (0 = unbounded)")
      ->capture_default_str();
  cmd_mesh->add_flag("--binary", mesh.binary, "write binary MSH");
  cmd_mesh->add_option("--pieces", mesh.pieces,
                       "with -o X.pvtu: the number of .vtu pieces X_<k>.vtu (the quads in subregion order, in runs of "
                       "equal length), written in parallel (0 = one per million quads)")
      ->check(CLI::Range(std::size_t{0}, std::size_t{4096}))->capture_default_str();
  cmd_mesh->add_option("--msh-version", mesh.msh_version,
                       "MSH version: 2.2 (read by Gmsh, meshio, deal.II, MFEM, MOOSE, DUNE) or 4.1 (Gmsh's current; "
                       "not MFEM or DUNE)")
      ->check(CLI::IsMember({"2.2", "4.1"}))->capture_default_str();
  cmd_mesh->add_option("--msh-features", mesh.msh_features,
                       "feature curves in MSH: nodes (a physical point group per curve; every reader takes the file), "
                       "lines (physical curves of line elements; deal.II refuses them) or none")
      ->check(CLI::IsMember({"nodes", "lines", "none"}))->capture_default_str();
  cmd_mesh->add_option("--time-limit", mesh.time_limit,
                       "seconds of wall time the run may take (reading, meshing, checks; not writing) before it ends "
                       "in exit 3 naming the stage it was in, with nothing written (0 = no limit)")
      ->capture_default_str();
  cmd_mesh->add_option("--read-time-limit", mesh.read_time_limit,
                       "seconds reading the input may take before the run ends in exit 3 (a reader stuck in a "
                       "malformed file: GDAL 3.6's DXF driver can loop for ever; 0 = no limit)")
      ->capture_default_str();
  cmd_mesh->add_flag("-q,--quiet", mesh.quiet, "print errors and warnings only (no progress, no summary)");
  cmd_mesh->add_flag("-v,--verbose", mesh.verbose, "print each stage's wall time as it finishes (on stderr)");
  cmd_mesh->add_flag("--repair", mesh.input_options.repair,
                     "drop repeated points and clip features crossing holes instead of refusing the input (reported)");

  std::string quality_mesh, quality_domain;
  bool quality_json = false, quality_require_quads = false;
  auto* cmd_quality = app.add_subcommand("quality", "report the quality of a mesh (MSH 2.2/4.1, VTU)");
  cmd_quality->add_option("mesh", quality_mesh, "mesh file")->required();
  cmd_quality->add_option("--domain", quality_domain, "input region, to measure boundary and feature distances");
  cmd_quality->add_flag("--json", quality_json, "print JSON");
  cmd_quality->add_flag("--require-quads", quality_require_quads, "exit 2 if the mesh has triangles");

  RenderArgs render;
  auto* cmd_render = app.add_subcommand("render", "draw a mesh (MSH, VTU) as a PNG or SVG picture");
  cmd_render->add_option("mesh", render.mesh, "mesh file")->required();
  cmd_render->add_option("-o,--output", render.output, "picture: .png (any size) or .svg (small meshes)")->required();
  cmd_render->add_option("--color", render.color,
                         "quad colours: sj (scaled Jacobian), skew, part (subregion) or singularities (plain, valence "
                         "marks only)")
      ->check(CLI::IsMember({"sj", "skew", "part", "singularities"}))->capture_default_str();
  cmd_render->add_option("--window", render.window, "x0,y0,x1,y1: the part of the plane to draw (mesh units)");
  cmd_render->add_option("--width", render.width, "picture width in pixels, colour bar included")
      ->check(CLI::Range(300, 16000))->capture_default_str();
  cmd_render->add_option("--domain", render.domain, "input region to draw under the mesh (thin dashed lines)");

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
    if (*cmd_mesh) return run_mesh(mesh);
    if (*cmd_render) return run_render(render);
    if (*cmd_quality) return run_quality(quality_mesh, quality_domain, quality_json, quality_require_quads);
  } catch (const InputError& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 2;
  } catch (const MeshingError& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 3;
  } catch (const std::exception& e) {
    // Not an error every process meets alike (those are InputError and MeshingError): the others may be waiting
    // for this one, so it is printed by whichever process met it and ends the whole job.
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
  return 1;
}
