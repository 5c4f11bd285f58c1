// Invariant 7 (design.md): no two quads overlap. find_overlapping_quads on hand-made meshes whose answer is known,
// check_invariants refusing them, and the CLI on inputs whose parts lie closer than a boundary chord's sagitta
// (issue 13, class 1; tests/data/adversarial/README.md).
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "polysquare/io/mesh_io.h"
#include "polysquare/pipeline/invariants.h"

namespace fs = std::filesystem;
using namespace polysquare;

namespace {

// An nx x ny grid of unit squares from `origin`, counter-clockwise, boundary edges tagged (ring 0).
QuadMesh grid(int nx, int ny, Vec2 origin = {0, 0}, double step = 1.0) {
  QuadMesh m;
  auto id = [&](int i, int j) { return static_cast<std::int32_t>(j * (nx + 1) + i); };
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) m.nodes.push_back({origin.x + step * i, origin.y + step * j});
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) m.quads.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
  for (int i = 0; i < nx; ++i) {
    m.boundary_edges.push_back({id(i, 0), id(i + 1, 0)});
    m.boundary_edges.push_back({id(i, ny), id(i + 1, ny)});
  }
  for (int j = 0; j < ny; ++j) {
    m.boundary_edges.push_back({id(0, j), id(0, j + 1)});
    m.boundary_edges.push_back({id(nx, j), id(nx, j + 1)});
  }
  m.boundary_edge_ring.assign(m.boundary_edges.size(), 0);
  return m;
}

// Appends the quad with corners a b c d as four new nodes (shares no node with anything).
std::size_t add_quad(QuadMesh& m, Vec2 a, Vec2 b, Vec2 c, Vec2 d) {
  const auto n = static_cast<std::int32_t>(m.nodes.size());
  m.nodes.insert(m.nodes.end(), {a, b, c, d});
  m.quads.push_back({n, n + 1, n + 2, n + 3});
  return m.quads.size() - 1;
}

}  // namespace

TEST(Overlap, TwoQuadsSharingNoNodeAreCaughtAndNamed) {
  QuadMesh m;
  add_quad(m, {0, 0}, {1, 0}, {1, 1}, {0, 1});
  add_quad(m, {0.5, 0.5}, {1.5, 0.5}, {1.5, 1.5}, {0.5, 1.5});
  const QuadOverlaps o = find_overlapping_quads(m);
  EXPECT_EQ(o.pairs, 1u);
  EXPECT_EQ(o.first_a, 0);
  EXPECT_EQ(o.first_b, 1);
  // The point named lies inside both squares.
  EXPECT_GT(o.at.x, 0.5);
  EXPECT_LT(o.at.x, 1.0);
  EXPECT_GT(o.at.y, 0.5);
  EXPECT_LT(o.at.y, 1.0);
  const InvariantReport r = check_invariants(m);
  EXPECT_EQ(r.overlapping_quad_pairs, 1u);
  EXPECT_FALSE(r.ok());
  EXPECT_NE(r.first_problem.find("1 pair of quads overlaps, first quads 0 and 1"), std::string::npos) << r.first_problem;
}

TEST(Overlap, OverlapsWithNoEdgeCrossingAreCaught) {
  // The same square twice on different nodes (every vertex on the other's boundary, no proper crossing), a small
  // square inside a large one (no edge crossing at all), and a square covering half of another with two
  // edges along it: each pair overlaps.
  QuadMesh same;
  add_quad(same, {0, 0}, {1, 0}, {1, 1}, {0, 1});
  add_quad(same, {0, 0}, {1, 0}, {1, 1}, {0, 1});
  EXPECT_EQ(find_overlapping_quads(same).pairs, 1u);
  QuadMesh inside;
  add_quad(inside, {0, 0}, {10, 0}, {10, 10}, {0, 10});
  add_quad(inside, {4, 4}, {5, 4}, {5, 5}, {4, 5});
  EXPECT_EQ(find_overlapping_quads(inside).pairs, 1u);
  QuadMesh half;
  add_quad(half, {0, 0}, {1, 0}, {1, 2}, {0, 2});
  add_quad(half, {0, 0}, {1, 0}, {1, 1}, {0, 1});
  EXPECT_EQ(find_overlapping_quads(half).pairs, 1u);
}

TEST(Overlap, QuadsThatOnlyTouchDoNotOverlap) {
  // Side by side on separate nodes, corner to corner, and a T-junction (a node of one in the middle of an edge of
  // the other): touching, not overlapping (check_invariants reports the cracks, not an overlap).
  QuadMesh m;
  add_quad(m, {0, 0}, {1, 0}, {1, 1}, {0, 1});
  add_quad(m, {1, 0}, {2, 0}, {2, 1}, {1, 1});
  add_quad(m, {2, 1}, {3, 1}, {3, 2}, {2, 2});
  add_quad(m, {0, 1}, {0.5, 1}, {0.5, 2}, {0, 2});
  add_quad(m, {0.5, 1}, {1, 1}, {1, 2}, {0.5, 2});
  EXPECT_EQ(find_overlapping_quads(m).pairs, 0u);
  EXPECT_EQ(check_invariants(m).overlapping_quad_pairs, 0u);
}

