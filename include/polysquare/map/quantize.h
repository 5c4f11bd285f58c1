// Stage 5: integer quantization of a poly-square layout (interval assignment).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "polysquare/core/error.h"

#include "polysquare/core/work_sharing.h"
#include "polysquare/map/layout.h"

namespace polysquare {

class QuantizeMemo;

struct QuantizeOptions {
  double position_weight = 1e-3;  ///< weak pull of each break point towards its deformed position (anchors
                                  ///< pieces, such as interior features, that no segment ties to the boundary)
  double max_side_change = 2.5;   ///< band [t / 2.5, 2.5 t] for a side of target length t (every side gets >= 1)
  double outside_band_weight = 20.0;  ///< cost per element outside the band, relative to the cost inside it: the
                                      ///< band is soft so that tight layouts still close; quality checks judge them
  int max_separation_rounds = 20; ///< rounds of re-solving with separations between overlapping sides
  int time_limit_ms = 20000;      ///< time limit of each LP (Clp) or branch-and-cut (Cbc) solve
  double gap = 1.0;  ///< branch-and-cut stops within this cost of the optimum: one element of deviation on a
                     ///< side of target length 1 (proving optimality among the many near-equal parity choices
                     ///< of a coast's joint program took up to the time limit per solve)
  double dive_gap = 5.0;  ///< a fractional LP optimum is dived from (columns fixed one by one), and the dive's
                         ///< point kept when its cost is within this of the LP's per 1000 sides of the program
                         ///< (at least this: five elements of deviation on unit sides); else branch-and-cut
                         ///< (only up to large_program_columns)
  int large_program_columns = 5000;  ///< above this many columns (counted in the inequality form) a program is
                                     ///< built in a compact form (one equality row per side and per anchor:
                                     ///< about a third of the rows) and solved by the dual simplex, its dive fixes
                                     ///< every fractional column at once, and the dive's integer point is
                                     ///< kept at any cost: branch-and-cut ran to the time limit and kept the
                                     ///< dive's point on each such program measured (25k columns, 20 s per
                                     ///< solve), and what it returns at a time limit depends on the machine
  double transition_cost = 2.0;  ///< graded PPM: cost of one transition fan on a coupling marked `transition`
                                 ///< (two elements of mismatch, two singular nodes), relative to the coupled
                                 ///< target as the sides' deviations are; 0 = no coupling is marked
  double graded_fewer_weight = 2.0;  ///< graded meshes (`graded`): an element fewer than a side's target costs this
                                     ///< many times an element more, inside and beyond the band (the field is the
                                     ///< largest size wanted, so a side would rather have quads smaller than it)
  bool graded = false;  ///< the layouts' targets are in units of a size field's local size (the pipeline sets it)
  bool screen_separations = true;  ///< each round's separations are tried on their layout alone before they join
                                   ///< the program; those that contradict its sides or each other give way to the
                                   ///< next choice for their conflict (false: added as found, and the solve fails)
  std::size_t reuse_separations_sides = 5000;  ///< joint programs of more sides than this start from the
                                              ///< separations their layouts' last joint quantization ended with
                                              ///< (Layout::separations): a round costs a large solve (1-2 s at 60k
                                              ///< columns; the 5,000-feature region: 51 -> 25 solves). Below, a
                                              ///< round costs a tenth of a second and the carried separations
                                              ///< narrow the optimum (delta_box 200 m, 4 rotations, medians:
                                              ///< 22.1 -> 22.9 interior singular nodes per 1000 quads)
  int localize_rings = 1;  ///< joint programs of more than reuse_separations_sides sides whose layouts mostly met
                           ///< an earlier map of the part (a split round, a repair round, the pulled snaps) solve
                           ///< only what changed and this many couplings around it, the rest keeping its
                           ///< counts (quantize_locally); -1 = always the whole program
  double localize_max_fraction = 0.3;  ///< ... when that is at most this fraction of the sides
  double broken_coupling_cost = 1e4;  ///< cost per element of an elastic coupling's mismatch (quantize_layouts
                                      ///< with `broken`): above any saving in deviation, so only what cannot agree breaks
  /// Each layout's quantization alone (the separations it needs, or why it cannot close) and each joint
  /// quantization's outcome, shared by the copies of these options within one run (the pipeline sets it; null =
  /// none): every joint solve starts from the former, and the joint maps, their re-solves and the repair rounds
  /// meet the same layouts, and the same joint programs, again.
  std::shared_ptr<QuantizeMemo> memo;
};

/// Each layout's quantization alone and each joint quantization (see QuantizeOptions::memo), by a 128-bit digest
/// of what it reads (the layouts' sides and break points, their deformed positions, the couplings and even
/// groups, the options, the part's name); the solve is deterministic, so a reused result is the one a new solve
/// would give (or, where branch-and-cut stopped at its time limit, the one this run gave before). Thread-safe.
class QuantizeMemo {
 public:
  QuantizeMemo();
  ~QuantizeMemo();
  QuantizeMemo(const QuantizeMemo&) = delete;
  QuantizeMemo& operator=(const QuantizeMemo&) = delete;
  std::size_t hits() const;

