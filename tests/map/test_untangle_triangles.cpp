// Foldover-free maps with a fixed boundary (map/untangle_triangles.h): the snap's last resort.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "map/loop_path.h"
#include "map/untangle_triangles.h"
#include "polysquare/map/deform.h"

using namespace polysquare;

namespace {

// A rest grid of nx x ny unit cells, two triangles each, counter-clockwise; vertex (i, j) is j * (nx + 1) + i.
DeformProblem grid(int nx, int ny) {
  DeformProblem p;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) p.rest.push_back({static_cast<double>(i), static_cast<double>(j)});
  auto id = [&](int i, int j) { return static_cast<std::int32_t>(j * (nx + 1) + i); };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      p.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      p.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return p;
}

// The uniform harmonic (Tutte) embedding of the free vertices, by Gauss-Seidel sweeps.
void tutte(const DeformProblem& p, const std::vector<std::uint8_t>& movable, std::vector<Vec2>& x) {
  std::vector<std::vector<std::int32_t>> nb(x.size());
  for (const auto& t : p.triangles)
    for (int k = 0; k < 3; ++k) nb[static_cast<std::size_t>(t[k])].push_back(t[(k + 1) % 3]), nb[static_cast<std::size_t>(t[(k + 1) % 3])].push_back(t[k]);
  for (int sweep = 0; sweep < 20000; ++sweep)
    for (std::size_t v = 0; v < x.size(); ++v) {
      if (!movable[v]) continue;
      Vec2 s{};
      for (std::int32_t w : nb[v]) s = s + x[static_cast<std::size_t>(w)];
      x[v] = (1.0 / static_cast<double>(nb[v].size())) * s;
    }
}

}  // namespace

TEST(UntangleTriangles, ASquareGridOnAUShapedBoundaryUnfoldsWhereItsTutteEmbeddingFolds) {
  // A 12 x 12 grid whose four sides are spread round a U (a 3 x 3 square with a 1-wide slot cut 2 deep from the
  // top; the grid's top side runs down and up the slot): the boundary is a simple polygon, and each grid corner
  // sits on a corner of the U, but the uniform harmonic embedding averages the interior across the slot.
  const int n = 12;
  DeformProblem p = grid(n, n);
  const std::vector<Vec2> loop = {{0, 0}, {3, 0}, {3, 3}, {2, 3}, {2, 1}, {1, 1}, {1, 3}, {0, 3}};
  // The grid's sides, counter-clockwise from (0, 0), take the arcs [0, 3], [3, 7], [7, 12] and [12, 16].
  auto arc = [&](Vec2 r) {
    if (r.y == 0) return 3.0 * r.x / n;
    if (r.x == n) return 3.0 + 4.0 * r.y / n;
    if (r.y == n) return 7.0 + 5.0 * (n - r.x) / n;
    return 12.0 + 4.0 * (n - r.y) / n;
  };
  std::vector<std::uint8_t> movable(p.rest.size(), 0);
  std::vector<Vec2> x(p.rest.size());
  for (std::size_t v = 0; v < p.rest.size(); ++v) {
    const Vec2 r = p.rest[v];
    const bool boundary = r.x == 0 || r.y == 0 || r.x == n || r.y == n;
    movable[v] = !boundary;
    x[v] = boundary ? point_on_loop(loop, arc(r)) : Vec2{1.5, 1.5};
  }
  tutte(p, movable, x);
  ASSERT_LE(min_signed_area(p.triangles, x), 0.0) << "the test needs a folded start";
  const std::vector<Vec2> start = x;
  ASSERT_TRUE(untangle_triangles(p, movable, x));
  EXPECT_GT(min_signed_area(p.triangles, x), 0.0);
  for (std::size_t v = 0; v < x.size(); ++v)
    if (!movable[v]) EXPECT_EQ(x[v], start[v]);
}

TEST(UntangleTriangles, ATriangleOfFixedVerticesTurnedOverCannotBeMended) {
  // Every vertex fixed, one triangle inverted: nothing may move, and the answer is no.
  DeformProblem p = grid(2, 1);
  std::vector<Vec2> x = p.rest;
  x[0] = {1.5, 0.8};  // vertex (0, 0) moved across the diagonal of its triangles
  const std::vector<std::uint8_t> movable(p.rest.size(), 0);
  EXPECT_FALSE(untangle_triangles(p, movable, x));
  EXPECT_EQ(x[0], (Vec2{1.5, 0.8}));
}

TEST(UntangleTriangles, AFoldedInteriorVertexReturnsInsideItsStar) {
  // A 4 x 4 grid whose four central vertices are thrown outside the square: untangling brings them back so
  // that every triangle is positive, the boundary untouched.
  DeformProblem p = grid(4, 4);
  std::vector<Vec2> x = p.rest;
  std::vector<std::uint8_t> movable(p.rest.size(), 0);
  for (std::size_t v = 0; v < p.rest.size(); ++v) {
    const Vec2 r = p.rest[v];
    movable[v] = r.x > 0 && r.x < 4 && r.y > 0 && r.y < 4;
  }
  x[6] = {5.0, -1.0};
  x[12] = {-2.0, 7.0};
  ASSERT_LE(min_signed_area(p.triangles, x), 0.0);
  ASSERT_TRUE(untangle_triangles(p, movable, x));
  EXPECT_GT(min_signed_area(p.triangles, x), 0.0);
  for (std::size_t v : {6u, 12u}) {
    EXPECT_GT(x[v].x, 0.0);
    EXPECT_LT(x[v].x, 4.0);
    EXPECT_GT(x[v].y, 0.0);
    EXPECT_LT(x[v].y, 4.0);
  }
}
