#include "polysquare/refine/local_patch.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <span>
#include <unordered_map>
#include <unordered_set>

#include <oneapi/tbb/enumerable_thread_specific.h>
#include <oneapi/tbb/parallel_for.h>

#include "polysquare/core/error.h"
#include "polysquare/core/quad_topology.h"
#include "polysquare/fallback/patch.h"

namespace polysquare {
namespace {

double worst_corner(const QuadMesh& m) {
  double worst = 1.0;
  for (const auto& q : m.quads)
    worst = std::min(worst, quad_min_sj(m.nodes[q[0]], m.nodes[q[1]], m.nodes[q[2]], m.nodes[q[3]]));
  return worst;
}

// A region of quads that can be meshed again: simple boundary loops (the outer one counter-clockwise, holes
// clockwise, the region on their left), no feature edge inside, every interior node of kind interior.
struct QuadRegion {
  std::vector<std::int32_t> quads;
  std::vector<std::int32_t> loop;        // boundary nodes in order, loop after loop
  std::vector<std::size_t> loop_sizes;   // nodes of each loop, the outer one first
  std::vector<std::int32_t> interior;    // nodes of the region not on its loops nor given inside it
  // With inner features: the feature curves inside the region (node chains between anchors, or cycles) and
  // other nodes that must stay; `given` is every node the patch keeps, in the patch input's order.
  std::vector<std::vector<std::int32_t>> inner_curves;
  std::vector<std::uint8_t> inner_closed;
  std::vector<std::int32_t> points;
  std::vector<std::int32_t> given;
};

class Cutter {
 public:
  // Quads are found across edges through the quads at each node (compressed), not a hash map of every edge: at
  // millions of quads that map's nodes were most of a local-patch pass (three passes a round).
  explicit Cutter(const QuadMesh& m) : m_(m), node_quads_(node_quads(m)) {
    for (std::size_t e = 0; e < m.feature_edges.size(); ++e)
      feature_[edge_key(m.feature_edges[e][0], m.feature_edges[e][1])] = m.feature_edge_curve[e];
    for (std::size_t e = 0; e < m.boundary_edges.size(); ++e)
      boundary_[edge_key(m.boundary_edges[e][0], m.boundary_edges[e][1])] = m.boundary_edge_ring[e];
  }

  // The quad across edge i of quad q, or -1.
  std::int32_t neighbour(std::int32_t q, int i) const {
    const std::int32_t a = m_.quads[q][i], b = m_.quads[q][(i + 1) % 4];
    for (const std::int32_t n : quads_at(a)) {
      if (n == q) continue;
      const auto& x = m_.quads[static_cast<std::size_t>(n)];
      for (int j = 0; j < 4; ++j)
        if (x[j] == b && (x[(j + 1) % 4] == a || x[(j + 3) % 4] == a)) return n;
    }
    return -1;
  }
  bool feature_edge(std::int32_t a, std::int32_t b) const { return feature_.count(edge_key(a, b)) > 0; }
  std::span<const std::int32_t> quads_at(std::int32_t v) const {
    const auto at = static_cast<std::size_t>(v);
    return {node_quads_.quads.data() + node_quads_.offset[at], node_quads_.offset[at + 1] - node_quads_.offset[at]};
  }

  // Grows `in` by one ring of edge neighbours (not across feature edges, not into `blocked`), then fills quads
  // with two or more edges on the region (notches that would pinch its loop).
  void grow(std::vector<std::uint8_t>& in, std::vector<std::int32_t>& quads, const std::vector<std::uint8_t>& blocked) const {
    const std::size_t before = quads.size();
    for (std::size_t k = 0; k < before; ++k)
      for (int i = 0; i < 4; ++i) {
        const std::int32_t q = quads[k], n = neighbour(q, i);
        if (n < 0 || in[n] || blocked[n] || feature_edge(m_.quads[q][i], m_.quads[q][(i + 1) % 4])) continue;
        in[n] = 1;
        quads.push_back(n);
      }
    for (bool again = true; again;) {
      again = false;
      for (std::size_t k = 0; k < quads.size(); ++k)
        for (int i = 0; i < 4; ++i) {
          const std::int32_t n = neighbour(quads[k], i);
          if (n < 0 || in[n] || blocked[n]) continue;
          int sides = 0;
          for (int j = 0; j < 4; ++j) {
            const std::int32_t o = neighbour(n, j);
            sides += o >= 0 && in[o] && !feature_edge(m_.quads[n][j], m_.quads[n][(j + 1) % 4]);
          }
          if (sides < 2) continue;
          in[n] = 1;
          quads.push_back(n);
          again = true;
        }
    }
  }

