// The quantization's solver (map/integer_program.h): the LP relaxation when it is integral, branch-and-cut when
// it is not, and infeasibility reported rather than a wrong point.
#include <gtest/gtest.h>

#include <cmath>

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
  // A difference-constraint program (a network matrix, as the quantization's): x1 - x0 >= 3, x2 - x1 >= 2,
  // pulled towards x0 = 0 and x2 as small as possible; every vertex is integral.
  IntegerProgram p;
  const int x = p.add_columns(3, -100.0, 100.0, 0.0, true);
  p.add_row({{x + 1, 1.0}, {x, -1.0}}, 3.0, IntegerProgram::inf);
  p.add_row({{x + 2, 1.0}, {x + 1, -1.0}}, 2.0, IntegerProgram::inf);
  p.add_row({{x, 1.0}}, 0.0, 0.0);
  const int u = p.add_columns(1, -100.0, 100.0, 1.0);
  p.add_row({{u, 1.0}, {x + 2, -1.0}}, 0.0, 0.0);
  const auto s = p.solve(10.0);
  ASSERT_TRUE(s);
  EXPECT_NEAR((*s)[static_cast<std::size_t>(x + 2)], 5.0, 1e-9);
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
