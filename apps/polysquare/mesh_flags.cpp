// The flags of `polysquare mesh`, by stage: each function below maps one stage's flags to the options structs
// (MeshArgs, InputOptions, MeshOptions). add_mesh_command adds them to the command in one fixed order, the order
// `polysquare mesh --help` has always listed them in (and in which CLI11 names the first missing required one).
#include <functional>
#include <initializer_list>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "mesh_command.h"

namespace polysquare::cli {
namespace {

// Flags defined in one place and added to a command in another order. Each flag keeps the CLI11 calls made on
// it (required, check, capture_default_str), applied in the order written.
class FlagTable {
 public:
  class Flag {
   public:
    Flag& required() {
      return then([](CLI::Option* o) { o->required(); });
    }
    Flag& check(const CLI::Validator& v) {
      return then([v](CLI::Option* o) { o->check(v); });
    }
    Flag& capture_default_str() {
      return then([](CLI::Option* o) { o->capture_default_str(); });
    }

   private:
    friend class FlagTable;
    Flag& then(std::function<void(CLI::Option*)> step) {
      steps_.push_back(std::move(step));
      return *this;
    }
    std::function<CLI::Option*(CLI::App&)> add_;
    std::vector<std::function<void(CLI::Option*)>> steps_;
  };

  template <class T>
  Flag& option(const std::string& names, T& target, const std::string& help) {
    return define(names, [names, &target, help](CLI::App& cmd) { return cmd.add_option(names, target, help); });
  }
  Flag& flag(const std::string& names, bool& target, const std::string& help) {
    return define(names, [names, &target, help](CLI::App& cmd) { return cmd.add_flag(names, target, help); });
  }

  /// Adds every flag to `cmd` in `order` (their names as defined); each flag must be named there exactly once.
  void add_to(CLI::App& cmd, std::initializer_list<const char*> order) {
    for (const char* names : order) {
      const auto it = flags_.find(names);
      if (it == flags_.end()) throw std::logic_error(std::string("mesh flag ordered but not defined: ") + names);
      CLI::Option* o = it->second.add_(cmd);
      for (const auto& step : it->second.steps_) step(o);
      flags_.erase(it);
    }
    if (!flags_.empty()) throw std::logic_error("mesh flag defined but not ordered: " + flags_.begin()->first);
  }

