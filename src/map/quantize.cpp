#include "polysquare/map/quantize.h"

#include <glpk.h>
#include <cstdio>
#include <cstdlib>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <memory>
#include <mutex>
#include <array>

#include "polysquare/core/error.h"

namespace polysquare {
namespace {

// GLPK keeps its environment in process-wide state unless built with thread-local storage; parts and candidates
// are quantized from several threads, so every call into GLPK holds this lock (the programs take milliseconds).
std::mutex glpk_mutex;

struct UnionFind {
  std::vector<int> parent;
  explicit UnionFind(int n) : parent(static_cast<std::size_t>(n)) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int a) { return parent[a] == a ? a : parent[a] = find(parent[a]); }
  void unite(int a, int b) { parent[find(a)] = find(b); }
};

// Break points that share a coordinate along `axis` (joined by sides of the other axis) form one class.
std::vector<int> axis_classes(const Layout& layout, int axis, int& ncls) {
  const int nb = static_cast<int>(layout.break_vertex.size());
  UnionFind uf(nb);
  for (const LayoutSegment& s : layout.segments)
    if (label_axis(s.label) != axis) uf.unite(s.break_a, s.break_b);
  std::vector<int> cls(nb, -1), root_cls(nb, -1);
  ncls = 0;
  for (int b = 0; b < nb; ++b) {
    const int r = uf.find(b);
    if (root_cls[r] < 0) root_cls[r] = ncls++;
    cls[b] = root_cls[r];
  }
  return cls;
}

// coordinate(hi) - coordinate(lo) >= 1 along `axis` in one layout: keeps apart two pieces that overlapped.
struct Separation {
  int layout, axis, lo, hi;
  bool operator==(const Separation&) const = default;
};

// The joint integer program over several layouts (PPM subregions, each in its own frame): one integer
// coordinate per class of break points per axis per layout; every segment's length n = sign * (end - start)
// >= 1, near t and preferably within [t / c, c t] (deviation columns); coupled segments (the two sides of an interface) get the
// same n. Without couplings the matrix is totally unimodular and the simplex optimum is integral; with them,
// GLPK's branch-and-cut finishes from the simplex optimum.
struct JointProblem {
  std::vector<Layout*> layouts;
  std::vector<const std::vector<Vec2>*> deformed;
  std::vector<std::array<std::vector<int>, 2>> cls;  // per layout, per axis: class of each break point
  std::vector<std::array<int, 2>> ncls, col0;        // class counts and first column per layout and axis
};

void solve_joint(JointProblem& jp, const std::vector<SegmentCoupling>& couplings,
                 const std::vector<EvenGroup>& even_groups, const std::vector<Separation>& separations,
                 const QuantizeOptions& options, const std::string& part_name, QuantizeStats& stats) {
  const std::lock_guard<std::mutex> lock(glpk_mutex);
  std::unique_ptr<glp_prob, void (*)(glp_prob*)> lp(glp_create_prob(), glp_delete_prob);
  glp_prob* P = lp.get();
  glp_set_obj_dir(P, GLP_MIN);
  const bool integer = !couplings.empty() || !even_groups.empty();
  std::vector<int> ia{0}, ja{0};
  std::vector<double> ar{0.0};
  auto add_row = [&](std::initializer_list<std::pair<int, double>> terms, int type, double lo, double hi) {
    const int row = glp_add_rows(P, 1);
    glp_set_row_bnds(P, row, type, lo, hi);
    for (auto [col, val] : terms) { ia.push_back(row); ja.push_back(col); ar.push_back(val); }
  };
  auto col = [&](std::size_t l, int axis, int b) { return jp.col0[l][axis] + jp.cls[l][axis][b]; };
  // Class coordinate columns with the weak pull of each class towards its mean deformed coordinate (anchors
  // pieces, such as interior features, that no segment ties to the boundary).
  for (std::size_t l = 0; l < jp.layouts.size(); ++l) {
    const Layout& layout = *jp.layouts[l];
    const int nb = static_cast<int>(layout.break_vertex.size());
    for (int axis = 0; axis < 2; ++axis) {
      const int ncls = jp.ncls[l][axis];
      jp.col0[l][axis] = glp_add_cols(P, ncls);
      std::vector<double> anchor(ncls, 0.0);
      std::vector<int> members(ncls, 0);
      for (int b = 0; b < nb; ++b) {
        const Vec2 p = (*jp.deformed[l])[layout.break_vertex[b]];
        anchor[jp.cls[l][axis][b]] += axis == 0 ? p.x : p.y;
        members[jp.cls[l][axis][b]]++;
      }
      const int v0 = glp_add_cols(P, ncls);
      for (int c = 0; c < ncls; ++c) {
        const int xc = jp.col0[l][axis] + c;
        glp_set_col_bnds(P, xc, GLP_DB, -1e8, 1e8);
        if (integer) glp_set_col_kind(P, xc, GLP_IV);
        const double a = std::round(anchor[c] / members[c]);
        glp_set_col_bnds(P, v0 + c, GLP_LO, 0.0, 0.0);
        glp_set_obj_coef(P, v0 + c, options.position_weight);
        add_row({{v0 + c, 1.0}, {xc, -1.0}}, GLP_LO, -a, 0.0);
        add_row({{v0 + c, 1.0}, {xc, 1.0}}, GLP_LO, a, 0.0);
      }
    }
    for (std::size_t k = 0; k < layout.segments.size(); ++k) {
      const LayoutSegment& s = layout.segments[k];
      const int axis = label_axis(s.label);
      const int xa = col(l, axis, s.break_a), xb = col(l, axis, s.break_b);
      if (xa == xb)
        throw MeshingError(part_name + ": quantization is infeasible: a side of the poly-square (chain " +
                           std::to_string(s.chain) + ") would have zero length");
      const double sg = label_sign(s.label);
      const int u = glp_add_cols(P, 2);  // u: deviation from t; w: deviation beyond the band [lo, hi]
      glp_set_col_bnds(P, u, GLP_LO, 0.0, 0.0);
      glp_set_obj_coef(P, u, 1.0 / std::max(s.target, 1.0));
      glp_set_col_bnds(P, u + 1, GLP_LO, 0.0, 0.0);
      glp_set_obj_coef(P, u + 1, options.outside_band_weight / std::max(s.target, 1.0));
      // Integer right-hand sides keep the LP vertex integral (the matrix is totally unimodular).
      const double t = std::max(std::round(s.target), 1.0);
      // n = sg (X_b - X_a) >= 1 ; u >= |n - t| ; w >= n - hi, w >= lo - n. The band is soft: a layout that only
      // closes with a stretched side still gets counts, and the quality checks downstream judge the result.
      const double lo = std::max(1.0, std::ceil(t / options.max_side_change));
      const double hi = std::max(lo, std::floor(t * options.max_side_change));
      add_row({{xb, sg}, {xa, -sg}}, GLP_LO, 1.0, 0.0);
      add_row({{u, 1.0}, {xb, -sg}, {xa, sg}}, GLP_LO, -t, 0.0);
      add_row({{u, 1.0}, {xb, sg}, {xa, -sg}}, GLP_LO, t, 0.0);
      add_row({{u + 1, 1.0}, {xb, -sg}, {xa, sg}}, GLP_LO, -hi, 0.0);
      add_row({{u + 1, 1.0}, {xb, sg}, {xa, -sg}}, GLP_LO, lo, 0.0);
    }
  }
  for (const SegmentCoupling& c : couplings) {
    const LayoutSegment& s = jp.layouts[c.layout_a]->segments[c.segment_a];
    const LayoutSegment& t = jp.layouts[c.layout_b]->segments[c.segment_b];
    const double ss = label_sign(s.label), st = label_sign(t.label);
    const int sa = col(c.layout_a, label_axis(s.label), s.break_a), sb = col(c.layout_a, label_axis(s.label), s.break_b);
    const int ta = col(c.layout_b, label_axis(t.label), t.break_a), tb = col(c.layout_b, label_axis(t.label), t.break_b);
    add_row({{sb, ss}, {sa, -ss}, {tb, -st}, {ta, st}}, GLP_FX, 0.0, 0.0);
  }
  for (const EvenGroup& g : even_groups) {
    // sum of the counts - 2 m = 0, m integer.
    const int m = glp_add_cols(P, 1);
    glp_set_col_bnds(P, m, GLP_LO, 0.0, 0.0);
    glp_set_col_kind(P, m, GLP_IV);
    const int row = glp_add_rows(P, 1);
    glp_set_row_bnds(P, row, GLP_FX, 0.0, 0.0);
    ia.push_back(row); ja.push_back(m); ar.push_back(-2.0);
    for (const auto& [l, k] : g) {
      const LayoutSegment& s = jp.layouts[l]->segments[static_cast<std::size_t>(k)];
      const double sg = label_sign(s.label);
      const int axis = label_axis(s.label);
      ia.push_back(row); ja.push_back(col(l, axis, s.break_b)); ar.push_back(sg);
      ia.push_back(row); ja.push_back(col(l, axis, s.break_a)); ar.push_back(-sg);
    }
  }
  for (const Separation& sep : separations)
    add_row({{col(sep.layout, sep.axis, sep.hi), 1.0}, {col(sep.layout, sep.axis, sep.lo), -1.0}}, GLP_LO, 1.0, 0.0);
  // A row may name one column twice (consecutive sides of one axis in an even group share a break class; a
  // coupling may tie a layout to itself): GLPK refuses repeated entries, so they are summed and zeros dropped.
  {
    std::vector<std::size_t> order(ia.size() - 1);
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i + 1;
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
      return ia[a] != ia[b] ? ia[a] < ia[b] : (ja[a] != ja[b] ? ja[a] < ja[b] : a < b);
    });
    std::vector<int> mi{0}, mj{0};
    std::vector<double> ma{0.0};
    for (std::size_t i : order) {
      if (mi.size() > 1 && mi.back() == ia[i] && mj.back() == ja[i]) {
        ma.back() += ar[i];
        continue;
      }
      if (mi.size() > 1 && ma.back() == 0.0) { mi.pop_back(); mj.pop_back(); ma.pop_back(); }
      mi.push_back(ia[i]); mj.push_back(ja[i]); ma.push_back(ar[i]);
    }
    if (mi.size() > 1 && ma.back() == 0.0) { mi.pop_back(); mj.pop_back(); ma.pop_back(); }
    ia.swap(mi); ja.swap(mj); ar.swap(ma);
  }
  glp_load_matrix(P, static_cast<int>(ia.size()) - 1, ia.data(), ja.data(), ar.data());
  glp_smcp parm;
  glp_init_smcp(&parm);
  parm.presolve = GLP_ON;
  parm.msg_lev = GLP_MSG_OFF;
  parm.tm_lim = options.time_limit_ms;
  const std::string infeasible = part_name + ": quantization has no integer solution (the labelled sides cannot close "
                                             "into poly-squares without overlapping)";
  if (glp_simplex(P, &parm) != 0 || glp_get_status(P) != GLP_OPT) throw MeshingError(infeasible);
  auto value = [&](int c) { return integer ? glp_mip_col_val(P, c) : glp_get_col_prim(P, c); };
  if (integer) {
    glp_iocp iparm;
    glp_init_iocp(&iparm);
    iparm.msg_lev = GLP_MSG_OFF;
    iparm.tm_lim = options.time_limit_ms;
    if (glp_intopt(P, &iparm) != 0 || (glp_mip_status(P) != GLP_OPT && glp_mip_status(P) != GLP_FEAS))
      throw MeshingError(infeasible);
  }
  for (std::size_t l = 0; l < jp.layouts.size(); ++l) {
    Layout& layout = *jp.layouts[l];
    const std::size_t nb = layout.break_vertex.size();
    layout.lattice.resize(nb);
    for (std::size_t b = 0; b < nb; ++b)
      for (int axis = 0; axis < 2; ++axis) {
        const double v = value(col(l, axis, static_cast<int>(b)));
        if (std::abs(v - std::round(v)) > 1e-6)
          throw MeshingError(part_name + ": quantization returned a fractional coordinate " + std::to_string(v));
        layout.lattice[b][static_cast<std::size_t>(axis)] = std::llround(v);
      }
    for (const LayoutSegment& s : layout.segments) {
      const auto pa = layout.lattice[s.break_a], pb = layout.lattice[s.break_b];
      const double n = static_cast<double>(std::llabs(pb[0] - pa[0]) + std::llabs(pb[1] - pa[1]));
      stats.max_relative_deviation = std::max(stats.max_relative_deviation, std::abs(n - s.target) / std::max(s.target, 1.0));
    }
    stats.segments += static_cast<int>(layout.segments.size());
    stats.variables += jp.ncls[l][0] + jp.ncls[l][1];
  }
}

