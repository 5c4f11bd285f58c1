#include <algorithm>
#include <map>
#include <set>
#include <unordered_map>
#include <unordered_set>

#include "polysquare/partition/partition.h"

namespace polysquare {

std::size_t add_separator_chains(TriMesh& mesh, const std::vector<std::int32_t>& triangle_part) {
  auto owners = edge_owners(mesh);  // edge -> its (one or two) triangles
  // Part boundaries along a feature curve are already chains (feature faces): no separator doubles them.
  std::unordered_set<std::uint64_t> on_feature;
  for (const TriChain& ch : mesh.chains) {
    if (ch.kind != TriChain::Kind::feature) continue;
    const std::size_t n = ch.vertices.size();
    for (std::size_t i = 0; i + 1 < n + (ch.closed ? 1 : 0); ++i) on_feature.insert(edge_key(ch.vertices[i], ch.vertices[(i + 1) % n]));
  }
  std::vector<std::vector<std::int32_t>> adj(mesh.vertices.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const std::int32_t a = mesh.triangles[t][k], b = mesh.triangles[t][(k + 1) % 3];
      const auto& o = owners[edge_key(a, b)];
      if (o[1] < 0 || triangle_part[o[0]] == triangle_part[o[1]] || a > b || on_feature.count(edge_key(a, b))) continue;
      adj[a].push_back(b);
      adj[b].push_back(a);
    }
  std::vector<std::uint8_t> on_chain(mesh.vertices.size(), 0);
  for (const TriChain& ch : mesh.chains)
    for (auto v : ch.vertices) on_chain[v] = 1;
  for (auto v : mesh.feature_point_vertices) on_chain[v] = 1;
  for (auto& list : adj) std::sort(list.begin(), list.end());  // deterministic walks
  auto junction = [&](std::int32_t v) { return !adj[v].empty() && (adj[v].size() != 2 || on_chain[v]); };
  std::unordered_set<std::uint64_t> used;
  std::size_t added = 0;
  auto add = [&](std::vector<std::int32_t> verts, bool closed) {
    TriChain ch;
    ch.kind = TriChain::Kind::separator;
    ch.index = static_cast<int>(added++);
    ch.closed = closed;
    ch.is_input.assign(verts.size(), 0);
    ch.vertices = std::move(verts);
    mesh.chains.push_back(std::move(ch));
  };
  auto walk = [&](std::int32_t start, std::int32_t next) {
    std::vector<std::int32_t> verts{start};
    std::int32_t prev = start, cur = next;
    used.insert(edge_key(prev, cur));
    while (true) {
      verts.push_back(cur);
      if (junction(cur) || cur == start) break;
      const std::int32_t nxt = adj[cur][0] == prev ? adj[cur][1] : adj[cur][0];
      if (used.count(edge_key(cur, nxt))) break;
      used.insert(edge_key(cur, nxt));
      prev = cur;
      cur = nxt;
    }
    return verts;
  };
  for (std::int32_t v = 0; v < static_cast<std::int32_t>(mesh.vertices.size()); ++v) {
    if (!junction(v)) continue;
    for (std::int32_t w : adj[v])
      if (!used.count(edge_key(v, w))) add(walk(v, w), false);
  }
  // Loops that meet nothing (a part inside another): closed chains.
  for (std::int32_t v = 0; v < static_cast<std::int32_t>(mesh.vertices.size()); ++v)
    for (std::int32_t w : adj[v])
      if (!used.count(edge_key(v, w))) {
        auto verts = walk(v, w);
        if (verts.size() > 2 && verts.back() == verts.front()) verts.pop_back();
        add(std::move(verts), true);
      }
  return added;
}

}  // namespace polysquare

