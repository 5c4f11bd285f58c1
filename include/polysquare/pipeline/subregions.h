// Stage 3 as mesh_region runs it: into how many subregions each polygon part is partitioned, and which counts
// (candidates) it tries before keeping the best mesh (src/pipeline/candidates.cpp).
#pragma once

#include <cstddef>
#include <vector>

namespace polysquare {

struct SubregionOptions {
  int parts = 0;                 ///< subregions per polygon part. 0 = automatic: a part above search_quads quads
                                 ///< is meshed one way, with max(its quads / target_quads_per_part, its boundary
                                 ///< length / (perimeter_per_subregion * size)) subregions (feature curves count
                                 ///< twice), plus one poly-square (see single_map_quads); smaller
                                 ///< parts also try one poly-square and the counts of search_subregions, and the
                                 ///< best mesh is kept. K > 0: K subregions, one poly-square if that fails.
  std::size_t target_quads_per_part = 20000;  ///< subregion size for large parts in automatic mode
  double perimeter_per_subregion = 30.0;      ///< boundary length per subregion in automatic mode, in sizes
  int max_automatic_subregions = 64;          ///< cap on the boundary-length count (each subregion adds columns
                                              ///< and coupling rows to the part's one mixed-integer quantization)
  std::size_t single_map_quads = 100'000;     ///< automatic mode: a part above search_quads quads with a
                                              ///< convoluted boundary is meshed as one poly-square beside its
                                              ///< partition up to this many quads; a larger one only when its
                                              ///< partition fails (one map must close every side of the part at
                                              ///< once, which failed on every coast tried beyond this size)
  std::size_t search_quads = 5'000;           ///< parts up to this many quads try every count of search_subregions
  std::vector<int> search_subregions{2, 3, 4, 5, 6, 8};
  double fine_parameterization_ratio = 0.5;   ///< automatic mode, parts up to search_quads quads: when no
                                              ///< candidate is fully structured, the straight ones are meshed
                                              ///< again with background edges of this many sizes on the curves
                                              ///< (PolysquareMapOptions::parameterization_ratio); 0 = off
  double graded_quads_per_subregion = 150.0;  ///< graded meshes: at least one subregion per this many quads of
                                             ///< the field. A map has no singular node inside, so it absorbs
                                             ///< the size's change across it by stretching its quads; the
                                             ///< subregions' corners, where the singular nodes go, must come
                                             ///< about as often as the grading needs them (one per ~70 quads
                                             ///< at a gradient of 0.15, 2 G^2 / pi of the quads); at
                                             ///< gradients G below graded_reference_grade, times
                                             ///< (graded_reference_grade / G)^2
  double graded_reference_grade = 0.15;      ///< the gradient graded_quads_per_subregion is meant for
  std::size_t bent_round_quads = 5'000;       ///< automatic mode retries partitions with bendable interfaces only
                                              ///< for parts up to this many quads (larger parts spent long there
                                              ///< and rarely gained)
};

/// A graded part's quads per subregion at gradient `grade`: graded_quads_per_subregion, times
/// (graded_reference_grade / grade)^2 below the reference gradient.
double graded_subregion_quads(const SubregionOptions& options, double grade);

}  // namespace polysquare
