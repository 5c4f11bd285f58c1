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

namespace {

// The rounds being built: a candidate is added to the last round unless a round holds it already.
struct Rounds {
  std::vector<std::vector<CandidateSpec>> list = std::vector<std::vector<CandidateSpec>>(1);

  void add(CandidateSpec c) {
    for (const auto& r : list)
      if (std::find(r.begin(), r.end(), c) != r.end()) return;
    list.back().push_back(c);
  }
  // A new round: the partitioned candidates so far again, with bendable interfaces (PPM only).
  void add_bent_round(const MeshOptions& options) {
    std::vector<CandidateSpec> bent;
    for (const auto& r : list)
      for (const CandidateSpec& c : r)
        if (c.subregions > 1 && !c.bend_interfaces && options.map.composition == MapComposition::ppm)
          bent.push_back({c.subregions, true});
    if (!bent.empty()) list.push_back(std::move(bent));
  }
};

// An explicit --parts K: K subregions, then K with bendable interfaces, then one poly-square, then K unsplit.
void explicit_rounds(Rounds& rounds, const MeshOptions& options) {
  rounds.add({options.subregions.parts});
  rounds.add_bent_round(options);
  rounds.list.emplace_back();
  rounds.add({1});
  if (options.subregions.parts > 1 && options.map.split_rounds > 0) {  // the retry round (see large_part_rounds)
    rounds.list.emplace_back();
    rounds.add({options.subregions.parts, false, false});
  }
}

// The figures automatic mode chooses a part's subregion counts from.
struct AutomaticCounts {
  double quads = 0.0;        // the part's area in quads of the size
  double ring_length = 0.0;  // the length of its rings, in quads
  int by_area = 1;           // subregions of target_quads_per_part quads
  int automatic = 1;         // by area, or by boundary length when that asks for more
  bool convoluted = false;
};

// Lengths and areas in quads: of the size, or of the field's local sizes on a graded run.
struct QuadMeasure {
  const MeshOptions& options;
  const SizeField* field;

