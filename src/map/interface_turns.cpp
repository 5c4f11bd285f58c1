#include "map/interface_turns.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <unordered_map>
#include <utility>

#include "polysquare/core/error.h"

namespace polysquare {
namespace {

// A layout's segments as loops: the segment after each one (through the break point at its end), the quarter
// turn between two, and the total turn of the loop through each segment.
class LoopTurns {
 public:
  explicit LoopTurns(const Layout& layout) : l_(layout) {
    const int ns = static_cast<int>(l_.segments.size());
    starting_.assign(l_.break_vertex.size(), -1);
    ending_.assign(l_.break_vertex.size(), -1);
    for (int k = 0; k < ns; ++k) {
      const LayoutSegment& s = l_.segments[static_cast<std::size_t>(k)];
      if (s.break_a >= 0 && static_cast<std::size_t>(s.break_a) < starting_.size()) starting_[static_cast<std::size_t>(s.break_a)] = k;
      if (s.break_b >= 0 && static_cast<std::size_t>(s.break_b) < ending_.size()) ending_[static_cast<std::size_t>(s.break_b)] = k;
    }
    // Each loop is walked once; a walk that does not come back leaves only its start unclosed.
    sum_.assign(static_cast<std::size_t>(ns), 0);
    closed_.assign(static_cast<std::size_t>(ns), 0);
    std::vector<std::uint8_t> done(static_cast<std::size_t>(ns), 0);
    for (int k = 0; k < ns; ++k) {
      if (done[static_cast<std::size_t>(k)]) continue;
      done[static_cast<std::size_t>(k)] = 1;
      std::vector<int> loop{k};
      int sum = 0;
      for (int steps = 0, at = k; steps <= ns; ++steps) {
        const int l = next(at);
        if (l < 0) break;
        const int t = turn(at, l);
        sum += t == 1 ? 1 : (t == 3 ? -1 : 0);
        if (l == k) {
          for (int m : loop) {
            done[static_cast<std::size_t>(m)] = closed_[static_cast<std::size_t>(m)] = 1;
            sum_[static_cast<std::size_t>(m)] = sum;
          }
          break;
        }
        loop.push_back(at = l);
      }
    }
  }
  // The segment that starts at break point b, or -1.
  int starting(int b) const { return b >= 0 && static_cast<std::size_t>(b) < starting_.size() ? starting_[static_cast<std::size_t>(b)] : -1; }
  int next(int k) const { return starting(l_.segments[static_cast<std::size_t>(k)].break_b); }
  int turn(int k, int l) const {
    return ((l_.segments[static_cast<std::size_t>(l)].label - l_.segments[static_cast<std::size_t>(k)].label) % 4 + 4) % 4;
  }
  // The turn (1: left, 3: right) that is convex on the loop through segment k: a loop whose turns add up to a
  // full left turn has its subregion on its left. 0 when the segments from k do not close into a loop.
  int convex_turn(int k) const {
    return closed_[static_cast<std::size_t>(k)] ? (sum_[static_cast<std::size_t>(k)] > 0 ? 1 : 3) : 0;
  }
  // Quads the layout puts at break point b: 1 at a convex corner, 2 where it goes straight, 3 at a reflex corner;
  // 0 when no loop with a total turn closes through b, or it turns back there.
  int quads_at(int b) const {
    const int l = starting(b), k = b >= 0 && static_cast<std::size_t>(b) < ending_.size() ? ending_[static_cast<std::size_t>(b)] : -1;
    if (l < 0 || k < 0 || next(k) != l || !closed_[static_cast<std::size_t>(l)] || sum_[static_cast<std::size_t>(l)] == 0) return 0;
    const int t = turn(k, l), convex = convex_turn(l);
    return t == 0 ? 2 : t == convex ? 1 : t == 4 - convex ? 3 : 0;
  }
  // The same at triangulation vertex v (0 when v is no break point).
  int quads_at_vertex(std::int32_t v) const { return quads_at(l_.vertex_break[static_cast<std::size_t>(v)]); }
  std::size_t corners() const {
    std::size_t c = 0;
    for (std::size_t b = 0; b < l_.break_vertex.size(); ++b) c += quads_at(static_cast<int>(b)) != 2;
    return c;
  }

