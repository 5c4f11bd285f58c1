#include "polysquare/pipeline/mesh_region.h"

#include <oneapi/tbb/global_control.h>
#include <oneapi/tbb/info.h>
#include <oneapi/tbb/parallel_for.h>

#include <algorithm>
#include <cctype>
#include <limits>
#include <map>
#include <numeric>
#include <chrono>
#include <cmath>
#include <optional>
#include <set>
#include <sstream>

#include "polysquare/core/error.h"
#include "polysquare/core/version.h"
#include "polysquare/fallback/split_triangles.h"
#include "polysquare/input/chord_clearance.h"
#include "polysquare/input/simplify.h"
#include "polysquare/pipeline/check_options.h"
#include "polysquare/input/snap_points.h"
#include "polysquare/map/map_bytes.h"
#include "polysquare/pipeline/invariants.h"
#include "polysquare/quality/quality.h"
#include "polysquare/triangulate/background_triangulation.h"

namespace polysquare {
namespace {

double region_area(const Region& region) {
  double a = 0.0;
  for (const Ring& r : region.rings) a += ring_signed_area(r.points);  // outer rings counter-clockwise (+), holes (-)
  return a;
}

nlohmann::json part_json(const PartMapStats& s) {
  nlohmann::json subregions = nlohmann::json::array();
  for (const SubregionStats& r : s.subregions) {
    nlohmann::json j = {{"subregion", r.subregion}, {"quads", r.quads}, {"meshed_by", r.mapped ? "map" : "patch"},
                        {"at", {r.at.x, r.at.y}}};
    if (r.local_patch_quads > 0) j["local_patch_quads"] = r.local_patch_quads;
    if (r.untangled) j["untangled"] = true;
    if (!r.mapped) j["reason"] = r.reason;
    subregions.push_back(std::move(j));
  }
  return {{"subregions", subregions},
          {"part", s.part},
          {"triangles", s.triangles},
          {"rotation_deg", s.rotation_deg},
          {"deform", {{"iterations", s.deform.iterations},
                      {"energy_before", s.deform.energy_before},
                      {"energy_after", s.deform.energy_after},
                      {"alignment_before", s.deform.alignment_before},
                      {"alignment_after", s.deform.alignment_after}}},
          {"split", {{"rounds", s.split.rounds}, {"subregions_split", s.split.split},
                     {"maps_tried", s.split.tested}, {"pieces_mapped", s.split.pieces_mapped},
                     {"seconds", s.split.seconds}, {"after_joint_map", s.joint_splits}}},
          {"break_points", s.break_points},
          {"segments", s.segments},
          {"quantization_max_relative_deviation", s.quantize.max_relative_deviation},
          {"quads", s.quads},
          {"seconds", {{"triangulate", s.seconds_triangulate},
                       {"deform", s.seconds_deform},
                       {"quantize", s.seconds_quantize},
                       {"snap", s.seconds_snap},
                       {"extract", s.seconds_extract},
                       {"joint_maps", s.seconds_joint_maps}}},
          {"joint_maps", s.joint_maps},
          {"agreed_turns", s.agreed_turns},
          {"multipass", {{"passes", s.multipass.passes}, {"colours", s.multipass.colours},
                         {"last_move", s.multipass.last_move}, {"seconds", s.multipass.seconds}}}};
}

nlohmann::json dropped_json(const std::vector<DroppedCurve>& curves) {
  nlohmann::json out = nlohmann::json::array();
  for (const DroppedCurve& d : curves) {
    const char* kind = d.kind == DroppedCurve::Kind::hole           ? "hole"
                       : d.kind == DroppedCurve::Kind::feature_loop  ? "feature_loop"
                       : d.kind == DroppedCurve::Kind::feature_piece ? "feature_piece"
                                                                     : "wedge_stretch";
    out.push_back({{"kind", kind}, {"input_feature", d.source_feature}, {"width", d.width}, {"area", d.area},
                   {"distance", d.distance}, {"at", {d.at.x, d.at.y}}});
  }
  return out;
}

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

// "FILE: part P", how messages name a part.
std::string name_of(const Region& region, const RegionPart& part) {
  return (region.source.empty() ? std::string("region") : region.source) + ": part " + std::to_string(part.part);
}

// One way to map a part: the number of subregions and whether PPM interfaces may bend.
struct CandidateSpec {
  int subregions = 1;
  bool bend_interfaces = false;
  bool split = true;  // failed subregions are split before the joint map (PolysquareMapOptions::split_rounds)
  bool fine = false;  // background triangulation at MeshOptions::fine_parameterization_ratio
  bool operator==(const CandidateSpec&) const = default;
};

// Candidates for one part, in rounds: a round is meshed only when every candidate of the rounds before it
// failed or left unstructured patches. An explicit --parts K is one round, K with bendable interfaces the next,
// one poly-square the last.
// Automatic mode meshes small parts every way at once (one poly-square, the counts of search_subregions, the
// area- and perimeter-based counts) and retries their partitions with bendable interfaces (parts up to
// bent_round_quads); a large part is meshed one way (see MeshOptions::parts), the whole-part fallback only when
// that fails.
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

// One way of meshing a part: the map, then smoothing, then the checks every output must pass.
struct Candidate {
  std::optional<PartMapResult> result;
  SmoothStats smooth;
  double min_sj = -2.0, max_edge_ratio = 0.0;
  double gated_sj = -2.0;  // SJ min without the quads pinned by sharp input corners: what the mesher controls
  std::size_t interior_singularities = 0;
  std::string error;
  nlohmann::json summary;

  double size_deviation = 0.0;  // |log(mean quad area / h^2)|: how far the element size is from the request
  double structured = 0.0;      // fraction of its quads in poly-square-mapped subregions (0 for the fallback)
  std::size_t poor_quads = 0;   // unpinned quads outside the gates, accepted within MeshOptions::max_poor_fraction

