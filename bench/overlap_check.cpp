// Cost of the overlap invariant (find_overlapping_quads) and of the whole check_invariants on a large mesh:
// a jittered structured grid of about N quads (default 2,000,000), or a mesh file given as the second argument.
// Usage: overlap_check [N] [mesh-file]. Prints seconds for each, best of three runs.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>

#include "polysquare/io/mesh_io.h"
#include "polysquare/pipeline/invariants.h"

using namespace polysquare;

namespace {

QuadMesh jittered_grid(std::size_t target) {
  const auto n = static_cast<std::int32_t>(std::lround(std::sqrt(static_cast<double>(target))));
  QuadMesh m;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-0.2, 0.2);  // keeps every quad convex
  for (std::int32_t j = 0; j <= n; ++j)
    for (std::int32_t i = 0; i <= n; ++i) {
      const bool inner = i > 0 && j > 0 && i < n && j < n;
      m.nodes.push_back({i + (inner ? jitter(rng) : 0.0), j + (inner ? jitter(rng) : 0.0)});
    }
  auto id = [&](std::int32_t i, std::int32_t j) { return j * (n + 1) + i; };
  for (std::int32_t j = 0; j < n; ++j)
    for (std::int32_t i = 0; i < n; ++i) m.quads.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
  for (std::int32_t k = 0; k < n; ++k) {
    m.boundary_edges.push_back({id(k, 0), id(k + 1, 0)});
    m.boundary_edges.push_back({id(k, n), id(k + 1, n)});
    m.boundary_edges.push_back({id(0, k), id(0, k + 1)});
    m.boundary_edges.push_back({id(n, k), id(n, k + 1)});
  }
  m.boundary_edge_ring.assign(m.boundary_edges.size(), 0);
  return m;
}

template <class F>
double best_of_three(F&& f) {
  double best = 1e300;
  for (int k = 0; k < 3; ++k) {
    const auto t0 = std::chrono::steady_clock::now();
    f();
    best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  return best;
}

}  // namespace

int main(int argc, char** argv) {
  const std::size_t target = argc > 1 ? std::strtoull(argv[1], nullptr, 10) : 2000000;
  const QuadMesh mesh = argc > 2 ? read_mesh(argv[2]) : jittered_grid(target);
  std::size_t pairs = 0;
  const double overlap_s = best_of_three([&] { pairs = find_overlapping_quads(mesh).pairs; });
  bool ok = false;
  const double all_s = best_of_three([&] { ok = check_invariants(mesh).ok(); });
  std::printf("%zu quads, %zu nodes: find_overlapping_quads %.3f s (%zu pairs), check_invariants %.3f s (%s)\n",
              mesh.quads.size(), mesh.nodes.size(), overlap_s, pairs, all_s, ok ? "ok" : "not ok");
  return 0;
}