// The separation that holds with the largest margin in the deformed plane, between two sets of break points
// (the ends of two overlapping sides, or two break points on one lattice point). Returns false if none is
// possible (the sets share a break point on every candidate axis).
bool best_separation(const Layout& layout, const std::vector<Vec2>& deformed, const std::vector<int>& A,
                     const std::vector<int>& B, const std::array<std::vector<int>, 2>& cls, Separation& out) {
  double best = -INFINITY;
  for (int axis = 0; axis < 2; ++axis) {
    auto coord = [&](int b) { const Vec2 p = deformed[layout.break_vertex[b]]; return axis == 0 ? p.x : p.y; };
    auto extreme = [&](const std::vector<int>& S, bool want_max) {
      int e = S.front();
      for (int b : S)
        if (want_max ? coord(b) > coord(e) : coord(b) < coord(e)) e = b;
      return e;
    };
    // A before B along the axis, or B before A.
    for (int order = 0; order < 2; ++order) {
      const std::vector<int>& first = order == 0 ? A : B;
      const std::vector<int>& second = order == 0 ? B : A;
      const int lo = extreme(first, true), hi = extreme(second, false);
      if (cls[axis][lo] == cls[axis][hi]) continue;
      const double margin = coord(hi) - coord(lo);
      if (margin > best) { best = margin; out = {out.layout, axis, lo, hi}; }
    }
  }
  return best > -INFINITY;
}

}  // namespace