namespace polysquare {

std::size_t straighten_separator_chains(TriMesh& mesh, int iterations) {
  // Triangles around each vertex, to keep every move valid.
  std::vector<std::vector<std::int32_t>> around(mesh.vertices.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    for (auto v : mesh.triangles[t]) around[v].push_back(static_cast<std::int32_t>(t));
  std::vector<std::uint8_t> fixed(mesh.vertices.size(), 0);
  for (const TriChain& ch : mesh.chains) {
    if (ch.kind != TriChain::Kind::separator) {
      for (auto v : ch.vertices) fixed[v] = 1;
    } else if (!ch.closed) {
      fixed[ch.vertices.front()] = fixed[ch.vertices.back()] = 1;
    }
  }
  for (auto v : mesh.feature_point_vertices) fixed[v] = 1;
  auto min_area = [&](std::int32_t v) {
    double m = INFINITY;
    for (auto t : around[v]) {
      const auto& tri = mesh.triangles[t];
      m = std::min(m, orient2(mesh.vertices[tri[0]], mesh.vertices[tri[1]], mesh.vertices[tri[2]]));
    }
    return m;
  };
  std::size_t moves = 0;
  for (int it = 0; it < iterations; ++it) {
    for (const TriChain& ch : mesh.chains) {
      if (ch.kind != TriChain::Kind::separator) continue;
      const std::size_t n = ch.vertices.size();
      for (std::size_t i = 0; i < n; ++i) {
        if (!ch.closed && (i == 0 || i + 1 == n)) continue;
        const std::int32_t v = ch.vertices[i];
        if (fixed[v]) continue;
        const Vec2 target = lerp(mesh.vertices[ch.vertices[(i + n - 1) % n]], mesh.vertices[ch.vertices[(i + 1) % n]], 0.5);
        const Vec2 old = mesh.vertices[v];
        // Half a step towards the neighbours' midpoint; kept only if no incident triangle degenerates.
        const double before = min_area(v);
        mesh.vertices[v] = lerp(old, target, 0.5);
        if (min_area(v) > 0.25 * std::min(before, 0.0) + 0.1 * before) ++moves;
        else mesh.vertices[v] = old;
      }
    }
  }
  return moves;
}

}  // namespace polysquare

namespace polysquare {
namespace {

// Whether the triangles of `part` form one edge-connected piece (a flood over them); false when it has none.
bool part_connected(const TriMesh& mesh, const std::vector<std::vector<std::int32_t>>& around,
                    const std::vector<std::int32_t>& triangle_part, std::int32_t part) {
  std::vector<std::int32_t> members;
  for (std::size_t t = 0; t < triangle_part.size(); ++t)
    if (triangle_part[t] == part) members.push_back(static_cast<std::int32_t>(t));
  if (members.empty()) return false;
  std::vector<std::uint8_t> seen(triangle_part.size(), 0);
  std::vector<std::int32_t> stack{members.front()};
  seen[members.front()] = 1;
  std::size_t reached = 0;
  while (!stack.empty()) {
    const auto t = stack.back();
    stack.pop_back();
    ++reached;
    for (int k = 0; k < 3; ++k) {
      const auto a = mesh.triangles[t][k], b = mesh.triangles[t][(k + 1) % 3];
      for (auto u : around[a]) {
        if (seen[u] || triangle_part[u] != part) continue;
        const auto& tu = mesh.triangles[u];
        if (tu[0] == b || tu[1] == b || tu[2] == b) { seen[u] = 1; stack.push_back(u); }
      }
    }
  }
  return reached == members.size();
}

std::vector<std::vector<std::int32_t>> vertex_triangles(const TriMesh& mesh) {
  std::vector<std::vector<std::int32_t>> around(mesh.vertices.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    for (auto v : mesh.triangles[t]) around[v].push_back(static_cast<std::int32_t>(t));
  return around;
}

}  // namespace

std::size_t snap_separator_ends_to_corners(const TriMesh& mesh, std::vector<std::int32_t>& triangle_part,
                                           double corner_threshold_deg, int max_edges) {
  const auto around = vertex_triangles(mesh);
  auto edge_triangle = [&](std::int32_t a, std::int32_t b) {
    for (auto t : around[a])
      for (auto v : mesh.triangles[t])
        if (v == b) return t;
    return std::int32_t{-1};
  };
  auto connected = [&](std::int32_t part) { return part_connected(mesh, around, triangle_part, part); };
  // A separator that ends where a feature meets the ring runs along that feature (feature faces): it stays.
  std::vector<std::uint8_t> on_feature(mesh.vertices.size(), 0);
  for (const TriChain& ch : mesh.chains)
    if (ch.kind == TriChain::Kind::feature)
      for (auto v : ch.vertices) on_feature[v] = 1;
  std::size_t moved = 0;
  for (const TriChain& ch : mesh.chains) {
    if (ch.kind != TriChain::Kind::ring || !ch.closed) continue;
    const int n = static_cast<int>(ch.vertices.size());
    std::vector<std::uint8_t> sharp(n, 0);
    for (int i = 0; i < n; ++i) {
      if (!ch.is_input[i]) continue;
      sharp[i] = sharp_turn(mesh.vertices[ch.vertices[(i + n - 1) % n]], mesh.vertices[ch.vertices[i]],
                            mesh.vertices[ch.vertices[(i + 1) % n]], corner_threshold_deg);
    }
    auto edge_part = [&](int i) {  // part of the triangle on ring edge i (vertices i, i + 1)
      const auto t = edge_triangle(ch.vertices[((i % n) + n) % n], ch.vertices[(((i + 1) % n) + n) % n]);
      return t < 0 ? -1 : triangle_part[t];
    };
    for (int i = 0; i < n; ++i) {
      const int before = edge_part(i - 1), after = edge_part(i);
      if (before == after || before < 0 || after < 0 || sharp[i] || on_feature[ch.vertices[i]]) continue;
      // The nearest sharp corner within max_edges on either side, whose edges all belong to one part.
      for (int d = 1; d <= max_edges; ++d) {
        int dir = 0;
        if (sharp[(i + d) % n] && [&] { for (int e = 0; e < d; ++e) if (edge_part(i + e) != after) return false; return true; }()) dir = 1;
        else if (sharp[((i - d) % n + n) % n] && [&] { for (int e = 1; e <= d; ++e) if (edge_part(i - e) != before) return false; return true; }()) dir = -1;
        if (dir == 0) continue;
        // Hand the triangles of the losing part around the ring vertices between the separator's end and the
        // corner to the other part: the separator then ends at the corner.
        const std::int32_t from = dir == 1 ? after : before, to = dir == 1 ? before : after;
        std::vector<std::int32_t> changed;
        for (int e = 0; e < d; ++e)
          for (auto t : around[ch.vertices[((i + dir * e) % n + n) % n]])
            if (triangle_part[t] == from) { triangle_part[t] = to; changed.push_back(t); }
        if (connected(from) && connected(to)) {
          moved += changed.size();
        } else {
          for (auto t : changed) triangle_part[t] = from;
        }
        break;
      }
    }
  }
  return moved;
}

}  // namespace polysquare

namespace polysquare {

std::size_t absorb_pieces_cut_off_by_features(const TriMesh& mesh, std::vector<std::int32_t>& triangle_part,
                                              int max_rounds) {
  std::unordered_set<std::uint64_t> feature_edges;
  for (const TriChain& ch : mesh.chains) {
    if (ch.kind != TriChain::Kind::feature) continue;
    const std::size_t n = ch.vertices.size();
    for (std::size_t i = 0; i + (ch.closed ? 0 : 1) < n; ++i) feature_edges.insert(edge_key(ch.vertices[i], ch.vertices[(i + 1) % n]));
  }
  if (feature_edges.empty()) return 0;
  // Edge neighbours of every triangle, with whether the shared edge lies on a feature.
  auto owners = edge_owners(mesh);  // edge -> its (one or two) triangles
  struct Nb { std::int32_t t; bool feature; double length; };
  std::vector<std::array<Nb, 3>> nb(mesh.triangles.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const auto a = mesh.triangles[t][k], b = mesh.triangles[t][(k + 1) % 3];
      const auto& o = owners[edge_key(a, b)];
      nb[t][k] = {o[0] == static_cast<std::int32_t>(t) ? o[1] : o[0], feature_edges.count(edge_key(a, b)) > 0,
                  distance(mesh.vertices[a], mesh.vertices[b])};
    }
  std::size_t moved = 0;
  for (int round = 0; round < max_rounds; ++round) {
    // Components of each part with feature edges as walls; all but the largest (by area) of a part move to the
    // neighbouring part they share the longest non-feature edge length with.
    std::vector<std::int32_t> comp(mesh.triangles.size(), -1);
    std::vector<double> comp_area;
    std::vector<std::int32_t> comp_part;
    for (std::size_t s = 0; s < mesh.triangles.size(); ++s) {
      if (comp[s] >= 0) continue;
      const auto c = static_cast<std::int32_t>(comp_area.size());
      comp_area.push_back(0.0);
      comp_part.push_back(triangle_part[s]);
      std::vector<std::int32_t> stack{static_cast<std::int32_t>(s)};
      comp[s] = c;
      while (!stack.empty()) {
        const auto t = stack.back();
        stack.pop_back();
        const auto& tr = mesh.triangles[t];
        comp_area[c] += orient2(mesh.vertices[tr[0]], mesh.vertices[tr[1]], mesh.vertices[tr[2]]);
        for (const Nb& e : nb[t])
          if (e.t >= 0 && !e.feature && comp[e.t] < 0 && triangle_part[e.t] == triangle_part[t]) {
            comp[e.t] = c;
            stack.push_back(e.t);
          }
      }
    }
    std::unordered_map<std::int32_t, std::int32_t> largest;  // part -> its largest component
    for (std::size_t c = 0; c < comp_area.size(); ++c) {
      auto [it, inserted] = largest.try_emplace(comp_part[c], static_cast<std::int32_t>(c));
      if (!inserted && comp_area[c] > comp_area[it->second]) it->second = static_cast<std::int32_t>(c);
    }
    std::vector<std::unordered_map<std::int32_t, double>> contact(comp_area.size());
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
      for (const Nb& e : nb[t])
        if (e.t >= 0 && !e.feature && triangle_part[e.t] != triangle_part[t]) contact[comp[t]][triangle_part[e.t]] += e.length;
    std::vector<std::int32_t> target(comp_area.size(), -1);
    for (std::size_t c = 0; c < comp_area.size(); ++c) {
      if (largest[comp_part[c]] == static_cast<std::int32_t>(c)) continue;
      double best = 0.0;
      for (const auto& [p, len] : contact[c])
        if (len > best || (len == best && p < target[c])) { best = len; target[c] = p; }
    }
    std::size_t round_moves = 0;
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
      if (target[comp[t]] >= 0) { triangle_part[t] = target[comp[t]]; ++round_moves; }
    moved += round_moves;
    if (round_moves == 0) break;
  }
  return moved;
}

}  // namespace polysquare

namespace polysquare {

std::size_t keep_feature_loops_whole(const TriMesh& mesh, std::vector<std::int32_t>& triangle_part) {
  const auto around = vertex_triangles(mesh);
  std::size_t moved = 0;
  for (const TriChain& ch : mesh.chains) {
    if (ch.kind != TriChain::Kind::feature || !ch.closed) continue;
    std::vector<Vec2> loop;
    for (auto v : ch.vertices) loop.push_back(mesh.vertices[v]);
    Box2 box;
    for (Vec2 p : loop) box.add(p);
    // The loop's inside and every triangle touching the loop.
    std::vector<std::uint8_t> in(mesh.triangles.size(), 0);
    for (auto v : ch.vertices)
      for (auto t : around[v]) in[t] = 1;
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      if (in[t]) continue;
      const auto& tr = mesh.triangles[t];
      const Vec2 c = (1.0 / 3.0) * (mesh.vertices[tr[0]] + mesh.vertices[tr[1]] + mesh.vertices[tr[2]]);
      if (c.x >= box.lo.x && c.x <= box.hi.x && c.y >= box.lo.y && c.y <= box.hi.y && point_in_ring(c, loop)) in[t] = 1;
    }
    std::map<std::int32_t, double> area;
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
      if (in[t]) {
        const auto& tr = mesh.triangles[t];
        area[triangle_part[t]] += orient2(mesh.vertices[tr[0]], mesh.vertices[tr[1]], mesh.vertices[tr[2]]);
      }
    if (area.size() < 2) continue;
    const std::int32_t owner =
        std::max_element(area.begin(), area.end(), [](const auto& a, const auto& b) { return a.second < b.second; })->first;
    std::vector<std::pair<std::int32_t, std::int32_t>> changed;  // triangle, old part
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
      if (in[t] && triangle_part[t] != owner) {
        changed.push_back({static_cast<std::int32_t>(t), triangle_part[t]});
        triangle_part[t] = owner;
      }
    bool ok = part_connected(mesh, around, triangle_part, owner);
    for (const auto& [p, a] : area)
      if (p != owner) ok = ok && part_connected(mesh, around, triangle_part, p);
    if (ok) {
      moved += changed.size();
    } else {
      for (const auto& [t, old] : changed) triangle_part[t] = old;
    }
  }
  return moved;
}

}  // namespace polysquare

namespace polysquare {

int merge_enclosed_parts(const TriMesh& mesh, std::vector<std::int32_t>& triangle_part) {
  auto owners = edge_owners(mesh);  // edge -> its (one or two) triangles
  auto key = [](std::int32_t part, std::int32_t v) {
    return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(part)) << 32) | static_cast<std::uint32_t>(v);
  };
  for (bool changed = true; changed;) {
    changed = false;
    // Every boundary loop of every part, walked with the part on its left (outer loops counter-clockwise), and
    // for every vertex on a part boundary the parts around it (-1: outside). A part whose outer loop faces one
    // other part only and meets no third part, ring or pinch is enclosed by it: that loop has no vertex where a
    // poly-square corner could sit on both sides, whatever else (holes, other parts inside) the part holds.
    std::map<std::uint64_t, std::pair<std::int32_t, std::int32_t>> next;  // (part, vertex) -> (vertex, across)
    std::unordered_map<std::int32_t, std::set<std::int32_t>> parts_at;
    std::unordered_set<std::int32_t> pinched;
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      const std::int32_t p = triangle_part[t];
      for (int k = 0; k < 3; ++k) {
        const std::int32_t x = mesh.triangles[t][k], y = mesh.triangles[t][(k + 1) % 3];
        const auto& o = owners.at(edge_key(x, y));
        const std::int32_t other = o[1] < 0 ? -1 : triangle_part[o[0] == static_cast<std::int32_t>(t) ? o[1] : o[0]];
        if (other == p) continue;
        for (auto v : {x, y}) parts_at[v].insert({p, other});
        if (!next.try_emplace(key(p, x), y, other).second) pinched.insert(x);
      }
    }
    std::set<std::uint64_t> visited;
    std::map<std::int32_t, std::int32_t> merge;  // enclosed part -> the part around it
    std::set<std::int32_t> touched;              // parts whose neighbourhood a merge of this pass changes
    for (const auto& [k0, first] : next) {
      if (visited.count(k0)) continue;
      const auto part = static_cast<std::int32_t>(k0 >> 32);
      std::int32_t v = static_cast<std::int32_t>(k0 & 0xffffffffULL);
      const std::int32_t across = first.second;
      bool enclosed = across >= 0;
      double area = 0.0;
      for (std::uint64_t k = k0; !visited.count(k);) {
        visited.insert(k);
        const auto it = next.find(k);
        if (it == next.end()) { enclosed = false; break; }
        const auto [w, a] = it->second;
        enclosed = enclosed && a == across && !pinched.count(v) && parts_at[v].size() == 2;
        area += cross(mesh.vertices[v], mesh.vertices[w]);
        v = w;
        k = key(part, v);
      }
      // Merges of one pass must not depend on each other (a part merged into one that is merged itself);
      // the others wait for the next pass, which sees the new neighbourhoods.
      if (!enclosed || area <= 0.0 || touched.count(part) || touched.count(across)) continue;
      merge[part] = across;
      touched.insert({part, across});
    }
    for (auto& p : triangle_part)
      if (auto it = merge.find(p); it != merge.end()) p = it->second;
    changed = !merge.empty();
  }
  // Renumber the remaining parts 0 .. k-1 in their old order.
  std::map<std::int32_t, std::int32_t> renumber;
  for (auto p : triangle_part) renumber.emplace(p, 0);
  std::int32_t next = 0;
  for (auto& [old, id] : renumber) id = next++;
  for (auto& p : triangle_part) p = renumber[p];
  return next;
}

}  // namespace polysquare

