// Repairs of a finished candidate's subregions: which construction a subregion is meshed with again, and the
// patches cut into the finished mesh in place of mapped subregions.
#include <algorithm>
#include <limits>

#include "pipeline/finish_candidate.h"
#include "polysquare/refine/local_patch.h"

namespace polysquare::pipeline {

bool Repairs::add(const std::map<int, std::string>& bad, const PartMapStats& stats) {
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

// Cuts the quads of the subregions `cut` out of a finished part mesh and meshes each hole again as one patch on
// its boundary loop (refine/local_patch.h, the subregion's quads alone first), so that the rest of the part keeps
// its quads, their smoothing and their local patches: a repair round that mapped the part again redid all three
// (delta_box 10 m: 350 s a round). `local_patched` (#quads) is carried; the new quads are the subregions' own.
// False when a subregion keeps some of its quads (the mesh may have changed: the caller maps the part again).
bool patch_subregions_in_place(QuadMesh& mesh, const std::map<int, std::string>& cut, const MeshOptions& options,
                               const std::shared_ptr<const SizeField>& field, std::vector<std::uint8_t>& local_patched) {
  if (mesh.quad_part.size() != mesh.quads.size()) return false;
  const std::size_t nq = mesh.quads.size();
  std::vector<std::int32_t> region(nq, -1);
  std::vector<std::uint8_t> made(nq, 0);
  for (std::size_t q = 0; q < nq; ++q) {
    if (cut.count(mesh.quad_part[q])) region[q] = mesh.quad_part[q];  // each subregion a patch of its own
    made[q] = q < local_patched.size() && local_patched[q] ? 2 : 0;  // the new quads come back as 1
  }
  LocalPatchOptions lp = options.local_patch;
  lp.size = options.size.h;
  lp.size_field = field;
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

}  // namespace polysquare::pipeline