 private:
  friend struct QuantizeMemoAccess;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

struct QuantizeStats {
  double max_relative_deviation = 0.0;  ///< max over segments of |n - target| / max(target, 1)
  int segments = 0;
  int variables = 0;
  std::size_t separations = 0;  ///< separation constraints added to undo overlaps
};

/// Two sides of the quantized layout that overlap (seg_a, seg_b), or two break points on one lattice point
/// (break_a, break_b; seg_a = seg_b = -1), at lattice point `at`.
struct LayoutConflict {
  int seg_a = -1, seg_b = -1, break_a = -1, break_b = -1;
  std::array<long long, 2> at{};
};

/// Two segments of different layouts (the two sides of a PPM interface) that must get the same number of
/// elements.
struct SegmentCoupling {
  std::size_t layout_a = 0;
  int segment_a = 0;
  std::size_t layout_b = 0;
  int segment_b = 0;
  bool transition = false;  ///< the counts may differ by an even number, joined by a transition row (fans)
};

/// Segments (layout, segment) whose element counts must add up to an even number: the interfaces around a
/// subregion that an unstructured patch will fill (a quad mesh has an even number of boundary edges).
using EvenGroup = std::vector<std::pair<std::size_t, int>>;

/// At most max_conflicts conflicts of the quantized layout.
std::vector<LayoutConflict> find_conflicts(const Layout& layout, std::size_t max_conflicts);

/// Chooses integer lattice positions for every break point so that each segment of label +-X (+-Y) keeps y (x)
/// constant and advances by an integer n >= 1 in its direction, with n close to its target, minimizing
/// sum |n - target| / max(target, 1). X and Y are independent programs solved with Clp (Cbc with couplings); the constraint
/// matrices are network matrices, so the LP optimum is already integral. When the solution makes sides overlap,
/// the separation the deformed layout shows (one side left of / below the other) is added and the programs are
/// solved again. Fills layout.lattice. Throws MeshingError naming `part_name` when there is no solution.
QuantizeStats quantize_layout(Layout& layout, const std::vector<Vec2>& deformed, const QuantizeOptions& options,
                              const std::string& part_name);

/// Quantizes several layouts (PPM subregions, each in its own frame) in one integer program whose coupled
/// segments get equal element counts; each layout must close and keep its sides apart as in quantize_layout.
/// Without couplings the layouts are independent and the program is the totally unimodular one above.
/// With `broken` given, couplings are elastic (options.broken_coupling_cost per element of mismatch): the program
/// then fails only where a layout cannot close alone (or with its even groups and separations), and `broken`
/// receives the indices of the couplings the solution does not honour (empty when all agree). One solve locates
/// the subregions that make a joint program infeasible. Each layout is first quantized alone (its separations
/// start the joint program); layouts that cannot close alone are reported at once (LayoutsCannotClose). In a
/// program of more than options.reuse_separations_sides sides, a layout whose Layout::separations an earlier
/// joint quantization set starts from those instead, and every layout of such a program that is solved gets
/// the separations it ended with.
QuantizeStats quantize_layouts(const std::vector<Layout*>& layouts, const std::vector<const std::vector<Vec2>*>& deformed,
                               const std::vector<SegmentCoupling>& couplings, const QuantizeOptions& options,
                               const std::string& part_name, const std::vector<EvenGroup>& even_groups = {},
                               std::vector<std::size_t>* broken = nullptr);

/// quantize_layouts' error when some of its layouts cannot close even alone, so the joint program cannot either:
/// `layouts` holds their indices in the call and `reasons` why each failed alone (without the part's name).
class LayoutsCannotClose : public MeshingError {
 public:
  LayoutsCannotClose(const std::string& what, std::vector<std::size_t> layouts, std::vector<std::string> reasons)
      : MeshingError(what), layouts(std::move(layouts)), reasons(std::move(reasons)) {}
  std::vector<std::size_t> layouts;
  std::vector<std::string> reasons;
};

/// quantize_layouts solved by one of the processes of `sharing` (null: this one), its lattices, statistics and
/// broken couplings (or its error) copied to the others: the solver's wall-clock limit (time_limit_ms) then
/// decides for all of them, so they cannot part ways.
QuantizeStats quantize_layouts_shared(const WorkSharing* sharing, const std::vector<Layout*>& layouts,
                                      const std::vector<const std::vector<Vec2>*>& deformed,
                                      const std::vector<SegmentCoupling>& couplings, const QuantizeOptions& options,
                                      const std::string& part_name, const std::vector<EvenGroup>& even_groups = {},
                                      std::vector<std::size_t>* broken = nullptr);
/// Checks that the quantized layout is a valid poly-square: no zero-length segment, and segments of different
/// chains or non-adjacent segments of one chain meet only at shared break points. Returns an empty string when
/// valid, otherwise a description of the first conflict.
std::string check_layout(const Layout& layout);

}  // namespace polysquare
