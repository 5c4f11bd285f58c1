#include "map/transition_rows.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <unordered_map>
#include <utility>

#include "polysquare/core/error.h"

namespace polysquare {

std::vector<std::int32_t> nodes_along(const QuadMesh& mesh, std::size_t side_nodes, const std::vector<Vec2>& line,
                                      double tolerance) {
  std::vector<std::pair<double, std::int32_t>> found;
  for (std::size_t v = 0; v < side_nodes && v < mesh.nodes.size(); ++v) {
    double along = 0.0;
    for (std::size_t i = 0; i + 1 < line.size(); ++i) {
      const Vec2 a = line[i], d = line[i + 1] - a;
      const double len2 = dot(d, d);
      const double t = len2 > 0.0 ? std::clamp(dot(mesh.nodes[v] - a, d) / len2, 0.0, 1.0) : 0.0;
      if (distance(mesh.nodes[v], a + t * d) <= tolerance) {
        found.push_back({along + t * std::sqrt(len2), static_cast<std::int32_t>(v)});
        break;
      }
      along += std::sqrt(len2);
    }
  }
  std::sort(found.begin(), found.end());
  std::vector<std::int32_t> out;
  for (const auto& [t, v] : found) out.push_back(v);
  return out;
}

namespace {

// The row of quads along the interface nodes u (in order): per interface edge its quad, and the inner nodes w
// (w[i] across from u[i]). `forward`: the quads run u[i], u[i+1], w[i+1], w[i] in their own order.
struct Row {
  std::vector<std::size_t> quads;
  std::vector<std::int32_t> w;
  bool forward = true;
  bool taken_front = false, taken_back = false;  // the end quad is an earlier row's (a corner of both)
};

Row find_row(const QuadMesh& mesh, const std::vector<std::int32_t>& u, const std::vector<std::uint8_t>& in_row) {
  std::unordered_map<std::uint64_t, std::vector<std::pair<std::size_t, int>>> owner;
  for (std::size_t q = 0; q < mesh.quads.size(); ++q)
    for (int k = 0; k < 4; ++k) owner[edge_key(mesh.quads[q][k], mesh.quads[q][(k + 1) % 4])].push_back({q, k});
  Row row;
  const std::size_t n = u.size() - 1;
  row.w.assign(n + 1, -1);
  for (std::size_t i = 0; i < n; ++i) {
    const auto it = owner.find(edge_key(u[i], u[i + 1]));
    if (it == owner.end() || it->second.size() != 1) throw MeshingError("its interface edges are not one row's");
    const auto [q, k] = it->second.front();
    if (in_row[q] && i == 0 && n > 1) row.taken_front = true;
    else if (in_row[q] && i + 1 == n && n > (row.taken_front ? 2u : 1u)) row.taken_back = true;
    else if (in_row[q]) throw MeshingError("a corner quad would join two transition rows");
    const auto& quad = mesh.quads[q];
    const bool forward = quad[static_cast<std::size_t>(k)] == u[i];
    if (i > 0 && forward != row.forward) throw MeshingError("its row turns over");
    row.forward = forward;
    const std::int32_t w_next = forward ? quad[(k + 2) % 4] : quad[(k + 3) % 4];
    const std::int32_t w_here = forward ? quad[(k + 3) % 4] : quad[(k + 2) % 4];
    if (row.w[i] >= 0 && row.w[i] != w_here) throw MeshingError("its row is not a row of quads");
    row.w[i] = w_here;
    row.w[i + 1] = w_next;
    row.quads.push_back(q);
  }
  for (std::int32_t w : row.w)
    if (std::find(u.begin(), u.end(), w) != u.end()) throw MeshingError("its row is one quad thin at a corner");
  return row;
}

// The quads of the transition row, in the coarse mesh's numbering: top[] the top nodes, w[] the bottom ones.
std::vector<std::array<std::int32_t, 4>> row_quads(const std::vector<std::int32_t>& top, const std::vector<std::int32_t>& w,
                                                   bool forward) {
  const std::size_t n = w.size() - 1, t = (top.size() - 1 - n) / 2, cells = n + t;
  std::vector<std::array<std::int32_t, 4>> out;
  std::size_t i = 0, j = 0;
  for (std::size_t k = 0; k < cells; ++k) {
    // Fans spread evenly (the rounded multiples of t / cells change at exactly t cells).
    const auto step = [&](std::size_t c) { return std::floor(static_cast<double>(c * t) / static_cast<double>(cells) + 0.5); };
    std::array<std::int32_t, 4> q{};
    if (step(k + 1) > step(k)) {
      q = {top[i], top[i + 1], top[i + 2], w[j]};
      i += 2;
    } else {
      q = {top[i], top[i + 1], w[j + 1], w[j]};
      ++i, ++j;
    }
    if (!forward) std::reverse(q.begin(), q.end());
    out.push_back(q);
  }
  return out;
}

}  // namespace

void replace_with_transition_row(QuadMesh& coarse, std::size_t& side_nodes, std::vector<std::uint8_t>& in_row,
                                 const std::vector<Vec2>& line, const std::vector<Vec2>& top_in,
                                 const std::vector<NodeKind>& top_kind_in, double tolerance) {
  std::vector<std::int32_t> u = nodes_along(coarse, side_nodes, line, tolerance);
  if (u.size() < 2) throw MeshingError("it has no nodes on the interface");
  std::size_t n = u.size() - 1;
  if (top_in.size() <= n + 1 || (top_in.size() - 1 - n) % 2 != 0)
    throw MeshingError("the finer side's " + std::to_string(top_in.size() - 1) + " edges do not exceed its " +
                       std::to_string(n) + " by an even number");
  if (distance(coarse.nodes[static_cast<std::size_t>(u.front())], top_in.front()) > tolerance ||
      distance(coarse.nodes[static_cast<std::size_t>(u.back())], top_in.back()) > tolerance)
    throw MeshingError("the two sides' end nodes differ");
  Row row = find_row(coarse, u, in_row);
  // A corner quad an earlier row took stays out of this one: its edge on the line meets the finer side's end
  // edge, its inner node sliding along the line onto the finer side's node; the row is one edge shorter on both
  // sides, so its fans are as many.
  std::vector<Vec2> top = top_in;
  std::vector<NodeKind> top_kind = top_kind_in;
  if (row.taken_front) {
    u.erase(u.begin()), top.erase(top.begin()), top_kind.erase(top_kind.begin());
    row.quads.erase(row.quads.begin()), row.w.erase(row.w.begin());
    coarse.nodes[static_cast<std::size_t>(u.front())] = top.front();
  }
  if (row.taken_back) {
    u.pop_back(), top.pop_back(), top_kind.pop_back();
    row.quads.pop_back(), row.w.pop_back();
    coarse.nodes[static_cast<std::size_t>(u.back())] = top.back();
  }
  n = u.size() - 1;

  // New numbering: side nodes but the interface's inner ones, the finer side's inner ones, the other nodes.
  const std::size_t old_count = coarse.nodes.size();
  std::vector<std::uint8_t> removed(old_count, 0);
  for (std::size_t i = 1; i < n; ++i) removed[static_cast<std::size_t>(u[i])] = 1;
  std::vector<std::int32_t> to(old_count, -1);
  std::vector<Vec2> nodes;
  std::vector<NodeKind> kinds;
  const bool with_kinds = coarse.node_kind.size() == old_count;
  auto keep = [&](std::size_t v) {
    to[v] = static_cast<std::int32_t>(nodes.size());
    nodes.push_back(coarse.nodes[v]);
    if (with_kinds) kinds.push_back(coarse.node_kind[v]);
  };
  for (std::size_t v = 0; v < side_nodes; ++v)
    if (!removed[v]) keep(v);
  std::vector<std::int32_t> top_index{to[static_cast<std::size_t>(u.front())]};
  for (std::size_t i = 1; i + 1 < top.size(); ++i) {
    top_index.push_back(static_cast<std::int32_t>(nodes.size()));
    nodes.push_back(top[i]);
    if (with_kinds) kinds.push_back(top_kind[i]);
  }
  top_index.push_back(to[static_cast<std::size_t>(u.back())]);
  const std::size_t new_side_nodes = nodes.size();
  for (std::size_t v = side_nodes; v < old_count; ++v) keep(v);

  std::vector<std::uint8_t> gone(coarse.quads.size(), 0);
  for (std::size_t q : row.quads) gone[q] = 1;
  QuadMesh out;
  out.crs = coarse.crs, out.units = coarse.units;
  out.nodes = std::move(nodes);
  if (with_kinds) out.node_kind = std::move(kinds);
  std::vector<std::uint8_t> rows;
  const bool with_parts = coarse.quad_part.size() == coarse.quads.size();
  for (std::size_t q = 0; q < coarse.quads.size(); ++q) {
    if (gone[q]) continue;
    std::array<std::int32_t, 4> r{};
    for (int k = 0; k < 4; ++k) r[k] = to[static_cast<std::size_t>(coarse.quads[q][k])];
    out.quads.push_back(r);
    rows.push_back(in_row[q]);
    if (with_parts) out.quad_part.push_back(coarse.quad_part[q]);
  }
  std::vector<std::int32_t> w;
  for (std::int32_t v : row.w) w.push_back(to[static_cast<std::size_t>(v)]);
  for (const auto& q : row_quads(top_index, w, row.forward)) {
    out.quads.push_back(q);
    rows.push_back(1);
    if (with_parts) out.quad_part.push_back(coarse.quad_part[row.quads.front()]);
  }
  auto edges = [&](const std::vector<std::array<std::int32_t, 2>>& in, std::vector<std::array<std::int32_t, 2>>& into) {
    for (const auto& e : in) {
      const std::int32_t a = to[static_cast<std::size_t>(e[0])], b = to[static_cast<std::size_t>(e[1])];
      if (a < 0 || b < 0) throw MeshingError("a tagged edge lies on its interface");
      into.push_back({a, b});
    }
  };
  edges(coarse.boundary_edges, out.boundary_edges);
  out.boundary_edge_ring = coarse.boundary_edge_ring;
  edges(coarse.feature_edges, out.feature_edges);
  out.feature_edge_curve = coarse.feature_edge_curve;
  if (!coarse.triangles.empty()) throw MeshingError("it holds triangles");
  coarse = std::move(out);
  in_row = std::move(rows);
  side_nodes = new_side_nodes;
}

}  // namespace polysquare
