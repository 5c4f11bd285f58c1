// The finishing sequence of a candidate: map (or patch in place), smooth, local patches, valence relaxation,
// wide patches in large maps, the round's verdict; repair rounds run the same sequence again until the verdict
// asks for no more, then the invariants and the gates.
#include "pipeline/finish_candidate.h"

#include <chrono>

#include "polysquare/core/error.h"
#include "polysquare/refine/local_patch.h"

namespace polysquare::pipeline {
namespace {

// After local patches or valence moves the mesh is smoothed again only near what changed and near quads still
// below this corner scaled Jacobian, with this many rings of quads around them: the rest was smoothed already,
// and searching it again cost as much as the first smoothing (5.5 s of a 209k-quad delta_water part at 40 m).
constexpr double kResmoothBelowSj = 0.5;
constexpr int kResmoothRings = 4;

// The mesh's smoothing again near the quads `changed`: the new quads' seams with the rest are smoothed from
// both sides.
template <typename Changed>
void smooth_near(FinishWork& w, Changed changed) {
  const std::vector<std::uint8_t> near = nodes_near(w.r.mesh, changed, kResmoothRings);
  timed(w.times.smooth, [&] { w.c.smooth = smooth_quads(w.r.mesh, w.smooth, &w.region, &near); });
}

// The subregions a round works on: 1 where this round changed the mesh, the rest kept from the round before;
// empty: everywhere (the round mapped the part again).
struct Scope {
  std::vector<std::uint8_t> subregions;
  bool everywhere() const { return subregions.empty(); }
};

bool in_scope(const FinishWork& w, const Scope& scope, std::size_t q) {
  if (scope.everywhere()) return true;
  const int s = subregion_of(w, q);
  return s >= 0 && scope.subregions[static_cast<std::size_t>(s)] != 0;
}

// Mapped subregions the round before asked to patch in place (`in_place`, with why) are cut out of the finished
// mesh and patched; the scope is the subregions that changed, everywhere when there were none or a patch failed
// (the round maps the part again).
Scope patch_in_place(FinishWork& w, std::map<int, std::string>& in_place) {
  Scope scope;
  if (in_place.empty()) return scope;
  bool done = false;
  timed(w.times.repair_patches, [&] { done = patch_subregions_in_place(w.r.mesh, in_place, w.options, w.field, w.local_patched); });
  if (done) {
    for (const auto& [s, why] : in_place) {
      SubregionStats& sr = w.r.stats.subregions[static_cast<std::size_t>(s)];
      sr.mapped = false;
      sr.reason = w.name + ": subregion " + std::to_string(s) + ": " + why + " (meshed again as a patch)";
    }
    auto cut = [&](std::size_t q) { return in_place.count(subregion_of(w, q)) > 0; };
    scope.subregions = subregions_touching(w.r.mesh, cut, w.r.stats.subregions.size());
    smooth_near(w, cut);
  }
  in_place.clear();
  return scope;
}

// The part mapped (with the repairs so far), its flat corners and feature loops refined, smoothed.
void map_and_smooth(FinishWork& w, const MakeMesh& make_mesh, int round) {
  PartMapResult& r = w.r;
  CandidateReport& summary = w.c.summary;
  timed(w.times.map, [&] { r = make_mesh(w.repairs); });
  if (round == 0) {
    w.times.first_map = w.times.map;
    w.times.first_map_of = {r.stats.seconds_partition, r.stats.split.seconds, r.stats.joint_maps,
                            r.stats.seconds_joint_maps};
  }
  RefineStats refined;
  timed(w.times.refine, [&] { refined = refine_flat_corners(r.mesh, w.options.refine); });
  if (r.stats.split.tested > 0 || r.stats.joint_splits > 0) summary.split = split_report(r.stats);
  summary.flat_corners = refined.flat_corners;
  summary.flat_corners_collapsed = refined.collapsed;
  RefineStats loops;
  timed(w.times.refine, [&] { loops = pillow_feature_loops(r.mesh, w.options.refine); });
  if (loops.feature_loops > 0) {
    summary.feature_loops_flat = loops.feature_loops;
    summary.feature_loops_pillowed = loops.pillowed;
  }
  timed(w.times.smooth, [&] { w.c.smooth = smooth_quads(r.mesh, w.smooth, &w.region); });
  w.local_patched.clear();
}

// First the neighbourhoods of the poor quads are meshed again (a few rings of quads, the rest of their
// subregions keeps its map), then smoothed near them.
void mend_poor_quads(FinishWork& w, const Scope& scope) {
  const MeshOptions& options = w.options;
  // The first pass also mends valid quads under local_patch.mend_below_sj where a patch does better.
  // Outside the scope the quads are the last round's, local patches tried already.
  measure(w);
  bool any_flagged = false;
  std::vector<std::uint8_t> flagged(w.poor.size(), 0);
  for (std::size_t q = 0; q < flagged.size(); ++q) {
    if (!in_scope(w, scope, q)) continue;
    flagged[q] = w.poor[q] ? 1 : !w.pinned[q] && w.metrics.sj[q] < options.local_patch.mend_below_sj ? 2 : 0;
    any_flagged = any_flagged || flagged[q];
  }
  auto poor_in_scope = [&] {
    std::vector<std::uint8_t> f(w.poor.size(), 0);
    for (std::size_t q = 0; q < f.size(); ++q) f[q] = w.poor[q] && in_scope(w, scope, q);
    return f;
  };
  if (any_flagged && options.local_patch.enabled &&
      patch_locally(w, flagged, options.local_patch.max_rings, options.local_patch.max_quads))
    patch_locally(w, poor_in_scope(), options.local_patch.second_rings, options.local_patch.second_max_quads);
}

// A round in place adds its scope's figures to the round before's (a mapped round's cover the part).
void add_relax_summary(std::optional<RelaxReport>& summary, const RelaxValencesStats& relaxed, const Scope& scope) {
  if (scope.everywhere() || !summary) summary.emplace();
  RelaxReport& rv = *summary;
  rv.quads += relaxed.region_quads;
  rv.flips += relaxed.flips;
  rv.collapses += relaxed.collapses;
  rv.energy_before += relaxed.energy_before;
  rv.energy_after += relaxed.energy_after;
}

// The unstructured quads (patched subregions, local patches) cleaned up across their seams, where each
// patch alone could only guess what its neighbours put at its boundary nodes.
void relax_unstructured_valences(FinishWork& w, const Scope& scope) {
  PartMapResult& r = w.r;
  std::vector<std::uint8_t> unstructured_quads(r.mesh.quads.size(), 0);
  for (std::size_t q = 0; q < unstructured_quads.size(); ++q) {
    const int s = subregion_of(w, q);
    unstructured_quads[q] = in_scope(w, scope, q) && ((q < w.local_patched.size() && w.local_patched[q]) ||
                                                      (s >= 0 && !r.stats.subregions[static_cast<std::size_t>(s)].mapped));
  }
  std::vector<std::size_t> origin;
  RelaxValencesStats relaxed;
  RelaxValencesOptions ro = w.options.relax_valences;
  ro.poor_sj = w.options.gates.min_scaled_jacobian;
  timed(w.times.relax, [&] { relaxed = relax_region_valences(r.mesh, unstructured_quads, ro, w.smooth, origin); });
  if (relaxed.region_quads > 0) add_relax_summary(w.c.summary.relax_valences, relaxed, scope);
  if (relaxed.kept) {
    if (!w.local_patched.empty()) {
      std::vector<std::uint8_t> moved(origin.size(), 0);
      for (std::size_t q = 0; q < origin.size(); ++q) moved[q] = origin[q] < w.local_patched.size() && w.local_patched[origin[q]];
      w.local_patched = std::move(moved);
    }
    // A piece alone kept its border nodes fixed: its seams with the mapped quads are smoothed now.
    smooth_near(w, [&](std::size_t q) { return q >= relaxed.first_kept_quad; });
    measure(w);
  }
}

// Quads far outside a gate in a large map get the widest local patches (see severe).
void patch_severe_in_large_maps(FinishWork& w, const Scope& scope) {
  if (!w.options.local_patch.enabled) return;
  std::vector<std::uint8_t> wide(w.metrics.sj.size(), 0);
  bool any = false;
  for (std::size_t q = 0; q < wide.size(); ++q) any |= (wide[q] = severe(w, q) && in_large_map(w, q) && in_scope(w, scope, q)) != 0;
  if (any) patch_locally(w, wide, w.options.local_patch.wide_rings, w.options.local_patch.wide_max_quads);
}

// Whether the round's verdict asks for another round: its bad subregions are added to the repairs (and, when
// they are all mapped ones, set to be patched in place).
bool schedule_repairs(FinishWork& w, const RoundVerdict& v, std::map<int, std::string>& in_place) {
  // Mapped subregions becoming patches are patched in place, unless a crack beside one asks for new nodes
  // on its interfaces; a patch to be rebuilt otherwise (matching, grown) needs the part mapped again.
  const bool in_place_only =
      w.options.repair.in_place && std::all_of(v.bad.begin(), v.bad.end(), [&](const auto& b) {
        return w.r.stats.subregions[static_cast<std::size_t>(b.first)].mapped && !v.cracked_subregion.count(b.first);
      });
  if (!w.repairs.add(v.bad, w.r.stats)) return false;
  if (in_place_only) in_place = v.bad;
  return true;
}

// The candidate's rounds: each one runs the same steps, on the whole part (mapped again) or on the subregions
// a repair in place changed, until no repair is left to try; then the invariants are checked.
void run_rounds(FinishWork& w, const MakeMesh& make_mesh) {
  // Mapped subregions a repair round cuts out of the finished mesh and patches in place, with why (empty: the
  // round maps the part again).
  std::map<int, std::string> in_place;
  for (int round = 0;; ++round) {
    const Scope scope = patch_in_place(w, in_place);
    if (scope.everywhere()) map_and_smooth(w, make_mesh, round);
    mend_poor_quads(w, scope);
    relax_unstructured_valences(w, scope);
    patch_severe_in_large_maps(w, scope);
    const RoundVerdict verdict = judge_round(w);
    if (round < w.options.repair.rounds && schedule_repairs(w, verdict, in_place)) continue;
    // The invariants are checked once the repair rounds are over (a round that continues never reads them).
    check_final_invariants(w, verdict.first_folded);
    return;
  }
}

}  // namespace

int subregion_of(const FinishWork& w, std::size_t q) {
  if (q >= w.r.mesh.quad_part.size()) return -1;
  const int s = w.r.mesh.quad_part[q];
  return s >= 0 && static_cast<std::size_t>(s) < w.r.stats.subregions.size() ? s : -1;
}

std::string in_subregion(const FinishWork& w, std::size_t q) {
  const int s = subregion_of(w, q);
  if (s < 0) return std::string();
  return " in subregion " + std::to_string(s) +
         (w.r.stats.subregions[static_cast<std::size_t>(s)].mapped ? " (mapped)" : " (patch)");
}

bool measure(FinishWork& w) {
  const MeshOptions& options = w.options;
  timed(w.times.measure, [&] {
    w.metrics = quad_metrics(w.r.mesh);
    w.pinned = quads_pinned_by_sharp_input(w.r.mesh, options.gates.min_scaled_jacobian, options.size.h);
  });
  w.poor.assign(w.metrics.sj.size(), 0);
  bool any = false;
  for (std::size_t q = 0; q < w.metrics.sj.size(); ++q) {
    w.poor[q] = w.metrics.sj[q] <= 0.0 || (!w.pinned[q] && (w.metrics.sj[q] < options.gates.min_scaled_jacobian ||
                                                            w.metrics.edge_ratio[q] > options.gates.max_edge_ratio));
    any = any || w.poor[q];
  }
  return any;
}

bool patch_locally(FinishWork& w, const std::vector<std::uint8_t>& flagged, int rings, std::size_t max_quads) {
  LocalPatchOptions lp = w.options.local_patch;
  lp.size = w.options.size.h;
  lp.size_field = w.field;
  lp.max_rings = rings;
  lp.max_quads = max_quads;
  LocalPatchStats done;
  timed(w.times.local, [&] { done = remesh_poor_quads(w.r.mesh, flagged, lp, w.local_patched); });
  w.local_stats.clusters += done.clusters;
  w.local_stats.patched += done.patched;
  w.local_stats.quads_added += done.quads_added;
  w.local_stats.quads_removed += done.quads_removed;
  if (done.patched == 0) return true;  // the flagged quads are as they were
  smooth_near(w, [&](std::size_t q) {
    return w.local_patched[q] != 0 || quad_min_corner_sj(w.r.mesh, q) < kResmoothBelowSj;
  });
  return measure(w);
}

bool severe(const FinishWork& w, std::size_t q) {
  const MeshOptions& options = w.options;
  return w.metrics.sj[q] > 0.0 && !w.pinned[q] &&
         (w.metrics.sj[q] < 0.5 * options.gates.min_scaled_jacobian ||
          w.metrics.edge_ratio[q] > 2.0 * options.gates.max_edge_ratio);
}

bool in_large_map(const FinishWork& w, std::size_t q) {
  const int s = subregion_of(w, q);
  return s >= 0 && w.r.stats.subregions[static_cast<std::size_t>(s)].mapped &&
         w.r.stats.subregions[static_cast<std::size_t>(s)].quads > w.options.repair.keep_map_above_quads;
}

Candidate finish_candidate(const Region& region, const RegionPart& part, const MeshOptions& options,
                           std::shared_ptr<const SizeField> field, CandidateReport summary, const MakeMesh& make_mesh) {
  Candidate c;
  c.summary = std::move(summary);
  // Wall time of the candidate, map to gates, so the report shows where a part's search spent its time.
  const auto t_start = std::chrono::steady_clock::now();
  try {
    FinishWork w(region, part, options, std::move(field), c);
    run_rounds(w, make_mesh);
    c.summary.stage_seconds = w.times.report();
    measure_finished(w);
    c.result = std::move(w.r);
  } catch (const MeshingError& e) {
    c.error = e.what();
    c.summary.error = c.error;
  }
  c.summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  return c;
}

}  // namespace polysquare::pipeline
