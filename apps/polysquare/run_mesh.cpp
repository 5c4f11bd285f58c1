// `polysquare mesh`: checks the arguments, reads the input, meshes it (in a local frame far from the origin),
// measures the mesh, writes every output at once, then says what was left out, patched or refused.
#include <algorithm>
#include <cmath>
#include <limits>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <sstream>

#include <spdlog/spdlog.h>

#include "mesh_command.h"
#include "polysquare/core/error.h"
#include "polysquare/core/place_text.h"
#include "polysquare/input/project_region.h"
#include "polysquare/io/atomic_file.h"
#include "polysquare/io/bathymetry.h"
#include "polysquare/io/render_size_field.h"
#include "polysquare/io/mesh_groups.h"
#include "polysquare/io/mesh_io.h"
#include "polysquare/io/render.h"
#include "polysquare/io/solver_files.h"
#include "polysquare/io/svg.h"
#include "polysquare/partition/partition.h"
#include "polysquare/pipeline/check_options.h"
#include "polysquare/size/size_field.h"
#include "polysquare/pipeline/invariants.h"
#include "polysquare/pipeline/local_frame.h"
#include "polysquare/pipeline/report.h"
#include "polysquare/quality/quality.h"
#include "terminal_progress.h"
#include "time_limit.h"