QuantizeStats quantize_layouts(const std::vector<Layout*>& layouts, const std::vector<const std::vector<Vec2>*>& deformed,
                               const std::vector<SegmentCoupling>& couplings, const QuantizeOptions& options,
                               const std::string& part_name, const std::vector<EvenGroup>& even_groups) {
  {
    const std::lock_guard<std::mutex> lock(glpk_mutex);
    glp_term_out(GLP_OFF);
  }
  JointProblem jp;
  jp.layouts = layouts;
  jp.deformed = deformed;
  jp.cls.resize(layouts.size());
  jp.ncls.resize(layouts.size());
  jp.col0.resize(layouts.size());
  for (std::size_t l = 0; l < layouts.size(); ++l)
    for (int axis = 0; axis < 2; ++axis) jp.cls[l][axis] = axis_classes(*layouts[l], axis, jp.ncls[l][axis]);
  // Solve; where sides overlap or corners coincide, add the separation the deformed layout shows and solve
  // again (a few rounds settle it: each round only adds constraints the deformed plane satisfies).
  std::vector<Separation> separations;
  QuantizeStats stats;
  for (int round = 0;; ++round) {
    stats = QuantizeStats{};
    solve_joint(jp, couplings, even_groups, separations, options, part_name, stats);
    if (round >= options.max_separation_rounds) break;
    std::size_t added = 0;
    for (std::size_t l = 0; l < layouts.size(); ++l) {
      const Layout& layout = *layouts[l];
      for (const LayoutConflict& c : find_conflicts(layout, 64)) {
        std::vector<int> A, B;
        if (c.seg_a >= 0) {
          A = {layout.segments[c.seg_a].break_a, layout.segments[c.seg_a].break_b};
          B = {layout.segments[c.seg_b].break_a, layout.segments[c.seg_b].break_b};
        } else {
          A = {c.break_a};
          B = {c.break_b};
        }
        Separation sep{static_cast<int>(l), 0, 0, 0};
        if (best_separation(layout, *deformed[l], A, B, jp.cls[l], sep) &&
            std::find(separations.begin(), separations.end(), sep) == separations.end()) {
          separations.push_back(sep);
          ++added;
        }
      }
    }
    if (added == 0) break;
  }
  stats.separations = separations.size();
  return stats;
}

