#include "polysquare/map/quantize.h"

#include <algorithm>
#include <cstdlib>
#include <chrono>
#include <map>
#include <mutex>
#include <cmath>
#include <numeric>
#include <optional>
#include <array>

#include <oneapi/tbb/parallel_for.h>
#include <spdlog/spdlog.h>

#include "core/digest.h"
#include "map/integer_program.h"
#include "polysquare/core/error.h"
#include "polysquare/core/union_find.h"

namespace polysquare {
namespace {

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
// Cbc's branch-and-cut finishes from the LP optimum.
struct JointProblem {
  std::vector<Layout*> layouts;
  std::vector<const std::vector<Vec2>*> deformed;
  std::vector<std::array<std::vector<int>, 2>> cls;  // per layout, per axis: class of each break point
  std::vector<std::array<int, 2>> ncls, col0;        // class counts and first column per layout and axis
  bool large = false;  // its program is built in the compact form and solved as large (joint_program decides)
  // Sides coupled to a layout left out of the program (quantize_locally): their counts are given. A transition
  // coupling's side may differ from the given count by an even number, as between two layouts in the program.
  struct FixedCount {
    std::size_t layout;
    int segment;
    long long count;
    bool transition;
  };
  std::vector<FixedCount> fixed;
  std::vector<long long> even_offset;  // per even group: the count its members outside the program add (or none)
  // The program's column of break point b's coordinate along `axis` in layout l.
  int col(std::size_t l, int axis, int b) const { return col0[l][axis] + cls[l][axis][b]; }
};

// The target length of every segment in the joint program: its own map's, but for the two sides of a coupling,
// whose maps may disagree on the interface's length (each subregion is deformed alone), the geometric mean of
// both. With each side's own target the optimum of the relative deviations sits at the shorter target (its cost
// per element is higher), so the longer side took the whole disagreement; the mean shares it equally in ratio.
std::vector<std::vector<double>> coupled_targets(const JointProblem& jp, const std::vector<SegmentCoupling>& couplings) {
  std::vector<std::vector<double>> target(jp.layouts.size());
  for (std::size_t l = 0; l < jp.layouts.size(); ++l)
    for (const LayoutSegment& s : jp.layouts[l]->segments) target[l].push_back(s.target);
  for (const SegmentCoupling& c : couplings) {
    double& ta = target[c.layout_a][static_cast<std::size_t>(c.segment_a)];
    double& tb = target[c.layout_b][static_cast<std::size_t>(c.segment_b)];
    ta = tb = std::sqrt(std::max(ta, 1e-9) * std::max(tb, 1e-9));
  }
  return target;
}

// Large programs take the compact form (see QuantizeOptions::large_program_columns): the same costs, so the
// same optimal cost, with the deviations as bounded columns of one equality row instead of inequality rows.
bool is_large(const JointProblem& jp, std::size_t couplings, std::size_t even_groups, const QuantizeOptions& options,
              bool elastic) {
  // A part's program solved locally is a piece of a large one: solved the same way (no branch-and-cut, whose time
  // limit would make the answer depend on the machine's load; 41 s on one such piece of 1,032 sides).
  if (!jp.fixed.empty()) return true;
  std::size_t inequality_columns = (elastic ? 2 : 0) * couplings + even_groups;
  for (std::size_t l = 0; l < jp.layouts.size(); ++l)
    inequality_columns += 2 * static_cast<std::size_t>(jp.ncls[l][0] + jp.ncls[l][1]) + 2 * jp.layouts[l]->segments.size();
  return inequality_columns > static_cast<std::size_t>(std::max(options.large_program_columns, 0));
}

// Layout l's class coordinate columns, with the weak pull of each class towards its mean deformed coordinate
// (anchors pieces, such as interior features, that no segment ties to the boundary).
void add_class_columns(IntegerProgram& P, JointProblem& jp, std::size_t l, const QuantizeOptions& options,
                       bool integer) {
  constexpr double inf = IntegerProgram::inf;
  const Layout& layout = *jp.layouts[l];
  const int nb = static_cast<int>(layout.break_vertex.size());
  for (int axis = 0; axis < 2; ++axis) {
    const int ncls = jp.ncls[l][axis];
    // Free in a graded large program: boxed at +-1e8, the dual simplex's bound flips sent columns to 1e8 and a
    // dive step crawled (4,489 iterations in 31 s on graded delta_box, where steps run a thousand a second).
    // Uniform programs keep the box: free, delta_box 200 m took another optimum among equals and came out worse
    // (26.6 interior singular nodes per 1000 quads against 22.4).
    const double bound = jp.large && options.graded ? IntegerProgram::inf : 1e8;
    jp.col0[l][axis] = P.add_columns(ncls, -bound, bound, 0.0, integer);
    std::vector<double> anchor(ncls, 0.0);
    std::vector<int> members(ncls, 0);
    for (int b = 0; b < nb; ++b) {
      const Vec2 p = (*jp.deformed[l])[layout.break_vertex[b]];
      anchor[jp.cls[l][axis][b]] += axis == 0 ? p.x : p.y;
      members[jp.cls[l][axis][b]]++;
    }
    // v >= |X - a|; compact: X - a = above - below.
    const int v0 = P.add_columns(jp.large ? 2 * ncls : ncls, 0.0, inf, options.position_weight);
    for (int c = 0; c < ncls; ++c) {
      const int xc = jp.col0[l][axis] + c;
      const double a = std::round(anchor[c] / members[c]);
      if (jp.large) {
        P.add_row({{xc, 1.0}, {v0 + 2 * c, -1.0}, {v0 + 2 * c + 1, 1.0}}, a, a);
        continue;
      }
      P.add_row({{v0 + c, 1.0}, {xc, -1.0}}, -a, inf);
      P.add_row({{v0 + c, 1.0}, {xc, 1.0}}, a, inf);
    }
  }
}

// Layout l's side counts n = sg (X_b - X_a) >= 1 and their deviations from the targets: u >= |n - t|,
// w >= n - hi, w >= lo - n. The band [lo, hi] is soft: a layout that only closes with a stretched side still
// gets counts, and the quality checks downstream judge the result.
void add_side_rows(IntegerProgram& P, const JointProblem& jp, std::size_t l, const std::vector<double>& target,
                   const QuantizeOptions& options, const std::string& part_name) {
  constexpr double inf = IntegerProgram::inf;
  const Layout& layout = *jp.layouts[l];
  const double fewer = options.graded ? options.graded_fewer_weight : 1.0;
  for (std::size_t k = 0; k < layout.segments.size(); ++k) {
    const LayoutSegment& s = layout.segments[k];
    const int axis = label_axis(s.label);
    const int xa = jp.col(l, axis, s.break_a), xb = jp.col(l, axis, s.break_b);
    if (xa == xb)
      throw MeshingError(part_name + ": quantization is infeasible: a side of the poly-square (chain " +
                         std::to_string(s.chain) + ") would have zero length");
    const double sg = label_sign(s.label);
    const double unit = 1.0 / std::max(target[k], 1.0);
    // Divided, not `* unit`: bit for bit the cost the small cases' meshes were made with.
    const double outside = options.outside_band_weight / std::max(target[k], 1.0);
    // Integer right-hand sides keep the LP vertex integral (the matrix is totally unimodular).
    const double t = std::max(std::round(target[k]), 1.0);
    const double lo = std::max(1.0, std::ceil(t / options.max_side_change));
    const double hi = std::max(lo, std::floor(t * options.max_side_change));
    if (jp.large) {
      // n = t + longer within the band + longer beyond it - shorter within - shorter beyond; beyond the band
      // costs u's and w's weights together and the costs are convex, so the band fills first. The bounds
      // keep n >= 1.
      const double beyond = unit * (1.0 + options.outside_band_weight);
      const int d = P.add_columns(1, 0.0, hi - t, unit);
      P.add_columns(1, 0.0, inf, beyond);
      P.add_columns(1, 0.0, t - lo, fewer * unit);
      P.add_columns(1, 0.0, lo - 1.0, fewer * beyond);
      P.add_row({{xb, sg}, {xa, -sg}, {d, -1.0}, {d + 1, -1.0}, {d + 2, 1.0}, {d + 3, 1.0}}, t, t);
      continue;
    }
    // Graded: the deviations below take columns of their own (a weighted row would cost the matrix its total
    // unimodularity).
    const int u = P.add_columns(1, 0.0, inf, unit);
    const int w = P.add_columns(1, 0.0, inf, outside);
    const int u_below = fewer == 1.0 ? u : P.add_columns(1, 0.0, inf, fewer * unit);
    const int w_below = fewer == 1.0 ? w : P.add_columns(1, 0.0, inf, fewer * outside);
    P.add_row({{xb, sg}, {xa, -sg}}, 1.0, inf);
    P.add_row({{u, 1.0}, {xb, -sg}, {xa, sg}}, -t, inf);
    P.add_row({{u_below, 1.0}, {xb, sg}, {xa, -sg}}, t, inf);
    P.add_row({{w, 1.0}, {xb, -sg}, {xa, sg}}, -hi, inf);
    P.add_row({{w_below, 1.0}, {xb, sg}, {xa, -sg}}, lo, inf);
  }
}

// Appends sign * (the count of layout l's segment k) to a row: sign * sg * (X_b - X_a).
void add_count_terms(std::vector<std::pair<int, double>>& row, const JointProblem& jp, std::size_t l, int k,
                     double sign) {
  const LayoutSegment& s = jp.layouts[l]->segments[static_cast<std::size_t>(k)];
  const double sg = sign * label_sign(s.label);
  const int axis = label_axis(s.label);
  row.push_back({jp.col(l, axis, s.break_b), sg});
  row.push_back({jp.col(l, axis, s.break_a), -sg});
}

// Transition fans on a coupling row n_a - n_b = 2 (fans on b's side - fans on a's side); a fan costs as a
// relative deviation of the coupled target t_a.
void add_fan_terms(IntegerProgram& P, std::vector<std::pair<int, double>>& row, double t_a,
                   const QuantizeOptions& options) {
  const int f = P.add_columns(2, 0.0, IntegerProgram::inf, options.transition_cost / std::max(t_a, 1.0), true);
  P.round_first(f, 0.0), P.round_first(f + 1, 0.0);
  row.insert(row.end(), {{f, -2.0}, {f + 1, 2.0}});
}

// Equal counts on the two sides of every coupling; elastic ones may break, transition ones differ by 2 per fan.
void add_coupling_rows(IntegerProgram& P, const JointProblem& jp, const std::vector<SegmentCoupling>& couplings,
                       const std::vector<std::vector<double>>& target, const QuantizeOptions& options, bool elastic) {
  for (const SegmentCoupling& c : couplings) {
    std::vector<std::pair<int, double>> row;
    add_count_terms(row, jp, c.layout_a, c.segment_a, 1.0);
    add_count_terms(row, jp, c.layout_b, c.segment_b, -1.0);
    if (elastic) {
      const int e = P.add_columns(2, 0.0, IntegerProgram::inf, options.broken_coupling_cost);
      row.insert(row.end(), {{e, 1.0}, {e + 1, -1.0}});
    }
    if (c.transition) add_fan_terms(P, row, target[c.layout_a][static_cast<std::size_t>(c.segment_a)], options);
    P.add_row(row, 0.0, 0.0);
  }
}

// Sides whose count a layout outside the program gives: n = count, or n - count = 2 (fans there - fans here).
void add_fixed_rows(IntegerProgram& P, const JointProblem& jp, const std::vector<std::vector<double>>& target,
                    const QuantizeOptions& options) {
  for (const JointProblem::FixedCount& f : jp.fixed) {
    std::vector<std::pair<int, double>> row;
    add_count_terms(row, jp, f.layout, f.segment, 1.0);
    if (f.transition) add_fan_terms(P, row, target[f.layout][static_cast<std::size_t>(f.segment)], options);
    const double n = static_cast<double>(f.count);
    P.add_row(row, n, n);
  }
}

// Every even group's counts sum to an even number: sum - 2 m = 0, m integer.
void add_even_rows(IntegerProgram& P, const JointProblem& jp, const std::vector<EvenGroup>& even_groups) {
  for (std::size_t i = 0; i < even_groups.size(); ++i) {
    const EvenGroup& g = even_groups[i];
    const double offset = i < jp.even_offset.size() ? static_cast<double>(jp.even_offset[i]) : 0.0;
    const int m = P.add_columns(1, 0.0, IntegerProgram::inf, 0.0, true);
    std::vector<std::pair<int, double>> terms{{m, -2.0}};
    for (const auto& [l, k] : g) add_count_terms(terms, jp, l, k, 1.0);
    P.add_row(terms, -offset, -offset);
  }
}

// With `broken` given, the couplings are elastic: a coupling may break at a cost per element far above any
// deviation cost, so the program has a solution whenever each layout closes alone, and the couplings the
// optimum breaks (appended to `broken`) show which subregions cannot agree.
IntegerProgram joint_program(JointProblem& jp, const std::vector<SegmentCoupling>& couplings,
                             const std::vector<EvenGroup>& even_groups, const QuantizeOptions& options,
                             const std::string& part_name, bool elastic) {
  IntegerProgram P;
  const bool integer = !couplings.empty() || !even_groups.empty() || !jp.fixed.empty();
  jp.large = is_large(jp, couplings.size(), even_groups.size(), options, elastic);
  const std::vector<std::vector<double>> target = coupled_targets(jp, couplings);
  for (std::size_t l = 0; l < jp.layouts.size(); ++l) {
    add_class_columns(P, jp, l, options, integer);
    add_side_rows(P, jp, l, target[l], options, part_name);
  }
  add_coupling_rows(P, jp, couplings, target, options, elastic);
  add_fixed_rows(P, jp, target, options);
  add_even_rows(P, jp, even_groups);
  return P;
}

MeshingError no_integer_solution(const std::string& part_name) {
  return MeshingError(part_name + ": quantization has no integer solution (the labelled sides cannot close into "
                                  "poly-squares without overlapping)");
}

// A segment's element count in a quantized lattice.
long long lattice_count(const LayoutSegment& s, const std::vector<std::array<long long, 2>>& lattice) {
  const auto a = lattice[static_cast<std::size_t>(s.break_a)], b = lattice[static_cast<std::size_t>(s.break_b)];
  return std::llabs(b[0] - a[0]) + std::llabs(b[1] - a[1]);
}

// max over a quantized layout's segments of |n - target| / max(target, 1).
double max_relative_deviation(const Layout& layout) {
  double out = 0.0;
  for (const LayoutSegment& s : layout.segments)
    out = std::max(out, std::abs(static_cast<double>(lattice_count(s, layout.lattice)) - s.target) / std::max(s.target, 1.0));
  return out;
}

// Adds the separations from `first` on to the program, solves it and reads the lattice of every layout.
void solve_joint(JointProblem& jp, IntegerProgram& P, const std::vector<SegmentCoupling>& couplings,
                 const std::vector<Separation>& separations, std::size_t first, const QuantizeOptions& options,
                 const std::string& part_name, QuantizeStats& stats, std::vector<std::size_t>* broken) {
  for (std::size_t k = first; k < separations.size(); ++k) {
    const Separation& sep = separations[k];
    P.add_row({{jp.col(static_cast<std::size_t>(sep.layout), sep.axis, sep.hi), 1.0},
               {jp.col(static_cast<std::size_t>(sep.layout), sep.axis, sep.lo), -1.0}}, 1.0, IntegerProgram::inf);
  }
  std::size_t sides = 0;
  for (const Layout* layout : jp.layouts) sides += layout->segments.size();
  const double dive_gap = jp.large ? IntegerProgram::inf
                                   : options.dive_gap * std::max(1.0, static_cast<double>(sides) / 1000.0);
  const auto t0 = std::chrono::steady_clock::now();
  const std::optional<std::vector<double>> x = P.solve(options.time_limit_ms / 1000.0, options.gap, dive_gap, jp.large);
  // A large program's solve is the costliest step of a coast's map: the run's log shows how each ended.
  if (jp.large)
    spdlog::debug("{}: joint quantization of {} columns, {} rows: {}, {} dive restarts, {:.2f} s", part_name,
                  P.columns(), P.rows(), !x ? "no solution" : P.branched() ? "branch-and-cut" : "LP and dive",
                  P.dive_restarts(), std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  if (!x)
    throw no_integer_solution(part_name);
  for (std::size_t l = 0; l < jp.layouts.size(); ++l) {
    Layout& layout = *jp.layouts[l];
    const std::size_t nb = layout.break_vertex.size();
    layout.lattice.resize(nb);
    for (std::size_t b = 0; b < nb; ++b)
      for (int axis = 0; axis < 2; ++axis) {
        const double v = (*x)[static_cast<std::size_t>(jp.col(l, axis, static_cast<int>(b)))];
        if (std::abs(v - std::round(v)) > 1e-6)
          throw MeshingError(part_name + ": quantization returned a fractional coordinate " + std::to_string(v));
        layout.lattice[b][static_cast<std::size_t>(axis)] = std::llround(v);
      }
    stats.max_relative_deviation = std::max(stats.max_relative_deviation, max_relative_deviation(layout));
    stats.segments += static_cast<int>(layout.segments.size());
    stats.variables += jp.ncls[l][0] + jp.ncls[l][1];
  }
  if (broken)
    for (std::size_t c = 0; c < couplings.size(); ++c) {
      auto count = [&](std::size_t l, int k) {
        return lattice_count(jp.layouts[l]->segments[static_cast<std::size_t>(k)], jp.layouts[l]->lattice);
      };
      if (count(couplings[c].layout_a, couplings[c].segment_a) != count(couplings[c].layout_b, couplings[c].segment_b))
        broken->push_back(c);
    }
}

// The separations possible between two sets of break points (the ends of two overlapping sides, or two break
// points on one lattice point), largest margin in the deformed plane first: one axis or the other, A before B
// or B before A. Empty when none is possible (the sets share a class on both axes).
std::vector<Separation> separation_candidates(const Layout& layout, int l, const std::vector<Vec2>& deformed,
                                              const std::vector<int>& A, const std::vector<int>& B,
                                              const std::array<std::vector<int>, 2>& cls) {
  std::vector<std::pair<double, Separation>> found;
  for (int axis = 0; axis < 2; ++axis) {
    auto coord = [&](int b) { const Vec2 p = deformed[layout.break_vertex[b]]; return axis == 0 ? p.x : p.y; };
    auto extreme = [&](const std::vector<int>& S, bool want_max) {
      int e = S.front();
      for (int b : S)
        if (want_max ? coord(b) > coord(e) : coord(b) < coord(e)) e = b;
      return e;
    };
    for (int order = 0; order < 2; ++order) {
      const std::vector<int>& first = order == 0 ? A : B;
      const std::vector<int>& second = order == 0 ? B : A;
      const int lo = extreme(first, true), hi = extreme(second, false);
      if (cls[axis][lo] == cls[axis][hi]) continue;
      found.push_back({coord(hi) - coord(lo), Separation{l, axis, lo, hi}});
    }
  }
  // Stable: among equal margins the first found (x before y, A before B) comes first.
  std::stable_sort(found.begin(), found.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  std::vector<Separation> out;
  for (const auto& f : found) out.push_back(f.second);
  return out;
}

// Whether layout l closes with the given separations (those of l among them) on its own sides alone: one
// layout's program is a network program, solved in about a millisecond. Within a joint program with elastic
// couplings this is exactly what the separations of l can break.
bool closes_alone(const JointProblem& jp, std::size_t l, const std::vector<Separation>& separations,
                  const QuantizeOptions& options, const std::string& part_name);
JointProblem joint_problem(const std::vector<Layout*>& layouts, const std::vector<const std::vector<Vec2>*>& deformed);

}  // namespace

struct QuantizeMemo::Impl {
  struct Entry {
    std::vector<Separation> own;          // the separations the layout needs alone
    std::optional<std::string> why_not;   // or why it cannot close alone
  };
  // A joint quantization's outcome: the lattices it left (also when it failed), and its figures or its error.
  struct Joint {
    std::vector<std::vector<std::array<long long, 2>>> lattices;
    std::vector<std::vector<std::array<int, 3>>> separations;
    QuantizeStats stats;
    std::vector<std::size_t> broken;
    std::optional<std::string> error;
    std::vector<std::size_t> cannot_close;  // with `error`: LayoutsCannotClose's layouts and reasons
    std::vector<std::string> reasons;
  };
  mutable std::mutex mutex;
  std::map<std::array<std::uint64_t, 2>, Entry> entries;
  std::map<std::array<std::uint64_t, 2>, Joint> joints;
  // By learned_key (a layout and its part): the separations its last large joint quantization ended with,
  // which a later map's program holding the same layout starts from, and the lattice it got there.
  struct Learned {
    std::vector<std::array<int, 3>> separations;
    std::vector<std::array<long long, 2>> lattice;
  };
  std::map<std::array<std::uint64_t, 2>, Learned> learned;
  mutable std::size_t hits = 0;
};

QuantizeMemo::QuantizeMemo() : impl_(std::make_unique<Impl>()) {}
QuantizeMemo::~QuantizeMemo() = default;

std::size_t QuantizeMemo::hits() const {
  const std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->hits;
}

struct QuantizeMemoAccess {
  using Joint = QuantizeMemo::Impl::Joint;
  static bool find(const QuantizeMemo& memo, const std::array<std::uint64_t, 2>& key, std::vector<Separation>& own,
                   std::optional<std::string>& why_not) {
    QuantizeMemo::Impl& m = *memo.impl_;
    const std::lock_guard<std::mutex> lock(m.mutex);
    const auto it = m.entries.find(key);
    if (it == m.entries.end()) return false;
    own = it->second.own;
    why_not = it->second.why_not;
    ++m.hits;
    return true;
  }
  static void store(const QuantizeMemo& memo, const std::array<std::uint64_t, 2>& key, const std::vector<Separation>& own,
                    const std::optional<std::string>& why_not) {
    QuantizeMemo::Impl& m = *memo.impl_;
    const std::lock_guard<std::mutex> lock(m.mutex);
    m.entries.try_emplace(key, QuantizeMemo::Impl::Entry{own, why_not});
  }
  static std::optional<QuantizeMemo::Impl::Joint> find_joint(const QuantizeMemo& memo,
                                                             const std::array<std::uint64_t, 2>& key) {
    QuantizeMemo::Impl& m = *memo.impl_;
    const std::lock_guard<std::mutex> lock(m.mutex);
    const auto it = m.joints.find(key);
    if (it == m.joints.end()) return std::nullopt;
    ++m.hits;
    return it->second;
  }
  static void store_joint(const QuantizeMemo& memo, const std::array<std::uint64_t, 2>& key,
                          QuantizeMemo::Impl::Joint joint) {
    QuantizeMemo::Impl& m = *memo.impl_;
    const std::lock_guard<std::mutex> lock(m.mutex);
    m.joints.try_emplace(key, std::move(joint));
  }
  using Learned = QuantizeMemo::Impl::Learned;
  static std::optional<Learned> find_learned(const QuantizeMemo& memo, const std::array<std::uint64_t, 2>& key) {
    QuantizeMemo::Impl& m = *memo.impl_;
    const std::lock_guard<std::mutex> lock(m.mutex);
    const auto it = m.learned.find(key);
    if (it == m.learned.end()) return std::nullopt;
    return it->second;
  }
  static void store_learned(const QuantizeMemo& memo, const std::array<std::uint64_t, 2>& key, const Layout& layout) {
    QuantizeMemo::Impl& m = *memo.impl_;
    const std::lock_guard<std::mutex> lock(m.mutex);
    m.learned[key] = Learned{layout.separations, layout.lattice};
  }
};

namespace {

// Whether a program of these layouts starts from (and keeps) their Layout::separations: a joint program of more
// than options.reuse_separations_sides sides.
bool reuses_separations(const std::vector<Layout*>& layouts, const std::vector<SegmentCoupling>& couplings,
                        const std::vector<EvenGroup>& even_groups, const QuantizeOptions& options) {
  if (layouts.size() < 2 || (couplings.empty() && even_groups.empty())) return false;
  std::size_t sides = 0;
  for (const Layout* layout : layouts) sides += layout->segments.size();
  return sides > options.reuse_separations_sides;
}

// The options and the part's name, which every quantization reads, into a memo key.
void digest_options(Digest& d, const QuantizeOptions& o, const std::string& part_name) {
  d.text(part_name);
  for (double v : {o.position_weight, o.max_side_change, o.outside_band_weight, o.gap, o.dive_gap, o.broken_coupling_cost,
                   o.graded ? o.graded_fewer_weight : 1.0, o.localize_max_fraction})
    d.real(v);
  for (long long v : {static_cast<long long>(o.max_separation_rounds), static_cast<long long>(o.time_limit_ms),
                      static_cast<long long>(o.large_program_columns), static_cast<long long>(o.screen_separations),
                      static_cast<long long>(o.reuse_separations_sides), static_cast<long long>(o.localize_rings)})
    d.word(static_cast<std::uint64_t>(v));
}

// What the quantization reads of one layout (find_conflicts and check-free solves read its sides and break
// points, the program their deformed positions) into a memo key.
void digest_layout(Digest& d, const Layout& layout, const std::vector<Vec2>& deformed) {
  auto integer = [&](long long v) { d.word(static_cast<std::uint64_t>(v)); };
  d.raw(layout.break_vertex);
  integer(static_cast<long long>(layout.segments.size()));
  for (const LayoutSegment& s : layout.segments) {  // field by field: the struct has padding
    for (int v : {s.chain, s.first, s.count, s.label, s.break_a, s.break_b}) integer(v);
    d.real(s.target);
  }
  for (std::int32_t v : layout.break_vertex) {
    d.real(deformed[static_cast<std::size_t>(v)].x);
    d.real(deformed[static_cast<std::size_t>(v)].y);
  }
}

// The key of `layout`'s quantization alone.
std::array<std::uint64_t, 2> alone_key(const Layout& layout, const std::vector<Vec2>& deformed,
                                       const QuantizeOptions& o, const std::string& part_name) {
  Digest d;
  digest_options(d, o, part_name);
  digest_layout(d, layout, deformed);
  return d.key();
}

// The key of the separations `layout` ended with in its last large joint program (QuantizeMemo::Impl::learned):
// the layout alone, whatever the options (a separation is a choice any program of the layout may start from).
std::array<std::uint64_t, 2> learned_key(const Layout& layout, const std::vector<Vec2>& deformed,
                                         const std::string& part_name) {
  Digest d;
  d.word(2);  // never equal to an alone or a joint key
  d.text(part_name);
  digest_layout(d, layout, deformed);
  return d.key();
}

// The key of a joint quantization: its layouts, couplings and even groups, and whether its couplings are
// elastic.
std::array<std::uint64_t, 2> joint_key(const std::vector<Layout*>& layouts,
                                       const std::vector<const std::vector<Vec2>*>& deformed,
                                       const std::vector<SegmentCoupling>& couplings, const QuantizeOptions& o,
                                       const std::string& part_name, const std::vector<EvenGroup>& even_groups,
                                       bool elastic) {
  Digest d;
  d.word(1);  // a joint key, never equal to a layout's alone
  digest_options(d, o, part_name);
  d.word(elastic ? 1 : 0);
  d.word(layouts.size());
  // Separations a program does not start from are not read: the key stays the one of its first solve.
  const bool reuse = reuses_separations(layouts, couplings, even_groups, o);
  for (std::size_t l = 0; l < layouts.size(); ++l) {
    digest_layout(d, *layouts[l], *deformed[l]);
    if (!reuse) continue;
    d.word(layouts[l]->separations.size());
    for (const auto& sep : layouts[l]->separations)
      for (int v : sep) d.word(static_cast<std::uint64_t>(static_cast<std::int64_t>(v)));
  }
  d.word(couplings.size());
  for (const SegmentCoupling& c : couplings)
    for (std::size_t v : {c.layout_a, static_cast<std::size_t>(c.segment_a), c.layout_b,
                          static_cast<std::size_t>(c.segment_b), static_cast<std::size_t>(c.transition)})
      d.word(v);
  d.word(even_groups.size());
  for (const EvenGroup& g : even_groups) {
    d.word(g.size());
    for (const auto& [l, k] : g) d.word(l), d.word(static_cast<std::uint64_t>(k));
  }
  return d.key();
}

}  // namespace

namespace {

// Solves the program; where sides overlap or corners coincide, adds the separation the deformed layout shows and
// solves again (a few rounds settle it: each round only adds constraints the deformed plane satisfies).
QuantizeStats solve_with_separations(JointProblem& jp, const std::vector<SegmentCoupling>& couplings,
                                     const std::vector<EvenGroup>& even_groups, std::vector<Separation>& separations,
                                     const QuantizeOptions& options, const std::string& part_name,
                                     std::vector<std::size_t>* broken) {
  QuantizeStats stats;
  int round = 0;
  std::vector<Separation> rejected;  // separations that contradicted their layout's others
  // The last round's choices: per layout given separations, per conflict the separations not tried yet, the one
  // with the largest margin in the deformed plane (the one added) first.
  std::vector<std::pair<std::size_t, std::vector<std::vector<Separation>>>> choices;
  std::size_t round_start = 0;  // separations before the last round's
  auto tried = [&](const Separation& sep) {
    return std::find(separations.begin(), separations.end(), sep) != separations.end() ||
           std::find(rejected.begin(), rejected.end(), sep) != rejected.end();
  };
  // One program for all rounds: a round adds its separations as rows, and the solver starts from the last
  // round's basis.
  IntegerProgram P = joint_program(jp, couplings, even_groups, options, part_name, broken != nullptr);
  for (std::size_t in_program = 0;; ) {
    stats = QuantizeStats{};
    if (broken) broken->clear();
    try {
      solve_joint(jp, P, couplings, separations, in_program, options, part_name, stats, broken);
    } catch (const MeshingError&) {
      // The round's separations were screened before the solve, so what fails is the joint program itself (a
      // warm start that did not end optimal, coupling or parity rows): it is built again and solved from scratch
      // once with them.
      if (!options.screen_separations || choices.empty()) throw;
      choices.clear();
      P = joint_program(jp, couplings, even_groups, options, part_name, broken != nullptr);
      in_program = 0;
      continue;
    }
    in_program = separations.size();
    if (++round > options.max_separation_rounds) break;
    round_start = separations.size();
    choices.clear();
    for (std::size_t l = 0; l < jp.layouts.size(); ++l) {
      const Layout& layout = *jp.layouts[l];
      std::vector<std::vector<Separation>> mine;
      for (const LayoutConflict& c : find_conflicts(layout, 64)) {
        std::vector<int> A, B;
        if (c.seg_a >= 0) {
          A = {layout.segments[c.seg_a].break_a, layout.segments[c.seg_a].break_b};
          B = {layout.segments[c.seg_b].break_a, layout.segments[c.seg_b].break_b};
        } else {
          A = {c.break_a};
          B = {c.break_b};
        }
        std::vector<Separation> cand = separation_candidates(layout, static_cast<int>(l), *jp.deformed[l], A, B, jp.cls[l]);
        // A conflict whose best separation is in the program already (or was refused) is left as it is.
        if (cand.empty() || tried(cand.front())) continue;
        const Separation best = cand.front();
        separations.push_back(best);
        std::erase_if(cand, [&](const Separation& sep) { return sep != best && tried(sep); });
        mine.push_back(std::move(cand));
      }
      if (!mine.empty()) choices.push_back({l, std::move(mine)});
    }
    if (separations.size() == round_start) break;
    // Separations chosen one conflict at a time can contradict each other or their layout's sides (the deformed
    // plane holds each of them, not their integer margins all at once), and one layout that cannot close leaves
    // the whole program without a solution. So each layout's are tried on it alone before they join the
    // program (a network program, about a millisecond): where the best of each do not close, each conflict
    // takes its first choice that closes with those kept before it, or none (the layout keeps that conflict, and
    // check_layout fails it alone). The program then goes on from its last basis instead of being built and
    // solved again from scratch (3 s per solve at 30k columns, about ten times the warm solve).
    // Layouts are screened in parallel (each sees only its own separations), then joined in their order.
    if (options.screen_separations) {
      std::vector<std::vector<Separation>> earlier(jp.layouts.size());  // each layout's from the rounds before
      for (std::size_t k = 0; k < round_start; ++k) earlier[static_cast<std::size_t>(separations[k].layout)].push_back(separations[k]);
      std::vector<std::vector<Separation>> kept(choices.size()), refused(choices.size());
      oneapi::tbb::parallel_for(std::size_t{0}, choices.size(), [&](std::size_t i) {
        const auto& [l, mine] = choices[i];
        std::vector<Separation> now = earlier[l];  // then this round's
        const std::size_t first_new = now.size();
        for (const auto& cand : mine) now.push_back(cand.front());
        if (!closes_alone(jp, l, now, options, part_name)) {
          now.resize(first_new);
          for (const auto& cand : mine)
            for (const Separation& sep : cand) {
              now.push_back(sep);
              if (closes_alone(jp, l, now, options, part_name)) break;
              now.pop_back();
              refused[i].push_back(sep);
            }
        }
        kept[i].assign(now.begin() + static_cast<std::ptrdiff_t>(first_new), now.end());
      });
      separations.resize(round_start);
      for (std::size_t i = 0; i < choices.size(); ++i) {
        separations.insert(separations.end(), kept[i].begin(), kept[i].end());
        rejected.insert(rejected.end(), refused[i].begin(), refused[i].end());
      }
    }
  }
  // A layout alone whose overlap no separation can undo has no solution; in a joint program such a layout is
  // left to check_layout, which fails that subregion alone.
  if (jp.layouts.size() == 1 && !rejected.empty() && !find_conflicts(*jp.layouts[0], 1).empty())
    throw no_integer_solution(part_name);
  stats.separations = separations.size();
  return stats;
}

JointProblem joint_problem(const std::vector<Layout*>& layouts, const std::vector<const std::vector<Vec2>*>& deformed) {
  JointProblem jp;
  jp.layouts = layouts;
  jp.deformed = deformed;
  jp.cls.resize(layouts.size());
  jp.ncls.resize(layouts.size());
  jp.col0.resize(layouts.size());
  for (std::size_t l = 0; l < layouts.size(); ++l)
    for (int axis = 0; axis < 2; ++axis) jp.cls[l][axis] = axis_classes(*layouts[l], axis, jp.ncls[l][axis]);
  return jp;
}

bool closes_alone(const JointProblem& jp, std::size_t l, const std::vector<Separation>& separations,
                  const QuantizeOptions& options, const std::string& part_name) {
  JointProblem one = joint_problem({jp.layouts[l]}, {jp.deformed[l]});
  IntegerProgram P;
  try {
    P = joint_program(one, {}, {}, options, part_name, false);
  } catch (const MeshingError&) {
    return false;
  }
  for (const Separation& sep : separations)
    if (sep.layout == static_cast<int>(l))
      P.add_row({{one.col(0, sep.axis, sep.hi), 1.0}, {one.col(0, sep.axis, sep.lo), -1.0}}, 1.0, IntegerProgram::inf);
  // Any integer point answers: a dive's is taken at any cost.
  return P.solve(options.time_limit_ms / 1000.0, options.gap, IntegerProgram::inf, one.large).has_value();
}

}  // namespace

namespace {

QuantizeStats quantize_unmemoized(const std::vector<Layout*>& layouts,
                                  const std::vector<const std::vector<Vec2>*>& deformed,
                                  const std::vector<SegmentCoupling>& couplings, const QuantizeOptions& options,
                                  const std::string& part_name, const std::vector<EvenGroup>& even_groups,
                                  std::vector<std::size_t>* broken,
                                  std::vector<JointProblem::FixedCount> fixed = {},
                                  std::vector<long long> even_offset = {}) {
  JointProblem jp = joint_problem(layouts, deformed);
  jp.fixed = std::move(fixed);
  jp.even_offset = std::move(even_offset);
  std::vector<Separation> separations;
  // A joint program is a mixed-integer one, each solve of it costly; each layout alone is a network program
  // solved in milliseconds. The separations each layout needs alone start the joint program, which then
  // mostly settles in one or two rounds instead of one per separation found.
  // A layout that cannot close alone (no solution for its sides, or overlaps that no separation undoes) is said
  // at once, naming it, instead of after failed solves of the whole. Keeping one whose overlaps might close with
  // its neighbours' counts was measured worse (delta_box ensembles: it fails later, after the joint solve).
  std::vector<std::size_t> cannot_close;
  std::vector<std::string> reasons;
  const bool reuse = reuses_separations(layouts, couplings, even_groups, options);
  if (!jp.fixed.empty() || (layouts.size() > 1 && (!couplings.empty() || !even_groups.empty()))) {
    // Each layout alone, in parallel (they share nothing), then collected in layout order.
    std::vector<std::vector<Separation>> own(layouts.size());
    std::vector<std::optional<std::string>> why_not(layouts.size());
    oneapi::tbb::parallel_for(std::size_t{0}, layouts.size(), [&](std::size_t l) {
      std::array<std::uint64_t, 2> key{};
      if (options.memo) {
        key = alone_key(*layouts[l], *deformed[l], options, part_name);
        if (QuantizeMemoAccess::find(*options.memo, key, own[l], why_not[l])) return;
      }
      Layout alone = *layouts[l];
      JointProblem one = joint_problem({&alone}, {deformed[l]});
      try {
        solve_with_separations(one, {}, {}, own[l], options, part_name, nullptr);
      } catch (const MeshingError& e) {
        std::string why = e.what();
        if (why.starts_with(part_name + ": ")) why.erase(0, part_name.size() + 2);
        why_not[l] = std::move(why);
      }
      if (options.memo) QuantizeMemoAccess::store(*options.memo, key, own[l], why_not[l]);
    });
    for (std::size_t l = 0; l < layouts.size(); ++l) {
      if (why_not[l]) {
        cannot_close.push_back(l);
        reasons.push_back(*why_not[l]);
        continue;
      }
      // A layout met in an earlier joint quantization (a map's program solved again without the subregions
      // that failed, or with elastic couplings) starts from the separations that one ended with, which hold its
      // own: each such program otherwise found them again, one round of a large solve per batch (the
      // 5,000-feature region: 51 -> 25 solves, 79 -> 31 s).
      if (reuse && !layouts[l]->separations.empty()) {
        for (const auto& [axis, lo, hi] : layouts[l]->separations)
          separations.push_back({static_cast<int>(l), axis, lo, hi});
        continue;
      }
      for (Separation sep : own[l]) {
        sep.layout = static_cast<int>(l);
        separations.push_back(sep);
      }
    }
  }
  if (!cannot_close.empty())
    throw LayoutsCannotClose(part_name + ": " + std::to_string(cannot_close.size()) + " of " +
                                 std::to_string(layouts.size()) + " poly-squares cannot close alone (" + reasons.front() + ")",
                             cannot_close, reasons);
  // The layouts' own separations are not dropped when the joint program fails: each closes with its layout,
  // so what fails is the couplings (the caller's elastic solve names them). A second solve without them
  // succeeded in none of 42 such failures on delta_box 40 m, at a cold solve of the whole program each.
  const QuantizeStats stats = solve_with_separations(jp, couplings, even_groups, separations, options, part_name, broken);
  if (reuse) {
    for (Layout* layout : layouts) layout->separations.clear();
    for (const Separation& sep : separations)
      layouts[static_cast<std::size_t>(sep.layout)]->separations.push_back({sep.axis, sep.lo, sep.hi});
  }
  return stats;
}

// A large joint program whose layouts mostly kept the lattices an earlier map of the part gave them (`known`,
// empty where a layout is new): only the new layouts, those whose known counts disagree with a neighbour's or
// that border a patch (even groups), and their neighbours out to options.localize_rings couplings are solved; the
// sides they share with the rest take the rest's known counts. nullopt when that is more than
// options.localize_max_fraction of the sides, or when the smaller program has no solution (the caller then
// solves the whole).
std::optional<QuantizeStats> quantize_locally(const std::vector<Layout*>& layouts,
                                              const std::vector<const std::vector<Vec2>*>& deformed,
                                              const std::vector<SegmentCoupling>& couplings,
                                              const QuantizeOptions& options, const std::string& part_name,
                                              const std::vector<EvenGroup>& even_groups,
                                              const std::vector<std::vector<std::array<long long, 2>>>& known) {
  const std::size_t n = layouts.size();
  std::vector<std::uint8_t> solve(n, 0);
  for (std::size_t l = 0; l < n; ++l) solve[l] = known[l].size() != layouts[l]->break_vertex.size();
  auto known_count = [&](std::size_t l, int k) {
    return lattice_count(layouts[l]->segments[static_cast<std::size_t>(k)], known[l]);
  };
  // An even group whose members all kept lattices that sum to an even count is met already.
  for (const EvenGroup& g : even_groups) {
    long long sum = 0;
    bool all_known = true;
    for (const auto& [l, k] : g) {
      all_known = all_known && !solve[l];
      if (!solve[l]) sum += known_count(l, k);
    }
    if (!all_known || sum % 2 != 0)
      for (const auto& [l, k] : g) solve[l] = 1;
  }
  std::vector<std::vector<std::size_t>> next(n);
  for (const SegmentCoupling& c : couplings) {
    next[c.layout_a].push_back(c.layout_b), next[c.layout_b].push_back(c.layout_a);
    if (solve[c.layout_a] || solve[c.layout_b]) continue;
    const long long d = known_count(c.layout_a, c.segment_a) - known_count(c.layout_b, c.segment_b);
    if (c.transition ? d % 2 != 0 : d != 0) solve[c.layout_a] = solve[c.layout_b] = 1;
  }
  for (int ring = 0; ring < options.localize_rings; ++ring) {
    std::vector<std::uint8_t> grown = solve;
    for (std::size_t l = 0; l < n; ++l)
      if (solve[l])
        for (std::size_t q : next[l]) grown[q] = 1;
    solve = std::move(grown);
  }
  std::size_t sides = 0, solved_sides = 0;
  for (std::size_t l = 0; l < n; ++l) {
    sides += layouts[l]->segments.size();
    solved_sides += solve[l] ? layouts[l]->segments.size() : 0;
  }
  if (static_cast<double>(solved_sides) > options.localize_max_fraction * static_cast<double>(sides)) return std::nullopt;
  // The smaller program: the solved layouts, their couplings among themselves, and the known counts across.
  std::vector<std::int64_t> index(n, -1);
  std::vector<std::size_t> full;  // the layout of each in the smaller program
  std::vector<Layout*> sub;
  std::vector<const std::vector<Vec2>*> sub_deformed;
  for (std::size_t l = 0; l < n; ++l)
    if (solve[l]) {
      index[l] = static_cast<std::int64_t>(sub.size());
      full.push_back(l), sub.push_back(layouts[l]), sub_deformed.push_back(deformed[l]);
    }
  std::vector<SegmentCoupling> sub_couplings;
  std::vector<JointProblem::FixedCount> fixed;
  for (const SegmentCoupling& c : couplings) {
    const std::int64_t a = index[c.layout_a], b = index[c.layout_b];
    if (a >= 0 && b >= 0)
      sub_couplings.push_back({static_cast<std::size_t>(a), c.segment_a, static_cast<std::size_t>(b), c.segment_b, c.transition});
    else if (a >= 0)
      fixed.push_back({static_cast<std::size_t>(a), c.segment_a, known_count(c.layout_b, c.segment_b), c.transition});
    else if (b >= 0)
      fixed.push_back({static_cast<std::size_t>(b), c.segment_b, known_count(c.layout_a, c.segment_a), c.transition});
  }
  // Even groups with a member in the program; the members outside add their known counts.
  std::vector<EvenGroup> sub_even;
  std::vector<long long> even_offset;
  for (const EvenGroup& g : even_groups) {
    EvenGroup h;
    long long offset = 0;
    for (const auto& [l, k] : g) {
      if (index[l] >= 0) h.push_back({static_cast<std::size_t>(index[l]), k});
      else offset += known_count(l, k);
    }
    if (h.empty()) continue;
    sub_even.push_back(std::move(h));
    even_offset.push_back(offset);
  }
  QuantizeStats stats;
  const auto t0 = std::chrono::steady_clock::now();
  if (!sub.empty()) {
    std::vector<std::vector<std::array<long long, 2>>> before;
    for (const Layout* l : sub) before.push_back(l->lattice);
    try {
      stats = quantize_unmemoized(sub, sub_deformed, sub_couplings, options, part_name, sub_even, nullptr, std::move(fixed),
                                  std::move(even_offset));
    } catch (const LayoutsCannotClose& e) {  // as in the whole program: those layouts do not close alone
      std::vector<std::size_t> which;
      for (std::size_t i : e.layouts) which.push_back(full[i]);
      throw LayoutsCannotClose(part_name + ": " + std::to_string(which.size()) + " of " + std::to_string(n) +
                                   " poly-squares cannot close alone (" + e.reasons.front() + ")",
                               std::move(which), e.reasons);
    } catch (const MeshingError&) {
      for (std::size_t i = 0; i < sub.size(); ++i) sub[i]->lattice = std::move(before[i]);
      return std::nullopt;
    }
  }
  stats.segments = 0;
  for (std::size_t l = 0; l < n; ++l) {
    Layout& layout = *layouts[l];
    if (!solve[l]) layout.lattice = known[l];
    stats.max_relative_deviation = std::max(stats.max_relative_deviation, max_relative_deviation(layout));
    stats.segments += static_cast<int>(layout.segments.size());
  }
  spdlog::debug("{}: joint quantization solved locally: {} of {} layouts ({} of {} sides), {:.2f} s", part_name, sub.size(), n,
                solved_sides, sides, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  return stats;
}

// A memo's joint outcome replayed: the lattices, then the figures or the error.
QuantizeStats replay(const QuantizeMemoAccess::Joint& joint, const std::vector<Layout*>& layouts,
                     std::vector<std::size_t>* broken) {
  for (std::size_t l = 0; l < layouts.size(); ++l) {
    layouts[l]->lattice = joint.lattices[l];
    layouts[l]->separations = joint.separations[l];
  }
  if (!joint.cannot_close.empty()) throw LayoutsCannotClose(*joint.error, joint.cannot_close, joint.reasons);
  if (joint.error) throw MeshingError(*joint.error);
  if (broken) *broken = joint.broken;
  return joint.stats;
}

}  // namespace

QuantizeStats quantize_layouts(const std::vector<Layout*>& layouts, const std::vector<const std::vector<Vec2>*>& deformed,
                               const std::vector<SegmentCoupling>& couplings, const QuantizeOptions& options,
                               const std::string& part_name, const std::vector<EvenGroup>& even_groups,
                               std::vector<std::size_t>* broken) {
  if (!options.memo) return quantize_unmemoized(layouts, deformed, couplings, options, part_name, even_groups, broken);
  // A large program's layouts met in an earlier map of the part (a joint split round, a repair round, the pulled
  // snaps: each maps the part again, most subregions unchanged) start from the separations they ended with there;
  // each new map otherwise found them again in rounds of a large solve (graded delta_box: 4-6 per map).
  const bool reuse = reuses_separations(layouts, couplings, even_groups, options);
  std::vector<std::array<std::uint64_t, 2>> layout_keys;
  std::vector<std::vector<std::array<long long, 2>>> known(layouts.size());
  if (reuse)
    for (std::size_t l = 0; l < layouts.size(); ++l) {
      layout_keys.push_back(learned_key(*layouts[l], *deformed[l], part_name));
      if (auto learned = QuantizeMemoAccess::find_learned(*options.memo, layout_keys.back())) {
        if (layouts[l]->separations.empty()) layouts[l]->separations = std::move(learned->separations);
        known[l] = std::move(learned->lattice);
      }
    }
  // The repair rounds and the candidates with and without transition rows quantize the same subregions again
  // (graded delta_box: 5 solves of a 64,519-column program, twice).
  const auto key = joint_key(layouts, deformed, couplings, options, part_name, even_groups, broken != nullptr);
  if (const auto joint = QuantizeMemoAccess::find_joint(*options.memo, key)) return replay(*joint, layouts, broken);
  QuantizeMemoAccess::Joint joint;
  auto store = [&] {
    for (const Layout* l : layouts) joint.lattices.push_back(l->lattice), joint.separations.push_back(l->separations);
    QuantizeMemoAccess::store_joint(*options.memo, key, std::move(joint));
  };
  try {
    std::optional<QuantizeStats> local;
    if (reuse && !broken && options.localize_rings >= 0)
      local = quantize_locally(layouts, deformed, couplings, options, part_name, even_groups, known);
    joint.stats = local ? *local : quantize_unmemoized(layouts, deformed, couplings, options, part_name, even_groups, broken);
  } catch (const LayoutsCannotClose& e) {
    joint.error = e.what(), joint.cannot_close = e.layouts, joint.reasons = e.reasons;
    store();
    throw;
  } catch (const MeshingError& e) {
    joint.error = e.what();
    store();
    throw;
  }
  if (broken) joint.broken = *broken;
  for (std::size_t l = 0; l < layout_keys.size(); ++l)
    QuantizeMemoAccess::store_learned(*options.memo, layout_keys[l], *layouts[l]);
  store();
  return joint.stats;
}

QuantizeStats quantize_layouts_shared(const WorkSharing* sharing, const std::vector<Layout*>& layouts,
                                      const std::vector<const std::vector<Vec2>*>& deformed,
                                      const std::vector<SegmentCoupling>& couplings, const QuantizeOptions& options,
                                      const std::string& part_name, const std::vector<EvenGroup>& even_groups,
                                      std::vector<std::size_t>* broken) {
  QuantizeStats q;
  std::string error;
  std::vector<std::size_t> broken_here, cannot_close;
  std::vector<std::string> reasons;
  shared_for(sharing, 1, {}, "quantize", [&](std::size_t) {
    try {
      q = quantize_layouts(layouts, deformed, couplings, options, part_name, even_groups, broken ? &broken_here : nullptr);
    } catch (const LayoutsCannotClose& e) {
      error = e.what();
      cannot_close = e.layouts;
      reasons = e.reasons;
    } catch (const MeshingError& e) {
      error = e.what();  // shared like a result: the lattices it left are copied too
    }
  }, [&](std::size_t, ByteWriter& w) {
    w.put(error), w.put(q), w.put(broken_here), w.put(cannot_close), w.put(reasons);
    for (const Layout* l : layouts) w.put(l->lattice), w.put(l->separations);
  }, [&](std::size_t, ByteReader& r) {
    r.get(error), r.get(q), r.get(broken_here), r.get(cannot_close), r.get(reasons);
    for (Layout* l : layouts) r.get(l->lattice), r.get(l->separations);
  });
  if (!cannot_close.empty()) throw LayoutsCannotClose(error, cannot_close, reasons);
  if (!error.empty()) throw MeshingError(error);
  if (broken) *broken = std::move(broken_here);
  return q;
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