  double length(Vec2 a, Vec2 b) const {
    return distance(a, b) / (field ? field->at(0.5 * (a + b)) : options.size.h);
  }
  double area(const Region& region, const RegionPart& part) const {
    return field ? estimate_quads(*field, region, part.rings)
                 : part_area(region, part) / (options.size.h * options.size.h);
  }
};

AutomaticCounts automatic_counts(const Region& region, const RegionPart& part, const MeshOptions& options,
                                 const PolysquareMapOptions& map) {
  AutomaticCounts n;
  const QuadMeasure in_quads{options, map.size_field.get()};
  const double quads = in_quads.area(region, part);
  // Boundary complexity: the length of the rings and, counted twice (a subregion meets them from both sides),
  // of the feature curves. Long, convoluted boundaries (coastlines) need more subregions than their area says.
  double perimeter = 0.0;
  auto add_length = [&](const std::vector<Vec2>& pts, bool closed, double weight) {
    for (std::size_t i = 0; i + (closed ? 0 : 1) < pts.size(); ++i)
      perimeter += weight * in_quads.length(pts[i], pts[(i + 1) % pts.size()]);
  };
  for (int r : part.rings) add_length(region.rings[static_cast<std::size_t>(r)].points, true, 1.0);
  double ring_length = perimeter;
  for (int f : part.features) {
    const FeatureCurve& c = region.features[static_cast<std::size_t>(f)];
    add_length(c.points, c.closed, 2.0);
  }
  const int by_area =
      std::max(1, static_cast<int>(std::lround(quads / static_cast<double>(options.subregions.target_quads_per_part))));
  const int by_perimeter = static_cast<int>(std::lround(perimeter / options.subregions.perimeter_per_subregion));
  n.automatic = std::max(by_area, std::min(by_perimeter, options.subregions.max_automatic_subregions));
  if (map.size_field)
    n.automatic = std::max(
        n.automatic, static_cast<int>(std::lround(quads / graded_subregion_quads(options.subregions, options.size.field.grade))));
  // A boundary much longer than a square's of the same area (twice over), or features longer than the rings.
  n.convoluted = ring_length > 8.0 * std::sqrt(quads) || perimeter > 2.0 * ring_length;
  n.quads = quads;
  n.ring_length = ring_length;  // in quads
  n.by_area = by_area;
  return n;
}

// Large convoluted parts: one deterministic path (subregions from size and boundary complexity, failures
// repaired locally), with one poly-square beside it (a comb or a square full of square islands is one map
// with no singular node; on a coast it fails within the time the partitioned map takes). A part with a
// short boundary (a rectangle at millions of quads) tries the one map alone first: partitioning it only
// adds singular nodes, and its subregions' maps cost as much again.
void large_part_rounds(Rounds& rounds, const AutomaticCounts& n, const MeshOptions& options) {
  const double quads = n.quads;
  const int automatic = n.automatic;
  const bool convoluted = n.convoluted;
  const bool partitioned = automatic > 1 && quads / automatic >= 16.0;
  // A graded part that asks for subregions has no one-poly-square mesh: the map has no singular node to let
  // the size change (on delta_water at 50-1000 m each such try failed after 76-90 s).
  const bool graded = options.size.graded() && partitioned;
  if (partitioned && (convoluted || graded)) rounds.add({automatic});
  const bool single_beside =
      !graded && (!(partitioned && convoluted) || quads <= static_cast<double>(options.subregions.single_map_quads));
  if (single_beside) rounds.add({1});
  // A retry round, meshed only when every candidate before it failed: the same subregions without splitting
  // (a split can leave a piece whose repair folds, where the unsplit subregion's patch holds), and the one
  // poly-square of a part too large to try it beside the partition.
  if (partitioned && (convoluted || graded) && (options.map.split_rounds > 0 || !single_beside)) {
    rounds.list.emplace_back();
    if (options.map.split_rounds > 0) rounds.add({automatic, false, false});
    if (!single_beside && !graded) rounds.add({1, false, false});
  }
  if (partitioned && !convoluted && !graded) {
    rounds.list.emplace_back();
    rounds.add({automatic});
  }
}

// Small parts are cheap to mesh several ways: the automatic count (on convoluted parts), the counts from area
// and ring length alone, the fixed search counts and one poly-square; the best mesh wins.
void small_part_rounds(Rounds& rounds, const AutomaticCounts& n, const MeshOptions& options) {
  const double quads = n.quads;
  if (n.convoluted && quads / n.automatic >= 16.0) rounds.add({n.automatic});
  rounds.add({n.by_area});
  const int by_rings =
      static_cast<int>(std::lround(n.ring_length / (2.0 * options.subregions.perimeter_per_subregion)));
  if (by_rings > 1 && quads / by_rings >= 16.0) rounds.add({by_rings});
  for (int k : options.subregions.search_subregions)
    if (quads / k >= 16.0) rounds.add({k});  // at least a 4 x 4 block per subregion
  rounds.add({1});
  if (quads <= static_cast<double>(options.subregions.bent_round_quads)) rounds.add_bent_round(options);
  // Last, the straight candidates again on a finer background triangulation: thin subregions of a coast have
  // about as many vertices on their chains as inside, and a snap or fold that fails there often holds with
  // twice the chain vertices. Meshed only while no candidate is fully structured.
  if (options.subregions.fine_parameterization_ratio > 0.0) {
    std::vector<CandidateSpec> fine = rounds.list.front();  // the first round's candidates are the straight ones
    for (CandidateSpec& c : fine) c.fine = true;
    rounds.list.push_back(std::move(fine));
  }
}

}  // namespace

std::vector<std::vector<CandidateSpec>> candidate_rounds(const Region& region, const RegionPart& part,
                                                         const MeshOptions& options, const PolysquareMapOptions& map) {
  Rounds rounds;
  if (options.subregions.parts > 0) {
    explicit_rounds(rounds, options);
    return rounds.list;
  }
  const AutomaticCounts n = automatic_counts(region, part, options, map);
  if (n.quads > static_cast<double>(options.subregions.search_quads))
    large_part_rounds(rounds, n, options);
  else small_part_rounds(rounds, n, options);
  return rounds.list;
}