  // The region of `quads` when it is a disk with one simple loop (with `holes`, a connected region with any
  // number of holes) and nothing tagged inside (with `inner_features`, feature curves and feature points inside
  // are kept as curves and points of the patch).
  bool cut(const std::vector<std::int32_t>& quads, const std::vector<std::uint8_t>& in, bool holes, bool inner_features,
           QuadRegion& r) const {
    RegionEdges edges;
    if (!region_edges(quads, in, inner_features, edges)) return false;
    r = QuadRegion{};
    r.quads = quads;
    std::vector<std::vector<std::int32_t>> loops;
    if (!boundary_loops(edges.next, holes, loops)) return false;
    for (const auto& l : loops) {
      r.loop.insert(r.loop.end(), l.begin(), l.end());
      r.loop_sizes.push_back(l.size());
    }
    r.given = r.loop;
    if (!edges.inner.empty()) inner_feature_curves(edges.next, edges.inner, r);
    std::unordered_set<std::int32_t> given(r.given.begin(), r.given.end());
    for (const auto& c : r.inner_curves)
      for (std::int32_t v : c)
        if (given.insert(v).second) r.given.push_back(v);
    std::vector<std::int32_t> inside;
    for (std::int32_t v : edges.nodes)
      if (!given.count(v)) inside.push_back(v);
    std::sort(inside.begin(), inside.end());
    for (std::int32_t v : inside) {
      if (!m_.node_kind.empty() && m_.node_kind[static_cast<std::size_t>(v)] != NodeKind::interior) {
        if (!inner_features) return false;
        r.points.push_back(v);  // a feature point: it stays a node
        r.given.push_back(v);
        continue;
      }
      r.interior.push_back(v);
    }
    return true;
  }

  PatchInput patch_input(const QuadRegion& r) const {
    PatchInput in;
    std::size_t first = 0;
    for (const std::size_t n : r.loop_sizes) {
      PatchCurve c;
      c.closed = c.loop = true;
      for (std::size_t i = 0; i < n; ++i) {
        const std::int32_t a = r.loop[first + i], b = r.loop[first + (i + 1) % n];
        in.nodes.push_back(m_.nodes[static_cast<std::size_t>(a)]);
        in.kind.push_back(m_.node_kind.empty() ? NodeKind::interior : m_.node_kind[static_cast<std::size_t>(a)]);
        c.nodes.push_back(static_cast<std::int32_t>(first + i));
        const auto key = edge_key(a, b);
        if (auto it = boundary_.find(key); it != boundary_.end()) {
          c.role.push_back(PatchEdgeRole::boundary);
          c.tag.push_back(it->second);
        } else if (auto f = feature_.find(key); f != feature_.end()) {
          c.role.push_back(PatchEdgeRole::feature);
          c.tag.push_back(f->second);
        } else {
          c.role.push_back(PatchEdgeRole::none);
          c.tag.push_back(-1);
        }
      }
      first += n;
      in.curves.push_back(std::move(c));
    }
    // Inner feature curves and points, on the given nodes after the loops' (r.given's order).
    std::unordered_map<std::int32_t, std::int32_t> at;
    for (std::size_t i = 0; i < r.given.size(); ++i) at.emplace(r.given[i], static_cast<std::int32_t>(i));
    for (std::size_t i = r.loop.size(); i < r.given.size(); ++i) {
      const auto v = static_cast<std::size_t>(r.given[i]);
      in.nodes.push_back(m_.nodes[v]);
      in.kind.push_back(m_.node_kind.empty() ? NodeKind::feature : m_.node_kind[v]);
    }
    for (std::size_t k = 0; k < r.inner_curves.size(); ++k) {
      const auto& chain = r.inner_curves[k];
      PatchCurve c;
      c.closed = r.inner_closed[k] != 0;
      const std::size_t edges = c.closed ? chain.size() : chain.size() - 1;
      for (std::int32_t v : chain) c.nodes.push_back(at.at(v));
      for (std::size_t i = 0; i < edges; ++i) {
        c.role.push_back(PatchEdgeRole::feature);
        c.tag.push_back(feature_.at(edge_key(chain[i], chain[(i + 1) % chain.size()])));
      }
      in.curves.push_back(std::move(c));
    }
    for (std::int32_t v : r.points) in.points.push_back(at.at(v));
    return in;
  }

