// The pipeline: the library owns the stage order; the CLI only parses options and reports.
#pragma once

#include <cstdint>
#include <vector>

#include "polysquare/core/quad_mesh.h"
#include "polysquare/core/region.h"
#include "polysquare/map/polysquare_map.h"
#include "polysquare/pipeline/mesh_report.h"
#include "polysquare/pipeline/progress.h"
#include "polysquare/refine/local_patch.h"
#include "polysquare/refine/relax_valences.h"
#include "polysquare/refine/refine.h"
#include "polysquare/smooth/smooth.h"

namespace polysquare {

struct MeshOptions {
  double size = 0.0;             ///< target quad edge length h, region units (required, > 0)
  int threads = 0;               ///< worker threads; 0 = all cores. The mesh does not depend on it.
  std::uint64_t seed = 1;        ///< seed of every randomized stage (partitioning); the output depends only on it
  double corner_threshold_deg = 30.0;  ///< input vertices turning by more than this are mesh nodes
  double simplify = 0.5;         ///< simplify curves finer than the size first: remove vertices whose triangle area
                                 ///< is below (simplify * size)^2, keeping topology and every vertex within size of
                                 ///< the simplified curve; the mesh follows the simplified curves (MeshResult::region)
                                 ///< and the report gives the largest distance moved and the area change; 0 = off
  double smooth_curves = 0.5;    ///< with simplify on: stretches of curve finer than the size are smoothed first,
                                 ///< each vertex kept within smooth * size of the input, so that digitisation steps
                                 ///< (a shoreline's 45-degree turns every 120 m) are not corners; 0 = off
  double min_island_width = 1.0; ///< with simplify on: holes, closed feature loops and faces between feature
                                 ///< pieces whose largest inscribed disk is narrower than this times size hold no
                                 ///< quad of that size: the hole or loop is left out, the face opened by removing
                                 ///< one of its pieces (input/simplify.h); each is reported (report
                                 ///< `dropped_curves`, a CLI warning); 0 keeps them all
  std::size_t max_quads = 50'000'000;  ///< refuse sizes whose estimated quad count exceeds this
  int parts = 0;                 ///< subregions per polygon part. 0 = automatic: a part above search_quads quads
                                 ///< is meshed one way, with max(its quads / target_quads_per_part, its boundary
                                 ///< length / (perimeter_per_subregion * size)) subregions (feature curves count
                                 ///< twice), plus one poly-square (see single_map_quads); smaller
                                 ///< parts also try one poly-square and the counts of search_subregions, and the
                                 ///< best mesh is kept. K > 0: K subregions, one poly-square if that fails.
  std::size_t target_quads_per_part = 20000;  ///< subregion size for large parts in automatic mode
  double perimeter_per_subregion = 30.0;      ///< boundary length per subregion in automatic mode, in sizes
  int max_automatic_subregions = 64;          ///< cap on the boundary-length count (each subregion adds columns
                                              ///< and coupling rows to the part's one mixed-integer quantization)
  std::size_t single_map_quads = 100'000;     ///< automatic mode: a part above search_quads quads with a
                                              ///< convoluted boundary is meshed as one poly-square beside its
                                              ///< partition up to this many quads; a larger one only when its
                                              ///< partition fails (one map must close every side of the part at
                                              ///< once; on coasts it failed every time beyond this, after 10-16 s)
  bool drop_small_parts = true;               ///< leave out (and report) polygon parts smaller than size^2
  std::size_t search_quads = 5'000;           ///< parts up to this many quads try every count of search_subregions
  std::vector<int> search_subregions{2, 3, 4, 5, 6, 8};
  double fine_parameterization_ratio = 0.5;   ///< automatic mode, parts up to search_quads quads: when no
                                              ///< candidate is fully structured, the straight ones are meshed
                                              ///< again with background edges of this many sizes on the curves
                                              ///< (PolysquareMapOptions::parameterization_ratio); 0 = off
  std::size_t bent_round_quads = 5'000;       ///< automatic mode retries partitions with bendable interfaces only
                                              ///< for parts up to this many quads (smile, 1,300, needed it once;
                                              ///< delta_water's coastline parts spent half their search there and
                                              ///< meshed none)
  bool split_fallback = true;    ///< a part no poly-square candidate meshes gets an unstructured all-quad mesh
                                 ///< (triangles split into three quads), reported under `fallbacks`; false: refuse
  int repair_rounds = 4;          ///< times a candidate is meshed again with the mapped subregions whose quads stay
                                  ///< folded after smoothing turned into patches (local repair)
  bool repair_in_place = true;    ///< a repair round that only turns mapped subregions into patches cuts their
                                  ///< quads out of the finished mesh and patches each hole on its boundary nodes
                                  ///< (the rest keeps its quads, smoothing and local patches); false: the part is
                                  ///< mapped again with them as patches (their neighbours' counts quantized again)
  bool keep_partition = false;   ///< return the background triangulation and its partition (for pictures)
  double min_scaled_jacobian = 0.2;    ///< a candidate with a quad below this is refused (see max_poor_fraction);
                                       ///< 0 = accept any valid mesh
  double max_edge_ratio = 20.0;        ///< refuse a mesh with a quad whose longest / shortest edge exceeds this
  double max_poor_fraction = 0.001;    ///< valid quads outside the two gates above that local patches did not mend
                                       ///< are accepted, each reported with its place, while they are at most this
                                       ///< fraction of the part's quads; the repair rounds turn their subregions
                                       ///< into patches only beyond it, worst first (always for a quad below half
                                       ///< the SJ gate or above twice the edge-ratio gate), and a candidate with more is
                                       ///< refused. A candidate with none wins over one with some. 0 = every quad
                                       ///< must pass both gates (folded quads are never accepted)
  std::size_t keep_map_above_quads = 300;  ///< a mapped subregion of more quads keeps its map whatever valid quads
                                          ///< it holds outside the gates (they get the widest local patches and are
                                          ///< reported as poor quads): its patch would add more singular nodes
                                          ///< (about one per seven quads) than the quads it mends. Not for a quad
                                          ///< below smooth.untangle.target_sj that no sharp input corner pins: that
                                          ///< one counts as folded in any map
  double feature_tolerance = 0.1;      ///< largest distance, as a fraction of size, between a feature curve and the
                                       ///< mesh edges along it that smoothing allows (SmoothOptions::feature_tolerance);
                                       ///< 0 = unbounded
  PolysquareMapOptions map;      ///< stages 2 and 4-6 (map.size and map.layout.corner_threshold_deg are set from above)
  RefineOptions refine;          ///< stage 8 templates at flattened boundary corners (before smoothing)
  RelaxValencesOptions relax_valences;  ///< after the local patches, the unstructured quads' valences are cleaned
                                        ///< up across their seams (refine/relax_valences.h)
  LocalPatchOptions local_patch; ///< after smoothing, poor or folded quads are meshed again with a few rings
                                 ///< around them, before a repair round turns their whole subregion into a patch
                                 ///< (local_patch.size is set from size)
  SmoothOptions smooth;          ///< stage 7 smoothing
  ProgressCallback progress;     ///< told when each stage starts and finishes and as polygon parts are meshed
                                 ///< (ProgressEvent); empty = silent. It never changes the mesh.
};

struct MeshResult {
  QuadMesh mesh;                    ///< quad_part = global subregion index (parts in order, then subregions)
  TriMesh background;               ///< all parts' background triangulations, when keep_partition is set
  std::vector<std::int32_t> background_part;  ///< #background triangles, global subregion index
  std::vector<PartMapStats> parts;  ///< per polygon part, in part order
  MeshReport report;                ///< options, timings, counts (quality is added by the caller's choice)
  Region region;                    ///< the region the mesh conforms to: the input with curves simplified
                                    ///< (MeshOptions::simplify); the design invariants hold against it
};

/// Meshes every polygon part of a validated region (parts in parallel with oneTBB), assembles them in part
/// order, smooths, and checks the invariants. Throws InputError for bad options (size <= 0, too many quads) and
/// MeshingError naming every part that failed; never returns a mesh that breaks an invariant.
MeshResult mesh_region(const Region& region, const MeshOptions& options);

}  // namespace polysquare