void put_bytes(ByteWriter& w, const Candidate& c) {
  w.put(static_cast<std::uint8_t>(c.result.has_value()));
  if (c.result) put_bytes(w, *c.result);
  w.put(c.smooth), w.put(c.min_sj), w.put(c.max_edge_ratio), w.put(c.gated_sj), w.put(c.interior_singularities);
  w.put(c.error), w.put(nlohmann::json(c.summary).dump()), w.put(c.size_deviation), w.put(c.structured), w.put(c.poor_quads);
}

void get_bytes(ByteReader& r, Candidate& c) {
  std::uint8_t has = 0;
  r.get(has);
  c.result.reset();
  if (has) get_bytes(r, c.result.emplace());
  std::string summary;
  r.get(c.smooth), r.get(c.min_sj), r.get(c.max_edge_ratio), r.get(c.gated_sj), r.get(c.interior_singularities);
  r.get(c.error), r.get(summary), r.get(c.size_deviation), r.get(c.structured), r.get(c.poor_quads);
  c.summary = nlohmann::json::parse(summary).get<CandidateReport>();
}

namespace {

// A candidate's maps round after round: the first round's map, then the part mapped again with the repairs.
// Repair rounds remesh the subregions of the first round's partition (after its splits), so the subregion
// numbers they name stay valid and the splitting is not paid again.
class RepairedMaps {
 public:
  RepairedMaps(const Region& region, const RegionPart& part, const PolysquareMapOptions& map)
      : region_(region), part_(part), map_(map) {}

  PartMapResult operator()(const Repairs& repairs) {
    PolysquareMapOptions with_repairs = map_;
    with_repairs.patch_subregions.insert(with_repairs.patch_subregions.end(), repairs.patches.begin(), repairs.patches.end());
    for (const auto& [s, why] : failed_first_) with_repairs.patch_subregions.push_back(s);
    with_repairs.matched_patches = repairs.matched;
    with_repairs.grown_patches = repairs.grown;
    with_repairs.triangle_partition = partition_;
    const bool first_round = !partition_;
    PartMapResult r = map_part(region_, part_, with_repairs);
    if (first_round && r.partition) remember_first_round(r);
    for (int s : repairs.patches)
      explain(r, s, repairs.why.count(s) ? repairs.why.at(s) + " (meshed again as a patch)" : "a patch was requested");
    if (!first_round)
      for (const auto& [s, why] : failed_first_) explain(r, s, why);
    r.stats.split = split_;
    r.stats.joint_splits = joint_splits_;
    if (r.partition) r.partition->faces = faces_;  // a reused partition keeps the first round's count
    return r;
  }

 private:
  bool requested(int s) const {  // a patch the caller asked for, which keeps the map's own text
    return std::find(map_.patch_subregions.begin(), map_.patch_subregions.end(), s) != map_.patch_subregions.end();
  }

  void remember_first_round(const PartMapResult& r) {
    partition_ = std::make_shared<const std::vector<std::int32_t>>(r.partition->triangle_part);
    split_ = r.stats.split;
    joint_splits_ = r.stats.joint_splits;
    faces_ = r.partition->faces;
    // The reason without its "<part>: subregion s: " head and the union it was meshed in (a later round's own).
    for (const SubregionStats& sr : r.stats.subregions) {
      if (sr.mapped || requested(sr.subregion)) continue;
      const std::string head = "subregion " + std::to_string(sr.subregion) + ": ";
      std::string why = sr.reason;
      if (const std::size_t at = why.find(head); at != std::string::npos) why.erase(0, at + head.size());
      if (const std::size_t at = why.find(" (meshed in the patch of"); at != std::string::npos) why.erase(at);
      failed_first_.emplace(sr.subregion, why);
    }
  }

