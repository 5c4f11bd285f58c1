#include "polysquare/map/piecewise_map.h"

#include <oneapi/tbb/parallel_for.h>

#include <algorithm>
#include <exception>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <tuple>
#include <unordered_map>
#include <unordered_set>

#include "polysquare/core/error.h"
#include "polysquare/core/union_find.h"
#include "polysquare/fallback/patch.h"
#include "polysquare/map/extract.h"
#include "polysquare/map/layout.h"
#include "polysquare/map/map_bytes.h"
#include "polysquare/map/multipass.h"
#include "polysquare/map/quantize.h"
#include "polysquare/partition/partition.h"
#include "map/interface_turns.h"
#include "map/map_common.h"
#include "map/transition_rows.h"

namespace polysquare {
namespace {

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

// Where a subregion's chains end: vertices on three or more curves (rings, features, separators), feature points.
bool ends_chains(const PartitionTopology& g, std::int32_t v) {
  return g.curves[static_cast<std::size_t>(v)] >= 3 || g.point[static_cast<std::size_t>(v)];
}

// A subregion being cut out of the partitioned triangulation: its mesh so far and the local number of every
// vertex of `tri` it holds.
struct SubregionCut {
  const TriMesh& tri;
  const std::vector<std::int32_t>& tp;
  const PartitionTopology& g;
  int p;
  std::string where;
  Subregion sub;
  std::unordered_map<std::int32_t, std::int32_t> local;

  std::int32_t local_of(std::int32_t v) {
    auto [it, inserted] = local.try_emplace(v, static_cast<std::int32_t>(sub.mesh.vertices.size()));
    if (inserted) {
      sub.mesh.vertices.push_back(tri.vertices[v]);
      sub.global_vertex.push_back(v);
    }
    return it->second;
  }
  bool cut_at(std::int32_t v) const { return ends_chains(g, v); }
  // A chain of the subregion's boundary, after what lies across it; returns its index.
  int add_chain(const std::vector<std::int32_t>& verts, bool closed, const Across& across) {
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
    sub.mesh.chains.push_back(std::move(ch));
    return static_cast<int>(sub.mesh.chains.size()) - 1;
  }
};

// Boundary edges of a subregion, directed with the subregion on their left: global start -> (end, across).
using BoundaryEdges = std::unordered_map<std::int32_t, std::pair<std::int32_t, Across>>;

// The subregion's triangles added to its mesh, and its boundary edges.
BoundaryEdges add_triangles(SubregionCut& c, const std::vector<std::int32_t>& triangles) {
  BoundaryEdges next;
  for (std::int32_t t : triangles) {
    const auto& tr = c.tri.triangles[t];
    c.sub.mesh.triangles.push_back({c.local_of(tr[0]), c.local_of(tr[1]), c.local_of(tr[2])});
    for (int k = 0; k < 3; ++k) {
      const std::int32_t a = tr[k], b = tr[(k + 1) % 3];
      const std::uint64_t key = edge_key(a, b);
      const auto& o = c.g.owners.at(key);
      const std::int32_t other = o[0] == t ? o[1] : o[0];
      if (other >= 0 && c.tp[other] == c.p) continue;
      Across across;
      if (other < 0) {
        auto it = c.g.ring_chain.find(key);
        across.chain = it == c.g.ring_chain.end() ? -1 : it->second;
      } else {
        across.neighbour = c.tp[other];
        auto it = c.g.feature_chain.find(key);
        across.chain = it == c.g.feature_chain.end() ? -1 : it->second;
      }
      if (!next.try_emplace(a, b, across).second)
        throw MeshingError(c.where + " touches itself at " + at_text(c.tri.vertices[a]) +
                           "; its boundary is not one simple loop there");
    }
  }
  return next;
}

// One boundary loop cut into chains where what lies across it changes or curves meet (verts: its vertices,
// acr: what lies across the edge after each).
void add_loop(SubregionCut& c, const std::vector<std::int32_t>& verts, const std::vector<Across>& acr) {
  const std::size_t n = verts.size();
  std::vector<std::size_t> cuts;
  for (std::size_t i = 0; i < n; ++i)
    if (!(acr[(i + n - 1) % n] == acr[i]) || c.cut_at(verts[i])) cuts.push_back(i);
  if (cuts.empty()) {
    if (acr[0].neighbour >= 0)
      throw MeshingError(c.where + " is enclosed by subregion " + std::to_string(acr[0].neighbour) +
                         " alone; a poly-square needs corners where at least three curves meet");
    c.add_chain(verts, true, acr[0]);  // a whole ring (the part unpartitioned here, or a hole inside)
    return;
  }
  std::vector<int> loop;
  for (std::size_t k = 0; k < cuts.size(); ++k) {
    const std::size_t from = cuts[k], to = cuts[(k + 1) % cuts.size()];
    std::vector<std::int32_t> piece;
    for (std::size_t i = from;; i = (i + 1) % n) {
      piece.push_back(verts[i]);
      if (i == to && piece.size() > 1) break;
    }
    loop.push_back(c.add_chain(piece, false, acr[from]));
  }
  c.sub.mesh.loops.push_back(std::move(loop));
}

// The subregion's boundary loops, walked in a fixed order (by smallest start vertex) so that the output does
// not depend on hashing.
void add_boundary_loops(SubregionCut& c, const BoundaryEdges& next) {
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
      if (it == next.end()) throw MeshingError(c.where + ": its boundary does not close near " + at_text(c.tri.vertices[v]));
      acr.push_back(it->second.second);
      v = it->second.first;
      if (v == s0) break;
      if (visited.count(v)) throw MeshingError(c.where + " touches itself at " + at_text(c.tri.vertices[v]));
    }
    add_loop(c, verts, acr);
  }
}

// The pieces of feature curve `ch` inside the subregion, cut where they meet other curves.
void add_feature_pieces(SubregionCut& c, const TriChain& ch) {
  const std::size_t n = ch.vertices.size();
  const std::size_t edges = ch.closed ? n : n - 1;
  auto inside = [&](std::size_t i) {
    const auto& o = c.g.owners.at(edge_key(ch.vertices[i], ch.vertices[(i + 1) % n]));
    return o[1] >= 0 && c.tp[o[0]] == c.p && c.tp[o[1]] == c.p;
  };
  auto starts_piece = [&](std::size_t i) {  // edge i starts a new piece
    if (!inside(i)) return false;
    if (!ch.closed && i == 0) return true;
    return !inside((i + edges - 1) % edges) || c.cut_at(ch.vertices[i]);
  };
  std::size_t first = edges;
  for (std::size_t i = 0; i < edges && first == edges; ++i)
    if (starts_piece(i)) first = i;
  if (first == edges) {
    bool all = edges > 0;
    for (std::size_t i = 0; i < edges && all; ++i) all = inside(i);
    if (all && ch.closed) {  // a feature loop inside the subregion, touching nothing
      TriChain piece = ch;
      for (auto& v : piece.vertices) v = c.local_of(v);
      piece.interface = -1;
      c.sub.mesh.chains.push_back(std::move(piece));
    }
    return;
  }
  for (std::size_t k = 0; k < edges; ++k) {
    const std::size_t i = (first + k) % edges;
    if (!starts_piece(i)) continue;
    std::vector<std::int32_t> verts{ch.vertices[i]};
    std::size_t j = i;
    do {
      verts.push_back(ch.vertices[(j + 1) % n]);
      j = (j + 1) % edges;
    } while ((ch.closed || j != 0) && j != i && inside(j) && !c.cut_at(ch.vertices[j]));
    TriChain piece;
    piece.kind = TriChain::Kind::feature;
    piece.index = ch.index;
    for (std::int32_t v : verts) {
      piece.vertices.push_back(c.local_of(v));
      piece.is_input.push_back(c.g.input[v]);
    }
    c.sub.mesh.chains.push_back(std::move(piece));
  }
}

Subregion cut_subregion(const TriMesh& tri, const std::vector<std::int32_t>& tp, const PartitionTopology& g, int p,
                        const std::vector<std::int32_t>& triangles, const std::string& name) {
  SubregionCut c{tri, tp, g, p, name + ": subregion " + std::to_string(p), {}, {}};
  add_boundary_loops(c, add_triangles(c, triangles));
  // Pieces of feature curves inside the subregion, cut where they meet other curves.
  for (const TriChain& ch : tri.chains)
    if (ch.kind == TriChain::Kind::feature) add_feature_pieces(c, ch);
  TriMesh& m = c.sub.mesh;
  for (auto v : tri.feature_point_vertices)
    if (auto it = c.local.find(v); it != c.local.end()) m.feature_point_vertices.push_back(it->second);

  // Interior edges between two boundary vertices would be squeezed flat by the map: split them.
  split_constrained_interior_edges(m);
  c.sub.global_vertex.resize(m.vertices.size(), -1);
  return std::move(c.sub);
}

// An interface side by its global end vertices and the vertex after the smaller end (two interfaces between the
// same junctions differ there).
using SideKey = std::tuple<std::int32_t, std::int32_t, std::int32_t>;

// Makes every face even: the faces are the subregion's triangles cut by its inner feature pieces, and a face's
// count is the sum of the pieces along it (an inner piece between two faces counts in both). An odd face moves
// the count of the inner piece to its parent in a breadth-first tree of the faces, which passes the flip on.
template <class Piece, class EvenOut>
void even_faces(const TriMesh& m, std::vector<std::vector<Piece>>& loops, std::vector<std::vector<Piece>>& inner,
                EvenOut&& even_out) {
  if (inner.empty()) return;
  std::unordered_set<std::uint64_t> cut;
  for (const auto& pieces : inner)
    for (const Piece& pc : pieces)
      for (std::size_t i = 0; i + 1 < pc.verts.size(); ++i) cut.insert(edge_key(pc.verts[i], pc.verts[i + 1]));
  const auto owners = edge_owners(m);
  UnionFind face(static_cast<int>(m.triangles.size()));
  auto root = [&](std::int32_t t) { return face.find(t); };
  for (const auto& [key, own] : owners)
    if (own[1] >= 0 && !cut.count(key)) face.unite(own[0], own[1]);
  auto sides = [&](const Piece& pc) -> std::array<std::int32_t, 2> {
    const auto it = owners.find(edge_key(pc.verts[0], pc.verts[1]));
    if (it == owners.end()) return {-1, -1};
    return {root(it->second[0]), it->second[1] >= 0 ? root(it->second[1]) : root(it->second[0])};
  };
  std::map<std::int32_t, long long> parity;
  for (const auto& pieces : loops)
    for (const Piece& pc : pieces)
      if (const auto f = sides(pc); f[0] >= 0) parity[f[0]] += pc.n;
  // Face graph: an edge per inner piece between two faces; a breadth-first tree from the first face.
  std::map<std::int32_t, std::vector<std::pair<std::int32_t, Piece*>>> graph;
  for (auto& pieces : inner)
    for (Piece& pc : pieces) {
      const auto f = sides(pc);
      if (f[0] < 0) continue;
      parity[f[0]] += pc.n;
      parity[f[1]] += pc.n;
      if (f[0] != f[1]) {
        graph[f[0]].push_back({f[1], &pc});
        graph[f[1]].push_back({f[0], &pc});
      }
    }
  std::map<std::int32_t, std::pair<std::int32_t, Piece*>> parent;
  std::vector<std::int32_t> order;
  for (const auto& [start, unused] : parity) {
    if (parent.count(start)) continue;
    parent[start] = {-1, nullptr};
    order.push_back(start);
    for (std::size_t i = order.size() - 1; i < order.size(); ++i)
      for (const auto& [g, pc] : graph[order[i]])
        if (!parent.count(g)) {
          parent[g] = {order[i], pc};
          order.push_back(g);
        }
  }
  // Leaves first: an odd face flips the piece to its parent, which passes the flip on.
  for (std::size_t i = order.size(); i-- > 0;) {
    const std::int32_t f = order[i];
    const auto [up, pc] = parent[f];
    if (parity[f] % 2 == 0 || !pc) continue;
    const long long before = pc->n;
    even_out(*pc);
    parity[f] += pc->n - before;
    parity[up] += pc->n - before;
  }
}

