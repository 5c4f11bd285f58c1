#include "map/integer_program.h"

#include <Cbc_C_Interface.h>
#include <ClpSimplex.hpp>

#include <algorithm>
#include <cmath>
#include <memory>
#include <mutex>
#include <numeric>

namespace polysquare {
namespace {

// Cbc_solve runs CbcMain1, which keeps some state in statics; Clp models are independent. Branch-and-cut calls
// are therefore serialized (they take milliseconds to seconds), LP solves run in parallel.
std::mutex cbc_mutex;

// The program's matrix in compressed sparse columns, duplicates summed and zeros dropped.
struct Csc {
  std::vector<CoinBigIndex> start;
  std::vector<int> index;
  std::vector<double> value;
};

Csc compress(int columns, const std::vector<int>& rows, const std::vector<int>& cols, const std::vector<double>& values) {
  std::vector<std::size_t> order(values.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return cols[a] != cols[b] ? cols[a] < cols[b] : rows[a] < rows[b];
  });
  // Entries in column-major order, repeats summed; then the zeros dropped while the column starts are counted.
  std::vector<int> col_of, row_of;
  std::vector<double> sum;
  for (std::size_t i : order) {
    if (!sum.empty() && col_of.back() == cols[i] && row_of.back() == rows[i]) {
      sum.back() += values[i];
      continue;
    }
    col_of.push_back(cols[i]);
    row_of.push_back(rows[i]);
    sum.push_back(values[i]);
  }
  Csc m;
  m.start.assign(static_cast<std::size_t>(columns) + 1, 0);
  for (std::size_t e = 0; e < sum.size(); ++e) {
    if (sum[e] == 0.0) continue;
    m.index.push_back(row_of[e]);
    m.value.push_back(sum[e]);
    ++m.start[static_cast<std::size_t>(col_of[e]) + 1];
  }
  for (std::size_t c = 0; c < static_cast<std::size_t>(columns); ++c) m.start[c + 1] += m.start[c];
  return m;
}

}  // namespace

int IntegerProgram::add_columns(int count, double lo, double hi, double cost, bool integer) {
  const int first = columns();
  col_lo_.insert(col_lo_.end(), static_cast<std::size_t>(count), lo);
  col_hi_.insert(col_hi_.end(), static_cast<std::size_t>(count), hi);
  cost_.insert(cost_.end(), static_cast<std::size_t>(count), cost);
  integer_.insert(integer_.end(), static_cast<std::size_t>(count), integer ? 1 : 0);
  return first;
}

void IntegerProgram::add_row(std::initializer_list<std::pair<int, double>> terms, double lo, double hi) {
  add_row(std::vector<std::pair<int, double>>(terms), lo, hi);
}

void IntegerProgram::add_row(const std::vector<std::pair<int, double>>& terms, double lo, double hi) {
  const int row = rows();
  row_lo_.push_back(lo);
  row_hi_.push_back(hi);
  for (const auto& [col, value] : terms) {
    entry_row_.push_back(row);
    entry_col_.push_back(col);
    entry_value_.push_back(value);
  }
}

struct IntegerProgram::Lp {
  std::unique_ptr<ClpSimplex> model = std::make_unique<ClpSimplex>();
  int columns = 0, rows = 0;  // the program's size when it was loaded or last extended
  std::size_t entries = 0;
};

IntegerProgram::IntegerProgram() = default;
IntegerProgram::~IntegerProgram() = default;
IntegerProgram::IntegerProgram(IntegerProgram&&) noexcept = default;
IntegerProgram& IntegerProgram::operator=(IntegerProgram&&) noexcept = default;