namespace polysquare {

namespace {

// A part's triangles around one vertex, each fan joined through the edges at the vertex its triangles share.
using Fan = std::vector<std::int32_t>;
using FansByPart = std::map<std::int32_t, std::vector<Fan>>;

// The mesh's triangles around each vertex and across each edge, and the partition being changed.
struct PinchSearch {
  const TriMesh& mesh;
  std::vector<std::int32_t>& triangle_part;
  std::unordered_map<std::uint64_t, std::array<std::int32_t, 2>> owners;  // edge -> its (one or two) triangles
  std::vector<std::size_t> off;  // the triangles at vertex v: around[off[v] .. off[v + 1])
  std::vector<std::int32_t> around;

  PinchSearch(const TriMesh& m, std::vector<std::int32_t>& part) : mesh(m), triangle_part(part), owners(edge_owners(m)) {
    const std::size_t nv = mesh.vertices.size(), nt = mesh.triangles.size();
    off.assign(nv + 1, 0);
    for (const auto& t : mesh.triangles)
      for (std::int32_t v : t) off[static_cast<std::size_t>(v) + 1]++;
    for (std::size_t v = 0; v < nv; ++v) off[v + 1] += off[v];
    around.resize(off.back());
    std::vector<std::size_t> fill(off.begin(), off.end() - 1);
    for (std::size_t t = 0; t < nt; ++t)
      for (std::int32_t v : mesh.triangles[t]) around[fill[static_cast<std::size_t>(v)]++] = static_cast<std::int32_t>(t);
  }

