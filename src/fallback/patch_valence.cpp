#include "fallback/patch_valence.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <unordered_set>

#include <oneapi/tbb/parallel_for.h>

#include "polysquare/core/geometry.h"
#include "polysquare/smooth/smooth.h"

namespace polysquare::patch_valence {
namespace {

using Quad = std::array<std::int32_t, 4>;

// Patches of more quads than this search their moves in parallel, in blocks of about this many quads.
constexpr std::size_t kQuadsPerBlock = 2048;

Quad rotated_to(Quad q, std::int32_t first) {
  while (q[0] != first) std::rotate(q.begin(), q.begin() + 1, q.end());
  return q;
}

// A candidate move: the quads it replaces and what replaces them, with the energy change.
// A flip replaces two quads by two, a collapse removes one (fixed arrays: a pass finds tens of thousands).
struct Move {
  double gain = 0.0;                   // energy decrease (> 0)
  std::array<std::int32_t, 2> quads{};  // the quads replaced: a flip's two (rewritten), a collapse's one (removed)
  std::array<Quad, 2> by{};             // a flip's new quads
  std::int32_t merged = -1, removed = -1;  // a collapse: the node kept and the one merged into it
  Vec2 at{};                               // the kept node's new position
  int replaced() const { return merged >= 0 ? 1 : 2; }
};

class Relaxer {
 public:
  Relaxer(QuadMesh& mesh, std::size_t given, const std::vector<std::array<std::int32_t, 2>>& kept_edges,
          const std::vector<double>& given_targets)
      : m_(mesh), given_(given) {
    for (const auto& e : kept_edges) kept_.insert(edge_key(e[0], e[1]));
    const double right = std::acos(0.0);
    std::vector<double> angle(m_.nodes.size(), 0.0);
    for (const Quad& q : m_.quads)
      for (int k = 0; k < 4; ++k) {
        const Vec2 p = pos(q[k]), next = pos(q[(k + 1) % 4]) - p, prev = pos(q[(k + 3) % 4]) - p;
        double a = std::atan2(cross(next, prev), dot(next, prev));
        if (a < 0) a += 4.0 * right;
        angle[static_cast<std::size_t>(q[k])] += a;
      }
    target_.assign(m_.nodes.size(), 4.0);
    for (std::size_t v = 0; v < given_ && v < m_.nodes.size(); ++v)
      target_[v] = given_targets.empty() ? std::clamp(angle[v] / right, 1.0, 4.0) : given_targets[v];
  }

  double energy() const {
    double e = 0.0;
    for (std::size_t v = 0; v < val_.size(); ++v)
      if (val_[v] > 0) e += sq(val_[v] - target_[v]);
    return e;
  }

  // One pass: every improving move, best first, none touching a node an earlier one touched. Returns the moves made.
  // With `plateau`, the moves that leave the energy as it is instead, in a shuffled order: irregular nodes wander
  // (a valence 3 beside a 5 moves as a pair) until the next greedy passes find them beside one they cancel with.
  std::size_t pass(Moves& moves, std::size_t budget, std::mt19937* plateau = nullptr) {
    index();
    mark_off_target();
    // A quad's moves read the quads at its nodes (their nodes' valences and places, which edges exist): they are
    // searched again only where a node of those quads changed since the last pass (a move's quads, the nodes
    // smoothing moved), and kept from the pass before elsewhere, so that a pass costs what changed, not the
    // patch (about 145 passes on a 46k-quad patch, each searching 40k quads, were a quarter of a coast's run).
    // Each quad keeps the moves that do not raise the energy; a pass takes those above its own least gain.
    const std::size_t nn = m_.nodes.size(), nq = m_.quads.size();
    if (flips_of_.size() != nq) all_dirty_ = true;
    // The first pass smooths the whole patch, as it came from its construction, and so does each plateau pass
    // (its moves are spread over the patch, and the smoothing in between is what lets later moves keep every
    // quad valid: smoothing only near the greedy moves' nodes raised the patches' singular nodes by 5-7 %).
    smooth_all_ = all_dirty_ || plateau != nullptr;
    const std::vector<std::uint8_t> dirty = dirty_quads();
    flips_of_.resize(nq);
    collapses_of_.resize(nq);
    all_dirty_ = false;
    changed_.assign(nn, 0);
    min_gain_ = -1e-9;
    search_moves(dirty);
    std::vector<std::int32_t> gone;
    const std::size_t made = make_moves(found_moves(plateau), budget, moves, gone);
    if (!gone.empty()) drop_quads(gone);  // one compaction, quad_part and the kept moves alongside
    if (made > 0) smooth(3);
    return made;
  }