bool IntegerProgram::solve_relaxation(bool large) {
  ClpSimplex* model = nullptr;
  if (lp_ && lp_->columns == columns()) {
    // Rows added since the last solve join its model, the bounds a dive fixed are restored, and the dual
    // simplex starts from the last basis (still dual feasible: only rows were added).
    model = lp_->model.get();
    if (rows() > lp_->rows) {
      // The new rows' entries (row by row since the last solve), compressed as compress() does columns: the
      // matrix of the added rows, transposed.
      const auto from = static_cast<std::ptrdiff_t>(lp_->entries);
      std::vector<int> row(entry_row_.begin() + from, entry_row_.end());
      for (int& r : row) r -= lp_->rows;
      const Csc added = compress(rows() - lp_->rows, std::vector<int>(entry_col_.begin() + from, entry_col_.end()), row,
                                 std::vector<double>(entry_value_.begin() + from, entry_value_.end()));
      model->addRows(rows() - lp_->rows, row_lo_.data() + lp_->rows, row_hi_.data() + lp_->rows, added.start.data(),
                     added.index.data(), added.value.data());
    }
    model->chgColumnLower(col_lo_.data());
    model->chgColumnUpper(col_hi_.data());
    model->dual(0);
  } else {
    lp_ = std::make_unique<Lp>();
    model = lp_->model.get();
    const Csc m = compress(columns(), entry_row_, entry_col_, entry_value_);
    model->setLogLevel(0);
    model->loadProblem(columns(), rows(), m.start.data(), m.index.data(), m.value.data(), col_lo_.data(), col_hi_.data(),
                       cost_.data(), row_lo_.data(), row_hi_.data());
    // No time limit: Clp's is a deadline in the process's CPU time (every thread's) from when it is set, so on
    // two threads a large program's dive ran past it within seconds and every later step stopped at once, as
    // if infeasible (graded delta_box: each dead end of its large dives, one of them then 44 s in Cbc for
    // nothing), and answers depended on the machine's load. LP solves run to their end.
    // The primal simplex: on the small cases its choice among equal-cost optima gave the same meshes as the
    // GLPK primal simplex used before (turtle_shell SJ min 0.72; the dual simplex's choice 0.69). Large
    // programs (a coast's joint quantization, in the compact form) take the dual simplex, several times faster
    // there.
    if (large)
      model->dual(0);
    else
      model->primal(0);
  }
  lp_->columns = columns();
  lp_->rows = rows();
  lp_->entries = entry_row_.size();
  return model->status() == 0;  // 0: optimal
}

// The integer column nearest an integer without being one in the relaxation's solution, or -1; with `all`,
// every such column into it.
int IntegerProgram::fractional_column(std::vector<int>* all) const {
  const double* x = lp_->model->getColSolution();
  int best = -1;
  double off_best = 1.0;
  if (all) all->clear();
  for (std::size_t c = 0; c < cost_.size(); ++c) {
    if (!integer_[c]) continue;
    const double off = std::abs(x[c] - std::round(x[c]));
    if (off <= 1e-9) continue;
    if (all) all->push_back(static_cast<int>(c));
    if (off < off_best) {
      off_best = off;
      best = static_cast<int>(c);
    }
  }
  return best;
}

// Fan columns (coefficient 2) rounded and fixed first: the rest is then a network program with integral
// right-hand sides, mostly integral at once. Dived with them free, the dive met parity dead ends (a column
// infeasible on both sides) and branch-and-cut ran to the time limit per solve, minutes on a graded delta_box;
// where the rounded values have no solution, the fallback values (no fans) are the program without them, and
// where those have none either, the columns are released. `keep`: Clp's startFinishOptions for the next solve.
void IntegerProgram::fix_round_first(int& keep) {
  ClpSimplex* const lp = lp_->model.get();
  const double* x = lp->getColSolution();
  if (std::none_of(round_first_.begin(), round_first_.end(),
                   [&](const auto& rf) { return std::abs(x[rf.first] - std::round(x[rf.first])) > 1e-9; }))
    return;
  std::vector<double> rounded;
  for (const auto& [c, fallback] : round_first_) rounded.push_back(std::ceil(x[c] - 0.5 - 1e-9));
  double* lo = lp->columnLower();
  double* hi = lp->columnUpper();
  for (int attempt = 0; attempt < 3; ++attempt) {  // rounded, fallback, released
    for (std::size_t i = 0; i < round_first_.size(); ++i) {
      const auto c = static_cast<std::size_t>(round_first_[i].first);
      const double v = attempt == 0 ? std::clamp(rounded[i], col_lo_[c], col_hi_[c]) : round_first_[i].second;
      lo[c] = attempt == 2 ? col_lo_[c] : v;
      hi[c] = attempt == 2 ? col_hi_[c] : v;
    }
    lp->dual(0, keep);
    keep = 1 | 2;
    if (lp->status() == 0) return;
  }
}

