#include "polysquare/smooth/smooth.h"

#include <algorithm>
#include <cmath>

namespace polysquare {

double quad_min_corner_sj(const QuadMesh& mesh, std::size_t q) {
  const auto& quad = mesh.quads[q];
  double mn = 1.0;
  for (int k = 0; k < 4; ++k) {
    const Vec2 p = mesh.nodes[quad[k]];
    const Vec2 e_next = mesh.nodes[quad[(k + 1) % 4]] - p, e_prev = mesh.nodes[quad[(k + 3) % 4]] - p;
    const double l = norm(e_next) * norm(e_prev);
    mn = std::min(mn, l > 0 ? cross(e_next, e_prev) / l : -1.0);
  }
  return mn;
}

SmoothStats smooth_quads(QuadMesh& mesh, const SmoothOptions& options) {
  const std::size_t nn = mesh.nodes.size();
  // Compressed node -> incident quads and node -> edge neighbours.
  std::vector<std::size_t> qoff(nn + 1, 0);
  for (const auto& q : mesh.quads)
    for (auto v : q) qoff[v + 1]++;
  for (std::size_t i = 0; i < nn; ++i) qoff[i + 1] += qoff[i];
  std::vector<std::int32_t> qadj(qoff[nn]);
  {
    std::vector<std::size_t> fill(qoff.begin(), qoff.end() - 1);
    for (std::size_t q = 0; q < mesh.quads.size(); ++q)
      for (auto v : mesh.quads[q]) qadj[fill[v]++] = static_cast<std::int32_t>(q);
  }
  SmoothStats stats;
  std::vector<std::int32_t> nbrs;
  for (int sweep = 0; sweep < options.iterations; ++sweep) {
    std::size_t moved = 0;
    for (std::size_t v = 0; v < nn; ++v) {
      if (mesh.node_kind.empty() || mesh.node_kind[v] != NodeKind::interior) continue;
      nbrs.clear();
      for (std::size_t k = qoff[v]; k < qoff[v + 1]; ++k) {
        const auto& q = mesh.quads[qadj[k]];
        const int at = static_cast<int>(std::find(q.begin(), q.end(), static_cast<std::int32_t>(v)) - q.begin());
        nbrs.push_back(q[(at + 1) % 4]);
        nbrs.push_back(q[(at + 3) % 4]);
      }
      std::sort(nbrs.begin(), nbrs.end());
      nbrs.erase(std::unique(nbrs.begin(), nbrs.end()), nbrs.end());
      Vec2 mean{};
      for (auto w : nbrs) mean = mean + mesh.nodes[w];
      mean = (1.0 / static_cast<double>(nbrs.size())) * mean;
      auto worst = [&] {
        double m = 1.0;
        for (std::size_t k = qoff[v]; k < qoff[v + 1]; ++k) m = std::min(m, quad_min_corner_sj(mesh, qadj[k]));
        return m;
      };
      const Vec2 old = mesh.nodes[v];
      const double before = worst();
      mesh.nodes[v] = mean;
      if (worst() > before + options.min_gain) {
        ++moved;
      } else {
        mesh.nodes[v] = old;
      }
    }
    stats.sweeps = sweep + 1;
    stats.moves += moved;
    if (moved == 0) break;
  }
  // Then a derivative-free pattern search on the worst corner around the nodes of poor quads: it untangles and
  // lifts the minimum where the Laplacian average cannot (next to poly-square corners).
  const Vec2 dirs[8] = {{1, 0}, {0.7071, 0.7071}, {0, 1}, {-0.7071, 0.7071}, {-1, 0}, {-0.7071, -0.7071}, {0, -1}, {0.7071, -0.7071}};
  for (int sweep = 0; sweep < options.worst_sweeps; ++sweep) {
    std::size_t moved = 0;
    for (std::size_t v = 0; v < nn; ++v) {
      if (mesh.node_kind.empty() || mesh.node_kind[v] != NodeKind::interior) continue;
      double before = 1.0, edge = 0.0;
      int nedge = 0;
      for (std::size_t k = qoff[v]; k < qoff[v + 1]; ++k) {
        before = std::min(before, quad_min_corner_sj(mesh, qadj[k]));
        const auto& q = mesh.quads[qadj[k]];
        for (int c = 0; c < 4; ++c) { edge += distance(mesh.nodes[q[c]], mesh.nodes[q[(c + 1) % 4]]); ++nedge; }
      }
      if (before >= options.worst_threshold) continue;
      auto worst = [&] {
        double m = 1.0;
        for (std::size_t k = qoff[v]; k < qoff[v + 1]; ++k) m = std::min(m, quad_min_corner_sj(mesh, qadj[k]));
        return m;
      };
      double best = before;
      double step = 0.25 * edge / nedge;
      for (int level = 0; level < 12; ++level) {
        bool improved = false;
        const Vec2 centre = mesh.nodes[v];
        Vec2 best_p = centre;
        for (const Vec2& d : dirs) {
          mesh.nodes[v] = centre + step * d;
          const double w = worst();
          if (w > best + 1e-12) { best = w; best_p = mesh.nodes[v]; improved = true; }
        }
        mesh.nodes[v] = best_p;
        if (!improved) step *= 0.5;
      }
      if (best > before) ++moved;
    }
    stats.moves += moved;
    if (moved == 0) break;
  }
  return stats;
}

}  // namespace polysquare
