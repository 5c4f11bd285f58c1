#include "polysquare/map/multipass.h"

#include <oneapi/tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <unordered_map>
#include <unordered_set>

#include "polysquare/map/polysquare_map.h"

namespace polysquare {
namespace {

// One subregion's deformation chart: its triangles and k rings of its neighbours', in local numbering.
struct Chart {
  std::vector<std::int32_t> vertex;                   // chart vertex -> vertex of the part
  DeformProblem problem;                              // rest = input / size; fixed = the outer ring
  std::vector<std::array<std::int32_t, 2>> boundary;  // edges of the subregion's own boundary (re-orientation)
};

Chart build_chart(const TriMesh& tri, const std::vector<std::int32_t>& triangle_part, std::int32_t p,
                  const std::vector<std::size_t>& own_triangles, const std::vector<std::vector<std::int32_t>>& triangles_at,
                  const std::unordered_set<std::uint64_t>& feature_edges,
                  const std::unordered_map<std::uint64_t, std::array<std::int32_t, 2>>& owners, double size, int rings,
                  const DeformOptions& deform) {
  // Membership by hash, not a flag per triangle of the part: one chart per subregion, thousands on a coast.
  std::unordered_set<std::size_t> in(own_triangles.begin(), own_triangles.end());
  std::vector<std::size_t> chart_triangles = own_triangles;
  for (int r = 0; r < rings; ++r) {
    std::vector<std::size_t> added;
    for (std::size_t t : chart_triangles)
      for (std::int32_t v : tri.triangles[t])
        for (std::int32_t u : triangles_at[static_cast<std::size_t>(v)])
          if (in.insert(static_cast<std::size_t>(u)).second) added.push_back(static_cast<std::size_t>(u));
    if (added.empty()) break;
    chart_triangles.insert(chart_triangles.end(), added.begin(), added.end());
  }
  std::sort(chart_triangles.begin(), chart_triangles.end());
  Chart c;
  std::unordered_map<std::int32_t, std::int32_t> local;
  auto index = [&](std::int32_t v) {
    auto [it, inserted] = local.try_emplace(v, static_cast<std::int32_t>(c.vertex.size()));
    if (inserted) c.vertex.push_back(v);
    return it->second;
  };
  for (std::size_t t : chart_triangles) {
    const auto& tr = tri.triangles[t];
    c.problem.triangles.push_back({index(tr[0]), index(tr[1]), index(tr[2])});
  }
  const std::size_t n = c.vertex.size();
  c.problem.rest.resize(n);
  for (std::size_t i = 0; i < n; ++i) c.problem.rest[i] = (1.0 / size) * tri.vertices[static_cast<std::size_t>(c.vertex[i])];
  // The outer ring of the chart stays; the subregion's own vertices always move (its ring pieces too).
  c.problem.fixed.assign(n, 0);
  std::vector<std::uint8_t> own(n, 0);
  for (std::size_t t : chart_triangles)
    if (triangle_part[t] == p)
      for (std::int32_t v : tri.triangles[t]) own[static_cast<std::size_t>(local.at(v))] = 1;
  for (std::size_t t : chart_triangles)
    for (int k = 0; k < 3; ++k) {
      const std::int32_t a = tri.triangles[t][k], b = tri.triangles[t][(k + 1) % 3];
      const auto& o = owners.at(edge_key(a, b));
      const bool other_in = o[1] >= 0 && in.count(static_cast<std::size_t>(o[0] == static_cast<std::int32_t>(t) ? o[1] : o[0])) > 0;
      if (other_in) continue;
      for (std::int32_t v : {a, b})
        if (!own[static_cast<std::size_t>(local.at(v))]) c.problem.fixed[static_cast<std::size_t>(local.at(v))] = 1;
    }
  // Pulled to the axes: the subregion's ring pieces and the feature edges in it or on its boundary. Interfaces are
  // not: each side would pull them to the axes of its own frame, and two frames that do not differ by a quarter
  // turn pull them apart (with them, delta_box 200 m still moved 5-6 elements in the eighth pass, and 1.7-2.2
  // without); the labelled deformation of each subregion straightens them afterwards.
  for (std::size_t t : own_triangles)
    for (int k = 0; k < 3; ++k) {
      const std::int32_t a = tri.triangles[t][k], b = tri.triangles[t][(k + 1) % 3];
      const auto& o = owners.at(edge_key(a, b));
      const std::int32_t other = o[0] == static_cast<std::int32_t>(t) ? o[1] : o[0];
      const bool feature = feature_edges.count(edge_key(a, b)) > 0;
      if (other >= 0 && triangle_part[static_cast<std::size_t>(other)] == p) {
        // a feature inside the subregion, once (from its lower-numbered triangle)
        if (feature && static_cast<std::int32_t>(t) < other) c.problem.aligned.push_back({local.at(a), local.at(b), deform.feature_weight});
        continue;
      }
      c.boundary.push_back({local.at(a), local.at(b)});
      if (other < 0 || feature) c.problem.aligned.push_back({local.at(a), local.at(b), deform.boundary_weight});
    }
  return c;
}

// Rotates `x` by `theta` about `centre`.
void rotate(std::vector<Vec2>& x, double theta, Vec2 centre) {
  const double cs = std::cos(theta), sn = std::sin(theta);
  for (Vec2& p : x) {
    const Vec2 q = p - centre;
    p = centre + Vec2{cs * q.x - sn * q.y, sn * q.x + cs * q.y};
  }
}

}  // namespace

std::vector<Vec2> multipass_deform(const TriMesh& tri, const std::vector<std::int32_t>& triangle_part, int parts,
                                   double size, const MultipassOptions& options, const DeformOptions& deform,
                                   MultipassStats& stats) {
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<Vec2> y(tri.vertices.size());
  for (std::size_t v = 0; v < y.size(); ++v) y[v] = (1.0 / size) * tri.vertices[v];
  const auto np = static_cast<std::size_t>(std::max(parts, 0));
  std::vector<std::vector<std::int32_t>> triangles_at(tri.vertices.size());
  for (std::size_t t = 0; t < tri.triangles.size(); ++t)
    for (std::int32_t v : tri.triangles[t]) triangles_at[static_cast<std::size_t>(v)].push_back(static_cast<std::int32_t>(t));
  const auto owners = edge_owners(tri);
  std::unordered_set<std::uint64_t> feature_edges;
  for (const TriChain& ch : tri.chains)
    if (ch.kind == TriChain::Kind::feature)
      for (std::size_t i = 0; i + (ch.closed ? 0 : 1) < ch.vertices.size(); ++i)
        feature_edges.insert(edge_key(ch.vertices[i], ch.vertices[(i + 1) % ch.vertices.size()]));
  std::vector<std::vector<std::size_t>> own(np);
  for (std::size_t t = 0; t < tri.triangles.size(); ++t)
    if (triangle_part[t] >= 0 && static_cast<std::size_t>(triangle_part[t]) < np) own[static_cast<std::size_t>(triangle_part[t])].push_back(t);

  std::vector<Chart> charts(np);
  oneapi::tbb::parallel_for(std::size_t{0}, np, [&](std::size_t p) {
    charts[p] = build_chart(tri, triangle_part, static_cast<std::int32_t>(p), own[p], triangles_at, feature_edges, owners, size,
                            options.buffer_rings, deform);
  });
  // Colours: greedy over the subregions in order, two charts that share a vertex apart, so that the charts of one
  // colour move disjoint vertices and can be deformed at once from the same positions.
  std::vector<std::vector<std::int32_t>> charts_at(tri.vertices.size());
  for (std::size_t p = 0; p < np; ++p)
    for (std::int32_t v : charts[p].vertex) charts_at[static_cast<std::size_t>(v)].push_back(static_cast<std::int32_t>(p));
  std::vector<int> colour(np, -1);
  int colours = 0;
  for (std::size_t p = 0; p < np; ++p) {
    std::vector<std::uint8_t> used(static_cast<std::size_t>(colours) + 1, 0);
    for (std::int32_t v : charts[p].vertex)
      for (std::int32_t q : charts_at[static_cast<std::size_t>(v)])
        if (colour[static_cast<std::size_t>(q)] >= 0) used[static_cast<std::size_t>(colour[static_cast<std::size_t>(q)])] = 1;
    int c = 0;
    while (used[static_cast<std::size_t>(c)]) ++c;
    colour[p] = c;
    colours = std::max(colours, c + 1);
  }
  stats.colours = colours;
  DeformOptions solve = deform;
  solve.memo = nullptr;
  for (int pass = 0; pass < options.max_passes; ++pass) {
    // The first pass goes down the whole smoothing schedule of the L1 terms; later ones start near their
    // optimum and solve at its last value only.
    if (pass == 1 && !solve.eps_schedule.empty()) solve.eps_schedule = {solve.eps_schedule.back()};
    double moved = 0.0;
    for (int c = 0; c < colours; ++c) {
      std::vector<std::size_t> group;
      for (std::size_t p = 0; p < np; ++p)
        if (colour[p] == c) group.push_back(p);
      std::vector<std::vector<Vec2>> result(group.size());
      oneapi::tbb::parallel_for(std::size_t{0}, group.size(), [&](std::size_t g) {
        const Chart& ch = charts[group[g]];
        std::vector<Vec2> x(ch.vertex.size());
        Vec2 centre{0.0, 0.0};
        for (std::size_t i = 0; i < x.size(); ++i) x[i] = y[static_cast<std::size_t>(ch.vertex[i])], centre = centre + x[i];
        if (x.empty()) return;
        centre = (1.0 / static_cast<double>(x.size())) * centre;
        // Re-orientation (eq. 11) of the subregion as it is now, the chart turned with it and back after.
        const double theta = preorientation_angle(x, ch.boundary);
        rotate(x, theta, centre);
        deform_to_polysquare(ch.problem, solve, x);
        rotate(x, -theta, centre);
        result[g] = std::move(x);
      });
      for (std::size_t g = 0; g < group.size(); ++g) {
        const Chart& ch = charts[group[g]];
        for (std::size_t i = 0; i < result[g].size(); ++i) {
          if (ch.problem.fixed[i]) continue;
          Vec2& at = y[static_cast<std::size_t>(ch.vertex[i])];
          moved = std::max(moved, distance(at, result[g][i]));
          at = result[g][i];
        }
      }
    }
    stats.passes = pass + 1;
    stats.last_move = moved;
    if (moved <= options.tolerance) break;
  }
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return y;
}

}  // namespace polysquare
