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
  if (options.curves.simplify <= 0.0) {
    // Unsimplified rings are still meshed with chords: where one could cut across another curve, ring vertices
    // become nodes (as simplify_region does last), so that parts and islands close to each other do not overlap.
    out.stats.chord_pins = pin_chords_clear_of_curves(simplified, options.size.h).size();
    return out;
  }
  // Islands and faces between curves narrower than the size hold no quad of that size: their curves go first.
  out.dropped_curves = drop_narrow_islands(simplified, options.curves.min_island_width * options.size.h);
  for (DroppedCurve& d : collapse_narrow_faces(simplified, options.curves.min_island_width * options.size.h))
    out.dropped_curves.push_back(d);
  for (DroppedCurve& d : open_narrow_wedges(simplified, options.curves.min_island_width * options.size.h))
    out.dropped_curves.push_back(d);
  // Feature curves that end a small fraction of the size short of the boundary or of another curve (crossing
  // points computed in another projection) are joined to it first: a gap far below h cannot be meshed, and a
  // curve that reaches the boundary splits the part into feature faces for the partition.
  const Box2 box = region.bounding_box();
  out.end_snaps = snap_near_coincident(simplified, 0.1 * options.size.h / std::max(box.diagonal(), 1e-300), nullptr);
  SimplifyOptions so;
  so.min_area = (options.curves.simplify * options.size.h) * (options.curves.simplify * options.size.h);
  so.max_distance = options.size.h;  // the simplified curves stay within h of the input
  so.max_segment = options.size.h;   // and are coarsened to the size, not beyond
  so.smooth_distance = options.curves.smooth_curves * options.size.h;
  out.stats = simplify_region(simplified, so);
  return out;
}

// A graded run's size field, built on the simplified curves; refused before meshing when it needs more quads
// than the limit.
SizedRegion size_region(const Region& simplified, const MeshOptions& options, const std::string& src) {
  SizedRegion out;
  if (!options.size.graded()) return out;
  SizeFieldResult made = make_size_field(simplified, options.size.field);
  out.stats = made.stats;
  check_field_estimate(made.stats.estimated_quads, options, src);
  out.field = std::make_shared<const SizeField>(std::move(made.field));
  return out;
}

// The map options of this run: its size (and field), corner threshold, seed, and memos its repair rounds share.
PolysquareMapOptions run_map_options(const MeshOptions& options, const SizedRegion& sized) {
  PolysquareMapOptions map = options.map;
  map.size_field = sized.field;
  map.partition.size_field = sized.field;
  map.partition.size_ref = options.size.h;
  map.deform.memo = std::make_shared<DeformMemo>();  // this run's solved deformations (repair rounds repeat them)
  map.quantize.memo = std::make_shared<QuantizeMemo>();  // and its layouts quantized alone
  map.quantize.graded = sized.field != nullptr;
  map.size = options.size.h;
  map.layout.corner_threshold_deg = options.curves.corner_threshold_deg;
  map.keep_partition = options.run.keep_partition;
  map.partition.seed = options.run.seed;
  return map;
}

// Polygon parts smaller than one element (islets, slivers of a coastline at this size) cannot hold a quad:
// with drop_small_parts they are left out and listed in the report, never silently.
RegionParts split_parts(const Region& work, const MeshOptions& options, const std::string& src) {
  RegionParts out;
  for (RegionPart& p : split_into_parts(work)) {
    const double a = part_area(work, p);
    if (options.curves.drop_small_parts && a < options.size.h * options.size.h) {
      const Vec2 at = work.rings[static_cast<std::size_t>(p.rings.front())].points.front();
      out.dropped.push_back({p.part, a, at});
      continue;
    }
    out.parts.push_back(std::move(p));
  }
  if (out.parts.empty())  // a size problem (check_mesh_size says so before simplifying, here after)
    throw InputError(src + ": every polygon part is smaller than one element once its curves are simplified (" +
                     std::string(options.size.graded() ? "--size-min " : "--size ") + short_number(options.size.h) +
                     ", size^2 = " + short_number(options.size.h * options.size.h) + "); use a smaller size");
  return out;
}

std::size_t thread_limit(const MeshOptions& options) {
  const int threads =
      options.run.threads > 0 ? options.run.threads : static_cast<int>(oneapi::tbb::info::default_concurrency());
  return static_cast<std::size_t>(threads);
}

void check_assembled(const QuadMesh& mesh, const std::string& src) {
  const InvariantReport inv = check_invariants(mesh);
  if (!inv.ok())
    throw MeshingError(src + ": the assembled mesh breaks an invariant (" + inv.first_problem + "); nothing was written");
}

}  // namespace
}  // namespace pipeline

MeshResult mesh_region(const Region& region, const MeshOptions& given) {
  using namespace pipeline;
  const std::string src = region.source.empty() ? std::string("region") : region.source;
  check_mesh_options(given);      // NaN gates and out-of-range values, named by their flag
  check_mesh_size(region, given);  // size against the region's extent and the quad budget
  const MeshOptions options = resolve_sizes(given);  // graded: size.h is the least size
  RegionTimes times;
  ProgressReporter progress(options.run.progress);

  progress.start("simplify");
  SimplifiedRegion simplified = simplify_curves(region, options);
  progress.finish("simplify");

  if (options.size.graded()) progress.start("size field");
  const SizedRegion sized = size_region(simplified.region, options, src);
  if (options.size.graded()) progress.finish("size field");

  const PolysquareMapOptions map = run_map_options(options, sized);
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
  MeshResult out = assemble_parts(meshed, region, options.run.keep_partition);
  check_assembled(out.mesh, src);
  out.report = region_report({region, options, map, simplified, sized, parts, meshed, out, times});
  out.region = std::move(simplified.region);
  progress.finish("assemble");
  return out;
}

}  // namespace polysquare