// A piece of a patch's boundary or inner feature curve between two given nodes, with its element count.
struct PatchPiece {
  std::vector<std::int32_t> verts;  // chain vertices, first and last are ends
  long long n = 1;
  bool adjustable = false;
  PatchEdgeRole role = PatchEdgeRole::none;
  int tag = -1;
  double length = 0;
  double sizes = 0;  // the length in local sizes: length / h, or graded the integral of 1 / h along it
};

// What cutting a subregion's chains into patch pieces reads.
struct PatchPieces {
  const Subregion& sub;
  const std::vector<std::uint8_t>& corner;
  const std::vector<std::uint8_t>& is_patch;
  const std::map<SideKey, long long>& side_count;
  const std::vector<std::uint8_t>& chain_ends;
  double h;
  const SizeField* field;  // graded: the size along the pieces; null: h everywhere
  const std::string& where;

  std::int32_t gv(std::int32_t v) const { return sub.global_vertex[static_cast<std::size_t>(v)]; }
  double length_of(const std::vector<std::int32_t>& verts) const {
    const TriMesh& m = sub.mesh;
    double l = 0.0;
    // Summed from the end with the smaller global index, so both patches of a shared interface agree.
    if (gv(verts.front()) <= gv(verts.back()))
      for (std::size_t i = 1; i < verts.size(); ++i) l += distance(m.vertices[verts[i - 1]], m.vertices[verts[i]]);
    else
      for (std::size_t i = verts.size() - 1; i > 0; --i) l += distance(m.vertices[verts[i - 1]], m.vertices[verts[i]]);
    return l;
  }
  // The piece's length in local sizes, summed from the same end as length_of: both sides of an interface between
  // two patches take the same count from it. Graded, each patch's least size would give each side its own.
  double sizes_of(const std::vector<std::int32_t>& verts, double length) const {
    if (!field) return length / h;
    const TriMesh& m = sub.mesh;
    auto step = [&](std::size_t i) {
      const Vec2 a = m.vertices[verts[i - 1]], b = m.vertices[verts[i]];
      return distance(a, b) / field->at(0.5 * (a + b));
    };
    double n = 0.0;
    if (gv(verts.front()) <= gv(verts.back()))
      for (std::size_t i = 1; i < verts.size(); ++i) n += step(i);
    else
      for (std::size_t i = verts.size() - 1; i > 0; --i) n += step(i);
    return n;
  }
};

// Counts of an interface come from the quantization when its other side was quantized (the neighbour is
// mapped, or was patched only after quantization); otherwise both patches take an even count. Between two
// patches no piece passes a chain end of the subregions (`chain_ends`): a union of patches has one chain
// where its neighbour has one per member, and both must cut it alike (else a crack).
// Returns the quantized count of the interface piece from verts[i] (-1: none, an even count) and sets j to
// its end.
long long interface_piece(const PatchPieces& c, const TriChain& ch, const std::vector<std::int32_t>& verts,
                          std::size_t i, std::size_t& j) {
  const bool mapped_side = !c.is_patch[static_cast<std::size_t>(ch.interface)];
  long long count = -1;
  std::size_t end = verts.size() - 1;
  if (!mapped_side)
    for (end = i + 1; end + 1 < verts.size(); ++end) {
      const std::int32_t g = c.gv(verts[end]);
      if (g >= 0 && static_cast<std::size_t>(g) < c.chain_ends.size() && c.chain_ends[static_cast<std::size_t>(g)]) break;
    }
  for (; j <= end; ++j) {
    const std::int32_t a = c.gv(verts[i]), b = c.gv(verts[j]);
    const SideKey key{std::min(a, b), std::max(a, b), a < b ? c.gv(verts[i + 1]) : c.gv(verts[j - 1])};
    if (auto it = c.side_count.find(key); it != c.side_count.end()) { count = it->second; break; }
  }
  if (count < 0 && !mapped_side) {
    j = end;  // no quantized side up to the next chain end: one piece, an even count
  } else if (count < 0)
    throw MeshingError(c.where + ": no element count for its interface with subregion " +
                       std::to_string(ch.interface) + " at " + at_text(c.sub.mesh.vertices[verts[i]]));
  return count;
}

// Pieces of one chain (vertices in chain order; closed chains repeat the first vertex at the end).
std::vector<PatchPiece> pieces_of(const PatchPieces& c, const TriChain& ch, bool inner_feature) {
  std::vector<std::int32_t> verts = ch.vertices;
  if (ch.closed) {
    // Start at a sharp vertex when there is one, so a closed chain's pieces end there.
    std::size_t s = 0;
    for (std::size_t i = 0; i < verts.size(); ++i)
      if (c.corner[static_cast<std::size_t>(verts[i])]) { s = i; break; }
    std::rotate(verts.begin(), verts.begin() + static_cast<std::ptrdiff_t>(s), verts.end());
    verts.push_back(verts.front());
  }
  const bool interface = ch.interface >= 0;
  std::vector<PatchPiece> out;
  std::size_t i = 0;
  while (i + 1 < verts.size()) {
    std::size_t j = i + 1;
    long long count = -1;
    if (interface) {
      count = interface_piece(c, ch, verts, i, j);
    } else {
      // Ring pieces also end at every input vertex: the patch's coarse triangulation then follows the input
      // polyline itself, and its edges cannot cut across a convoluted shoreline.
      const bool ring = ch.kind == TriChain::Kind::ring;
      while (j + 1 < verts.size() && !c.corner[static_cast<std::size_t>(verts[j])] &&
             !(ring && ch.is_input.size() == ch.vertices.size() && ch.is_input[static_cast<std::size_t>(
                   std::find(ch.vertices.begin(), ch.vertices.end(), verts[j]) - ch.vertices.begin())]))
        ++j;
    }
    PatchPiece pc;
    pc.verts.assign(verts.begin() + static_cast<std::ptrdiff_t>(i), verts.begin() + static_cast<std::ptrdiff_t>(j) + 1);
    pc.length = c.length_of(pc.verts);
    pc.sizes = c.sizes_of(pc.verts, pc.length);
    pc.role = ch.kind == TriChain::Kind::ring ? PatchEdgeRole::boundary
                                               : (ch.kind == TriChain::Kind::feature ? PatchEdgeRole::feature : PatchEdgeRole::none);
    pc.tag = ch.index;
    if (count >= 0) {
      pc.n = count;
    } else if (inner_feature || ch.kind == TriChain::Kind::ring || interface) {
      pc.n = 2 * std::max(1LL, std::llround(pc.sizes / 2.0));  // even: its ends stay coarse vertices
      pc.adjustable = ch.kind == TriChain::Kind::ring;
    } else {
      pc.n = std::max(1LL, std::llround(pc.sizes));
    }
    out.push_back(std::move(pc));
    i = j;
  }
  return out;
}

// A piece's count made odd or even by one more element (one fewer when it is already well above its sizes).
void even_out(PatchPiece& pc) {
  pc.n = pc.n + 1 <= std::llround(pc.sizes) + 1 || pc.n == 1 ? pc.n + 1 : pc.n - 1;
}

// Every run of fixed pieces (interfaces) with an odd count is evened out by the ring piece right after it
// (or before it), so that ring pieces keep starting on coarse vertices. Anchors (ends of inner features) start
// new runs: between two of them the count must be even.
void even_out_runs(std::vector<PatchPiece>& pieces, const std::set<std::int32_t>& anchors) {
  const std::size_t np = pieces.size();
  std::size_t start = 0;  // a run may not wrap past a loop start that is an adjustable piece or an anchor
  for (std::size_t k = 0; k < np; ++k)
    if (pieces[k].adjustable || anchors.count(pieces[k].verts.front())) { start = k; break; }
  long long run = 0;
  std::size_t run_begin = start;
  for (std::size_t step = 0; step <= np; ++step) {
    const std::size_t k = (start + step) % np;
    const bool boundary = step == np || pieces[k].adjustable || anchors.count(pieces[k].verts.front());
    if (boundary && run % 2 != 0) {
      // Even out with the adjustable piece at k, or the one before the run.
      const std::size_t before = (run_begin + np - 1) % np;
      std::size_t fix = np;
      if (pieces[k].adjustable) fix = k;  // at step == np, k is the loop's start again
      else if (pieces[before].adjustable) fix = before;
      // No ring piece next to the run: the split construction cannot take it, the matching one can (it
      // needs only an even count in all, below).
      if (fix != np) even_out(pieces[fix]);
      run = 0;
    }
    if (step == np) break;
    if (boundary) {
      run = 0;
      run_begin = (k + 1) % np;
      if (!pieces[k].adjustable) { run = pieces[k].n; run_begin = k; }  // an anchored interface opens a run
    } else {
      run += pieces[k].n;
    }
  }
}

// Chords between given nodes must not cross another curve's: where two curves run closer than the node
// spacing (a shallow crossing, a river beside a shoreline) the pieces there whose counts are free (inner
// features) take twice the nodes, at most three times.
void refine_crossing_chords(const TriMesh& m, std::vector<std::vector<PatchPiece>>& loops,
                            std::vector<std::vector<PatchPiece>>& inner, double h) {
  auto pts_of = [&](const PatchPiece& pc) {
    std::vector<Vec2> pts;
    for (std::int32_t v : pc.verts) pts.push_back(m.vertices[static_cast<std::size_t>(v)]);
    return spread_along(pts, pts, pc.n);
  };
  for (int round = 0; round < 3; ++round) {
    std::vector<PatchPiece*> all;
    std::vector<std::uint8_t> free_count;
    for (auto& pieces : loops)
      for (PatchPiece& pc : pieces) { all.push_back(&pc); free_count.push_back(0); }
    for (auto& pieces : inner)
      for (PatchPiece& pc : pieces) { all.push_back(&pc); free_count.push_back(1); }
    struct Chord { Vec2 a, b; std::size_t piece; };
    std::vector<Chord> chords;
    for (std::size_t k = 0; k < all.size(); ++k) {
      const std::vector<Vec2> q = pts_of(*all[k]);
      for (std::size_t i = 0; i + 1 < q.size(); ++i) chords.push_back({q[i], q[i + 1], k});
    }
    std::unordered_map<std::uint64_t, std::vector<std::size_t>> cells;
    auto cell_key = [&](long long i, long long j) { return (static_cast<std::uint64_t>(i) << 32) ^ static_cast<std::uint64_t>(j & 0xffffffffLL); };
    std::vector<std::uint8_t> crossed(all.size(), 0);
    for (std::size_t c = 0; c < chords.size(); ++c) {
      const Chord& e = chords[c];
      const long long i0 = static_cast<long long>(std::floor(std::min(e.a.x, e.b.x) / h)), i1 = static_cast<long long>(std::floor(std::max(e.a.x, e.b.x) / h));
      const long long j0 = static_cast<long long>(std::floor(std::min(e.a.y, e.b.y) / h)), j1 = static_cast<long long>(std::floor(std::max(e.a.y, e.b.y) / h));
      std::set<std::size_t> near;
      for (long long i = i0; i <= i1; ++i)
        for (long long j = j0; j <= j1; ++j) {
          auto& cell = cells[cell_key(i, j)];
          near.insert(cell.begin(), cell.end());
          cell.push_back(c);
        }
      for (std::size_t d : near) {
        const Chord& f = chords[d];
        if (f.piece == e.piece) continue;
        if (segments_cross(e.a, e.b, f.a, f.b)) crossed[e.piece] = crossed[f.piece] = 1;
      }
    }
    bool refined = false;
    for (std::size_t k = 0; k < all.size(); ++k)
      if (crossed[k] && free_count[k]) {
        all[k]->n *= 2;
        refined = true;
      }
    if (!refined) break;
  }
}