  double energy_now() { index(); return energy(); }
  void quads_replaced() {  // the caller put other quads into the mesh
    stale_ = true;
    all_dirty_ = true;
  }
  void finish(Moves& moves) {
    index();
    moves.energy_after = energy();
  }

  void start(Moves& moves) {
    index();
    moves.energy_before = energy();
  }

 private:
  static double sq(double x) { return x * x; }
  Vec2 pos(std::int32_t v) const { return m_.nodes[static_cast<std::size_t>(v)]; }
  bool is_given(std::int32_t v) const { return static_cast<std::size_t>(v) < given_; }

  // A move changes the valence of the nodes of its quads only, and each node at its target adds at least 1 to
  // the energy when it changes: a move that does not raise the energy has a node off its target among its
  // quads' nodes. Quads with none (most of a large patch after the first passes) are not searched.
  void mark_off_target() {
    const std::size_t nn = m_.nodes.size(), nq = m_.quads.size();
    off_quad_.assign(nq, 0);
    near_off_.assign(nn, 0);
    for (std::size_t i = 0; i < nq; ++i)
      for (std::int32_t v : m_.quads[i]) {
        const auto u = static_cast<std::size_t>(v);
        if (std::abs(val_[u] - target_[u]) > 1e-9) off_quad_[i] = 1;
      }
    for (std::size_t i = 0; i < nq; ++i)
      if (off_quad_[i])
        for (std::int32_t v : m_.quads[i]) near_off_[static_cast<std::size_t>(v)] = 1;
  }

  // The quads whose moves are searched again: all of them, or those with a node in a quad with a changed node.
  std::vector<std::uint8_t> dirty_quads() const {
    const std::size_t nn = m_.nodes.size(), nq = m_.quads.size();
    std::vector<std::uint8_t> dirty(nq, all_dirty_ ? 1 : 0);
    if (all_dirty_) return dirty;
    std::vector<std::uint8_t> ring(nn, 0);  // nodes of quads with a changed node
    for (std::size_t i = 0; i < nq; ++i)
      if (std::any_of(m_.quads[i].begin(), m_.quads[i].end(), [&](std::int32_t v) { return changed_[static_cast<std::size_t>(v)] != 0; }))
        for (std::int32_t v : m_.quads[i]) ring[static_cast<std::size_t>(v)] = 1;
    for (std::size_t i = 0; i < nq; ++i)
      dirty[i] = std::any_of(m_.quads[i].begin(), m_.quads[i].end(), [&](std::int32_t v) { return ring[static_cast<std::size_t>(v)] != 0; });
    return dirty;
  }

  // The candidates of the dirty quads in a fixed order (flips by quad and side, then collapses by quad and
  // diagonal), searched in blocks of quads that large patches search in parallel.
  void search_moves(const std::vector<std::uint8_t>& dirty) {
    const std::size_t nq = m_.quads.size();
    const std::size_t blocks = std::max<std::size_t>(1, nq / kQuadsPerBlock);
    auto search = [&](std::size_t block) {
      for (std::size_t i = block * nq / blocks; i < (block + 1) * nq / blocks; ++i)
        if (dirty[i]) search_quad(i);
    };
    if (blocks == 1) search(0);
    else oneapi::tbb::parallel_for(std::size_t{0}, blocks, search);
  }

  void search_quad(std::size_t i) {
    flips_of_[i].clear();
    collapses_of_[i].clear();
    // A flip's second quad shares two nodes with quad i: none near an off node, no move from quad i.
    if (std::none_of(m_.quads[i].begin(), m_.quads[i].end(), [&](std::int32_t v) { return near_off_[static_cast<std::size_t>(v)] != 0; }))
      return;
    for (int k = 0; k < 4; ++k) {
      const std::int32_t a = m_.quads[i][k], b = m_.quads[i][(k + 1) % 4];
      std::array<std::int32_t, 2> two{};
      if (edge_quads(a, b, two) == 2 && two[0] == static_cast<std::int32_t>(i) &&
          (off_quad_[i] || off_quad_[static_cast<std::size_t>(two[1])]) && !kept_.count(edge_key(a, b)))
        flip_candidates(two[0], two[1], flips_of_[i]);
    }
    if (!off_quad_[i]) return;
    collapse_candidate(static_cast<std::int32_t>(i), 0, collapses_of_[i]);
    collapse_candidate(static_cast<std::int32_t>(i), 1, collapses_of_[i]);
  }

