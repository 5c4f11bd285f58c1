// The stages of mesh_region, in its order, each with its input and its result: simplify the region's curves
// (mesh_region.cpp), split it into polygon parts, mesh each part (mesh_parts.cpp: the candidate search),
// assemble the parts' meshes (assemble.cpp), and report (region_report.cpp).
#pragma once

#include <chrono>
#include <memory>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "polysquare/input/simplify.h"
#include "polysquare/input/snap_points.h"
#include "polysquare/pipeline/mesh_region.h"
#include "polysquare/pipeline/mesh_report.h"

namespace polysquare::pipeline {

// The run's wall times, kept in this one place: the report's `seconds`.
struct RegionTimes {
  std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
  double parts = 0.0;  // from the start through meshing the parts (simplify and split included)

  double elapsed() const { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); }
};

// Stage "simplify": the region the mesh follows, and what simplifying it changed.
struct SimplifiedRegion {
  Region region;
  SimplifyStats stats;
  SnapStats end_snaps;
  std::vector<DroppedCurve> dropped_curves;
};

// Stage "size": a graded run's size field over the simplified region (none on a uniform run).
struct SizedRegion {
  std::shared_ptr<const SizeField> field;
  SizeFieldStats stats;
};

// Stage "split into parts": the polygon parts to mesh, and those left out as smaller than one element.
struct RegionParts {
  std::vector<RegionPart> parts;
  std::vector<DroppedPartReport> dropped;
};

// Stage "mesh parts": one polygon part's outcome of the candidate search.
struct PartOutcome {
  std::optional<PartMapResult> result;  // the best candidate's mesh
  std::string error;                    // why no candidate meshed the part (then result is empty)
  std::vector<CandidateReport> tried;  // every candidate's summary, the chosen one marked
  SmoothStats smoothed;
  double structured = 0.0;     // fraction of the part's quads from poly-square maps
  std::size_t poor_quads = 0;  // quads accepted outside the gates (max_poor_fraction)
};

// Meshes every part (in parallel, or shared among processes) with the search over candidates; results in part
// order, so the output does not depend on the thread count. Progress: one "mesh parts" item a part.
std::vector<PartOutcome> mesh_parts(const Region& region, const std::vector<RegionPart>& parts,
                                    const PolysquareMapOptions& map, const MeshOptions& options,
                                    ProgressReporter& progress);

// Throws MeshingError naming every part that failed.
void check_every_part_meshed(const std::vector<PartOutcome>& parts);

// Stage "assemble": the parts' meshes in part order as one mesh (MeshResult's mesh, background, background_part
// and parts); subregion indices are made global.
MeshResult assemble_parts(const std::vector<PartOutcome>& parts, const Region& region, bool keep_partition);

// Everything the report is written from.
struct ReportInput {
  const Region& region;  // the input, before simplification
  const MeshOptions& options;
  const PolysquareMapOptions& map;
  const SimplifiedRegion& simplified;
  const SizedRegion& sized;
  const RegionParts& parts;
  const std::vector<PartOutcome>& outcomes;
  const MeshResult& result;  // assembled (mesh and parts)
  const RegionTimes& times;
};

// Stage "report": MeshResult::report (region_report.cpp).
MeshReport region_report(const ReportInput& in);

}  // namespace polysquare::pipeline
