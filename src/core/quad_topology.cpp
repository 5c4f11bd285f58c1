#include "polysquare/core/quad_topology.h"

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>
#include <oneapi/tbb/parallel_sort.h>

#include <algorithm>

namespace polysquare {

EdgeCounts quad_edge_counts(const QuadMesh& mesh) {
  const std::size_t n = mesh.quads.size();
  std::vector<std::uint64_t> keys(4 * n);
  oneapi::tbb::parallel_for(oneapi::tbb::blocked_range<std::size_t>(0, n, 4096),
                            [&](const oneapi::tbb::blocked_range<std::size_t>& r) {
                              for (std::size_t q = r.begin(); q != r.end(); ++q)
                                for (std::size_t k = 0; k < 4; ++k)
                                  keys[4 * q + k] = edge_key(mesh.quads[q][k], mesh.quads[q][(k + 1) % 4]);
                            });
  oneapi::tbb::parallel_sort(keys.begin(), keys.end());  // equal keys are equal: one result for any thread count
  EdgeCounts out;
  out.edges.reserve(keys.size() / 2 + 4);
  for (std::size_t i = 0; i < keys.size();) {
    std::size_t j = i + 1;
    while (j < keys.size() && keys[j] == keys[i]) ++j;
    out.edges.push_back({keys[i], static_cast<int>(j - i)});
    i = j;
  }
  return out;
}

int EdgeCounts::count(std::uint64_t key) const {
  const auto it = std::lower_bound(edges.begin(), edges.end(), key,
                                   [](const std::pair<std::uint64_t, int>& e, std::uint64_t k) { return e.first < k; });
  return it != edges.end() && it->first == key ? it->second : 0;
}

NodeValences node_valences(const QuadMesh& mesh, const EdgeCounts& edge_counts) {
  NodeValences out;
  out.valence.assign(mesh.nodes.size(), 0);
  out.on_boundary.assign(mesh.nodes.size(), 0);
  for (const auto& [key, count] : edge_counts) {
    const auto a = static_cast<std::size_t>(key >> 32), b = static_cast<std::size_t>(key & 0xffffffffu);
    out.valence[a]++;
    out.valence[b]++;
    if (count == 1) out.on_boundary[a] = out.on_boundary[b] = 1;
  }
  return out;
}

NodeQuads node_quads(const QuadMesh& mesh) {
  NodeQuads n;
  n.offset.assign(mesh.nodes.size() + 1, 0);
  for (const auto& q : mesh.quads)
    for (auto v : q) n.offset[static_cast<std::size_t>(v) + 1]++;
  for (std::size_t i = 0; i + 1 < n.offset.size(); ++i) n.offset[i + 1] += n.offset[i];
  n.quads.resize(n.offset.back());
  std::vector<std::size_t> fill(n.offset.begin(), n.offset.end() - 1);
  for (std::size_t q = 0; q < mesh.quads.size(); ++q)
    for (auto v : mesh.quads[q]) n.quads[fill[static_cast<std::size_t>(v)]++] = static_cast<std::int32_t>(q);
  return n;
}

}  // namespace polysquare