  // The kept moves this pass takes: those that lower the energy, best first, or with `plateau` those that keep it,
  // shuffled.
  std::vector<Move> found_moves(std::mt19937* plateau) const {
    const double least = plateau ? -1e-9 : 1e-9;
    std::vector<Move> found;
    for (const auto* per_quad : {&flips_of_, &collapses_of_})
      for (const std::vector<Move>& list : *per_quad)
        for (const Move& mv : list)
          if (mv.gain > least) found.push_back(mv);
    if (plateau) {
      found.erase(std::remove_if(found.begin(), found.end(), [](const Move& mv) { return mv.gain > 1e-9; }), found.end());
      std::shuffle(found.begin(), found.end(), *plateau);
    } else {
      std::stable_sort(found.begin(), found.end(), [](const Move& x, const Move& y) { return x.gain > y.gain; });
    }
    return found;
  }

  // Calls f(u) for every node whose quads move mv changes: the nodes of its quads, and for a collapse those of
  // every quad at both its nodes.
  template <typename F>
  void for_each_node_touched(const Move& mv, F f) const {
    for (int j = 0; j < mv.replaced(); ++j)
      for (std::int32_t v : m_.quads[static_cast<std::size_t>(mv.quads[static_cast<std::size_t>(j)])]) f(v);
    if (mv.merged >= 0)  // a collapse changes every quad at both nodes
      for (std::int32_t v : {mv.merged, mv.removed})
        for (std::int32_t q : quads_at_[static_cast<std::size_t>(v)])
          for (std::int32_t u : m_.quads[static_cast<std::size_t>(q)]) f(u);
  }

  // Makes the found moves in order, at most `budget`, skipping those that touch a node an earlier one touched;
  // a collapse's removed quad goes to `gone`. Returns the moves made.
  std::size_t make_moves(const std::vector<Move>& found, std::size_t budget, Moves& moves, std::vector<std::int32_t>& gone) {
    std::vector<std::uint8_t> touched(m_.nodes.size(), 0);
    std::size_t made = 0;
    for (const Move& mv : found) {
      if (made >= budget) break;
      bool free = true;
      for_each_node_touched(mv, [&](std::int32_t u) { free = free && !touched[static_cast<std::size_t>(u)]; });
      if (!free) continue;
      for_each_node_touched(mv, [&](std::int32_t u) { touched[static_cast<std::size_t>(u)] = 1; });
      if (mv.merged >= 0) {
        for (std::int32_t q : quads_at_[static_cast<std::size_t>(mv.removed)])
          for (std::int32_t& v : m_.quads[static_cast<std::size_t>(q)])
            if (v == mv.removed) v = mv.merged;
        m_.nodes[static_cast<std::size_t>(mv.merged)] = mv.at;
        gone.push_back(mv.quads[0]);
        ++moves.collapses;
      } else {
        for (std::size_t k = 0; k < 2; ++k) m_.quads[static_cast<std::size_t>(mv.quads[k])] = mv.by[k];
        ++moves.flips;
      }
      stale_ = true;
      ++made;
    }
    // The nodes of every quad a move replaced or changed: their valences, quads or places changed.
    for (std::size_t v = 0; v < touched.size(); ++v) changed_[v] |= touched[v];
    return made;
  }

  // Removes the `gone` quads, renumbering quad_part and the kept moves alongside.
  void drop_quads(const std::vector<std::int32_t>& gone) {
    std::vector<std::uint8_t> drop(m_.quads.size(), 0);
    for (std::int32_t q : gone) drop[static_cast<std::size_t>(q)] = 1;
    std::vector<std::int32_t> renumber(m_.quads.size(), -1);
    const bool parts = m_.quad_part.size() == m_.quads.size();
    std::size_t kept = 0;
    for (std::size_t q = 0; q < m_.quads.size(); ++q) {
      if (drop[q]) continue;
      renumber[q] = static_cast<std::int32_t>(kept);
      m_.quads[kept] = m_.quads[q];
      flips_of_[kept] = std::move(flips_of_[q]);
      collapses_of_[kept] = std::move(collapses_of_[q]);
      if (parts) m_.quad_part[kept] = m_.quad_part[q];
      ++kept;
    }
    m_.quads.resize(kept);
    flips_of_.resize(kept);
    collapses_of_.resize(kept);
    if (parts) m_.quad_part.resize(kept);
    for (auto* per_quad : {&flips_of_, &collapses_of_})
      for (std::vector<Move>& list : *per_quad)
        for (Move& mv : list)
          for (std::int32_t& q : mv.quads)
            if (q >= 0) {
              q = renumber[static_cast<std::size_t>(q)];
              if (q < 0) all_dirty_ = true;  // a kept move on a removed quad: cannot happen, but search all then
            }
  }