// Branch-and-cut from the dive's point (if any): its optimum, else its best point at the time limit, else the
// dive's.
std::optional<std::vector<double>> IntegerProgram::branch_and_cut(double seconds, double gap,
                                                                  const std::optional<std::vector<double>>& dived) {
  const std::size_t n = cost_.size();
  const Csc m = compress(columns(), entry_row_, entry_col_, entry_value_);
  const std::lock_guard<std::mutex> lock(cbc_mutex);
  std::unique_ptr<Cbc_Model, void (*)(Cbc_Model*)> mip(Cbc_newModel(), Cbc_deleteModel);
  Cbc_Model* P = mip.get();
  Cbc_loadProblem(P, columns(), rows(), m.start.data(), m.index.data(), m.value.data(), col_lo_.data(), col_hi_.data(),
                  cost_.data(), row_lo_.data(), row_hi_.data());
  for (std::size_t c = 0; c < n; ++c)
    if (integer_[c]) Cbc_setInteger(P, static_cast<int>(c));
  if (dived) {
    std::vector<int> all(n);
    std::iota(all.begin(), all.end(), 0);
    Cbc_setMIPStartI(P, static_cast<int>(n), all.data(), dived->data());
  }
  Cbc_setLogLevel(P, 0);
  Cbc_setMaximumSeconds(P, seconds);
  Cbc_setAllowableGap(P, gap);
  Cbc_solve(P);
  if (Cbc_isProvenOptimal(P)) {
    const double* x = Cbc_getColSolution(P);
    return std::vector<double>(x, x + n);
  }
  if (!Cbc_isProvenInfeasible(P) && Cbc_numberSavedSolutions(P) > 0 && Cbc_bestSolution(P) != nullptr) {
    const double* x = Cbc_bestSolution(P);
    return std::vector<double>(x, x + n);
  }
  return dived;
}

// One step of a large program's dive: the fractional columns `batch`, nearest to an integer first, fixed at
// their nearest integers: all of them, else the first half, quarter, ... (each fixing that has no solution is
// released). Fixing all or one only, the step fell back to one column whenever all had no solution: on a graded
// delta_box's programs that was nearly every step, 150 re-solves for one dive (39 s). True when some were fixed
// (appended to `fixed`).
bool IntegerProgram::fix_nearest_first(const std::vector<int>& batch, std::vector<int>& fixed, int& keep) {
  ClpSimplex* const lp = lp_->model.get();
  const double* x = lp->getColSolution();
  std::vector<std::pair<double, int>> order;  // distance to the nearest integer, column
  for (int k : batch) order.push_back({std::abs(x[k] - std::round(x[k])), k});
  std::sort(order.begin(), order.end());
  std::vector<double> value;
  for (const auto& [off, k] : order) value.push_back(std::round(x[k]));
  double* lo = lp->columnLower();
  double* hi = lp->columnUpper();
  // An attempt is a guess: one that takes more dual iterations than a step mostly needs is given up as if it
  // had no solution (proving that took 31,033 iterations, 32 s, once on graded delta_box; steps take 800-3,700).
  const int iterations = lp->maximumIterations();
  lp->setMaximumIterations(std::max(1000, rows() / 5));
  std::size_t n = order.size();
  for (; n > 1; n /= 2) {
    for (std::size_t i = 0; i < n; ++i) lo[order[i].second] = hi[order[i].second] = value[i];
    lp->dual(0, keep);
    keep = 1 | 2;
    if (lp->status() == 0) break;
    for (std::size_t i = 0; i < n; ++i) release(order[i].second);
  }
  lp->setMaximumIterations(iterations);
  if (n <= 1) return false;
  for (std::size_t i = 0; i < n; ++i) fixed.push_back(order[i].second);
  return true;
}

void IntegerProgram::release(int k) {
  const auto c = static_cast<std::size_t>(k);
  lp_->model->columnLower()[c] = col_lo_[c];
  lp_->model->columnUpper()[c] = col_hi_[c];
}

// Restarts of a large program's dive after a dead end (see solve).
constexpr int kDiveRestarts = 3;