QuantizeStats quantize_layout(Layout& layout, const std::vector<Vec2>& deformed, const QuantizeOptions& options,
                              const std::string& part_name) {
  return quantize_layouts({&layout}, {&deformed}, {}, options, part_name);
}

std::vector<LayoutConflict> find_conflicts(const Layout& layout, std::size_t max_conflicts) {
  std::vector<LayoutConflict> out;
  struct Seg { long long x0, y0, x1, y1; int a, b, index; };
  std::vector<Seg> segs;
  for (std::size_t k = 0; k < layout.segments.size(); ++k) {
    const auto& s = layout.segments[k];
    const auto pa = layout.lattice[s.break_a], pb = layout.lattice[s.break_b];
    segs.push_back({std::min(pa[0], pb[0]), std::min(pa[1], pb[1]), std::max(pa[0], pb[0]), std::max(pa[1], pb[1]),
                    s.break_a, s.break_b, static_cast<int>(k)});
  }
  // Distinct break points must not share a lattice point.
  std::vector<std::pair<std::array<long long, 2>, int>> pts;
  for (std::size_t b = 0; b < layout.lattice.size(); ++b) pts.push_back({layout.lattice[b], static_cast<int>(b)});
  std::sort(pts.begin(), pts.end());
  for (std::size_t i = 1; i < pts.size() && out.size() < max_conflicts; ++i)
    if (pts[i].first == pts[i - 1].first) out.push_back({-1, -1, pts[i - 1].second, pts[i].second, pts[i].first});
  // Axis-aligned boxes overlap test; segments may only share an end point that is a common break point.
  std::sort(segs.begin(), segs.end(), [](const Seg& a, const Seg& b) { return a.x0 < b.x0; });
  for (std::size_t i = 0; i < segs.size() && out.size() < max_conflicts; ++i) {
    for (std::size_t j = i + 1; j < segs.size() && segs[j].x0 <= segs[i].x1 && out.size() < max_conflicts; ++j) {
      const Seg &s = segs[i], &t = segs[j];
      const long long ox0 = std::max(s.x0, t.x0), ox1 = std::min(s.x1, t.x1);
      const long long oy0 = std::max(s.y0, t.y0), oy1 = std::min(s.y1, t.y1);
      if (ox0 > ox1 || oy0 > oy1) continue;
      const auto at = std::array<long long, 2>{ox0, oy0};
      if (ox0 == ox1 && oy0 == oy1) {  // touching at one point: fine if it is a break point both end at
        auto is_end = [&](const Seg& q) { return layout.lattice[q.a] == at || layout.lattice[q.b] == at; };
        const bool shared = s.a == t.a || s.a == t.b || s.b == t.a || s.b == t.b;
        if (shared && is_end(s) && is_end(t)) continue;
      }
      out.push_back({std::min(s.index, t.index), std::max(s.index, t.index), -1, -1, at});
    }
  }
  return out;
}

std::string check_layout(const Layout& layout) {
  for (std::size_t k = 0; k < layout.segments.size(); ++k)
    if (layout.lattice[layout.segments[k].break_a] == layout.lattice[layout.segments[k].break_b])
      return "side " + std::to_string(k) + " has zero length";
  const auto conflicts = find_conflicts(layout, 1);
  if (conflicts.empty()) return {};
  const LayoutConflict& c = conflicts.front();
  const std::string where = " at (" + std::to_string(c.at[0]) + ", " + std::to_string(c.at[1]) + ")";
  if (c.seg_a < 0)
    return "corners " + std::to_string(c.break_a) + " and " + std::to_string(c.break_b) + " land on the same lattice point" + where;
  return "sides " + std::to_string(c.seg_a) + " and " + std::to_string(c.seg_b) + " of the poly-square overlap" + where;
}

}  // namespace polysquare
