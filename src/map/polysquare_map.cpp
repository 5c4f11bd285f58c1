#include "polysquare/map/polysquare_map.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "polysquare/core/error.h"
#include "polysquare/map/extract.h"
#include "polysquare/map/piecewise_map.h"
#include "polysquare/partition/partition.h"
#include "map/map_common.h"

namespace polysquare {
namespace {

// The background triangulation of a part: fine on its curves, grown inside.
TriMesh part_triangulation(const Region& region, const RegionPart& part, const PolysquareMapOptions& options) {
  const double h = options.size;
  TriangulationOptions topt;
  topt.boundary_edge = options.parameterization_ratio * h;
  // The deformation is smooth away from the curves: interior triangles grow to a fraction of the part's size.
  Box2 part_box;
  for (int r : part.rings)
    for (Vec2 p : region.rings[static_cast<std::size_t>(r)].points) part_box.add(p);
  topt.max_edge = std::max(options.interior_ratio * h, part_box.diagonal() / options.interior_divisions);
  topt.shape_bound = options.triangle_shape_bound;
  topt.max_triangles = options.max_triangles;
  return triangulate_part(region, part, topt);
}

// Throws when the triangulation is too fine for the part (curves, corners or feature points finer than the size
// throughout): no map is tried. Deforming costs triangles x iterations; past this many triangles per quad every map of the part would spend
// minutes on detail the quads cannot show.
void check_triangulation_density(const TriMesh& tri, const PolysquareMapOptions& options, const std::string& name,
                                 double area) {
  const double h = options.size;
  const double quads = area / (h * h);
  if (tri.triangles.size() > 4096 && static_cast<double>(tri.triangles.size()) > options.max_triangles_per_quad * quads)
    throw MeshingError(name + ": its background triangulation has " + std::to_string(tri.triangles.size()) +
                       " triangles for about " + std::to_string(static_cast<long long>(std::ceil(quads))) +
                       " quads (more than " + std::to_string(static_cast<int>(options.max_triangles_per_quad)) +
                       " per quad): curves or corners finer than the size throughout, no map is tried");
  const std::size_t points = tri.feature_point_vertices.size();
  if (points > 64 && static_cast<double>(points) * options.min_quads_per_feature_point > quads)
    throw MeshingError(name + ": " + std::to_string(points) + " feature points for about " +
                       std::to_string(static_cast<long long>(std::ceil(quads))) + " quads (fewer than " +
                       std::to_string(static_cast<int>(options.min_quads_per_feature_point)) +
                       " quads per point): too dense for a regular grid between them, no map is tried");
}

// GPM: the subregions' separators become chains of `tri` (straightened, their constrained interior edges split);
// returns the subregion of every triangle of the new `tri`.
std::vector<std::int32_t> add_gpm_separators(TriMesh& tri, PartitionResult& pr, const PolysquareMapOptions& options,
                                             PartMapResult& result) {
  result.stats.separators = add_separator_chains(tri, pr.triangle_part);
  straighten_separator_chains(tri, options.separator_straightening);
  std::vector<std::int32_t> parent;
  split_constrained_interior_edges(tri, &parent);
  std::vector<std::int32_t> triangle_part(parent.size());
  for (std::size_t t = 0; t < parent.size(); ++t) triangle_part[t] = pr.triangle_part[static_cast<std::size_t>(parent[t])];
  pr.triangle_part = triangle_part;
  if (options.keep_partition) result.background = tri;
  return triangle_part;
}

// PPM: the METIS partition cleaned up (feature loops whole, pieces cut off by features absorbed, separator ends
// on corners, enclosed parts merged, pinched parts separated) and its subregions that do not map alone split.
void clean_ppm_partition(const TriMesh& tri, PartitionResult& pr, const PolysquareMapOptions& options,
                         const std::string& name, PartMapStats& st) {
  keep_feature_loops_whole(tri, pr.triangle_part);
  absorb_pieces_cut_off_by_features(tri, pr.triangle_part);
  snap_separator_ends_to_corners(tri, pr.triangle_part, options.layout.corner_threshold_deg);
  pr.parts = merge_enclosed_parts(tri, pr.triangle_part);
  if (separate_pinched_parts(tri, pr.triangle_part) > 0) pr.parts = merge_enclosed_parts(tri, pr.triangle_part);
  pr.parts = split_unmappable_subregions(tri, pr.triangle_part, pr.parts, options, name, st.split);
}

// GPM (paper Sec. 5.1): the subregions' separators become chains of the one global map, so shared separator
// vertices are identical on both sides by construction (eq. 12) and one quantization serves all subregions.
// PPM (Sec. 5.2): the subregions are cut apart and mapped in their own frames (map_piecewise).
// Sets result.partition; returns the subregion of every triangle, and in `reuse` whether the options' PPM
// partition was taken as it is.
std::vector<std::int32_t> partition_part(TriMesh& tri, const PolysquareMapOptions& options, const std::string& name,
                                         PartMapResult& result, bool& reuse) {
  PartMapStats& st = result.stats;
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<std::int32_t> triangle_part;
  reuse = options.composition == MapComposition::ppm && options.triangle_partition &&
          options.triangle_partition->size() == tri.triangles.size();
  PartitionResult pr;
  if (reuse) {
    pr.triangle_part = *options.triangle_partition;
    pr.parts = 1 + *std::max_element(pr.triangle_part.begin(), pr.triangle_part.end());
  } else {
    PartitionOptions popt = options.partition;
    if (popt.min_face_area <= 0) popt.min_face_area = 16.0 * options.size * options.size;  // a face must hold a subregion of 4 x 4 quads
    pr = partition_triangles(tri, popt);
  }
  if (options.composition == MapComposition::gpm) {
    triangle_part = add_gpm_separators(tri, pr, options, result);
  } else {
    if (!reuse) clean_ppm_partition(tri, pr, options, name, st);
    triangle_part = pr.triangle_part;
    if (options.keep_partition) {
      result.background = tri;
      st.separators = add_separator_chains(result.background, triangle_part);
    }
  }
  result.partition = std::move(pr);
  st.seconds_partition = seconds_since(t0);
  return triangle_part;
}

// The joint maps (map_piecewise) of one part, counted and timed (also those that throw).
struct JointMaps {
  const TriMesh& tri;
  const std::string& name;
  int count = 0;
  double seconds = 0.0;

