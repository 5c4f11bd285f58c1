// The gates a candidate mesh must pass, and the repairs tried on subregions that miss them
// (src/pipeline/candidate_verdict.cpp judges, src/pipeline/finish_candidate.cpp repairs).
#pragma once

#include <cstddef>

namespace polysquare {

struct GateOptions {
  double min_scaled_jacobian = 0.2;    ///< a candidate with a quad below this is refused (see max_poor_fraction);
                                       ///< 0 = accept any valid mesh
  double max_edge_ratio = 20.0;        ///< refuse a mesh with a quad whose longest / shortest edge exceeds this
  double max_poor_fraction = 0.001;    ///< valid quads outside the two gates above that local patches did not mend
                                       ///< are accepted, each reported with its place, while they are at most this
                                       ///< fraction of the part's quads; the repair rounds turn their subregions
                                       ///< into patches only beyond it, worst first (always for a quad below half
                                       ///< the SJ gate or above twice the edge-ratio gate), and a candidate with more
                                       ///< is refused. A candidate with none wins over one with some. 0 = every quad
                                       ///< must pass both gates (folded quads are never accepted)
  double feature_tolerance = 0.1;      ///< largest distance, as a fraction of size, between a feature curve and the
                                       ///< mesh edges along it that smoothing allows (SmoothOptions::feature_tolerance);
                                       ///< 0 = unbounded
};

struct RepairOptions {
  bool split_fallback = true;     ///< a part no poly-square candidate meshes gets an unstructured all-quad mesh
                                  ///< (triangles split into three quads), reported under `fallbacks`; false: refuse
  int rounds = 4;                 ///< times a candidate is meshed again with the mapped subregions whose quads stay
                                  ///< folded after smoothing turned into patches (local repair)
  bool in_place = true;           ///< a repair round that only turns mapped subregions into patches cuts their
                                  ///< quads out of the finished mesh and patches each hole on its boundary nodes
                                  ///< (the rest keeps its quads, smoothing and local patches); false: the part is
                                  ///< mapped again with them as patches (their neighbours' counts quantized again)
  std::size_t keep_map_above_quads = 300;  ///< a mapped subregion of more quads keeps its map whatever valid quads
                                          ///< it holds outside the gates (they get the widest local patches and are
                                          ///< reported as poor quads): its patch would add more singular nodes
                                          ///< (about one per seven quads) than the quads it mends. Not for a quad
                                          ///< below smooth.untangle.target_sj that no sharp input corner pins: that
                                          ///< one counts as folded in any map
};

}  // namespace polysquare
