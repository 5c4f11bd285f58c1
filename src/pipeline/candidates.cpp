// The candidates of a part: which ways of meshing it are tried, in which rounds, and how each one is made
// (a map of the part with the repairs asked for so far, or the split-triangle fallback).
#include <algorithm>
#include <cmath>
#include <memory>

#include "pipeline/candidate.h"
#include "polysquare/fallback/split_triangles.h"
#include "polysquare/map/map_bytes.h"

namespace polysquare::pipeline {

std::string name_of(const Region& region, const RegionPart& part) {
  return (region.source.empty() ? std::string("region") : region.source) + ": part " + std::to_string(part.part);
}

std::vector<std::vector<CandidateSpec>> candidate_rounds(const Region& region, const RegionPart& part,
                                                         const MeshOptions& options) {
  const double quads = part_area(region, part) / (options.size * options.size);
  std::vector<std::vector<CandidateSpec>> rounds(1);
  auto add = [&](CandidateSpec c) {
    for (const auto& r : rounds)
      if (std::find(r.begin(), r.end(), c) != r.end()) return;
    rounds.back().push_back(c);
  };
  auto add_bent_round = [&] {
    std::vector<CandidateSpec> bent;
    for (const auto& r : rounds)
      for (const CandidateSpec& c : r)
        if (c.subregions > 1 && !c.bend_interfaces && options.map.composition == MapComposition::ppm)
          bent.push_back({c.subregions, true});
    if (!bent.empty()) rounds.push_back(std::move(bent));
  };
  if (options.parts > 0) {
    add({options.parts});
    add_bent_round();
    rounds.emplace_back();
    add({1});
    if (options.parts > 1 && options.map.split_rounds > 0) {  // the retry round (see below)
      rounds.emplace_back();
      add({options.parts, false, false});
    }
    return rounds;
  }
  // Boundary complexity: the length of the rings and, counted twice (a subregion meets them from both sides),
  // of the feature curves. Long, convoluted boundaries (coastlines) need more subregions than their area says.
  double perimeter = 0.0;
  auto add_length = [&](const std::vector<Vec2>& pts, bool closed, double weight) {
    for (std::size_t i = 0; i + (closed ? 0 : 1) < pts.size(); ++i)
      perimeter += weight * distance(pts[i], pts[(i + 1) % pts.size()]);
  };
  for (int r : part.rings) add_length(region.rings[static_cast<std::size_t>(r)].points, true, 1.0);
  double ring_length = perimeter;
  for (int f : part.features) {
    const FeatureCurve& c = region.features[static_cast<std::size_t>(f)];
    add_length(c.points, c.closed, 2.0);
  }
  const int by_area = std::max(1, static_cast<int>(std::lround(quads / static_cast<double>(options.target_quads_per_part))));
  const int by_perimeter = static_cast<int>(std::lround(perimeter / (options.perimeter_per_subregion * options.size)));
  const int automatic = std::max(by_area, std::min(by_perimeter, options.max_automatic_subregions));
  // A boundary much longer than a square's of the same area (twice over), or features longer than the rings.
  const bool convoluted = ring_length > 8.0 * std::sqrt(quads) * options.size || perimeter > 2.0 * ring_length;
  if (quads > static_cast<double>(options.search_quads)) {
    // Large convoluted parts: one deterministic path (subregions from size and boundary complexity, failures
    // repaired locally), with one poly-square beside it (a comb or a square full of square islands is one map
    // with no singular node; on a coast it fails within the time the partitioned map takes). A part with a
    // short boundary (a rectangle at millions of quads) tries the one map alone first: partitioning it only
    // adds singular nodes, and its subregions' maps cost as much again.
    const bool partitioned = automatic > 1 && quads / automatic >= 16.0;
    if (partitioned && convoluted) add({automatic});
    const bool single_beside = !(partitioned && convoluted) || quads <= static_cast<double>(options.single_map_quads);
    if (single_beside) add({1});
    // A retry round, meshed only when every candidate before it failed: the same subregions without splitting
    // (a split can leave a piece whose repair folds, where the unsplit subregion's patch holds), and the one
    // poly-square of a part too large to try it beside the partition.
    if (partitioned && convoluted && (options.map.split_rounds > 0 || !single_beside)) {
      rounds.emplace_back();
      if (options.map.split_rounds > 0) add({automatic, false, false});
      if (!single_beside) add({1, false, false});
    }
    if (partitioned && !convoluted) {
      rounds.emplace_back();
      add({automatic});
    }
    return rounds;
  }
  // Small parts are cheap to mesh several ways: the automatic count (on convoluted parts), the counts from area
  // and ring length alone, the fixed search counts and one poly-square; the best mesh wins.
  if (convoluted && quads / automatic >= 16.0) add({automatic});
  add({by_area});
  const int by_rings = static_cast<int>(std::lround(ring_length / (2.0 * options.perimeter_per_subregion * options.size)));
  if (by_rings > 1 && quads / by_rings >= 16.0) add({by_rings});
  for (int k : options.search_subregions)
    if (quads / k >= 16.0) add({k});  // at least a 4 x 4 block per subregion
  add({1});
  if (quads <= static_cast<double>(options.bent_round_quads)) add_bent_round();
  // Last, the straight candidates again on a finer background triangulation: thin subregions of a coast have
  // about as many vertices on their chains as inside, and a snap or fold that fails there often holds with
  // twice the chain vertices. Meshed only while no candidate is fully structured.
  if (options.fine_parameterization_ratio > 0.0) {
    std::vector<CandidateSpec> fine = rounds.front();  // the first round's candidates are the straight ones
    for (CandidateSpec& c : fine) c.fine = true;
    rounds.push_back(std::move(fine));
  }
  return rounds;
}

void put_bytes(ByteWriter& w, const Candidate& c) {
  w.put(static_cast<std::uint8_t>(c.result.has_value()));
  if (c.result) put_bytes(w, *c.result);
  w.put(c.smooth), w.put(c.min_sj), w.put(c.max_edge_ratio), w.put(c.gated_sj), w.put(c.interior_singularities);
  w.put(c.error), w.put(c.summary.dump()), w.put(c.size_deviation), w.put(c.structured), w.put(c.poor_quads);
}

void get_bytes(ByteReader& r, Candidate& c) {
  std::uint8_t has = 0;
  r.get(has);
  c.result.reset();
  if (has) get_bytes(r, c.result.emplace());
  std::string summary;
  r.get(c.smooth), r.get(c.min_sj), r.get(c.max_edge_ratio), r.get(c.gated_sj), r.get(c.interior_singularities);
  r.get(c.error), r.get(summary), r.get(c.size_deviation), r.get(c.structured), r.get(c.poor_quads);
  c.summary = nlohmann::json::parse(summary);
}

Candidate try_candidate(const Region& region, const RegionPart& part, const PolysquareMapOptions& map,
                        const MeshOptions& options) {
  const int k = map.partition.parts;
  nlohmann::json summary = {{"part", part.part}, {"subregions", k}, {"parameterization_ratio", map.parameterization_ratio}};
  if (k > 1 && map.composition == MapComposition::ppm) {
    summary["bent_interfaces"] = !map.layout.straight_interfaces;
    summary["split_rounds"] = map.split_rounds;
  }
  // Repair rounds remesh the subregions of the first round's partition (after its splits), so the subregion
  // numbers they name stay valid and the splitting is not paid again.
  std::shared_ptr<const std::vector<std::int32_t>> partition;
  SplitStats split;
  int joint_splits = 0;
  int faces = 0;
  // Subregions whose map the first round gave up (quantization or snap), with why: later rounds patch them from
  // the start instead of finding them again, which took most of a round's time on a coast (each search is
  // several joint solves); the map is deterministic, so they would fail the same way.
  std::map<int, std::string> failed_first;
  auto requested = [&](int s) {  // a patch the caller asked for, which keeps the map's own text
    return std::find(map.patch_subregions.begin(), map.patch_subregions.end(), s) != map.patch_subregions.end();
  };
  return finish_candidate(region, part, options, std::move(summary), [&](const Repairs& repairs) {
    PolysquareMapOptions with_repairs = map;
    with_repairs.patch_subregions.insert(with_repairs.patch_subregions.end(), repairs.patches.begin(), repairs.patches.end());
    for (const auto& [s, why] : failed_first) with_repairs.patch_subregions.push_back(s);
    with_repairs.matched_patches = repairs.matched;
    with_repairs.grown_patches = repairs.grown;
    with_repairs.triangle_partition = partition;
    const bool first_round = !partition;
    PartMapResult r = map_part(region, part, with_repairs);
    if (first_round && r.partition) {
      partition = std::make_shared<const std::vector<std::int32_t>>(r.partition->triangle_part);
      split = r.stats.split;
      joint_splits = r.stats.joint_splits;
      faces = r.partition->faces;
      // The reason without its "<part>: subregion s: " head and the union it was meshed in (a later round's own).
      for (const SubregionStats& sr : r.stats.subregions) {
        if (sr.mapped || requested(sr.subregion)) continue;
        const std::string head = "subregion " + std::to_string(sr.subregion) + ": ";
        std::string why = sr.reason;
        if (const std::size_t at = why.find(head); at != std::string::npos) why.erase(0, at + head.size());
        if (const std::size_t at = why.find(" (meshed in the patch of"); at != std::string::npos) why.erase(at);
        failed_first.emplace(sr.subregion, why);
      }
    }
    // Subregions the repair rounds (or the first round's map) turned into patches say why, not merely that a
    // patch was asked for. The map's text says a patch was requested; what follows it (a union it joined) is kept.
    auto explain = [&](int s, const std::string& why) {
      if (static_cast<std::size_t>(s) >= r.stats.subregions.size() || r.stats.subregions[static_cast<std::size_t>(s)].mapped ||
          requested(s))
        return;
      std::string& reason = r.stats.subregions[static_cast<std::size_t>(s)].reason;
      const std::string asked = "a patch was requested";
      if (const std::size_t at = reason.find(asked); at != std::string::npos) reason.replace(at, asked.size(), why);
      else reason = name_of(region, part) + ": subregion " + std::to_string(s) + ": " + why;
    };
    for (int s : repairs.patches)
      explain(s, repairs.why.count(s) ? repairs.why.at(s) + " (meshed again as a patch)" : "a patch was requested");
    if (!first_round)
      for (const auto& [s, why] : failed_first) explain(s, why);
    r.stats.split = split;
    r.stats.joint_splits = joint_splits;
    if (r.partition) r.partition->faces = faces;  // a reused partition keeps the first round's count
    return r;
  });
}

// The last resort for a part no poly-square candidate meshes: triangles split into quads (unstructured).
Candidate try_split_fallback(const Region& region, const RegionPart& part, const MeshOptions& options) {
  nlohmann::json summary = {{"part", part.part}, {"subregions", 0}, {"fallback", "split_triangles"}};
  return finish_candidate(region, part, options, std::move(summary), [&](const Repairs&) {
    SplitOptions so;
    so.size = options.size;
    so.corner_threshold_deg = options.corner_threshold_deg;
    PartMapResult r;
    r.stats.part = part.part;
    r.mesh = split_triangles(region, part, so);
    r.stats.quads = r.mesh.quads.size();
    return r;
  });
}

}  // namespace polysquare::pipeline
