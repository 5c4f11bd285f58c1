#include "polysquare/map/layout.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "polysquare/core/error.h"

namespace polysquare {
namespace {

const Vec2 kLabelDir[4] = {{1, 0}, {0, 1}, {-1, 0}, {0, -1}};
constexpr double kForbidden = 1e300;  // cost of a label (change) that must not happen

// Labels of one chain by dynamic programming: each edge pays its length times (1 - cos) of the angle between
// its deformed direction and the label's axis direction; a label change into edge i pays change_cost[i] (nothing at a
// sharp input vertex, where a corner is natural; kForbidden forbids it); U-turns are forbidden. This removes the staircases that the
// L1 term alone favours and the short runs that would become spurious corners. A closed chain is solved once
// per label of its first edge, with the running number of quarter turns in the state, so that it closes with
// exactly `required_turns` (+4 counter-clockwise, -4 clockwise): every loop becomes a valid orthogonal polygon.
std::vector<int> label_chain(const std::vector<Vec2>& edge_vec, const std::vector<double>& change_cost,
                             const std::vector<std::uint8_t>& allowed, bool closed, int required_turns) {
  const int m = static_cast<int>(edge_vec.size());
  constexpr double kBig = kForbidden;
  constexpr int kMaxTurns = 48;  // |running turns| bound: coastlines with many bays wind far before closing
  constexpr int kT = 2 * kMaxTurns + 1;
  auto edge_cost = [&](int i, int l) {
    if (!(allowed[i] >> l & 1)) return kBig;
    return norm(edge_vec[i]) - dot(edge_vec[i], kLabelDir[l]);  // = length * (1 - cos)
  };
  auto turn = [](int from, int to) { const int d = (to - from + 4) % 4; return d == 0 ? 0 : (d == 1 ? 1 : (d == 3 ? -1 : 99)); };
  auto change = [&](int i, int from, int to) {  // cost of the transition into edge i
    if (from == to) return 0.0;
    return change_cost[i];
  };
  const int turn_states = closed ? kT : 1;
  std::vector<int> best_labels;
  double best_total = kBig;
  const int first_options = closed ? 4 : 1;
  // cost[i][l][t], back[i][l][t] = previous (label, turns) packed as label * kT + t.
  std::vector<double> cost(static_cast<std::size_t>(m) * 4 * turn_states);
  std::vector<int> back(cost.size());
  auto at = [&](int i, int l, int t) { return (static_cast<std::size_t>(i) * 4 + l) * turn_states + t; };
  for (int f = 0; f < first_options; ++f) {
    std::fill(cost.begin(), cost.end(), kBig);
    const int t0 = closed ? kMaxTurns : 0;
    for (int l = 0; l < 4; ++l)
      if (!closed || l == f) cost[at(0, l, t0)] = edge_cost(0, l);
    for (int i = 1; i < m; ++i)
      for (int k = 0; k < 4; ++k)
        for (int t = 0; t < turn_states; ++t) {
          const double base = cost[at(i - 1, k, t)];
          if (base >= kBig) continue;
          for (int l = 0; l < 4; ++l) {
            const int dt = turn(k, l);
            if (dt == 99) continue;  // U-turn
            const int nt = closed ? t + dt : 0;
            if (nt < 0 || nt >= turn_states) continue;
            const double c = base + change(i, k, l) + edge_cost(i, l);
            if (c >= kBig) continue;
            if (c < cost[at(i, l, nt)]) { cost[at(i, l, nt)] = c; back[at(i, l, nt)] = k * kT + t; }
          }
        }
    int last = -1, last_t = 0;
    double total = kBig;
    for (int l = 0; l < 4; ++l)
      for (int t = 0; t < turn_states; ++t) {
        double c = cost[at(m - 1, l, t)];
        if (c >= kBig) continue;
        if (closed) {
          const int dt = turn(l, f);
          if (dt == 99 || t - kMaxTurns + dt != required_turns) continue;
          c += change(0, l, f);
          if (c >= kBig) continue;
        }
        if (c < total) { total = c; last = l; last_t = t; }
      }
    if (last < 0 || total >= best_total) continue;
    best_total = total;
    best_labels.assign(m, 0);
    for (int i = m - 1; i >= 0; --i) {
      best_labels[i] = last;
      if (i > 0) {
        const int packed = back[at(i, last, last_t)];
        last = packed / kT;
        last_t = packed % kT;
      }
    }
  }
  return best_labels;
}

// Break points from the flags and the straight sides between them, along every chain with its labels.
void set_breaks(Layout& layout, const TriMesh& mesh, const std::vector<Vec2>& deformed,
                const std::vector<std::uint8_t>& is_break, const std::vector<std::uint8_t>& corner,
                const std::string& part_name) {
  const std::size_t nv = mesh.vertices.size();
  layout.vertex_break.assign(nv, -1);
  layout.break_vertex.clear();
  layout.break_is_corner.clear();
  layout.segments.clear();
  for (std::size_t v = 0; v < nv; ++v) {
    if (!is_break[v]) continue;
    layout.vertex_break[v] = static_cast<std::int32_t>(layout.break_vertex.size());
    layout.break_vertex.push_back(static_cast<std::int32_t>(v));
    layout.break_is_corner.push_back(corner[v]);
  }

  for (std::size_t c = 0; c < mesh.chains.size(); ++c) {
    const TriChain& ch = mesh.chains[c];
    const int n = static_cast<int>(ch.vertices.size());
    const int m = ch.closed ? n : n - 1;
    const auto& labels = layout.chain_labels[c];
    int start = -1;
    for (int i = 0; i < n && start < 0; ++i)
      if (is_break[ch.vertices[i]]) start = i;
    if (start < 0)
      throw MeshingError(part_name + ": " + chain_name(ch) + " has no corner");
    int first = start;
    for (int k = 1; k <= (ch.closed ? m : m - start); ++k) {
      const int i = ch.closed ? (start + k) % n : start + k;
      if (!is_break[ch.vertices[i]]) continue;
      LayoutSegment s;
      s.chain = static_cast<int>(c);
      s.first = first;
      s.count = (i - first + n) % n == 0 ? n : (i - first + n) % n;
      if (!ch.closed) s.count = i - first;
      s.label = labels[first % m];
      // Chord rather than arc length: a side that still zig-zags after the deformation would otherwise get
      // far too many elements.
      s.target = distance(deformed[ch.vertices[first]], deformed[ch.vertices[i]]);
      s.break_a = layout.vertex_break[ch.vertices[first]];
      s.break_b = layout.vertex_break[ch.vertices[i]];
      layout.segments.push_back(s);
      first = i;
    }
  }
}

}  // namespace

Layout build_layout(const TriMesh& mesh, const std::vector<Vec2>& original, const std::vector<Vec2>& deformed,
                    const LayoutOptions& options, const std::string& part_name) {
  const std::size_t nv = mesh.vertices.size();
  Layout layout;
  const std::vector<std::uint8_t> corner = corner_vertices(mesh, original, options.corner_threshold_deg);
  std::vector<std::uint8_t> is_break = corner;

  // Sequences labelled together: the chains of each loop (a PPM subregion's boundary made of ring pieces and
  // interfaces), so that the loop closes with +-4 quarter turns, and every other chain alone.
  std::vector<std::vector<int>> sequences = mesh.loops;
  std::vector<std::uint8_t> in_loop(mesh.chains.size(), 0);
  for (const auto& loop : mesh.loops)
    for (int c : loop) in_loop[static_cast<std::size_t>(c)] = 1;
  for (std::size_t c = 0; c < mesh.chains.size(); ++c)
    if (!in_loop[c]) sequences.push_back({static_cast<int>(c)});

  layout.chain_labels.resize(mesh.chains.size());
  std::vector<std::uint8_t> used_dirs(nv, 0);  // per vertex, the lattice directions labelled chains leave it by
  for (const auto& seq : sequences) {
    const bool closed = seq.size() > 1 || mesh.chains[static_cast<std::size_t>(seq.front())].closed;
    std::vector<std::int32_t> verts;  // edge i runs from verts[i] to verts[i + 1] (cyclic when closed)
    std::vector<Vec2> edge_vec;
    std::vector<double> change_cost;  // of a label change into each edge
    for (int c : seq) {
      const TriChain& ch = mesh.chains[static_cast<std::size_t>(c)];
      const int n = static_cast<int>(ch.vertices.size());
      const int m = ch.closed ? n : n - 1;
      for (int i = 0; i < m; ++i) {
        const std::int32_t v = ch.vertices[i];
        verts.push_back(v);
        edge_vec.push_back(deformed[ch.vertices[(i + 1) % n]] - deformed[v]);
        // Free at corners; an interface is one straight side on both of its subregions (so both get the same
        // nodes) unless bending is allowed, at its own cost.
        if (corner[v]) change_cost.push_back(0.0);
        else if (ch.interface < 0) change_cost.push_back(options.label_change_cost);
        else change_cost.push_back(options.straight_interfaces ? kForbidden : options.interface_change_cost);
      }
      if (!closed) verts.push_back(ch.vertices.back());
    }
    const int m = static_cast<int>(edge_vec.size());
    const int nverts = static_cast<int>(verts.size());
    const std::string what = seq.size() > 1 ? "the boundary loop through " + chain_name(mesh.chains[static_cast<std::size_t>(seq.front())])
                                            : chain_name(mesh.chains[static_cast<std::size_t>(seq.front())]);
    // Closed sequences turn by +4 quarter turns when counter-clockwise in the deformed plane (outer rings, and
    // feature loops drawn that way), -4 when clockwise (holes).
    double area = 0.0;
    for (int i = 0; i < nverts; ++i) area += cross(deformed[verts[i]], deformed[verts[(i + 1) % nverts]]);
    // An open chain must not leave its end points along a direction a labelled chain already takes there (a
    // feature leaving the boundary along the boundary's side would overlap it); relaxed if nothing else fits.
    std::vector<std::uint8_t> allowed(static_cast<std::size_t>(m), 0xF);
    if (!closed && m > 0) {
      allowed.front() = static_cast<std::uint8_t>(0xF & ~used_dirs[verts.front()]);
      std::uint8_t back = 0xF;
      for (int l = 0; l < 4; ++l)
        if (used_dirs[verts.back()] >> ((l + 2) % 4) & 1) back = static_cast<std::uint8_t>(back & ~(1 << l));
      allowed.back() = static_cast<std::uint8_t>(allowed.back() & back);
    }
    std::vector<int> labels =
        label_chain(edge_vec, change_cost, allowed, closed, area >= 0 ? 4 : -4);
    if (labels.empty() && !closed) {
      std::fill(allowed.begin(), allowed.end(), 0xF);
      labels = label_chain(edge_vec, change_cost, allowed, closed, 0);
    }
    for (int i = 0; i < m && !labels.empty(); ++i) {
      used_dirs[verts[i]] |= static_cast<std::uint8_t>(1 << labels[i]);
      used_dirs[verts[(i + 1) % nverts]] |= static_cast<std::uint8_t>(1 << ((labels[i] + 2) % 4));
    }
    if (labels.empty())
      throw MeshingError(part_name + ": no axis labelling of " + what + " closes into an orthogonal polygon");
    int turning = 0;
    for (int i = 0; i < m; ++i) {
      if (!closed && i == 0) continue;
      const int prev = labels[(i + m - 1) % m];
      if (prev == labels[i]) continue;
      is_break[verts[i]] = 1;
      const int diff = (labels[i] - prev + 4) % 4;
      if (diff == 2)
        throw MeshingError(part_name + ": the poly-square of " + what + " folds back on itself near (" +
                           std::to_string(original[verts[i]].x) + ", " + std::to_string(original[verts[i]].y) + ")");
      turning += diff == 1 ? 1 : -1;
    }
    if (closed && std::abs(turning) != 4)
      throw MeshingError(part_name + ": the poly-square of " + what + " turns by " + std::to_string(turning) +
                         " quarter turns instead of 4; one poly-square cannot represent this region");
    int offset = 0;
    for (int c : seq) {
      const TriChain& ch = mesh.chains[static_cast<std::size_t>(c)];
      const int cm = ch.closed ? static_cast<int>(ch.vertices.size()) : static_cast<int>(ch.vertices.size()) - 1;
      layout.chain_labels[static_cast<std::size_t>(c)].assign(labels.begin() + offset, labels.begin() + offset + cm);
      offset += cm;
    }
  }

  set_breaks(layout, mesh, deformed, is_break, corner, part_name);
  return layout;
}

}  // namespace polysquare

namespace polysquare {

void add_straight_breaks(Layout& layout, const TriMesh& mesh, const std::vector<Vec2>& deformed,
                         const std::vector<std::uint8_t>& extra, const std::string& part_name) {
  std::vector<std::uint8_t> is_break = extra, corner(mesh.vertices.size(), 0);
  for (std::size_t b = 0; b < layout.break_vertex.size(); ++b) {
    is_break[static_cast<std::size_t>(layout.break_vertex[b])] = 1;
    corner[static_cast<std::size_t>(layout.break_vertex[b])] = layout.break_is_corner[b];
  }
  set_breaks(layout, mesh, deformed, is_break, corner, part_name);
}

}  // namespace polysquare