  // Subregions the repair rounds (or the first round's map) turned into patches say why, not merely that a
  // patch was asked for. The map's text says a patch was requested; what follows it (a union it joined) is kept.
  void explain(PartMapResult& r, int s, const std::string& why) const {
    if (static_cast<std::size_t>(s) >= r.stats.subregions.size() || r.stats.subregions[static_cast<std::size_t>(s)].mapped ||
        requested(s))
      return;
    std::string& reason = r.stats.subregions[static_cast<std::size_t>(s)].reason;
    const std::string asked = "a patch was requested";
    if (const std::size_t at = reason.find(asked); at != std::string::npos) reason.replace(at, asked.size(), why);
    else reason = name_of(region_, part_) + ": subregion " + std::to_string(s) + ": " + why;
  }

  const Region& region_;
  const RegionPart& part_;
  const PolysquareMapOptions& map_;
  std::shared_ptr<const std::vector<std::int32_t>> partition_;
  SplitStats split_;
  int joint_splits_ = 0;
  int faces_ = 0;
  // Subregions whose map the first round gave up (quantization or snap), with why: later rounds patch them from
  // the start instead of finding them again, which took most of a round's time on a coast (each search is
  // several joint solves); the map is deterministic, so they would fail the same way.
  std::map<int, std::string> failed_first_;
};

}  // namespace

Candidate try_candidate(const Region& region, const RegionPart& part, const PolysquareMapOptions& map,
                        const MeshOptions& options) {
  const int k = map.partition.parts;
  CandidateReport summary;
  summary.part = part.part;
  summary.subregions = k;
  summary.parameterization_ratio = map.parameterization_ratio;
  if (k > 1 && map.composition == MapComposition::ppm) {
    summary.bent_interfaces = !map.layout.straight_interfaces;
    summary.split_rounds = map.split_rounds;
  }
  RepairedMaps maps(region, part, map);
  Candidate c = finish_candidate(region, part, options, map.size_field, summary, std::ref(maps));
  // Graded: a candidate whose transition rows left what its repair rounds could not mend (cracks and
  // overlapping quads on a graded delta_box, round after round, then the unstructured fallback for the whole
  // part) is made again without them, from its first round.
  const auto& rounds = c.summary.repair_rounds;
  const bool cracked = rounds && std::any_of(rounds->begin(), rounds->end(), [](const RepairRoundReport& r) { return r.beside_cracks > 0; });
  if (c.error.empty() || !cracked || !map.size_field || map.quantize.transition_cost <= 0.0) return c;
  PolysquareMapOptions plain = map;
  plain.quantize.transition_cost = 0.0;
  summary.with_transitions_error = c.error;
  RepairedMaps again(region, part, plain);
  return finish_candidate(region, part, options, map.size_field, std::move(summary), std::ref(again));
}

// The last resort for a part no poly-square candidate meshes: triangles split into quads (unstructured).
Candidate try_split_fallback(const Region& region, const RegionPart& part, const MeshOptions& options) {
  CandidateReport summary;
  summary.part = part.part;
  summary.fallback = "split_triangles";
  return finish_candidate(region, part, options, nullptr, std::move(summary), [&](const Repairs&) {
    SplitOptions so;
    so.size = options.size.h;
    if (options.size.graded()) so.max_size = options.size.field.size_max;
    so.corner_threshold_deg = options.curves.corner_threshold_deg;
    PartMapResult r;
    r.stats.part = part.part;
    r.mesh = split_triangles(region, part, so);
    r.stats.quads = r.mesh.quads.size();
    return r;
  });
}

}  // namespace polysquare::pipeline

namespace polysquare {

// The singular nodes a grading needs go as G^2 (2 G^2 / pi of the quads), so below the reference gradient the
// subregions grow as (reference / G)^2 and each still spans about the same change of size (a coast at 10-1000 m
// and G = 0.04 had 13,400 subregions of 150 quads, a joint program of 515k columns).
double graded_subregion_quads(const SubregionOptions& options, double grade) {
  const double ratio = options.graded_reference_grade / grade;
  return options.graded_quads_per_subregion * std::max(1.0, ratio * ratio);
}

}  // namespace polysquare