TEST(Overlap, ValidGridsPassFarFromTheOriginAndWithTinySteps) {
  for (const Vec2 origin : {Vec2{0, 0}, Vec2{1e8, -3e7}, Vec2{4.1e11, 4.1e11}}) {
    const QuadMesh m = grid(60, 45, origin, origin.x > 1e10 ? 0.37 : 0.1);
    const InvariantReport r = check_invariants(m);
    EXPECT_TRUE(r.ok()) << r.first_problem;
    EXPECT_EQ(r.overlapping_quad_pairs, 0u);
  }
  // A grid of skewed, non-convex-free but oblique quads: shear every row.
  QuadMesh sheared = grid(30, 30);
  for (Vec2& p : sheared.nodes) p.x += 0.7 * p.y + 0.1 * std::sin(p.y);
  EXPECT_TRUE(check_invariants(sheared).ok()) << check_invariants(sheared).first_problem;
}

TEST(Overlap, AFanOfConvexQuadsTurningPastAFullCircleOverlaps) {
  // Five convex quads around one node, 90 degrees each: every quad is fine alone and every edge has at most two
  // quads, but the fifth lies on the first.
  QuadMesh m;
  m.nodes.push_back({0, 0});
  const int n = 5;
  for (int k = 0; k <= n; ++k) {
    const double a = k * M_PI / 2;
    m.nodes.push_back({std::cos(a), std::sin(a)});
    m.nodes.push_back({std::cos(a + M_PI / 4) * 1.4, std::sin(a + M_PI / 4) * 1.4});
  }
  for (int k = 0; k < n; ++k) {
    const auto e = static_cast<std::int32_t>(1 + 2 * k);
    m.quads.push_back({0, e, e + 1, e + 2});
  }
  const QuadOverlaps o = find_overlapping_quads(m);
  EXPECT_EQ(o.pairs, 1u);
  EXPECT_EQ(o.first_a, 0);
  EXPECT_EQ(o.first_b, 4);
}

TEST(Overlap, NonConvexQuadsAreSplitAlongTheirInnerDiagonal) {
  // A dart (reflex corner at (1, 0.5)) and a square in its notch: the notch is outside the dart, so no overlap;
  // moved into the dart's body, the square overlaps it.
  QuadMesh m;
  add_quad(m, {0, 0}, {2, 0}, {1, 0.5}, {0, 2});  // dart, counter-clockwise; its notch is the corner region
  add_quad(m, {1.2, 0.7}, {1.6, 0.7}, {1.6, 1.1}, {1.2, 1.1});
  EXPECT_EQ(find_overlapping_quads(m).pairs, 0u);
  add_quad(m, {0.2, 0.2}, {0.4, 0.2}, {0.4, 0.4}, {0.2, 0.4});
  const QuadOverlaps o = find_overlapping_quads(m);
  EXPECT_EQ(o.pairs, 1u);
  EXPECT_EQ(o.first_b, 2);
}

TEST(Overlap, TheFirstPairIsTheLowestAndTheCountIsExact) {
  // Two grids on separate nodes, the second shifted by half a cell: every cell of the overlap region meets four
  // of the other grid's cells.
  QuadMesh m = grid(20, 20);
  const QuadMesh other = grid(20, 20, {10.5, 10.5});
  const auto offset = static_cast<std::int32_t>(m.nodes.size());
  m.nodes.insert(m.nodes.end(), other.nodes.begin(), other.nodes.end());
  for (auto q : other.quads) {
    for (auto& v : q) v += offset;
    m.quads.push_back(q);
  }
  const QuadOverlaps o = find_overlapping_quads(m);
  // Cell (i, j) of the first grid overlaps cells (i - 10 + di, j - 10 + dj), di, dj in {-1, 0}, of the second
  // where they exist.
  std::size_t expected = 0;
  for (int i = 10; i < 20; ++i)
    for (int j = 10; j < 20; ++j)
      for (int di = -1; di <= 0; ++di)
        for (int dj = -1; dj <= 0; ++dj) {
          const int k = i - 10 + di, l = j - 10 + dj;  // the second grid's cell k spans [10.5 + k, 11.5 + k]
          expected += k >= 0 && l >= 0 && k < 20 && l < 20;
        }
  EXPECT_EQ(o.pairs, expected);
  EXPECT_EQ(o.first_a, 10 * 20 + 10);  // cell (10, 10) of the first grid
  EXPECT_EQ(o.first_b, 400);           // cell (0, 0) of the second
}

