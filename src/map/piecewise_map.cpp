#include "polysquare/map/piecewise_map.h"

#include <oneapi/tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <set>
#include <tuple>
#include <unordered_map>

#include "polysquare/core/error.h"
#include "polysquare/map/extract.h"
#include "polysquare/map/layout.h"
#include "polysquare/map/quantize.h"

namespace polysquare {
namespace {

std::string at_text(Vec2 p) { return "(" + std::to_string(p.x) + ", " + std::to_string(p.y) + ")"; }

// What lies across a boundary edge of a subregion: the outside (a ring piece) or a neighbour, with the feature
// curve the edge belongs to, if any. A loop is cut where this changes.
struct Across {
  int neighbour = -1;  // -1: outside the domain
  int chain = -1;      // ring chain (outside) or feature chain (interface along a feature), or -1
  bool operator==(const Across&) const = default;
};

// Global facts about the partitioned triangulation that both sides of every interface read identically.
struct PartitionTopology {
  std::unordered_map<std::uint64_t, std::array<std::int32_t, 2>> owners;  // edge -> triangles (second -1 on rings)
  std::unordered_map<std::uint64_t, int> ring_chain, feature_chain;       // edge -> chain index
  std::vector<std::uint8_t> input;     // vertex is an input vertex of some chain
  std::vector<int> curves;             // number of ring, feature and separator edges at each vertex
  std::vector<std::uint8_t> point;     // isolated feature point
};

PartitionTopology topology(const TriMesh& tri, const std::vector<std::int32_t>& tp) {
  PartitionTopology g;
  const std::size_t nv = tri.vertices.size();
  g.owners = edge_owners(tri);
  g.input.assign(nv, 0);
  for (std::size_t c = 0; c < tri.chains.size(); ++c) {
    const TriChain& ch = tri.chains[c];
    const std::size_t n = ch.vertices.size();
    for (std::size_t i = 0; i < n; ++i) {
      if (ch.is_input[i]) g.input[ch.vertices[i]] = 1;
      if (!ch.closed && i + 1 == n) continue;
      auto& table = ch.kind == TriChain::Kind::ring ? g.ring_chain : g.feature_chain;
      table[edge_key(ch.vertices[i], ch.vertices[(i + 1) % n])] = static_cast<int>(c);
    }
  }
  g.curves.assign(nv, 0);
  for (const auto& [key, o] : g.owners) {
    const bool curve = o[1] < 0 || tp[o[0]] != tp[o[1]] || g.feature_chain.count(key);
    if (!curve) continue;
    g.curves[key >> 32]++;
    g.curves[key & 0xffffffffULL]++;
  }
  g.point.assign(nv, 0);
  for (auto v : tri.feature_point_vertices) g.point[v] = 1;
  return g;
}

Subregion cut_subregion(const TriMesh& tri, const std::vector<std::int32_t>& tp, const PartitionTopology& g, int p,
                        const std::vector<std::int32_t>& triangles, const std::string& name) {
  Subregion sub;
  TriMesh& m = sub.mesh;
  std::unordered_map<std::int32_t, std::int32_t> local;
  auto local_of = [&](std::int32_t v) {
    auto [it, inserted] = local.try_emplace(v, static_cast<std::int32_t>(m.vertices.size()));
    if (inserted) {
      m.vertices.push_back(tri.vertices[v]);
      sub.global_vertex.push_back(v);
    }
    return it->second;
  };
  const std::string where = name + ": subregion " + std::to_string(p);
  // Boundary edges of the subregion, directed with the subregion on their left.
  std::unordered_map<std::int32_t, std::pair<std::int32_t, Across>> next;  // global start -> (end, across)
  for (std::int32_t t : triangles) {
    const auto& tr = tri.triangles[t];
    m.triangles.push_back({local_of(tr[0]), local_of(tr[1]), local_of(tr[2])});
    for (int k = 0; k < 3; ++k) {
      const std::int32_t a = tr[k], b = tr[(k + 1) % 3];
      const std::uint64_t key = edge_key(a, b);
      const auto& o = g.owners.at(key);
      const std::int32_t other = o[0] == t ? o[1] : o[0];
      if (other >= 0 && tp[other] == p) continue;
      Across across;
      if (other < 0) {
        auto it = g.ring_chain.find(key);
        across.chain = it == g.ring_chain.end() ? -1 : it->second;
      } else {
        across.neighbour = tp[other];
        auto it = g.feature_chain.find(key);
        across.chain = it == g.feature_chain.end() ? -1 : it->second;
      }
      if (!next.try_emplace(a, b, across).second)
        throw MeshingError(where + " touches itself at " + at_text(tri.vertices[a]) +
                           "; its boundary is not one simple loop there");
    }
  }
  auto cut_at = [&](std::int32_t v) { return g.curves[v] >= 3 || g.point[v]; };
  auto add_chain = [&](const std::vector<std::int32_t>& verts, bool closed, const Across& across) {
    TriChain ch;
    if (across.neighbour < 0) {
      ch.kind = TriChain::Kind::ring;
      ch.index = across.chain >= 0 ? tri.chains[static_cast<std::size_t>(across.chain)].index : -1;
    } else {
      ch.kind = across.chain >= 0 ? TriChain::Kind::feature : TriChain::Kind::separator;
      ch.index = across.chain >= 0 ? tri.chains[static_cast<std::size_t>(across.chain)].index : across.neighbour;
      ch.interface = across.neighbour;
    }
    ch.closed = closed;
    for (std::int32_t v : verts) {
      ch.vertices.push_back(local_of(v));
      ch.is_input.push_back(g.input[v]);
    }
    m.chains.push_back(std::move(ch));
    return static_cast<int>(m.chains.size()) - 1;
  };

  // Walk the loops in a fixed order (by smallest start vertex) so that the output does not depend on hashing.
  std::vector<std::int32_t> starts;
  for (const auto& [a, e] : next) starts.push_back(a);
  std::sort(starts.begin(), starts.end());
  std::unordered_map<std::int32_t, std::uint8_t> visited;
  for (std::int32_t s0 : starts) {
    if (visited.count(s0)) continue;
    std::vector<std::int32_t> verts;
    std::vector<Across> acr;
    for (std::int32_t v = s0;;) {
      visited[v] = 1;
      verts.push_back(v);
      auto it = next.find(v);
      if (it == next.end()) throw MeshingError(where + ": its boundary does not close near " + at_text(tri.vertices[v]));
      acr.push_back(it->second.second);
      v = it->second.first;
      if (v == s0) break;
      if (visited.count(v)) throw MeshingError(where + " touches itself at " + at_text(tri.vertices[v]));
    }
    const std::size_t n = verts.size();
    std::vector<std::size_t> cuts;
    for (std::size_t i = 0; i < n; ++i)
      if (!(acr[(i + n - 1) % n] == acr[i]) || cut_at(verts[i])) cuts.push_back(i);
    if (cuts.empty()) {
      if (acr[0].neighbour >= 0)
        throw MeshingError(where + " is enclosed by subregion " + std::to_string(acr[0].neighbour) +
                           " alone; a poly-square needs corners where at least three curves meet");
      add_chain(verts, true, acr[0]);  // a whole ring (the part unpartitioned here, or a hole inside)
      continue;
    }
    std::vector<int> loop;
    for (std::size_t k = 0; k < cuts.size(); ++k) {
      const std::size_t from = cuts[k], to = cuts[(k + 1) % cuts.size()];
      std::vector<std::int32_t> piece;
      for (std::size_t i = from;; i = (i + 1) % n) {
        piece.push_back(verts[i]);
        if (i == to && piece.size() > 1) break;
      }
      loop.push_back(add_chain(piece, false, acr[from]));
    }
    m.loops.push_back(std::move(loop));
  }

  // Pieces of feature curves inside the subregion, cut where they meet other curves.
  for (std::size_t c = 0; c < tri.chains.size(); ++c) {
    const TriChain& ch = tri.chains[c];
    if (ch.kind != TriChain::Kind::feature) continue;
    const std::size_t n = ch.vertices.size();
    const std::size_t edges = ch.closed ? n : n - 1;
    auto inside = [&](std::size_t i) {
      const auto& o = g.owners.at(edge_key(ch.vertices[i], ch.vertices[(i + 1) % n]));
      return o[1] >= 0 && tp[o[0]] == p && tp[o[1]] == p;
    };
    auto starts_piece = [&](std::size_t i) {  // edge i starts a new piece
      if (!inside(i)) return false;
      if (!ch.closed && i == 0) return true;
      return !inside((i + edges - 1) % edges) || cut_at(ch.vertices[i]);
    };
    std::size_t first = edges;
    for (std::size_t i = 0; i < edges && first == edges; ++i)
      if (starts_piece(i)) first = i;
    if (first == edges) {
      bool all = edges > 0;
      for (std::size_t i = 0; i < edges && all; ++i) all = inside(i);
      if (all && ch.closed) {  // a feature loop inside the subregion, touching nothing
        TriChain piece = ch;
        for (auto& v : piece.vertices) v = local_of(v);
        piece.interface = -1;
        m.chains.push_back(std::move(piece));
      }
      continue;
    }
    for (std::size_t k = 0; k < edges; ++k) {
      const std::size_t i = (first + k) % edges;
      if (!starts_piece(i)) continue;
      std::vector<std::int32_t> verts{ch.vertices[i]};
      std::size_t j = i;
      do {
        verts.push_back(ch.vertices[(j + 1) % n]);
        j = (j + 1) % edges;
      } while ((ch.closed || j != 0) && j != i && inside(j) && !cut_at(ch.vertices[j]));
      TriChain piece;
      piece.kind = TriChain::Kind::feature;
      piece.index = ch.index;
      for (std::int32_t v : verts) {
        piece.vertices.push_back(local_of(v));
        piece.is_input.push_back(g.input[v]);
      }
      m.chains.push_back(std::move(piece));
    }
  }
  for (auto v : tri.feature_point_vertices)
    if (auto it = local.find(v); it != local.end()) m.feature_point_vertices.push_back(it->second);

  // Interior edges between two boundary vertices would be squeezed flat by the map: split them.
  split_constrained_interior_edges(m);
  sub.global_vertex.resize(m.vertices.size(), -1);
  return sub;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Runs f(i) for every subregion in parallel; the first failure in subregion order is rethrown, so the error
// does not depend on the thread count.
template <class F>
void for_each_subregion(std::size_t count, F&& f) {
  std::vector<std::string> errors(count);
  oneapi::tbb::parallel_for(std::size_t{0}, count, [&](std::size_t i) {
    try {
      f(i);
    } catch (const std::exception& e) {
      errors[i] = e.what();
    }
  });
  for (const auto& e : errors)
    if (!e.empty()) throw MeshingError(e);
}

}  // namespace

std::vector<Subregion> split_subregions(const TriMesh& tri, const std::vector<std::int32_t>& triangle_part, int parts,
                                        const std::string& name) {
  const PartitionTopology g = topology(tri, triangle_part);
  std::vector<std::vector<std::int32_t>> triangles(static_cast<std::size_t>(parts));
  for (std::size_t t = 0; t < triangle_part.size(); ++t)
    triangles[static_cast<std::size_t>(triangle_part[t])].push_back(static_cast<std::int32_t>(t));
  std::vector<Subregion> subs(static_cast<std::size_t>(parts));
  for_each_subregion(subs.size(), [&](std::size_t p) {
    if (triangles[p].empty()) throw MeshingError(name + ": subregion " + std::to_string(p) + " is empty");
    subs[p] = cut_subregion(tri, triangle_part, g, static_cast<int>(p), triangles[p], name);
  });
  return subs;
}

QuadMesh stitch_quad_meshes(const std::vector<QuadMesh>& meshes, const std::vector<std::size_t>& side_nodes,
                            double tolerance) {
  QuadMesh out;
  std::vector<std::vector<std::int32_t>> node_map(meshes.size());
  // Side nodes go into a hash grid of cell `tolerance`; a node merges with one already within tolerance.
  std::unordered_map<std::uint64_t, std::vector<std::int32_t>> grid;
  auto cell = [&](double v) { return static_cast<std::int64_t>(std::floor(v / tolerance)); };
  auto cell_key = [](std::int64_t i, std::int64_t j) {
    return (static_cast<std::uint64_t>(i) * 0x9E3779B97F4A7C15ULL) ^ static_cast<std::uint64_t>(j);
  };
  for (std::size_t k = 0; k < meshes.size(); ++k) {
    const QuadMesh& m = meshes[k];
    node_map[k].resize(m.nodes.size());
    for (std::size_t i = 0; i < m.nodes.size(); ++i) {
      const Vec2 p = m.nodes[i];
      std::int32_t found = -1;
      if (i < side_nodes[k]) {
        const std::int64_t ci = cell(p.x), cj = cell(p.y);
        for (std::int64_t di = -1; di <= 1 && found < 0; ++di)
          for (std::int64_t dj = -1; dj <= 1 && found < 0; ++dj) {
            auto it = grid.find(cell_key(ci + di, cj + dj));
            if (it == grid.end()) continue;
            for (std::int32_t q : it->second)
              if (distance(out.nodes[q], p) <= tolerance) { found = q; break; }
          }
      }
      if (found < 0) {
        found = static_cast<std::int32_t>(out.nodes.size());
        out.nodes.push_back(p);
        out.node_kind.push_back(m.node_kind[i]);
        if (i < side_nodes[k]) grid[cell_key(cell(p.x), cell(p.y))].push_back(found);
      } else if (static_cast<int>(m.node_kind[i]) > static_cast<int>(out.node_kind[found])) {
        out.node_kind[found] = m.node_kind[i];
      }
      node_map[k][i] = found;
    }
  }
  std::map<std::tuple<std::int32_t, std::int32_t, int>, std::uint8_t> seen_feature;
  for (std::size_t k = 0; k < meshes.size(); ++k) {
    const QuadMesh& m = meshes[k];
    const auto& nm = node_map[k];
    for (const auto& q : m.quads) {
      out.quads.push_back({nm[q[0]], nm[q[1]], nm[q[2]], nm[q[3]]});
      out.quad_part.push_back(static_cast<std::int32_t>(k));
    }
    for (std::size_t e = 0; e < m.boundary_edges.size(); ++e) {
      out.boundary_edges.push_back({nm[m.boundary_edges[e][0]], nm[m.boundary_edges[e][1]]});
      out.boundary_edge_ring.push_back(m.boundary_edge_ring[e]);
    }
    for (std::size_t e = 0; e < m.feature_edges.size(); ++e) {
      const std::int32_t a = nm[m.feature_edges[e][0]], b = nm[m.feature_edges[e][1]];
      if (!seen_feature.emplace(std::make_tuple(std::min(a, b), std::max(a, b), m.feature_edge_curve[e]), 1).second) continue;
      out.feature_edges.push_back({a, b});
      out.feature_edge_curve.push_back(m.feature_edge_curve[e]);
    }
  }
  return out;
}

QuadMesh map_piecewise(const TriMesh& tri, const std::vector<std::int32_t>& triangle_part, int parts,
                       const PolysquareMapOptions& options, const std::string& name, PartMapStats& st) {
  auto t0 = std::chrono::steady_clock::now();
  std::vector<Subregion> subs = split_subregions(tri, triangle_part, parts, name);
  const std::size_t n = subs.size();
  std::vector<MappedMesh> mapped(n);
  std::vector<Layout> layouts(n);
  auto sub_name = [&](std::size_t p) { return name + ": subregion " + std::to_string(p); };
  for_each_subregion(n, [&](std::size_t p) {
    mapped[p] = deform_mesh(subs[p].mesh, options, true);
    layouts[p] = build_layout(subs[p].mesh, subs[p].mesh.vertices, mapped[p].x, options.layout, sub_name(p));
  });
  if (!options.layout.straight_interfaces) {
    // Bent interfaces: a break point one side puts on an interface becomes a (straight) break point on the
    // other side too, so the two sides split it into the same segments.
    std::set<std::int32_t> interface_breaks;
    for (std::size_t p = 0; p < n; ++p)
      for (std::int32_t v : layouts[p].break_vertex)
        if (subs[p].global_vertex[static_cast<std::size_t>(v)] >= 0)
          interface_breaks.insert(subs[p].global_vertex[static_cast<std::size_t>(v)]);
    for_each_subregion(n, [&](std::size_t p) {
      const TriMesh& m = subs[p].mesh;
      std::vector<std::uint8_t> extra(m.vertices.size(), 0);
      for (const TriChain& ch : m.chains)
        if (ch.interface >= 0)
          for (std::int32_t v : ch.vertices)
            extra[static_cast<std::size_t>(v)] = interface_breaks.count(subs[p].global_vertex[static_cast<std::size_t>(v)]) > 0;
      add_straight_breaks(layouts[p], m, mapped[p].x, extra, sub_name(p));
    });
  }
  for_each_subregion(n, [&](std::size_t p) {
    straighten_to_labels(mapped[p], layouts[p], subs[p].mesh, options);
  });
  st.seconds_deform = seconds_since(t0);
  for (std::size_t p = 0; p < n; ++p) {
    st.deform.iterations += mapped[p].stats.iterations;
    st.deform.energy_before += mapped[p].stats.energy_before;
    st.deform.energy_after += mapped[p].stats.energy_after;
    st.break_points += layouts[p].break_vertex.size();
    st.segments += layouts[p].segments.size();
  }

  // The two sides of an interface: segments with the same end vertices and the same first edge from the
  // smaller end (two interfaces between the same junctions differ there).
  t0 = std::chrono::steady_clock::now();
  std::map<std::tuple<std::int32_t, std::int32_t, std::int32_t>, std::pair<std::size_t, int>> open;
  std::vector<SegmentCoupling> couplings;
  for (std::size_t p = 0; p < n; ++p) {
    const Subregion& sub = subs[p];
    for (std::size_t k = 0; k < layouts[p].segments.size(); ++k) {
      const LayoutSegment& s = layouts[p].segments[k];
      const TriChain& ch = sub.mesh.chains[static_cast<std::size_t>(s.chain)];
      if (ch.interface < 0) continue;
      const int cn = static_cast<int>(ch.vertices.size());
      auto gv = [&](int i) { return sub.global_vertex[static_cast<std::size_t>(ch.vertices[(s.first + i) % cn])]; };
      const std::int32_t a = gv(0), b = gv(s.count);
      const std::int32_t second = a < b ? gv(1) : gv(s.count - 1);
      const auto key = std::make_tuple(std::min(a, b), std::max(a, b), second);
      auto [it, inserted] = open.try_emplace(key, p, static_cast<int>(k));
      if (inserted) continue;
      couplings.push_back({it->second.first, it->second.second, p, static_cast<int>(k)});
      open.erase(it);
    }
  }
  if (!open.empty()) {
    const auto& [key, ps] = *open.begin();
    throw MeshingError(name + ": the interface of subregion " + std::to_string(ps.first) + " at " +
                       at_text(tri.vertices[std::get<0>(key)]) + " is split differently by its neighbour");
  }
  std::vector<Layout*> lp;
  std::vector<const std::vector<Vec2>*> dp;
  for (std::size_t p = 0; p < n; ++p) {
    lp.push_back(&layouts[p]);
    dp.push_back(&mapped[p].x);
  }
  try {
    st.quantize = quantize_layouts(lp, dp, couplings, options.quantize, name);
  } catch (const MeshingError& joint) {
    // Name the subregion that cannot close on its own; if each can, the interfaces cannot agree.
    for (std::size_t p = 0; p < n; ++p) {
      Layout alone = layouts[p];
      try {
        quantize_layout(alone, mapped[p].x, options.quantize, sub_name(p));
      } catch (const MeshingError& e) {
        throw MeshingError(std::string(e.what()) + " [" + std::to_string(layouts[p].segments.size()) + " sides]");
      }
    }
    throw MeshingError(std::string(joint.what()) + ": every subregion closes alone, but not with equal counts on both "
                       "sides of every interface");
  }
  for (std::size_t p = 0; p < n; ++p)
    if (const std::string problem = check_layout(layouts[p]); !problem.empty())
      throw MeshingError(sub_name(p) + ": the quantized poly-square is not valid: " + problem);
  st.seconds_quantize = seconds_since(t0);

  t0 = std::chrono::steady_clock::now();
  std::vector<QuadMesh> meshes(n);
  std::vector<std::size_t> side_nodes(n, 0);
  for_each_subregion(n, [&](std::size_t p) {
    snap_to_layout(subs[p].mesh, mapped[p], layouts[p], options, sub_name(p));
    meshes[p] = extract_quads(subs[p].mesh, subs[p].mesh.vertices, mapped[p].x, layouts[p], sub_name(p), nullptr,
                              &side_nodes[p]);
  });
  st.seconds_snap = seconds_since(t0);
  t0 = std::chrono::steady_clock::now();
  QuadMesh out = stitch_quad_meshes(meshes, side_nodes, 1e-6 * options.size);
  st.seconds_extract = seconds_since(t0);
  st.separators = couplings.size();
  return out;
}

}  // namespace polysquare
