// The flags of `polysquare mesh`, by stage: each function below maps one stage's flags to the options structs
// (MeshArgs, InputOptions, MeshOptions); `polysquare mesh --help` lists them in that order.
#include <cmath>
#include <cstdlib>
#include <string>

#include "mesh_command.h"

namespace polysquare::cli {
namespace {

// A count given in exponent notation ("2e9" quads, as counts that large are written) as the integer it is, when it
// is a whole number in range; any other text is left to the conversion, which refuses it.
std::string whole_count(std::string text) {
  if (text.find_first_of("eE.") == std::string::npos) return text;
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (end == text.c_str() || *end != '\0' || !(v >= 1.0 && v < 1e19) || v != std::floor(v)) return text;
  return std::to_string(static_cast<unsigned long long>(v));
}

// Reading the input: files, layers, filter, CRS, repairs.
void input_flags(CLI::App& t, MeshArgs& m) {
  t.add_option("input", m.input,
           "input region: GeoJSON, or any vector dataset GDAL reads (.shp, .gpkg, .kml, .gml, .dxf, .fgb); "
           "every layer, roles from a 'role' attribute or the geometry type")
      ->required();
  t.add_option("--features", m.input_options.feature_files,
           "more vector datasets whose layers are feature curves (repeatable)");
  t.add_option("--boundary", m.input_options.boundary_files,
           "vector datasets whose lines lie on the domain boundary and split it into named segments "
           "(attributes 'name', 'kind': open, land, ...; repeatable)");
  t.add_option("--domain-layer", m.input_options.domain_layer,
           "the input layer that is the domain (the other layers give features)");
  t.add_option("--feature-layer", m.input_options.feature_layers,
           "a layer that gives feature curves (repeatable; other feature layers are then skipped)");
  t.add_option("--where", m.input_options.where, "OGR SQL attribute filter applied to every layer read");
  t.add_option("--crs", m.input_options.crs,
           "projected CRS to mesh geographic input in, e.g. EPSG:32615 (default: UTM zone of the centre)");
  t.add_flag("--repair", m.input_options.repair,
         "drop repeated points and clip features crossing holes instead of refusing the input (reported)");
}

// The curves the mesh follows: corners kept, simplification, smoothing, narrow islands.
void curve_flags(CLI::App& t, MeshArgs& m) {
  t.add_option("--corner-angle", m.options.curves.corner_threshold_deg,
               "input vertices turning by more than this (degrees) become mesh nodes")
      ->capture_default_str();
  t.add_option("--simplify", m.options.curves.simplify,
               "simplify curves finer than the size first: drop vertices whose triangle area < (F*size)^2, each within "
               "size of the result (0 = off: the mesh follows every input vertex)")
      ->capture_default_str();
  t.add_option("--smooth-curves", m.options.curves.smooth_curves,
               "with --simplify: smooth stretches of curve finer than the size first, each vertex within F*size of the "
               "input, so that digitisation steps are not corners (0 = off)")
      ->capture_default_str();
  t.add_option("--min-island-width", m.options.curves.min_island_width,
               "with --simplify: leave out (and report) holes, closed feature curves and feature pieces around regions "
               "narrower than F*size (0 keeps them)")
      ->capture_default_str();
}

void size_flags(CLI::App& t, MeshArgs& m) {
  CLI::Option* size = t.add_option("--size", m.options.size.h,
                                    "target quad edge length h, in region units (metres for geographic input); or "
                                    "grade the size with --size-min and --size-max");
  CLI::Option* size_min = t.add_option("--size-min", m.options.size.field.size_min,
                                       "graded mesh: the size at the boundary and the feature curves, and the least");
  CLI::Option* size_max =
      t.add_option("--size-max", m.options.size.field.size_max, "graded mesh: the largest size, far from the shore");
  size->excludes(size_min)->excludes(size_max);
  size_min->needs(size_max);
  size_max->needs(size_min);
  t.add_option("--grade", m.options.size.field.grade,
               "graded mesh: the size grows by at most this times the distance (|h(x) - h(y)| <= G |x - y|)")
      ->capture_default_str();
  t.add_option("--across", m.options.size.field.across,
               "graded mesh: at least N quads across every passage between two shores (h <= width / N; 0 = off)")
      ->capture_default_str();
  t.add_option("--size-field", m.size_raster,
               "graded mesh: a raster of sizes (any GDAL raster, in its own CRS): h <= its value (bilinear)");
  t.add_option("--per-wavelength", m.per_wavelength,
               "graded mesh, with --bathymetry: at least N quads per M2 tidal wavelength, 44712 s * sqrt(9.81 m/s2 * "
               "depth) (0 = off)")
      ->capture_default_str();
  t.add_option("--max-quads", m.options.size.max_quads,
               "refuse sizes that need more quads than this (sizes needing more memory than the machine has "
               "available are refused too)")
      ->transform(whole_count)
      ->check(CLI::PositiveNumber)
      ->capture_default_str();  // "-5" would otherwise wrap around to 2^64 - 5
}

void partition_flags(CLI::App& t, MeshArgs& m) {
  t.add_option("--graded-subregion-quads", m.options.subregions.graded_quads_per_subregion,
               "graded mesh: at least one subregion per this many quads (their corners take the singular nodes the "
               "grading needs; fewer quads per subregion: less stretched quads, more singular nodes; at --grade G below 0.15, "
               "times (0.15 / G)^2)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  t.add_option("--transition-cost", m.options.map.quantize.transition_cost,
               "graded mesh: where two subregions' sizes differ, their interface counts may differ by 2 k, joined by "
               "a row of k transition quads (two singular nodes each) costing this much each (0 = off)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  t.add_option(
       "--parts", m.options.subregions.parts,
       "subregions per polygon part (1 = one poly-square per part, 0 = try several counts and keep the best mesh)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  t.add_option("--seed", m.options.run.seed, "seed of randomized stages");
}

// Mapping the subregions to poly-squares (deformation, layout, splits).
void map_flags(CLI::App& t, MeshArgs& m) {
  t.add_option("--map", m.map,
           "how subregions are mapped: ppm (a poly-square per subregion, singularities where they meet) or "
           "gpm (one global poly-square, separators as its sides)")
      ->check(CLI::IsMember({"ppm", "gpm"}))
      ->capture_default_str();
  t.add_option("--split-rounds", m.options.map.split_rounds,
           "times a subregion whose map fails alone is split into smaller ones before meshing (0 = patch it)")
      ->capture_default_str()
      ->check(CLI::Range(0, 8));
  t.add_option("--agree-turns", m.options.map.layout.agree_turn_elements,
           "PPM: where a feature between two subregions turns on one side only, turn one side's labels a "
           "quarter over stretches of at most this many elements so both sides agree (0 = off)")
      ->capture_default_str();
  t.add_option("--multipass", m.options.map.multipass.max_passes,
           "PPM: deform the subregions together in at most this many passes over charts with buffer zones "
           "(the paper's Algorithm 1) instead of each alone (0)")
      ->capture_default_str()
      ->check(CLI::Range(0, 100));
  t.add_flag("--bend-interfaces", m.bend_interfaces,
         "PPM: let interfaces between subregions bend (both sides share every break point) instead of "
         "keeping each one straight");
  t.add_option("--boundary-weight", m.options.map.deform.boundary_weight,
           "lambda of the boundary alignment term (paper eq. 9)")
      ->capture_default_str();
  t.add_option("--feature-weight", m.options.map.deform.feature_weight,
           "weight of the feature alignment term (paper eq. 10)")
      ->capture_default_str();
}

// Templates at flat corners (refine) and smoothing along features.
void refine_and_smooth_flags(CLI::App& t, MeshArgs& m) {
  t.add_option("--flat-corner-angle", m.options.refine.flat_corner_deg,
           "collapse the quad at a boundary node whose single corner there is flatter than this (degrees), "
           "leaving an interior valence-3 node; 180 = off")
      ->capture_default_str();
  t.add_option("--loop-corner-angle", m.options.refine.loop_corner_deg,
           "add a layer of quads inside a closed feature curve whose single corner there is flatter than "
           "this (degrees), leaving eight singular nodes; 180 = off")
      ->capture_default_str();
  t.add_option("--feature-tolerance", m.options.gates.feature_tolerance,
               "largest distance between a feature curve and the mesh edges along it, as a fraction of the size (0 = "
               "unbounded)")
      ->capture_default_str();
}

// The quality gates a mesh must pass (after local repair).
void gate_flags(CLI::App& t, MeshArgs& m) {
  t.add_option("--min-sj", m.options.gates.min_scaled_jacobian,
               "refuse a mesh with quads whose scaled Jacobian is below this (see --max-poor-fraction; 0 accepts any "
               "valid mesh)")
      ->capture_default_str();
  t.add_option("--max-edge-ratio", m.options.gates.max_edge_ratio,
               "refuse a mesh with quads whose longest / shortest edge exceeds this (see --max-poor-fraction)")
      ->capture_default_str();
  t.add_option("--max-poor-fraction", m.options.gates.max_poor_fraction,
               "accept (and report) a mesh whose quads outside --min-sj or --max-edge-ratio, after local repair, are "
               "at most this fraction of a part's quads (0 = every quad must pass)")
      ->capture_default_str();
}

// The mesh file, its format's choices, and the other outputs (report, pictures).
void output_flags(CLI::App& t, MeshArgs& m) {
  t.add_option("-o,--output", m.output,
           "output mesh (.msh Gmsh, .vtu VTK, .pvtu VTK in pieces, .gr3 SCHISM hgrid, .nc D-Flow FM UGRID net file, .2dm SMS, .exo Exodus II)")
      ->required();
  t.add_flag("--binary", m.binary, "write binary MSH");
  t.add_option("--pieces", m.pieces,
           "with -o X.pvtu: the number of .vtu pieces X_<k>.vtu (the quads in subregion order, in runs of "
           "equal length), written in parallel (0 = one per million quads)")
      ->check(CLI::Range(std::size_t{0}, std::size_t{4096}))
      ->capture_default_str();
  t.add_option("--msh-version", m.msh_version,
           "MSH version: 2.2 (read by Gmsh, meshio, deal.II, MFEM, MOOSE, DUNE) or 4.1 (Gmsh's current; "
           "not MFEM or DUNE)")
      ->check(CLI::IsMember({"2.2", "4.1"}))
      ->capture_default_str();
  t.add_option("--msh-features", m.msh_features,
           "feature curves in MSH: nodes (a physical point group per curve; every reader takes the file), "
           "lines (physical curves of line elements; deal.II refuses them) or none")
      ->check(CLI::IsMember({"nodes", "lines", "none"}))
      ->capture_default_str();
  t.add_option("--report", m.report, "write a JSON report (options, timings, counts, quality)");
  CLI::Option* picture = t.add_option("--picture", m.picture,
           "write a picture of the mesh coloured by --picture-color: .png, or .svg for small meshes");
  t.add_option("--picture-color", m.picture_color,
               "what colours --picture's quads: sj (scaled Jacobian), skew, part (subregion), singularities (plain, "
               "valence marks only) or size (graded mesh: sqrt(area) / h of the size field, log scale 0.5-2)")
      ->check(CLI::IsMember({"sj", "skew", "part", "singularities", "size"}))
      ->needs(picture)
      ->capture_default_str();
  t.add_option("--size-picture", m.size_picture, "graded mesh: a PNG of the size field (log colour scale)");
  t.add_option("--partition-picture", m.partition_picture,
           "write an SVG of the background triangulation coloured by subregion, separators and features");
}

// Depths of the solver files (.gr3, .nc, .2dm).
void depth_flags(CLI::App& t, MeshArgs& m) {
  t.add_option("--depth", m.depth,
           "constant water depth, positive down, for .gr3 (depth column), .nc (mesh2d_node_z = -depth) "
           "and .2dm files");
  t.add_option("--bathymetry", m.bathymetry,
           "raster GDAL reads (GeoTIFF, netCDF, ASCII grid, ...) sampled bilinearly at the nodes, in the "
           "raster's CRS, for the depths of .gr3, .nc and .2dm files");
  t.add_option("--bathymetry-positive", m.bathymetry_positive,
           "up: the raster holds elevations (depth = -value, as GEBCO and DEMs); down: it holds depths")
      ->check(CLI::IsMember({"up", "down"}))
      ->capture_default_str();
}

// How the run goes: threads, time limits, what it prints.
void run_flags(CLI::App& t, MeshArgs& m) {
  t.add_option("--threads", m.options.run.threads, "worker threads (0 = all cores); output does not depend on it")
      ->check(CLI::NonNegativeNumber);
  t.add_option("--time-limit", m.time_limit,
           "seconds of wall time the run may take (reading, meshing, checks; not writing) before it ends "
           "in exit 3 naming the stage it was in, with nothing written (0 = no limit)")
      ->capture_default_str();
  t.add_option("--read-time-limit", m.read_time_limit,
           "seconds reading the input may take before the run ends in exit 3 (a reader stuck in a "
           "malformed file: GDAL 3.6's DXF driver can loop for ever; 0 = no limit)")
      ->capture_default_str();
  t.add_flag("-q,--quiet", m.quiet, "print errors and warnings only (no progress, no summary)");
  t.add_flag("-v,--verbose", m.verbose, "print each stage's wall time as it finishes, and how each large quantization program was solved (on stderr)");
}

}  // namespace

CLI::App* add_mesh_command(CLI::App& app, MeshArgs& args) {
  auto* cmd = app.add_subcommand("mesh", "mesh a region (GeoJSON) into all quadrilaterals");
  input_flags(*cmd, args);
  curve_flags(*cmd, args);
  size_flags(*cmd, args);
  partition_flags(*cmd, args);
  map_flags(*cmd, args);
  refine_and_smooth_flags(*cmd, args);
  gate_flags(*cmd, args);
  output_flags(*cmd, args);
  depth_flags(*cmd, args);
  run_flags(*cmd, args);
  return cmd;
}

}  // namespace polysquare::cli