TEST(Overlap, NonFiniteNodesAreInvalidNotACrash) {
  QuadMesh m = grid(3, 3);
  m.nodes[5].x = std::nan("");
  const InvariantReport r = check_invariants(m);
  EXPECT_FALSE(r.ok());
  EXPECT_GE(r.inverted_quads, 1u);
  EXPECT_EQ(r.overlapping_quad_pairs, 0u);
}

// --- the CLI on inputs whose parts lie closer than the sagitta of a boundary chord (issue 13, class 1) ---

namespace {
struct CliRun {
  int code;
  std::string out, err;
};
std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}
CliRun run_cli(const std::string& args) {
  const fs::path tmp = fs::temp_directory_path();
  const std::string tag = std::to_string(::getpid());
  const fs::path out = tmp / ("polysquare_overlap_out_" + tag), err = tmp / ("polysquare_overlap_err_" + tag);
  const int status = std::system((std::string(POLYSQUARE_CLI) + " " + args + " > " + out.string() + " 2> " + err.string()).c_str());
  CliRun r{WEXITSTATUS(status), slurp(out), slurp(err)};
  fs::remove(out);
  fs::remove(err);
  return r;
}
std::string adversarial(const std::string& name) { return std::string(POLYSQUARE_TEST_DATA_DIR) + "/adversarial/" + name; }
}  // namespace

TEST(Overlap, CloseRingsEndInAnEmbeddedMeshOrARefusalNeverAnOverlappingFile) {
  const fs::path dir = fs::temp_directory_path() / ("polysquare_overlap_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  // With --simplify 0 no simplification pins the rings (input/chord_clearance.h): the invariant check refuses.
  for (const std::string name : {"parts_two_disks_gap_0_05", "island_in_hole_gap_0_05", "island_in_hole_gap_0_01",
                                 "parts_disk_in_notch_gap_0_05", "island_in_hole_gap_0_05 --simplify 0",
                                 "parts_disk_in_notch_gap_0_05 --simplify 0"}) {
    SCOPED_TRACE(name);
    const std::string tag = name.substr(0, name.find(' ')) + (name.find(' ') == std::string::npos ? "" : "_s0");
    fs::create_directories(dir / tag);
    const fs::path out = dir / tag / "mesh.msh";
    const CliRun r = run_cli("mesh " + adversarial(name.substr(0, name.find(' ')) + ".geojson") +
                             name.substr(std::min(name.size(), name.find(' '))) + " --size 2 -q -o " + out.string());
    if (r.code == 0) {
      ASSERT_TRUE(fs::exists(out));
      const QuadMesh m = read_mesh(out);
      const QuadOverlaps o = find_overlapping_quads(m);
      EXPECT_EQ(o.pairs, 0u) << "first quads " << o.first_a << " and " << o.first_b;
      EXPECT_EQ(run_cli("quality " + out.string()).code, 0);
    } else {
      EXPECT_EQ(r.code, 3) << r.err;
      EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
      EXPECT_EQ(r.err.rfind("error: ", 0), 0u) << r.err;
      EXPECT_NE(r.err.find("overlap"), std::string::npos) << r.err;
      EXPECT_NE(r.err.find(" at ("), std::string::npos) << r.err;
      EXPECT_FALSE(fs::exists(out));
    }
    // Nothing but the mesh (or nothing at all) is left in the directory: no temporaries.
    for (const auto& e : fs::directory_iterator(dir / tag)) EXPECT_EQ(e.path(), out) << e.path();
  }
  // Convex rings facing each other cannot overlap (their chords cut inward); the pins of the simplification
  // (input/chord_clearance.h) keep the concave ones' chords off the other ring: all four mesh.
  for (const char* name : {"parts_two_disks_gap_0_05", "island_in_hole_gap_0_05", "island_in_hole_gap_0_01",
                           "parts_disk_in_notch_gap_0_05"})
    EXPECT_TRUE(fs::exists(dir / name / "mesh.msh")) << name;
  fs::remove_all(dir);
}

TEST(Overlap, QualityRefusesAnOverlappingMeshNamingThePair) {
  const CliRun r = run_cli("quality " + adversarial("quality_overlapping.msh"));
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.out.find("overlapping quad pairs 1"), std::string::npos) << r.out;
  EXPECT_NE(r.err.find("1 pair of quads overlaps, first quads 0 and 1"), std::string::npos) << r.err;
  const CliRun j = run_cli("quality --json " + adversarial("quality_overlapping.msh"));
  EXPECT_EQ(j.code, 2);
  EXPECT_NE(j.out.find("\"overlapping_quad_pairs\": 1"), std::string::npos) << j.out;
}
