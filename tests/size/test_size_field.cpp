// The size field of graded meshes: its gradient limit, its terms (distance to the shores and curves, passages
// crossed by N quads) and its refusals, on the bundled coasts and on shapes whose field is known.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "polysquare/core/error.h"
#include "polysquare/input/read_region.h"
#include "polysquare/size/size_field.h"

using namespace polysquare;

namespace {

Region rectangle_ring(std::vector<Vec2> pts) {
  Region r;
  r.rings.push_back({std::move(pts), 0, false, -1, {}});
  r.num_parts = 1;
  return r;
}

// The largest violation of |h(a) - h(b)| <= grade |a - b| over the grid's 8-neighbour pairs (0 when it holds).
double gradient_excess(const SizeField& f, double grade) {
  double worst = 0.0;
  const std::vector<double>& h = f.values();
  for (int j = 0; j < f.ny(); ++j)
    for (int i = 0; i < f.nx(); ++i)
      for (const auto [di, dj] : {std::pair{1, 0}, std::pair{0, 1}, std::pair{1, 1}, std::pair{-1, 1}}) {
        const int a = i + di, b = j + dj;
        if (a < 0 || a >= f.nx() || b >= f.ny()) continue;
        const double step = f.cell() * std::hypot(di, dj);
        const double d = std::fabs(h[static_cast<std::size_t>(j) * f.nx() + i] - h[static_cast<std::size_t>(b) * f.nx() + a]);
        worst = std::max(worst, d - grade * step * (1.0 + 1e-12));
      }
  return worst;
}

}  // namespace

TEST(SizeField, GradientLimitHoldsOnACoastAndTheShoreIsAtTheLeastSize) {
  const Region region = read_region(std::string(POLYSQUARE_DATA_DIR) + "/cases/delta_water.geojson");
  SizeFieldOptions o;
  o.size_min = 50.0;
  o.size_max = 1000.0;
  o.grade = 0.15;
  const SizeFieldResult r = make_size_field(region, o);
  EXPECT_LE(gradient_excess(r.field, o.grade), 0.0);
  EXPECT_GE(r.stats.min, o.size_min);
  EXPECT_LE(r.stats.max, o.size_max);
  EXPECT_GT(r.stats.max, 0.9 * o.size_max);  // open water far from any shore reaches HMAX
  // At every ring vertex the field is within one cell's growth of HMIN.
  for (const Ring& ring : region.rings)
    for (const Vec2 p : ring.points) ASSERT_LE(r.field.at(p), o.size_min + 2.0 * o.grade * r.stats.cell) << point_text(p);
  // The graded mesh needs far fewer quads than the uniform one at HMIN (area / HMIN^2), and about what a band of
  // sizes HMIN + G d along the shores holds: integral over d of L / (HMIN + G d)^2 = L / (G HMIN) for shores of
  // length L, plus the open water at HMAX (islands fan their bands out, so up to about twice that).
  const double area = static_cast<double>(r.stats.inside_cells) * r.stats.cell * r.stats.cell;
  const double uniform = area / (o.size_min * o.size_min);
  double shore = 0.0;
  for (const Ring& ring : region.rings)
    for (std::size_t k = 0; k < ring.points.size(); ++k)
      shore += distance(ring.points[k], ring.points[(k + 1) % ring.points.size()]);
  const double band = shore / (o.grade * o.size_min) + area / (o.size_max * o.size_max);
  EXPECT_LT(r.stats.estimated_quads, uniform / 5.0);
  EXPECT_LT(r.stats.estimated_quads, 2.0 * band);
  EXPECT_GT(r.stats.estimated_quads, 0.25 * band);
}

TEST(SizeField, GradientLimitOfOneSmallValueIsACone) {
  const int n = 101;
  std::vector<double> h(static_cast<std::size_t>(n) * n, 100.0);
  h[50 * n + 50] = 1.0;
  const std::size_t lowered = limit_gradient(h, n, n, 1.0, 0.2);
  EXPECT_GT(lowered, 1000u);
  for (int j = 0; j < n; j += 7)
    for (int i = 0; i < n; i += 5) {
      const double expect = std::min(100.0, 1.0 + 0.2 * std::hypot(i - 50, j - 50));
      ASSERT_NEAR(h[static_cast<std::size_t>(j) * n + i], expect, 1e-9) << i << " " << j;
    }
}