  std::int32_t across(std::int32_t t, std::int32_t a, std::int32_t b) const {
    const auto& o = owners.at(edge_key(a, b));
    return o[0] == t ? o[1] : o[0];
  }
  std::int32_t part_of(std::int32_t t) const { return triangle_part[static_cast<std::size_t>(t)]; }
  void assign(const Fan& fan, std::int32_t p) {
    for (std::int32_t t : fan) triangle_part[static_cast<std::size_t>(t)] = p;
  }

  // Whether part p's triangles are still one piece through shared edges.
  bool connected(std::int32_t p) const {
    std::vector<std::int32_t> members;
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
      if (triangle_part[t] == p) members.push_back(static_cast<std::int32_t>(t));
    if (members.empty()) return false;
    std::unordered_set<std::int32_t> seen{members.front()};
    std::vector<std::int32_t> stack{members.front()};
    while (!stack.empty()) {
      const std::int32_t t = stack.back();
      stack.pop_back();
      const auto& tr = mesh.triangles[static_cast<std::size_t>(t)];
      for (int k = 0; k < 3; ++k) {
        const std::int32_t n = across(t, tr[k], tr[(k + 1) % 3]);
        if (n >= 0 && part_of(n) == p && seen.insert(n).second) stack.push_back(n);
      }
    }
    return seen.size() == members.size();
  }