  QuadMesh operator()(const std::vector<std::int32_t>& tp, int parts, const PolysquareMapOptions& o, PartMapStats& s) {
    const auto t = std::chrono::steady_clock::now();
    ++count;
    struct Add {  // counted when the map throws too
      double& total;
      std::chrono::steady_clock::time_point t;
      ~Add() { total += seconds_since(t); }
    } add{seconds, t};
    return map_piecewise(tri, tp, parts, o, name, s);
  }
};

// The fraction of a map's quads that come from maps (not patches).
double mapped_fraction(const PartMapStats& s) {
  std::size_t mapped = 0, all = 0;
  for (const SubregionStats& r : s.subregions) {
    all += r.quads;
    mapped += r.mapped ? r.quads : 0;
  }
  return all > 0 ? static_cast<double>(mapped) / static_cast<double>(all) : 0.0;
}

// The PPM of one partitioned part, its state between the joint maps.
struct PpmPart {
  const TriMesh& tri;
  std::vector<std::int32_t>& triangle_part;
  const PolysquareMapOptions& options;
  const std::string& name;
  PartMapResult& result;
  JointMaps joint_map;
};

// Splits the listed subregions and maps the part again; true when that was kept.
bool split_round(PpmPart& ppm, const std::vector<std::pair<int, int>>& listed) {
  PartMapResult& result = ppm.result;
  PartMapStats& st = result.stats;
  std::vector<std::int32_t> tp = ppm.triangle_part;
  int split = 0;
  const int parts = split_listed_subregions(ppm.tri, tp, result.partition->parts, listed, ppm.options, ppm.name, split);
  if (split == 0) return false;
  PartMapStats trial = st;
  QuadMesh mesh;
  try {
    mesh = ppm.joint_map(tp, parts, ppm.options, trial);
  } catch (const MeshingError&) {
    return false;  // a patch of the new partition cannot be built: keep the last one
  }
  if (mapped_fraction(trial) <= mapped_fraction(st)) return false;
  trial.joint_splits = st.joint_splits + 1;
  st = std::move(trial);
  result.mesh = std::move(mesh);
  ppm.triangle_part = std::move(tp);
  result.partition->triangle_part = ppm.triangle_part;
  result.partition->parts = parts;
  if (ppm.options.keep_partition) {
    result.background = ppm.tri;
    st.separators = add_separator_chains(result.background, ppm.triangle_part);
  }
  return true;
}

// Failures the joint map found (counts a subregion's snap cannot reach, an infeasible quantization) are
// repaired where they are: those subregions are split and the part is mapped again, kept when more of its
// quads come from maps.
void split_failed_subregions(PpmPart& ppm) {
  const PartMapStats& st = ppm.result.stats;
  for (int round = 0; round < ppm.options.joint_split_rounds && !st.failed_maps.empty(); ++round) {
    if (split_round(ppm, st.failed_maps)) continue;
    // Splitting every failed subregion moved failures elsewhere: the one with the most quads alone.
    if (st.failed_maps.size() < 2) break;
    std::pair<int, int> largest = st.failed_maps.front();
    for (const auto& f : st.failed_maps)
      if (st.subregions[static_cast<std::size_t>(f.first)].quads > st.subregions[static_cast<std::size_t>(largest.first)].quads)
        largest = f;
    if (!split_round(ppm, {largest})) break;
  }
}

// The PPM of a partitioned part: a joint map, split rounds for its failed subregions, then a map with pulled
// snaps. A reused partition is final (repair rounds name its subregions).
void map_partitioned(const TriMesh& tri, std::vector<std::int32_t>& triangle_part, bool reuse,
                     const PolysquareMapOptions& options, const std::string& name, PartMapResult& result) {
  PartMapStats& st = result.stats;
  // The snaps no split could make are pulled to their targets (a distorted map, still structured) in the
  // part's last map: at once for a reused partition (repair rounds split nothing), else after the splits.
  PolysquareMapOptions pulled = options;
  pulled.deform.pull_when_path_fails = options.pull_failed_snaps;
  pulled.deform.untangle_when_path_fails = options.pull_failed_snaps;
  PpmPart ppm{tri, triangle_part, options, name, result, JointMaps{tri, name}};
  result.mesh = ppm.joint_map(triangle_part, result.partition->parts, reuse ? pulled : options, st);
  if (!reuse) split_failed_subregions(ppm);
  if (!reuse && options.pull_failed_snaps && !st.failed_maps.empty()) {
    PartMapStats trial = st;
    try {
      QuadMesh mesh = ppm.joint_map(triangle_part, result.partition->parts, pulled, trial);
      if (mapped_fraction(trial) > mapped_fraction(st)) {
        st = std::move(trial);
        result.mesh = std::move(mesh);
      }
    } catch (const MeshingError&) {
      // a patch of the pulled map cannot be built: the last map stays
    }
  }
  st.quads = result.mesh.quads.size();
  st.joint_maps = ppm.joint_map.count;
  st.seconds_joint_maps = ppm.joint_map.seconds;
}

// One poly-square map of the whole part (GPM when `triangle_part` is given): deformation, layout,
// quantization, snap and extraction.
void map_single(const TriMesh& tri, const std::vector<std::int32_t>& triangle_part, const PolysquareMapOptions& options,
                const std::string& name, PartMapResult& result, std::chrono::steady_clock::time_point t0) {
  PartMapStats& st = result.stats;
  MappedMesh mm = deform_mesh(tri, options, false);
  st.rotation_deg = mm.rotation_deg;
  st.deform = mm.stats;
  st.seconds_deform = seconds_since(t0);

  t0 = std::chrono::steady_clock::now();
  Layout layout = build_layout(tri, tri.vertices, mm.x, options.layout, name);
  st.break_points = layout.break_vertex.size();
  st.segments = layout.segments.size();
  straighten_to_labels(mm, layout, tri, options);
  st.quantize = quantize_layouts_shared(options.sharing.get(), {&layout}, {&mm.x}, {}, options.quantize, name);
  if (const std::string invalid = invalid_poly_square(layout, name); !invalid.empty()) throw MeshingError(invalid);
  st.seconds_quantize = seconds_since(t0);

  t0 = std::chrono::steady_clock::now();
  snap_to_layout(tri, mm, layout, options, name);
  st.seconds_snap = seconds_since(t0);

  t0 = std::chrono::steady_clock::now();
  result.mesh = extract_quads(tri, tri.vertices, mm.x, layout, name, triangle_part.empty() ? nullptr : &triangle_part);
  st.quads = result.mesh.quads.size();
  st.seconds_extract = seconds_since(t0);
}

}  // namespace

PartMapResult map_part(const Region& region, const RegionPart& part, const PolysquareMapOptions& options) {
  PartMapResult result;
  PartMapStats& st = result.stats;
  st.part = part.part;
  const std::string name = (region.source.empty() ? std::string("region") : region.source) + ": part " +
                           std::to_string(part.part);
  const double h = options.size;

  const double area = part_area(region, part);
  if (area < h * h)
    throw MeshingError(name + " has area " + std::to_string(area) + ", less than one element (size^2 = " +
                       std::to_string(h * h) + "); remove it from the input or use a smaller size");

  auto t0 = std::chrono::steady_clock::now();
  TriMesh tri = part_triangulation(region, part, options);
  st.seconds_triangulate = seconds_since(t0);
  check_triangulation_density(tri, options, name, area);

  std::vector<std::int32_t> triangle_part;
  bool reuse = false;
  if (options.partition.parts != 1) triangle_part = partition_part(tri, options, name, result, reuse);
  st.triangles = tri.triangles.size();
  st.triangle_vertices = tri.vertices.size();

  t0 = std::chrono::steady_clock::now();
  if (options.composition == MapComposition::ppm && result.partition)
    map_partitioned(tri, triangle_part, reuse, options, name, result);
  else
    map_single(tri, triangle_part, options, name, result, t0);
  return result;
}

}  // namespace polysquare
