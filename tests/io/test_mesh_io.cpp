// Mesh files round-trip exactly, other tools read what we write, malformed files are clean errors.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "polysquare/core/error.h"
#include "polysquare/input/read_region.h"
#include "polysquare/io/atomic_file.h"
#include "polysquare/io/mesh_io.h"
#include "polysquare/pipeline/mesh_region.h"
#include "polysquare/quality/quality.h"

using namespace polysquare;
namespace fs = std::filesystem;

namespace {
QuadMesh sample_mesh() {
  MeshOptions o;
  o.size = 3.0;
  return mesh_region(read_region(std::string(POLYSQUARE_DATA_DIR) + "/cases/square_feature.geojson"), o).mesh;
}
fs::path temp(const std::string& name) { return fs::temp_directory_path() / ("polysquare_test_" + std::to_string(::getpid()) + "_" + name); }
}  // namespace

TEST(MeshIo, MshRoundTripAsciiAndBinary) {
  const QuadMesh m = sample_mesh();
  for (bool binary : {false, true}) {
    const fs::path p = temp(binary ? "b.msh" : "a.msh");
    write_mesh(p, m, {binary});
    const QuadMesh r = read_mesh(p);
    ASSERT_EQ(r.nodes.size(), m.nodes.size());
    for (std::size_t i = 0; i < m.nodes.size(); ++i) ASSERT_TRUE(r.nodes[i] == m.nodes[i]);
    EXPECT_EQ(r.quads, m.quads);
    EXPECT_EQ(r.boundary_edges.size(), m.boundary_edges.size());
    EXPECT_EQ(r.feature_edges.size(), m.feature_edges.size());
    fs::remove(p);
  }
}

TEST(MeshIo, VtuRoundTrip) {
  const QuadMesh m = sample_mesh();
  const fs::path p = temp("m.vtu");
  write_mesh(p, m);
  const QuadMesh r = read_mesh(p);
  ASSERT_EQ(r.nodes.size(), m.nodes.size());
  for (std::size_t i = 0; i < m.nodes.size(); ++i) ASSERT_TRUE(r.nodes[i] == m.nodes[i]);
  EXPECT_EQ(r.quads, m.quads);
  fs::remove(p);
}

TEST(MeshIo, GmshAndMeshioReadOurMsh) {
  const QuadMesh m = sample_mesh();
  const fs::path p = temp("g.msh"), out = temp("g_out.msh");
  write_mesh(p, m);
  if (std::system("command -v gmsh > /dev/null 2>&1") != 0) GTEST_SKIP() << "gmsh not installed";
  // Gmsh re-reads and re-writes the file; the re-written mesh has the same quads.
  const std::string cmd = "gmsh " + p.string() + " -0 -format msh41 -o " + out.string() + " > /dev/null 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  EXPECT_EQ(compute_quality(read_mesh(out)).quads, m.quads.size());
  const std::string py = "/usr/bin/python3 -c \"import meshio,sys; m=meshio.read('" + p.string() +
                         "'); sys.exit(0 if sum(len(c.data) for c in m.cells if c.type=='quad')==" +
                         std::to_string(m.quads.size()) + " else 1)\" 2>/dev/null";
  if (std::system("/usr/bin/python3 -c 'import meshio' 2>/dev/null") == 0) EXPECT_EQ(std::system(py.c_str()), 0);
  fs::remove(p);
  fs::remove(out);
}

TEST(MeshIo, MalformedFilesAreInputErrors) {
  const QuadMesh m = sample_mesh();
  const fs::path good = temp("t.msh");
  write_mesh(good, m);
  std::ifstream in(good, std::ios::binary);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const fs::path bad = temp("trunc.msh");
  for (std::size_t cut : {text.size() / 3, text.size() / 2, text.size() - 20}) {
    std::ofstream(bad, std::ios::binary) << text.substr(0, cut);
    EXPECT_THROW(read_mesh(bad), InputError) << cut;
  }
  std::ofstream(bad, std::ios::binary) << "garbage\x01\x02";
  EXPECT_THROW(read_mesh(bad), InputError);
  EXPECT_THROW(read_mesh(temp("x.stl")), InputError);
  fs::remove(good);
  fs::remove(bad);
}

TEST(MeshIo, AtomicWriteLeavesNothingWhenTheWriterFails) {
  const fs::path p = temp("atomic.txt");
  EXPECT_THROW(write_file_atomically(p, [](std::ostream& os) { os << "partial"; throw std::runtime_error("boom"); }, false),
               std::runtime_error);
  EXPECT_FALSE(fs::exists(p));
  for (const auto& e : fs::directory_iterator(p.parent_path()))
    EXPECT_EQ(e.path().filename().string().find(p.filename().string() + ".tmp"), std::string::npos);
}

TEST(Quality, HandMadeQuads) {
  QuadMesh m;
  m.nodes = {{0, 0}, {1, 0}, {1, 1}, {0, 1}, {1.5, 0.8660254037844386}, {0.5, 0.8660254037844386}, {3, 0}, {3, 1}};
  m.quads = {{0, 1, 2, 3}, {0, 1, 4, 5}, {1, 6, 7, 2}};
  const QuadMetrics q = quad_metrics(m);
  EXPECT_NEAR(q.sj[0], 1.0, 1e-12);
  EXPECT_NEAR(q.skew[0], 0.0, 1e-12);
  EXPECT_NEAR(q.sj[1], std::sqrt(3.0) / 2, 1e-9);   // 60/120 degree rhombus
  EXPECT_NEAR(q.eta[1], std::sqrt(3.0) / 2, 1e-9);
  EXPECT_NEAR(q.skew[1], 1.0 / 3.0, 1e-9);
  EXPECT_NEAR(q.edge_ratio[2], 2.0, 1e-12);
  m.quads = {{0, 3, 2, 1}};  // clockwise: inverted
  EXPECT_LT(quad_metrics(m).sj[0], 0.0);
}

TEST(Quality, SingularitiesOfAGridAndOfAValenceThreeVertex) {
  QuadMesh g;
  for (int j = 0; j <= 3; ++j)
    for (int i = 0; i <= 3; ++i) g.nodes.push_back({double(i), double(j)});
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) g.quads.push_back({j * 4 + i, j * 4 + i + 1, (j + 1) * 4 + i + 1, (j + 1) * 4 + i});
  QualityReport q = compute_quality(g);
  EXPECT_EQ(q.interior_singularities, 0u);
  EXPECT_EQ(q.boundary_singularities, 4u);  // corners have valence 2
  // Three quads around a centre: the centre is an interior valence-3 vertex.
  QuadMesh t;
  t.nodes = {{0, 0}, {1, 0}, {0.8, 0.8}, {-0.2, 1}, {-1, 0.2}, {-0.8, -0.8}, {0.2, -1}};
  t.quads = {{0, 1, 2, 3}, {0, 3, 4, 5}, {0, 5, 6, 1}};
  q = compute_quality(t);
  EXPECT_EQ(q.interior_singularities, 1u);
}