std::optional<std::vector<double>> IntegerProgram::solve(double seconds, double gap, double dive_gap, bool large) {
  const std::size_t n = cost_.size();
  dive_restarts_ = 0;
  branched_ = false;
  // The LP relaxation first: the quantization's matrices are network matrices apart from a few coupling and
  // parity rows, so its optimum is often integral already (then it is the integer optimum too), and Clp finds
  // it in a fraction of branch-and-cut's time. An infeasible relaxation means an infeasible program; a warm
  // start that does not end optimal is repeated from scratch before that is said, unless the dual simplex
  // proved the rows just added infeasible (status 1): the cold solve only agreed, at the cost of a whole solve
  // (delta_box 40 m: 105 such restarts of 28-36k-column programs).
  const bool warm = lp_ != nullptr;
  if (!solve_relaxation(large)) {
    if (!warm || lp_->model->status() == 1) return std::nullopt;
    lp_.reset();
    if (!solve_relaxation(large)) return std::nullopt;
  }
  ClpSimplex* const lp = lp_->model.get();
  auto fractional = [&](std::vector<int>* all = nullptr) { return fractional_column(all); };
  if (fractional() < 0) {
    const double* x = lp->getColSolution();
    return std::vector<double>(x, x + n);
  }
  // Fan columns first (fix_round_first), then the dive, then branch-and-cut.
  const double bound = lp->objectiveValue();
  int keep = 1;  // Clp's startFinishOptions for the next solve: 1 keep the factorization after, 2 start from it
  fix_round_first(keep);
  // A dive: the quantization's coupled programs are network programs but for a few rows, and fixing one
  // fractional column (to its nearest integer, else the other side) and re-solving by the dual simplex from the
  // last basis mostly makes the whole solution integral within a few steps, at a cost near the LP's; a fraction
  // of branch-and-cut's time on coasts' joint programs.
  // Each step changes two bounds only, so the steps keep Clp's factorization and work areas between them
  // (startFinishOptions 1: keep them at the end, 2: start from them) instead of refactorizing a matrix of tens
  // of thousands of columns each time; they are released when the dive ends (it takes at least one step: the
  // relaxation was fractional).
  // In a large program the fractional columns are mostly independent halves (a coast's parity choices, each
  // fixed alone took a re-solve of its own: 20-40 steps per dive), so a step first fixes them all, each to its
  // nearest integer, then halves of them (fix_nearest_first), and falls back to the one column.
  // A column infeasible on both sides is a dead end of the columns fixed before it: in a large program the dive
  // starts again with every column free but that one, at its nearest value (a few times; then it gives up).
  std::optional<std::vector<double>> dived;
  std::vector<int> all_fractional, fixed;
  for (int c; (c = fractional(large ? &all_fractional : nullptr)) >= 0;) {
    double* lo = lp->columnLower();
    double* hi = lp->columnUpper();
    const double v = lp->getColSolution()[c], near = std::round(v);
    if (all_fractional.size() > 1 && fix_nearest_first(all_fractional, fixed, keep)) continue;
    fixed.push_back(c);
    lo[c] = hi[c] = near;
    lp->dual(0, keep);
    keep = 1 | 2;
    if (lp->status() == 0) continue;
    lo[c] = hi[c] = v > near ? near + 1.0 : near - 1.0;
    lp->dual(0, keep);
    if (lp->status() == 0) continue;
    if (!large || dive_restarts_ >= kDiveRestarts || fixed.size() < 2) break;
    for (int k : fixed) release(k);  // the dive's own fixes (the fans fix_round_first fixed are never fractional)
    fixed.assign(1, c);
    ++dive_restarts_;
    lo[c] = hi[c] = near;
    lp->dual(0, keep);
    if (lp->status() != 0) break;
  }
  lp->finish(0);
  if (lp->status() == 0 && fractional() < 0) {
    const double* x = lp->getColSolution();
    dived = std::vector<double>(x, x + n);
    if (lp->objectiveValue() <= bound + dive_gap) return dived;
  }
  // A large program whose dive found no point is given up: branch-and-cut found none either, in every such
  // program traced (graded delta_box 50-1000, 62k columns, 44 s; the 5,000-feature region, 62k and 64k columns,
  // 42 s and 28 s; a 2M-quad delta_box), and the caller's elastic solve then names what cannot agree.
  if (large) return std::nullopt;
  branched_ = true;
  return branch_and_cut(seconds, gap, dived);
}

}  // namespace polysquare