namespace polysquare::cli {
namespace {

namespace fs = std::filesystem;

// --picture: PNG, or SVG when the mesh is small enough for one (else a PNG beside it, with a warning); coloured
// by --picture-color, `field` the graded run's size field (nullptr for a uniform run).
void write_picture(const MeshArgs& args, const QuadMesh& mesh, const Region& region, const SizeField* field) {
  const fs::path picture = args.picture;
  RenderOptions ro;
  ro.color = parse_render_color(args.picture_color);
  ro.size_field = field;
  fs::path to = picture;
  if (lower_extension(picture) == ".svg" && mesh.quads.size() > ro.svg_max_quads) {
    to.replace_extension(".png");
    std::cerr << "warning: " << mesh.quads.size() << " quads are too many for an SVG picture (limit "
              << ro.svg_max_quads << "); wrote " << to.string() << " instead\n";
  }
  render_mesh(to, mesh, &region, ro);
}

// What reading the input says about the files the run writes: its CRS (a .gr3 of geographic input gets a .ll),
// its open boundary segments (a .nc gets a .pli for each) and the quads it needs (a .pvtu's pieces).
struct InputFacts {
  std::string input_crs;
  std::vector<std::string> open_segments;
  double estimated_quads = 0.0;
};

// Every file the run may write, and every file it reads, checked before any work: format, directory, writability,
// name lengths, and none the same file as another output or an input (weakly canonical paths, links). Companions
// included: the PNG a too-large SVG picture becomes, a .pvtu's pieces, and, once the input is read (facts), a
// .gr3's .ll and a .nc's .pli files. Called before reading (facts nullptr: a refusal takes milliseconds) and
// after (facts given), both before meshing, so that nothing is refused after minutes of work or half written.
void check_outputs(const MeshArgs& args, const InputFacts* facts) {
  check_output_path(args.output);
  std::vector<std::pair<fs::path, std::string>> outputs{{args.output, "-o"}}, inputs{{args.input, "input"}};
  auto add = [&](const fs::path& path, const std::string& what, std::vector<std::string> extensions) {
    check_output_file(path, what, extensions);
    outputs.push_back({path, what});
  };
  if (facts)
    for (const CompanionFile& c : companion_files(args.output, facts->input_crs, facts->open_segments))
      add(c.path, c.what + " (" + args.output + ")", {});
  // A .pvtu's pieces: those asked for, or as many as the estimate (or the processes) will make; any others are
  // checked when they are written, before anything is committed.
  if (lower_extension(args.output) == ".pvtu") {
    double pieces = static_cast<double>(std::max<std::size_t>(args.pieces, 1));
    if (args.pieces == 0 && facts) pieces = std::max(pieces, std::ceil(1.5 * facts->estimated_quads / 1e6));
    if (args.pieces == 0 && args.mpi) pieces = std::max(pieces, static_cast<double>(args.mpi->processes()));
    for (std::size_t k = 0; k < static_cast<std::size_t>(std::min(pieces, 4096.0)); ++k)
      add(pvtu_piece_path(args.output, k), "a piece of -o", {".vtu"});
  }
  if (!args.report.empty()) add(args.report, "--report", {".json"});
  if (!args.picture.empty()) {
    add(args.picture, "--picture", {".png", ".svg"});
    if (lower_extension(args.picture) == ".svg")
      add(fs::path(args.picture).replace_extension(".png"),
          "--picture's PNG (written instead of the SVG when the mesh has more than " +
              std::to_string(RenderOptions().svg_max_quads) + " quads)",
          {".png"});
  }
  if (!args.partition_picture.empty()) add(args.partition_picture, "--partition-picture", {".svg"});
  if (!args.size_picture.empty()) add(args.size_picture, "--size-picture", {".png"});
  if (!args.size_picture.empty() && !args.options.size.graded())
    throw InputError("--size-picture draws a graded run's size field: give --size-min and --size-max");
  if (args.picture_color == "size" && !args.options.size.graded())
    throw InputError("--picture-color size colours the quads by a graded run's size field: give --size-min and "
                     "--size-max");
  if (!args.size_raster.empty()) inputs.push_back({args.size_raster, "--size-field raster"});
  for (const auto& f : args.input_options.feature_files) inputs.push_back({f, "--features file"});
  for (const auto& f : args.input_options.boundary_files) inputs.push_back({f, "--boundary file"});
  if (!args.bathymetry.empty()) inputs.push_back({args.bathymetry, "--bathymetry raster"});
  check_distinct_files(outputs, inputs);
}

// What can be refused before minutes of meshing: options, limits, outputs, depths.
void check_mesh_args(const MeshArgs& args) {
  if (!(args.options.size.h > 0.0) && !args.options.size.graded())
    throw InputError("--size is required: the quad edge length (or --size-min and --size-max for a graded mesh)");
  check_mesh_options(args.options);
  if (args.depth_given && !std::isfinite(args.depth))
    throw InputError("--depth must be a finite number, got " + short_number(args.depth));
  if (!(std::isfinite(args.time_limit) && args.time_limit >= 0))
    throw InputError("--time-limit must be a finite number of seconds >= 0 (0 = none), got " + short_number(args.time_limit));
  if (!(std::isfinite(args.read_time_limit) && args.read_time_limit >= 0))
    throw InputError("--read-time-limit must be a finite number of seconds >= 0 (0 = none), got " +
                     short_number(args.read_time_limit));
  check_outputs(args, nullptr);  // before reading, let alone meshing
  const std::string out_ext = lower_extension(args.output);
  if (args.pieces > 0 && out_ext != ".pvtu")
    throw InputError("--pieces writes a parallel VTK file: -o must end in .pvtu, not " + args.output);
  if ((args.depth_given || !args.bathymetry.empty()) && (out_ext == ".msh" || out_ext == ".vtu" || out_ext == ".pvtu"))
    std::cerr << "warning: depths are written to .gr3, .nc and .2dm files only, not to " << args.output << "\n";
  if (args.depth_given && !args.bathymetry.empty()) throw InputError("--depth and --bathymetry exclude each other");
  if (!args.bathymetry.empty() && !fs::is_regular_file(args.bathymetry))
    throw InputError(args.bathymetry + ": the bathymetry raster does not exist");
  if ((!args.size_raster.empty() || args.per_wavelength != 0.0) && !args.options.size.graded())
    throw InputError("--size-field and --per-wavelength grade the mesh: give --size-min and --size-max too");
  if (!args.size_raster.empty() && !fs::is_regular_file(args.size_raster))
    throw InputError(args.size_raster + ": the --size-field raster does not exist");
  if (!(std::isfinite(args.per_wavelength) && args.per_wavelength >= 0))
    throw InputError("--per-wavelength must be a finite number of quads >= 0 (0 = off), got " +
                     short_number(args.per_wavelength));
  if (args.per_wavelength > 0 && args.bathymetry.empty())
    throw InputError("--per-wavelength needs the depths: give --bathymetry RASTER");
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

// Reads the input and says what reading it changed: of each kind of note the first few, then one line with the
// count (all of them are in the report).
Region read_noted_input(const MeshArgs& args, ProgressReporter& progress, InputNotes& notes, std::ostream& info) {
  progress.start("read input");
  Region region = read_input(args.input, args.input_options, notes);
  progress.finish("read input");
  auto summarise = [](const std::vector<std::string>& lines, const char* prefix, const char* what) {
    for (std::size_t i = 0; i < lines.size() && i < 5; ++i) std::cerr << "warning: " << prefix << lines[i] << "\n";
    if (lines.size() > 5) std::cerr << "warning: ... and " << lines.size() - 5 << " more " << what << " (see the report)\n";
  };
  summarise(notes.repairs, "repaired: ", "repairs");
  summarise(notes.warnings, "", "input warnings");
  summarise(notes.snaps, "", "snapped points");
  if (notes.reprojected) info << "input in " << notes.input_crs << ", meshed in " << region.crs << " (--size in metres)\n";
  return region;
}

// The rasters, opened and checked against the region before meshing (readable, placed by a CRS, covering the
// domain), their warnings said.
void check_rasters(const MeshArgs& args, const Region& region, const InputNotes& notes) {
  std::vector<Vec2> domain;
  for (const Ring& r : region.rings) domain.insert(domain.end(), r.points.begin(), r.points.end());
  std::vector<std::string> warnings;
  if (!args.bathymetry.empty())
    warnings = check_bathymetry(args.bathymetry, domain, region.crs, notes.input_crs, {args.bathymetry_positive == "down"});
  if (!args.size_raster.empty()) {
    const std::vector<std::string> more = check_bathymetry(args.size_raster, domain, region.crs, notes.input_crs, {true});
    warnings.insert(warnings.end(), more.begin(), more.end());
  }
  for (const std::string& w : warnings) std::cerr << "warning: " << w << "\n";
}

// The sampled terms of a graded run's field, for points of a frame whose origin is `origin` in the input's
// coordinates (crs): --size-field's sizes, and --per-wavelength's N quads per M2 wavelength where the water is
// deeper than zero (44,712 s is the M2 period; lambda = T sqrt(g depth), OceanMesh2D's `wl` term).
std::vector<SizeTerm> raster_terms(const MeshArgs& args, const std::string& crs, Vec2 origin) {
  std::vector<SizeTerm> terms;
  auto in_input = [origin](std::vector<Vec2> p) {
    for (Vec2& q : p) q = q + origin;
    return p;
  };
  if (!args.size_raster.empty())
    terms.push_back({"--size-field " + args.size_raster, [=, &args](const std::vector<Vec2>& p) {
                       return sample_bathymetry(args.size_raster, in_input(p), crs, {true});  // values as they are
                     }});
  if (args.per_wavelength > 0)
    terms.push_back({"--per-wavelength with " + args.bathymetry, [=, &args](const std::vector<Vec2>& p) {
                       std::vector<double> h = sample_bathymetry(args.bathymetry, in_input(p), crs,
                                                                 {args.bathymetry_positive == "down"});
                       for (double& d : h)
                         d = d > 0.0 ? 44712.0 * std::sqrt(9.81 * d) / args.per_wavelength
                                     : std::numeric_limits<double>::infinity();
                       return h;
                     }});
  return terms;
}

// A graded run's estimate, from its field on the input curves (mesh_region builds it again on the simplified
// ones): refused past --max-quads before any meshing.
double say_field_estimate(std::ostream& info, const Region& region, const MeshOptions& options,
                          const SizeFieldResult& made) {
  check_field_estimate(made.stats.estimated_quads, options, region.source.empty() ? "region" : region.source);
  const double area = domain_area(region), h = options.size.field.size_min;
  info << "size field " << short_number(made.stats.min) << " .. " << short_number(made.stats.max) << ", grade "
       << short_number(options.size.field.grade) << ": about "
       << static_cast<long long>(std::llround(made.stats.estimated_quads))
       << " quads (integral of 1 / h^2; uniform at --size-min: " << static_cast<long long>(std::llround(area / (h * h)))
       << ")\n";
  for (const std::string& w : made.warnings) std::cerr << "warning: " << w << "\n";
  return made.stats.estimated_quads;
}

// The figure to choose --size from, before minutes of meshing: quads of size h cover about area / h^2. Returns
// the estimate.
double say_size_estimate(std::ostream& info, const Region& region, const MeshOptions& options,
                       const std::optional<SizeFieldResult>& field) {
  if (field) return say_field_estimate(info, region, options, *field);
  if (has_size_attributes(region))
    std::cerr << "warning: the input's size attributes are followed by graded runs only: give --size-min and "
                 "--size-max (instead of --size) to follow them\n";
  const double size = options.size.h;
  const Box2 box = region.bounding_box();
  const double area = domain_area(region);
  info << "region " << short_number(box.hi.x - box.lo.x) << " x " << short_number(box.hi.y - box.lo.y)
       << ", area " << short_number(area) << ": --size " << short_number(size) << " gives about "
       << static_cast<long long>(std::llround(area / (size * size)))
       << " quads (area / size^2; half the size, four times as many)\n";
  return area / (size * size);
}

// Far from the origin (1e8 .. 1e11 around a small domain) the region is meshed in a local frame and the mesh
// moved back before writing; figures are measured in the local frame, places printed in the input's: with the
// origin added, and in lon/lat when the input was (the user's file holds no UTM metres). Places are converted
// here, on the thread that prints, not where the library writes them: its stages run on worker threads, where
// no ScopedPlaceText is installed.
struct LocalFrame {
  Vec2 origin{0, 0};
  bool moved = false;
  Region region;  ///< the input region in the frame
  std::unique_ptr<PlaceTextHook> input_places;  ///< reprojected input: writes a place in its own CRS; else nullptr

  /// A place in the meshed CRS (the origin added) as printed.
  std::string input_place(Vec2 p) const {
    return input_places ? input_places->text(p) : "(" + short_number(p.x) + ", " + short_number(p.y) + ")";
  }
  /// The same, for a message that writes places its own way (`plain`) when the input was not reprojected.
  std::string input_place_or(Vec2 p, std::string (*plain)(Vec2)) const { return input_places ? input_place(p) : plain(p); }
  /// A place of the report (local frame) as printed.
  std::string place(Vec2 at) const { return input_place(at + origin); }
  /// The library's text about the local frame (an error, a reason) with its places as printed; as it is when the
  /// input was not reprojected.
  std::string local_text(const std::string& text) const { return in_input(text, origin); }
  /// The same for a text whose places have the origin added already.
  std::string input_text(const std::string& text) const { return in_input(text, {0, 0}); }
  /// What the quality summaries write places with: input_place, or their own format (empty) for input not reprojected.
  PlaceWriter place_writer() const {
    if (!input_places) return {};
    return [this](Vec2 p) { return input_place(p); };
  }

 private:
  std::string in_input(const std::string& text, Vec2 shift) const {
    if (!input_places) return text;
    return rewrite_places(text, [&](Vec2 p) { return input_place(p + shift); });
  }
};

LocalFrame local_frame(const Region& region, const InputNotes& notes) {
  LocalFrame frame;
  frame.origin = local_origin(region);
  frame.moved = frame.origin.x != 0 || frame.origin.y != 0;
  frame.region = region;
  frame.input_places = input_place_text(region, notes);
  if (frame.moved) {
    const Vec2 origin = frame.origin;
    translate(frame.region, {-origin.x, -origin.y});
    std::cerr << "meshed relative to " << frame.input_place(origin) << ", "
              << short_number(std::max(std::abs(origin.x), std::abs(origin.y)) / region.bounding_box().diagonal())
              << " times the domain's size away from the origin; written back in the input's coordinates\n";
  }
  return frame;
}

// Runs `step`; the places of an InputError or MeshingError it throws are printed as the frame prints them
// (`in_frame`: they are in the local frame, else the origin is added already).
template <class Step>
auto with_input_places(const LocalFrame& frame, bool in_frame, Step&& step) {
  auto text = [&](const std::exception& e) { return in_frame ? frame.local_text(e.what()) : frame.input_text(e.what()); };
  try {
    return step();
  } catch (const MeshingError& e) {
    if (!frame.input_places) throw;
    throw MeshingError(text(e));
  } catch (const InputError& e) {
    if (!frame.input_places) throw;
    throw InputError(text(e));
  }
}

// The options the flags give indirectly: map composition and interfaces, partition kept for its picture, progress,
// processes.
void set_derived_options(MeshOptions& options, const MeshArgs& args, ProgressCallback progress) {
  options.run.keep_partition = !args.partition_picture.empty();
  options.map.composition = args.map == "gpm" ? MapComposition::gpm : MapComposition::ppm;
  options.map.layout.straight_interfaces = !args.bend_interfaces;
  options.run.progress = std::move(progress);
  if (args.mpi && args.mpi->active()) {
    // The processes of one machine share its cores (0 = all cores between them).
    options.map.sharing = args.mpi->sharing();
    if (options.run.threads == 0) options.run.threads = args.mpi->threads_per_process();
  }
}

// Meshes the region in its frame; a failure's places are then relative to the frame's origin, which it says.
MeshResult mesh_in_frame(const LocalFrame& frame, const MeshOptions& options) {
  MeshResult result;
  try {
    result = with_input_places(frame, true, [&] { return mesh_region(frame.region, options); });
  } catch (const MeshingError& e) {
    if (!frame.moved || frame.input_places) throw;  // reprojected: its places were written back in the input's CRS
    throw MeshingError(std::string(e.what()) + " (places relative to (" + short_number(frame.origin.x) + ", " +
                       short_number(frame.origin.y) + "))");
  }
  if (frame.moved) result.report.input.local_origin = frame.origin;
  return result;
}

// How a .pvtu is cut: the pieces, and whether each process writes its share of them.
struct PieceSplit {
  bool by_process = false;
  std::size_t pieces = 0;
};

// Every process holds the mesh; rank 0 measures and writes it, but for the pieces of a .pvtu, which each
// process writes its share of.
PieceSplit piece_split(const MeshArgs& args, const QuadMesh& mesh) {
  PieceSplit split;
  split.by_process = args.mpi && args.mpi->active() && lower_extension(args.output) == ".pvtu";
  split.pieces = args.pieces > 0 ? args.pieces
                                 : std::max<std::size_t>(pvtu_pieces(mesh, 0), split.by_process ? static_cast<std::size_t>(args.mpi->processes()) : 1);
  return split;
}

// A process other than rank 0: writes its share of a .pvtu's pieces, if any, and commits them when all did.
int write_share_of_pieces(const MeshArgs& args, MeshResult& result, Vec2 origin, const PieceSplit& split,
                          PieceAgreement& agreement) {
  if (!split.by_process) return 0;
  std::string failed;
  OutputBatch batch;
  try {
    translate(result.mesh, origin);
    MeshWriteOptions write;
    write.pieces = split.pieces;
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

// The mesh's figures, places in the input's frame.
struct MeshMeasures {
  QualityReport quality;
  FiniteVolumeQuality fv;
  DomainDistance domain;
  std::optional<DomainDistance> simplified;  ///< against the simplified curves, when simplifying changed them
};

MeshMeasures measure_mesh(const MeshResult& result, const LocalFrame& frame, const MeshArgs& args) {
  const Vec2 origin = frame.origin;
  MeshMeasures m;
  m.quality = compute_quality(result.mesh);
  m.quality.schism.angle_ratio_worst_at = m.quality.schism.angle_ratio_worst_at + origin;
  m.quality.schism.aspect_ratio_worst_at = m.quality.schism.aspect_ratio_worst_at + origin;
  DomainDistanceOptions measure{args.options.curves.corner_threshold_deg, {}};
  for (const DroppedPartReport& d : result.report.dropped_parts) measure.skip_parts.push_back(d.part);
  // The mesh covers the (simplified) domain it conforms to, less the parts left out as too small, up to the
  // chords along curves: a larger change is said, never silent.
  if (const double change = area_relative_mismatch(result.mesh, result.region, measure.skip_parts);
      !(std::abs(change) <= 0.01))
    std::cerr << "warning: the mesh's area differs from the domain's by " << short_number(100 * change)
              << " % (more than 1 %: chords of coarse curves, or a region read wrongly)\n";
  m.domain = domain_distance(result.mesh, frame.region, measure);
  // Places in the input's frame, as every other place the CLI prints.
  auto to_input_frame = [&](DomainDistance& d) {
    d.feature_max_at = d.feature_max_at + origin;
    d.feature_node_max_at = d.feature_node_max_at + origin;
  };
  to_input_frame(m.domain);
  m.fv = finite_volume_quality(result.mesh);
  m.fv.orthogonality_worst_at = m.fv.orthogonality_worst_at + origin;
  m.fv.smoothness_worst_at = m.fv.smoothness_worst_at + origin;
  // Against the simplified curves too, which the mesh conforms to (the input distance includes the simplification).
  if (result.report.simplify.vertices_after != result.report.simplify.vertices_before ||
      !result.report.dropped_curves.empty()) {
    m.simplified = domain_distance(result.mesh, result.region, measure);
    to_input_frame(*m.simplified);
  }
  return m;
}

// The report's quality and input sections; the named groups (domains, ring pieces, features, boundary
// segments) from the region the mesh conforms to, their warnings said.
MeshGroups complete_report(MeshResult& result, const MeshMeasures& m, const InputNotes& notes, const Region& region,
                           const LocalFrame& frame, double size) {
  add_quality_to_report(result.report, m.quality, m.fv, m.domain, size, m.simplified ? &*m.simplified : nullptr);
  result.report.input.notes =
      InputNotesReport{notes.repairs, notes.snaps, notes.warnings, notes.input_crs, region.boundary_segments.size()};
  MeshGroups groups = mesh_groups(result.mesh, &result.region);
  result.report.groups = group_reports(groups);
  for (const std::string& w : groups.warnings) std::cerr << "warning: " << frame.local_text(w) << "\n";
  return groups;
}

// Moves the mesh back to the input's coordinates, where they may be too coarse for the size: a quad that folds
// there is refused.
void move_back(QuadMesh& mesh, const LocalFrame& frame, double size) {
  translate(mesh, frame.origin);
  if (const std::int64_t q = frame.moved ? first_folded_quad(mesh) : -1; q >= 0) {
    const auto& quad = mesh.quads[static_cast<std::size_t>(q)];
    throw MeshingError("written back in the input's coordinates, " + short_number(std::max(std::abs(frame.origin.x), std::abs(frame.origin.y))) +
                       " from the origin, quad " + std::to_string(q) + " at " + point_text(mesh.nodes[static_cast<std::size_t>(quad[0])]) +
                       " folds: coordinates there are too coarse for --size " + short_number(size) +
                       "; use a larger size or move the input nearer the origin");
  }
}

MeshWriteOptions write_options(const MeshArgs& args, const QuadMesh& mesh, const std::string& input_crs,
                               MeshGroups groups, const PieceSplit& split) {
  MeshWriteOptions write{args.binary,
                               args.msh_features == "lines" ? MshFeatures::lines
                               : args.msh_features == "none" ? MshFeatures::none : MshFeatures::nodes,
                               args.msh_version == "4.1" ? MshVersion::v4_1 : MshVersion::v2_2,
                               !args.bathymetry.empty()
                                   ? sample_bathymetry(args.bathymetry, mesh.nodes, mesh.crs,
                                                       {args.bathymetry_positive == "down"})
                               : args.depth_given ? std::vector<double>(mesh.nodes.size(), args.depth)
                                                  : std::vector<double>{},
                               input_crs,
                               std::move(groups)};
  write.pieces = split.pieces;
  if (split.by_process) write.piece_processes = static_cast<std::size_t>(args.mpi->processes());
  return write;
}

// Outputs are written only after the whole mesh passed its checks, and committed together: each goes to a
// synced temporary, and all are renamed onto their targets only when every one was written. `field`: a graded
// run's size field, in the input's coordinates (nullptr for a uniform run).
void write_outputs(const MeshArgs& args, const MeshResult& result, const Region& region,
                   const SizeFieldResult* field, const MeshWriteOptions& write, PieceAgreement& agreement) {
  OutputBatch batch;
  write_mesh(args.output, result.mesh, write);
  if (!args.report.empty())
    write_file_atomically(args.report, [&](std::ostream& os) { os << report_text(result.report); }, false);
  if (!args.picture.empty()) write_picture(args, result.mesh, region, field ? &field->field : nullptr);
  if (field && !args.size_picture.empty()) render_size_field(args.size_picture, field->field, field->inside, region);
  if (!args.partition_picture.empty()) {
    PartitionResult partition;
    partition.triangle_part = result.background_part;
    write_partition_svg(args.partition_picture, result.background, partition);
  }
  if (const std::string other = agreement.agree(""); !other.empty())
    throw InputError(args.output + ": a process could not write its pieces (" + other + ")");
  batch.commit();
}

// A figure printed as the report writes it (the shortest text that reads back the same), so that a message and
// the report agree to the digit.
std::string figure(double x) { return nlohmann::json(x).dump(); }

// Parts left out as smaller than one element: the first few by place, then one line for the rest; curves
// around regions narrower than the size, by kind.
void warn_left_out(const MeshReport& report, const LocalFrame& frame) {
  const std::vector<DroppedPartReport>& dropped = report.dropped_parts;
  for (std::size_t i = 0; i < dropped.size() && i < 3; ++i)
    std::cerr << "warning: part " << dropped[i].part << " left out: its area " << figure(dropped[i].area)
              << " is less than one element, at " << frame.place(dropped[i].at) << "\n";
  if (dropped.size() > 3) {
    double area = 0;
    for (const DroppedPartReport& d : dropped) area += d.area;
    std::cerr << "warning: " << dropped.size() << " parts smaller than one element left out in all (total area "
              << short_number(area) << "); the report's dropped_parts lists each\n";
  }
  if (const std::vector<DroppedCurveReport>& curves = report.dropped_curves; !curves.empty()) {
    std::map<std::string, std::size_t> kinds;
    const DroppedCurveReport* widest = &curves.front();
    for (const DroppedCurveReport& d : curves) {
      kinds[d.kind]++;
      if (d.width > widest->width) widest = &d;
    }
    std::cerr << "warning: " << curves.size() << " curves around regions narrower than the size left out (";
    for (const auto& [kind, n] : kinds) std::cerr << (kind == kinds.begin()->first ? "" : ", ") << n << " " << kind;
    std::cerr << "; the widest " << figure(widest->width) << " at " << frame.place(widest->at)
              << "; the report's dropped_curves lists them; --min-island-width 0 keeps them)\n";
  }
}

// Unstructured patches: the first few by place, then one line for the rest; then the simplification and the
// structured fraction.
void say_patches_and_simplification(const MeshReport& report, const LocalFrame& frame, std::ostream& info) {
  std::size_t patches = 0, patch_quads = 0;
  for (const UnstructuredReport& u : report.unstructured)
    if (u.meshed_by == "patch" && ++patches <= 5)
      std::cerr << "warning: part " << u.part << ": subregion " << u.subregion << " at " << frame.place(u.at)
                << " is an unstructured patch of " << u.quads << " quads: " << frame.local_text(u.reason.value_or("")) << "\n";
    else if (u.meshed_by == "patch")
      patch_quads += u.quads;
  if (patches > 5)
    std::cerr << "warning: ... and " << patches - 5 << " more unstructured patches (" << patch_quads
              << " quads; the report's unstructured lists each)\n";
  if (const SimplifyReport& simp = report.simplify; simp.vertices_after != simp.vertices_before)
    info << "simplified curves finer than the size: " << simp.vertices_before << " -> " << simp.vertices_after
         << " vertices, largest distance moved " << figure(simp.max_distance) << " ("
         << figure(simp.max_distance_over_size) << " of the size), area change " << figure(simp.area_change)
         << " (--simplify 0 keeps them)\n";
  info << "structured fraction " << figure(report.summary.structured_fraction) << " ("
       << report.summary.unstructured_subregions << " of " << report.summary.subregions << " subregions unstructured)\n";
}

// The warnings about one part's chosen candidate: quads pinned by sharp input corners, poor quads accepted, or
// the unstructured fallback.
void warn_chosen_candidate(const CandidateReport& c, std::size_t candidates, const LocalFrame& frame) {
  if (const std::optional<PinnedReport>& p = c.pinned)
    std::cerr << "warning: part " << c.part << ": " << p->quads_pinned_by_sharp_input
              << " quads lie in input corners sharper than the --min-sj gate and are left out of it (scaled "
                 "Jacobian min "
              << figure(p->pinned_min_scaled_jacobian) << " at " << frame.place(p->pinned_worst_at)
              << "; the others' min is " << figure(p->unpinned_min_scaled_jacobian) << ")\n";
  if (c.poor_quads) {
    const PoorQuadReport& first = c.poor_quads->first.at(0);
    std::cerr << "warning: part " << c.part << ": " << c.poor_quads->count
              << " quads stay outside --min-sj or --max-edge-ratio after local repair (within --max-poor-fraction); "
                 "the first at "
              << frame.place(first.at) << " (scaled Jacobian " << figure(first.scaled_jacobian) << ", edge ratio "
              << figure(first.edge_ratio) << "); the report's candidates list them\n";
  }
  if (c.fallback)  // a chosen candidate is measured
    std::cerr << "warning: part " << c.part << ": none of " << candidates - 1
              << " poly-square candidates meshed it; meshed unstructured by splitting triangles into quads ("
              << c.measures.value().interior_singularities << " interior singularities, scaled Jacobian min "
              << figure(c.measures.value().min_scaled_jacobian) << "); the report's candidates say why each failed\n";
}

// Which candidate each part kept, and why the explicitly requested one was not kept.
void say_candidates(const MeshReport& report, int requested_parts, const LocalFrame& frame, std::ostream& info) {
  for (const std::vector<CandidateReport>& part : report.candidates) {
    const bool explicit_parts = requested_parts > 0;
    for (const CandidateReport& c : part) {
      if (c.chosen) {
        warn_chosen_candidate(c, part.size(), frame);
        if (!c.fallback && part.size() > 1 && !explicit_parts)
          info << "part " << c.part << ": " << c.subregions << " subregion(s) kept of " << part.size()
               << " candidates (scaled Jacobian min " << figure(c.measures.value().min_scaled_jacobian) << ")\n";
      } else if (explicit_parts && c.error && c.subregions == requested_parts) {
        std::cerr << "warning: part " << c.part << " meshed as one poly-square: " << frame.local_text(*c.error) << "\n";
      }
    }
  }
}

// The summary on stdout: counts, groups, quality (against the simplified curves too), finite-volume figures.
void print_summary(const MeshResult& result, const MeshMeasures& m, const std::string& output,
                   const std::string& group_summary, const PlaceWriter& place) {
  std::cout << "polysquare: " << result.mesh.quads.size() << " quads, " << result.mesh.nodes.size() << " nodes -> "
            << output << "\n"
            << group_summary << format_quality_text(m.quality, &m.domain, place)
            << (m.simplified ? "  against the simplified curves the mesh follows: boundary distance max " +
                                   short_number(m.simplified->boundary_max_distance) + ", feature distance to mesh edges max " +
                                   short_number(m.simplified->feature_max_distance) + ", feature nodes off curves max " +
                                   short_number(m.simplified->feature_node_max_distance) + "\n"
                             : std::string())
            << format_finite_volume_text(m.fv, place) << format_schism_text(m.quality.schism, place)
            << (result.report.summary.sj_below_0_3_pinned > 0
                    ? "  of the quads below scaled Jacobian 0.3, " + std::to_string(result.report.summary.sj_below_0_3_pinned) +
                          " lie in input corners or wedges sharper than 17.5 degrees; the others are a fraction " +
                          short_number(result.report.summary.sj_below_0_3_unpinned_fraction) + "\n"
                    : std::string());
}

}  // namespace

namespace {

// The run after its arguments were checked; `estimated_quads` is set as soon as the input is read (for the
// out-of-memory message).
int mesh_checked(const MeshArgs& args, double& estimated_quads) {
  // Progress on a terminal (never in a pipe or under CI), stage timings with --verbose; quiet: warnings only.
  TerminalProgress shown(args.quiet ? Verbosity::quiet : args.verbose ? Verbosity::verbose : Verbosity::normal);
  if (args.verbose && !args.quiet) {  // the library's debug lines (its solvers' costliest calls), plain
    spdlog::set_pattern("%v");
    spdlog::set_level(spdlog::level::debug);
  }
  // Under mpirun every process keeps the time; rank 0 alone says it was spent.
  TimeLimit limit(args.time_limit, args.read_time_limit, args.input, shown.callback(),
                  !args.mpi || args.mpi->rank() == 0);
  ProgressReporter progress(limit.callback());
  std::ostringstream discarded;
  std::ostream& info = args.quiet ? discarded : std::cerr;
  InputNotes notes;
  const Region region = read_noted_input(args, progress, notes, info);
  check_rasters(args, region, notes);  // before minutes of meshing
  MeshOptions options = resolve_sizes(args.options);  // graded: size.h is the least size
  check_mesh_size(region, options);
  options.size.field.terms = raster_terms(args, region.crs, {0.0, 0.0});
  // A graded run's field on the input curves: its estimate now, its picture with the outputs (mesh_region builds
  // it again on the simplified curves, in its frame).
  const std::optional<SizeFieldResult> field =
      options.size.graded() ? std::optional(make_size_field(region, options.size.field)) : std::nullopt;
  estimated_quads = say_size_estimate(info, region, options, field);
  // The files the input decides (a .gr3's .ll, a .nc's .pli files, a .pvtu's pieces), before meshing.
  const InputFacts facts{notes.input_crs, open_segment_names(region), estimated_quads};
  check_outputs(args, &facts);
  const LocalFrame frame = local_frame(region, notes);
  options.size.field.terms = raster_terms(args, region.crs, frame.origin);
  set_derived_options(options, args, limit.callback());
  MeshResult result = mesh_in_frame(frame, options);
  const PieceSplit split = piece_split(args, result.mesh);
  PieceAgreement agreement(split.by_process ? args.mpi->sharing().get() : nullptr);
  if (args.mpi && args.mpi->rank() != 0) return write_share_of_pieces(args, result, frame.origin, split, agreement);
  if (args.mpi && args.mpi->active()) result.report.summary.processes = args.mpi->processes();

  progress.start("quality");
  const MeshMeasures measures = measure_mesh(result, frame, args);
  MeshGroups groups = complete_report(result, measures, notes, region, frame, options.size.h);
  const std::string group_summary = format_groups_text(groups);
  progress.finish("quality");

  limit.stop();  // the outputs are committed whole or not at all, never cut off between two renames
  progress.start("write");
  with_input_places(frame, false, [&] {
    move_back(result.mesh, frame, options.size.h);
    write_outputs(args, result, region, field ? &*field : nullptr,
                  write_options(args, result.mesh, notes.input_crs, std::move(groups), split), agreement);
  });
  progress.finish("write");

  if (lower_extension(args.output) == ".nc" && measures.fv.orthogonality_above > 0)
    std::cerr << "warning: " << measures.fv.orthogonality_above << " of " << measures.fv.interior_edges
              << " interior edges have a D-Flow FM orthogonality above " << measures.fv.orthogonality_limit
              << ", which D-Flow FM refuses; the worst, " << measures.fv.orthogonality.max << ", at "
              << frame.input_place_or(measures.fv.orthogonality_worst_at, at_text) << "\n";
  warn_left_out(result.report, frame);
  say_patches_and_simplification(result.report, frame, info);
  say_candidates(result.report, args.options.subregions.parts, frame, info);
  if (!args.quiet) print_summary(result, measures, args.output, group_summary, frame.place_writer());
  return 0;
}

}  // namespace

int run_mesh(const MeshArgs& args) {
  check_mesh_args(args);
  double estimated_quads = 0.0;
  try {
    return mesh_checked(args, estimated_quads);
  } catch (const std::bad_alloc&) {
    // Everything the run held is freed by now (the outputs' temporaries too: OutputBatch); say what it needed.
    std::string text = args.input + ": the run ran out of memory";
    if (estimated_quads > 0)
      text += " (about " + short_number(estimated_quads) + " quads estimated; a larger --size needs fewer, and "
              "--max-quads refuses such runs before meshing)";
    text += "; nothing written";
    throw OutOfMemory(text);
  }
}

}  // namespace polysquare::cli
