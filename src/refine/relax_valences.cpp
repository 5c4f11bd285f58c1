#include "polysquare/refine/relax_valences.h"

#include <oneapi/tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <unordered_map>
#include <unordered_set>

#include "fallback/patch_valence.h"
#include "polysquare/core/geometry.h"

namespace polysquare {
namespace {

// What the moves made of one connected piece of the region.
struct Piece {
  RelaxValencesStats stats;
  std::vector<std::array<std::int32_t, 4>> quads;  // the new quads, by the mesh's node indices
  std::vector<std::size_t> slot;                   // the quad each new one replaces (its per-quad data)
  std::vector<std::pair<std::int32_t, Vec2>> moved;  // free nodes' new positions
};

// The figures of the whole mesh the pieces need: quads at each node and their angle there, and the boundary and
// feature edges (never turned).
struct NodeTotals {
  std::vector<int> quads;
  std::vector<double> angle;
  std::unordered_set<std::uint64_t> curve_edges;
};

// The piece as a mesh of its own: fixed nodes first, then the free ones (all their quads in the piece, and
// neither on the boundary nor on a feature); quad_part holds the index of the quad in the mesh.
struct LocalPiece {
  QuadMesh local;
  std::vector<std::int32_t> to_global;             // local node -> mesh node
  std::vector<double> targets;                     // the fixed nodes' valence targets
  std::vector<std::array<std::int32_t, 2>> kept;   // boundary and feature edges, in local nodes
  std::size_t fixed = 0;                           // the fixed nodes: the first `fixed` local nodes
};

LocalPiece local_piece(const QuadMesh& mesh, const std::vector<std::size_t>& quads, const NodeTotals& totals) {
  std::unordered_map<std::int32_t, int> inside;
  std::vector<std::int32_t> order;
  for (std::size_t q : quads)
    for (std::int32_t v : mesh.quads[q])
      if (inside[v]++ == 0) order.push_back(v);
  std::sort(order.begin(), order.end());
  auto is_free = [&](std::int32_t v) {
    const auto u = static_cast<std::size_t>(v);
    return inside.at(v) == totals.quads[u] && (mesh.node_kind.empty() || mesh.node_kind[u] == NodeKind::interior);
  };
  const double right = std::acos(0.0);
  LocalPiece lp;
  std::unordered_map<std::int32_t, std::int32_t> to_local;
  for (int pass = 0; pass < 2; ++pass)
    for (std::int32_t v : order) {
      if (is_free(v) != (pass == 1)) continue;
      const auto u = static_cast<std::size_t>(v);
      to_local[v] = static_cast<std::int32_t>(lp.to_global.size());
      lp.to_global.push_back(v);
      lp.local.nodes.push_back(mesh.nodes[u]);
      lp.local.node_kind.push_back(pass == 0 ? NodeKind::corner : NodeKind::interior);  // smoothing moves the free only
      // A fixed node aims at its share of a regular node: its angle over a right angle, less its quads outside.
      if (pass == 0)
        lp.targets.push_back(std::max(1.0, std::clamp(totals.angle[u] / right, 1.0, 4.0) - (totals.quads[u] - inside.at(v))));
    }
  lp.fixed = lp.targets.size();
  for (std::size_t q : quads) {
    std::array<std::int32_t, 4> x{};
    for (int k = 0; k < 4; ++k) x[k] = to_local.at(mesh.quads[q][k]);
    lp.local.quads.push_back(x);
    lp.local.quad_part.push_back(static_cast<std::int32_t>(q));
  }
  for (std::size_t q : quads)
    for (int k = 0; k < 4; ++k) {
      const std::int32_t a = mesh.quads[q][k], b = mesh.quads[q][(k + 1) % 4];
      if (totals.curve_edges.count(edge_key(a, b))) lp.kept.push_back({to_local.at(a), to_local.at(b)});
    }
  return lp;
}

// Plain Laplacian sweeps over the free nodes (those from `fixed` on).
void laplacian_sweeps(QuadMesh& local, std::size_t fixed, int sweeps) {
  std::vector<std::vector<std::int32_t>> adj(local.nodes.size());
  for (const auto& q : local.quads)
    for (int k = 0; k < 4; ++k) {
      auto& a = adj[static_cast<std::size_t>(q[k])];
      for (std::int32_t u : {q[(k + 1) % 4], q[(k + 3) % 4]})
        if (std::find(a.begin(), a.end(), u) == a.end()) a.push_back(u);
    }
  for (int sweep = 0; sweep < sweeps; ++sweep)
    for (std::size_t v = fixed; v < local.nodes.size(); ++v) {
      if (adj[v].empty()) continue;
      Vec2 c{};
      for (std::int32_t u : adj[v]) c = c + local.nodes[static_cast<std::size_t>(u)];
      local.nodes[v] = (1.0 / static_cast<double>(adj[v].size())) * c;
    }
}

Piece relax_piece(const QuadMesh& mesh, const std::vector<std::size_t>& quads, const NodeTotals& totals,
                  const RelaxValencesOptions& options, const SmoothOptions& smooth) {
  Piece piece;
  piece.stats.region_quads = quads.size();
  LocalPiece lp = local_piece(mesh, quads, totals);
  QuadMesh& local = lp.local;
  const std::size_t fixed = lp.fixed;
  const QuadMesh before = local;
  const auto was = patch_valence::folded_and_poor(before, options.poor_sj);
  // The moves with wandering rounds first; where the smoothing cannot follow them, the improving moves alone.
  for (int plateau : {options.plateau_rounds, 0}) {
    local = before;
    const patch_valence::Moves moves =
        patch_valence::relax_valences(local, fixed, lp.kept, options.max_moves, plateau, lp.targets);
    piece.stats.flips = moves.flips;
    piece.stats.collapses = moves.collapses;
    piece.stats.energy_before = moves.energy_before;
    piece.stats.energy_after = moves.energy_after;
    if (moves.flips + moves.collapses == 0) return piece;
    // Plain Laplacian sweeps over the free nodes (the moves leave them where they were), then the mesh's own
    // smoothing (untangling, guarded Laplacian, the worst-corner search), as the quads before the moves had it.
    laplacian_sweeps(local, fixed, options.laplacian_sweeps);
    const std::vector<std::int32_t> slots = local.quad_part;
    smooth_quads(local, smooth);
    local.quad_part = slots;
    const auto now = patch_valence::folded_and_poor(local, options.poor_sj);
    if (now.first <= was.first && now.second <= was.second) {
      piece.stats.kept = true;
      break;
    }
    if (plateau == 0) return piece;
  }
  for (std::size_t i = 0; i < local.quads.size(); ++i) {
    std::array<std::int32_t, 4> x{};
    for (int k = 0; k < 4; ++k) x[k] = lp.to_global[static_cast<std::size_t>(local.quads[i][k])];
    piece.quads.push_back(x);
    piece.slot.push_back(static_cast<std::size_t>(local.quad_part[i]));
  }
  for (std::size_t v = fixed; v < local.nodes.size(); ++v) piece.moved.push_back({lp.to_global[v], local.nodes[v]});
  return piece;
}

// The whole mesh's figures, and the flagged quads at each node in `at`.
NodeTotals node_totals(const QuadMesh& mesh, const std::vector<std::uint8_t>& flagged,
                       std::vector<std::vector<std::int32_t>>& at) {
  const std::size_t nv = mesh.nodes.size(), nq = mesh.quads.size();
  NodeTotals totals{std::vector<int>(nv, 0), std::vector<double>(nv, 0.0), {}};
  for (const auto* edges : {&mesh.boundary_edges, &mesh.feature_edges})
    for (const auto& e : *edges) totals.curve_edges.insert(edge_key(e[0], e[1]));
  at.assign(nv, {});
  for (std::size_t q = 0; q < nq; ++q) {
    const auto& x = mesh.quads[q];
    for (int k = 0; k < 4; ++k) {
      const auto v = static_cast<std::size_t>(x[k]);
      totals.quads[v]++;
      if (flagged[q]) at[v].push_back(static_cast<std::int32_t>(q));
      const Vec2 p = mesh.nodes[v], next = mesh.nodes[static_cast<std::size_t>(x[(k + 1) % 4])] - p,
                 prev = mesh.nodes[static_cast<std::size_t>(x[(k + 3) % 4])] - p;
      double a = std::atan2(cross(next, prev), dot(next, prev));
      if (a < 0) a += 4.0 * std::acos(0.0);
      totals.angle[v] += a;
    }
  }
  return totals;
}

// Pieces: flagged quads that share a node (`at`: the flagged quads at each node), each quad's piece in piece_of.
std::vector<std::vector<std::size_t>> flagged_pieces(const QuadMesh& mesh, const std::vector<std::uint8_t>& flagged,
                                                     const std::vector<std::vector<std::int32_t>>& at,
                                                     std::vector<std::int32_t>& piece_of) {
  const std::size_t nq = mesh.quads.size();
  piece_of.assign(nq, -1);
  std::vector<std::vector<std::size_t>> pieces;
  for (std::size_t q0 = 0; q0 < nq; ++q0) {
    if (!flagged[q0] || piece_of[q0] >= 0) continue;
    const auto id = static_cast<std::int32_t>(pieces.size());
    pieces.push_back({q0});
    piece_of[q0] = id;
    for (std::size_t k = 0; k < pieces.back().size(); ++k)
      for (std::int32_t v : mesh.quads[pieces.back()[k]])
        for (std::int32_t n : at[static_cast<std::size_t>(v)])
          if (piece_of[static_cast<std::size_t>(n)] < 0) {
            piece_of[static_cast<std::size_t>(n)] = id;
            pieces.back().push_back(static_cast<std::size_t>(n));
          }
  }
  return pieces;
}

// The mesh again: the quads outside kept pieces in their order, then each kept piece's; unused nodes removed
// (but not those in no quad before: `quads_at`, not this stage's to drop). origin: each quad's quad before.
void replace_kept_pieces(QuadMesh& mesh, const std::vector<Piece>& done, const std::vector<std::uint8_t>& flagged,
                         const std::vector<std::int32_t>& piece_of, const std::vector<int>& quads_at,
                         std::vector<std::size_t>& origin, RelaxValencesStats& total) {
  const std::size_t nv = mesh.nodes.size(), nq = mesh.quads.size();
  std::vector<std::array<std::int32_t, 4>> quads;
  for (std::size_t q = 0; q < nq; ++q) {
    if (flagged[q] && done[static_cast<std::size_t>(piece_of[q])].stats.kept) continue;
    quads.push_back(mesh.quads[q]);
    origin.push_back(q);
  }
  total.first_kept_quad = quads.size();
  for (const Piece& p : done) {
    if (!p.stats.kept) continue;
    quads.insert(quads.end(), p.quads.begin(), p.quads.end());
    origin.insert(origin.end(), p.slot.begin(), p.slot.end());
    for (const auto& [v, x] : p.moved) mesh.nodes[static_cast<std::size_t>(v)] = x;
  }
  std::vector<std::uint8_t> used(nv, 0);
  for (const auto& x : quads)
    for (std::int32_t v : x) used[static_cast<std::size_t>(v)] = 1;
  for (std::size_t v = 0; v < nv; ++v) used[v] = used[v] || quads_at[v] == 0;  // not this stage's to drop
  std::vector<std::int32_t> index(nv, -1);
  std::size_t n = 0;
  for (std::size_t v = 0; v < nv; ++v) {
    if (!used[v]) continue;
    index[v] = static_cast<std::int32_t>(n);
    mesh.nodes[n] = mesh.nodes[v];
    if (!mesh.node_kind.empty()) mesh.node_kind[n] = mesh.node_kind[v];
    ++n;
  }
  mesh.nodes.resize(n);
  if (!mesh.node_kind.empty()) mesh.node_kind.resize(n);
  for (auto& x : quads)
    for (std::int32_t& v : x) v = index[static_cast<std::size_t>(v)];
  for (auto* edges : {&mesh.boundary_edges, &mesh.feature_edges})
    for (auto& e : *edges)
      for (std::int32_t& v : e) v = index[static_cast<std::size_t>(v)];
  if (mesh.quad_part.size() == nq) {
    std::vector<std::int32_t> parts(origin.size());
    for (std::size_t q = 0; q < origin.size(); ++q) parts[q] = mesh.quad_part[origin[q]];
    mesh.quad_part = std::move(parts);
  }
  mesh.quads = std::move(quads);
}

}  // namespace

RelaxValencesStats relax_region_valences(QuadMesh& mesh, const std::vector<std::uint8_t>& region,
                                         const RelaxValencesOptions& options, const SmoothOptions& smooth,
                                         std::vector<std::size_t>& origin) {
  RelaxValencesStats total;
  origin.clear();
  const std::size_t nq = mesh.quads.size();
  if (!options.enabled) return total;
  std::vector<std::uint8_t> flagged(nq, 0);
  for (std::size_t q = 0; q < nq; ++q) flagged[q] = q < region.size() && region[q] != 0;

  std::vector<std::vector<std::int32_t>> at;  // flagged quads at each node
  const NodeTotals totals = node_totals(mesh, flagged, at);
  // Pieces: flagged quads that share a node. They share no node with each other, so each is relaxed, and kept
  // or not, on its own (in parallel; the result does not depend on the order).
  std::vector<std::int32_t> piece_of;
  std::vector<std::vector<std::size_t>> pieces = flagged_pieces(mesh, flagged, at, piece_of);
  if (pieces.empty()) return total;
  std::vector<Piece> done(pieces.size());
  oneapi::tbb::parallel_for(std::size_t{0}, pieces.size(), [&](std::size_t i) {
    std::sort(pieces[i].begin(), pieces[i].end());
    done[i] = relax_piece(mesh, pieces[i], totals, options, smooth);
  });
  for (const Piece& p : done) {
    total.region_quads += p.stats.region_quads;
    total.energy_before += p.stats.energy_before;
    total.energy_after += p.stats.kept ? p.stats.energy_after : p.stats.energy_before;
    if (!p.stats.kept) continue;
    total.kept = true;
    total.flips += p.stats.flips;
    total.collapses += p.stats.collapses;
  }
  if (!total.kept) return total;
  replace_kept_pieces(mesh, done, flagged, piece_of, totals.quads, origin, total);
  return total;
}

}  // namespace polysquare
