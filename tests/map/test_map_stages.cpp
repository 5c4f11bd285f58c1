// Stage-level tests of the poly-square map on hand-made inputs with known answers.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>

#include "map/loop_path.h"
#include "polysquare/core/error.h"
#include "polysquare/map/deform.h"
#include "polysquare/map/polysquare_map.h"
#include "polysquare/map/quantize.h"

using namespace polysquare;

TEST(Preorientation, RotatesARotatedSquareBackToTheAxes) {
  for (double deg : {0.0, 10.0, 30.0, -22.0}) {
    const double a = deg * std::numbers::pi / 180.0;
    std::vector<Vec2> pts;
    for (Vec2 p : {Vec2{0, 0}, Vec2{2, 0}, Vec2{2, 1}, Vec2{0, 1}})
      pts.push_back({std::cos(a) * p.x - std::sin(a) * p.y, std::sin(a) * p.x + std::cos(a) * p.y});
    const double theta = preorientation_angle(pts, {{0, 1}, {1, 2}, {2, 3}, {3, 0}});
    // The rotated edges must be axis-aligned again: theta = -a modulo quarter turns.
    const double r = std::remainder(theta + a, std::numbers::pi / 2);
    EXPECT_NEAR(r, 0.0, 1e-12) << deg;
  }
}

TEST(Deformation, AlignsAQuadrilateralWithoutInverting) {
  DeformProblem p;
  p.rest = {{0, 0}, {1, 0.3}, {0.2, 1}, {1.3, 1.2}};
  p.triangles = {{0, 1, 2}, {1, 3, 2}};
  p.aligned = {{0, 1, 5.0}, {1, 3, 5.0}, {3, 2, 5.0}, {2, 0, 5.0}};
  std::vector<Vec2> x = p.rest;
  const DeformStats st = deform_to_polysquare(p, DeformOptions{}, x);
  EXPECT_LT(st.alignment_after, 0.1 * st.alignment_before);
  EXPECT_GT(min_signed_area(p.triangles, x), 0.0);
  for (const auto& e : p.aligned) {  // every boundary edge within 5 degrees of an axis
    const Vec2 d = x[e.b] - x[e.a];
    const double off = std::min(std::abs(d.x), std::abs(d.y)) / norm(d);
    EXPECT_LT(off, std::sin(5.0 * std::numbers::pi / 180.0));
  }
}

TEST(Deformation, ConstrainedMoveReachesTargetsAndStaysValid) {
  // A fan around one free centre vertex; the ring is moved onto a square.
  DeformProblem p;
  const int n = 12;
  p.rest.push_back({0, 0});
  for (int i = 0; i < n; ++i) {
    const double a = 2 * std::numbers::pi * i / n;
    p.rest.push_back({std::cos(a), std::sin(a)});
  }
  for (int i = 0; i < n; ++i) p.triangles.push_back({0, 1 + i, 1 + (i + 1) % n});
  std::vector<Vec2> x = p.rest, targets = p.rest;
  std::vector<std::uint8_t> mask(p.rest.size(), 1);
  mask[0] = 0;
  for (int i = 1; i <= n; ++i) {
    const Vec2 q = p.rest[i];
    const double s = std::max(std::abs(q.x), std::abs(q.y));
    targets[i] = {q.x / s + 3.0, q.y / s - 1.0};  // project to the square and translate
  }
  ASSERT_TRUE(move_constrained_vertices(p, DeformOptions{}, mask, targets, x));
  for (int i = 1; i <= n; ++i) EXPECT_EQ(x[i], targets[i]);
  EXPECT_GT(min_signed_area(p.triangles, x), 0.0);
  EXPECT_NEAR(x[0].x, 3.0, 0.2);
  EXPECT_NEAR(x[0].y, -1.0, 0.2);
}