// A quad mesh has an even number of boundary edges in all (every quad has four edges, every inner edge is
// in two quads); the first ring piece evens it out, and without one the quantization should have.
void even_out_total(const TriMesh& m, std::vector<std::vector<PatchPiece>>& loops, const std::string& where) {
  long long total = 0;
  PatchPiece* first_adjustable = nullptr;
  for (auto& pieces : loops)
    for (PatchPiece& pc : pieces) {
      total += pc.n;
      if (pc.adjustable && !first_adjustable) first_adjustable = &pc;
    }
  if (total % 2 != 0) {
    if (!first_adjustable)
      throw MeshingError(where + ": an odd number of interface elements (" + std::to_string(total) +
                         ") all round it, from " + at_text(m.vertices[loops.front().front().verts.front()]) +
                         ", and no boundary piece to even it out");
    even_out(*first_adjustable);
  }
}

// The given nodes and curves of a patch, built piece by piece.
struct PatchNodes {
  const TriMesh& m;
  const std::vector<std::uint8_t>& corner;
  PatchInput in;
  std::unordered_map<std::int32_t, std::int32_t> node_of;

  static NodeKind kind_of(PatchEdgeRole r) {
    return r == PatchEdgeRole::boundary ? NodeKind::boundary : (r == PatchEdgeRole::feature ? NodeKind::feature : NodeKind::interior);
  }
  std::int32_t end_node(std::int32_t v, PatchEdgeRole role) {
    auto [it, inserted] = node_of.try_emplace(v, static_cast<std::int32_t>(in.nodes.size()));
    NodeKind kind = corner[static_cast<std::size_t>(v)] && role != PatchEdgeRole::none ? NodeKind::corner : kind_of(role);
    if (inserted) {
      in.nodes.push_back(m.vertices[static_cast<std::size_t>(v)]);
      in.kind.push_back(kind);
    } else if (static_cast<int>(kind) > static_cast<int>(in.kind[static_cast<std::size_t>(it->second)])) {
      in.kind[static_cast<std::size_t>(it->second)] = kind;
    }
    return it->second;
  }
  void add_curve(const std::vector<PatchPiece>& pieces, bool closed, bool loop) {
    PatchCurve c;
    c.closed = closed;
    c.loop = loop;
    for (const PatchPiece& pc : pieces) {
      std::vector<Vec2> pts;
      for (std::int32_t v : pc.verts) pts.push_back(m.vertices[static_cast<std::size_t>(v)]);
      const std::vector<Vec2> spread = spread_along(pts, pts, pc.n);
      if (c.nodes.empty()) c.nodes.push_back(end_node(pc.verts.front(), pc.role));
      for (long long k = 1; k < pc.n; ++k) {
        c.nodes.push_back(static_cast<std::int32_t>(in.nodes.size()));
        in.nodes.push_back(spread[static_cast<std::size_t>(k)]);
        in.kind.push_back(kind_of(pc.role));
      }
      c.nodes.push_back(end_node(pc.verts.back(), pc.role));
      for (long long k = 0; k < pc.n; ++k) {
        c.role.push_back(pc.role);
        c.tag.push_back(pc.tag);
      }
    }
    if (closed) c.nodes.pop_back();  // the last end is the first node again
    in.curves.push_back(std::move(c));
  }
  void add_point(std::int32_t v) {
    auto [it, inserted] = node_of.try_emplace(v, static_cast<std::int32_t>(in.nodes.size()));
    if (inserted) {
      in.nodes.push_back(m.vertices[static_cast<std::size_t>(v)]);
      in.kind.push_back(NodeKind::corner);
    }
    in.points.push_back(it->second);
  }
};

// The given nodes of the patch that repairs subregion `sub`: its boundary loops and inner feature curves cut
// into pieces (at sharp vertices, curve meetings and the mapped neighbours' side ends), each with its element
// count: a mapped neighbour's count on its interfaces, length / h elsewhere (even on inner features, which the
// patch splits in pairs). Ring pieces absorb the parity: the split construction needs an even count between two
// anchors (ends of inner features), the matching one only an even count in all.
PatchInput patch_input(const Subregion& sub, const std::vector<std::uint8_t>& is_patch,
                       const std::map<SideKey, long long>& side_count, const std::vector<std::uint8_t>& chain_ends,
                       double h, const SizeField* field, double corner_deg, const std::string& where) {
  const TriMesh& m = sub.mesh;
  const std::vector<std::uint8_t> corner = corner_vertices(m, m.vertices, corner_deg);
  const PatchPieces cut{sub, corner, is_patch, side_count, chain_ends, h, field, where};
  std::vector<std::uint8_t> in_loop(m.chains.size(), 0);
  std::vector<std::vector<PatchPiece>> loops, inner;
  for (const auto& loop : m.loops) {
    loops.emplace_back();
    for (int c : loop) {
      in_loop[static_cast<std::size_t>(c)] = 1;
      for (PatchPiece& pc : pieces_of(cut, m.chains[static_cast<std::size_t>(c)], false)) loops.back().push_back(std::move(pc));
    }
  }
  for (std::size_t c = 0; c < m.chains.size(); ++c) {
    if (in_loop[c]) continue;
    const TriChain& ch = m.chains[c];
    if (ch.kind == TriChain::Kind::ring) loops.push_back(pieces_of(cut, ch, false));  // a whole ring inside
    else inner.push_back(pieces_of(cut, ch, true));
  }
  // Anchors: ends of inner feature pieces. Between two anchors along a loop the count must be even.
  std::set<std::int32_t> anchors;
  for (const auto& pieces : inner)
    for (const PatchPiece& pc : pieces) {
      anchors.insert(pc.verts.front());
      anchors.insert(pc.verts.back());
    }
  for (auto& pieces : loops) even_out_runs(pieces, anchors);
  refine_crossing_chords(m, loops, inner, h);
  even_out_total(m, loops, where);
  // Inner features cut the patch into faces, and the matching construction pairs triangles within a face: each
  // face needs an even count along its sides too. An inner piece between two faces flips both when its count
  // changes by one, so odd faces are paired along a spanning tree of the faces (the total is even, so they pair).
  even_faces(m, loops, inner, [](PatchPiece& pc) { even_out(pc); });

  PatchNodes nodes{m, corner, {}, {}};
  for (const auto& pieces : loops) nodes.add_curve(pieces, true, true);
  for (std::size_t k = 0, c = 0; c < m.chains.size(); ++c) {
    if (in_loop[c] || m.chains[c].kind == TriChain::Kind::ring) continue;
    const auto& pieces = inner[k++];
    // Each inner piece is its own curve, so its ends are anchors; a closed feature without sharp vertices is one.
    if (m.chains[c].closed && pieces.size() == 1) nodes.add_curve(pieces, true, false);
    else
      for (const PatchPiece& pc : pieces) nodes.add_curve({pc}, false, false);
  }
  for (std::int32_t v : m.feature_point_vertices) nodes.add_point(v);
  return std::move(nodes.in);
}

}  // namespace

std::vector<Subregion> split_subregions(const TriMesh& tri, const std::vector<std::int32_t>& triangle_part, int parts,
                                        const std::string& name, std::vector<std::uint8_t>* chain_ends) {
  const PartitionTopology g = topology(tri, triangle_part);
  if (chain_ends) {
    chain_ends->assign(tri.vertices.size(), 0);
    for (std::size_t v = 0; v < tri.vertices.size(); ++v) (*chain_ends)[v] = ends_chains(g, static_cast<std::int32_t>(v));
  }
  std::vector<std::vector<std::int32_t>> triangles(static_cast<std::size_t>(parts));
  for (std::size_t t = 0; t < triangle_part.size(); ++t)
    triangles[static_cast<std::size_t>(triangle_part[t])].push_back(static_cast<std::int32_t>(t));
  std::vector<Subregion> subs(static_cast<std::size_t>(parts));
  for_each_item(subs.size(), [&](std::size_t p) {
    if (triangles[p].empty()) throw MeshingError(name + ": subregion " + std::to_string(p) + " is empty");
    subs[p] = cut_subregion(tri, triangle_part, g, static_cast<int>(p), triangles[p], name);
  });
  return subs;
}

int split_listed_subregions(const TriMesh& tri, std::vector<std::int32_t>& triangle_part, int parts,
                            const std::vector<std::pair<int, int>>& listed, const PolysquareMapOptions& options,
                            const std::string& name, int& split) {
  split = 0;
  const double h = options.size;
  std::vector<std::vector<std::int32_t>> triangles(static_cast<std::size_t>(parts));
  std::vector<double> sub_area(static_cast<std::size_t>(parts), 0.0);
  double part_area = 0.0;
  double field_quads = 0.0;  // graded: the part's quads by the field's local sizes (its subregions are small by design)
  for (std::size_t t = 0; t < triangle_part.size(); ++t) {
    const auto p = static_cast<std::size_t>(triangle_part[t]);
    const auto& tr = tri.triangles[t];
    const Vec2 va = tri.vertices[tr[0]], vb = tri.vertices[tr[1]], vc = tri.vertices[tr[2]];
    const double a = 0.5 * orient2(va, vb, vc);
    triangles[p].push_back(static_cast<std::int32_t>(t));
    sub_area[p] += a;
    part_area += a;
    if (options.size_field) {
      const double hc = options.size_field->at((1.0 / 3.0) * (va + vb + vc));
      field_quads += a / (hc * hc);
    }
  }
  const std::vector<std::int32_t> before = triangle_part;
  const int parts_before = parts;
  const double part_quads = options.size_field ? field_quads : part_area / (h * h);
  const std::size_t per_subregion =
      options.size_field ? options.split_graded_quads_per_subregion : options.split_quads_per_subregion;
  const double cap = std::max(static_cast<double>(options.split_max_subregions),
                              part_quads / static_cast<double>(std::max<std::size_t>(per_subregion, 1)));
  for (const auto& [p, sides] : listed) {
    const auto& mine = triangles[static_cast<std::size_t>(p)];
    const double area = sub_area[static_cast<std::size_t>(p)];
    const int k = std::clamp((sides + options.sides_per_split - 1) / options.sides_per_split, 2, 8);
    if (area / (h * h) < 16.0 * k || static_cast<int>(mine.size()) < 8 * k) continue;  // pieces of 4 x 4
    if (static_cast<double>(parts + k - 1) > cap) continue;
    // The subregion's triangles as a mesh of their own (global vertex numbers, the feature curves for the
    // partition energy); piece 0 keeps the number p, the others are appended.
    TriMesh piece;
    piece.vertices = tri.vertices;
    for (std::int32_t t : mine) piece.triangles.push_back(tri.triangles[static_cast<std::size_t>(t)]);
    for (const TriChain& ch : tri.chains)
      if (ch.kind == TriChain::Kind::feature) piece.chains.push_back(ch);
    PartitionOptions popt = options.partition;
    popt.parts = k;
    if (popt.min_face_area <= 0) popt.min_face_area = 16.0 * h * h;  // as map_part
    PartitionResult pr;
    try {
      pr = partition_triangles(piece, popt);
    } catch (const MeshingError&) {
      continue;  // METIS refuses some pieces (too few triangles for k balanced parts): it stays as it is
    }
    for (std::size_t i = 0; i < mine.size(); ++i) {
      const std::int32_t q = pr.triangle_part[i];
      triangle_part[static_cast<std::size_t>(mine[i])] = q == 0 ? static_cast<std::int32_t>(p) : parts + q - 1;
    }
    parts += pr.parts - 1;
    ++split;
  }
  if (split == 0) return parts;
  keep_feature_loops_whole(tri, triangle_part);
  absorb_pieces_cut_off_by_features(tri, triangle_part);
  snap_separator_ends_to_corners(tri, triangle_part, options.layout.corner_threshold_deg);
  parts = merge_enclosed_parts(tri, triangle_part);
  if (separate_pinched_parts(tri, triangle_part) > 0) parts = merge_enclosed_parts(tri, triangle_part);
  try {
    split_subregions(tri, triangle_part, parts, name);
  } catch (const MeshingError&) {
    triangle_part = before;  // the pieces cannot be cut apart: keep the partition as it was
    split = 0;
    return parts_before;
  }
  return parts;
}

