#include "polysquare/size/size_conformity.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

namespace polysquare {
namespace {

// The value at fraction q (0..1) of sorted `v` (nearest rank); 0 for none.
double quantile(std::vector<double>& v, double q) {
  if (v.empty()) return 0.0;
  const auto k = static_cast<std::size_t>(std::lround(q * static_cast<double>(v.size() - 1)));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

}  // namespace

double quad_size(const QuadMesh& mesh, std::size_t q) {
  const auto& k = mesh.quads[q];
  const Vec2 a = mesh.nodes[k[0]], b = mesh.nodes[k[1]], c = mesh.nodes[k[2]], d = mesh.nodes[k[3]];
  return std::sqrt(std::max(0.5 * (orient2(a, b, c) + orient2(a, c, d)), 0.0));
}

double quad_size_ratio(const QuadMesh& mesh, std::size_t q, const SizeField& field) {
  const auto& k = mesh.quads[q];
  const Vec2 centroid = 0.25 * (mesh.nodes[k[0]] + mesh.nodes[k[1]] + mesh.nodes[k[2]] + mesh.nodes[k[3]]);
  return quad_size(mesh, q) / field.at(centroid);
}

SizeConformity size_conformity(const QuadMesh& mesh, const SizeField& field) {
  SizeConformity out;
  const std::size_t n = mesh.quads.size();
  out.quads = n;
  if (n == 0 || field.empty()) return out;
  std::vector<double> size(n), ratio(n);
  for (std::size_t q = 0; q < n; ++q) {
    size[q] = quad_size(mesh, q);
    ratio[q] = quad_size_ratio(mesh, q, field);
  }
  // Each edge's first quad, then the ratio when the second one comes.
  std::unordered_map<std::uint64_t, std::size_t> first;
  std::vector<double> jumps;
  for (std::size_t q = 0; q < n; ++q)
    for (int e = 0; e < 4; ++e) {
      auto [it, inserted] = first.try_emplace(edge_key(mesh.quads[q][e], mesh.quads[q][(e + 1) % 4]), q);
      if (inserted) continue;
      const double s = size[it->second], t = size[q];
      jumps.push_back(std::max(s, t) / std::max(std::min(s, t), 1e-300));
    }
  out.median = quantile(ratio, 0.5);
  out.p05 = quantile(ratio, 0.05);
  out.p95 = quantile(ratio, 0.95);
  out.neighbour_p99 = quantile(jumps, 0.99);
  out.neighbour_max = jumps.empty() ? 0.0 : *std::max_element(jumps.begin(), jumps.end());
  return out;
}

}  // namespace polysquare