TEST(SizeField, AcrossPutsNQuadsAcrossANarrowChannelBetweenTwoBasins) {
  // Two 1000 x 1000 basins joined by a channel 40 wide and 600 long.
  const Region region = rectangle_ring({{0, 0}, {1000, 0}, {1000, 480}, {1600, 480}, {1600, 0}, {2600, 0},
                                        {2600, 1000}, {1600, 1000}, {1600, 520}, {1000, 520}, {1000, 1000}, {0, 1000}});
  SizeFieldOptions o;
  o.size_min = 2.0;
  o.size_max = 200.0;
  o.grade = 0.25;
  o.distance_term = false;
  o.across = 3.0;
  o.cell = 2.0;
  const SizeFieldResult r = make_size_field(region, o);
  EXPECT_NEAR(r.stats.narrowest_passage, 40.0, 2.0 * o.cell);
  // Across the channel's middle: about 40 / 3, never more, so at least three quads cross it.
  for (const double y : {482.0, 490.0, 500.0, 510.0, 518.0}) {
    const double h = r.field.at({1300.0, y});
    EXPECT_LE(h, 40.0 / 3.0 * 1.02) << y;
    EXPECT_GE(h, 40.0 / 3.0 * 0.8) << y;
  }
  // The basins' middles are far from any passage: large, limited by the gradient from the channel mouth only.
  EXPECT_GT(r.field.at({400.0, 500.0}), 100.0);
  EXPECT_GT(r.field.at({2200.0, 500.0}), 100.0);
  EXPECT_LE(gradient_excess(r.field, o.grade), 0.0);
}

TEST(SizeField, DistanceTermGrowsFromFeatureCurvesToo) {
  Region region = rectangle_ring({{0, 0}, {1000, 0}, {1000, 1000}, {0, 1000}});
  region.features.push_back({{{500, 200}, {500, 800}}, false, -1, {}, {}});
  SizeFieldOptions o;
  o.size_min = 5.0;
  o.size_max = 100.0;
  o.grade = 0.2;
  const SizeFieldResult r = make_size_field(region, o);
  EXPECT_NEAR(r.field.at({500, 500}), 5.0, 0.2 * r.stats.cell + 1e-9);
  EXPECT_NEAR(r.field.at({400, 500}), 5.0 + 0.2 * 100.0, 0.2 * r.stats.cell * 1.5);
  EXPECT_NEAR(r.field.at({250, 500}), 5.0 + 0.2 * 250.0, 0.2 * r.stats.cell * 1.5);  // the nearest curve: the ring
}

TEST(SizeField, BadOptionsAreRefusedNamingTheFlag) {
  auto refused = [](SizeFieldOptions o, const std::string& flag) {
    try {
      check_size_field_options(o);
    } catch (const InputError& e) {
      return std::string(e.what()).rfind(flag, 0) == 0;
    }
    return false;
  };
  SizeFieldOptions good;
  good.size_min = 10;
  good.size_max = 100;
  EXPECT_NO_THROW(check_size_field_options(good));
  SizeFieldOptions o = good;
  o.size_min = 0;
  EXPECT_TRUE(refused(o, "--size-min"));
  o.size_min = -5;
  EXPECT_TRUE(refused(o, "--size-min"));
  o.size_min = NAN;
  EXPECT_TRUE(refused(o, "--size-min"));
  o = good;
  o.size_max = 5;  // below size_min
  EXPECT_TRUE(refused(o, "--size-max"));
  o.size_max = INFINITY;
  EXPECT_TRUE(refused(o, "--size-max"));
  o = good;
  o.grade = 0;
  EXPECT_TRUE(refused(o, "--grade"));
  o.grade = NAN;
  EXPECT_TRUE(refused(o, "--grade"));
  o = good;
  o.across = -1;
  EXPECT_TRUE(refused(o, "--across"));
}

TEST(SizeField, BilinearBetweenCellCentres) {
  // A linear field is reproduced exactly between the centres and held at the edge value beyond the grid.
  std::vector<double> h;
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 5; ++i) h.push_back(1.0 + 2.0 * i + 3.0 * j);
  const SizeField f({10.0, 20.0}, 0.5, 5, 4, h);
  EXPECT_NEAR(f.at({10.0 + 0.5 * 1.3, 20.0 + 0.5 * 2.6}), 1.0 + 2.0 * 1.3 + 3.0 * 2.6, 1e-12);
  EXPECT_NEAR(f.at({0.0, 0.0}), 1.0, 1e-12);
  EXPECT_NEAR(f.at({100.0, 100.0}), 1.0 + 2.0 * 4 + 3.0 * 3, 1e-12);
}