  // Rebuilt after every change of the quads (not of the positions), keeping its allocations: the per-node lists
  // are cleared, not freed. An edge's quads are found from its end node's quads (about four), not from a table
  // of all edges: sorting one was a fifth of the moves' time on 20-50k-quad patches.
  void index() {
    if (!stale_) return;
    stale_ = false;
    const std::size_t nn = m_.nodes.size();
    val_.assign(nn, 0);
    quads_at_.resize(nn);
    neighbours_.resize(nn);
    for (std::size_t v = 0; v < nn; ++v) {
      quads_at_[v].clear();
      neighbours_[v].clear();
    }
    for (std::size_t i = 0; i < m_.quads.size(); ++i) {
      const Quad& q = m_.quads[i];
      for (int k = 0; k < 4; ++k) {
        const auto v = static_cast<std::size_t>(q[k]);
        val_[v]++;
        quads_at_[v].push_back(static_cast<std::int32_t>(i));
        auto& nb = neighbours_[v];
        for (std::int32_t u : {q[(k + 1) % 4], q[(k + 3) % 4]})
          if (std::find(nb.begin(), nb.end(), u) == nb.end()) nb.push_back(u);
      }
    }
  }

  // How many times the edge (a, b) is a side of a quad (a quad counted once per side), and the first two such
  // quads in increasing order in `two`.
  int edge_quads(std::int32_t a, std::int32_t b, std::array<std::int32_t, 2>& two) const {
    int n = 0;
    std::int32_t last = -1;
    for (std::int32_t i : quads_at_[static_cast<std::size_t>(a)]) {
      if (i == last) continue;  // a quad holding a twice is listed twice; its sides are counted once each
      last = i;
      const Quad& q = m_.quads[static_cast<std::size_t>(i)];
      for (int k = 0; k < 4; ++k)
        if ((q[k] == a && q[(k + 1) % 4] == b) || (q[k] == b && q[(k + 1) % 4] == a)) {
          if (n < 2) two[static_cast<std::size_t>(n)] = i;
          ++n;
        }
    }
    return n;
  }

  // Positive area at the current positions (with `moved` at `to`), and no corner of three given nodes that is
  // reflex or within 10 degrees of flat: no move of the free nodes could open it.
  bool valid(const Quad& q, std::int32_t moved = -1, Vec2 to = {}) const {
    auto p = [&](std::int32_t v) { return v == moved ? to : pos(v); };
    double area = 0.0;
    for (int k = 0; k < 4; ++k) area += cross(p(q[k]), p(q[(k + 1) % 4]));
    if (area <= 0.0) return false;
    for (int k = 0; k < 4; ++k) {
      const std::int32_t v = q[k], n = q[(k + 1) % 4], r = q[(k + 3) % 4];
      if (!is_given(v) || !is_given(n) || !is_given(r) || v == moved) continue;
      const Vec2 e1 = p(n) - p(v), e2 = p(r) - p(v);
      const double l = std::sqrt(dot(e1, e1) * dot(e2, e2));
      if (l <= 0.0 || cross(e1, e2) < 0.17 * l) return false;
    }
    return true;
  }

  double change(std::int32_t v, int delta) const {
    const double x = val_[static_cast<std::size_t>(v)] - target_[static_cast<std::size_t>(v)];
    return sq(x + delta) - sq(x);
  }
  bool may_lose_one(std::int32_t v) const { return val_[static_cast<std::size_t>(v)] > (is_given(v) ? 1 : 3); }
  bool is_edge(std::int32_t a, std::int32_t b) const {
    std::array<std::int32_t, 2> two{};
    return edge_quads(a, b, two) > 0;
  }

