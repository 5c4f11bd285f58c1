// A small sparse (mixed-integer) linear program and its solution with COIN-OR: the LP relaxation by Clp, a dive
// from it when that is fractional, and Cbc's branch-and-cut only when the dive is not good enough. Internal to
// the map module (quantization).
#pragma once

#include <memory>
#include <optional>
#include <utility>
#include <vector>

namespace polysquare {

/// min c^T x subject to row_lo <= A x <= row_hi and col_lo <= x <= col_hi, some x integer.
class IntegerProgram {
 public:
  static constexpr double inf = 1e30;  ///< an absent bound (COIN-OR's infinity)

  /// Adds `count` columns with the given bounds, objective coefficient and kind; returns the first one's index.
  int add_columns(int count, double lo, double hi, double cost = 0.0, bool integer = false);
  /// Adds the row lo <= sum of coefficient * column <= hi. A column named twice in one row has its coefficients
  /// summed.
  void add_row(std::initializer_list<std::pair<int, double>> terms, double lo, double hi);
  void add_row(const std::vector<std::pair<int, double>>& terms, double lo, double hi);

  /// Marks an integer column whose coefficients make the program leave network form (a 2 in a coupling row):
  /// when the relaxation leaves such columns fractional, solve() first fixes them all at their rounded values
  /// (halves down) and solves again; should that have no solution, at `fallback` (see solve()).
  void round_first(int column, double fallback) { round_first_.push_back({column, fallback}); }

  int columns() const { return static_cast<int>(cost_.size()); }
  int rows() const { return static_cast<int>(row_lo_.size()); }

  /// The optimal column values: the LP relaxation's optimum when its integer columns are integral (it is then
  /// the integer optimum too); otherwise a dive from it (fractional columns fixed one by one, the LP re-solved
  /// from its last basis) when that ends within `dive_gap` of the LP's cost; otherwise branch-and-cut's, started
  /// from the dive's point, which stops at a point whose cost is within `gap` of the best bound (or at its best
  /// feasible point when stopped by the time limit); nullopt when the program is infeasible or branch-and-cut
  /// found no feasible point within `seconds` (LP solves have no limit: they always end, and the answer does not
  /// depend on the machine's load).
  /// Columns marked round_first() are rounded and fixed before the dive when one of them is fractional; should
  /// that leave no solution, they are fixed at their fallback values instead, and released when that has none
  /// either.
  /// Solving again after rows were added starts from the last solve's LP basis (the dual simplex).
  /// `large`: the relaxation is solved from scratch by the dual simplex instead of the primal, and each step of
  /// the dive fixes every fractional column at once (else the half nearest to integers, a quarter, ..., one
  /// column), and a dive that dead-ends (a column infeasible on both sides) starts again with only that column
  /// fixed; when the dive finds no point, the answer is nullopt without branch-and-cut.
  std::optional<std::vector<double>> solve(double seconds, double gap = 0.0, double dive_gap = 0.0, bool large = false);

  /// What the last solve did: its dive's restarts, and whether it went on to branch-and-cut.
  int dive_restarts() const { return dive_restarts_; }
  bool branched() const { return branched_; }

  IntegerProgram();
  ~IntegerProgram();
  IntegerProgram(IntegerProgram&&) noexcept;
  IntegerProgram& operator=(IntegerProgram&&) noexcept;

 private:
  struct Lp;  // the LP relaxation's model as the last solve left it
  bool solve_relaxation(bool large);
  int fractional_column(std::vector<int>* all) const;
  void fix_round_first(int& keep);
  bool fix_nearest_first(const std::vector<int>& batch, std::vector<int>& fixed, int& keep);
  void release(int column);  // back to its own bounds in the LP
  std::optional<std::vector<double>> branch_and_cut(double seconds, double gap,
                                                    const std::optional<std::vector<double>>& dived);
  std::unique_ptr<Lp> lp_;
  std::vector<double> col_lo_, col_hi_, cost_;
  std::vector<char> integer_;
  std::vector<std::pair<int, double>> round_first_;  // column, fallback value
  std::vector<double> row_lo_, row_hi_;
  std::vector<int> entry_row_, entry_col_;
  std::vector<double> entry_value_;
  int dive_restarts_ = 0;
  bool branched_ = false;
};

}  // namespace polysquare
