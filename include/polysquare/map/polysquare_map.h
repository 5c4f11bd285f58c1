// Stages 2 and 4-6 for one polygon part: background triangulation, pre-orientation, poly-square deformation,
// layout, integer quantization, snapping and quad extraction.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "polysquare/core/quad_mesh.h"
#include "polysquare/core/region.h"
#include "polysquare/core/work_sharing.h"
#include "polysquare/map/deform.h"
#include "polysquare/map/layout.h"
#include "polysquare/map/multipass.h"
#include "polysquare/map/quantize.h"
#include "polysquare/partition/partition.h"
#include "polysquare/size/size_field.h"
#include "polysquare/triangulate/background_triangulation.h"

namespace polysquare {

/// How the subregions of a partitioned part are mapped (paper Sec. 5).
enum class MapComposition : std::uint8_t {
  gpm,  ///< Global Poly-square Map: one frame, the separators are sides of one poly-square (no interior singularities)
  ppm,  ///< Piecewise Poly-square Map: one frame per subregion, interfaces matched by count (singularities at junctions)
};

struct PolysquareMapOptions {
  double size = 1.0;               ///< target quad edge length h (region units); must be set by the caller
  std::shared_ptr<const SizeField> size_field;  ///< graded meshes: the size at each point (null = `size`
                                                ///< everywhere); deformations then work in lattice units of the
                                                ///< local size, so the integer sides are local-size quads
  double parameterization_ratio = 1.0;  ///< background triangle edge length on rings and features / h
  double interior_ratio = 4.0;          ///< interior background triangles grow to max(interior_ratio * h,
  double interior_divisions = 40.0;     ///< part diagonal / interior_divisions): the map is smooth inside, and
                                        ///< grading keeps the triangle count near perimeter / h
  double triangle_shape_bound = 0.125;  ///< CGAL shape bound (0.125 = 20.7 degree minimum angle)
  std::size_t max_triangles = 20'000'000;  ///< refuse larger background triangulations
  double max_triangles_per_quad = 32.0;  ///< refuse a map whose background triangulation (past 4096 triangles)
                                         ///< has more triangles than this per quad of the part's area / h^2:
                                         ///< curves or angles finer than h throughout (needles, spike stars);
                                         ///< the bundled cases stay below 10; the fallback meshes such parts
  double min_quads_per_feature_point = 16.0;  ///< refuse a map of a part (with more than 64 feature points)
                                              ///< whose feature points are denser than one per this many quads:
                                              ///< points about 4 h apart leave no regular grid between them, and
                                              ///< keeping each off the others' lattice nodes is a search without end
  bool preorient = true;           ///< rotate by the eq. 11 optimum before deforming
  PartitionOptions partition{.parts = 1};  ///< subregions of the part (GPM); parts = 1: one poly-square
  int separator_straightening = 0;   ///< smoothing sweeps over the separators zig-zag (0 = keep triangle edges; 20
                                     ///< changed SJ min by -0.09 to +0.01 on the cases and broke dam_channel k = 4)
  MapComposition composition = MapComposition::ppm;  ///< used when partition.parts != 1
  bool keep_partition = false;     ///< keep the background triangulation in the result (for the partition picture)
  std::vector<int> patch_subregions;  ///< PPM subregions meshed by an unstructured patch whatever their map does
                                      ///< (a user who wants a zone unstructured; the tests of local repair)
  std::vector<int> matched_patches;   ///< patches built by the matching construction (PatchMethod::matching): the
                                      ///< retry for a patch whose first construction left a poor or folded quad
  std::vector<int> grown_patches;     ///< patches rebuilt over their neighbours' area at once (patch_growth): the
                                      ///< retry for a matched patch that still left a folded or poor quad
  int split_rounds = 2;      ///< PPM: times a subregion whose map fails alone is split into smaller ones before
                            ///< the joint map (split_unmappable_subregions); 0 = patch it at once
  int joint_split_rounds = 3;  ///< PPM: times the subregions whose map still fails in the joint map (a snap the
                               ///< joint counts cannot reach, an infeasible quantization) are split and the part
                               ///< mapped again; the new partition is kept when more quads come from maps, and
                               ///< the rounds stop at the first that brings none (a fourth kept nothing on a
                               ///< coast and costs a whole map of every partitioned candidate)
  bool pull_failed_snaps = true;  ///< PPM: after the split rounds, the part is mapped once more with snaps that
                                  ///< a straight path cannot make pulled to their targets by stiffening springs
                                  ///< (DeformOptions::pull_when_path_fails), kept when more quads are structured;
                                  ///< last because a pulled map is more distorted than its split pieces' maps.
                                  ///< Snaps that no path makes then have the folds of their harmonic embedding
                                  ///< untangled (DeformOptions::untangle_when_path_fails): once a split has
                                  ///< failed, a distorted map beats a patch (delta_box 100 m, 4 start vertices:
                                  ///< structured 0.956 -> 0.968); untangling in every snap mapped subregions
                                  ///< that a split maps better, whose slivers kept quads below SJ 0.3
  int split_max_subregions = 512; ///< no split takes a part beyond this many subregions, or beyond its quads over
                                  ///< split_quads_per_subregion when that is more: the joint quantization's time
                                  ///< grows with the count (delta_box 100 m: 322 subregions, 0.94 of its quads
                                  ///< mapped; at a cap of 256, 0.84)
  std::size_t split_quads_per_subregion = 2000;  ///< (see split_max_subregions) large parts may split down to
                                                 ///< subregions of about this many quads
  std::size_t split_graded_quads_per_subregion = 100;  ///< the same on a graded run, whose quads are counted by the
                                                       ///< field (integral of 1 / h^2): its subregions start at
                                                       ///< about 150 quads (SubregionOptions::
                                                       ///< graded_quads_per_subregion), so a coast holds more than
                                                       ///< split_max_subregions before any split (graded delta_box:
                                                       ///< 649, none of its 53 failed subregions split; 100: 857
                                                       ///< subregions after the splits, structured 0.86 -> 0.97)
  int sides_per_split = 12; ///< a failed subregion with s poly-square sides is split into ceil(s / this) pieces
                            ///< (at least 2, at most 8)
  /// PPM: the subregion of every background triangle from an earlier map_part of the same part with the same
  /// options (PartMapResult::partition), reused as it is (no partitioning, no splitting): repair rounds remesh
  /// the same subregions.
  std::shared_ptr<const std::vector<std::int32_t>> triangle_partition;
  int patch_growth = 3;  ///< times a patch that cannot be built takes in its neighbouring subregions and is built
                         ///< again over their union (a narrow or odd-counted subregion gains room and a ring piece)
  /// The processes meshing this region together (driver/mpi_driver.h): the subregions' maps, split tests and
  /// snaps are divided among them; null = this process alone. The mesh does not depend on it.
  std::shared_ptr<const WorkSharing> sharing;
  DeformOptions deform;
  /// PPM: the subregions deformed together in passes over charts with buffer zones (paper Algorithm 1) instead
  /// of each alone; off by default (see multipass.h and the README's measurement)
  MultipassOptions multipass;
  /// Weights of the labelled deformation that runs between labelling and quantization (continuation, one L-BFGS
  /// solve per weight): every side is pulled straight along its label, so the deformed layout the quantization
  /// reads orders and sizes the sides as the labels say (turtle_shell's bottom otherwise stays a staircase under
  /// a straight label and its holes overlap it). Empty: off.
  std::vector<double> label_weights{5.0, 50.0, 500.0};
  LayoutOptions layout;
  QuantizeOptions quantize;
};

/// How one subregion of a partitioned part was meshed.
struct SubregionStats {
  int subregion = 0;
  bool mapped = true;     ///< false: its map failed and an unstructured patch repairs it (fallback/patch.h)
  std::size_t quads = 0;
  std::size_t local_patch_quads = 0;  ///< of a mapped subregion's quads, those made by local patches around poor
                                      ///< quads (refine/local_patch.h)
  bool untangled = false; ///< its map reached the quantized poly-square only by untangling folds (mapped only)
  std::string reason;     ///< why its map failed (patches only)
  Vec2 at{};              ///< its first boundary vertex, to find it
};

/// What split_unmappable_subregions did.
struct SplitStats {
  int rounds = 0;   ///< rounds that split something
  int split = 0;    ///< subregions split, over all rounds
  int tested = 0;   ///< subregion maps tried alone
  int pieces_mapped = 0;  ///< pieces of split subregions whose maps then succeeded alone
  double seconds = 0;
};

struct PartMapStats {
  int part = 0;
  std::size_t triangles = 0, triangle_vertices = 0;
  double rotation_deg = 0.0;       ///< pre-orientation angle
  DeformStats deform;
  std::size_t break_points = 0, segments = 0;
  QuantizeStats quantize;
  std::size_t quads = 0;
  std::size_t separators = 0;      ///< separator chains between subregions
  std::size_t agreed_turns = 0;    ///< PPM: pairs of breaks on feature interfaces made to turn alike on both sides
  std::vector<SubregionStats> subregions;  ///< PPM: every subregion, in order
  std::size_t transition_rows = 0;         ///< PPM, graded: rows joining two counts of one interface (last map)
  SplitStats split;                        ///< PPM: subregions split before the joint map
  std::vector<std::pair<int, int>> failed_maps;  ///< PPM: subregions whose own map failed in the joint map (not
                                                 ///< requested patches), with their poly-square side counts
  int joint_splits = 0;                    ///< PPM: rounds that split failed subregions after the joint map
  double seconds_partition = 0;
  double seconds_triangulate = 0, seconds_deform = 0, seconds_quantize = 0, seconds_snap = 0, seconds_extract = 0;
  MultipassStats multipass;       ///< PPM with multi-pass deformation: the passes of the kept map
  int joint_maps = 0;             ///< PPM: joint maps of the part (first, split rounds, pulled snaps), kept or not
  double seconds_joint_maps = 0;  ///< PPM: their time together (the seconds_* above are the kept map's only)
};

struct PartMapResult {
  QuadMesh mesh;  ///< quads of this part; quad_part = subregion within the part (0 without partitioning)
  PartMapStats stats;
  std::optional<PartitionResult> partition;  ///< when partitioned: METIS/MH figures, triangle_part of `background`
  TriMesh background;                        ///< the background triangulation, when keep_partition is set
};

/// Pre-orientation angle (radians) minimizing sum over edges of len * nx^2 ny^2 (eq. 11). With the normal at
/// angle phi, nx^2 ny^2 = (1 - cos 4 phi) / 8, so the optimum is closed-form: theta = -arg(sum len e^{4 i phi})/4.
double preorientation_angle(const std::vector<Vec2>& points, const std::vector<std::array<std::int32_t, 2>>& edges);

/// A triangulation deformed towards a poly-square, in lattice units (1 = one element).
struct MappedMesh {
  DeformProblem problem;  ///< rest shape (centred, pre-oriented, scaled by 1 / h), triangles, aligned edges
  std::vector<Vec2> x;    ///< deformed positions
  double rotation_deg = 0.0;
  DeformStats stats;
};

/// Deforms `tri` towards a poly-square: every chain edge is pulled to an axis. The pre-orientation (eq. 11) is
/// computed over the ring edges, or with `orient_all_chains` over every chain but interior features.
MappedMesh deform_mesh(const TriMesh& tri, const PolysquareMapOptions& options, bool orient_all_chains);

/// The mapped mesh of a PPM subregion `tri` whose vertices were deformed elsewhere (multipass.h) to `deformed`
/// (#vertices, any frame): deform_mesh's problem, `deformed` turned so that its chains run along the axes.
MappedMesh deformed_mesh(const TriMesh& tri, const PolysquareMapOptions& options, std::vector<Vec2> deformed);

/// Deforms `mm` again with every chain edge pulled along its layout label (options.label_weights), then sets each
/// side's target to its new chord length. Keeps the map inversion-free; does nothing when the weights are empty.
void straighten_to_labels(MappedMesh& mm, Layout& layout, const TriMesh& tri, const PolysquareMapOptions& options);

/// Moves the chain vertices of a deformed mesh onto the quantized layout without inverting a triangle.
/// Throws MeshingError naming `name` when no valid path exists. Returns whether the map got there only by
/// untangling (DeformOptions::untangle_when_path_fails).
bool snap_to_layout(const TriMesh& tri, MappedMesh& mm, const Layout& layout, const PolysquareMapOptions& options,
                    const std::string& name);

/// Meshes one part with a single poly-square map. Throws MeshingError naming the part when the map fails.
PartMapResult map_part(const Region& region, const RegionPart& part, const PolysquareMapOptions& options);

}  // namespace polysquare
