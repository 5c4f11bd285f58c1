// The quantization's solver (map/integer_program.h): the LP relaxation when it is integral, branch-and-cut when
// it is not, and infeasibility reported rather than a wrong point.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "map/integer_program.h"

using namespace polysquare;

namespace {

// min -(x + y) subject to 2x + 2y <= 3, 0 <= x, y <= 10: the relaxation stops at x + y = 1.5.
IntegerProgram half_integral(bool integer) {
  IntegerProgram p;
  const int x = p.add_columns(2, 0.0, 10.0, -1.0, integer);
  p.add_row({{x, 2.0}, {x + 1, 2.0}}, -IntegerProgram::inf, 3.0);
  return p;
}

// A difference-constraint program (a network matrix, as the quantization's): x1 - x0 >= 3, x2 - x1 >= 2,
// pulled towards x0 = 0 and x2 as small as possible; every vertex is integral.
IntegerProgram difference_chain() {
  IntegerProgram p;
  const int x = p.add_columns(3, -100.0, 100.0, 0.0, true);
  p.add_row({{x + 1, 1.0}, {x, -1.0}}, 3.0, IntegerProgram::inf);
  p.add_row({{x + 2, 1.0}, {x + 1, -1.0}}, 2.0, IntegerProgram::inf);
  p.add_row({{x, 1.0}}, 0.0, 0.0);
  const int u = p.add_columns(1, -100.0, 100.0, 1.0);
  p.add_row({{u, 1.0}, {x + 2, -1.0}}, 0.0, 0.0);
  return p;
}

}  // namespace

TEST(IntegerProgram, AFractionalRelaxationIsBranchedToTheIntegerOptimum) {
  const auto relaxed = half_integral(false).solve(10.0);
  ASSERT_TRUE(relaxed);
  EXPECT_NEAR((*relaxed)[0] + (*relaxed)[1], 1.5, 1e-9);  // the relaxation really is fractional
  const auto integral = half_integral(true).solve(10.0);
  ASSERT_TRUE(integral);
  for (double v : *integral) EXPECT_NEAR(v, std::round(v), 1e-9);
  EXPECT_NEAR((*integral)[0] + (*integral)[1], 1.0, 1e-9);
}

TEST(IntegerProgram, AnIntegralRelaxationIsTheAnswer) {
  const auto s = difference_chain().solve(10.0);
  ASSERT_TRUE(s);
  EXPECT_NEAR((*s)[2], 5.0, 1e-9);
}

TEST(IntegerProgram, ColumnsNamedTwiceInARowAreSummed) {
  IntegerProgram p;
  const int x = p.add_columns(1, 0.0, 10.0, -1.0);
  p.add_row({{x, 1.0}, {x, 1.0}}, -IntegerProgram::inf, 4.0);  // 2x <= 4
  const auto s = p.solve(10.0);
  ASSERT_TRUE(s);
  EXPECT_NEAR((*s)[0], 2.0, 1e-9);
}

TEST(IntegerProgram, InfeasibilityIsReportedForTheRelaxationAndForTheIntegers) {
  IntegerProgram lp;
  const int x = lp.add_columns(1, 0.0, 10.0);
  lp.add_row({{x, 1.0}}, 2.0, 1.0);  // 2 <= x <= 1
  EXPECT_FALSE(lp.solve(10.0));
  // 2x = 1 has the relaxed solution 0.5 and no integer one.
  IntegerProgram ip;
  const int y = ip.add_columns(1, -10.0, 10.0, 0.0, true);
  ip.add_row({{y, 2.0}}, 1.0, 1.0);
  EXPECT_FALSE(ip.solve(10.0));
}

TEST(IntegerProgram, ADiveIsKeptOnlyWithinItsGapOfTheRelaxation) {
  // Small random packing programs (max sum c x, A x <= b, x integer in [0, 5]): the dive's point, taken whatever
  // its cost (dive_gap huge), is integral, feasible and never better than branch-and-cut's optimum (dive_gap 0);
  // some dives end above the optimum, so the gap decides.
  std::uint64_t state = 12345;
  auto next = [&](int n) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<int>((state >> 33) % static_cast<std::uint64_t>(n));
  };
  int worse = 0;
  for (int trial = 0; trial < 200; ++trial) {
    IntegerProgram p;
    std::vector<double> cost(4), rhs(3);
    std::vector<std::vector<double>> a(3, std::vector<double>(4));
    for (double& c : cost) c = -(1 + next(9));
    for (int r = 0; r < 3; ++r) {
      for (double& v : a[r]) v = 1 + next(7);
      rhs[r] = 4 + next(15) + 0.5;
    }
    for (int c = 0; c < 4; ++c) p.add_columns(1, 0.0, 5.0, cost[c], true);
    for (int r = 0; r < 3; ++r)
      p.add_row({{0, a[r][0]}, {1, a[r][1]}, {2, a[r][2]}, {3, a[r][3]}}, -IntegerProgram::inf, rhs[r]);
    auto value = [&](const std::vector<double>& x) {
      double v = 0.0;
      for (int c = 0; c < 4; ++c) v += cost[c] * x[c];
      return v;
    };
    const auto dive = p.solve(10.0, 0.0, 1e9), best = p.solve(10.0, 0.0, 0.0);
    ASSERT_TRUE(dive && best);
    for (int c = 0; c < 4; ++c) EXPECT_NEAR((*dive)[c], std::round((*dive)[c]), 1e-9);
    for (int r = 0; r < 3; ++r) {
      double lhs = 0.0;
      for (int c = 0; c < 4; ++c) lhs += a[r][c] * (*dive)[c];
      EXPECT_LE(lhs, rhs[r] + 1e-9);
    }
    EXPECT_GE(value(*dive), value(*best) - 1e-9);
    worse += value(*dive) > value(*best) + 1e-9;
  }
  EXPECT_GT(worse, 0);
  EXPECT_LT(worse, 200);
}

