// The quality figures of a large mesh are computed in parallel (per quad, per edge, per face): they must be the
// figures of one thread, bit for bit, and right on a mesh whose answers are known.
#include <gtest/gtest.h>

#include <oneapi/tbb/global_control.h>

#include <cmath>
#include <random>

#include "polysquare/core/quad_topology.h"
#include "polysquare/quality/quality.h"

using namespace polysquare;

namespace {

// An n x n lattice of unit squares; with `jitter`, interior nodes moved by up to that much (fixed seed).
QuadMesh lattice(int n, double jitter) {
  QuadMesh m;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> d(-jitter, jitter);
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const bool inner = i > 0 && j > 0 && i < n && j < n;
      m.nodes.push_back({i + (inner ? d(rng) : 0.0), j + (inner ? d(rng) : 0.0)});
      m.node_kind.push_back(inner ? NodeKind::interior : NodeKind::boundary);
    }
  auto id = [&](int i, int j) { return static_cast<std::int32_t>(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) m.quads.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
  return m;
}

struct Figures {
  QuadMetrics metrics;
  QualityReport report;
  FiniteVolumeQuality fv;
};

Figures figures(const QuadMesh& m, int threads) {
  oneapi::tbb::global_control limit(oneapi::tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
  return {quad_metrics(m), compute_quality(m), finite_volume_quality(m)};
}

}  // namespace

TEST(ParallelQuality, ALargeLatticeHasItsKnownFigures) {
  const QuadMesh m = lattice(200, 0.0);  // 40,000 quads: the parallel path
  const Figures f = figures(m, 2);
  EXPECT_EQ(f.report.quads, 40000u);
  EXPECT_DOUBLE_EQ(f.report.sj.min, 1.0);
  EXPECT_DOUBLE_EQ(f.report.edge_ratio.max, 1.0);
  EXPECT_EQ(f.report.interior_singularities, 0u);
  EXPECT_EQ(f.report.boundary_edges, 800u);
  EXPECT_EQ(f.report.non_manifold_edges, 0u);
  EXPECT_EQ(f.fv.interior_edges, 2u * 200u * 199u);
  EXPECT_NEAR(f.fv.orthogonality.max, 0.0, 1e-12);  // square cells: centre links cross every edge at right angles
  EXPECT_NEAR(f.fv.smoothness.max, 1.0, 1e-12);
  EXPECT_EQ(f.report.schism.failing, 0u);
  const EdgeCounts counts = quad_edge_counts(m);
  EXPECT_EQ(counts.size(), 2u * 200u * 201u);
  EXPECT_EQ(counts.count(edge_key(0, 1)), 1);          // on the boundary
  EXPECT_EQ(counts.count(edge_key(202, 203)), 2);      // inside
  EXPECT_EQ(counts.count(edge_key(0, 202)), 0);        // a diagonal is no edge
}

TEST(ParallelQuality, OneThreadAndTwoGiveTheSameFigures) {
  const QuadMesh m = lattice(180, 0.3);  // 32,400 distorted quads
  const Figures a = figures(m, 1), b = figures(m, 2);
  EXPECT_EQ(a.metrics.sj, b.metrics.sj);
  EXPECT_EQ(a.metrics.eta, b.metrics.eta);
  EXPECT_EQ(a.metrics.skew, b.metrics.skew);
  EXPECT_EQ(a.metrics.edge_ratio, b.metrics.edge_ratio);
  EXPECT_EQ(to_json(a.report).dump(), to_json(b.report).dump());
  EXPECT_EQ(to_json(a.fv).dump(), to_json(b.fv).dump());
  EXPECT_LT(a.report.sj.min, 0.9);  // the jitter made the figures non-trivial
  EXPECT_GT(a.fv.orthogonality.max, 0.01);
}