 private:
  // The edges of a region of quads: each boundary node's edge out (the region on its left), the region's nodes
  // and the feature edges inside it.
  struct RegionEdges {
    std::unordered_map<std::int32_t, std::int32_t> next;
    std::unordered_set<std::int32_t> nodes;
    std::vector<std::uint64_t> inner;  // feature edges inside the region, each once
  };

  // False when the region touches itself at a node, has no boundary, or (without `inner_features`) a feature edge
  // inside.
  bool region_edges(const std::vector<std::int32_t>& quads, const std::vector<std::uint8_t>& in, bool inner_features,
                    RegionEdges& e) const {
    for (std::int32_t q : quads)
      for (int i = 0; i < 4; ++i) {
        const std::int32_t a = m_.quads[q][i], b = m_.quads[q][(i + 1) % 4], n = neighbour(q, i);
        e.nodes.insert(a);
        if (n >= 0 && in[n]) {
          if (feature_edge(a, b)) {
            if (!inner_features) return false;  // a feature would be lost inside the patch
            if (q < n) e.inner.push_back(edge_key(a, b));
          }
          continue;
        }
        if (!e.next.try_emplace(a, b).second) return false;  // the region touches itself at a
      }
    return !e.next.empty();
  }

  // The boundary loops, the outer one first; false on a pinch, on more than one loop without `holes`, or when the
  // loops do not bound one connected region.
  bool boundary_loops(const std::unordered_map<std::int32_t, std::int32_t>& next, bool holes,
                      std::vector<std::vector<std::int32_t>>& loops) const {
    // Every boundary node has one edge out; the loops, each from its smallest node, in order of that node.
    std::vector<std::int32_t> starts;
    for (const auto& [a, b] : next) starts.push_back(a);
    std::sort(starts.begin(), starts.end());
    std::unordered_set<std::int32_t> visited;
    for (std::int32_t start : starts) {
      if (visited.count(start)) continue;
      std::vector<std::int32_t> loop;
      for (std::int32_t v = start;;) {
        if (!visited.insert(v).second) return false;  // two edges into v: a pinch
        loop.push_back(v);
        v = next.at(v);
        if (v == start) break;
      }
      loops.push_back(std::move(loop));
    }
    if (loops.size() > 1 && !holes) return false;  // more than one loop: a hole
    // One counter-clockwise loop (the outer one), the others clockwise: a connected region.
    std::size_t outer = loops.size() == 1 ? 0 : loops.size();
    for (std::size_t k = 0; k < loops.size() && loops.size() > 1; ++k) {
      std::vector<Vec2> ring;
      for (std::int32_t v : loops[k]) ring.push_back(m_.nodes[static_cast<std::size_t>(v)]);
      if (ring_signed_area(ring) <= 0.0) continue;
      if (outer != loops.size()) return false;
      outer = k;
    }
    if (outer == loops.size()) return false;
    std::rotate(loops.begin(), loops.begin() + static_cast<std::ptrdiff_t>(outer), loops.begin() + static_cast<std::ptrdiff_t>(outer) + 1);
    return true;
  }

  // The inner feature edges as curves of r: chains from every anchor (a loop node, or a node with other than two
  // inner feature edges), then cycles.
  static void inner_feature_curves(const std::unordered_map<std::int32_t, std::int32_t>& next,
                                   std::vector<std::uint64_t>& inner, QuadRegion& r) {
    std::unordered_map<std::int32_t, std::vector<std::int32_t>> along;  // node -> its inner feature neighbours
    std::sort(inner.begin(), inner.end());
    for (const std::uint64_t key : inner) {
      const auto a = static_cast<std::int32_t>(key >> 32), b = static_cast<std::int32_t>(key & 0xffffffffu);
      along[a].push_back(b);
      along[b].push_back(a);
    }
    std::vector<std::int32_t> anchors, ends;
    for (const auto& [v, nb] : along) ends.push_back(v);
    std::sort(ends.begin(), ends.end());
    for (std::int32_t v : ends)
      if (next.count(v) || along.at(v).size() != 2) anchors.push_back(v);
    std::unordered_set<std::uint64_t> walked;
    auto walk = [&](std::int32_t from, std::int32_t to) {
      std::vector<std::int32_t> chain{from};
      for (std::int32_t prev = from, v = to;;) {
        walked.insert(edge_key(prev, v));
        chain.push_back(v);
        if (v == from || next.count(v) || along.at(v).size() != 2) break;
        const std::int32_t w = along.at(v)[0] == prev ? along.at(v)[1] : along.at(v)[0];
        prev = v;
        v = w;
      }
      return chain;
    };
    for (std::int32_t a : anchors)
      for (std::int32_t b : along.at(a))
        if (!walked.count(edge_key(a, b))) {
          r.inner_curves.push_back(walk(a, b));
          r.inner_closed.push_back(0);
        }
    for (std::int32_t a : ends)
      for (std::int32_t b : along.at(a))
        if (!walked.count(edge_key(a, b))) {
          std::vector<std::int32_t> cycle = walk(a, b);
          cycle.pop_back();  // back at a
          r.inner_curves.push_back(std::move(cycle));
          r.inner_closed.push_back(1);
        }
  }