 private:
  Flag& define(const std::string& names, std::function<CLI::Option*(CLI::App&)> add) {
    const auto [it, inserted] = flags_.try_emplace(names);
    if (!inserted) throw std::logic_error("mesh flag defined twice: " + names);
    it->second.add_ = std::move(add);
    return it->second;
  }
  std::map<std::string, Flag> flags_;
};

// Reading the input: files, layers, filter, CRS, repairs.
void input_flags(FlagTable& t, MeshArgs& m) {
  t.option("input", m.input,
           "input region: GeoJSON, or any vector dataset GDAL reads (.shp, .gpkg, .kml, .gml, .dxf, .fgb); "
           "every layer, roles from a 'role' attribute or the geometry type")
      .required();
  t.option("--features", m.input_options.feature_files,
           "more vector datasets whose layers are feature curves (repeatable)");
  t.option("--boundary", m.input_options.boundary_files,
           "vector datasets whose lines lie on the domain boundary and split it into named segments "
           "(attributes 'name', 'kind': open, land, ...; repeatable)");
  t.option("--domain-layer", m.input_options.domain_layer,
           "the input layer that is the domain (the other layers give features)");
  t.option("--feature-layer", m.input_options.feature_layers,
           "a layer that gives feature curves (repeatable; other feature layers are then skipped)");
  t.option("--where", m.input_options.where, "OGR SQL attribute filter applied to every layer read");
  t.option("--crs", m.input_options.crs,
           "projected CRS to mesh geographic input in, e.g. EPSG:32615 (default: UTM zone of the centre)");
  t.flag("--repair", m.input_options.repair,
         "drop repeated points and clip features crossing holes instead of refusing the input (reported)");
}

// The curves the mesh follows: corners kept, simplification, smoothing, narrow islands.
void curve_flags(FlagTable& t, MeshArgs& m) {
  t.option("--corner-angle", m.options.corner_threshold_deg,
           "input vertices turning by more than this (degrees) become mesh nodes")
      .capture_default_str();
  t.option("--simplify", m.options.simplify,
           "simplify curves finer than the size first: drop vertices whose triangle area < (F*size)^2, each within size of the result (0 = off: the mesh follows every input vertex)")
      .capture_default_str();
  t.option("--smooth-curves", m.options.smooth_curves,
           "with --simplify: smooth stretches of curve finer than the size first, each vertex within F*size of the input, so that digitisation steps are not corners (0 = off)")
      .capture_default_str();
  t.option("--min-island-width", m.options.min_island_width,
           "with --simplify: leave out (and report) holes, closed feature curves and feature pieces around regions narrower than F*size (0 keeps them)")
      .capture_default_str();
}

void size_flags(FlagTable& t, MeshArgs& m) {
  t.option("--size", m.options.size, "target quad edge length h, in region units (metres for geographic input)")
      .required();
  t.option("--max-quads", m.options.max_quads, "refuse sizes that need more quads than this")
      .check(CLI::PositiveNumber)
      .capture_default_str();  // "-5" would otherwise wrap around to 2^64 - 5
}

void partition_flags(FlagTable& t, MeshArgs& m) {
  t.option("--parts", m.options.parts,
           "subregions per polygon part (1 = one poly-square per part, 0 = try several counts and keep the best mesh)")
      .capture_default_str()
      .check(CLI::NonNegativeNumber);
  t.option("--seed", m.options.seed, "seed of randomized stages");
}

// Mapping the subregions to poly-squares (deformation, layout, splits).
void map_flags(FlagTable& t, MeshArgs& m) {
  t.option("--map", m.map,
           "how subregions are mapped: ppm (a poly-square per subregion, singularities where they meet) or "
           "gpm (one global poly-square, separators as its sides)")
      .check(CLI::IsMember({"ppm", "gpm"}))
      .capture_default_str();
  t.option("--split-rounds", m.options.map.split_rounds,
           "times a subregion whose map fails alone is split into smaller ones before meshing (0 = patch it)")
      .capture_default_str()
      .check(CLI::Range(0, 8));
  t.option("--agree-turns", m.options.map.layout.agree_turn_elements,
           "PPM: where a feature between two subregions turns on one side only, turn one side's labels a "
           "quarter over stretches of at most this many elements so both sides agree (0 = off)")
      .capture_default_str();
  t.option("--multipass", m.options.map.multipass.max_passes,
           "PPM: deform the subregions together in at most this many passes over charts with buffer zones "
           "(the paper's Algorithm 1) instead of each alone (0)")
      .capture_default_str()
      .check(CLI::Range(0, 100));
  t.flag("--bend-interfaces", m.bend_interfaces,
         "PPM: let interfaces between subregions bend (both sides share every break point) instead of "
         "keeping each one straight");
  t.option("--boundary-weight", m.options.map.deform.boundary_weight,
           "lambda of the boundary alignment term (paper eq. 9)")
      .capture_default_str();
  t.option("--feature-weight", m.options.map.deform.feature_weight,
           "weight of the feature alignment term (paper eq. 10)")
      .capture_default_str();
}

// Templates at flat corners (refine) and smoothing along features.
void refine_and_smooth_flags(FlagTable& t, MeshArgs& m) {
  t.option("--flat-corner-angle", m.options.refine.flat_corner_deg,
           "collapse the quad at a boundary node whose single corner there is flatter than this (degrees), "
           "leaving an interior valence-3 node; 180 = off")
      .capture_default_str();
  t.option("--loop-corner-angle", m.options.refine.loop_corner_deg,
           "add a layer of quads inside a closed feature curve whose single corner there is flatter than "
           "this (degrees), leaving eight singular nodes; 180 = off")
      .capture_default_str();
  t.option("--feature-tolerance", m.options.feature_tolerance,
           "largest distance between a feature curve and the mesh edges along it, as a fraction of the size (0 = unbounded)")
      .capture_default_str();
}

// The quality gates a mesh must pass (after local repair).
void gate_flags(FlagTable& t, MeshArgs& m) {
  t.option("--min-sj", m.options.min_scaled_jacobian,
           "refuse a mesh with quads whose scaled Jacobian is below this (see --max-poor-fraction; 0 accepts any valid mesh)")
      .capture_default_str();
  t.option("--max-edge-ratio", m.options.max_edge_ratio,
           "refuse a mesh with quads whose longest / shortest edge exceeds this (see --max-poor-fraction)")
      .capture_default_str();
  t.option("--max-poor-fraction", m.options.max_poor_fraction,
           "accept (and report) a mesh whose quads outside --min-sj or --max-edge-ratio, after local repair, are at most this fraction of a part's quads (0 = every quad must pass)")
      .capture_default_str();
}

// The mesh file, its format's choices, and the other outputs (report, pictures).
void output_flags(FlagTable& t, MeshArgs& m) {
  t.option("-o,--output", m.output,
           "output mesh (.msh Gmsh, .vtu VTK, .pvtu VTK in pieces, .gr3 SCHISM hgrid, .nc D-Flow FM UGRID net file, .2dm SMS, .exo Exodus II)")
      .required();
  t.flag("--binary", m.binary, "write binary MSH");
  t.option("--pieces", m.pieces,
           "with -o X.pvtu: the number of .vtu pieces X_<k>.vtu (the quads in subregion order, in runs of "
           "equal length), written in parallel (0 = one per million quads)")
      .check(CLI::Range(std::size_t{0}, std::size_t{4096}))
      .capture_default_str();
  t.option("--msh-version", m.msh_version,
           "MSH version: 2.2 (read by Gmsh, meshio, deal.II, MFEM, MOOSE, DUNE) or 4.1 (Gmsh's current; "
           "not MFEM or DUNE)")
      .check(CLI::IsMember({"2.2", "4.1"}))
      .capture_default_str();
  t.option("--msh-features", m.msh_features,
           "feature curves in MSH: nodes (a physical point group per curve; every reader takes the file), "
           "lines (physical curves of line elements; deal.II refuses them) or none")
      .check(CLI::IsMember({"nodes", "lines", "none"}))
      .capture_default_str();
  t.option("--report", m.report, "write a JSON report (options, timings, counts, quality)");
  t.option("--picture", m.picture,
           "write a picture of the mesh coloured by scaled Jacobian: .png, or .svg for small meshes");
  t.option("--partition-picture", m.partition_picture,
           "write an SVG of the background triangulation coloured by subregion, separators and features");
}

// Depths of the solver files (.gr3, .nc, .2dm).
void depth_flags(FlagTable& t, MeshArgs& m) {
  t.option("--depth", m.depth,
           "constant water depth, positive down, for .gr3 (depth column), .nc (mesh2d_node_z = -depth) "
           "and .2dm files");
  t.option("--bathymetry", m.bathymetry,
           "raster GDAL reads (GeoTIFF, netCDF, ASCII grid, ...) sampled bilinearly at the nodes, in the "
           "raster's CRS, for the depths of .gr3, .nc and .2dm files");
  t.option("--bathymetry-positive", m.bathymetry_positive,
           "up: the raster holds elevations (depth = -value, as GEBCO and DEMs); down: it holds depths")
      .check(CLI::IsMember({"up", "down"}))
      .capture_default_str();
}

// How the run goes: threads, time limits, what it prints.
void run_flags(FlagTable& t, MeshArgs& m) {
  t.option("--threads", m.options.threads, "worker threads (0 = all cores); output does not depend on it")
      .check(CLI::NonNegativeNumber);
  t.option("--time-limit", m.time_limit,
           "seconds of wall time the run may take (reading, meshing, checks; not writing) before it ends "
           "in exit 3 naming the stage it was in, with nothing written (0 = no limit)")
      .capture_default_str();
  t.option("--read-time-limit", m.read_time_limit,
           "seconds reading the input may take before the run ends in exit 3 (a reader stuck in a "
           "malformed file: GDAL 3.6's DXF driver can loop for ever; 0 = no limit)")
      .capture_default_str();
  t.flag("-q,--quiet", m.quiet, "print errors and warnings only (no progress, no summary)");
  t.flag("-v,--verbose", m.verbose, "print each stage's wall time as it finishes (on stderr)");
}

}  // namespace

CLI::App* add_mesh_command(CLI::App& app, MeshArgs& args) {
  FlagTable t;
  input_flags(t, args);
  curve_flags(t, args);
  size_flags(t, args);
  partition_flags(t, args);
  map_flags(t, args);
  refine_and_smooth_flags(t, args);
  gate_flags(t, args);
  output_flags(t, args);
  depth_flags(t, args);
  run_flags(t, args);
  auto* cmd = app.add_subcommand("mesh", "mesh a region (GeoJSON) into all quadrilaterals");
  t.add_to(*cmd, {"input", "--features", "--boundary", "--domain-layer", "--feature-layer", "--where", "--crs",
                  "--size", "-o,--output", "--depth", "--bathymetry", "--bathymetry-positive", "--report",
                  "--picture", "--parts", "--split-rounds", "--agree-turns", "--multipass", "--map",
                  "--partition-picture", "--threads", "--seed", "--bend-interfaces", "--corner-angle", "--simplify",
                  "--smooth-curves", "--min-island-width", "--max-quads", "--min-sj", "--max-edge-ratio",
                  "--max-poor-fraction", "--boundary-weight", "--feature-weight", "--flat-corner-angle",
                  "--loop-corner-angle", "--feature-tolerance", "--binary", "--pieces", "--msh-version",
                  "--msh-features", "--time-limit", "--read-time-limit", "-q,--quiet", "-v,--verbose", "--repair"});
  return cmd;
}

}  // namespace polysquare::cli