  void flip_candidates(std::int32_t i1, std::int32_t i2, std::vector<Move>& out) const {
    const Quad& q1 = m_.quads[static_cast<std::size_t>(i1)];
    const Quad& q2 = m_.quads[static_cast<std::size_t>(i2)];
    // q1 = (a, b, c, d) and q2 = (b, a, e, f), both counter-clockwise: the hexagon (b, c, d, a, e, f).
    for (int k = 0; k < 4; ++k) {
      const std::int32_t a = q1[k], b = q1[(k + 1) % 4];
      if (std::find(q2.begin(), q2.end(), b) == q2.end()) continue;
      const Quad r2 = rotated_to(q2, b);
      if (r2[1] != a) continue;
      const std::int32_t c = q1[(k + 2) % 4], d = q1[(k + 3) % 4], e = r2[2], f = r2[3];
      std::array<std::int32_t, 6> hex{b, c, d, a, e, f};
      std::sort(hex.begin(), hex.end());
      if (std::adjacent_find(hex.begin(), hex.end()) != hex.end()) return;
      if (!may_lose_one(a) || !may_lose_one(b)) return;
      const double lose = change(a, -1) + change(b, -1);
      const std::array<std::array<std::int32_t, 2>, 2> diagonals{{{c, e}, {d, f}}};
      const std::array<std::array<Quad, 2>, 2> splits{{{Quad{c, d, a, e}, Quad{e, f, b, c}},
                                                       {Quad{d, a, e, f}, Quad{f, b, c, d}}}};
      for (int s = 0; s < 2; ++s) {
        const auto [x, y] = diagonals[static_cast<std::size_t>(s)];
        if (is_edge(x, y)) continue;
        const double gain = -(lose + change(x, 1) + change(y, 1));
        if (gain <= min_gain_) continue;
        const auto& split = splits[static_cast<std::size_t>(s)];
        if (!valid(split[0]) || !valid(split[1])) continue;
        out.push_back({gain, {i1, i2}, {split[0], split[1]}, -1, -1, {}});
      }
      return;
    }
  }

  // Collapse quad i along its diagonal (k, k + 2): its nodes there merge, the other two lose a quad.
  void collapse_candidate(std::int32_t i, int k, std::vector<Move>& out) const {
    const Quad& q = m_.quads[static_cast<std::size_t>(i)];
    std::int32_t a = q[k], c = q[k + 2];
    const std::int32_t b = q[k + 1], d = q[(k + 3) % 4];
    if (is_given(a) && is_given(c)) return;
    if (is_given(c)) std::swap(a, c);  // a is kept: the given one, else the lower index
    else if (!is_given(a) && c < a) std::swap(a, c);
    if (!may_lose_one(b) || !may_lose_one(d) || is_edge(a, c)) return;
    for (std::int32_t u : neighbours_[static_cast<std::size_t>(a)])
      if (u != b && u != d &&
          std::find(neighbours_[static_cast<std::size_t>(c)].begin(), neighbours_[static_cast<std::size_t>(c)].end(), u) !=
              neighbours_[static_cast<std::size_t>(c)].end())
        return;
    const auto& at_a = quads_at_[static_cast<std::size_t>(a)];
    for (std::int32_t j : quads_at_[static_cast<std::size_t>(c)])
      if (j != i && std::find(at_a.begin(), at_a.end(), j) != at_a.end()) return;
    const double va = val_[static_cast<std::size_t>(a)], vc = val_[static_cast<std::size_t>(c)];
    const double ta = target_[static_cast<std::size_t>(a)], tc = target_[static_cast<std::size_t>(c)];
    const double gain = sq(va - ta) + sq(vc - tc) - sq(va + vc - 2 - ta) - change(b, -1) - change(d, -1);
    if (gain <= min_gain_) return;
    const Vec2 to = is_given(a) ? pos(a) : 0.5 * (pos(a) + pos(c));
    for (std::int32_t j : at_a)
      if (j != i && !valid(m_.quads[static_cast<std::size_t>(j)], a, to)) return;
    for (std::int32_t j : quads_at_[static_cast<std::size_t>(c)]) {
      if (j == i) continue;
      Quad moved = m_.quads[static_cast<std::size_t>(j)];
      for (std::int32_t& v : moved)
        if (v == c) v = a;
      if (!valid(moved, a, to)) return;
    }
    out.push_back({gain, {i, -1}, {}, a, c, to});
  }

