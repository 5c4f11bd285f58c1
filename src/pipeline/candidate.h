// A part's candidates: the ways of meshing it that the search tries (candidates.cpp), and the one finishing
// sequence every candidate goes through, round after round (finish_candidate.cpp).
#pragma once

#include <cmath>
#include <cstddef>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "polysquare/core/region.h"
#include "polysquare/core/work_sharing.h"
#include "polysquare/map/polysquare_map.h"
#include "polysquare/pipeline/mesh_region.h"

namespace polysquare::pipeline {

// "FILE: part P", how messages name a part.
std::string name_of(const Region& region, const RegionPart& part);

// A map's split rounds, as the report and the candidates' summaries give them (region_report.cpp).
SplitReport split_report(const PartMapStats& s);

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
                                                         const MeshOptions& options, const PolysquareMapOptions& map);

// One way of meshing a part: the map, then smoothing, then the checks every output must pass.
struct Candidate {
  std::optional<PartMapResult> result;
  SmoothStats smooth;
  double min_sj = -2.0, max_edge_ratio = 0.0;
  double gated_sj = -2.0;  // SJ min without the quads pinned by sharp input corners: what the mesher controls
  std::size_t interior_singularities = 0;
  std::string error;
  CandidateReport summary;

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
void put_bytes(ByteWriter& w, const Candidate& c);
void get_bytes(ByteReader& r, Candidate& c);

// What a candidate is meshed again with, after a round left folded or poor quads in some subregions: mapped
// subregions become patches, patches are built by the other (matching) construction.
struct Repairs {
  std::vector<int> patches, matched, grown;
  std::map<int, std::string> why;  // a subregion of `patches` -> why its map was given up
  // Adds the subregions in `bad` (subregion -> what is wrong with its quads); false when none of them can be
  // repaired further. A mapped one becomes a patch, a patch is built by the matching construction, and a
  // matched patch grows over its neighbours.
  bool add(const std::map<int, std::string>& bad, const PartMapStats& stats);
};

// Makes a candidate's mesh (a map of the part, or the fallback) with the repairs asked for so far.
using MakeMesh = std::function<PartMapResult(const Repairs&)>;

// Meshes a part with `make_mesh` (a map candidate or the fallback), then smooths, checks and measures it; patches
// follow `field` (graded runs; null: uniform).
Candidate finish_candidate(const Region& region, const RegionPart& part, const MeshOptions& options,
                           std::shared_ptr<const SizeField> field, CandidateReport summary, const MakeMesh& make_mesh);

// The candidate of `map` (its partition.parts subregions), finished.
Candidate try_candidate(const Region& region, const RegionPart& part, const PolysquareMapOptions& map,
                        const MeshOptions& options);

// The last resort for a part no poly-square candidate meshes: triangles split into quads (unstructured).
Candidate try_split_fallback(const Region& region, const RegionPart& part, const MeshOptions& options);

}  // namespace polysquare::pipeline
