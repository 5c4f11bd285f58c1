#include "map/interface_turns.h"

#include <map>
#include <utility>

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

}  // namespace polysquare