  // Laplacian sweeps over the free nodes still in a quad within two rings of the nodes the moves changed, so the
  // next pass judges moves there at sensible positions (the rest did not change since it was last smoothed).
  void smooth(int sweeps) {
    index();
    std::vector<std::uint8_t> near = changed_;
    if (smooth_all_) near.assign(m_.nodes.size(), 1);
    for (int ring = 0; ring < 2 && !smooth_all_; ++ring) {
      std::vector<std::uint8_t> grown = near;
      for (const Quad& q : m_.quads)
        if (near[static_cast<std::size_t>(q[0])] || near[static_cast<std::size_t>(q[1])] || near[static_cast<std::size_t>(q[2])] ||
            near[static_cast<std::size_t>(q[3])])
          for (std::int32_t v : q) grown[static_cast<std::size_t>(v)] = 1;
      near = std::move(grown);
    }
    for (int s = 0; s < sweeps; ++s)
      for (std::size_t v = given_; v < m_.nodes.size(); ++v) {
        if (neighbours_[v].empty() || !near[v]) continue;
        Vec2 c{};
        for (std::int32_t u : neighbours_[v]) c = c + pos(u);
        const Vec2 to = (1.0 / static_cast<double>(neighbours_[v].size())) * c;
        bool ok = true;
        for (std::int32_t q : quads_at_[v]) ok = ok && valid(m_.quads[static_cast<std::size_t>(q)], static_cast<std::int32_t>(v), to);
        if (ok && !(m_.nodes[v] == to)) {
          m_.nodes[v] = to;
          changed_[v] = 1;
        }
      }
  }

  QuadMesh& m_;
  std::size_t given_;
  double min_gain_ = 1e-9;
  std::unordered_set<std::uint64_t> kept_;
  std::vector<double> target_;
  std::vector<int> val_;
  std::vector<std::uint8_t> off_quad_, near_off_;  // per pass: quads with a node off its target, nodes of those
  std::vector<std::vector<Move>> flips_of_, collapses_of_;  // per quad: its moves that keep or lower the energy
  std::vector<std::uint8_t> changed_;  // per node: its quads, valence or place changed since the last search
  bool all_dirty_ = true;              // every quad is searched at the next pass
  bool smooth_all_ = true;             // this pass smooths every free node
  std::vector<std::vector<std::int32_t>> quads_at_;
  std::vector<std::vector<std::int32_t>> neighbours_;
  bool stale_ = true;  // the quads changed since index() ran
};

}  // namespace

std::pair<std::size_t, std::size_t> folded_and_poor(const QuadMesh& m, double poor) {
  std::pair<std::size_t, std::size_t> r{0, 0};
  for (std::size_t q = 0; q < m.quads.size(); ++q) {
    const double sj = quad_min_corner_sj(m, q);
    r.first += sj <= 0.0;
    r.second += sj < poor;
  }
  return r;
}

Moves relax_valences(QuadMesh& mesh, std::size_t given, const std::vector<std::array<std::int32_t, 2>>& kept_edges,
                     std::size_t max_moves, int plateau_rounds, const std::vector<double>& given_targets) {
  Moves moves;
  Relaxer r(mesh, given, kept_edges, given_targets);
  r.start(moves);
  std::size_t made = 0;
  auto greedy = [&] {
    while (made < max_moves) {
      const std::size_t now = r.pass(moves, max_moves - made);
      if (now == 0) break;
      made += now;
    }
  };
  greedy();
  // Plateau rounds; the mesh with the lowest energy seen is kept.
  QuadMesh best = mesh;
  Moves best_moves = moves;
  double best_energy = r.energy_now();
  std::mt19937 order(12345);
  for (int round = 0, stale = 0; round < plateau_rounds && stale < 6 && made < max_moves; ++round) {
    const std::size_t wandered = r.pass(moves, std::max<std::size_t>(1, mesh.quads.size() / 20), &order);
    if (wandered == 0) break;
    made += wandered;
    greedy();
    const double e = r.energy_now();
    if (e < best_energy - 1e-9) {
      best = mesh;
      best_moves = moves;
      best_energy = e;
      stale = 0;
    } else {
      ++stale;
    }
  }
  mesh = std::move(best);
  r.quads_replaced();
  moves = best_moves;
  r.finish(moves);
  return moves;
}

}  // namespace polysquare::patch_valence