  // Fans of each part around v.
  FansByPart fans_at(std::size_t v) const {
    const auto vi = static_cast<std::int32_t>(v);
    FansByPart fans;
    std::set<std::int32_t> done;
    for (std::size_t i = off[v]; i < off[v + 1]; ++i) {
      const std::int32_t start = around[i];
      if (done.count(start)) continue;
      const std::int32_t p = part_of(start);
      Fan fan{start}, stack{start};
      done.insert(start);
      while (!stack.empty()) {
        const std::int32_t t = stack.back();
        stack.pop_back();
        for (std::int32_t w : mesh.triangles[static_cast<std::size_t>(t)]) {
          if (w == vi) continue;
          const std::int32_t n = across(t, vi, w);
          if (n >= 0 && part_of(n) == p && done.insert(n).second) {
            fan.push_back(n);
            stack.push_back(n);
          }
        }
      }
      fans[p].push_back(std::move(fan));
    }
    return fans;
  }

  // The part other than p that the fan borders most around v, -1 when none.
  std::int32_t most_bordered_part(const Fan& fan, std::int32_t vi, std::int32_t p) const {
    std::map<std::int32_t, int> border;
    for (std::int32_t t : fan)
      for (std::int32_t w : mesh.triangles[static_cast<std::size_t>(t)]) {
        if (w == vi) continue;
        const std::int32_t n = across(t, vi, w);
        if (n >= 0 && part_of(n) != p) border[part_of(n)]++;
      }
    if (border.empty()) return -1;
    return std::max_element(border.begin(), border.end(), [](const auto& a, const auto& b) {
             return a.second < b.second;
           })->first;
  }

