// The pipeline: the library owns the stage order; the CLI only parses options and reports.
#pragma once

#include <cstdint>
#include <vector>

#include "polysquare/core/quad_mesh.h"
#include "polysquare/core/region.h"
#include "polysquare/map/polysquare_map.h"
#include "polysquare/input/simplify.h"
#include "polysquare/pipeline/mesh_report.h"
#include "polysquare/pipeline/progress.h"
#include "polysquare/pipeline/repair.h"
#include "polysquare/pipeline/subregions.h"
#include "polysquare/refine/local_patch.h"
#include "polysquare/refine/relax_valences.h"
#include "polysquare/refine/refine.h"
#include "polysquare/size/size_field.h"
#include "polysquare/smooth/smooth.h"

namespace polysquare {

/// What the caller asks of a run, not of the mesh: none of these changes the mesh.
struct RunOptions {
  int threads = 0;               ///< worker threads; 0 = all cores. The mesh does not depend on it.
  std::uint64_t seed = 1;        ///< seed of every randomized stage (partitioning); the output depends only on it
  bool keep_partition = false;   ///< return the background triangulation and its partition (for pictures)
  ProgressCallback progress;     ///< told when each stage starts and finishes and as polygon parts are meshed
                                 ///< (ProgressEvent); empty = silent. It never changes the mesh.
};

/// Every option of mesh_region, one struct per stage, each documented in its stage's header. The CLI maps its
/// flags onto them in apps/polysquare/mesh_flags.cpp, one function per stage.
struct MeshOptions {
  SizeOptions size;           ///< the size (size/size_field.h)
  CurveOptions curves;           ///< stage 1: corners, simplification, narrow islands (input/simplify.h)
  SubregionOptions subregions;   ///< stage 3: how many subregions each polygon part tries (pipeline/subregions.h)
  PolysquareMapOptions map;      ///< stages 2 and 4-6 (map.size and map.layout.corner_threshold_deg are set from
                                 ///< size and curves)
  RefineOptions refine;          ///< stage 8 templates at flattened boundary corners (before smoothing)
  SmoothOptions smooth;          ///< stage 7 smoothing
  LocalPatchOptions local_patch; ///< after smoothing, poor or folded quads are meshed again with a few rings
                                 ///< around them, before a repair round turns their whole subregion into a patch
                                 ///< (local_patch.size is set from size)
  RelaxValencesOptions relax_valences;  ///< after the local patches, the unstructured quads' valences are cleaned
                                        ///< up across their seams (refine/relax_valences.h)
  GateOptions gates;             ///< the quality a candidate must reach (pipeline/repair.h)
  RepairOptions repair;          ///< what happens to subregions that miss the gates (pipeline/repair.h)
  RunOptions run;                ///< threads, seed, progress
};

struct MeshResult {
  QuadMesh mesh;                    ///< quad_part = global subregion index (parts in order, then subregions)
  TriMesh background;               ///< all parts' background triangulations, when run.keep_partition is set
  std::vector<std::int32_t> background_part;  ///< #background triangles, global subregion index
  std::vector<PartMapStats> parts;  ///< per polygon part, in part order
  MeshReport report;                ///< options, timings, counts (quality is added by the caller's choice)
  Region region;                    ///< the region the mesh conforms to: the input with curves simplified
                                    ///< (MeshOptions::curves); the design invariants hold against it
};

/// Meshes every polygon part of a validated region (parts in parallel with oneTBB), assembles them in part
/// order, smooths, and checks the invariants. Throws InputError for bad options (size <= 0, too many quads) and
/// MeshingError naming every part that failed; never returns a mesh that breaks an invariant.
MeshResult mesh_region(const Region& region, const MeshOptions& options);

}  // namespace polysquare
