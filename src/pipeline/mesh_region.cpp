// The pipeline's stage order: check options, simplify, split into parts, mesh the parts (the candidate search,
// mesh_parts.cpp), assemble, check the invariants, report. Each stage is a function with its input and its
// result (pipeline/region_stages.h).
#include "polysquare/pipeline/mesh_region.h"

#include <oneapi/tbb/global_control.h>
#include <oneapi/tbb/info.h>

#include <algorithm>
#include <memory>

#include "pipeline/region_stages.h"
#include "polysquare/core/error.h"
#include "polysquare/input/chord_clearance.h"
#include "polysquare/pipeline/check_options.h"
#include "polysquare/pipeline/invariants.h"
#include "polysquare/triangulate/background_triangulation.h"

namespace polysquare {
namespace pipeline {
namespace {

// Curves far finer than h (coastlines) are simplified first; the mesh then follows the simplified curves and
// the quality report measures the distance to the original ones.
SimplifiedRegion simplify_curves(const Region& region, const MeshOptions& options) {
  SimplifiedRegion out;
  Region& simplified = out.region;
  simplified = region;
  if (options.simplify <= 0.0) {
    // Unsimplified rings are still meshed with chords: where one could cut across another curve, ring vertices
    // become nodes (as simplify_region does last), so that parts and islands close to each other do not overlap.
    out.stats.chord_pins = pin_chords_clear_of_curves(simplified, options.size).size();
    return out;
  }
  // Islands and faces between curves narrower than the size hold no quad of that size: their curves go first.
  out.dropped_curves = drop_narrow_islands(simplified, options.min_island_width * options.size);
  for (DroppedCurve& d : collapse_narrow_faces(simplified, options.min_island_width * options.size))
    out.dropped_curves.push_back(d);
  for (DroppedCurve& d : open_narrow_wedges(simplified, options.min_island_width * options.size))
    out.dropped_curves.push_back(d);
  // Feature curves that end a small fraction of the size short of the boundary or of another curve (crossing
  // points computed in another projection) are joined to it first: a gap far below h cannot be meshed, and a
  // curve that reaches the boundary splits the part into feature faces for the partition.
  const Box2 box = region.bounding_box();
  out.end_snaps = snap_near_coincident(simplified, 0.1 * options.size / std::max(box.diagonal(), 1e-300), nullptr);
  SimplifyOptions so;
  so.min_area = (options.simplify * options.size) * (options.simplify * options.size);
  so.max_distance = options.size;  // the simplified curves stay within h of the input
  so.max_segment = options.size;   // and are coarsened to the size, not beyond
  so.smooth_distance = options.smooth_curves * options.size;
  out.stats = simplify_region(simplified, so);
  return out;
}

// The map options of this run: its size, corner threshold, seed, and memos its repair rounds share.
PolysquareMapOptions run_map_options(const MeshOptions& options) {
  PolysquareMapOptions map = options.map;
  map.deform.memo = std::make_shared<DeformMemo>();  // this run's solved deformations (repair rounds repeat them)
  map.quantize.memo = std::make_shared<QuantizeMemo>();  // and its layouts quantized alone
  map.size = options.size;
  map.layout.corner_threshold_deg = options.corner_threshold_deg;
  map.keep_partition = options.keep_partition;
  map.partition.seed = options.seed;
  return map;
}

// Polygon parts smaller than one element (islets, slivers of a coastline at this size) cannot hold a quad:
// with drop_small_parts they are left out and listed in the report, never silently.
RegionParts split_parts(const Region& work, const MeshOptions& options, const std::string& src) {
  RegionParts out;
  for (RegionPart& p : split_into_parts(work)) {
    const double a = part_area(work, p);
    if (options.drop_small_parts && a < options.size * options.size) {
      const Vec2 at = work.rings[static_cast<std::size_t>(p.rings.front())].points.front();
      out.dropped.push_back({p.part, a, at});
      continue;
    }
    out.parts.push_back(std::move(p));
  }
  if (out.parts.empty())
    throw MeshingError(src + ": every polygon part is smaller than one element (size^2 = " +
                       std::to_string(options.size * options.size) + "); use a smaller size");
  return out;
}

std::size_t thread_limit(const MeshOptions& options) {
  const int threads = options.threads > 0 ? options.threads : static_cast<int>(oneapi::tbb::info::default_concurrency());
  return static_cast<std::size_t>(threads);
}

void check_assembled(const QuadMesh& mesh, const std::string& src) {
  const InvariantReport inv = check_invariants(mesh);
  if (!inv.ok())
    throw MeshingError(src + ": the assembled mesh breaks an invariant (" + inv.first_problem + "); nothing was written");
}

}  // namespace
}  // namespace pipeline

MeshResult mesh_region(const Region& region, const MeshOptions& options) {
  using namespace pipeline;
  const std::string src = region.source.empty() ? std::string("region") : region.source;
  check_mesh_options(options);      // NaN gates and out-of-range values, named by their flag
  check_mesh_size(region, options);  // size against the region's extent and the quad budget
  RegionTimes times;
  ProgressReporter progress(options.progress);

  progress.start("simplify");
  SimplifiedRegion simplified = simplify_curves(region, options);
  progress.finish("simplify");

  const PolysquareMapOptions map = run_map_options(options);
  const RegionParts parts = split_parts(simplified.region, options, src);

  // One thread limit for every parallel stage (parts, candidates, subregions, colours in smoothing).
  const oneapi::tbb::global_control limit(oneapi::tbb::global_control::max_allowed_parallelism, thread_limit(options));
  progress.start("mesh parts");
  // Parts are independent: mesh them in parallel; results land in part order, so the output does not depend
  // on the thread count. A failure in one part is recorded and reported with all the others, never dropped.
  const std::vector<PartOutcome> meshed = mesh_parts(simplified.region, parts.parts, map, options, progress);
  check_every_part_meshed(meshed);
  times.parts = times.elapsed();
  progress.finish("mesh parts");

  progress.start("assemble");
  MeshResult out = assemble_parts(meshed, region, options.keep_partition);
  check_assembled(out.mesh, src);
  out.report = region_report({region, options, map, simplified, parts, meshed, out, times});
  out.region = std::move(simplified.region);
  progress.finish("assemble");
  return out;
}

}  // namespace polysquare