  // The fan is p's only link between its sides: p takes a neighbouring part's fan at v instead (the smallest
  // whose part stays one piece), which joins its fans around v; when no fan can change hands, the smallest part
  // around v joins p whole (the caller renumbers). Returns whether the partition changed.
  bool join_fans_of(std::int32_t p, FansByPart& fans, std::size_t& moved) {
    std::vector<std::pair<std::size_t, std::pair<std::int32_t, std::size_t>>> others;
    for (const auto& [q, qlist] : fans)
      if (q != p)
        for (std::size_t g = 0; g < qlist.size(); ++g) others.push_back({qlist[g].size(), {q, g}});
    std::sort(others.begin(), others.end());
    for (const auto& [count, which] : others) {
      const auto& fan = fans[which.first][which.second];
      assign(fan, p);
      if (connected(which.first)) {
        moved += fan.size();
        return true;
      }
      assign(fan, which.first);
    }
    if (others.empty()) return false;
    const std::size_t nt = mesh.triangles.size();
    std::map<std::int32_t, std::size_t> size;
    for (std::size_t t = 0; t < nt; ++t) size[triangle_part[t]]++;
    std::int32_t q = -1;
    for (const auto& [count, which] : others)
      if (q < 0 || size[which.first] < size[q]) q = which.first;
    for (std::size_t t = 0; t < nt; ++t)
      if (triangle_part[t] == q) triangle_part[t] = p, ++moved;
    return true;
  }

