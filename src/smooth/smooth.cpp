#include "polysquare/smooth/smooth.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>

#include "polysquare/core/quad_topology.h"

namespace polysquare {
namespace {

// Shape measure the smoother maximizes: the worst corner scaled Jacobian (sj), capped by 3 / edge ratio so that a
// quad with a collapsed edge (angles fine, one edge near zero) counts as bad too. 3 leaves edge ratios up to 3
// alone: on letter_M it gives SJ min 0.80 with edge ratio max 3.7 (2: 0.60 / 3.3; 4: 0.87 / 4.6).
// 3 / edge ratio from the squared shortest and longest edges (-1 for a quad with no length).
double edge_ratio_cap(double lmin, double lmax) { return lmax > 0 ? 3.0 * std::sqrt(lmin / lmax) : -1.0; }

double quad_shape(const QuadMesh& mesh, std::size_t q, double sj) {
  const auto& quad = mesh.quads[q];
  double lmin = INFINITY, lmax = 0.0;  // squared edge lengths: one sqrt per quad, not four hypot
  for (int k = 0; k < 4; ++k) {
    const Vec2 e = mesh.nodes[quad[(k + 1) % 4]] - mesh.nodes[quad[k]];
    lmin = std::min(lmin, dot(e, e));
    lmax = std::max(lmax, dot(e, e));
  }
  return std::min(sj, edge_ratio_cap(lmin, lmax));
}

// Node -> incident quads (core/quad_topology.h), with the measures the smoother reads around a node.
struct Incidence : NodeQuads {
  explicit Incidence(const QuadMesh& mesh) : NodeQuads(node_quads(mesh)) {}
  // Folded quads around v first, then the worst shape: lifting the worst of several folded quads may fold
  // another, so a move that leaves more folded quads around the node is never better.
  struct Score {
    std::size_t folded;
    double worst;
    double min_sj;  // worst corner scaled Jacobian alone (the feature repair's floor reads it)
    bool better_than(const Score& o, double eps = 0.0) const {
      return folded != o.folded ? folded < o.folded : worst > o.worst + eps;
    }
  };
  Score score(const QuadMesh& mesh, std::size_t v) const {
    Score s{0, 1.0, 1.0};
    for (std::size_t k = offset[v]; k < offset[v + 1]; ++k) {
      const double sj = quad_min_corner_sj(mesh, quads[k]);
      s.folded += sj <= 0.0;
      s.min_sj = std::min(s.min_sj, sj);
      s.worst = std::min(s.worst, quad_shape(mesh, quads[k], sj));
    }
    return s;
  }
  double mean_edge(const QuadMesh& mesh, std::size_t v) const {
    double len = 0.0;
    int n = 0;
    for (std::size_t k = offset[v]; k < offset[v + 1]; ++k) {
      const auto& q = mesh.quads[quads[k]];
      for (int c = 0; c < 4; ++c, ++n) len += distance(mesh.nodes[q[c]], mesh.nodes[q[(c + 1) % 4]]);
    }
    return n ? len / n : 0.0;
  }
};

// An input polyline with cumulative arc length, for positions by arc parameter.
struct Curve {
  std::vector<Vec2> pts;
  std::vector<double> cum;  // cum[i] = arc length at pts[i]; closed curves repeat pts[0] at the end
  bool closed = false;
  Curve(const std::vector<Vec2>& p, bool is_closed) : pts(p), closed(is_closed) {
    if (closed) pts.push_back(p.front());
    cum.assign(pts.size(), 0.0);
    for (std::size_t i = 1; i < pts.size(); ++i) cum[i] = cum[i - 1] + distance(pts[i - 1], pts[i]);
  }
  double length() const { return cum.back(); }
  Vec2 at(double s) const {
    if (closed) s = s - std::floor(s / length()) * length();
    s = std::clamp(s, 0.0, length());
    const std::size_t i = static_cast<std::size_t>(std::upper_bound(cum.begin(), cum.end(), s) - cum.begin());
    const std::size_t j = std::clamp<std::size_t>(i, 1, pts.size() - 1);
    const double seg = cum[j] - cum[j - 1];
    return seg > 0 ? lerp(pts[j - 1], pts[j], (s - cum[j - 1]) / seg) : pts[j];
  }
  // Largest distance from the curve between arc parameters s0 < s1 (unwrapped on closed curves) to the chord
  // joining their points: how far the mesh edge between two nodes on this curve strays from it.
  double chord_deviation(double s0, double s1) const {
    const Vec2 a = at(s0), b = at(s1);
    const std::size_t n = closed ? pts.size() - 1 : pts.size();
    const double L = length();
    double shift = 0.0;
    if (closed && L > 0) {
      shift = std::floor(s0 / L) * L;
      s0 -= shift;
      s1 -= shift;
    }
    double worst = 0.0;
    for (int lap = 0; lap < (closed ? 2 : 1); ++lap) {
      const double base = lap * L;
      for (auto i = static_cast<std::size_t>(std::upper_bound(cum.begin(), cum.begin() + static_cast<std::ptrdiff_t>(n), s0 - base) - cum.begin());
           i < n && cum[i] + base < s1; ++i)
        worst = std::max(worst, point_segment_distance(pts[i], a, b));
    }
    return worst;
  }
  double project(Vec2 p) const {
    double best = INFINITY, s = 0.0;
    for (std::size_t i = 1; i < pts.size(); ++i) {
      const Vec2 d = pts[i] - pts[i - 1];
      const double l2 = dot(d, d);
      const double t = l2 > 0 ? std::clamp(dot(p - pts[i - 1], d) / l2, 0.0, 1.0) : 0.0;
      const Vec2 e = p - (pts[i - 1] + t * d);
      const double dist2 = dot(e, e);  // squared: the nearest is the same, without a hypot per segment
      if (dist2 < best) { best = dist2; s = cum[i - 1] + t * (cum[i] - cum[i - 1]); }
    }
    return s;
  }
};

// Colours such that two nodes of one quad never share a colour: a colour's nodes can move in parallel, since
// each node's move reads and changes only its own incident quads. Greedy in node order, so deterministic.
std::vector<std::vector<std::int32_t>> colour_classes(const QuadMesh& mesh, const Incidence& inc,
                                                      const std::vector<std::uint8_t>& movable) {
  const std::size_t nn = mesh.nodes.size();
  std::vector<int> colour(nn, -1);
  std::vector<std::vector<std::int32_t>> classes;
  std::vector<char> taken;
  for (std::size_t v = 0; v < nn; ++v) {
    if (!movable[v]) continue;
    taken.assign(classes.size() + 1, 0);
    for (std::size_t k = inc.offset[v]; k < inc.offset[v + 1]; ++k)
      for (auto w : mesh.quads[inc.quads[k]])
        if (colour[w] >= 0) taken[static_cast<std::size_t>(colour[w])] = 1;
    int c = 0;
    while (taken[static_cast<std::size_t>(c)]) ++c;
    colour[v] = c;
    if (static_cast<std::size_t>(c) == classes.size()) classes.emplace_back();
    classes[static_cast<std::size_t>(c)].push_back(static_cast<std::int32_t>(v));
  }
  return classes;
}

// Runs `step(v)` for every node, colour by colour, the nodes of a colour in parallel.
// The quads around one node with what moving it leaves unchanged (each quad's corner opposite the node and its two
// edges away from it), so that a trial position computes only the rest: the pattern search tries about a hundred
// positions per node. Gives Incidence::score's values bit for bit (the same operations on the same operands).
struct Star {
  struct Quad {
    Vec2 a, b, c;          // the quad's nodes after v, in order
    double far_corner;     // corner scaled Jacobian at b
    double far_lmin, far_lmax;  // squared lengths of the edges a-b and b-c
  };
  std::vector<Quad> quads;
  Star(const QuadMesh& mesh, const Incidence& inc, std::int32_t v) {
    for (std::size_t k = inc.offset[v]; k < inc.offset[v + 1]; ++k) {
      const auto& q = mesh.quads[inc.quads[k]];
      const int i = static_cast<int>(std::find(q.begin(), q.end(), v) - q.begin());
      Quad s;
      s.a = mesh.nodes[q[(i + 1) % 4]];
      s.b = mesh.nodes[q[(i + 2) % 4]];
      s.c = mesh.nodes[q[(i + 3) % 4]];
      s.far_corner = corner_sj(s.a, s.b, s.c);
      const Vec2 ab = s.b - s.a, bc = s.c - s.b;
      s.far_lmin = std::min(dot(ab, ab), dot(bc, bc));
      s.far_lmax = std::max(dot(ab, ab), dot(bc, bc));
      quads.push_back(s);
    }
  }
  // The score with v at p, into s, when it is better than `best` (Score::better_than with eps). A trial stops at
  // the first quad that shows it cannot be: the folded count only grows and the worst corner only falls as quads
  // are added; with nothing folded to beat, every corner and edge ratio must clear best.worst (> 0), so the first
  // one that does not ends it. Most trials of the pattern search fail, most of them at once.
  bool better_at(Vec2 p, const Incidence::Score& best, double eps, Incidence::Score& s) const {
    s = {0, 1.0, 1.0};
    const double floor = best.worst + eps;
    const bool each = best.folded == 0 && best.worst > 0.0;
    auto fails = [&](double value) { return each && value <= floor; };
    for (const Quad& q : quads) {
      if (fails(q.far_corner)) return false;
      const double c1 = corner_sj(q.c, p, q.a);
      if (fails(c1)) return false;
      const double c2 = corner_sj(p, q.a, q.b);
      if (fails(c2)) return false;
      const double c3 = corner_sj(q.b, q.c, p);
      if (fails(c3)) return false;
      const double sj = std::min(std::min(c1, c2), std::min(q.far_corner, c3));
      const Vec2 ea = q.a - p, ec = p - q.c;
      const double lmin = std::min({q.far_lmin, dot(ea, ea), dot(ec, ec)});
      const double lmax = std::max({q.far_lmax, dot(ea, ea), dot(ec, ec)});
      s.folded += sj <= 0.0;
      s.min_sj = std::min(s.min_sj, sj);
      s.worst = std::min(s.worst, std::min(sj, edge_ratio_cap(lmin, lmax)));
      if (s.folded > best.folded || (s.folded == best.folded && !(s.worst > floor))) return false;
    }
    return s.better_than(best, eps);
  }
};

template <typename F>
void for_each_by_colour(const std::vector<std::vector<std::int32_t>>& classes, std::int64_t& clock, F step) {
  for (const auto& cls : classes) {
    ++clock;
    oneapi::tbb::parallel_for(oneapi::tbb::blocked_range<std::size_t>(0, cls.size(), 256),
                              [&](const oneapi::tbb::blocked_range<std::size_t>& r) {
                                for (std::size_t i = r.begin(); i != r.end(); ++i) step(cls[i]);
                              });
  }
}

// Gauss-Seidel bookkeeping, in colour steps of for_each_by_colour's clock: when each node last moved and when a
// sweep last visited it. A node whose quads did not change since its last visit would decide the same again (its
// move reads nothing else), so it is skipped: same mesh, a fraction of the work once most nodes have settled.
struct Visits {
  std::vector<std::int64_t> moved, visited;
  explicit Visits(std::size_t nn) : moved(nn, -1), visited(nn, -1) {}
  // True when no node of v's quads (v itself too, if `self`) moved since v's last visit.
  bool settled(const QuadMesh& mesh, const Incidence& inc, std::int32_t v, bool self) const {
    const std::int64_t seen = visited[v];
    if (seen < 0) return false;
    for (std::size_t k = inc.offset[v]; k < inc.offset[v + 1]; ++k)
      for (std::int32_t w : mesh.quads[inc.quads[k]])
        if ((self || w != v) && moved[w] >= seen) return false;
    return true;
  }
};

// A node that slides: its curve and its two neighbours along the curve.
struct Slider {
  int curve = -1;
  std::int32_t prev = -1, next = -1;
};

// What the sweeps share: the mesh they move, its node -> quad incidence, the nodes that move freely in the plane
// and for_each_by_colour's clock.
struct Sweeps {
  QuadMesh& mesh;
  const Incidence& inc;
  const SmoothOptions& options;
  const std::vector<std::uint8_t>& interior;
  std::int64_t clock = 0;
};

// Per-node results of an averaging sweep, reduced in node order afterwards so that the stopping test is
// deterministic.
struct AverageResults {
  std::vector<double> moved_by, edge_of;
  std::vector<std::uint8_t> moved_flag;
  explicit AverageResults(std::size_t nn) : moved_by(nn, 0.0), edge_of(nn, 0.0), moved_flag(nn, 0) {}
};

// Moves interior node v to the mean of its edge neighbours when that improves its score; records the move and
// v's mean edge length in `out`.
void average_node(Sweeps& sw, Visits& lap, std::int32_t v, AverageResults& out) {
  QuadMesh& mesh = sw.mesh;
  const Incidence& inc = sw.inc;
  std::int32_t nbrs[32];
  int n = 0;
  for (std::size_t k = inc.offset[v]; k < inc.offset[v + 1]; ++k) {
    const auto& q = mesh.quads[inc.quads[k]];
    const int at = static_cast<int>(std::find(q.begin(), q.end(), v) - q.begin());
    for (std::int32_t w : {q[(at + 1) % 4], q[(at + 3) % 4]})
      if (n < 32 && std::find(nbrs, nbrs + n, w) == nbrs + n) nbrs[n++] = w;
  }
  Vec2 mean{};
  double edge = 0.0;
  const Vec2 old = mesh.nodes[v];
  for (int i = 0; i < n; ++i) {
    mean = mean + mesh.nodes[nbrs[i]];
    edge += distance(old, mesh.nodes[nbrs[i]]);
  }
  mean = (1.0 / n) * mean;
  out.edge_of[v] = edge / n;
  out.moved_flag[v] = 0;
  out.moved_by[v] = 0.0;
  // Its neighbours unmoved, v is at their mean already or was refused it.
  if (lap.settled(mesh, inc, v, false)) return;
  lap.visited[v] = sw.clock;
  const Incidence::Score before = inc.score(mesh, v);
  mesh.nodes[v] = mean;
  if (inc.score(mesh, v).better_than(before)) {
    out.moved_flag[v] = 1;
    out.moved_by[v] = distance(old, mean);
    lap.moved[v] = sw.clock;
  } else {
    mesh.nodes[v] = old;
    out.moved_flag[v] = 0;
    out.moved_by[v] = 0.0;
  }
}

// Gauss-Seidel sweeps of guarded Laplacian smoothing of the interior nodes, until converged.
void average_sweeps(Sweeps& sw, Visits& lap, SmoothStats& stats) {
  const std::size_t nn = sw.mesh.nodes.size();
  const auto interior_classes = colour_classes(sw.mesh, sw.inc, sw.interior);
  AverageResults out(nn);
  for (int sweep = 0; sweep < sw.options.iterations; ++sweep) {
    for_each_by_colour(interior_classes, sw.clock, [&](std::int32_t v) { average_node(sw, lap, v, out); });
    std::size_t moved = 0;
    double largest_move = 0.0, edge_sum = 0.0;
    for (std::size_t v = 0; v < nn; ++v) {
      if (!sw.interior[v]) continue;
      moved += out.moved_flag[v];
      largest_move = std::max(largest_move, out.moved_by[v]);
      edge_sum += out.edge_of[v];
    }
    stats.sweeps = sweep + 1;
    stats.moves += moved;
    // Converged when no node moved by more than a small fraction of the mean edge.
    if (moved == 0 || largest_move < sw.options.converged_fraction * edge_sum / static_cast<double>(nn)) break;
  }
}

// Curves of sliding nodes: rings then feature curves of the region, each node with its curve neighbours.
struct SlideCurves {
  std::vector<Curve> curves;
  std::vector<Slider> slider;
  int feature_base = 0;  // index of the first feature curve (the rings come first)
  bool slides(const QuadMesh& mesh, std::size_t v) const {
    const NodeKind k = mesh.node_kind[v];
    return (k == NodeKind::boundary || k == NodeKind::feature) && slider[v].curve >= 0 && slider[v].prev >= 0 &&
           slider[v].next >= 0;
  }
};

SlideCurves slide_curves(const QuadMesh& mesh, const Region* region, bool slide_on_curves, bool kinds) {
  SlideCurves sc;
  sc.slider.resize(mesh.nodes.size());
  if (region && slide_on_curves && kinds) {
    for (const Ring& r : region->rings) sc.curves.emplace_back(r.points, true);
    for (const FeatureCurve& f : region->features) sc.curves.emplace_back(f.points, f.closed);
    auto link = [&](const std::vector<std::array<std::int32_t, 2>>& edges, const std::vector<std::int32_t>& tag, int base) {
      for (std::size_t e = 0; e < edges.size(); ++e) {
        const int c = base + tag[e];
        for (int side = 0; side < 2; ++side) {
          Slider& s = sc.slider[edges[e][side]];
          s.curve = c;
          (side == 0 ? s.next : s.prev) = edges[e][1 - side];
        }
      }
    };
    link(mesh.boundary_edges, mesh.boundary_edge_ring, 0);
    link(mesh.feature_edges, mesh.feature_edge_curve, static_cast<int>(region->rings.size()));
  }
  sc.feature_base = region ? static_cast<int>(region->rings.size()) : 0;
  return sc;
}

const Vec2 search_dirs[8] = {{1, 0}, {0.7071067811865476, 0.7071067811865476}, {0, 1}, {-0.7071067811865476, 0.7071067811865476},
                             {-1, 0}, {-0.7071067811865476, -0.7071067811865476}, {0, -1}, {0.7071067811865476, -0.7071067811865476}};

// Pattern search in the plane: 12 levels of the eight directions around the best position so far, the step halved
// when none is better.
void search_in_plane(QuadMesh& mesh, const Star& star, std::int32_t v, double step, Incidence::Score& best) {
  for (int level = 0; level < 12; ++level) {
    const Vec2 centre = mesh.nodes[v];
    Vec2 best_p = centre;
    for (const Vec2& d : search_dirs) {
      const Vec2 p = centre + step * d;
      Incidence::Score w;
      if (star.better_at(p, best, 1e-12, w)) { best = w; best_p = p; }
    }
    mesh.nodes[v] = best_p;
    if (best_p == centre) step *= 0.5;
  }
}

// A sliding node's place on its curve: arc parameter s, strictly between its curve neighbours' lo < hi.
struct CurveSpan {
  const Curve& c;
  double s, lo, hi, margin;
  // How far the mesh edges beside a node at t would stray from the curve.
  double deviation(double t) const { return std::max(c.chord_deviation(lo, t), c.chord_deviation(t, hi)); }
};

std::optional<CurveSpan> curve_span(const QuadMesh& mesh, const Curve& c, const Slider& sl, std::int32_t v) {
  const double s = c.project(mesh.nodes[v]);
  auto unwrap = [&](double t) {
    if (!c.closed) return t;
    const double L = c.length();
    while (t - s > 0.5 * L) t -= L;
    while (s - t > 0.5 * L) t += L;
    return t;
  };
  double lo = unwrap(c.project(mesh.nodes[sl.prev])), hi = unwrap(c.project(mesh.nodes[sl.next]));
  if (lo > hi) std::swap(lo, hi);
  if (!(lo < s && s < hi)) return std::nullopt;
  return CurveSpan{c, s, lo, hi, 0.05 * (hi - lo)};
}

// A feature node whose mesh edges stray beyond the tolerance moves towards the position that balances the two
// edges, if the worst corner around it stays above the floor. Returns whether it moved; `allowed` is the deviation
// its later slides may reach.
bool balance_feature_chords(QuadMesh& mesh, const Incidence& inc, std::int32_t v, CurveSpan& span, double tolerance,
                            double floor, const Incidence::Score& before, Incidence::Score& best, double& allowed) {
  const Curve& c = span.c;
  const double lo = span.lo, hi = span.hi, s = span.s;
  const double now = span.deviation(s);
  allowed = std::max(tolerance, now);
  if (!(now > tolerance)) return false;
  double a = lo, b = hi;  // bisection on the sign of (left deviation - right deviation)
  for (int it = 0; it < 40; ++it) {
    const double mid = 0.5 * (a + b);
    (c.chord_deviation(lo, mid) < c.chord_deviation(mid, hi) ? a : b) = mid;
  }
  const double balanced = std::clamp(0.5 * (a + b), lo + span.margin, hi - span.margin);
  const Vec2 old = mesh.nodes[v];
  for (double frac : {1.0, 0.5, 0.25}) {
    const double cand = s + frac * (balanced - s);
    const double dev = span.deviation(cand);
    if (!(dev < now - 1e-12)) continue;
    mesh.nodes[v] = c.at(cand);
    const Incidence::Score moved = inc.score(mesh, v);
    if (moved.min_sj >= floor && moved.folded <= before.folded) {
      span.s = cand;
      allowed = std::max(tolerance, dev);
      best = moved;
      return true;
    }
    mesh.nodes[v] = old;
  }
  return false;
}

// Pattern search along the curve, within the span's margins and, when bounded, the allowed chord deviation.
void search_on_curve(QuadMesh& mesh, const Star& star, std::int32_t v, CurveSpan& span, bool bounded,
                     double allowed, double step, Incidence::Score& best) {
  double& s = span.s;
  for (int level = 0; level < 12; ++level) {
    double best_s = s;
    for (double cand : {s - step, s + step}) {
      if (cand <= span.lo + span.margin || cand >= span.hi - span.margin) continue;
      if (bounded && span.deviation(cand) > allowed) continue;
      Incidence::Score w;
      if (star.better_at(span.c.at(cand), best, 1e-12, w)) { best = w; best_s = cand; }
    }
    if (best_s != s) { s = best_s; mesh.nodes[v] = span.c.at(s); } else step *= 0.5;
  }
}

struct SearchMove {
  std::uint8_t moved = 0, on_curve = 0;
};

// Pattern search on the worst corner around node v: in the plane for interior nodes, along the curve (strictly
// between the curve neighbours, so the boundary order never changes) for sliding ones.
SearchMove search_node(Sweeps& sw, const SlideCurves& sc, std::int32_t v) {
  QuadMesh& mesh = sw.mesh;
  const SmoothOptions& options = sw.options;
  const bool is_inner = sw.interior[v] != 0;
  const Incidence::Score before = sw.inc.score(mesh, v);
  if (is_inner && before.worst >= options.worst_threshold) return {};
  Incidence::Score best = before;
  const double step = 0.25 * sw.inc.mean_edge(mesh, v);
  const Star star(mesh, sw.inc, v);
  if (is_inner) {
    search_in_plane(mesh, star, v, step, best);
    return {static_cast<std::uint8_t>(best.better_than(before)), 0};
  }
  const Curve& c = sc.curves[static_cast<std::size_t>(sc.slider[v].curve)];
  std::optional<CurveSpan> span = curve_span(mesh, c, sc.slider[v], v);
  if (!span) return {};
  // Feature nodes keep the two mesh edges beside them within the feature tolerance of the curve; a node
  // that starts outside it first moves towards the position that balances the two edges.
  const double tolerance = options.feature_tolerance;
  const bool bounded = tolerance > 0 && sc.slider[v].curve >= sc.feature_base;
  double allowed = INFINITY;
  bool repaired = false;
  if (bounded) {
    const double floor = std::min(before.min_sj, options.feature_repair_min_sj);
    repaired = balance_feature_chords(mesh, sw.inc, v, *span, tolerance, floor, before, best, allowed);
  }
  if (!repaired && before.worst >= options.worst_threshold) return {};
  search_on_curve(mesh, star, v, *span, bounded, allowed, step, best);
  if (repaired || best.better_than(before)) return {1, 1};
  return {};
}

// Sweeps of the pattern search on the worst corner around poor nodes: lifts the minimum where averaging cannot
// (next to poly-square corners), and untangles.
void search_sweeps(Sweeps& sw, const SlideCurves& sc, const std::vector<std::uint8_t>& searchable, Visits& search,
                   SmoothStats& stats) {
  const std::size_t nn = sw.mesh.nodes.size();
  const auto search_classes = colour_classes(sw.mesh, sw.inc, searchable);
  std::vector<std::uint8_t> moved_flag(nn, 0), curve_moved(nn, 0);
  for (int sweep = 0; sweep < sw.options.worst_sweeps; ++sweep) {
    std::fill(moved_flag.begin(), moved_flag.end(), 0);
    std::fill(curve_moved.begin(), curve_moved.end(), 0);
    for_each_by_colour(search_classes, sw.clock, [&](std::int32_t v) {
      // The search from an unchanged neighbourhood finds what it found last time: nothing, or v moved.
      if (search.settled(sw.mesh, sw.inc, v, true)) return;
      search.visited[v] = sw.clock;
      const Vec2 start = sw.mesh.nodes[v];
      const SearchMove m = search_node(sw, sc, v);
      if (m.moved) moved_flag[v] = 1;
      if (m.on_curve) curve_moved[v] = 1;
      if (!(sw.mesh.nodes[v] == start)) search.moved[v] = sw.clock;
    });
    std::size_t moved = 0;
    for (std::size_t v = 0; v < nn; ++v) {
      moved += moved_flag[v];
      stats.curve_moves += curve_moved[v];
    }
    stats.moves += moved;
    if (moved == 0) break;
  }
}

}  // namespace

double quad_min_corner_sj(const QuadMesh& mesh, std::size_t q) {
  const auto& quad = mesh.quads[q];
  return quad_min_sj(mesh.nodes[quad[0]], mesh.nodes[quad[1]], mesh.nodes[quad[2]], mesh.nodes[quad[3]]);
}

SmoothStats smooth_quads(QuadMesh& mesh, const SmoothOptions& options, const Region* region,
                         const std::vector<std::uint8_t>* only) {
  const std::size_t nn = mesh.nodes.size();
  const Incidence inc(mesh);
  const bool kinds = mesh.node_kind.size() == nn;
  auto allowed = [&](std::size_t v) { return only == nullptr || (*only)[v] != 0; };
  SmoothStats stats;
  std::vector<std::uint8_t> interior(nn, 0);
  for (std::size_t v = 0; v < nn; ++v) interior[v] = kinds && mesh.node_kind[v] == NodeKind::interior && allowed(v);
  // The guarded moves below never make a node's worst quad worse, so a folded quad stays folded unless it is
  // untangled first.
  stats.untangle = untangle_quads(mesh, interior, options.untangle);
  Sweeps sw{mesh, inc, options, interior};
  Visits lap(nn);
  average_sweeps(sw, lap, stats);

  const SlideCurves sc = slide_curves(mesh, region, options.slide_on_curves, kinds);
  std::vector<std::uint8_t> searchable(nn, 0);
  for (std::size_t v = 0; v < nn; ++v)
    searchable[v] = interior[v] || (kinds && !sc.curves.empty() && sc.slides(mesh, v) && allowed(v));
  Visits search(nn);
  search.moved = lap.moved;
  search_sweeps(sw, sc, searchable, search, stats);
  return stats;
}

}  // namespace polysquare
