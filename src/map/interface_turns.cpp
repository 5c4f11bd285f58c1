#include "map/interface_turns.h"

#include <algorithm>
#include <map>
#include <optional>
#include <unordered_map>
#include <utility>

#include "polysquare/core/error.h"

namespace polysquare {

std::optional<ConvexOnBothSides> convex_on_both_sides(const std::vector<const Layout*>& layouts,
                                                      const std::vector<SegmentCoupling>& couplings) {
  std::map<std::pair<std::size_t, int>, std::pair<std::size_t, int>> partner;
  for (const SegmentCoupling& c : couplings) {
    partner[{c.layout_a, c.segment_a}] = {c.layout_b, c.segment_b};
    partner[{c.layout_b, c.segment_b}] = {c.layout_a, c.segment_a};
  }
  const std::size_t n = layouts.size();
  std::vector<std::vector<int>> starting(n);  // per layout: the segment that starts at each break point
  for (std::size_t p = 0; p < n; ++p) {
    if (!layouts[p]) continue;
    starting[p].assign(layouts[p]->break_vertex.size(), -1);
    for (std::size_t k = 0; k < layouts[p]->segments.size(); ++k) {
      const int b = layouts[p]->segments[k].break_a;
      if (b >= 0 && static_cast<std::size_t>(b) < starting[p].size()) starting[p][static_cast<std::size_t>(b)] = static_cast<int>(k);
    }
  }
  auto segment = [&](std::size_t p, int k) -> const LayoutSegment& { return layouts[p]->segments[static_cast<std::size_t>(k)]; };
  auto next = [&](std::size_t p, int k) {
    const int b = segment(p, k).break_b;
    return b >= 0 && static_cast<std::size_t>(b) < starting[p].size() ? starting[p][static_cast<std::size_t>(b)] : -1;
  };
  auto turn = [&](std::size_t p, int k, int l) { return ((segment(p, l).label - segment(p, k).label) % 4 + 4) % 4; };
  // The turn (1: left, 3: right) that is convex on the loop through segment k: a loop whose turns add up to a
  // full left turn has its subregion on its left. 0 when the segments do not close into a loop.
  auto convex_turn = [&](std::size_t p, int k) {
    int sum = 0, at = k;
    for (std::size_t steps = 0; steps <= layouts[p]->segments.size(); ++steps) {
      const int l = next(p, at);
      if (l < 0) return 0;
      const int t = turn(p, at, l);
      sum += t == 1 ? 1 : (t == 3 ? -1 : 0);
      at = l;
      if (at == k) return sum > 0 ? 1 : 3;
    }
    return 0;
  };
  for (std::size_t p = 0; p < n; ++p) {
    if (!layouts[p]) continue;
    for (int k = 0; k < static_cast<int>(layouts[p]->segments.size()); ++k) {
      const auto pk = partner.find({p, k});
      const int l = next(p, k);
      if (pk == partner.end() || l < 0) continue;
      const auto pl = partner.find({p, l});
      if (pl == partner.end() || pl->second.first != pk->second.first) continue;
      const std::size_t q = pk->second.first;
      if (q >= n || !layouts[q]) continue;
      const int qk = pk->second.second, ql = pl->second.second;
      if (next(q, ql) != qk) continue;  // the neighbour's two segments do not meet at this break point
      const int cp = convex_turn(p, k), cq = convex_turn(q, ql);
      if (cp != 0 && cq != 0 && turn(p, k, l) == cp && turn(q, ql, qk) == cq) return ConvexOnBothSides{p, q, l};
    }
  }
  return std::nullopt;
}

namespace {

// Quads a layout puts at break vertex v: 1 at a convex corner, 2 where it goes straight, 3 at a reflex corner;
// 0 when v is no break point between two segments of one loop or the loop does not close (or turns back).
int quads_at_break(const Layout& layout, std::int32_t v) {
  const std::int32_t b = layout.vertex_break[static_cast<std::size_t>(v)];
  if (b < 0) return 0;
  const int ns = static_cast<int>(layout.segments.size());
  std::vector<int> starting(layout.break_vertex.size(), -1);
  for (int k = 0; k < ns; ++k) {
    const int a = layout.segments[static_cast<std::size_t>(k)].break_a;
    if (a >= 0) starting[static_cast<std::size_t>(a)] = k;
  }
  auto next = [&](int k) {
    const int e = layout.segments[static_cast<std::size_t>(k)].break_b;
    return e >= 0 ? starting[static_cast<std::size_t>(e)] : -1;
  };
  auto turn = [&](int k, int l) {
    return ((layout.segments[static_cast<std::size_t>(l)].label - layout.segments[static_cast<std::size_t>(k)].label) % 4 + 4) % 4;
  };
  const int l = starting[static_cast<std::size_t>(b)];
  if (l < 0) return 0;
  int k = -1, sum = 0, at = l;
  for (int steps = 0; steps <= ns; ++steps) {
    const int nx = next(at);
    if (nx < 0) return 0;
    const int t = turn(at, nx);
    sum += t == 1 ? 1 : (t == 3 ? -1 : 0);
    if (nx == l) {
      k = at;
      break;
    }
    at = nx;
  }
  if (k < 0 || sum == 0) return 0;
  const int t = turn(k, l), convex = sum > 0 ? 1 : 3;
  return t == 0 ? 2 : t == convex ? 1 : t == 4 - convex ? 3 : 0;
}

}  // namespace

std::size_t agree_feature_interface_turns(std::vector<InterfaceSide>& sides, double max_length) {
  const std::size_t n = sides.size();
  std::vector<std::unordered_map<std::int32_t, std::int32_t>> local(n);  // shared vertex -> vertex, on interfaces
  for (std::size_t p = 0; p < n; ++p) {
    if (!sides[p].layout) continue;
    for (const TriChain& ch : sides[p].mesh->chains)
      if (ch.interface >= 0)
        for (std::int32_t v : ch.vertices)
          if (const std::int32_t g = (*sides[p].global_vertex)[static_cast<std::size_t>(v)]; g >= 0) local[p].emplace(g, v);
  }
  // The edges of an open chain between the vertices at positions a and b (either order).
  auto stretch = [](int a, int b) {
    std::vector<int> edges;
    for (int e = std::min(a, b); e < std::max(a, b); ++e) edges.push_back(e);
    return edges;
  };
  auto position = [&](const TriChain& ch, std::int32_t v) {
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
      // q's chain along the same interface: the one holding both ends of ch.
      const auto qa = local[q].find((*sides[p].global_vertex)[static_cast<std::size_t>(ch.vertices.front())]);
      const auto qb = local[q].find((*sides[p].global_vertex)[static_cast<std::size_t>(ch.vertices.back())]);
      if (qa == local[q].end() || qb == local[q].end()) continue;
      int qc = -1;
      for (std::size_t d = 0; d < sides[q].mesh->chains.size() && qc < 0; ++d) {
        const TriChain& o = sides[q].mesh->chains[d];
        if (o.interface == static_cast<int>(p) && !o.closed && position(o, qa->second) >= 0 && position(o, qb->second) >= 0 &&
            o.vertices.size() == ch.vertices.size())
          qc = static_cast<int>(d);
      }
      if (qc < 0) continue;
      const TriChain& och = sides[q].mesh->chains[static_cast<std::size_t>(qc)];
      struct Mismatch {
        int i;  // position in ch
        int d;  // quads at the node less four
      };
      auto mismatch_at = [&](int i) {
        const std::int32_t v = ch.vertices[static_cast<std::size_t>(i)];
        const auto it = local[q].find((*sides[p].global_vertex)[static_cast<std::size_t>(v)]);
        if (it == local[q].end()) return 0;
        const int a = quads_at_break(*sides[p].layout, v), b = quads_at_break(*sides[q].layout, it->second);
        return a == 0 || b == 0 ? 0 : a + b - 4;
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
          const TriChain& xc = x == p ? ch : och;
          const int xchain = x == p ? static_cast<int>(c) : qc;
          const std::int32_t v1 = x == p ? ch.vertices[static_cast<std::size_t>(first.i)]
                                         : local[q].at((*sides[p].global_vertex)[static_cast<std::size_t>(ch.vertices[static_cast<std::size_t>(first.i)])]);
          const std::int32_t v2 = x == p ? ch.vertices[static_cast<std::size_t>(i)]
                                         : local[q].at((*sides[p].global_vertex)[static_cast<std::size_t>(ch.vertices[static_cast<std::size_t>(i)])]);
          const int a = position(xc, v1), b = position(xc, v2);
          if (a < 0 || b < 0) continue;
          const std::vector<int> edges = stretch(a, b);
          double length = 0.0;
          const std::vector<Vec2>& y = *sides[x].deformed;
          for (int e : edges)
            length += distance(y[static_cast<std::size_t>(xc.vertices[static_cast<std::size_t>(e)])],
                               y[static_cast<std::size_t>(xc.vertices[static_cast<std::size_t>(e + 1)])]);
          if (length > max_length) continue;
          for (const int delta : {1, 3}) {
            Layout trial = *sides[x].layout;
            for (int e : edges) {
              int& label = trial.chain_labels[static_cast<std::size_t>(xchain)][static_cast<std::size_t>(e)];
              label = (label + delta) % 4;
            }
            try {
              add_straight_breaks(trial, *sides[x].mesh, y, std::vector<std::uint8_t>(sides[x].mesh->vertices.size(), 0),
                                  sides[x].name);
            } catch (const MeshingError&) {
              continue;
            }
            const std::int32_t o1 = x == p ? local[q].at((*sides[p].global_vertex)[static_cast<std::size_t>(v1)]) : ch.vertices[static_cast<std::size_t>(first.i)];
            const std::int32_t o2 = x == p ? local[q].at((*sides[p].global_vertex)[static_cast<std::size_t>(v2)]) : ch.vertices[static_cast<std::size_t>(i)];
            const Layout& other = *sides[x == p ? q : p].layout;
            const int n1 = quads_at_break(trial, v1), n2 = quads_at_break(trial, v2);
            if (n1 == 0 || n2 == 0 || n1 + quads_at_break(other, o1) != 4 || n2 + quads_at_break(other, o2) != 4) continue;
            std::size_t corners = 0;  // corners left on side x
            for (std::int32_t bv : trial.break_vertex) corners += quads_at_break(trial, bv) != 2;
            if (!best || corners < best->corners || (corners == best->corners && length < best->length))
              best = Trial{x, std::move(trial), corners, length};
          }
        }
        if (!best) continue;
        *sides[best->x].layout = std::move(best->layout);
        ++agreed;
      }
    }
  }
  return agreed;
}

}  // namespace polysquare
