// The steps of finishing a candidate (finish_candidate.cpp): what every step reads and changes (FinishWork), and
// the steps the round loop, the round's verdict and the final measurement share.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "pipeline/candidate.h"
#include "polysquare/quality/quality.h"

namespace polysquare::pipeline {

// Where the candidate's time goes, summed over its repair rounds (the report's `stage_seconds`).
struct CandidateTimes {
  double map = 0.0, first_map = 0.0, refine = 0.0, smooth = 0.0, local = 0.0, relax = 0.0, measure = 0.0,
         repair_patches = 0.0;
  FirstMapReport first_map_of;  // the first round's map: partition, split rounds, joint maps

  CandidateSecondsReport report() const {
    return {first_map, first_map_of, map - first_map, repair_patches, refine, smooth, local, relax, measure};
  }
};

// f(), its wall time added to `total`.
template <typename F>
void timed(double& total, F&& f) {
  const auto t0 = std::chrono::steady_clock::now();
  f();
  total += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// A candidate being finished: its mesh and what the steps know of it, carried through the repair rounds.
struct FinishWork {
  FinishWork(const Region& region, const RegionPart& part, const MeshOptions& options,
             std::shared_ptr<const SizeField> field, Candidate& c)
      : region(region), options(options), field(std::move(field)), c(c), name(name_of(region, part)),
        smooth(options.smooth) {
    smooth.feature_tolerance = options.gates.feature_tolerance * options.size.h;
  }

  const Region& region;
  const MeshOptions& options;
  std::shared_ptr<const SizeField> field;  // graded runs: the size field, which patches follow (null: uniform)
  Candidate& c;  // its summary and smoothing figures are written as the steps go
  std::string name;
  SmoothOptions smooth;
  // A mapped subregion whose quads stay folded after smoothing (its map folds near a convoluted boundary) is
  // meshed again as a patch, with the subregions patched before; the rest of the part keeps its maps.
  Repairs repairs;
  PartMapResult r;
  std::vector<std::uint8_t> local_patched;  // #quads: made by a local patch (refine/local_patch.h)
  LocalPatchStats local_stats;
  QuadMetrics metrics;
  std::vector<std::uint8_t> pinned;
  // Folded quads, and unpinned ones outside the SJ or edge-ratio gate. The gates judge the quads the mesher controls: quads
  // pinned by an input corner sharper than the SJ gate are only counted (no conforming mesh does better).
  std::vector<std::uint8_t> poor;
  CandidateTimes times;
};

// The subregion of the quad q of a partitioned part's mesh, -1 otherwise.
int subregion_of(const FinishWork& w, std::size_t q);
// "in subregion s (mapped|patch)" for the quad q of a partitioned part's mesh, empty otherwise.
std::string in_subregion(const FinishWork& w, std::size_t q);

// Measures the quads (metrics, pinned, poor); whether any is poor.
bool measure(FinishWork& w);

// Local patches around the flagged quads, `rings` and `max_quads` as far as they may grow; then the mesh
// is smoothed near them and measured again. Returns whether poor quads remain.
bool patch_locally(FinishWork& w, const std::vector<std::uint8_t>& flagged, int rings, std::size_t max_quads);

// A valid quad far outside a gate (below half the SJ gate, above twice the edge-ratio gate) costs a small
// subregion its map, not a large one: a patch adds about one singular node per seven quads (delta_box 40 m:
// a 30,000-quad map was patched for one quad). In a map above options.keep_map_above_quads such quads get
// the widest local patches first and, if they stay, are kept and reported like the poor quads.
bool severe(const FinishWork& w, std::size_t q);
bool in_large_map(const FinishWork& w, std::size_t q);

// What a round left: the subregions to mesh again and why, and what the report's `repair_rounds` says of it.
struct RoundVerdict {
  std::map<int, std::string> bad;
  std::set<int> cracked_subregion;
  std::size_t first_folded = 0;  // the first folded quad, #quads when none is
  std::size_t poor_valid = 0;    // valid quads outside the gates that are kept
  std::size_t cracks = 0;        // quads beside a crack or overlapping another
};

// Judges the round's mesh and records it in the summary's `repair_rounds` (candidate_verdict.cpp).
RoundVerdict judge_round(FinishWork& w);

// After the last round: the invariants, with wider local patches around quads still folded first; throws
// MeshingError when they fail (candidate_verdict.cpp).
void check_final_invariants(FinishWork& w, std::size_t first_folded);

// The finished candidate measured: quality, structure, pinned quads, and the poor quads the gates accept; throws
// MeshingError when there are too many of them (candidate_quality.cpp).
void measure_finished(FinishWork& w);

// Cuts the quads of the subregions `cut` out of a finished part mesh and meshes each hole again as one patch
// (patch_in_place.cpp); false when a subregion keeps some of its quads.
bool patch_subregions_in_place(QuadMesh& mesh, const std::map<int, std::string>& cut, const MeshOptions& options,
                               const std::shared_ptr<const SizeField>& field, std::vector<std::uint8_t>& local_patched);

// #nodes: 1 for the nodes of the quads `changed(q)` and of `rings` rings of quads around them.
template <typename Changed>
std::vector<std::uint8_t> nodes_near(const QuadMesh& mesh, Changed changed, int rings) {
  std::vector<std::uint8_t> near(mesh.nodes.size(), 0);
  for (std::size_t q = 0; q < mesh.quads.size(); ++q)
    if (changed(q))
      for (std::int32_t v : mesh.quads[q]) near[static_cast<std::size_t>(v)] = 1;
  for (int ring = 0; ring < rings; ++ring) {
    std::vector<std::uint8_t> grown = near;
    for (const auto& x : mesh.quads)
      if (near[x[0]] || near[x[1]] || near[x[2]] || near[x[3]])
        for (std::int32_t v : x) grown[static_cast<std::size_t>(v)] = 1;
    near = std::move(grown);
  }
  return near;
}

// #subregions (of `count`): 1 for the subregions of the quads `changed(q)` and of the quads sharing a node with them.
template <typename Changed>
std::vector<std::uint8_t> subregions_touching(const QuadMesh& mesh, Changed changed, std::size_t count) {
  const std::vector<std::uint8_t> node = nodes_near(mesh, changed, 0);
  std::vector<std::uint8_t> touched(count, 0);
  for (std::size_t q = 0; q < mesh.quads.size(); ++q) {
    const auto& x = mesh.quads[q];
    const int s = q < mesh.quad_part.size() ? mesh.quad_part[q] : -1;
    if (s >= 0 && static_cast<std::size_t>(s) < count && (node[x[0]] || node[x[1]] || node[x[2]] || node[x[3]]))
      touched[static_cast<std::size_t>(s)] = 1;
  }
  return touched;
}

}  // namespace polysquare::pipeline