  // One part's fans around v reduced to one where possible: the smaller fans go to the part they border most,
  // if p stays one piece without them. Sets changed when a fan moved; returns whether v's fans are stale.
  bool separate_fans(std::int32_t vi, std::int32_t p, std::vector<Fan>& list, FansByPart& fans, std::size_t& moved,
                     bool& changed) {
    std::sort(list.begin(), list.end(), [](const auto& a, const auto& b) { return a.size() > b.size(); });
    for (std::size_t f = 1; f < list.size(); ++f) {
      const std::int32_t to = most_bordered_part(list[f], vi, p);
      if (to < 0) continue;
      assign(list[f], to);
      if (connected(p)) {
        moved += list[f].size();
        changed = true;
        continue;
      }
      assign(list[f], p);
      if (join_fans_of(p, fans, moved)) {
        changed = true;
        return true;
      }
      return false;
    }
    return false;
  }
};

}  // namespace

std::size_t separate_pinched_parts(const TriMesh& mesh, std::vector<std::int32_t>& triangle_part, int max_rounds) {
  PinchSearch search(mesh, triangle_part);
  const std::size_t nv = mesh.vertices.size();
  std::size_t moved = 0;
  for (int round = 0; round < max_rounds; ++round) {
    bool changed = false;
    for (std::size_t v = 0; v < nv; ++v) {
      FansByPart fans = search.fans_at(v);
      for (auto& [p, list] : fans) {
        if (list.size() < 2) continue;
        // Fans of v are stale after a change: the next round looks again.
        if (search.separate_fans(static_cast<std::int32_t>(v), p, list, fans, moved, changed)) break;
      }
    }
    if (!changed) break;
  }
  return moved;
}

}  // namespace polysquare