TEST(Deformation, ConstrainedMoveAroundAReflexCornerIsPulledOrUntangledWhereTheStraightPathFolds) {
  // An L-shaped grid (reflex corner at (1, 1)) whose boundary nodes slide 1.2 along the boundary: the straight
  // path takes the nodes near the reflex corner across the notch and folds triangles; pulled by springs, each
  // node goes its own way round and the move succeeds.
  const int n = 8;  // cells per unit
  DeformProblem p;
  std::map<std::pair<int, int>, std::int32_t> id;
  for (int j = 0; j <= 2 * n; ++j)
    for (int i = 0; i <= 2 * n; ++i)
      if (!(i > n && j > n)) {
        id[{i, j}] = static_cast<std::int32_t>(p.rest.size());
        p.rest.push_back({static_cast<double>(i) / n, static_cast<double>(j) / n});
      }
  for (int j = 0; j < 2 * n; ++j)
    for (int i = 0; i < 2 * n; ++i) {
      if (i >= n && j >= n) continue;
      const std::int32_t a = id[{i, j}], b = id[{i + 1, j}], c = id[{i + 1, j + 1}], d = id[{i, j + 1}];
      // The two convex corners whose cell would otherwise hold a triangle of three boundary nodes.
      if ((i == 2 * n - 1 && j == 0) || (i == 0 && j == 2 * n - 1)) {
        p.triangles.push_back({a, b, d});
        p.triangles.push_back({b, c, d});
      } else {
        p.triangles.push_back({a, b, c});
        p.triangles.push_back({a, c, d});
      }
    }
  const std::vector<Vec2> loop = {{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
  auto arc_of = [&](Vec2 q) {  // arc length of a boundary point, -1 inside
    double s = 0.0;
    for (std::size_t k = 0; k < loop.size(); ++k) {
      const Vec2 a = loop[k], b = loop[(k + 1) % loop.size()];
      const double len = distance(a, b), t = dot(q - a, b - a) / (len * len);
      if (t >= -1e-12 && t <= 1 + 1e-12 && distance(q, a + t * (b - a)) < 1e-12) return s + t * len;
      s += len;
    }
    return -1.0;
  };
  std::vector<std::uint8_t> mask(p.rest.size(), 0);
  std::vector<Vec2> targets = p.rest;
  for (std::size_t v = 0; v < p.rest.size(); ++v)
    if (const double s = arc_of(p.rest[v]); s >= 0.0) {
      mask[v] = 1;
      targets[v] = point_on_loop(loop, s + 1.2);
    }
  const DeformOptions straight_only;
  std::vector<Vec2> straight = p.rest;
  EXPECT_FALSE(move_constrained_vertices(p, straight_only, mask, targets, straight));
  DeformOptions pull = straight_only;
  pull.pull_when_path_fails = true;
  std::vector<Vec2> x = p.rest;
  bool untangled = true;
  ASSERT_TRUE(move_constrained_vertices(p, pull, mask, targets, x, &untangled));
  EXPECT_FALSE(untangled);
  for (std::size_t v = 0; v < x.size(); ++v)
    if (mask[v]) EXPECT_EQ(x[v], targets[v]);
  EXPECT_GT(min_signed_area(p.triangles, x), 0.0);
  // Without the springs, the folds of the harmonic embedding on the targets can be untangled instead.
  DeformOptions untangle = straight_only;
  untangle.untangle_when_path_fails = true;
  std::vector<Vec2> y = p.rest;
  ASSERT_TRUE(move_constrained_vertices(p, untangle, mask, targets, y, &untangled));
  EXPECT_TRUE(untangled);
  for (std::size_t v = 0; v < y.size(); ++v)
    if (mask[v]) EXPECT_EQ(y[v], targets[v]);
  EXPECT_GT(min_signed_area(p.triangles, y), 0.0);
}

TEST(Deformation, PreconditionedSolveNeedsFewerIterationsForTheSameResult) {
  // A wavy strip 48 x 12 triangles wide whose boundary edges are pulled to the axes: the plain L-BFGS needs many
  // iterations to carry the boundary's pull across the width; started from the rest stiffness it needs far
  // fewer and ends as aligned, with no inverted triangle.
  DeformProblem p;
  const int nx = 48, ny = 12;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i)
      p.rest.push_back({i + 0.3 * std::sin(0.4 * j), j + 1.5 * std::sin(0.15 * i)});
  auto id = [&](int i, int j) { return static_cast<std::int32_t>(j * (nx + 1) + i); };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      p.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      p.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  for (int i = 0; i < nx; ++i) {
    p.aligned.push_back({id(i, 0), id(i + 1, 0), 5.0});
    p.aligned.push_back({id(i + 1, ny), id(i, ny), 5.0});
  }
  for (int j = 0; j < ny; ++j) {
    p.aligned.push_back({id(nx, j), id(nx, j + 1), 5.0});
    p.aligned.push_back({id(0, j + 1), id(0, j), 5.0});
  }
  DeformOptions plain, pre;
  plain.precondition = false;
  pre.precondition = true;
  std::vector<Vec2> xp = p.rest, xq = p.rest;
  const DeformStats a = deform_to_polysquare(p, plain, xp), b = deform_to_polysquare(p, pre, xq);
  EXPECT_GT(min_signed_area(p.triangles, xq), 0.0);
  EXPECT_LT(b.iterations, a.iterations / 2) << "plain " << a.iterations << ", preconditioned " << b.iterations;
  EXPECT_LE(b.energy_after, a.energy_after * 1.01);
  EXPECT_LT(b.alignment_after, 0.1 * b.alignment_before);
}

TEST(Deformation, MemoAnswersOnlyTheSameProblem) {
  // A memo returns a stored solve only for exactly the same problem, options and start; anything else solves.
  DeformProblem p;
  p.rest = {{0, 0}, {1, 0.3}, {0.2, 1}, {1.3, 1.2}};
  p.triangles = {{0, 1, 2}, {1, 3, 2}};
  p.aligned = {{0, 1, 5.0}, {1, 3, 5.0}, {3, 2, 5.0}, {2, 0, 5.0}};
  std::vector<Vec2> plain = p.rest;
  const DeformStats solved = deform_to_polysquare(p, DeformOptions{}, plain);
  DeformOptions o;
  o.memo = std::make_shared<DeformMemo>();
  std::vector<Vec2> first = p.rest, again = p.rest;
  deform_to_polysquare(p, o, first);
  EXPECT_EQ(o.memo->hits(), 0u);
  const DeformStats reused = deform_to_polysquare(p, o, again);
  EXPECT_EQ(o.memo->hits(), 1u);
  EXPECT_EQ(again, plain);  // bit for bit what a solve without the memo gives
  EXPECT_EQ(reused.iterations, solved.iterations);
  // One weight, one option, one start coordinate changed: three new solves.
  DeformProblem q = p;
  q.aligned[2].weight = 4.0;
  std::vector<Vec2> x = p.rest;
  deform_to_polysquare(q, o, x);
  DeformOptions o2 = o;
  o2.eps_schedule = {0.1, 0.01};
  x = p.rest;
  deform_to_polysquare(p, o2, x);
  x = p.rest;
  x[3].x += 1e-9;
  deform_to_polysquare(p, o, x);
  EXPECT_EQ(o.memo->hits(), 1u);
  // The constrained move is remembered apart from the free solve, with its outcome.
  std::vector<std::uint8_t> mask(4, 1);
  const std::vector<Vec2> targets = {{0, 0}, {1, 0}, {0, 1}, {1, 1}};
  std::vector<Vec2> m1 = p.rest, m2 = p.rest;
  ASSERT_TRUE(move_constrained_vertices(p, o, mask, targets, m1));
  ASSERT_TRUE(move_constrained_vertices(p, o, mask, targets, m2));
  EXPECT_EQ(o.memo->hits(), 2u);
  EXPECT_EQ(m1, m2);
}

namespace {
// A layout of an L-shaped poly-square: 6 break points, sides labelled CCW, targets slightly off integers.
Layout l_shape(std::vector<Vec2>& deformed) {
  Layout L;
  deformed = {{0, 0}, {4.2, 0}, {4.2, 2.1}, {2.1, 2.1}, {2.1, 5.9}, {0, 5.9}};
  for (int i = 0; i < 6; ++i) { L.break_vertex.push_back(i); L.break_is_corner.push_back(1); }
  L.vertex_break = {0, 1, 2, 3, 4, 5};
  const int labels[6] = {0, 1, 2, 1, 2, 3};
  for (int i = 0; i < 6; ++i) {
    LayoutSegment s;
    s.chain = 0; s.first = i; s.count = 1; s.label = labels[i];
    s.break_a = i; s.break_b = (i + 1) % 6;
    s.target = distance(deformed[i], deformed[(i + 1) % 6]);
    L.segments.push_back(s);
  }
  return L;
}
}  // namespace

TEST(Quantization, LShapeClosesWithCountsNearTargets) {
  std::vector<Vec2> deformed;
  Layout L = l_shape(deformed);
  const QuantizeStats st = quantize_layout(L, deformed, QuantizeOptions{}, "test");
  EXPECT_EQ(check_layout(L), "");
  // Closure: every segment keeps its perpendicular coordinate and has length >= 1.
  for (const auto& s : L.segments) {
    const auto a = L.lattice[s.break_a], b = L.lattice[s.break_b];
    const int ax = label_axis(s.label);
    EXPECT_EQ(a[1 - ax], b[1 - ax]);
    EXPECT_GE(label_sign(s.label) * (b[ax] - a[ax]), 1);
    EXPECT_LE(std::abs(std::abs(b[ax] - a[ax]) - s.target), 1.0);
  }
  EXPECT_LT(st.max_relative_deviation, 0.5);
  // The two +Y sides must sum to the -Y side: 2 + 4 = 6.
  EXPECT_EQ(L.lattice[5][1] - L.lattice[0][1], 6);
}

TEST(Quantization, ContradictoryLabelsAreInfeasible) {
  std::vector<Vec2> deformed;
  Layout L = l_shape(deformed);
  // Relabel the closing -Y side as -X: the two +Y sides then require y(2,3) > y(0,1,4,5) > y(2,3).
  L.segments[5].label = 2;
  EXPECT_THROW(quantize_layout(L, deformed, QuantizeOptions{}, "test"), MeshingError);
}

TEST(Quantization, SeparationRoundsRefuseAnUnavoidableOverlap) {
  std::vector<Vec2> deformed;
  Layout L = l_shape(deformed);
  // +Y notch side relabelled +X: sides 2, 3, 4 read -X, +X, -X, all on one horizontal line (an X side keeps its
  // y), so sides 2 and 3 share at least one unit of that line whatever the counts. The plain integer program
  // returns such a folded polygon ...
  L.segments[3].label = 0;
  QuantizeOptions plain;
  plain.max_separation_rounds = 0;
  quantize_layout(L, deformed, plain, "test");
  EXPECT_NE(check_layout(L), "");
  // ... and the separation rounds must refuse it as overlapping (they can never make it simple).
  try {
    quantize_layout(L, deformed, QuantizeOptions{}, "test");
    ADD_FAILURE() << "an L-shape with a -X, +X, -X run was quantized: " << check_layout(L);
  } catch (const MeshingError& e) {
    EXPECT_NE(std::string(e.what()).find("overlapping"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("test"), std::string::npos) << e.what();
  }
}

TEST(Quantization, OverlappingSidesAreReported) {
  std::vector<Vec2> deformed;
  Layout L = l_shape(deformed);
  quantize_layout(L, deformed, QuantizeOptions{}, "test");
  L.lattice[3] = L.lattice[1];  // fold the notch onto another corner
  EXPECT_NE(check_layout(L), "");
}

TEST(Quantization, TheCompactFormOfALargeProgramHasTheSameOptimum) {
  // Above QuantizeOptions::large_program_columns the program is built with one equality row per side (bounded
  // deviation columns) and solved by the dual simplex; the L-shape's optimum (the counts nearest its targets)
  // must not depend on the form.
  std::vector<Vec2> deformed;
  Layout inequality = l_shape(deformed), compact = inequality;
  quantize_layout(inequality, deformed, QuantizeOptions{}, "test");
  QuantizeOptions all_large;
  all_large.large_program_columns = 0;
  quantize_layout(compact, deformed, all_large, "test");
  EXPECT_EQ(check_layout(compact), "");
  for (const auto& s : compact.segments) {
    auto count = [&](const Layout& L) {
      const auto a = L.lattice[s.break_a], b = L.lattice[s.break_b];
      return std::abs(b[0] - a[0]) + std::abs(b[1] - a[1]);
    };
    EXPECT_EQ(count(compact), count(inequality));
  }
}

TEST(Quantization, GradedSidesRatherTakeAnElementMoreThanOneFewer) {
  // A rectangle whose -X side wants 5 elements and +X side 3 (a subregion widening towards coarser quads): one
  // count serves both. Uniform: 3 (costs 2/5, against 2/3 for 5). Graded, an element fewer costs
  // graded_fewer_weight = 2 times one more: 5 (2/3, against 4/5 for 3 and 1/3 + 2/5 for 4), in both forms.
  for (const bool large : {false, true}) {
    for (const bool graded : {false, true}) {
      Layout L;
      const std::vector<Vec2> deformed = {{0, 0}, {3, 0}, {4, 2}, {-1, 2}};
      const int labels[4] = {0, 1, 2, 3};
      const double targets[4] = {3.0, 2.0, 5.0, 2.0};
      for (int i = 0; i < 4; ++i) {
        L.break_vertex.push_back(i);
        L.break_is_corner.push_back(1);
        LayoutSegment s;
        s.chain = 0; s.first = i; s.count = 1; s.label = labels[i];
        s.break_a = i; s.break_b = (i + 1) % 4;
        s.target = targets[i];
        L.segments.push_back(s);
      }
      L.vertex_break = {0, 1, 2, 3};
      QuantizeOptions o;
      o.graded = graded;
      if (large) o.large_program_columns = 0;
      quantize_layout(L, deformed, o, "test");
      ASSERT_EQ(check_layout(L), "");
      EXPECT_EQ(L.lattice[1][0] - L.lattice[0][0], graded ? 5 : 3) << (large ? "compact" : "inequality") << " form";
    }
  }
}