  bool better_than(const Candidate& o) const {
    // A mesh every quad of which passes the gates first.
    if ((poor_quads == 0) != (o.poor_quads == 0)) return poor_quads == 0;
    // Semi-structured first: a candidate with fewer quads in unstructured patches wins.
    if (std::abs(structured - o.structured) > 0.01) return structured > o.structured;
    if (std::abs(gated_sj - o.gated_sj) > 0.02) return gated_sj > o.gated_sj;  // quality first, within a margin
    if (interior_singularities != o.interior_singularities) return interior_singularities < o.interior_singularities;
    if (std::abs(size_deviation - o.size_deviation) > 0.05) return size_deviation < o.size_deviation;
    return gated_sj > o.gated_sj;
  }
};

// A candidate meshed by another process (several processes, see mesh_region), copied as it is.
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

// What a candidate is meshed again with, after a round left folded or poor quads in some subregions: mapped
// subregions become patches, patches are built by the other (matching) construction.
struct Repairs {
  std::vector<int> patches, matched, grown;
  std::map<int, std::string> why;  // a subregion of `patches` -> why its map was given up
  // Adds the subregions in `bad` (subregion -> what is wrong with its quads); false when none of them can be
  // repaired further. A mapped one becomes a patch, a patch is built by the matching construction, and a
  // matched patch grows over its neighbours.
  bool add(const std::map<int, std::string>& bad, const PartMapStats& stats) {
    bool added = false;
    auto has = [](const std::vector<int>& list, int s) { return std::find(list.begin(), list.end(), s) != list.end(); };
    for (const auto& [s, what] : bad) {
      const bool mapped = stats.subregions[static_cast<std::size_t>(s)].mapped;
      std::vector<int>& list = mapped ? patches : (has(matched, s) ? grown : matched);
      if (has(list, s)) continue;
      list.push_back(s);
      if (mapped) why.emplace(s, what);
      added = true;
    }
    return added;
  }
};

// After local patches or valence moves the mesh is smoothed again only near what changed and near quads still
// below this corner scaled Jacobian, with this many rings of quads around them: the rest was smoothed already,
// and searching it again cost as much as the first smoothing (5.5 s of a 209k-quad delta_water part at 40 m).
constexpr double kResmoothBelowSj = 0.5;
constexpr int kResmoothRings = 4;

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

// Cuts the quads of the subregions `cut` out of a finished part mesh and meshes each hole again as one patch on
// its boundary loop (refine/local_patch.h, the subregion's quads alone first), so that the rest of the part keeps
// its quads, their smoothing and their local patches: a repair round that mapped the part again redid all three
// (delta_box 10 m: 350 s a round). `local_patched` (#quads) is carried; the new quads are the subregions' own.
// False when a subregion keeps some of its quads (the mesh may have changed: the caller maps the part again).
bool patch_subregions_in_place(QuadMesh& mesh, const std::map<int, std::string>& cut, const MeshOptions& options,
                               std::vector<std::uint8_t>& local_patched) {
  if (mesh.quad_part.size() != mesh.quads.size()) return false;
  const std::size_t nq = mesh.quads.size();
  std::vector<std::int32_t> region(nq, -1);
  std::vector<std::uint8_t> made(nq, 0);
  for (std::size_t q = 0; q < nq; ++q) {
    if (cut.count(mesh.quad_part[q])) region[q] = mesh.quad_part[q];  // each subregion a patch of its own
    made[q] = q < local_patched.size() && local_patched[q] ? 2 : 0;  // the new quads come back as 1
  }
  LocalPatchOptions lp = options.local_patch;
  lp.size = options.size;
  lp.min_rings = 0;
  lp.holes = true;           // a subregion around an island
  lp.inner_features = true;  // a subregion a feature runs into
  // Up to three rings of neighbours when the subregion alone is no disk or its patch does not build: a hole that
  // fails sends the part to be mapped, smoothed and local-patched again (delta_box 10 m: 340 s more wall time).
  lp.max_rings = 3;
  lp.max_quads = std::numeric_limits<std::size_t>::max();
  lp.target_sj = 0.0;  // the first patch that builds: smoothing follows, and each try costs a whole patch
  remesh_regions(mesh, region, lp, made);
  for (std::size_t q = 0; q < mesh.quads.size(); ++q)
    if (cut.count(mesh.quad_part[q]) && made[q] != 1) return false;
  local_patched.assign(mesh.quads.size(), 0);
  for (std::size_t q = 0; q < mesh.quads.size(); ++q) local_patched[q] = made[q] == 2;
  return true;
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

// Meshes a part with `make_mesh` (a map candidate or the fallback), then smooths, checks and measures it.
template <typename MakeMesh>
Candidate finish_candidate(const Region& region, const RegionPart& part, const MeshOptions& options,
                           nlohmann::json summary, MakeMesh make_mesh) {
  Candidate c;
  c.summary = std::move(summary);
  // Wall time of the candidate, map to gates, so the report shows where a part's search spent its time.
  const auto t_start = std::chrono::steady_clock::now();
  const std::string name = name_of(region, part);
  try {
    // A mapped subregion whose quads stay folded after smoothing (its map folds near a convoluted boundary) is
    // meshed again as a patch, with the subregions patched before; the rest of the part keeps its maps.
    Repairs repairs;
    PartMapResult r;
    std::vector<std::uint8_t> local_patched;  // #quads: made by a local patch (refine/local_patch.h)
    LocalPatchStats local_stats;
    QuadMetrics metrics;
    std::vector<std::uint8_t> pinned;
    // "in subregion s (mapped|patch)" for the quad q of a partitioned part's mesh, empty otherwise.
    auto subregion_of = [&](std::size_t q) -> int {
      if (q >= r.mesh.quad_part.size()) return -1;
      const int s = r.mesh.quad_part[q];
      return s >= 0 && static_cast<std::size_t>(s) < r.stats.subregions.size() ? s : -1;
    };
    auto in_subregion = [&](std::size_t q) {
      const int s = subregion_of(q);
      if (s < 0) return std::string();
      return " in subregion " + std::to_string(s) +
             (r.stats.subregions[static_cast<std::size_t>(s)].mapped ? " (mapped)" : " (patch)");
    };
    // Where the candidate's time goes, summed over its repair rounds (the report's `stage_seconds`).
    double t_map = 0.0, t_first_map = 0.0, t_refine = 0.0, t_smooth = 0.0, t_local = 0.0, t_relax = 0.0, t_measure = 0.0,
           t_repair_patches = 0.0;
    nlohmann::json first_map;  // the first round's map: partition, split rounds, joint maps
    auto timed = [](double& total, auto&& f) {
      const auto t0 = std::chrono::steady_clock::now();
      f();
      total += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    };
    SmoothOptions smooth = options.smooth;
    smooth.feature_tolerance = options.feature_tolerance * options.size;
    // Folded quads, and unpinned ones outside the SJ or edge-ratio gate. The gates judge the quads the mesher controls: quads
    // pinned by an input corner sharper than the SJ gate are only counted (no conforming mesh does better).
    std::vector<std::uint8_t> poor;
    auto measure = [&] {
      timed(t_measure, [&] {
        metrics = quad_metrics(r.mesh);
        pinned = quads_pinned_by_sharp_input(r.mesh, options.min_scaled_jacobian, options.size);
      });
      poor.assign(metrics.sj.size(), 0);
      bool any = false;
      for (std::size_t q = 0; q < metrics.sj.size(); ++q) {
        poor[q] = metrics.sj[q] <= 0.0 || (!pinned[q] && (metrics.sj[q] < options.min_scaled_jacobian ||
                                                          metrics.edge_ratio[q] > options.max_edge_ratio));
        any = any || poor[q];
      }
      return any;
    };
    // The mesh's smoothing again near the quads `changed`: the new quads' seams with the rest are smoothed from
    // both sides.
    auto smooth_near = [&](auto changed) {
      const std::vector<std::uint8_t> near = nodes_near(r.mesh, changed, kResmoothRings);
      timed(t_smooth, [&] { c.smooth = smooth_quads(r.mesh, smooth, &region, &near); });
    };
    // First the neighbourhoods of the poor quads are meshed again (a few rings of quads, the rest of their
    // subregions keeps its map), then smoothed near them.
    // Local patches around the flagged quads, `rings` and `max_quads` as far as they may grow; then the mesh
    // is smoothed near them (smooth_near) and measured again. Returns whether poor quads remain.
    auto patch_locally = [&](const std::vector<std::uint8_t>& flagged, int rings, std::size_t max_quads) {
      LocalPatchOptions lp = options.local_patch;
      lp.size = options.size;
      lp.max_rings = rings;
      lp.max_quads = max_quads;
      LocalPatchStats done;
      timed(t_local, [&] { done = remesh_poor_quads(r.mesh, flagged, lp, local_patched); });
      local_stats.clusters += done.clusters;
      local_stats.patched += done.patched;
      local_stats.quads_added += done.quads_added;
      local_stats.quads_removed += done.quads_removed;
      if (done.patched == 0) return true;  // the flagged quads are as they were
      smooth_near(
          [&](std::size_t q) { return local_patched[q] != 0 || quad_min_corner_sj(r.mesh, q) < kResmoothBelowSj; });
      return measure();
    };
    // Mapped subregions a repair round cuts out of the finished mesh and patches in place, with why (empty: the
    // round maps the part again).
    std::map<int, std::string> in_place;
    for (int round = 0;; ++round) {
      // #subregions: 1 where this round changed the mesh, the rest kept from the round before; empty: everywhere.
      std::vector<std::uint8_t> scope;
      if (!in_place.empty()) {
        bool done = false;
        timed(t_repair_patches, [&] { done = patch_subregions_in_place(r.mesh, in_place, options, local_patched); });
        if (done) {
          for (const auto& [s, why] : in_place) {
            SubregionStats& sr = r.stats.subregions[static_cast<std::size_t>(s)];
            sr.mapped = false;
            sr.reason = name + ": subregion " + std::to_string(s) + ": " + why + " (meshed again as a patch)";
          }
          auto cut = [&](std::size_t q) { return in_place.count(subregion_of(q)) > 0; };
          scope = subregions_touching(r.mesh, cut, r.stats.subregions.size());
          smooth_near(cut);
        }
        in_place.clear();
      }
      if (scope.empty()) {
        timed(t_map, [&] { r = make_mesh(repairs); });
        if (round == 0) {
          t_first_map = t_map;
          first_map = {{"partition", r.stats.seconds_partition}, {"split_rounds", r.stats.split.seconds},
                       {"joint_maps", r.stats.joint_maps}, {"joint_maps_seconds", r.stats.seconds_joint_maps}};
        }
        RefineStats refined;
        timed(t_refine, [&] { refined = refine_flat_corners(r.mesh, options.refine); });
        if (r.stats.split.tested > 0 || r.stats.joint_splits > 0)
          c.summary["split"] = {{"rounds", r.stats.split.rounds}, {"subregions_split", r.stats.split.split},
                                {"maps_tried", r.stats.split.tested}, {"pieces_mapped", r.stats.split.pieces_mapped},
                                {"seconds", r.stats.split.seconds}, {"after_joint_map", r.stats.joint_splits}};
        c.summary["flat_corners"] = refined.flat_corners;
        c.summary["flat_corners_collapsed"] = refined.collapsed;
        RefineStats loops;
        timed(t_refine, [&] { loops = pillow_feature_loops(r.mesh, options.refine); });
        if (loops.feature_loops > 0) {
          c.summary["feature_loops_flat"] = loops.feature_loops;
          c.summary["feature_loops_pillowed"] = loops.pillowed;
        }
        timed(t_smooth, [&] { c.smooth = smooth_quads(r.mesh, smooth, &region); });
        local_patched.clear();
      }
      auto in_scope = [&](std::size_t q) {
        if (scope.empty()) return true;
        const int s = subregion_of(q);
        return s >= 0 && scope[static_cast<std::size_t>(s)] != 0;
      };
      InvariantReport inv;
      // The first pass also mends valid quads under local_patch.mend_below_sj where a patch does better.
      // Outside the scope the quads are the last round's, local patches tried already.
      measure();
      bool any_flagged = false;
      std::vector<std::uint8_t> flagged(poor.size(), 0);
      for (std::size_t q = 0; q < flagged.size(); ++q) {
        if (!in_scope(q)) continue;
        flagged[q] = poor[q] ? 1 : !pinned[q] && metrics.sj[q] < options.local_patch.mend_below_sj ? 2 : 0;
        any_flagged = any_flagged || flagged[q];
      }
      auto poor_in_scope = [&] {
        std::vector<std::uint8_t> f(poor.size(), 0);
        for (std::size_t q = 0; q < f.size(); ++q) f[q] = poor[q] && in_scope(q);
        return f;
      };
      if (any_flagged && options.local_patch.enabled &&
          patch_locally(flagged, options.local_patch.max_rings, options.local_patch.max_quads))
        patch_locally(poor_in_scope(), options.local_patch.second_rings, options.local_patch.second_max_quads);
      {
        // The unstructured quads (patched subregions, local patches) cleaned up across their seams, where each
        // patch alone could only guess what its neighbours put at its boundary nodes.
        std::vector<std::uint8_t> unstructured_quads(r.mesh.quads.size(), 0);
        for (std::size_t q = 0; q < unstructured_quads.size(); ++q) {
          const int s = subregion_of(q);
          unstructured_quads[q] = in_scope(q) && ((q < local_patched.size() && local_patched[q]) ||
                                                  (s >= 0 && !r.stats.subregions[static_cast<std::size_t>(s)].mapped));
        }
        std::vector<std::size_t> origin;
        RelaxValencesStats relaxed;
        RelaxValencesOptions ro = options.relax_valences;
        ro.poor_sj = options.min_scaled_jacobian;
        timed(t_relax, [&] { relaxed = relax_region_valences(r.mesh, unstructured_quads, ro, smooth, origin); });
        if (relaxed.region_quads > 0) {
          // A round in place adds its scope's figures to the round before's (a mapped round's cover the part).
          nlohmann::json& rv = c.summary["relax_valences"];
          if (scope.empty() || !rv.is_object()) rv = {{"quads", 0}, {"flips", 0}, {"collapses", 0}, {"energy_before", 0.0}, {"energy_after", 0.0}};
          rv["quads"] = rv["quads"].get<std::size_t>() + relaxed.region_quads;
          rv["flips"] = rv["flips"].get<std::size_t>() + relaxed.flips;
          rv["collapses"] = rv["collapses"].get<std::size_t>() + relaxed.collapses;
          rv["energy_before"] = rv["energy_before"].get<double>() + relaxed.energy_before;
          rv["energy_after"] = rv["energy_after"].get<double>() + relaxed.energy_after;
        }
        if (relaxed.kept) {
          if (!local_patched.empty()) {
            std::vector<std::uint8_t> moved(origin.size(), 0);
            for (std::size_t q = 0; q < origin.size(); ++q) moved[q] = origin[q] < local_patched.size() && local_patched[origin[q]];
            local_patched = std::move(moved);
          }
          // A piece alone kept its border nodes fixed: its seams with the mapped quads are smoothed now.
          smooth_near([&](std::size_t q) { return q >= relaxed.first_kept_quad; });
          measure();
        }
      }
      // A valid quad far outside a gate (below half the SJ gate, above twice the edge-ratio gate) costs a small
      // subregion its map, not a large one: a patch adds about one singular node per seven quads (delta_box 40 m:
      // a 30,000-quad map was patched for one quad). In a map above options.keep_map_above_quads such quads get
      // the widest local patches first and, if they stay, are kept and reported like the poor quads below.
      auto severe = [&](std::size_t q) {
        return metrics.sj[q] > 0.0 && !pinned[q] &&
               (metrics.sj[q] < 0.5 * options.min_scaled_jacobian || metrics.edge_ratio[q] > 2.0 * options.max_edge_ratio);
      };
      auto in_large_map = [&](std::size_t q) {
        const int s = subregion_of(q);
        return s >= 0 && r.stats.subregions[static_cast<std::size_t>(s)].mapped &&
               r.stats.subregions[static_cast<std::size_t>(s)].quads > options.keep_map_above_quads;
      };
      if (options.local_patch.enabled) {
        std::vector<std::uint8_t> wide(metrics.sj.size(), 0);
        bool any = false;
        for (std::size_t q = 0; q < wide.size(); ++q) any |= (wide[q] = severe(q) && in_large_map(q) && in_scope(q)) != 0;
        if (any) patch_locally(wide, options.local_patch.wide_rings, options.local_patch.wide_max_quads);
      }
      // Quads beside a crack (pieces that do not share their nodes) count as folded: their subregions are meshed
      // again, instead of the whole candidate failing the invariants after the last round.
      const std::vector<std::uint8_t> cracked = quads_beside_cracks(r.mesh);
      const auto cracks = static_cast<std::size_t>(std::count(cracked.begin(), cracked.end(), std::uint8_t{1}));
      // Subregions still holding a folded quad are meshed again (a mapped one as a patch, a patch by the matching
      // construction); the rest of the part keeps its maps. Valid quads outside the gates cost a subregion its map
      // only beyond the max_poor_fraction budget, worst subregion first: a 400-quad map is not traded for a
      // quad at SJ 0.18.
      std::map<int, std::string> bad;
      std::set<int> cracked_subregion;
      std::size_t first_folded = metrics.sj.size();
      std::map<int, std::pair<double, std::size_t>> poor_in;  // subregion -> (worst gate ratio, poor valid quads)
      std::size_t poor_valid = 0;
      for (std::size_t q = 0; q < metrics.sj.size(); ++q) {
        const bool folded = metrics.sj[q] <= 0.0;
        // Below the untangling's target a quad counts as folded there, and no solver can use it: it costs even a
        // large map (delta_box 20 m kept quads of SJ 1e-9 beside a feature crossing).
        const bool degenerate = !folded && !pinned[q] && metrics.sj[q] < options.smooth.untangle.target_sj;
        if (folded && first_folded == metrics.sj.size()) first_folded = q;
        const int s = subregion_of(q);
        if (cracked[q] && s >= 0) cracked_subregion.insert(s);
        if (cracked[q] && s >= 0) bad.emplace(s, "its quads do not share their nodes with a neighbour's (a crack) at " + at_text(r.mesh.nodes[r.mesh.quads[q][0]]));
        if (!poor[q]) continue;
        // Far outside a gate (severe) counts as folded outside large maps: the budget is for quads just outside,
        // not for near-degenerate ones a patch can mend. A patch is not rebuilt for a valid quad however poor:
        // its given nodes (the input's, the neighbours' interface nodes) fix that quad's shape for any
        // construction, and each rebuild re-maps the whole part.
        const bool in_patch = s >= 0 && !r.stats.subregions[static_cast<std::size_t>(s)].mapped;
        if (folded || (!in_patch && ((severe(q) && !in_large_map(q)) || degenerate))) {
          if (s >= 0)
            bad.emplace(s, "its map left a " +
                               std::string(folded ? "folded" : degenerate ? "degenerate (SJ " + std::to_string(metrics.sj[q]) + ")" : "near-degenerate") +
                               " quad at " + at_text(r.mesh.nodes[r.mesh.quads[q][0]]) + " after smoothing and local patches");
          if (folded) continue;
        }
        ++poor_valid;
        if (s < 0 || in_patch || in_large_map(q)) continue;
        // Below 1 the quad fails a gate; the smaller, the further.
        const double ratio = std::min(options.min_scaled_jacobian > 0 ? metrics.sj[q] / options.min_scaled_jacobian : 1.0,
                                      options.max_edge_ratio / metrics.edge_ratio[q]);
        auto [it, fresh] = poor_in.try_emplace(s, ratio, 0);
        it->second.first = std::min(it->second.first, ratio);
        it->second.second++;
      }
      std::vector<std::pair<double, int>> worst_first;
      for (const auto& [s, e] : poor_in) {
        if (bad.count(s)) poor_valid -= e.second;
        else worst_first.push_back({e.first, s});
      }
      std::sort(worst_first.begin(), worst_first.end());
      const double budget = options.max_poor_fraction * static_cast<double>(metrics.sj.size());
      for (const auto& [ratio, s] : worst_first) {
        if (static_cast<double>(poor_valid) <= budget) break;
        bad.emplace(s, "its map left " + std::to_string(poor_in[s].second) +
                           " quads below --min-sj or above --max-edge-ratio after smoothing and local patches, beyond "
                           "the --max-poor-fraction budget");
        poor_valid -= poor_in[s].second;
      }
      {
        std::size_t folded = 0;
        for (double v : metrics.sj) folded += v <= 0.0;
        c.summary["repair_rounds"].push_back({{"folded", folded}, {"beside_cracks", cracks}, {"poor_kept", poor_valid},
                                              {"remeshed", [&] {
                                                 std::vector<int> v;
                                                 for (const auto& b : bad) v.push_back(b.first);
                                                 return v;
                                               }()}});
      }
      if (round < options.repair_rounds) {
        // Mapped subregions becoming patches are patched in place, unless a crack beside one asks for new nodes
        // on its interfaces; a patch to be rebuilt otherwise (matching, grown) needs the part mapped again.
        const bool in_place_only =
            options.repair_in_place && std::all_of(bad.begin(), bad.end(), [&](const auto& b) {
              return r.stats.subregions[static_cast<std::size_t>(b.first)].mapped && !cracked_subregion.count(b.first);
            });
        if (repairs.add(bad, r.stats)) {
          if (in_place_only) in_place = bad;
          continue;
        }
      }
      // The invariants are checked once the repair rounds are over (a round that continues never reads them).
      inv = check_invariants(r.mesh);
      if (!inv.ok() && first_folded < metrics.sj.size() && options.local_patch.enabled) {
        // Quads still folded after every repair round: wider local patches around them alone, so that a few
        // folded quads do not send the whole part to the unstructured fallback.
        std::vector<std::uint8_t> folded(metrics.sj.size(), 0);
        for (std::size_t q = 0; q < metrics.sj.size(); ++q) folded[q] = metrics.sj[q] <= 0.0;
        patch_locally(folded, options.local_patch.wide_rings, options.local_patch.wide_max_quads);
        inv = check_invariants(r.mesh);
        first_folded = metrics.sj.size();
        for (std::size_t q = 0; q < metrics.sj.size() && first_folded == metrics.sj.size(); ++q)
          if (metrics.sj[q] <= 0.0) first_folded = q;
      }
      if (!inv.ok() && !r.stats.subregions.empty()) {
        // How far the refused candidate got: its mapped and patched subregions, and why the patched ones are.
        std::size_t mapped = 0, mapped_quads = 0, all_quads = 0;
        std::map<std::string, int> reasons;
        for (const SubregionStats& sr : r.stats.subregions) {
          all_quads += sr.quads;
          if (sr.mapped) { ++mapped; mapped_quads += sr.quads; continue; }
          std::string why;  // numbers and coordinates blanked, so that alike reasons count together
          for (char ch : sr.reason.substr(std::min(sr.reason.size(), name.size())))
            if (!(std::isdigit(static_cast<unsigned char>(ch)) || ch == '.' || ch == '-') || why.empty() || why.back() != '#')
              why += std::isdigit(static_cast<unsigned char>(ch)) ? '#' : ch;
          reasons[why.substr(0, 140)]++;
        }
        c.summary["refused_mesh"] = {{"subregions", r.stats.subregions.size()}, {"mapped", mapped},
                                     {"structured_fraction", all_quads ? double(mapped_quads) / double(all_quads) : 0.0},
                                     {"patch_reasons", reasons}};
      }
      if (!inv.ok())
        throw MeshingError(name + ": the mesh breaks an invariant (" + inv.first_problem +
                           (first_folded < metrics.sj.size() ? "; first folded quad" + in_subregion(first_folded) : "") +
                           ")");
      break;
    }
    c.summary["stage_seconds"] = {{"map", t_first_map}, {"map_of", first_map}, {"repair_maps", t_map - t_first_map},
                                  {"repair_patches", t_repair_patches},
                                  {"refine", t_refine}, {"smooth", t_smooth}, {"local_patches", t_local},
                                  {"relax_valences", t_relax},
                                  {"measure", t_measure}};
    std::vector<std::uint8_t> singular_node;
    const QualityReport q = compute_quality(r.mesh, metrics, &singular_node);
    c.min_sj = q.sj.min;
    c.max_edge_ratio = q.edge_ratio.max;
    c.interior_singularities = q.interior_singularities;
    const double mean_area = mesh_area(r.mesh) / static_cast<double>(r.mesh.quads.size()) / (options.size * options.size);
    c.size_deviation = std::abs(std::log(mean_area));
    c.summary["quads"] = r.mesh.quads.size();
    if (local_stats.clusters > 0)
      c.summary["local_patches"] = {{"clusters", local_stats.clusters}, {"patched", local_stats.patched},
                                    {"quads_removed", local_stats.quads_removed}, {"quads_added", local_stats.quads_added}};
    if (!c.summary.contains("fallback")) {
      // Quads of mapped subregions, less those local patches made; subregion figures follow the final mesh.
      for (SubregionStats& sr : r.stats.subregions) sr.quads = sr.local_patch_quads = 0;
      std::size_t unstructured = 0;
      // Where the interior singular nodes are: 2 = at a local patch's quad, 1 = at a patched subregion's, 0 = maps.
      std::vector<std::uint8_t> origin(r.mesh.nodes.size(), 0);
      for (std::size_t q = 0; q < r.mesh.quads.size(); ++q) {
        const bool local = q < local_patched.size() && local_patched[q];
        const int s = subregion_of(q);
        bool patch = local;
        if (s >= 0) {
          SubregionStats& sr = r.stats.subregions[static_cast<std::size_t>(s)];
          sr.quads++;
          sr.local_patch_quads += local;
          unstructured += local || !sr.mapped;
          patch = patch || !sr.mapped;
        } else {
          unstructured += local;
        }
        const std::uint8_t o = local ? 2 : (patch ? 1 : 0);
        for (std::int32_t v : r.mesh.quads[q]) origin[static_cast<std::size_t>(v)] = std::max(origin[static_cast<std::size_t>(v)], o);
      }
      c.structured = r.mesh.quads.empty() ? 1.0 : 1.0 - static_cast<double>(unstructured) / static_cast<double>(r.mesh.quads.size());
      std::array<std::size_t, 3> singular{0, 0, 0};
      for (std::size_t v = 0; v < r.mesh.nodes.size(); ++v)
        if (singular_node[v]) singular[origin[v]]++;
      c.summary["interior_singularities_at"] = {{"maps", singular[0]}, {"subregion_patches", singular[1]},
                                                {"local_patches", singular[2]}};
    }
    c.summary["structured_fraction"] = c.structured;
    c.summary["min_scaled_jacobian"] = c.min_sj;
    c.summary["max_edge_ratio"] = c.max_edge_ratio;
    c.summary["interior_singularities"] = c.interior_singularities;
    c.summary["mean_area_over_size_squared"] = mean_area;
    double gated_sj = 1.0, gated_edge_ratio = 1.0, pinned_sj = 1.0;
    std::size_t pinned_count = 0, pinned_worst = 0;
    for (std::size_t q = 0; q < pinned.size(); ++q) {
      if (pinned[q]) {
        if (pinned_count++ == 0 || metrics.sj[q] < pinned_sj) pinned_worst = q;
        pinned_sj = std::min(pinned_sj, metrics.sj[q]);
        continue;
      }
      gated_sj = std::min(gated_sj, metrics.sj[q]);
      gated_edge_ratio = std::max(gated_edge_ratio, metrics.edge_ratio[q]);
    }
    c.gated_sj = gated_sj;
    if (pinned_count > 0) {
      c.summary["quads_pinned_by_sharp_input"] = pinned_count;
      c.summary["pinned_min_scaled_jacobian"] = pinned_sj;
      const Vec2 p = r.mesh.nodes[r.mesh.quads[pinned_worst][0]];
      c.summary["pinned_worst_at"] = {p.x, p.y};
      c.summary["unpinned_min_scaled_jacobian"] = gated_sj;
    }
    // Unpinned quads outside the gates that every repair left as they are: accepted, each reported with its
    // place, while they are few (max_poor_fraction); the mesh is refused with the worst of them otherwise.
    std::vector<std::size_t> outside;
    for (std::size_t q = 0; q < pinned.size(); ++q)
      if (!pinned[q] && (metrics.sj[q] < options.min_scaled_jacobian || metrics.edge_ratio[q] > options.max_edge_ratio))
        outside.push_back(q);
    c.poor_quads = outside.size();
    const bool refused = static_cast<double>(outside.size()) >
                         options.max_poor_fraction * static_cast<double>(r.mesh.quads.size());
    auto at = [&](const std::vector<double>& per_quad, bool largest) {
      std::size_t worst = outside.front();
      for (std::size_t q : outside)
        if (largest ? per_quad[q] > per_quad[worst] : per_quad[q] < per_quad[worst]) worst = q;
      return at_text(r.mesh.nodes[r.mesh.quads[worst][0]]) + in_subregion(worst);
    };
    const std::string how_many = " (" + std::to_string(outside.size()) + " of " + std::to_string(r.mesh.quads.size()) +
                                 " quads outside the gates, above --max-poor-fraction " +
                                 std::to_string(options.max_poor_fraction) + ")";
    if (refused && gated_edge_ratio > options.max_edge_ratio)
      throw MeshingError(name + ": the best mesh has a quad with edge ratio " + std::to_string(gated_edge_ratio) +
                         " at " + at(metrics.edge_ratio, true) + ", above the maximum " +
                         std::to_string(options.max_edge_ratio) + " (--max-edge-ratio)" + how_many);
    if (refused)
      throw MeshingError(name + ": the best mesh has a quad with scaled Jacobian " + std::to_string(gated_sj) + " at " +
                         at(metrics.sj, false) + ", below the minimum " +
                         std::to_string(options.min_scaled_jacobian) + " (--min-sj)" + how_many);
    if (!outside.empty()) {
      nlohmann::json places = nlohmann::json::array();
      for (std::size_t q : outside) {
        if (places.size() == 20) break;
        const Vec2 p = r.mesh.nodes[r.mesh.quads[q][0]];
        nlohmann::json j = {{"at", {p.x, p.y}}, {"scaled_jacobian", metrics.sj[q]}, {"edge_ratio", metrics.edge_ratio[q]}};
        if (subregion_of(q) >= 0) j["subregion"] = subregion_of(q);
        places.push_back(std::move(j));
      }
      c.summary["poor_quads"] = {{"count", outside.size()},
                                 {"fraction", static_cast<double>(outside.size()) / static_cast<double>(r.mesh.quads.size())},
                                 {"first", places}};
    }
    c.result = std::move(r);
  } catch (const MeshingError& e) {
    c.error = e.what();
    c.summary["error"] = c.error;
  }
  c.summary["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  return c;
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

}  // namespace

MeshResult mesh_region(const Region& region, const MeshOptions& options) {
  const std::string src = region.source.empty() ? std::string("region") : region.source;
  check_mesh_options(options);      // NaN gates and out-of-range values, named by their flag
  check_mesh_size(region, options);  // size against the region's extent and the quad budget
  const Box2 box = region.bounding_box();
  const double area = region_area(region);

  const auto t_start = std::chrono::steady_clock::now();
  ProgressReporter progress(options.progress);
  progress.start("simplify");
  // Curves far finer than h (coastlines) are simplified first; the mesh then follows the simplified curves and
  // the quality report measures the distance to the original ones.
  Region simplified;
  const Region* work = &region;
  SimplifyStats simplify_stats;
  SnapStats end_snaps;
  std::vector<DroppedCurve> dropped_curves;
  if (options.simplify > 0.0) {
    simplified = region;
    // Islands and faces between curves narrower than the size hold no quad of that size: their curves go first.
    dropped_curves = drop_narrow_islands(simplified, options.min_island_width * options.size);
    for (DroppedCurve& d : collapse_narrow_faces(simplified, options.min_island_width * options.size))
      dropped_curves.push_back(d);
    for (DroppedCurve& d : open_narrow_wedges(simplified, options.min_island_width * options.size))
      dropped_curves.push_back(d);
    // Feature curves that end a small fraction of the size short of the boundary or of another curve (crossing
    // points computed in another projection) are joined to it first: a gap far below h cannot be meshed, and a
    // curve that reaches the boundary splits the part into feature faces for the partition.
    end_snaps = snap_near_coincident(simplified, 0.1 * options.size / std::max(box.diagonal(), 1e-300), nullptr);
    SimplifyOptions so;
    so.min_area = (options.simplify * options.size) * (options.simplify * options.size);
    so.max_distance = options.size;  // the simplified curves stay within h of the input
    so.max_segment = options.size;   // and are coarsened to the size, not beyond
    so.smooth_distance = options.smooth_curves * options.size;
    simplify_stats = simplify_region(simplified, so);
    work = &simplified;
  } else {
    // Unsimplified rings are still meshed with chords: where one could cut across another curve, ring vertices
    // become nodes (as simplify_region does last), so that parts and islands close to each other do not overlap.
    simplified = region;
    simplify_stats.chord_pins = pin_chords_clear_of_curves(simplified, options.size).size();
    work = &simplified;
  }
  progress.finish("simplify");
  PolysquareMapOptions map = options.map;
  map.deform.memo = std::make_shared<DeformMemo>();  // this run's solved deformations (repair rounds repeat them)
  map.quantize.memo = std::make_shared<QuantizeMemo>();  // and its layouts quantized alone
  map.size = options.size;
  map.layout.corner_threshold_deg = options.corner_threshold_deg;
  map.keep_partition = options.keep_partition;
  map.partition.seed = options.seed;
  // Polygon parts smaller than one element (islets, slivers of a coastline at this size) cannot hold a quad:
  // with drop_small_parts they are left out and listed in the report, never silently.
  std::vector<RegionPart> parts;
  nlohmann::json dropped = nlohmann::json::array();
  for (RegionPart& p : split_into_parts(*work)) {
    const double a = part_area(*work, p);
    if (options.drop_small_parts && a < options.size * options.size) {
      const Vec2 at = work->rings[static_cast<std::size_t>(p.rings.front())].points.front();
      dropped.push_back({{"part", p.part}, {"area", a}, {"at", {at.x, at.y}}});
      continue;
    }
    parts.push_back(std::move(p));
  }
  if (parts.empty())
    throw MeshingError(src + ": every polygon part is smaller than one element (size^2 = " +
                       std::to_string(options.size * options.size) + "); use a smaller size");

  // Parts are independent: mesh them in parallel; results land in part order, so the output does not depend
  // on the thread count. A failure in one part is recorded and reported with all the others, never dropped.
  std::vector<std::optional<PartMapResult>> results(parts.size());
  std::vector<std::string> errors(parts.size());
  std::vector<nlohmann::json> tried(parts.size());
  std::vector<SmoothStats> smoothed(parts.size());
  std::vector<double> structured(parts.size(), 0.0);  // fraction of each part's quads from poly-square maps
  std::vector<std::size_t> poor_quads(parts.size(), 0);  // quads accepted outside the gates (max_poor_fraction)
  // One thread limit for every parallel stage (parts, candidates, subregions, colours in smoothing).
  const int threads = options.threads > 0 ? options.threads : static_cast<int>(oneapi::tbb::info::default_concurrency());
  oneapi::tbb::global_control limit(oneapi::tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
  progress.start("mesh parts");
  // Several processes (PolysquareMapOptions::sharing) divide among them the parts when there are several, else
  // the candidates of a round when there are several, else the subregions of a map; each process meshes what it
  // was given with its threads alone, and the results are copied to all of them.
  auto mesh_part = [&](std::size_t k, const PolysquareMapOptions& map) {
    const ProgressReporter::Item part_done(progress, "mesh parts", parts.size());
    std::vector<CandidateSpec> ks;
    std::vector<Candidate> cands;
    int best = -1;
    for (const std::vector<CandidateSpec>& round : candidate_rounds(*work, parts[k], options)) {
      const bool retry = std::none_of(round.begin(), round.end(), [](const CandidateSpec& c) { return c.split; });
      if (retry && best >= 0) continue;
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
        if (ks[c].fine) part_map.parameterization_ratio = options.fine_parameterization_ratio;
        cands[c] = try_candidate(*work, parts[k], part_map, options);
      };
      if (share_candidates)
        shared_for(map.sharing.get(), ks.size() - first, {}, "candidates", [&](std::size_t i) { mesh_candidate(first + i); },
                   [&](std::size_t i, ByteWriter& w) { put_bytes(w, cands[first + i]); },
                   [&](std::size_t i, ByteReader& r) { get_bytes(r, cands[first + i]); });
      else
        for_each_task(several_processes(map), first, ks.size(), mesh_candidate);
      for (std::size_t c = first; c < cands.size(); ++c) {
        tried[k].push_back(cands[c].summary);
        if (cands[c].error.empty() && (best < 0 || cands[c].better_than(cands[static_cast<std::size_t>(best)])))
          best = static_cast<int>(c);
      }
      // A later round is meshed while the best mesh so far holds unstructured patches nobody asked for; the
      // best of all wins.
      const Candidate& b = cands[static_cast<std::size_t>(std::max(best, 0))];
      if (best >= 0 && b.poor_quads == 0 && (b.structured >= 1.0 || !options.map.patch_subregions.empty()))
        break;
    }
    if (best < 0 && options.split_fallback) {
      cands.push_back(try_split_fallback(*work, parts[k], options));
      ks.push_back({0, false});
      tried[k].push_back(cands.back().summary);
      if (cands.back().error.empty()) best = static_cast<int>(cands.size()) - 1;
    }
    if (best < 0) {
      // Candidates that failed for the same reason (a triangle budget no candidate fits in) are named together
      // before it, so the message says each reason once.
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
      errors[k] = all;
      return;
    }
    tried[k][static_cast<std::size_t>(best)]["chosen"] = true;
    smoothed[k] = cands[static_cast<std::size_t>(best)].smooth;
    structured[k] = cands[static_cast<std::size_t>(best)].structured;
    poor_quads[k] = cands[static_cast<std::size_t>(best)].poor_quads;
    results[k] = std::move(cands[static_cast<std::size_t>(best)].result);
  };
  if (several_processes(map) && parts.size() > 1) {
    PolysquareMapOptions alone = map;
    alone.sharing = nullptr;
    std::vector<double> cost(parts.size());
    for (std::size_t k = 0; k < parts.size(); ++k) cost[k] = part_area(*work, parts[k]);
    shared_for(map.sharing.get(), parts.size(), cost, "parts", [&](std::size_t k) { mesh_part(k, alone); },
               [&](std::size_t k, ByteWriter& w) {
                 w.put(static_cast<std::uint8_t>(results[k].has_value()));
                 if (results[k]) put_bytes(w, *results[k]);
                 w.put(errors[k]), w.put(tried[k].dump()), w.put(smoothed[k]), w.put(structured[k]), w.put(poor_quads[k]);
               },
               [&](std::size_t k, ByteReader& r) {
                 std::uint8_t has = 0;
                 r.get(has);
                 if (has) get_bytes(r, results[k].emplace());
                 std::string text;
                 r.get(errors[k]), r.get(text), r.get(smoothed[k]), r.get(structured[k]), r.get(poor_quads[k]);
                 tried[k] = nlohmann::json::parse(text);
               });
  } else {
    for_each_task(several_processes(map), std::size_t{0}, parts.size(), [&](std::size_t k) { mesh_part(k, map); });
  }
  std::ostringstream failed;
  int nfailed = 0;
  for (std::size_t k = 0; k < parts.size(); ++k)
    if (!errors[k].empty()) { failed << (nfailed++ ? "; " : "") << errors[k]; }
  if (nfailed > 0)
    throw MeshingError(std::to_string(nfailed) + " of " + std::to_string(parts.size()) + " parts failed: " + failed.str());
  const double seconds_parts = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  progress.finish("mesh parts");
  progress.start("assemble");

  MeshResult out;
  QuadMesh& mesh = out.mesh;
  mesh.crs = region.crs;
  mesh.units = region.units;
  std::int32_t subregion_offset = 0;
  nlohmann::json partition_json = nlohmann::json::array();
  for (auto& r : results) {
    const QuadMesh& m = r->mesh;
    const auto offset = static_cast<std::int32_t>(mesh.nodes.size());
    if (options.keep_partition && r->partition) {
      const auto voff = static_cast<std::int32_t>(out.background.vertices.size());
      out.background.vertices.insert(out.background.vertices.end(), r->background.vertices.begin(), r->background.vertices.end());
      for (auto t : r->background.triangles) out.background.triangles.push_back({t[0] + voff, t[1] + voff, t[2] + voff});
      for (TriChain ch : r->background.chains) {
        for (auto& v : ch.vertices) v += voff;
        out.background.chains.push_back(std::move(ch));
      }
      for (auto p : r->partition->triangle_part) out.background_part.push_back(p + subregion_offset);
    }
    if (r->partition) {
      const PartitionResult& pr = *r->partition;
      auto energy = [](const PartitionEnergy& e) {
        return nlohmann::json{{"separator_length", e.separator_length}, {"angle_deviation", e.angle_deviation},
                              {"feature_on_separators", e.feature_on_separators}, {"energy", e.energy}};
      };
      partition_json.push_back({{"part", r->stats.part}, {"subregions", pr.parts}, {"faces", pr.faces}, {"separators", r->stats.separators},
                                {"metis", energy(pr.metis)}, {"final", energy(pr.final)},
                                {"feature_fraction_metis", pr.feature_fraction_metis},
                                {"feature_fraction_final", pr.feature_fraction_final},
                                {"balance_max_over_avg", pr.balance_max_over_avg},
                                {"mh_accepted", pr.mh_accepted}, {"mh_proposed", pr.mh_proposed},
                                {"repaired_triangles", pr.repaired_triangles}, {"seconds", r->stats.seconds_partition}});
    }
    auto shift = [offset](auto arr) { for (auto& v : arr) v += offset; return arr; };
    mesh.nodes.insert(mesh.nodes.end(), m.nodes.begin(), m.nodes.end());
    mesh.node_kind.insert(mesh.node_kind.end(), m.node_kind.begin(), m.node_kind.end());
    for (const auto& q : m.quads) mesh.quads.push_back(shift(q));
    for (auto p : m.quad_part) mesh.quad_part.push_back(p + subregion_offset);
    subregion_offset += r->partition ? r->partition->parts : 1;
    for (const auto& e : m.boundary_edges) mesh.boundary_edges.push_back(shift(e));
    mesh.boundary_edge_ring.insert(mesh.boundary_edge_ring.end(), m.boundary_edge_ring.begin(), m.boundary_edge_ring.end());
    for (const auto& e : m.feature_edges) mesh.feature_edges.push_back(shift(e));
    mesh.feature_edge_curve.insert(mesh.feature_edge_curve.end(), m.feature_edge_curve.begin(), m.feature_edge_curve.end());
    out.parts.push_back(r->stats);
  }

  SmoothStats smooth;
  for (const SmoothStats& st : smoothed) {
    smooth.sweeps = std::max(smooth.sweeps, st.sweeps);
    smooth.moves += st.moves;
    smooth.curve_moves += st.curve_moves;
    smooth.untangle.folded_before += st.untangle.folded_before;
    smooth.untangle.folded_after += st.untangle.folded_after;
    smooth.untangle.moves += st.untangle.moves;
  }
  const InvariantReport inv = check_invariants(mesh);
  if (!inv.ok())
    throw MeshingError(src + ": the assembled mesh breaks an invariant (" + inv.first_problem + "); nothing was written");

  nlohmann::json parts_json = nlohmann::json::array();
  for (const auto& s : out.parts) parts_json.push_back(part_json(s));
  // The summary outside checks read: how much of the mesh is semi-structured, and where it is not.
  double structured_quads = 0.0;
  std::size_t subregion_count = 0, local_patch_quads = 0;
  nlohmann::json unstructured = nlohmann::json::array();
  for (std::size_t k = 0; k < parts.size(); ++k) {
    const PartMapStats& st = results[k]->stats;
    structured_quads += structured[k] * static_cast<double>(results[k]->mesh.quads.size());
    if (st.subregions.empty()) {
      ++subregion_count;
      // One map for the whole part: what is not structured there was made by local patches.
      if (structured[k] > 0.0)
        local_patch_quads += static_cast<std::size_t>(
            std::llround((1.0 - structured[k]) * static_cast<double>(results[k]->mesh.quads.size())));
      if (structured[k] == 0.0) {
        const Vec2 at = work->rings[static_cast<std::size_t>(parts[k].rings.front())].points.front();
        unstructured.push_back({{"part", st.part}, {"subregion", -1}, {"quads", results[k]->mesh.quads.size()},
                                {"meshed_by", "split_triangles"}, {"at", {at.x, at.y}}});
      }
    }
    for (const SubregionStats& sr : st.subregions) {
      ++subregion_count;
      local_patch_quads += sr.mapped ? sr.local_patch_quads : 0;
      if (!sr.mapped)
        unstructured.push_back({{"part", st.part}, {"subregion", sr.subregion}, {"quads", sr.quads},
                                {"meshed_by", "patch"}, {"at", {sr.at.x, sr.at.y}}, {"reason", sr.reason}});
    }
  }
  // Quads below SJ 0.3 that no conforming mesh avoids: at an input corner, or inside a wedge between two curves,
  // sharper than asin(0.3) (17.5 degrees) and within a size of it. Reported apart from the rest below 0.3.
  std::size_t below_0_3 = 0, pinned_below_0_3 = 0;
  {
    const std::vector<std::uint8_t> pinned = quads_pinned_by_sharp_input(mesh, 0.3, options.size);
    for (std::size_t q = 0; q < mesh.quads.size(); ++q)
      if (quad_min_corner_sj(mesh, q) < 0.3) {
        ++below_0_3;
        pinned_below_0_3 += pinned[q];
      }
  }
  const nlohmann::json summary = {
      {"quads", mesh.quads.size()},
      {"sj_below_0_3_pinned", pinned_below_0_3},
      {"sj_below_0_3_unpinned_fraction",
       mesh.quads.empty() ? 0.0 : static_cast<double>(below_0_3 - pinned_below_0_3) / static_cast<double>(mesh.quads.size())},
      {"structured_fraction", mesh.quads.empty() ? 0.0 : structured_quads / static_cast<double>(mesh.quads.size())},
      {"subregions", subregion_count},
      {"unstructured_subregions", unstructured.size()},
      {"local_patch_quads", local_patch_quads},
      {"poor_quads", std::accumulate(poor_quads.begin(), poor_quads.end(), std::size_t{0})},
      {"seconds", std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count()},
      {"version", library_version()}};
  out.report = {
      {"summary", summary},
      {"unstructured", unstructured},
      {"input", {{"source", region.source}, {"crs", region.crs}, {"units", region.units},
                 {"parts", region.num_parts}, {"rings", region.rings.size()}, {"feature_curves", region.features.size()},
                 {"area", area}}},
      {"options", {{"size", options.size}, {"threads", options.threads}, {"seed", options.seed},
                   {"corner_threshold_deg", options.corner_threshold_deg}, {"max_quads", options.max_quads},
                   {"min_scaled_jacobian", options.min_scaled_jacobian}, {"max_edge_ratio", options.max_edge_ratio},
                   {"map", options.parts == 1 ? "single poly-square per part"
                                              : (map.composition == MapComposition::gpm ? "gpm" : "ppm")}, {"subregions_per_part", options.parts},
                   {"amips_alpha", map.deform.amips_alpha}, {"amips_s", map.deform.amips_s},
                   {"boundary_weight", map.deform.boundary_weight}, {"feature_weight", map.deform.feature_weight},
                   {"parameterization_ratio", map.parameterization_ratio},
                   {"feature_tolerance", options.feature_tolerance},
                   {"flat_corner_deg", options.refine.enabled ? options.refine.flat_corner_deg : 180.0},
                   {"loop_corner_deg", options.refine.enabled ? options.refine.loop_corner_deg : 180.0}}},
      {"counts", {{"nodes", mesh.nodes.size()}, {"quads", mesh.quads.size()},
                  {"boundary_edges", mesh.boundary_edges.size()}, {"feature_edges", mesh.feature_edges.size()}}},
      {"parts", parts_json},
      {"partition", partition_json},
      {"candidates", tried},
      {"dropped_parts", dropped},
      {"dropped_curves", dropped_json(dropped_curves)},
      {"simplify", {{"fraction_of_size", options.simplify}, {"smooth_curves_fraction_of_size", options.smooth_curves}, {"vertices_before", simplify_stats.vertices_before},
                    {"vertices_after", simplify_stats.vertices_after}, {"refused", simplify_stats.refused},
                    {"max_distance", simplify_stats.max_distance},
                    {"max_distance_over_size", simplify_stats.max_distance / options.size},
                    {"chord_pins", simplify_stats.chord_pins},
                    {"end_points_snapped", end_snaps.to_vertex + end_snaps.to_segment},
                    {"largest_snap", end_snaps.largest_move},
                    {"area_change", area != 0.0 ? region_area(*work) / area - 1.0 : 0.0}}},
      {"smooth", {{"sweeps", smooth.sweeps}, {"moves", smooth.moves}, {"curve_moves", smooth.curve_moves},
                  {"untangle", {{"target_sj", options.smooth.untangle.target_sj},
                                {"below_target_before", smooth.untangle.folded_before},
                                {"below_target_after", smooth.untangle.folded_after},
                                {"moves", smooth.untangle.moves}}}}},
      {"seconds", {{"parts", seconds_parts}}},
  };
  out.region = work == &region ? region : std::move(simplified);
  progress.finish("assemble");
  return out;
}

}  // namespace polysquare
