// Stage "mesh parts": each polygon part meshed by the search over its candidates (candidate.h), the best one
// kept; parts in parallel, or divided among processes.
#include <algorithm>
#include <sstream>

#include <oneapi/tbb/parallel_for.h>

#include "pipeline/candidate.h"
#include "pipeline/region_stages.h"
#include "polysquare/core/error.h"
#include "polysquare/map/map_bytes.h"
#include "polysquare/triangulate/background_triangulation.h"

namespace polysquare::pipeline {
namespace {

// f(i) for i in [first, last): in parallel, or in order when several processes mesh together (`in_order`):
// their shared loops (core/work_sharing.h) must come in the same order on every process, from the thread that
// started them.
template <class F>
void for_each_task(bool in_order, std::size_t first, std::size_t last, F&& f) {
  if (in_order) {
    for (std::size_t i = first; i < last; ++i) f(i);
    return;
  }
  oneapi::tbb::parallel_for(first, last, std::forward<F>(f));
}

bool several_processes(const PolysquareMapOptions& map) { return map.sharing && map.sharing->processes() > 1; }

// A part's candidates so far, in the order they were meshed, and the best valid one (-1: none yet).
struct CandidateSearch {
  std::vector<CandidateSpec> ks;
  std::vector<Candidate> cands;
  int best = -1;
};

// Meshes every candidate of a round (in parallel, or shared among processes) and keeps the best valid one so far.
void mesh_round(CandidateSearch& search, const std::vector<CandidateSpec>& round, const Region& work,
                const RegionPart& part, const PolysquareMapOptions& map, const MeshOptions& options,
                std::vector<CandidateReport>& tried) {
  std::vector<CandidateSpec>& ks = search.ks;
  std::vector<Candidate>& cands = search.cands;
  const std::size_t first = cands.size();
  ks.insert(ks.end(), round.begin(), round.end());
  cands.resize(ks.size());
  // Every candidate of a round is meshed, smoothed and measured; the best valid one wins, so the choice
  // depends only on the input and the options, never on timing.
  const bool share_candidates = several_processes(map) && ks.size() - first > 1;
  auto mesh_candidate = [&](std::size_t c) {
    PolysquareMapOptions part_map = map;
    if (share_candidates) part_map.sharing = nullptr;
    part_map.partition.parts = ks[c].subregions;
    part_map.layout.straight_interfaces = !ks[c].bend_interfaces;
    if (!ks[c].split) part_map.split_rounds = 0;
    if (ks[c].fine) part_map.parameterization_ratio = options.subregions.fine_parameterization_ratio;
    cands[c] = try_candidate(work, part, part_map, options);
  };
  if (share_candidates)
    shared_for(map.sharing.get(), ks.size() - first, {}, "candidates", [&](std::size_t i) { mesh_candidate(first + i); },
               [&](std::size_t i, ByteWriter& w) { put_bytes(w, cands[first + i]); },
               [&](std::size_t i, ByteReader& r) { get_bytes(r, cands[first + i]); });
  else
    for_each_task(several_processes(map), first, ks.size(), mesh_candidate);
  for (std::size_t c = first; c < cands.size(); ++c) {
    tried.push_back(cands[c].summary);
    if (cands[c].error.empty() && (search.best < 0 || cands[c].better_than(cands[static_cast<std::size_t>(search.best)])))
      search.best = static_cast<int>(c);
  }
}

// Why no candidate meshed the part. Candidates that failed for the same reason (a triangle budget no candidate
// fits in) are named together before it, so the message says each reason once.
std::string failure_message(const CandidateSearch& search) {
  const std::vector<CandidateSpec>& ks = search.ks;
  const std::vector<Candidate>& cands = search.cands;
  std::vector<std::pair<std::string, std::string>> reasons;  // error -> the candidates it sank
  for (std::size_t c = 0; c < cands.size(); ++c) {
    const std::string label =
        ks[c].subregions == 0 ? std::string("the split-triangle fallback")
                              : (ks[c].subregions == 1 ? std::string("one poly-square")
                                                       : "with " + std::to_string(ks[c].subregions) + " subregions") +
                                    (ks[c].bend_interfaces ? " (bent interfaces)" : "") +
                                    (ks[c].fine ? " (fine background)" : "");
    auto it = std::find_if(reasons.begin(), reasons.end(), [&](const auto& r) { return r.first == cands[c].error; });
    if (it == reasons.end()) reasons.push_back({cands[c].error, label});
    else it->second += ", " + label;
  }
  std::string all;
  for (const auto& [error, labels] : reasons)
    all += (all.empty() ? "" : "; ") + (cands.size() <= 1 ? std::string() : labels + ": ") + error;
  return all;
}

// One part: its candidates round by round, the split-triangle fallback when none meshed it, and the best kept.
PartOutcome mesh_part(const Region& work, const RegionPart& part, const PolysquareMapOptions& map,
                      const MeshOptions& options) {
  PartOutcome out;
  CandidateSearch search;
  for (const std::vector<CandidateSpec>& round : candidate_rounds(work, part, options, map)) {
    const bool retry = std::none_of(round.begin(), round.end(), [](const CandidateSpec& c) { return c.split; });
    if (retry && search.best >= 0) continue;
    mesh_round(search, round, work, part, map, options, out.tried);
    // A later round is meshed while the best mesh so far holds unstructured patches nobody asked for; the
    // best of all wins.
    const Candidate& b = search.cands[static_cast<std::size_t>(std::max(search.best, 0))];
    if (search.best >= 0 && b.poor_quads == 0 && (b.structured >= 1.0 || !options.map.patch_subregions.empty()))
      break;
  }
  if (search.best < 0 && options.repair.split_fallback) {
    search.cands.push_back(try_split_fallback(work, part, options));
    search.ks.push_back({0, false});
    out.tried.push_back(search.cands.back().summary);
    if (search.cands.back().error.empty()) search.best = static_cast<int>(search.cands.size()) - 1;
  }
  if (search.best < 0) {
    out.error = failure_message(search);
    return out;
  }
  Candidate& best = search.cands[static_cast<std::size_t>(search.best)];
  out.tried[static_cast<std::size_t>(search.best)].chosen = true;
  out.smoothed = best.smooth;
  out.structured = best.structured;
  out.poor_quads = best.poor_quads;
  out.result = std::move(best.result);
  return out;
}

// A part meshed by another process, copied as it is.
void put_bytes(ByteWriter& w, const PartOutcome& p) {
  w.put(static_cast<std::uint8_t>(p.result.has_value()));
  if (p.result) put_bytes(w, *p.result);
  w.put(p.error), w.put(nlohmann::json(p.tried).dump()), w.put(p.smoothed), w.put(p.structured), w.put(p.poor_quads);
}

void get_bytes(ByteReader& r, PartOutcome& p) {
  std::uint8_t has = 0;
  r.get(has);
  if (has) get_bytes(r, p.result.emplace());
  std::string text;
  r.get(p.error), r.get(text), r.get(p.smoothed), r.get(p.structured), r.get(p.poor_quads);
  p.tried = nlohmann::json::parse(text).get<std::vector<CandidateReport>>();
}

}  // namespace

std::vector<PartOutcome> mesh_parts(const Region& work, const std::vector<RegionPart>& parts,
                                    const PolysquareMapOptions& map, const MeshOptions& options,
                                    ProgressReporter& progress) {
  std::vector<PartOutcome> out(parts.size());
  auto one_part = [&](std::size_t k, const PolysquareMapOptions& part_map) {
    const ProgressReporter::Item part_done(progress, "mesh parts", parts.size());
    out[k] = mesh_part(work, parts[k], part_map, options);
  };
  // Several processes (PolysquareMapOptions::sharing) divide among them the parts when there are several, else
  // the candidates of a round when there are several, else the subregions of a map; each process meshes what it
  // was given with its threads alone, and the results are copied to all of them.
  if (several_processes(map) && parts.size() > 1) {
    PolysquareMapOptions alone = map;
    alone.sharing = nullptr;
    std::vector<double> cost(parts.size());
    for (std::size_t k = 0; k < parts.size(); ++k) cost[k] = part_area(work, parts[k]);
    shared_for(map.sharing.get(), parts.size(), cost, "parts", [&](std::size_t k) { one_part(k, alone); },
               [&](std::size_t k, ByteWriter& w) { put_bytes(w, out[k]); },
               [&](std::size_t k, ByteReader& r) { get_bytes(r, out[k]); });
  } else {
    for_each_task(several_processes(map), std::size_t{0}, parts.size(), [&](std::size_t k) { one_part(k, map); });
  }
  return out;
}

void check_every_part_meshed(const std::vector<PartOutcome>& parts) {
  std::ostringstream failed;
  int nfailed = 0;
  for (const PartOutcome& p : parts)
    if (!p.error.empty()) { failed << (nfailed++ ? "; " : "") << p.error; }
  if (nfailed > 0)
    throw MeshingError(std::to_string(nfailed) + " of " + std::to_string(parts.size()) + " parts failed: " + failed.str());
}

}  // namespace polysquare::pipeline