TEST(IntegerProgram, RowsAddedAfterASolveAreSolvedFromItsBasis) {
  // The quantization adds separation rows between rounds: the re-solve must answer the program with them, as a
  // fresh solve does, and say so when they make it infeasible.
  IntegerProgram p = difference_chain();
  ASSERT_TRUE(p.solve(10.0));
  p.add_row({{2, 1.0}, {1, -1.0}}, 4.0, IntegerProgram::inf);  // x2 - x1 >= 4 cuts the last optimum off
  p.add_row({{1, 1.0}, {1, 1.0}, {0, -1.0}}, 8.0, IntegerProgram::inf);  // 2 x1 - x0 >= 8: x1 >= 4
  const auto again = p.solve(10.0);
  IntegerProgram fresh = difference_chain();
  fresh.add_row({{2, 1.0}, {1, -1.0}}, 4.0, IntegerProgram::inf);
  fresh.add_row({{1, 2.0}, {0, -1.0}}, 8.0, IntegerProgram::inf);
  const auto expected = fresh.solve(10.0);
  ASSERT_TRUE(again && expected);
  EXPECT_NEAR((*again)[2], 8.0, 1e-9);
  for (std::size_t c = 0; c < 4; ++c) EXPECT_NEAR((*again)[c], (*expected)[c], 1e-9);
  p.add_row({{2, 1.0}}, -IntegerProgram::inf, 5.0);  // x2 <= 5 contradicts x2 >= 8
  EXPECT_FALSE(p.solve(10.0));
}

TEST(IntegerProgram, ALargeProgramDivesFromItsDualSolutionToTheOptimum) {
  // Eight independent copies of half_integral's program: the relaxation is fractional in each (x + y = 1.5), and
  // a large program's dive fixes the fractional columns of all copies in one step. Its point must be integral,
  // feasible and optimal (x + y = 1 in each copy), as the one-column-at-a-time dive's is; an infeasible step of
  // all at once (2x + 2y <= 3 with x = y = 1 after rounding halves up) must fall back to single fixes.
  constexpr int copies = 8;
  auto program = [] {
    IntegerProgram p;
    for (int k = 0; k < copies; ++k) {
      const int x = p.add_columns(2, 0.0, 10.0, -1.0, true);
      p.add_row({{x, 2.0}, {x + 1, 2.0}}, -IntegerProgram::inf, 3.0);
    }
    return p;
  };
  const auto large = program().solve(10.0, 0.0, 1e9, true), one_by_one = program().solve(10.0, 0.0, 1e9, false);
  ASSERT_TRUE(large && one_by_one);
  double sum_large = 0.0, sum_one = 0.0;
  for (int k = 0; k < copies; ++k) {
    const double x = (*large)[2 * k], y = (*large)[2 * k + 1];
    EXPECT_NEAR(x, std::round(x), 1e-9);
    EXPECT_NEAR(y, std::round(y), 1e-9);
    EXPECT_LE(2 * x + 2 * y, 3.0 + 1e-9);
    sum_large += x + y;
    sum_one += (*one_by_one)[2 * k] + (*one_by_one)[2 * k + 1];
  }
  EXPECT_NEAR(sum_large, copies, 1e-9);
  EXPECT_NEAR(sum_one, copies, 1e-9);
}

namespace {

// Two counts pulled towards 7 and 4 whose difference is twice an integer column f (a transition coupling's
// fans), f marked round_first with fallback `fallback`; `row_lo` <= na - nb <= `row_hi`. Columns: na, nb, f.
IntegerProgram fan_program(double fallback, double row_lo, double row_hi) {
  IntegerProgram p;
  const int n = p.add_columns(2, 1.0, 100.0, 0.0, true);
  const int f = p.add_columns(1, 0.0, IntegerProgram::inf, 0.1, true);
  p.round_first(f, fallback);
  const int u = p.add_columns(2, 0.0, IntegerProgram::inf, 1.0);
  const double target[2] = {7.0, 4.0};
  for (int k = 0; k < 2; ++k) {  // u_k >= |n_k - target_k|
    p.add_row({{u + k, 1.0}, {n + k, -1.0}}, -target[k], IntegerProgram::inf);
    p.add_row({{u + k, 1.0}, {n + k, 1.0}}, target[k], IntegerProgram::inf);
  }
  p.add_row({{n, 1.0}, {n + 1, -1.0}, {f, -2.0}}, 0.0, 0.0);
  p.add_row({{n, 1.0}, {n + 1, -1.0}}, row_lo, row_hi);
  return p;
}

}  // namespace