int split_unmappable_subregions(const TriMesh& tri, std::vector<std::int32_t>& triangle_part, int parts,
                                const PolysquareMapOptions& options, const std::string& name, SplitStats& stats) {
  const auto t0 = std::chrono::steady_clock::now();
  // Subregions known to map, by their triangle set: a later round tests only what changed.
  std::set<std::vector<std::int32_t>> maps_alone;
  for (int round = 0; round < options.split_rounds; ++round) {
    std::vector<std::vector<std::int32_t>> triangles(static_cast<std::size_t>(parts));
    for (std::size_t t = 0; t < triangle_part.size(); ++t)
      triangles[static_cast<std::size_t>(triangle_part[t])].push_back(static_cast<std::int32_t>(t));
    std::vector<Subregion> subs;
    try {
      subs = split_subregions(tri, triangle_part, parts, name);
    } catch (const MeshingError&) {
      break;  // the caller's map reports it
    }
    const std::size_t n = subs.size();
    // sides[p]: poly-square sides of subregion p's failed map (0 when it maps, or failed before its layout).
    std::vector<int> failed(n, 0), sides(n, 0);
    std::vector<std::uint8_t> test(n, 0);
    for (std::size_t p = 0; p < n; ++p) test[p] = maps_alone.count(triangles[p]) == 0;
    stats.tested += static_cast<int>(std::count(test.begin(), test.end(), 1));
    std::vector<double> cost(n, 0.0);
    for (std::size_t p = 0; p < n; ++p) cost[p] = test[p] ? static_cast<double>(subs[p].mesh.triangles.size()) : 0.0;
    shared_for(options.sharing.get(), n, cost, "split test", [&](std::size_t p) {
      if (!test[p]) return;
      try {
        MappedMesh mm = deform_mesh(subs[p].mesh, options, true);
        Layout layout = build_layout(subs[p].mesh, subs[p].mesh.vertices, mm.x, options.layout, name);
        sides[p] = static_cast<int>(layout.segments.size());
        straighten_to_labels(mm, layout, subs[p].mesh, options);
        quantize_layout(layout, mm.x, options.quantize, name);
        if (!check_layout(layout).empty()) throw MeshingError(name + ": invalid quantized layout");
        snap_to_layout(subs[p].mesh, mm, layout, options, name);
        sides[p] = 0;
      } catch (const MeshingError&) {
        failed[p] = 1;
      }
    }, [&](std::size_t p, ByteWriter& w) { w.put(failed[p]), w.put(sides[p]); },
       [&](std::size_t p, ByteReader& r) { r.get(failed[p]), r.get(sides[p]); });
    std::vector<std::pair<int, int>> listed;  // failed subregion, its sides
    for (std::size_t p = 0; p < n; ++p) {
      if (!failed[p]) {
        if (round > 0 && test[p]) stats.pieces_mapped++;
        maps_alone.insert(triangles[p]);
        continue;
      }
      listed.push_back({static_cast<int>(p), sides[p]});
    }
    int split_now = 0;
    parts = split_listed_subregions(tri, triangle_part, parts, listed, options, name, split_now);
    if (split_now == 0) break;
    stats.rounds++;
    stats.split += split_now;
  }
  stats.seconds = seconds_since(t0);
  return parts;
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

// The triangle partition with every subregion replaced by its group (the union of patches it joined), the
// triangles of each group in `roots`, and the topology of that partition.
struct GroupedPartition {
  std::vector<std::int32_t> tp;
  std::vector<std::vector<std::int32_t>> members;  // by group, for the groups in roots only
  PartitionTopology topology;
};

GroupedPartition group_partition(const TriMesh& tri, const std::vector<std::int32_t>& triangle_part,
                                 const std::vector<std::int32_t>& group, const std::set<std::int32_t>& roots) {
  GroupedPartition gp;
  gp.tp.resize(triangle_part.size());
  gp.members.resize(group.size());
  for (std::size_t t = 0; t < gp.tp.size(); ++t) {
    gp.tp[t] = group[static_cast<std::size_t>(triangle_part[t])];
    if (roots.count(gp.tp[t])) gp.members[static_cast<std::size_t>(gp.tp[t])].push_back(static_cast<std::int32_t>(t));
  }
  gp.topology = topology(tri, gp.tp);
  return gp;
}

// The runs of a subregion's boundary loops that its patch cannot even out itself (patch_input's parity rule):
// stretches of interfaces between two ends of inner feature pieces (anchors), or a whole loop without anchors,
// with no ring piece at either end. Each run is given as the global edge keys of its interface edges; the
// counts on them must add up to an even number.
std::vector<std::vector<std::uint64_t>> patch_runs(const Subregion& sub) {
  const TriMesh& m = sub.mesh;
  std::vector<std::uint8_t> in_loop(m.chains.size(), 0);
  for (const auto& loop : m.loops)
    for (int c : loop) in_loop[static_cast<std::size_t>(c)] = 1;
  std::set<std::int32_t> anchors;
  for (std::size_t c = 0; c < m.chains.size(); ++c)
    if (!in_loop[c] && m.chains[c].kind == TriChain::Kind::feature && !m.chains[c].closed) {
      anchors.insert(m.chains[c].vertices.front());
      anchors.insert(m.chains[c].vertices.back());
    }
  auto gv = [&](std::int32_t v) { return sub.global_vertex[static_cast<std::size_t>(v)]; };
  std::vector<std::vector<std::uint64_t>> runs;
  for (const auto& loop : m.loops) {
    const std::size_t k = loop.size();
    auto chain = [&](std::size_t i) -> const TriChain& { return m.chains[static_cast<std::size_t>(loop[i % k])]; };
    auto is_ring = [&](std::size_t i) { return chain(i).kind == TriChain::Kind::ring; };
    // A run starts after a ring piece or at an anchor; start the walk at such a place when there is one.
    std::size_t start = k;
    for (std::size_t i = 0; i < k && start == k; ++i)
      if (is_ring(i) || anchors.count(chain(i).vertices.front())) start = i;
    const bool whole = start == k;  // neither: the whole loop is one run
    if (whole) start = 0;
    std::vector<std::uint64_t> run;
    bool fixable = false;  // a ring piece opens the run
    auto close = [&](bool ring_after) {
      if (!run.empty() && !fixable && !ring_after) runs.push_back(run);
      run.clear();
    };
    for (std::size_t step = 0; step < k; ++step) {
      const std::size_t i = start + step;
      if (is_ring(i)) {
        close(true);
        fixable = true;
        continue;
      }
      if (step > 0 && anchors.count(chain(i).vertices.front())) {
        close(false);
        fixable = is_ring(i + k - 1);
      } else if (step == 0) {
        fixable = !whole && is_ring(i + k - 1);
      }
      if (chain(i).interface >= 0)
        for (std::size_t v = 0; v + 1 < chain(i).vertices.size(); ++v)
          run.push_back(edge_key(gv(chain(i).vertices[v]), gv(chain(i).vertices[v + 1])));
    }
    close(!whole && is_ring(start));
  }
  return runs;
}

namespace {

// The state of the PPM of one partitioned part, which its steps (map_piecewise, below) read and change.
struct PiecewiseMap {
  const TriMesh& tri;
  const std::vector<std::int32_t>& triangle_part;
  int parts;
  const PolysquareMapOptions& options;
  const std::string& name;
  PartMapStats& st;
  std::vector<std::uint8_t> chain_ends;  // of these subregions: where patches cut interfaces between them
  std::vector<Subregion> subs;
  std::size_t n = 0;
  std::vector<MappedMesh> mapped;
  std::vector<Layout> layouts;
  // failure[p]: why subregion p's map failed (empty while it maps). A failure stays local: the subregion is
  // left out of the joint quantization and repaired by an unstructured patch that takes its neighbours' nodes.
  std::vector<std::string> failure;
  // group[p]: the subregion whose patch holds p (p itself unless p joined a union of patches, see
  // grow_patches_by_one_neighbour); union_sub[r]: the area of the union numbered r, once the part is quantized
  // again for it.
  std::vector<std::int32_t> group;
  std::vector<std::optional<Subregion>> union_sub;
  std::vector<SegmentCoupling> couplings;
  // Quantization, snap and patches (map_piecewise's rounds).
  std::vector<std::uint8_t> quantized, is_patch;
  std::vector<std::string> patch_error;
  std::vector<std::string> grown_because;  // a grown patch's root: why its first patch could not be built
  std::vector<QuadMesh> meshes;
  std::vector<std::size_t> side_nodes;
  std::vector<std::uint8_t> untangled;          // #subregions: its snap untangled folds
  std::vector<std::vector<Vec2>> unsnapped;     // deformed positions before the snap, to snap again
  std::map<SideKey, long long> side_count;      // element count of every quantized interface segment
  std::size_t failed_maps = 0, failed_repairs = 0;
  double seconds_quantize = 0, seconds_snap = 0, seconds_patches = 0;

  PiecewiseMap(const TriMesh& tri, const std::vector<std::int32_t>& triangle_part, int parts,
               const PolysquareMapOptions& options, const std::string& name, PartMapStats& st)
      : tri(tri), triangle_part(triangle_part), parts(parts), options(options), name(name), st(st) {}
  std::string sub_name(std::size_t p) const { return name + ": subregion " + std::to_string(p); }
  bool is_root(std::size_t p) const { return group[p] == static_cast<std::int32_t>(p); }
  // The subregion a patch root meshes: the union's, or its own.
  const Subregion& patch_area(std::size_t p) const { return union_sub[p] ? *union_sub[p] : subs[p]; }
  std::vector<std::size_t> members_now() const {
    std::vector<std::size_t> m;
    for (std::size_t p = 0; p < n; ++p)
      if (failure[p].empty()) m.push_back(p);
    return m;
  }
  // The two sides of an interface: segments with the same end vertices and the same first edge from the
  // smaller end (two interfaces between the same junctions differ there).
  SideKey side_key(std::size_t p, const TriChain& ch, int first, int count) const {
    const int cn = static_cast<int>(ch.vertices.size());
    auto gv = [&](int i) { return subs[p].global_vertex[static_cast<std::size_t>(ch.vertices[(first + i) % cn])]; };
    const std::int32_t a = gv(0), b = gv(count);
    return SideKey{std::min(a, b), std::max(a, b), a < b ? gv(1) : gv(count - 1)};
  }
  // f(p) for every subregion still mapped, divided among the processes (options.sharing); pack and unpack
  // carry what f changed (also where it failed half-way) from the process that ran it to the others.
  template <class F, class Pack, class Unpack>
  void each_mapped(std::string_view tag, F&& f, Pack&& pack, Unpack&& unpack) {
    std::vector<double> cost(n, 0.0);
    std::vector<std::uint8_t> ran(n, 0);
    for (std::size_t p = 0; p < n; ++p)
      if (failure[p].empty()) ran[p] = 1, cost[p] = static_cast<double>(subs[p].mesh.triangles.size());
    shared_for(options.sharing.get(), n, cost, tag, [&](std::size_t p) {
      if (!ran[p]) return;
      try {
        f(p);
      } catch (const MeshingError& e) {
        failure[p] = e.what();
      }
    }, [&](std::size_t p, ByteWriter& w) {
      w.put(failure[p]);
      if (ran[p]) pack(p, w);
    }, [&](std::size_t p, ByteReader& r) {
      r.get(failure[p]);
      if (ran[p]) unpack(p, r);
    });
  }
  // What a patch loop shares between processes: the patch (or its error) of subregion p.
  void pack_patch(std::size_t p, ByteWriter& w) { w.put(patch_error[p]), put_bytes(w, meshes[p]), w.put(side_nodes[p]); }
  void unpack_patch(std::size_t p, ByteReader& r) { r.get(patch_error[p]), get_bytes(r, meshes[p]), r.get(side_nodes[p]); }
};

// The subregions of the part cut apart, each failed at once where a patch was requested.
void cut_subregions(PiecewiseMap& m) {
  m.subs = split_subregions(m.tri, m.triangle_part, m.parts, m.name, &m.chain_ends);
  const std::size_t n = m.n = m.subs.size();
  m.mapped.resize(n);
  m.layouts.resize(n);
  m.failure.resize(n);
  for (int p : m.options.patch_subregions)
    if (p >= 0 && static_cast<std::size_t>(p) < n)
      m.failure[static_cast<std::size_t>(p)] = m.sub_name(static_cast<std::size_t>(p)) + ": a patch was requested";
  m.group.resize(n);
  for (std::size_t p = 0; p < n; ++p) m.group[p] = static_cast<std::int32_t>(p);
  m.union_sub.resize(n);
}

// Multi-pass PPM: every subregion's map starts from the positions the passes left its vertices at (vertices
// added by splitting an edge between two chain vertices at the middle of that edge's ends).
std::vector<Vec2> multipass_start(const Subregion& sub, const std::vector<Vec2>& together) {
  const std::size_t nv = sub.mesh.vertices.size();
  std::vector<Vec2> x(nv);
  std::vector<std::vector<std::int32_t>> next(nv);
  for (const auto& t : sub.mesh.triangles)
    for (int k = 0; k < 3; ++k) next[static_cast<std::size_t>(t[k])].push_back(t[(k + 1) % 3]);
  for (std::size_t v = 0; v < nv; ++v)
    if (sub.global_vertex[v] >= 0) x[v] = together[static_cast<std::size_t>(sub.global_vertex[v])];
  for (std::size_t v = 0; v < nv; ++v) {
    if (sub.global_vertex[v] >= 0) continue;
    double best = std::numeric_limits<double>::infinity();
    for (std::int32_t a : next[v])
      for (std::int32_t b : next[v]) {
        const auto ua = static_cast<std::size_t>(a), ub = static_cast<std::size_t>(b);
        if (a >= b || sub.global_vertex[ua] < 0 || sub.global_vertex[ub] < 0) continue;
        const double off = distance(0.5 * (sub.mesh.vertices[ua] + sub.mesh.vertices[ub]), sub.mesh.vertices[v]);
        if (off < best) best = off, x[v] = 0.5 * (x[ua] + x[ub]);
      }
  }
  return x;
}

// Bent interfaces: a break point one side puts on an interface becomes a (straight) break point on the
// other side too, so the two sides split it into the same segments.
void share_interface_breaks(PiecewiseMap& m) {
  std::set<std::int32_t> interface_breaks;
  for (std::size_t p = 0; p < m.n; ++p)
    if (m.failure[p].empty())
      for (std::int32_t v : m.layouts[p].break_vertex)
        if (m.subs[p].global_vertex[static_cast<std::size_t>(v)] >= 0)
          interface_breaks.insert(m.subs[p].global_vertex[static_cast<std::size_t>(v)]);
  m.each_mapped("straight breaks", [&](std::size_t p) {
    const TriMesh& mesh = m.subs[p].mesh;
    std::vector<std::uint8_t> extra(mesh.vertices.size(), 0);
    for (const TriChain& ch : mesh.chains)
      if (ch.interface >= 0)
        for (std::int32_t v : ch.vertices)
          extra[static_cast<std::size_t>(v)] = interface_breaks.count(m.subs[p].global_vertex[static_cast<std::size_t>(v)]) > 0;
    add_straight_breaks(m.layouts[p], mesh, m.mapped[p].x, extra, m.sub_name(p));
  }, [&](std::size_t p, ByteWriter& w) { put_bytes(w, m.layouts[p]); },
     [&](std::size_t p, ByteReader& r) { get_bytes(r, m.layouts[p]); });
}

// Every subregion deformed towards a poly-square and labelled (in parallel), its interfaces' breaks and turns
// agreed with its neighbours', then deformed again along its labels.
void deform_and_label(PiecewiseMap& m) {
  const PolysquareMapOptions& options = m.options;
  std::vector<Vec2> together;
  if (options.multipass.max_passes > 0) {
    together = multipass_deform(m.tri, m.triangle_part, m.parts, options.size, options.multipass, options.deform,
                                m.st.multipass);
  }
  m.each_mapped("deform", [&](std::size_t p) {
    const TriMesh& mesh = m.subs[p].mesh;
    m.mapped[p] = together.empty() ? deform_mesh(mesh, options, true)
                                   : deformed_mesh(mesh, options, multipass_start(m.subs[p], together));
    m.layouts[p] = build_layout(mesh, mesh.vertices, m.mapped[p].x, options.layout, m.sub_name(p));
  }, [&](std::size_t p, ByteWriter& w) { put_bytes(w, m.mapped[p], true), put_bytes(w, m.layouts[p]); },
     [&](std::size_t p, ByteReader& r) { get_bytes(r, m.mapped[p], true), get_bytes(r, m.layouts[p]); });
  if (!options.layout.straight_interfaces) share_interface_breaks(m);
  if (options.layout.agree_turn_elements > 0.0) {
    // Feature interfaces: where one side turns and the other goes straight, one side is turned to agree.
    std::vector<InterfaceSide> sides(m.n);
    for (std::size_t p = 0; p < m.n; ++p)
      if (m.failure[p].empty())
        sides[p] = {&m.layouts[p], &m.subs[p].mesh, &m.mapped[p].x, &m.subs[p].global_vertex, m.sub_name(p)};
    m.st.agreed_turns = agree_feature_interface_turns(sides, options.layout.agree_turn_elements);
  }
  m.each_mapped("straighten", [&](std::size_t p) { straighten_to_labels(m.mapped[p], m.layouts[p], m.subs[p].mesh, options); },
                [&](std::size_t p, ByteWriter& w) { put_bytes(w, m.mapped[p], false), put_bytes(w, m.layouts[p]); },
                [&](std::size_t p, ByteReader& r) { get_bytes(r, m.mapped[p], false), get_bytes(r, m.layouts[p]); });
}

// The deformation and layout figures of the mapped subregions, added up.
void add_deform_stats(PiecewiseMap& m) {
  for (std::size_t p = 0; p < m.n; ++p) {
    if (!m.failure[p].empty()) continue;
    m.st.deform.iterations += m.mapped[p].stats.iterations;
    m.st.deform.energy_before += m.mapped[p].stats.energy_before;
    m.st.deform.energy_after += m.mapped[p].stats.energy_after;
    m.st.break_points += m.layouts[p].break_vertex.size();
    m.st.segments += m.layouts[p].segments.size();
  }
}

// Pairs the two sides of every interface between mapped subregions (m.couplings). False when a side has no
// partner: its mapped neighbour splits it differently, and that subregion is repaired instead.
bool pair_interface_sides(PiecewiseMap& m) {
  m.couplings.clear();
  std::map<SideKey, std::pair<std::size_t, int>> open;
  for (std::size_t p = 0; p < m.n; ++p) {
    if (!m.failure[p].empty()) continue;
    for (std::size_t k = 0; k < m.layouts[p].segments.size(); ++k) {
      const LayoutSegment& s = m.layouts[p].segments[k];
      const TriChain& ch = m.subs[p].mesh.chains[static_cast<std::size_t>(s.chain)];
      if (ch.interface < 0 || !m.failure[static_cast<std::size_t>(ch.interface)].empty()) continue;
      auto [it, inserted] = open.try_emplace(m.side_key(p, ch, s.first, s.count), p, static_cast<int>(k));
      if (inserted) continue;
      m.couplings.push_back({it->second.first, it->second.second, p, static_cast<int>(k)});
      open.erase(it);
    }
  }
  if (open.empty()) return true;
  const auto& [key, ps] = *open.begin();
  m.failure[ps.first] = m.sub_name(ps.first) + ": its interface at " + at_text(m.tri.vertices[std::get<0>(key)]) +
                        " is split differently by its neighbour";
  return false;
}

// Graded meshes: the counts of a separator's two sides may differ by an even number, which a transition row
// joins (build_transitions), so that the size can change where a structured map cannot follow it.
void allow_transitions(PiecewiseMap& m) {
  if (!m.options.size_field || m.options.quantize.transition_cost <= 0.0) return;
  // Only where the two sides' own maps ask for counts 30 % and 1.5 elements apart: each transition makes the
  // joint program larger and slower (on channel_estuary 13-500 m a ratio of 1.3 and of 1.6 gave the same
  // quality; every separator took the joint maps from 24 s to 166 s).
  constexpr double least_ratio = 1.3, least_difference = 1.5;
  for (SegmentCoupling& c : m.couplings) {
    const LayoutSegment& s = m.layouts[c.layout_a].segments[static_cast<std::size_t>(c.segment_a)];
    const double ta = s.target, tb = m.layouts[c.layout_b].segments[static_cast<std::size_t>(c.segment_b)].target;
    c.transition = m.subs[c.layout_a].mesh.chains[static_cast<std::size_t>(s.chain)].kind == TriChain::Kind::separator &&
                   std::max(ta, tb) >= least_ratio * std::min(ta, tb) && std::abs(ta - tb) >= least_difference;
  }
}

// Two convex corners where an interface turns: the smaller side is repaired instead. True when one was found.
bool fail_convex_on_both_sides(PiecewiseMap& m) {
  std::vector<const Layout*> mapped_layouts(m.n, nullptr);
  for (std::size_t p = 0; p < m.n; ++p)
    if (m.failure[p].empty()) mapped_layouts[p] = &m.layouts[p];
  const auto both = convex_on_both_sides(mapped_layouts, m.couplings);
  if (!both) return false;
  const std::size_t p =
      m.subs[both->a].mesh.triangles.size() <= m.subs[both->b].mesh.triangles.size() ? both->a : both->b;
  const LayoutSegment& s = m.layouts[both->a].segments[static_cast<std::size_t>(both->segment_a_next)];
  const std::int32_t v = m.layouts[both->a].break_vertex[static_cast<std::size_t>(s.break_a)];
  m.failure[p] = m.sub_name(p) + ": its interface with subregion " + std::to_string(p == both->a ? both->b : both->a) +
                 " turns at " + at_text(m.subs[both->a].mesh.vertices[static_cast<std::size_t>(v)]) +
                 " with a convex corner on both sides";
  return true;
}

// A subregion to be patched cannot even out the counts its mapped neighbours give it where no ring piece of
// its own is next to them: the quantization must make those counts even (see patch_runs). `index` numbers the
// subregions in the program (-1: not in it).
std::vector<EvenGroup> patch_even_groups(const PiecewiseMap& m, const std::vector<std::int32_t>& index) {
  std::vector<EvenGroup> even;
  for (std::size_t p = 0; p < m.n; ++p) {
    if (m.failure[p].empty() || !m.is_root(p)) continue;
    const Subregion& area = m.patch_area(p);
    std::map<std::uint64_t, std::size_t> run_of;  // global interface edge -> its run
    const std::vector<std::vector<std::uint64_t>> runs = patch_runs(area);
    for (std::size_t r = 0; r < runs.size(); ++r)
      for (std::uint64_t e : runs[r]) run_of[e] = r;
    std::set<std::size_t> neighbours;  // mapped ones in this program
    for (const TriChain& ch : area.mesh.chains)
      if (ch.interface >= 0 && index[static_cast<std::size_t>(ch.interface)] >= 0) neighbours.insert(static_cast<std::size_t>(ch.interface));
    std::vector<EvenGroup> groups(runs.size());
    for (std::size_t q : neighbours)
      for (std::size_t k = 0; k < m.layouts[q].segments.size(); ++k) {
        const LayoutSegment& s = m.layouts[q].segments[k];
        const TriChain& qc = m.subs[q].mesh.chains[static_cast<std::size_t>(s.chain)];
        if (qc.interface < 0 || m.group[static_cast<std::size_t>(qc.interface)] != static_cast<std::int32_t>(p)) continue;
        const std::size_t cn = qc.vertices.size();
        auto gv = [&](int i) { return m.subs[q].global_vertex[static_cast<std::size_t>(qc.vertices[static_cast<std::size_t>(i) % cn])]; };
        if (auto it = run_of.find(edge_key(gv(s.first), gv(s.first + 1))); it != run_of.end())
          groups[it->second].push_back({static_cast<std::size_t>(index[q]), static_cast<int>(k)});
      }
    for (EvenGroup& g : groups)
      if (!g.empty()) even.push_back(std::move(g));
  }
  return even;
}

// One integer program for all mapped subregions. When it has no solution, the subregions that cannot agree
// with their neighbours (elastic couplings) or cannot close alone are repaired; their neighbours keep their maps.
// With `disagree` given the couplings are elastic, and the pairs of subregions whose interface counts the
// solution could not make equal are appended to it.
// Subregions that cannot close even alone are marked failed as the solve finds them, and the rest solved again.
QuantizeStats solve_joint(PiecewiseMap& m, std::vector<std::size_t> members,
                          std::vector<std::pair<std::size_t, std::size_t>>* disagree = nullptr) {
  for (;;) {
    std::vector<std::int32_t> index(m.n, -1);
    std::vector<Layout*> lp;
    std::vector<const std::vector<Vec2>*> dp;
    for (std::size_t p : members) {
      index[p] = static_cast<std::int32_t>(lp.size());
      lp.push_back(&m.layouts[p]);
      dp.push_back(&m.mapped[p].x);
    }
    std::vector<SegmentCoupling> local;
    for (const SegmentCoupling& c : m.couplings)
      if (index[c.layout_a] >= 0 && index[c.layout_b] >= 0)
        local.push_back({static_cast<std::size_t>(index[c.layout_a]), c.segment_a,
                         static_cast<std::size_t>(index[c.layout_b]), c.segment_b, c.transition});
    const std::vector<EvenGroup> even = patch_even_groups(m, index);
    std::vector<std::size_t> broken;
    try {
      const QuantizeStats q = quantize_layouts_shared(m.options.sharing.get(), lp, dp, local, m.options.quantize, m.name,
                                                      even, disagree ? &broken : nullptr);
      for (std::size_t c : broken) disagree->push_back({members[local[c].layout_a], members[local[c].layout_b]});
      return q;
    } catch (const LayoutsCannotClose& e) {
      for (std::size_t i = 0; i < e.layouts.size(); ++i) {
        const std::size_t p = members[e.layouts[i]];
        m.failure[p] = m.sub_name(p) + ": " + e.reasons[i] + " [" + std::to_string(m.layouts[p].segments.size()) + " sides]";
      }
      std::erase_if(members, [&](std::size_t p) { return !m.failure[p].empty(); });
      if (members.empty()) return QuantizeStats{};
    }
  }
}

// Every mapped subregion quantized alone; those that cannot close even alone fail.
void fail_unquantizable_alone(PiecewiseMap& m) {
  const std::vector<std::size_t> members = m.members_now();
  std::vector<std::string> alone_failure(members.size());
  std::vector<double> cost(members.size());
  for (std::size_t i = 0; i < members.size(); ++i) cost[i] = static_cast<double>(m.layouts[members[i]].segments.size());
  shared_for(m.options.sharing.get(), members.size(), cost, "quantize alone", [&](std::size_t i) {
    const std::size_t p = members[i];
    Layout alone = m.layouts[p];
    try {
      quantize_layout(alone, m.mapped[p].x, m.options.quantize, m.sub_name(p));
    } catch (const MeshingError& e) {
      alone_failure[i] = std::string(e.what()) + " [" + std::to_string(m.layouts[p].segments.size()) + " sides]";
    }
  }, [&](std::size_t i, ByteWriter& w) { w.put(alone_failure[i]); },
     [&](std::size_t i, ByteReader& r) { r.get(alone_failure[i]); });
  for (std::size_t i = 0; i < members.size(); ++i)
    if (!alone_failure[i].empty()) m.failure[members[i]] = alone_failure[i];
}

// Of each disagreeing pair the subregion in the most disagreements (then the one with more sides) fails.
void fail_most_disagreeing(PiecewiseMap& m, std::vector<std::pair<std::size_t, std::size_t>> disagree,
                           const MeshingError& joint) {
  while (!disagree.empty()) {
    std::map<std::size_t, std::size_t> blame;
    for (const auto& [a, b] : disagree) ++blame[a], ++blame[b];
    const std::size_t p = std::max_element(blame.begin(), blame.end(), [&](const auto& x, const auto& y) {
                            if (x.second != y.second) return x.second < y.second;
                            return m.layouts[x.first].segments.size() < m.layouts[y.first].segments.size();
                          })->first;
    m.failure[p] = m.sub_name(p) + ": its sides cannot take the counts its neighbours need (" + joint.what() + ")";
    std::erase_if(disagree, [&](const auto& d) { return d.first == p || d.second == p; });
  }
}

// Elastic couplings first: one solve shows which neighbours cannot agree; those fail (fail_most_disagreeing)
// and the rest is solved again. A subregion that cannot close even alone is repaired first. True when a solve
// then succeeded with every coupling kept.
bool fail_disagreeing_neighbours(PiecewiseMap& m, const MeshingError& joint, bool& alone_checked) {
  bool located = false;
  while (!located && !m.members_now().empty()) {
    std::vector<std::pair<std::size_t, std::size_t>> disagree;
    try {
      m.st.quantize = solve_joint(m, m.members_now(), &disagree);
    } catch (const MeshingError&) {
      if (alone_checked) break;
      fail_unquantizable_alone(m);
      alone_checked = true;
      continue;
    }
    located = disagree.empty();
    fail_most_disagreeing(m, std::move(disagree), joint);
  }
  return located;
}

// The first subregion (in order) that makes the program infeasible is found by bisection over the rest,
// so c culprits among n subregions cost about c log n solves, not n.
void fail_by_bisection(PiecewiseMap& m, const MeshingError& joint) {
  auto feasible = [&](const std::vector<std::size_t>& members) {
    try {
      m.st.quantize = solve_joint(m, members);
      return true;
    } catch (const MeshingError&) {
      return false;
    }
  };
  std::vector<std::size_t> kept, rest = m.members_now();
  while (!rest.empty()) {
    std::vector<std::size_t> all = kept;
    all.insert(all.end(), rest.begin(), rest.end());
    if (feasible(all)) {
      kept = std::move(all);
      break;
    }
    std::size_t lo = 0, hi = rest.size() - 1;  // kept + rest[0..hi] is infeasible, kept alone is not
    while (lo < hi) {
      const std::size_t mid = (lo + hi) / 2;
      std::vector<std::size_t> trial = kept;
      trial.insert(trial.end(), rest.begin(), rest.begin() + static_cast<std::ptrdiff_t>(mid) + 1);
      if (feasible(trial)) lo = mid + 1; else hi = mid;
    }
    const std::size_t p = rest[lo];
    m.failure[p] = m.sub_name(p) + ": its sides cannot take the counts its neighbours need (" + joint.what() + ")";
    kept.insert(kept.end(), rest.begin(), rest.begin() + static_cast<std::ptrdiff_t>(lo));
    rest.erase(rest.begin(), rest.begin() + static_cast<std::ptrdiff_t>(lo) + 1);
  }
  if (!kept.empty()) m.st.quantize = solve_joint(m, kept);  // the last solve may have been a failed one
}

// The joint quantization of the mapped subregions; the subregions that make it fail are failed (repaired)
// until it succeeds, then the quantized layouts are checked.
void quantize_jointly(PiecewiseMap& m) {
  try {
    if (!m.members_now().empty()) m.st.quantize = solve_joint(m, m.members_now());
  } catch (const MeshingError& joint) {
    // The search by bisection is the last resort (parity rows or separations that no elastic coupling relaxes).
    bool alone_checked = false;
    if (!fail_disagreeing_neighbours(m, joint, alone_checked) && !m.members_now().empty()) {
      if (!alone_checked) fail_unquantizable_alone(m);
      try {
        if (!m.members_now().empty()) m.st.quantize = solve_joint(m, m.members_now());
      } catch (const MeshingError&) {
        fail_by_bisection(m, joint);
      }
    }
  }
  for (std::size_t p = 0; p < m.n; ++p) m.quantized[p] = m.failure[p].empty();
  for (std::size_t p = 0; p < m.n; ++p)
    if (m.failure[p].empty())
      if (std::string invalid = invalid_poly_square(m.layouts[p], m.sub_name(p)); !invalid.empty())
        m.failure[p] = std::move(invalid);
}

// Every mapped subregion snapped to its quantized layout and its quads extracted (in parallel).
void snap_and_extract(PiecewiseMap& m) {
  const std::size_t n = m.n;
  m.meshes.assign(n, {});
  m.side_nodes.assign(n, 0);
  m.untangled.assign(n, 0);
  for (std::size_t p = 0; p < n; ++p)
    if (m.failure[p].empty()) m.unsnapped[p] = m.mapped[p].x;
  m.each_mapped("snap", [&](std::size_t p) {
    const TriMesh& mesh = m.subs[p].mesh;
    m.untangled[p] = snap_to_layout(mesh, m.mapped[p], m.layouts[p], m.options, m.sub_name(p));
    m.meshes[p] = extract_quads(mesh, mesh.vertices, m.mapped[p].x, m.layouts[p], m.sub_name(p), nullptr, &m.side_nodes[p]);
  }, [&](std::size_t p, ByteWriter& w) {
    put_bytes(w, m.mapped[p], false), put_bytes(w, m.meshes[p]), w.put(m.side_nodes[p]), w.put(m.untangled[p]);
  }, [&](std::size_t p, ByteReader& r) {
    get_bytes(r, m.mapped[p], false), get_bytes(r, m.meshes[p]), r.get(m.side_nodes[p]), r.get(m.untangled[p]);
  });
}

// The element count of a segment of a quantized layout.
long long segment_count(const Layout& layout, const LayoutSegment& s) {
  const auto a = layout.lattice[static_cast<std::size_t>(s.break_a)], b = layout.lattice[static_cast<std::size_t>(s.break_b)];
  return std::llabs(b[0] - a[0]) + std::llabs(b[1] - a[1]);
}

// The input points of segment k of subregion p, in chain order.
std::vector<Vec2> segment_line(const PiecewiseMap& m, std::size_t p, int k) {
  const TriMesh& mesh = m.subs[p].mesh;
  const LayoutSegment& s = m.layouts[p].segments[static_cast<std::size_t>(k)];
  const TriChain& ch = mesh.chains[static_cast<std::size_t>(s.chain)];
  const std::size_t cn = ch.vertices.size();
  std::vector<Vec2> line;
  for (int i = 0; i <= s.count; ++i)
    line.push_back(mesh.vertices[static_cast<std::size_t>(ch.vertices[(static_cast<std::size_t>(s.first) + static_cast<std::size_t>(i)) % cn])]);
  return line;
}

// Every coupled separator whose two sides got different counts: the coarser side's row along it becomes a
// transition row onto the finer side's nodes. A row that cannot be built fails its subregion (repaired as a patch
// after the part is quantized again).
void build_transitions(PiecewiseMap& m) {
  const double tolerance = 1e-6 * m.options.size;
  std::vector<std::vector<std::uint8_t>> in_row(m.n);
  m.st.transition_rows = 0;
  for (const SegmentCoupling& c : m.couplings) {
    if (!c.transition) continue;
    const std::size_t a = c.layout_a, b = c.layout_b;
    if (!m.quantized[a] || !m.quantized[b] || !m.failure[a].empty() || !m.failure[b].empty()) continue;
    const long long na = segment_count(m.layouts[a], m.layouts[a].segments[static_cast<std::size_t>(c.segment_a)]),
                    nb = segment_count(m.layouts[b], m.layouts[b].segments[static_cast<std::size_t>(c.segment_b)]);
    if (na == nb) continue;
    const std::size_t fine = na > nb ? a : b, coarse = na > nb ? b : a;
    const int coarse_segment = na > nb ? c.segment_b : c.segment_a;
    try {
      const std::vector<Vec2> line = segment_line(m, coarse, coarse_segment);
      const QuadMesh& f = m.meshes[fine];
      std::vector<Vec2> top;
      std::vector<NodeKind> kinds;
      for (std::int32_t v : nodes_along(f, m.side_nodes[fine], line, tolerance)) {
        top.push_back(f.nodes[static_cast<std::size_t>(v)]);
        kinds.push_back(f.node_kind.empty() ? NodeKind::interior : f.node_kind[static_cast<std::size_t>(v)]);
      }
      in_row[coarse].resize(m.meshes[coarse].quads.size(), 0);
      replace_with_transition_row(m.meshes[coarse], m.side_nodes[coarse], in_row[coarse], line, top, kinds, tolerance);
      ++m.st.transition_rows;
    } catch (const MeshingError& e) {
      m.failure[coarse] = m.sub_name(coarse) + ": its transition row to subregion " + std::to_string(fine) +
                          " could not be built (" + e.what() + ")";
    }
  }
}

// The mapped subregions back at their deformed positions before the snap, to be quantized and snapped again.
void unsnap(PiecewiseMap& m) {
  for (std::size_t p = 0; p < m.n; ++p)
    if (m.failure[p].empty()) m.mapped[p].x = m.unsnapped[p];
}

// The element count of every quantized interface segment.
void count_interface_sides(PiecewiseMap& m) {
  m.side_count.clear();
  for (std::size_t p = 0; p < m.n; ++p) {
    if (!m.quantized[p]) continue;
    for (const LayoutSegment& s : m.layouts[p].segments) {
      const TriChain& ch = m.subs[p].mesh.chains[static_cast<std::size_t>(s.chain)];
      if (ch.interface < 0) continue;
      m.side_count[m.side_key(p, ch, s.first, s.count)] = segment_count(m.layouts[p], s);
    }
  }
}

// Builds the patch of subregion (or union) `sub`, numbered p, on the nodes of its quantized neighbours.
void build_patch(PiecewiseMap& m, std::size_t p, const Subregion& sub, const std::vector<std::uint8_t>& patch_now,
                 PatchMethod method) {
  const double size = least_size(sub.mesh, m.options);  // graded: the finest of the subregion
  const PatchInput in = patch_input(sub, patch_now, m.side_count, m.chain_ends, size, m.options.size_field.get(),
                                    m.options.layout.corner_threshold_deg, m.sub_name(p));
  PatchOptions po;
  po.size = size;
  po.size_field = m.options.size_field;
  po.method = method;
  try {
    m.meshes[p] = mesh_patch(in, po);
  } catch (const MeshingError&) {
    if (method == PatchMethod::automatic) throw;
    po.method = PatchMethod::automatic;  // the method asked for is a preference: the other may still work
    m.meshes[p] = mesh_patch(in, po);
  }
  m.side_nodes[p] = in.nodes.size();
}

// Repairs: every failed subregion becomes an unstructured patch on the nodes its mapped neighbours made.
void build_patches(PiecewiseMap& m) {
  const std::size_t n = m.n;
  for (std::size_t p = 0; p < n; ++p) m.is_patch[p] = !m.failure[p].empty();
  m.patch_error.assign(n, {});
  std::vector<double> patch_cost(n, 0.0);
  for (std::size_t p = 0; p < n; ++p)
    if (m.is_patch[p] && m.is_root(p)) patch_cost[p] = static_cast<double>(m.patch_area(p).mesh.triangles.size());
  shared_for(m.options.sharing.get(), n, patch_cost, "patches", [&](std::size_t p) {
    if (!m.is_patch[p] || !m.is_root(p)) return;  // a union's members are in its root's
    try {
      const bool matched = std::find(m.options.matched_patches.begin(), m.options.matched_patches.end(),
                                     static_cast<int>(p)) != m.options.matched_patches.end();
      build_patch(m, p, m.patch_area(p), m.is_patch, matched ? PatchMethod::matching : PatchMethod::automatic);
    } catch (const MeshingError& e) {
      m.patch_error[p] = m.sub_name(p) + ": its map failed (" + m.failure[p] + ") and so did its repair: " + e.what();
    }
  }, [&](std::size_t p, ByteWriter& w) { if (patch_cost[p] > 0.0) m.pack_patch(p, w); },
     [&](std::size_t p, ByteReader& r) { if (patch_cost[p] > 0.0) m.unpack_patch(p, r); });
  for (int p : m.options.grown_patches)
    if (p >= 0 && static_cast<std::size_t>(p) < n && m.is_patch[static_cast<std::size_t>(p)] &&
        m.patch_error[static_cast<std::size_t>(p)].empty())
      m.patch_error[static_cast<std::size_t>(p)] = m.sub_name(static_cast<std::size_t>(p)) + ": its patch left a folded or poor quad";
}

// The subregions of `roots` patched now (with the patches so far) under the grouping `trial`; the others
// of a root's group lose their own patch.
std::vector<std::uint8_t> patches_with(const PiecewiseMap& m, const std::vector<std::int32_t>& trial,
                                       const std::set<std::int32_t>& roots) {
  std::vector<std::uint8_t> patch_now(m.n, 0);
  for (std::size_t p = 0; p < m.n; ++p)
    patch_now[static_cast<std::size_t>(trial[p])] |= m.is_patch[p] || roots.count(trial[p]);
  return patch_now;
}

// The members of the groups of `roots` become patches, which their roots' patches hold.
void join_patches(PiecewiseMap& m, const std::vector<std::int32_t>& grouping, const std::set<std::int32_t>& roots) {
  for (std::size_t p = 0; p < m.n; ++p)
    if (roots.count(grouping[p])) {
      m.is_patch[p] = 1;
      m.patch_error[p].clear();
      if (grouping[p] != static_cast<std::int32_t>(p)) {
        m.meshes[p] = {};
        m.side_nodes[p] = 0;
      }
    }
}

// The groups next to group r (by their triangles), smallest first.
std::vector<std::pair<std::size_t, std::int32_t>> neighbour_groups(const PiecewiseMap& m, std::int32_t r) {
  std::map<std::int32_t, std::size_t> neighbours;  // group -> its triangles
  for (std::size_t p = 0; p < m.n; ++p)
    if (m.group[p] == r)
      for (const TriChain& ch : m.subs[p].mesh.chains)
        if (ch.interface >= 0 && m.group[static_cast<std::size_t>(ch.interface)] != r)
          neighbours.emplace(m.group[static_cast<std::size_t>(ch.interface)], 0);
  for (std::size_t p = 0; p < m.n; ++p)
    if (auto it = neighbours.find(m.group[p]); it != neighbours.end()) it->second += m.subs[p].mesh.triangles.size();
  std::vector<std::pair<std::size_t, std::int32_t>> smallest_first;
  for (const auto& [q, size] : neighbours) smallest_first.push_back({size, q});
  std::sort(smallest_first.begin(), smallest_first.end());
  return smallest_first;
}

// The patch of group r built over its union with group q; true when it could be, and the groups are then one.
bool grow_patch_into(PiecewiseMap& m, std::int32_t r, std::int32_t q) {
  const std::int32_t root = std::min(r, q);
  std::vector<std::int32_t> trial = m.group;
  for (std::int32_t& g : trial)
    if (g == r || g == q) g = root;
  const GroupedPartition gp = group_partition(m.tri, m.triangle_part, trial, {root});
  const std::vector<std::uint8_t> patch_now = patches_with(m, trial, {root});
  try {
    build_patch(m, static_cast<std::size_t>(root),
                cut_subregion(m.tri, gp.tp, gp.topology, root, gp.members[static_cast<std::size_t>(root)], m.name),
                patch_now, PatchMethod::automatic);
  } catch (const MeshingError&) {
    return false;
  }
  m.grown_because[static_cast<std::size_t>(root)] = m.patch_error[static_cast<std::size_t>(r)];
  join_patches(m, trial, {root});
  m.group = std::move(trial);
  return true;
}

// A patch that cannot be built (no room for its construction near a narrow neck, an odd count all round)
// takes in its neighbours, mapped or not, and is built again over their union, which gains room and reaches
// ring pieces that can even out its count; the subregions beyond keep their maps and nodes.
// First the least growth: a failed patch takes in one neighbouring group, the smallest that lets it build
// (a union over every neighbour, below, reached 1,400 quads on a coast where one neighbour was enough).
void grow_patches_by_one_neighbour(PiecewiseMap& m) {
  std::set<std::int32_t> failed;
  for (std::size_t p = 0; p < m.n; ++p)
    if (!m.patch_error[p].empty()) failed.insert(m.group[p]);
  for (std::int32_t r : failed) {
    if (std::none_of(m.group.begin(), m.group.end(), [&](std::int32_t g) { return g == r; })) continue;  // taken in
    if (m.patch_error[static_cast<std::size_t>(r)].empty()) continue;
    for (const auto& [size, q] : neighbour_groups(m, r))
      if (grow_patch_into(m, r, q)) break;
  }
}

// The groups whose patches failed (each root remembering why, the first time).
std::set<std::int32_t> failed_patch_groups(PiecewiseMap& m) {
  std::set<std::int32_t> failed;
  for (std::size_t p = 0; p < m.n; ++p)
    if (!m.patch_error[p].empty()) {
      failed.insert(m.group[p]);
      std::string& because = m.grown_because[static_cast<std::size_t>(m.group[p])];
      if (because.empty()) because = m.patch_error[p];
    }
  return failed;
}

// Every failed group absorbs the groups across its boundary (groups meeting through one merge). Returns the
// roots of the groups to patch again: the grown ones and the failed ones.
std::set<std::int32_t> absorb_neighbour_groups(PiecewiseMap& m, const std::set<std::int32_t>& failed) {
  std::vector<std::int32_t> into(m.n);
  for (std::size_t p = 0; p < m.n; ++p) into[p] = static_cast<std::int32_t>(p);
  auto root = [&](std::int32_t p) {
    while (into[static_cast<std::size_t>(p)] != p) p = into[static_cast<std::size_t>(p)];
    return p;
  };
  for (std::size_t p = 0; p < m.n; ++p) {
    if (!failed.count(m.group[p])) continue;
    for (const TriChain& ch : m.subs[p].mesh.chains)
      if (ch.interface >= 0) {
        const std::int32_t a = root(m.group[p]), b = root(m.group[static_cast<std::size_t>(ch.interface)]);
        if (a != b) into[static_cast<std::size_t>(std::max(a, b))] = std::min(a, b);
      }
  }
  std::set<std::int32_t> rebuilt;
  for (std::size_t p = 0; p < m.n; ++p) {
    const std::int32_t r = root(m.group[p]);
    if (r != m.group[p] || failed.count(r)) rebuilt.insert(r);
    m.group[p] = r;
  }
  return rebuilt;
}

// Failed patches grow over all their neighbours at once, up to options.patch_growth times.
void grow_patches_over_neighbours(PiecewiseMap& m) {
  for (int grow = 0; grow < m.options.patch_growth; ++grow) {
    const std::set<std::int32_t> failed = failed_patch_groups(m);
    if (failed.empty()) break;
    const std::set<std::int32_t> rebuilt = absorb_neighbour_groups(m, failed);
    const GroupedPartition gp = group_partition(m.tri, m.triangle_part, m.group, rebuilt);
    const std::vector<std::uint8_t> patch_now = patches_with(m, m.group, rebuilt);
    join_patches(m, m.group, rebuilt);
    const std::vector<std::int32_t> roots(rebuilt.begin(), rebuilt.end());
    std::vector<double> root_cost(roots.size(), 0.0);
    for (std::size_t k = 0; k < roots.size(); ++k) root_cost[k] = static_cast<double>(gp.members[static_cast<std::size_t>(roots[k])].size());
    shared_for(m.options.sharing.get(), roots.size(), root_cost, "grown patches", [&](std::size_t k) {
      const auto r = static_cast<std::size_t>(roots[k]);
      try {
        build_patch(m, r, cut_subregion(m.tri, gp.tp, gp.topology, roots[k], gp.members[r], m.name), patch_now,
                    PatchMethod::automatic);
      } catch (const MeshingError& e) {
        m.patch_error[r] = m.sub_name(r) + ": its repair failed even over its neighbours' area too (" +
                           std::to_string(grow + 1) + " times): " + e.what();
      }
    }, [&](std::size_t k, ByteWriter& w) { m.pack_patch(static_cast<std::size_t>(roots[k]), w); },
       [&](std::size_t k, ByteReader& rd) { m.unpack_patch(static_cast<std::size_t>(roots[k]), rd); });
  }
}

// Patches for the failed subregions, grown where they cannot be built; counts the failed maps and repairs.
void repair_failed_subregions(PiecewiseMap& m) {
  count_interface_sides(m);
  build_patches(m);
  if (m.options.patch_growth > 0) grow_patches_by_one_neighbour(m);
  grow_patches_over_neighbours(m);
  m.failed_maps = m.failed_repairs = 0;
  for (std::size_t p = 0; p < m.n; ++p) {
    m.failed_maps += m.is_patch[p];
    m.failed_repairs += !m.patch_error[p].empty();
  }
}

// Patches grown over their neighbours whose counts, quantized for the smaller patches, did not add up: the
// unions of the last growth are patched from the start. False when there are none.
bool patch_unions_from_start(PiecewiseMap& m) {
  std::set<std::int32_t> roots;
  for (std::size_t p = 0; p < m.n; ++p)
    if (!m.is_root(p)) roots.insert(m.group[p]);
  if (roots.empty()) return false;
  const GroupedPartition gp = group_partition(m.tri, m.triangle_part, m.group, roots);
  for (std::int32_t r : roots) {
    try {
      m.union_sub[static_cast<std::size_t>(r)] =
          cut_subregion(m.tri, gp.tp, gp.topology, r, gp.members[static_cast<std::size_t>(r)], m.name);
    } catch (const MeshingError&) {  // not one simple loop: its members are patched one by one
      for (std::size_t p = 0; p < m.n; ++p)
        if (m.group[p] == r) m.group[p] = static_cast<std::int32_t>(p);
      continue;
    }
    for (std::size_t p = 0; p < m.n; ++p)
      if (m.group[p] == r && m.failure[p].empty())
        m.failure[p] = m.sub_name(p) + ": meshed in a patch with its neighbours (their patch could not be built alone)";
  }
  return true;
}

// Quantization, snap and patches, repeated when a later stage shows the quantization was made for other
// patches: a subregion whose snap fails after quantization (at most twice), and once, patches that could only
// be built over their grown neighbours' area (their unions are then patched from the start). Either way the
// part is quantized again with them among the patches, whose neighbours' counts are then made even where the
// patch needs it (patch_runs); the subregions' maps are kept, only their snap is redone.
void quantize_snap_and_patch(PiecewiseMap& m) {
  const std::size_t n = m.n;
  m.quantized.assign(n, 0);
  m.is_patch.assign(n, 0);
  m.patch_error.resize(n);
  m.grown_because.resize(n);
  m.meshes.resize(n);
  m.side_nodes.assign(n, 0);
  m.untangled.assign(n, 0);
  m.unsnapped.resize(n);
  for (int requantized = 0, unions = 0;;) {
    auto t0 = std::chrono::steady_clock::now();
    quantize_jointly(m);
    m.seconds_quantize += seconds_since(t0);

    t0 = std::chrono::steady_clock::now();
    snap_and_extract(m);
    build_transitions(m);
    m.seconds_snap += seconds_since(t0);
    std::size_t late = 0;  // quantized, then failed
    for (std::size_t p = 0; p < n; ++p) late += m.quantized[p] && !m.failure[p].empty();
    if (late > 0 && requantized++ < 2) {
      unsnap(m);
      continue;
    }

    t0 = std::chrono::steady_clock::now();
    repair_failed_subregions(m);
    m.seconds_patches += seconds_since(t0);
    if (m.failed_repairs == 0 || unions++ > 0) break;
    if (!patch_unions_from_start(m)) break;
    unsnap(m);
  }
}

// The figures of every subregion: mapped or patched, why, its quads.
void report_subregions(PiecewiseMap& m) {
  PartMapStats& st = m.st;
  st.subregions.assign(m.n, {});
  st.failed_maps.clear();
  const std::vector<int>& requested = m.options.patch_subregions;
  for (std::size_t p = 0; p < m.n; ++p)
    if (!m.failure[p].empty() && m.is_root(p) &&
        std::find(requested.begin(), requested.end(), static_cast<int>(p)) == requested.end())
      st.failed_maps.push_back({static_cast<int>(p), static_cast<int>(m.layouts[p].segments.size())});
  for (std::size_t p = 0; p < m.n; ++p) {
    SubregionStats& s = st.subregions[p];
    s.subregion = static_cast<int>(p);
    s.mapped = !m.is_patch[p];
    s.untangled = s.mapped && m.untangled[p];
    s.reason = !m.failure[p].empty() ? m.failure[p]
               : m.is_patch[p]       ? m.sub_name(p) + ": its neighbour's patch could not be built without it"
                                     : std::string();
    if (!m.is_root(p)) s.reason += " (meshed in the patch of subregion " + std::to_string(m.group[p]) + ")";
    else if (m.is_patch[p] && !m.grown_because[p].empty())
      s.reason += "; its patch grew over its neighbours because " + m.grown_because[p];
    s.quads = m.meshes[p].quads.size();
    s.at = m.subs[p].mesh.vertices.empty() ? Vec2{} : m.subs[p].mesh.vertices.front();
  }
}

}  // namespace

QuadMesh map_piecewise(const TriMesh& tri, const std::vector<std::int32_t>& triangle_part, int parts,
                       const PolysquareMapOptions& options, const std::string& name, PartMapStats& st) {
  auto t0 = std::chrono::steady_clock::now();
  PiecewiseMap m(tri, triangle_part, parts, options, name, st);
  cut_subregions(m);
  deform_and_label(m);
  st.seconds_deform = seconds_since(t0);
  add_deform_stats(m);
  for (bool again = true; again;) again = !pair_interface_sides(m) || fail_convex_on_both_sides(m);
  allow_transitions(m);
  quantize_snap_and_patch(m);
  st.seconds_quantize = m.seconds_quantize;
  st.seconds_snap = m.seconds_snap;
  t0 = std::chrono::steady_clock::now();
  for (const std::string& e : m.patch_error)
    if (!e.empty())
      throw MeshingError(e + " [" + std::to_string(m.failed_repairs) + " of " + std::to_string(m.failed_maps) +
                         " repairs failed; " + std::to_string(m.failed_maps) + " of " + std::to_string(m.n) +
                         " subregions did not map]");
  QuadMesh out = stitch_quad_meshes(m.meshes, m.side_nodes, 1e-6 * options.size);
  st.seconds_extract = m.seconds_patches + seconds_since(t0);
  st.separators = m.couplings.size();
  report_subregions(m);
  return out;
}

}  // namespace polysquare
