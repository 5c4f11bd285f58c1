// The verdict on a candidate's round (which subregions are meshed again, and why) and, after the last round, on
// its invariants.
#include <algorithm>
#include <cctype>
#include <utility>

#include "pipeline/finish_candidate.h"
#include "polysquare/core/error.h"
#include "polysquare/pipeline/invariants.h"

namespace polysquare::pipeline {
namespace {

// Subregion -> (worst gate ratio, poor valid quads) of the mapped subregions whose valid quads outside the gates
// the budget may accept.
using PoorIn = std::map<int, std::pair<double, std::size_t>>;

// The round's folded, cracked and poor quads: the subregions they send to be meshed again (v.bad), the valid
// poor quads kept so far (v.poor_valid) and where those are (`poor_in`).
void find_bad_quads(const FinishWork& w, const std::vector<std::uint8_t>& cracked, RoundVerdict& v, PoorIn& poor_in) {
  const MeshOptions& options = w.options;
  const QuadMetrics& metrics = w.metrics;
  const PartMapResult& r = w.r;
  v.first_folded = metrics.sj.size();
  for (std::size_t q = 0; q < metrics.sj.size(); ++q) {
    const bool folded = metrics.sj[q] <= 0.0;
    // Below the untangling's target a quad counts as folded there, and no solver can use it: it costs even a
    // large map (delta_box 20 m kept quads of SJ 1e-9 beside a feature crossing).
    const bool degenerate = !folded && !w.pinned[q] && metrics.sj[q] < options.smooth.untangle.target_sj;
    if (folded && v.first_folded == metrics.sj.size()) v.first_folded = q;
    const int s = subregion_of(w, q);
    if (cracked[q] && s >= 0) v.cracked_subregion.insert(s);
    if (cracked[q] && s >= 0)
      v.bad.emplace(s, (cracked[q] == 2 ? "its quads overlap others at " : "its quads do not share their nodes with a neighbour's (a crack) at ") +
                           at_text(r.mesh.nodes[r.mesh.quads[q][0]]));
    if (!w.poor[q]) continue;
    // Far outside a gate (severe) counts as folded outside large maps: the budget is for quads just outside,
    // not for near-degenerate ones a patch can mend. A patch is not rebuilt for a valid quad however poor:
    // its given nodes (the input's, the neighbours' interface nodes) fix that quad's shape for any
    // construction, and each rebuild re-maps the whole part.
    const bool in_patch = s >= 0 && !r.stats.subregions[static_cast<std::size_t>(s)].mapped;
    if (folded || (!in_patch && ((severe(w, q) && !in_large_map(w, q)) || degenerate))) {
      if (s >= 0)
        v.bad.emplace(s, "its map left a " +
                             std::string(folded ? "folded" : degenerate ? "degenerate (SJ " + std::to_string(metrics.sj[q]) + ")" : "near-degenerate") +
                             " quad at " + at_text(r.mesh.nodes[r.mesh.quads[q][0]]) + " after smoothing and local patches");
      if (folded) continue;
    }
    ++v.poor_valid;
    if (s < 0 || in_patch || in_large_map(w, q)) continue;
    // Below 1 the quad fails a gate; the smaller, the further.
    const double ratio =
        std::min(options.gates.min_scaled_jacobian > 0 ? metrics.sj[q] / options.gates.min_scaled_jacobian : 1.0,
                 options.gates.max_edge_ratio / metrics.edge_ratio[q]);
    auto [it, fresh] = poor_in.try_emplace(s, ratio, 0);
    it->second.first = std::min(it->second.first, ratio);
    it->second.second++;
  }
}

// Beyond the max_poor_fraction budget, the subregions holding valid poor quads are meshed again, worst first.
void spend_poor_budget(const FinishWork& w, PoorIn& poor_in, RoundVerdict& v) {
  std::vector<std::pair<double, int>> worst_first;
  for (const auto& [s, e] : poor_in) {
    if (v.bad.count(s)) v.poor_valid -= e.second;
    else worst_first.push_back({e.first, s});
  }
  std::sort(worst_first.begin(), worst_first.end());
  const double budget = w.options.gates.max_poor_fraction * static_cast<double>(w.metrics.sj.size());
  for (const auto& [ratio, s] : worst_first) {
    if (static_cast<double>(v.poor_valid) <= budget) break;
    v.bad.emplace(s, "its map left " + std::to_string(poor_in[s].second) +
                         " quads below --min-sj or above --max-edge-ratio after smoothing and local patches, beyond "
                         "the --max-poor-fraction budget");
    v.poor_valid -= poor_in[s].second;
  }
}

// How far a refused candidate got: its mapped and patched subregions, and why the patched ones are.
RefusedMeshReport refused_mesh_report(const FinishWork& w) {
  std::size_t mapped = 0, mapped_quads = 0, all_quads = 0;
  std::map<std::string, int> reasons;
  for (const SubregionStats& sr : w.r.stats.subregions) {
    all_quads += sr.quads;
    if (sr.mapped) { ++mapped; mapped_quads += sr.quads; continue; }
    std::string why;  // numbers and coordinates blanked, so that alike reasons count together
    for (char ch : sr.reason.substr(std::min(sr.reason.size(), w.name.size())))
      if (!(std::isdigit(static_cast<unsigned char>(ch)) || ch == '.' || ch == '-') || why.empty() || why.back() != '#')
        why += std::isdigit(static_cast<unsigned char>(ch)) ? '#' : ch;
    reasons[why.substr(0, 140)]++;
  }
  return {w.r.stats.subregions.size(), mapped, all_quads ? double(mapped_quads) / double(all_quads) : 0.0,
          std::move(reasons)};
}

}  // namespace

RoundVerdict judge_round(FinishWork& w) {
  RoundVerdict v;
  // Quads beside a crack (pieces that do not share their nodes) count as folded: their subregions are meshed
  // again, instead of the whole candidate failing the invariants after the last round.
  std::vector<std::uint8_t> cracked = quads_beside_cracks(w.r.mesh);
  // So do valid quads that overlap others (2) in graded meshes: 40 such pairs with transition rows, 132 without,
  // sent a graded delta_box whole to the unstructured fallback. In uniform meshes a round's overlaps are left to
  // the final checks: marked in every round, they sent subregions of a uniform coast to patches that local
  // patches mend in place.
  if (w.options.size.graded())
    for (std::uint32_t q : find_overlapping_quads(w.r.mesh).quads) cracked[q] = 2;
  v.cracks = cracked.size() - static_cast<std::size_t>(std::count(cracked.begin(), cracked.end(), std::uint8_t{0}));
  // Subregions still holding a folded quad are meshed again (a mapped one as a patch, a patch by the matching
  // construction); the rest of the part keeps its maps. Valid quads outside the gates cost a subregion its map
  // only beyond the max_poor_fraction budget, worst subregion first: a 400-quad map is not traded for a
  // quad at SJ 0.18.
  PoorIn poor_in;
  find_bad_quads(w, cracked, v, poor_in);
  spend_poor_budget(w, poor_in, v);
  std::size_t folded = 0;
  for (double s : w.metrics.sj) folded += s <= 0.0;
  RepairRoundReport round{folded, v.cracks, v.poor_valid, {}};
  for (const auto& b : v.bad) round.remeshed.push_back(b.first);
  if (!w.c.summary.repair_rounds) w.c.summary.repair_rounds.emplace();
  w.c.summary.repair_rounds->push_back(std::move(round));
  return v;
}

void check_final_invariants(FinishWork& w, std::size_t first_folded) {
  const QuadMetrics& metrics = w.metrics;
  InvariantReport inv = check_invariants(w.r.mesh);
  if (!inv.ok() && first_folded < metrics.sj.size() && w.options.local_patch.enabled) {
    // Quads still folded after every repair round: wider local patches around them alone, so that a few
    // folded quads do not send the whole part to the unstructured fallback.
    std::vector<std::uint8_t> folded(metrics.sj.size(), 0);
    for (std::size_t q = 0; q < metrics.sj.size(); ++q) folded[q] = metrics.sj[q] <= 0.0;
    patch_locally(w, folded, w.options.local_patch.wide_rings, w.options.local_patch.wide_max_quads);
    inv = check_invariants(w.r.mesh);
    first_folded = metrics.sj.size();
    for (std::size_t q = 0; q < metrics.sj.size() && first_folded == metrics.sj.size(); ++q)
      if (metrics.sj[q] <= 0.0) first_folded = q;
  }
  if (!inv.ok() && !w.r.stats.subregions.empty()) w.c.summary.refused_mesh = refused_mesh_report(w);
  if (!inv.ok())
    throw MeshingError(w.name + ": the mesh breaks an invariant (" + inv.first_problem +
                       (first_folded < metrics.sj.size() ? "; first folded quad" + in_subregion(w, first_folded) : "") +
                       ")");
}

}  // namespace polysquare::pipeline