TEST(IntegerProgram, RoundFirstColumnsAreRoundedHalvesDownThenTheRestSolved) {
  // The relaxation keeps both targets with f = 1.5; rounded down, the counts differ by 2, one of them a step off.
  const auto s = fan_program(0.0, -100.0, 100.0).solve(10.0);
  ASSERT_TRUE(s);
  for (double v : *s) EXPECT_NEAR(v, std::round(v), 1e-9);
  EXPECT_NEAR((*s)[2], 1.0, 1e-9);
  EXPECT_NEAR((*s)[0] - (*s)[1], 2.0, 1e-9);
  EXPECT_NEAR(std::abs((*s)[0] - 7.0) + std::abs((*s)[1] - 4.0), 1.0, 1e-9);
}

TEST(IntegerProgram, RoundFirstColumnsTakeTheirFallbackWhenTheRoundedValuesHaveNoSolution) {
  // na - nb in [3, 4]: f = 1 (difference 2) has no solution, the fallback f = 2 (difference 4) has.
  const auto s = fan_program(2.0, 3.0, 4.0).solve(10.0);
  ASSERT_TRUE(s);
  EXPECT_NEAR((*s)[2], 2.0, 1e-9);
  EXPECT_NEAR((*s)[0] - (*s)[1], 4.0, 1e-9);
}

TEST(IntegerProgram, ALargeProgramsDiveStartsAgainAfterADeadEnd) {
  // min -x0 - 3 x1 + x2 subject to 2 x0 + 2 x1 + x2 = 3, x0 + 2 x3 = 5, integers in [0, 3]: the one integer point
  // is (1, 0, 1, 2). The relaxation's fractional columns, rounded all at once, leave a column that neither of its
  // sides can take (found among random programs of this form). The dive starts again with that column alone
  // fixed and reaches the point without branch-and-cut (where a dead end went before).
  IntegerProgram p;
  const double costs[4] = {-1.0, -3.0, 1.0, 0.0};
  for (double c : costs) p.add_columns(1, 0.0, 3.0, c, true);
  p.add_row({{0, 2.0}, {1, 2.0}, {2, 1.0}}, 3.0, 3.0);
  p.add_row({{0, 1.0}, {3, 2.0}}, 5.0, 5.0);
  const auto s = p.solve(10.0, 0.0, IntegerProgram::inf, true);
  ASSERT_TRUE(s);
  const double want[4] = {1.0, 0.0, 1.0, 2.0};
  for (int c = 0; c < 4; ++c) EXPECT_NEAR((*s)[static_cast<std::size_t>(c)], want[c], 1e-9) << c;
  EXPECT_GE(p.dive_restarts(), 1);
  EXPECT_FALSE(p.branched());
}

TEST(IntegerProgram, LpSolvesHaveNoTimeLimit) {
  // 500 copies of half_integral's program with a time limit far below any solve's: the relaxation and the dive
  // still run to their end (the limit is branch-and-cut's alone). Clp's own limit was a deadline in the
  // process's CPU time, set once per solve: the dive's steps stopped at once past it, read as dead ends.
  constexpr int copies = 500;
  IntegerProgram p;
  for (int k = 0; k < copies; ++k) {
    const int x = p.add_columns(2, 0.0, 10.0, -1.0, true);
    p.add_row({{x, 2.0}, {x + 1, 2.0}}, -IntegerProgram::inf, 3.0);
  }
  const auto s = p.solve(1e-9, 0.0, IntegerProgram::inf, true);
  ASSERT_TRUE(s);
  double sum = 0.0;
  for (double v : *s) {
    EXPECT_NEAR(v, std::round(v), 1e-9);
    sum += v;
  }
  EXPECT_NEAR(sum, copies, 1e-9);
  EXPECT_FALSE(p.branched());
}

TEST(IntegerProgram, ALargeProgramsFailedDiveIsNotBranched) {
  // 2 x = 1 with x integer: the relaxation is feasible (x = 1/2), no integer is. A large program's dive gives up
  // and the answer is nullopt at once (branch-and-cut found no point in any large program traced, at 20-40 s
  // each); a small program still goes to branch-and-cut, which proves it.
  for (const bool large : {true, false}) {
    IntegerProgram p;
    const int x = p.add_columns(1, 0.0, 10.0, 1.0, true);
    p.add_row({{x, 2.0}}, 1.0, 1.0);
    EXPECT_FALSE(p.solve(10.0, 0.0, IntegerProgram::inf, large)) << large;
    EXPECT_EQ(p.branched(), !large);
  }
}