 private:
  const Layout& l_;
  std::vector<int> starting_, ending_, sum_;
  std::vector<std::uint8_t> closed_;
};

}  // namespace

std::optional<ConvexOnBothSides> convex_on_both_sides(const std::vector<const Layout*>& layouts,
                                                      const std::vector<SegmentCoupling>& couplings) {
  std::map<std::pair<std::size_t, int>, std::pair<std::size_t, int>> partner;
  for (const SegmentCoupling& c : couplings) {
    partner[{c.layout_a, c.segment_a}] = {c.layout_b, c.segment_b};
    partner[{c.layout_b, c.segment_b}] = {c.layout_a, c.segment_a};
  }
  const std::size_t n = layouts.size();
  std::vector<std::optional<LoopTurns>> loops(n);
  for (std::size_t p = 0; p < n; ++p)
    if (layouts[p]) loops[p].emplace(*layouts[p]);
  for (std::size_t p = 0; p < n; ++p) {
    if (!layouts[p]) continue;
    const LoopTurns& lp = *loops[p];
    for (int k = 0; k < static_cast<int>(layouts[p]->segments.size()); ++k) {
      const auto pk = partner.find({p, k});
      const int l = lp.next(k);
      if (pk == partner.end() || l < 0) continue;
      const auto pl = partner.find({p, l});
      if (pl == partner.end() || pl->second.first != pk->second.first) continue;
      const std::size_t q = pk->second.first;
      if (q >= n || !layouts[q]) continue;
      const LoopTurns& lq = *loops[q];
      const int qk = pk->second.second, ql = pl->second.second;
      if (lq.next(ql) != qk) continue;  // the neighbour's two segments do not meet at this break point
      const int cp = lp.convex_turn(k), cq = lq.convex_turn(ql);
      if (cp != 0 && cq != 0 && lp.turn(k, l) == cp && lq.turn(ql, qk) == cq) return ConvexOnBothSides{p, q, l};
    }
  }
  return std::nullopt;
}

std::size_t agree_feature_interface_turns(std::vector<InterfaceSide>& sides, double max_length) {
  const std::size_t n = sides.size();
  std::vector<std::unordered_map<std::int32_t, std::int32_t>> local(n);  // shared vertex -> vertex, on interfaces
  std::vector<std::optional<LoopTurns>> loops(n);  // of each side's current layout
  for (std::size_t p = 0; p < n; ++p) {
    if (!sides[p].layout) continue;
    loops[p].emplace(*sides[p].layout);
    for (const TriChain& ch : sides[p].mesh->chains)
      if (ch.interface >= 0)
        for (std::int32_t v : ch.vertices)
          if (const std::int32_t g = (*sides[p].global_vertex)[static_cast<std::size_t>(v)]; g >= 0) local[p].emplace(g, v);
  }
  auto position = [](const TriChain& ch, std::int32_t v) {
    const auto it = std::find(ch.vertices.begin(), ch.vertices.end(), v);
    return it == ch.vertices.end() ? -1 : static_cast<int>(it - ch.vertices.begin());
  };
  std::size_t agreed = 0;
  for (std::size_t p = 0; p < n; ++p) {
    if (!sides[p].layout) continue;
    for (std::size_t c = 0; c < sides[p].mesh->chains.size(); ++c) {
      const TriChain& ch = sides[p].mesh->chains[c];
      if (ch.kind != TriChain::Kind::feature || ch.interface < 0 || ch.closed) continue;
      const auto q = static_cast<std::size_t>(ch.interface);
      if (q <= p || q >= n || !sides[q].layout) continue;
      // q's vertex at each vertex of ch (-1 where it has none), and q's chain along the same interface.
      std::vector<std::int32_t> across(ch.vertices.size(), -1);
      for (std::size_t i = 0; i < ch.vertices.size(); ++i)
        if (const auto it = local[q].find((*sides[p].global_vertex)[static_cast<std::size_t>(ch.vertices[i])]); it != local[q].end())
          across[i] = it->second;
      if (across.front() < 0 || across.back() < 0) continue;
      int qc = -1;
      for (std::size_t d = 0; d < sides[q].mesh->chains.size() && qc < 0; ++d) {
        const TriChain& o = sides[q].mesh->chains[d];
        if (o.interface == static_cast<int>(p) && !o.closed && o.vertices.size() == ch.vertices.size() &&
            position(o, across.front()) >= 0 && position(o, across.back()) >= 0)
          qc = static_cast<int>(d);
      }
      if (qc < 0) continue;
      // Quads at the node at position i of ch, both sides, less four.
      auto mismatch_at = [&](int i) {
        const auto k = static_cast<std::size_t>(i);
        if (across[k] < 0) return 0;
        const int a = loops[p]->quads_at_vertex(ch.vertices[k]), b = loops[q]->quads_at_vertex(across[k]);
        return a == 0 || b == 0 ? 0 : a + b - 4;
      };
      struct Mismatch {
        int i;  // position in ch
        int d;  // quads at the node less four
      };
      std::vector<Mismatch> open;
      for (int i = 1; i + 1 < static_cast<int>(ch.vertices.size()); ++i) {
        const int d = mismatch_at(i);
        if (d != 1 && d != -1) continue;
        if (open.empty() || open.back().d != -d) {
          open.push_back({i, d});
          continue;
        }
        const Mismatch first = open.back();
        open.pop_back();
        if (mismatch_at(first.i) != first.d || mismatch_at(i) != d) continue;  // changed by a fix since
        // The pair's two nodes on each side.
        const std::array<std::int32_t, 2> on_p{ch.vertices[static_cast<std::size_t>(first.i)], ch.vertices[static_cast<std::size_t>(i)]};
        const std::array<std::int32_t, 2> on_q{across[static_cast<std::size_t>(first.i)], across[static_cast<std::size_t>(i)]};
        // Try each side and each quarter turn of its stretch; keep the one that agrees both ends with the fewest
        // corners left on the changed side, then the shortest stretch.
        struct Trial {
          std::size_t x;
          Layout layout;
          std::size_t corners;
          double length;
        };
        std::optional<Trial> best;
        for (const std::size_t x : {p, q}) {
          const std::size_t other = x == p ? q : p;
          const TriChain& xc = sides[x].mesh->chains[x == p ? c : static_cast<std::size_t>(qc)];
          const std::array<std::int32_t, 2>& at = x == p ? on_p : on_q;
          const std::array<std::int32_t, 2>& facing = x == p ? on_q : on_p;
          const int a = position(xc, at[0]), b = position(xc, at[1]);
          if (a < 0 || b < 0) continue;
          const int lo = std::min(a, b), hi = std::max(a, b);
          const std::vector<Vec2>& y = *sides[x].deformed;
          double length = 0.0;
          for (int e = lo; e < hi; ++e)
            length += distance(y[static_cast<std::size_t>(xc.vertices[static_cast<std::size_t>(e)])],
                               y[static_cast<std::size_t>(xc.vertices[static_cast<std::size_t>(e + 1)])]);
          if (length > max_length) continue;
          for (const int delta : {1, 3}) {
            Layout trial = *sides[x].layout;
            std::vector<int>& labels = trial.chain_labels[x == p ? c : static_cast<std::size_t>(qc)];
            for (int e = lo; e < hi; ++e) labels[static_cast<std::size_t>(e)] = (labels[static_cast<std::size_t>(e)] + delta) % 4;
            try {
              add_straight_breaks(trial, *sides[x].mesh, y, std::vector<std::uint8_t>(sides[x].mesh->vertices.size(), 0),
                                  sides[x].name);
            } catch (const MeshingError&) {
              continue;
            }
            const LoopTurns turns(trial);
            bool agrees = true;
            for (int j = 0; j < 2; ++j) {
              const int mine = turns.quads_at_vertex(at[static_cast<std::size_t>(j)]);
              agrees = agrees && mine != 0 && mine + loops[other]->quads_at_vertex(facing[static_cast<std::size_t>(j)]) == 4;
            }
            if (!agrees) continue;
            const std::size_t corners = turns.corners();  // corners left on side x
            if (!best || corners < best->corners || (corners == best->corners && length < best->length))
              best = Trial{x, std::move(trial), corners, length};
          }
        }
        if (!best) continue;
        *sides[best->x].layout = std::move(best->layout);
        loops[best->x].emplace(*sides[best->x].layout);
        ++agreed;
      }
    }
  }
  return agreed;
}

}  // namespace polysquare
