#include "polysquare/map/extract.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "polysquare/core/error.h"

namespace polysquare {
namespace {

long long lattice_key(long long i, long long j) { return (i << 32) ^ (j & 0xffffffffLL); }

// Cumulative deformed arc length along a segment's chain vertices.
std::vector<double> cumulative(const TriChain& ch, const LayoutSegment& s, const std::vector<Vec2>& pos) {
  const int n = static_cast<int>(ch.vertices.size());
  std::vector<double> cum(static_cast<std::size_t>(s.count) + 1, 0.0);
  for (int e = 0; e < s.count; ++e)
    cum[e + 1] = cum[e] + distance(pos[ch.vertices[(s.first + e) % n]], pos[ch.vertices[(s.first + e + 1) % n]]);
  return cum;
}

// Uniform bucket grid over the deformed triangles for point location.
struct TriangleLocator {
  const std::vector<std::array<std::int32_t, 3>>& tris;
  const std::vector<Vec2>& pos;
  Box2 box;
  double cell = 1.0;
  long long nx = 1, ny = 1;
  std::vector<std::vector<std::int32_t>> buckets;

  TriangleLocator(const std::vector<std::array<std::int32_t, 3>>& t, const std::vector<Vec2>& p) : tris(t), pos(p) {
    for (const Vec2& q : p) box.add(q);
    double mean_edge = 0.0;
    for (const auto& tr : t) mean_edge += distance(p[tr[0]], p[tr[1]]);
    cell = std::max(1e-9, mean_edge / std::max<std::size_t>(1, t.size()));
    nx = std::max(1LL, static_cast<long long>((box.hi.x - box.lo.x) / cell) + 1);
    ny = std::max(1LL, static_cast<long long>((box.hi.y - box.lo.y) / cell) + 1);
    buckets.resize(static_cast<std::size_t>(nx * ny));
    for (std::size_t k = 0; k < t.size(); ++k) {
      Box2 b;
      for (int c = 0; c < 3; ++c) b.add(p[t[k][c]]);
      const auto [i0, j0] = index(b.lo);
      const auto [i1, j1] = index(b.hi);
      for (long long i = i0; i <= i1; ++i)
        for (long long j = j0; j <= j1; ++j) buckets[static_cast<std::size_t>(j * nx + i)].push_back(static_cast<std::int32_t>(k));
    }
  }
  std::pair<long long, long long> index(Vec2 q) const {
    const long long i = std::clamp(static_cast<long long>((q.x - box.lo.x) / cell), 0LL, nx - 1);
    const long long j = std::clamp(static_cast<long long>((q.y - box.lo.y) / cell), 0LL, ny - 1);
    return {i, j};
  }
  // Triangle containing q and its barycentric coordinates; -1 when q is outside every triangle.
  int locate(Vec2 q, std::array<double, 3>& bary, double tol = 1e-10) const {
    if (q.x < box.lo.x - tol || q.y < box.lo.y - tol || q.x > box.hi.x + tol || q.y > box.hi.y + tol) return -1;
    const auto [i, j] = index(q);
    int best = -1;
    double best_min = -tol;
    for (std::int32_t k : buckets[static_cast<std::size_t>(j * nx + i)]) {
      const auto& t = tris[k];
      const Vec2 a = pos[t[0]], b = pos[t[1]], c = pos[t[2]];
      const double area = orient2(a, b, c);
      const std::array<double, 3> w{orient2(q, b, c) / area, orient2(a, q, c) / area, orient2(a, b, q) / area};
      const double mn = std::min({w[0], w[1], w[2]});
      if (mn >= best_min) { best_min = mn; best = k; bary = w; }
    }
    return best;
  }
};

}  // namespace

std::vector<Vec2> spread_along(const std::vector<Vec2>& measure, const std::vector<Vec2>& place, long long n) {
  std::vector<double> cum(measure.size(), 0.0);
  for (std::size_t e = 1; e < measure.size(); ++e) cum[e] = cum[e - 1] + distance(measure[e - 1], measure[e]);
  std::vector<Vec2> out(static_cast<std::size_t>(n) + 1);
  out.front() = place.front();
  out.back() = place.back();
  std::size_t e = 0;
  for (long long k = 1; k < n; ++k) {
    const double t = static_cast<double>(k) * cum.back() / static_cast<double>(n);
    while (e + 1 < cum.size() - 1 && cum[e + 1] < t) ++e;
    const double tau = std::clamp((t - cum[e]) / (cum[e + 1] - cum[e]), 0.0, 1.0);
    out[static_cast<std::size_t>(k)] = lerp(place[e], place[e + 1], tau);
  }
  return out;
}

void polysquare_targets(const TriMesh& mesh, const std::vector<Vec2>& original, const std::vector<Vec2>& deformed,
                        const Layout& layout, std::vector<Vec2>& targets, std::vector<std::uint8_t>& mask) {
  targets = deformed;
  mask.assign(deformed.size(), 0);
  for (const LayoutSegment& s : layout.segments) {
    const TriChain& ch = mesh.chains[s.chain];
    const int n = static_cast<int>(ch.vertices.size());
    // Interfaces are spread by input arc length, so that the two subregions sharing one place the same nodes.
    const auto cum = cumulative(ch, s, ch.interface >= 0 ? original : deformed);
    const auto la = layout.lattice[s.break_a], lb = layout.lattice[s.break_b];
    const Vec2 pa{static_cast<double>(la[0]), static_cast<double>(la[1])};
    const Vec2 pb{static_cast<double>(lb[0]), static_cast<double>(lb[1])};
    for (int e = 0; e <= s.count; ++e) {
      const std::int32_t v = ch.vertices[(s.first + e) % n];
      targets[v] = e == 0 ? pa : (e == s.count ? pb : lerp(pa, pb, cum[e] / cum.back()));
      mask[v] = 1;
    }
  }
  for (std::int32_t v : mesh.feature_point_vertices) {
    const int b = layout.vertex_break[v];
    if (b >= 0) {
      targets[v] = {static_cast<double>(layout.lattice[b][0]), static_cast<double>(layout.lattice[b][1])};
      mask[v] = 1;
    }
  }
}

QuadMesh extract_quads(const TriMesh& mesh, const std::vector<Vec2>& original, const std::vector<Vec2>& snapped,
                       const Layout& layout, const std::string& part_name,
                       const std::vector<std::int32_t>* triangle_part, std::size_t* side_nodes) {
  QuadMesh out;
  std::unordered_map<long long, std::int32_t> node_of;
  auto add_node = [&](long long i, long long j, Vec2 p, NodeKind kind) {
    auto [it, inserted] = node_of.try_emplace(lattice_key(i, j), static_cast<std::int32_t>(out.nodes.size()));
    if (inserted) {
      out.nodes.push_back(p);
      out.node_kind.push_back(kind);
    } else if (static_cast<int>(kind) > static_cast<int>(out.node_kind[it->second])) {
      out.node_kind[it->second] = kind;
    }
    return it->second;
  };

  // Nodes on the sides of the poly-square, interpolated along the chains (exactly on the input polylines).
  for (const LayoutSegment& s : layout.segments) {
    const TriChain& ch = mesh.chains[s.chain];
    const int n = static_cast<int>(ch.vertices.size());
    const auto la = layout.lattice[s.break_a], lb = layout.lattice[s.break_b];
    const long long len = std::llabs(lb[0] - la[0]) + std::llabs(lb[1] - la[1]);
    const long long di = (lb[0] > la[0]) - (lb[0] < la[0]), dj = (lb[1] > la[1]) - (lb[1] < la[1]);
    const bool ring = ch.kind == TriChain::Kind::ring, separator = ch.kind == TriChain::Kind::separator;
    // Separators are inside the mesh: their nodes are interior (smoothing moves them), and no edge is tagged.
    const NodeKind line_kind = ring ? NodeKind::boundary : (separator ? NodeKind::interior : NodeKind::feature);
    std::vector<Vec2> measure, place;
    for (int e = 0; e <= s.count; ++e) {
      const std::int32_t v = ch.vertices[(s.first + e) % n];
      measure.push_back(ch.interface >= 0 ? original[v] : snapped[v]);
      place.push_back(original[v]);
    }
    const std::vector<Vec2> points = spread_along(measure, place, len);
    std::int32_t prev = -1;
    for (long long k = 0; k <= len; ++k) {
      const Vec2 p = points[static_cast<std::size_t>(k)];
      NodeKind kind = line_kind;
      if (k == 0 || k == len) {
        const int b = k == 0 ? s.break_a : s.break_b;
        if (layout.break_is_corner[b] && !separator) kind = NodeKind::corner;
      }
      const std::int32_t id = add_node(la[0] + k * di, la[1] + k * dj, p, kind);
      if (prev >= 0 && !separator) {
        if (ring) { out.boundary_edges.push_back({prev, id}); out.boundary_edge_ring.push_back(ch.index); }
        else { out.feature_edges.push_back({prev, id}); out.feature_edge_curve.push_back(ch.index); }
      }
      prev = id;
    }
  }

  if (side_nodes) *side_nodes = out.nodes.size();
  // Interior lattice nodes through the inverse of the deformation, cells kept when their centre is inside.
  TriangleLocator locator(mesh.triangles, snapped);
  const long long i0 = static_cast<long long>(std::floor(locator.box.lo.x)) - 1;
  const long long i1 = static_cast<long long>(std::ceil(locator.box.hi.x)) + 1;
  const long long j0 = static_cast<long long>(std::floor(locator.box.lo.y)) - 1;
  const long long j1 = static_cast<long long>(std::ceil(locator.box.hi.y)) + 1;
  auto lattice_node = [&](long long i, long long j) -> std::int32_t {
    auto it = node_of.find(lattice_key(i, j));
    if (it != node_of.end()) return it->second;
    std::array<double, 3> w{};
    const int t = locator.locate({static_cast<double>(i), static_cast<double>(j)}, w, 1e-9);
    if (t < 0)
      throw MeshingError(part_name + ": lattice node (" + std::to_string(i) + ", " + std::to_string(j) +
                         ") of the poly-square lies outside the deformed mesh");
    const auto& tri = mesh.triangles[t];
    const Vec2 p = w[0] * original[tri[0]] + w[1] * original[tri[1]] + w[2] * original[tri[2]];
    return add_node(i, j, p, NodeKind::interior);
  };
  for (long long j = j0; j < j1; ++j) {
    for (long long i = i0; i < i1; ++i) {
      std::array<double, 3> w{};
      const int t = locator.locate({i + 0.5, j + 0.5}, w, 1e-9);
      if (t < 0) continue;
      out.quads.push_back({lattice_node(i, j), lattice_node(i + 1, j), lattice_node(i + 1, j + 1), lattice_node(i, j + 1)});
      out.quad_part.push_back(triangle_part ? (*triangle_part)[static_cast<std::size_t>(t)] : 0);
    }
  }
  return out;
}

}  // namespace polysquare
