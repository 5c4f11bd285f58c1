// A finished candidate measured for the search (quality, structure, pinned quads) and judged by the gates: the
// poor quads every repair left are accepted while few, and the candidate refused otherwise.
#include <algorithm>
#include <array>
#include <cmath>

#include "pipeline/finish_candidate.h"
#include "polysquare/core/error.h"

namespace polysquare::pipeline {
namespace {

// The gated figures: the worst quads the mesher controls (pinned ones left out).
struct Gated {
  double sj = 1.0, edge_ratio = 1.0;
};

// Quads of mapped subregions, less those local patches made; subregion figures follow the final mesh. Also where
// the interior singular nodes are (`singular_node`, #nodes).
void measure_structure(FinishWork& w, const std::vector<std::uint8_t>& singular_node) {
  PartMapResult& r = w.r;
  for (SubregionStats& sr : r.stats.subregions) sr.quads = sr.local_patch_quads = 0;
  std::size_t unstructured = 0;
  // Where the interior singular nodes are: 2 = at a local patch's quad, 1 = at a patched subregion's, 0 = maps.
  std::vector<std::uint8_t> origin(r.mesh.nodes.size(), 0);
  for (std::size_t q = 0; q < r.mesh.quads.size(); ++q) {
    const bool local = q < w.local_patched.size() && w.local_patched[q];
    const int s = subregion_of(w, q);
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
  w.c.structured = r.mesh.quads.empty() ? 1.0 : 1.0 - static_cast<double>(unstructured) / static_cast<double>(r.mesh.quads.size());
  std::array<std::size_t, 3> singular{0, 0, 0};
  for (std::size_t v = 0; v < r.mesh.nodes.size(); ++v)
    if (singular_node[v]) singular[origin[v]]++;
  w.c.summary.interior_singularities_at = SingularitiesAtReport{singular[0], singular[1], singular[2]};
}

// The candidate's quality for the search: SJ, edge ratio, singular nodes, element size, structured fraction.
void measure_quality(FinishWork& w) {
  Candidate& c = w.c;
  const PartMapResult& r = w.r;
  std::vector<std::uint8_t> singular_node;
  const QualityReport q = compute_quality(r.mesh, w.metrics, &singular_node);
  c.min_sj = q.sj.min;
  c.max_edge_ratio = q.edge_ratio.max;
  c.interior_singularities = q.interior_singularities;
  const double mean_area =
      mesh_area(r.mesh) / static_cast<double>(r.mesh.quads.size()) / (w.options.size.h * w.options.size.h);
  c.size_deviation = std::abs(std::log(mean_area));
  const LocalPatchStats& local_stats = w.local_stats;
  if (local_stats.clusters > 0)
    c.summary.local_patches = LocalPatchesReport{local_stats.clusters, local_stats.patched, local_stats.quads_removed,
                                                 local_stats.quads_added};
  if (!c.summary.fallback) measure_structure(w, singular_node);
  c.summary.measures = CandidateMeasures{r.mesh.quads.size(), c.structured, c.min_sj, c.max_edge_ratio,
                                         c.interior_singularities, mean_area};
}

// The worst quads the mesher controls, and the quads pinned by sharp input corners apart.
Gated measure_pinned(FinishWork& w) {
  const QuadMetrics& metrics = w.metrics;
  const std::vector<std::uint8_t>& pinned = w.pinned;
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
  w.c.gated_sj = gated_sj;
  if (pinned_count > 0) {
    const Vec2 p = w.r.mesh.nodes[w.r.mesh.quads[pinned_worst][0]];
    w.c.summary.pinned = PinnedReport{pinned_count, pinned_sj, p, gated_sj};
  }
  return {gated_sj, gated_edge_ratio};
}

// Unpinned quads outside the gates that every repair left as they are: accepted, each reported with its
// place, while they are few (max_poor_fraction); the mesh is refused with the worst of them otherwise.
void accept_poor_quads(FinishWork& w, const Gated& gated) {
  const MeshOptions& options = w.options;
  const QuadMetrics& metrics = w.metrics;
  const PartMapResult& r = w.r;
  std::vector<std::size_t> outside;
  for (std::size_t q = 0; q < w.pinned.size(); ++q)
    if (!w.pinned[q] &&
        (metrics.sj[q] < options.gates.min_scaled_jacobian || metrics.edge_ratio[q] > options.gates.max_edge_ratio))
      outside.push_back(q);
  w.c.poor_quads = outside.size();
  const bool refused =
      static_cast<double>(outside.size()) > options.gates.max_poor_fraction * static_cast<double>(r.mesh.quads.size());
  auto at = [&](const std::vector<double>& per_quad, bool largest) {
    std::size_t worst = outside.front();
    for (std::size_t q : outside)
      if (largest ? per_quad[q] > per_quad[worst] : per_quad[q] < per_quad[worst]) worst = q;
    return at_text(r.mesh.nodes[r.mesh.quads[worst][0]]) + in_subregion(w, worst);
  };
  const std::string how_many = " (" + std::to_string(outside.size()) + " of " + std::to_string(r.mesh.quads.size()) +
                               " quads outside the gates, above --max-poor-fraction " +
                               std::to_string(options.gates.max_poor_fraction) + ")";
  if (refused && gated.edge_ratio > options.gates.max_edge_ratio)
    throw MeshingError(w.name + ": the best mesh has a quad with edge ratio " + std::to_string(gated.edge_ratio) +
                       " at " + at(metrics.edge_ratio, true) + ", above the maximum " +
                       std::to_string(options.gates.max_edge_ratio) + " (--max-edge-ratio)" + how_many);
  if (refused)
    throw MeshingError(w.name + ": the best mesh has a quad with scaled Jacobian " + std::to_string(gated.sj) + " at " +
                       at(metrics.sj, false) + ", below the minimum " +
                       std::to_string(options.gates.min_scaled_jacobian) + " (--min-sj)" + how_many);
  if (outside.empty()) return;
  PoorQuadsReport poor{outside.size(), static_cast<double>(outside.size()) / static_cast<double>(r.mesh.quads.size()),
                       {}};
  for (std::size_t q : outside) {
    if (poor.first.size() == 20) break;
    PoorQuadReport place{r.mesh.nodes[r.mesh.quads[q][0]], metrics.sj[q], metrics.edge_ratio[q], {}};
    if (subregion_of(w, q) >= 0) place.subregion = subregion_of(w, q);
    poor.first.push_back(place);
  }
  w.c.summary.poor_quads = std::move(poor);
}

}  // namespace

void measure_finished(FinishWork& w) {
  measure_quality(w);
  accept_poor_quads(w, measure_pinned(w));
}

}  // namespace polysquare::pipeline