  const QuadMesh& m_;
  NodeQuads node_quads_;
  std::unordered_map<std::uint64_t, std::int32_t> feature_, boundary_;
};

// The better of the two patch constructions on `in`, or nothing when neither builds without a folded quad.
bool best_patch(const PatchInput& in, const LocalPatchOptions& options, QuadMesh& out) {
  double best = 0.0;
  bool found = false;
  for (PatchMethod method : {PatchMethod::split, PatchMethod::matching}) {
    PatchOptions po;
    po.size = options.size;
    po.size_field = options.size_field;
    po.method = method;
    try {
      QuadMesh p = mesh_patch(in, po);
      const double w = worst_corner(p);
      if (w > best) {
        best = w;
        out = std::move(p);
        found = true;
      }
    } catch (const MeshingError&) {
    }
  }
  return found;
}

// A cluster's region and the patch that replaces it, its quads named after subregion `part`.
struct RegionPatch {
  QuadRegion region;
  QuadMesh patch;
  std::int32_t part = 0;
};

// What a cluster search reads: the mesh and its cutter, the flags of the quads (2 = to be mended only), the options.
struct ClusterSearch {
  const QuadMesh& mesh;
  const Cutter& cutter;
  const std::vector<std::uint8_t>& poor;
  const LocalPatchOptions& options;
};

// The subregion that held most of the region names the patch quads.
std::int32_t majority_part(const QuadMesh& mesh, const std::vector<std::int32_t>& quads) {
  std::map<std::int32_t, std::size_t> votes;
  for (std::int32_t q : quads) votes[mesh.quad_part.empty() ? 0 : mesh.quad_part[static_cast<std::size_t>(q)]]++;
  return std::max_element(votes.begin(), votes.end(), [](const auto& a, const auto& b) {
           return a.second < b.second;
         })->first;
}

// The best patch of a cluster's region grown around it, not into quads `used` by the patches of clusters before
// it; `reached` receives the quads of the largest region tried. `in` (#quads, all 0) is scratch, left all 0:
// one per thread, not one per cluster (thousands of clusters on a mesh of millions of quads).
std::optional<RegionPatch> search_cluster(const ClusterSearch& cs, const std::vector<std::int32_t>& cluster,
                                          const std::vector<std::uint8_t>& used, std::vector<std::uint8_t>& in,
                                          std::vector<std::int32_t>& reached) {
  const QuadMesh& mesh = cs.mesh;
  const LocalPatchOptions& options = cs.options;
  std::optional<RegionPatch> best;
  std::vector<std::int32_t> quads;
  for (std::int32_t q : cluster)
    if (!used[q]) {
      in[q] = 1;
      quads.push_back(q);
    }
  reached = quads;
  if (quads.empty()) return best;  // already inside another cluster's region
  // A cluster of valid quads flagged only to be mended (2) is replaced only by a patch whose worst corner
  // beats theirs: a patch always costs singular nodes.
  bool mend_only = true;
  double cluster_worst = 1.0;
  for (std::int32_t q : quads) {
    mend_only = mend_only && cs.poor[static_cast<std::size_t>(q)] == 2;
    const auto& c = mesh.quads[static_cast<std::size_t>(q)];
    cluster_worst = std::min(cluster_worst, quad_min_sj(mesh.nodes[c[0]], mesh.nodes[c[1]], mesh.nodes[c[2]], mesh.nodes[c[3]]));
  }
  // Rings are added until a patch builds whose worst corner reaches the target; the best one seen is kept.
  double best_worst = mend_only ? cluster_worst : 0.0;
  for (int ring = std::max(options.min_rings, 0); ring <= options.max_rings; ++ring) {
    if (ring > 0) cs.cutter.grow(in, quads, used);
    reached = quads;
    if (quads.size() > options.max_quads) break;
    QuadRegion r;
    if (!cs.cutter.cut(quads, in, options.holes, options.inner_features, r)) continue;
    QuadMesh patch;
    if (!best_patch(cs.cutter.patch_input(r), options, patch)) continue;
    const double worst = worst_corner(patch);
    if ((best || mend_only) && worst <= best_worst) continue;
    const std::int32_t part = majority_part(mesh, r.quads);
    best = RegionPatch{std::move(r), std::move(patch), part};
    best_worst = worst;
    if (worst >= options.target_sj) break;
  }
  for (std::int32_t q : reached) in[q] = 0;
  return best;
}

// The patches of the clusters, in cluster order, each region clear of the earlier ones; `used` flags their quads.
// Each cluster is searched on its own, in parallel, as if no patch were made before it; then, in cluster
// order, a search that never reached a quad used by an earlier cluster's patch is the one the sequence would
// have made (growth is only ever blocked by used quads), and the others are searched again with the quads used
// so far: the result does not depend on the thread count.
std::vector<RegionPatch> cluster_patches(const ClusterSearch& cs, const std::vector<std::vector<std::int32_t>>& clusters,
                                         std::vector<std::uint8_t>& used) {
  const std::size_t nq = cs.mesh.quads.size();
  const std::vector<std::uint8_t> none(nq, 0);
  std::vector<std::optional<RegionPatch>> alone(clusters.size());
  std::vector<std::vector<std::int32_t>> reached(clusters.size());  // each holds its cluster
  oneapi::tbb::enumerable_thread_specific<std::vector<std::uint8_t>> scratch([nq] { return std::vector<std::uint8_t>(nq, 0); });
  oneapi::tbb::parallel_for(std::size_t{0}, clusters.size(), [&](std::size_t c) {
    alone[c] = search_cluster(cs, clusters[c], none, scratch.local(), reached[c]);
  });
  used.assign(nq, 0);
  std::vector<RegionPatch> done;
  std::vector<std::int32_t> again;
  for (std::size_t c = 0; c < clusters.size(); ++c) {
    const bool clear = std::none_of(reached[c].begin(), reached[c].end(), [&](std::int32_t q) { return used[q] != 0; });
    std::optional<RegionPatch> best = clear ? std::move(alone[c]) : search_cluster(cs, clusters[c], used, scratch.local(), again);
    if (best) {
      for (std::int32_t q : best->region.quads) used[q] = 1;
      done.push_back(std::move(*best));
    }
  }
  return done;
}

// The mesh with the `used` quads replaced by the patches: nodes inside the regions go, patch interior nodes come
// at the end; tagged edges keep their nodes. `unstructured` follows the quads (1 on patch quads).
void replace_by_patches(QuadMesh& mesh, const std::vector<RegionPatch>& done, const std::vector<std::uint8_t>& used,
                        std::vector<std::uint8_t>& unstructured, LocalPatchStats& st) {
  const std::size_t nq = mesh.quads.size();
  std::vector<std::uint8_t> drop(mesh.nodes.size(), 0);
  for (const RegionPatch& d : done)
    for (std::int32_t v : d.region.interior) drop[static_cast<std::size_t>(v)] = 1;
  std::vector<std::int32_t> index(mesh.nodes.size(), -1);
  QuadMesh out;
  out.crs = mesh.crs;
  out.units = mesh.units;
  const bool kinds = !mesh.node_kind.empty();
  for (std::size_t v = 0; v < mesh.nodes.size(); ++v) {
    if (drop[v]) continue;
    index[v] = static_cast<std::int32_t>(out.nodes.size());
    out.nodes.push_back(mesh.nodes[v]);
    if (kinds) out.node_kind.push_back(mesh.node_kind[v]);
  }
  std::vector<std::uint8_t> flags;
  const bool parts = !mesh.quad_part.empty();
  for (std::size_t q = 0; q < nq; ++q) {
    if (used[q]) continue;
    const auto& quad = mesh.quads[q];
    out.quads.push_back({index[quad[0]], index[quad[1]], index[quad[2]], index[quad[3]]});
    if (parts) out.quad_part.push_back(mesh.quad_part[q]);
    flags.push_back(unstructured[q]);
  }
  for (const RegionPatch& d : done) {
    const std::size_t given = d.region.given.size();
    std::vector<std::int32_t> map(d.patch.nodes.size());
    for (std::size_t i = 0; i < d.patch.nodes.size(); ++i) {
      if (i < given) {
        map[i] = index[d.region.given[i]];
        continue;
      }
      map[i] = static_cast<std::int32_t>(out.nodes.size());
      out.nodes.push_back(d.patch.nodes[i]);
      if (kinds) out.node_kind.push_back(NodeKind::interior);
    }
    for (const auto& quad : d.patch.quads) {
      out.quads.push_back({map[quad[0]], map[quad[1]], map[quad[2]], map[quad[3]]});
      if (parts) out.quad_part.push_back(d.part);
      flags.push_back(1);
    }
    st.quads_removed += d.region.quads.size();
    st.quads_added += d.patch.quads.size();
    ++st.patched;
  }
  for (std::size_t e = 0; e < mesh.boundary_edges.size(); ++e) {
    out.boundary_edges.push_back({index[mesh.boundary_edges[e][0]], index[mesh.boundary_edges[e][1]]});
    out.boundary_edge_ring.push_back(mesh.boundary_edge_ring[e]);
  }
  for (std::size_t e = 0; e < mesh.feature_edges.size(); ++e) {
    out.feature_edges.push_back({index[mesh.feature_edges[e][0]], index[mesh.feature_edges[e][1]]});
    out.feature_edge_curve.push_back(mesh.feature_edge_curve[e]);
  }
  out.triangles = mesh.triangles;
  mesh = std::move(out);
  unstructured = std::move(flags);
}

// Meshes again the region around each of `clusters` (quads; `poor` flags them, 2 = to be mended only), in order.
LocalPatchStats remesh_clusters(QuadMesh& mesh, const Cutter& cutter, const std::vector<std::vector<std::int32_t>>& clusters,
                                const std::vector<std::uint8_t>& poor, const LocalPatchOptions& options,
                                std::vector<std::uint8_t>& unstructured) {
  LocalPatchStats st;
  const std::size_t nq = mesh.quads.size();
  if (unstructured.size() != nq) unstructured.assign(nq, 0);
  st.clusters = clusters.size();
  std::vector<std::uint8_t> used;
  const std::vector<RegionPatch> done = cluster_patches({mesh, cutter, poor, options}, clusters, used);
  if (done.empty()) return st;
  replace_by_patches(mesh, done, used, unstructured, st);
  return st;
}

}  // namespace

LocalPatchStats remesh_poor_quads(QuadMesh& mesh, const std::vector<std::uint8_t>& poor, const LocalPatchOptions& options,
                                  std::vector<std::uint8_t>& unstructured) {
  const std::size_t nq = mesh.quads.size();
  const Cutter cutter(mesh);
  std::vector<std::uint8_t> seen(nq, 0);
  // The clusters: flagged quads sharing a node, in quad order (poor quads and quads only to be mended apart).
  std::vector<std::vector<std::int32_t>> clusters;
  for (std::size_t q0 = 0; q0 < nq; ++q0) {
    if (!poor[q0] || seen[q0]) continue;
    std::vector<std::int32_t> cluster{static_cast<std::int32_t>(q0)};
    seen[q0] = 1;
    for (std::size_t k = 0; k < cluster.size(); ++k)
      for (std::int32_t v : mesh.quads[cluster[k]])
        for (std::int32_t n : cutter.quads_at(v))
          if (poor[n] == poor[q0] && !seen[n]) {
            seen[n] = 1;
            cluster.push_back(n);
          }
    clusters.push_back(std::move(cluster));
  }
  return remesh_clusters(mesh, cutter, clusters, poor, options, unstructured);
}

LocalPatchStats remesh_regions(QuadMesh& mesh, const std::vector<std::int32_t>& region, const LocalPatchOptions& options,
                               std::vector<std::uint8_t>& unstructured) {
  const Cutter cutter(mesh);
  std::map<std::int32_t, std::vector<std::int32_t>> by_id;
  std::vector<std::uint8_t> flagged(mesh.quads.size(), 0);
  for (std::size_t q = 0; q < region.size() && q < mesh.quads.size(); ++q)
    if (region[q] >= 0) {
      by_id[region[q]].push_back(static_cast<std::int32_t>(q));
      flagged[q] = 1;
    }
  std::vector<std::vector<std::int32_t>> clusters;
  for (auto& [id, quads] : by_id) clusters.push_back(std::move(quads));
  return remesh_clusters(mesh, cutter, clusters, flagged, options, unstructured);
}

}  // namespace polysquare
