// Mesh files round-trip exactly, other tools read what we write, malformed files are clean errors.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

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
  o.size.h = 3.0;
  return mesh_region(read_region(std::string(POLYSQUARE_DATA_DIR) + "/cases/square_feature.geojson"), o).mesh;
}
fs::path temp(const std::string& name) { return fs::temp_directory_path() / ("polysquare_test_" + std::to_string(::getpid()) + "_" + name); }
}  // namespace

// Curve edges as sorted (curve, lo, hi) triples, so files that list them in another order compare equal.
std::vector<std::array<std::int32_t, 3>> curve_edges(const std::vector<std::array<std::int32_t, 2>>& edges,
                                                     const std::vector<std::int32_t>& curve) {
  std::vector<std::array<std::int32_t, 3>> out;
  for (std::size_t e = 0; e < edges.size(); ++e)
    out.push_back({curve[e], std::min(edges[e][0], edges[e][1]), std::max(edges[e][0], edges[e][1])});
  std::sort(out.begin(), out.end());
  return out;
}

TEST(MeshIo, MshRoundTripEveryVersionFormAndFeatureMode) {
  const QuadMesh m = sample_mesh();
  ASSERT_GT(m.feature_edges.size(), 0u);
  for (MshVersion version : {MshVersion::v2_2, MshVersion::v4_1})
    for (bool binary : {false, true})
      for (MshFeatures features : {MshFeatures::nodes, MshFeatures::lines, MshFeatures::none}) {
        const std::string what = "version " + std::to_string(static_cast<int>(version)) + " binary " +
                                 std::to_string(binary) + " features " + std::to_string(static_cast<int>(features));
        const fs::path p = temp("rt.msh");
        write_mesh(p, m, {binary, features, version});
        const QuadMesh r = read_mesh(p);
        ASSERT_EQ(r.nodes.size(), m.nodes.size()) << what;
        for (std::size_t i = 0; i < m.nodes.size(); ++i) ASSERT_TRUE(r.nodes[i] == m.nodes[i]) << what;
        EXPECT_EQ(r.quads, m.quads) << what;
        EXPECT_EQ(curve_edges(r.boundary_edges, r.boundary_edge_ring), curve_edges(m.boundary_edges, m.boundary_edge_ring))
            << what;
        // Features come back exactly, whether written as lines or as point groups (rebuilt from the cell edges).
        if (features == MshFeatures::none) EXPECT_TRUE(r.feature_edges.empty()) << what;
        else EXPECT_EQ(curve_edges(r.feature_edges, r.feature_edge_curve), curve_edges(m.feature_edges, m.feature_edge_curve))
            << what;
        fs::remove(p);
      }
}

// An independent reading of the default file (ASCII MSH 2.2, parsed here without our reader): no line element may
// lie between two quads, since deal.II refuses such a file; every feature node is in a point group instead.
TEST(MeshIo, DefaultMshHasNoLineElementOnAnInteriorEdge) {
  const QuadMesh m = sample_mesh();
  for (MshFeatures features : {MshFeatures::nodes, MshFeatures::lines}) {
    const fs::path p = temp("interior.msh");
    write_mesh(p, m, {false, features});
    std::ifstream in(p);
    std::string word;
    while (in >> word && word != "$Elements") {}
    std::size_t n = 0;
    in >> n;
    std::map<std::pair<long, long>, int> quads_at_edge;
    std::vector<std::pair<long, long>> lines;
    std::set<long> points;
    for (std::size_t i = 0; i < n; ++i) {
      long id = 0, type = 0, ntags = 0, tag = 0;
      in >> id >> type >> ntags;
      for (long t = 0; t < ntags; ++t) in >> tag;
      const int nodes = type == 1 ? 2 : type == 15 ? 1 : type == 3 ? 4 : -1;
      ASSERT_GT(nodes, 0) << "element type " << type;
      std::array<long, 4> v{};
      for (int k = 0; k < nodes; ++k) in >> v[k];
      if (type == 1) lines.push_back(std::minmax(v[0], v[1]));
      if (type == 15) points.insert(v[0]);
      if (type == 3)
        for (int k = 0; k < 4; ++k) quads_at_edge[std::minmax(v[k], v[(k + 1) % 4])]++;
    }
    ASSERT_TRUE(in >> word && word == "$EndElements");
    std::size_t interior_lines = 0;
    for (const auto& e : lines) interior_lines += quads_at_edge[e] == 2;
    std::set<long> feature_nodes;
    for (const auto& e : m.feature_edges) feature_nodes.insert(e[0] + 1), feature_nodes.insert(e[1] + 1);
    if (features == MshFeatures::nodes) {
      EXPECT_EQ(interior_lines, 0u);
      EXPECT_EQ(lines.size(), m.boundary_edges.size());
      EXPECT_EQ(points, feature_nodes);
    } else {  // the mode for readers that take interior lines: the features are there as lines
      EXPECT_GT(interior_lines, 0u);
      EXPECT_TRUE(points.empty());
    }
    fs::remove(p);
  }
}

#ifdef POLYSQUARE_DEALII_READER
// deal.II 9.4's GridIn::read_msh on the default file of every bundled case: it must take it, with one cell per
// quad and boundary id k + 2 on the edges of the k-th ring. A file with interior feature lines must be refused,
// or this test would not notice the problem it guards against.
TEST(MeshIo, DealiiReadsTheDefaultMshOfEveryCase) {
  std::vector<fs::path> cases;
  for (const auto& e : fs::directory_iterator(std::string(POLYSQUARE_DATA_DIR) + "/cases"))
    if (e.path().extension() == ".geojson") cases.push_back(e.path());
  std::sort(cases.begin(), cases.end());
  ASSERT_GE(cases.size(), 16u);
  const fs::path p = temp("dealii.msh"), out = temp("dealii.txt");
  auto read_with_dealii = [&]() {
    const std::string cmd = std::string(POLYSQUARE_DEALII_READER) + " " + p.string() + " > " + out.string() + " 2>&1";
    const int status = std::system(cmd.c_str());
    std::ifstream in(out);
    return std::pair{status, std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>())};
  };
  bool refused_lines = false;
  for (const fs::path& c : cases) {
    // delta_box has no one-poly-square mesh (the fast path below refuses it): the CTest test
    // read_back.every_case_default_msh reads its 200 m mesh, and every other case's at its size with default
    // options, with deal.II and meshio.
    if (c.stem() == "delta_box") continue;
    const Region region = read_region(c);
    MeshOptions o;
    o.size.h = region.bounding_box().diagonal() / 50;  // one to three thousand quads on every case
    o.subregions.parts = 1;                            // the fast path: this test is about the file, not the mesh
    o.curves.simplify = 0.5;
    const QuadMesh m = mesh_region(region, o).mesh;
    write_mesh(p, m);
    const auto [status, text] = read_with_dealii();
    ASSERT_EQ(status, 0) << c << ": " << text;
    std::istringstream got(text);
    std::size_t cells = 0, faces = 0;
    got >> cells >> faces;
    EXPECT_EQ(cells, m.quads.size()) << c;
    EXPECT_EQ(faces, m.boundary_edges.size()) << c;
    std::map<int, std::size_t> per_ring;
    for (int r : m.boundary_edge_ring) per_ring[r]++;
    std::string expected;
    int id = 2;
    for (const auto& [ring, count] : per_ring) expected += " " + std::to_string(id++) + ":" + std::to_string(count);
    std::string ids;
    std::getline(got, ids);
    EXPECT_EQ(ids, expected) << c;
    if (!m.feature_edges.empty() && !refused_lines) {
      write_mesh(p, m, {false, MshFeatures::lines});
      refused_lines = read_with_dealii().first != 0;
      EXPECT_TRUE(refused_lines) << c << ": deal.II took interior feature lines";
    }
  }
  EXPECT_TRUE(refused_lines);
  fs::remove(p);
  fs::remove(out);
}
#else
TEST(MeshIo, DealiiReadsTheDefaultMshOfEveryCase) { GTEST_SKIP() << "deal.II not found by CMake (libdeal.ii-dev)"; }
#endif

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

// A .pvtu's pieces hold every quad exactly once, in runs of subregions; meshio reads each piece, and the pieces
// read back together give the mesh (nodes on the seams merged).
TEST(MeshIo, PvtuPiecesHoldEveryQuadOnce) {
  const QuadMesh m = sample_mesh();
  ASSERT_EQ(m.quad_part.size(), m.quads.size());
  const fs::path p = temp("pieces.pvtu");
  MeshWriteOptions o;
  o.pieces = 3;
  write_mesh(p, m, o);
  std::ifstream in(p);
  const std::string xml((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  using Corners = std::array<std::pair<double, double>, 4>;
  auto corners = [](const QuadMesh& mesh, std::size_t q) {
    Corners c;
    for (int k = 0; k < 4; ++k) {
      const Vec2 v = mesh.nodes[static_cast<std::size_t>(mesh.quads[q][static_cast<std::size_t>(k)])];
      c[static_cast<std::size_t>(k)] = {v.x, v.y};
    }
    std::sort(c.begin(), c.end());
    return c;
  };
  std::map<Corners, int> seen;
  std::size_t quads = 0;
  int last_part = -1;
  for (int k = 0; k < 3; ++k) {
    const std::string name = p.stem().string() + "_" + std::to_string(k) + ".vtu";
    EXPECT_NE(xml.find("Source=\"" + name + "\""), std::string::npos) << name;
    const fs::path piece = p.parent_path() / name;
    ASSERT_TRUE(fs::exists(piece)) << piece;
    const QuadMesh r = read_vtu(piece);
    EXPECT_GT(r.quads.size(), m.quads.size() / 4);  // nearly equal runs
    quads += r.quads.size();
    for (std::size_t q = 0; q < r.quads.size(); ++q) seen[corners(r, q)]++;
    // Subregions in order: a piece starts at or after the last subregion of the one before.
    std::ifstream pin(piece);
    const std::string pxml((std::istreambuf_iterator<char>(pin)), std::istreambuf_iterator<char>());
    const std::size_t at = pxml.find("Name=\"part\"");
    ASSERT_NE(at, std::string::npos);
    std::istringstream parts(pxml.substr(pxml.find('>', at) + 1));
    int part = 0, first = -1, last = -1;
    for (std::size_t q = 0; q < r.quads.size() && parts >> part; ++q) {
      if (first < 0) first = part;
      EXPECT_GE(part, last);
      last = part;
    }
    EXPECT_GE(first, last_part);
    last_part = last;
    const std::string py = "/usr/bin/python3 -c \"import meshio,sys; m=meshio.read('" + piece.string() +
                           "'); sys.exit(0 if sum(len(c.data) for c in m.cells if c.type=='quad')==" +
                           std::to_string(r.quads.size()) + " else 1)\" 2>/dev/null";
    if (std::system("/usr/bin/python3 -c 'import meshio' 2>/dev/null") == 0) EXPECT_EQ(std::system(py.c_str()), 0);
  }
  EXPECT_EQ(quads, m.quads.size());
  ASSERT_EQ(seen.size(), m.quads.size());
  for (std::size_t q = 0; q < m.quads.size(); ++q) EXPECT_EQ(seen[corners(m, q)], 1);
  const QuadMesh whole = read_mesh(p);
  EXPECT_EQ(whole.nodes.size(), m.nodes.size());
  const QualityReport a = compute_quality(whole), b = compute_quality(m);
  EXPECT_EQ(a.quads, b.quads);
  EXPECT_EQ(a.interior_singularities, b.interior_singularities);
  EXPECT_EQ(a.sj.min, b.sj.min);
  fs::remove(p);
  for (int k = 0; k < 3; ++k) fs::remove(p.parent_path() / (p.stem().string() + "_" + std::to_string(k) + ".vtu"));
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

// Runs a shell command; returns its stdout and sets `code` to its exit status.
std::string shell_output(const std::string& cmd, int& code) {
  const fs::path out = temp("shell.out");
  const int status = std::system((cmd + " > " + out.string() + " 2>/dev/null").c_str());
  code = WEXITSTATUS(status);
  std::ifstream in(out);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  fs::remove(out);
  return text;
}

TEST(MeshIo, MshAndVtuRecordTheCrsWhereOtherReadersKeepReading) {
  QuadMesh m = sample_mesh();
  m.crs = "EPSG:32616";
  const bool have_gmsh = std::system("command -v gmsh > /dev/null 2>&1") == 0;
  const bool have_meshio = std::system("/usr/bin/python3 -c 'import meshio' 2>/dev/null") == 0;
  const bool have_gdalsrsinfo = std::system("command -v gdalsrsinfo > /dev/null 2>&1") == 0;
  for (MshVersion version : {MshVersion::v2_2, MshVersion::v4_1})
    for (bool binary : {false, true}) {
      const std::string what = std::string(version == MshVersion::v4_1 ? "4.1" : "2.2") + (binary ? " binary" : " ASCII");
      const fs::path p = temp("crs.msh"), out = temp("crs_gmsh.msh");
      MeshWriteOptions o;
      o.msh_version = version;
      o.binary = binary;
      write_mesh(p, m, o);
      std::ifstream in(p, std::ios::binary);
      const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      // The Gmsh manual: a section with an unknown header is skipped, e.g. $Comments ... $EndComments. Ours holds
      // "key value" lines and comes after $EndElements (deal.II and DUNE stop reading there).
      const std::size_t begin = text.find("\n$Comments\n"), end = text.find("\n$EndComments\n");
      ASSERT_NE(begin, std::string::npos) << what;
      ASSERT_NE(end, std::string::npos) << what;
      EXPECT_GT(begin, text.rfind("$EndElements")) << what;
      std::map<std::string, std::string> keys;
      std::istringstream lines(text.substr(begin + 11, end - begin - 10));
      for (std::string line; std::getline(lines, line);) {
        ASSERT_NE(line.substr(0, 1), "$") << what << ": a line starting with $ would end the section for Gmsh";
        const std::size_t space = line.find(' ');
        if (space != std::string::npos) keys[line.substr(0, space)] = line.substr(space + 1);
      }
      EXPECT_EQ(keys["crs"], "EPSG:32616") << what;
      EXPECT_EQ(keys["crs_epsg"], "32616") << what;
      EXPECT_EQ(keys["crs_name"], "WGS 84 / UTM zone 16N") << what;
      if (have_gdalsrsinfo) {
        // GDAL's own tool identifies the WKT as the same CRS.
        const fs::path wkt = temp("crs.wkt");
        std::ofstream(wkt) << keys["crs_wkt"];
        int code = 0;
        const std::string epsg = shell_output("gdalsrsinfo -e " + wkt.string(), code);
        EXPECT_EQ(code, 0) << what;
        EXPECT_NE(epsg.find("EPSG:32616"), std::string::npos) << what << ": " << epsg;
        fs::remove(wkt);
      }
      // Our reader skips the section and takes the CRS back.
      const QuadMesh r = read_mesh(p);
      EXPECT_EQ(r.quads, m.quads) << what;
      EXPECT_EQ(r.crs, "EPSG:32616") << what;
      // Gmsh and meshio still read every quad.
      if (have_gmsh) {
        const std::string cmd = "gmsh " + p.string() + " -0 -format msh41 -o " + out.string() + " > /dev/null 2>&1";
        ASSERT_EQ(std::system(cmd.c_str()), 0) << what;
        EXPECT_EQ(compute_quality(read_mesh(out)).quads, m.quads.size()) << what;
      }
      if (have_meshio) {
        int code = 0;
        const std::string n = shell_output("/usr/bin/python3 -c \"import meshio; m=meshio.read('" + p.string() +
                                           "'); print(sum(len(c.data) for c in m.cells if c.type=='quad'))\"", code);
        EXPECT_EQ(code, 0) << what;
        EXPECT_EQ(std::atol(n.c_str()), static_cast<long>(m.quads.size())) << what;
      }
      fs::remove(p);
      fs::remove(out);
    }
  // VTU: the EPSG code as field data (meshio's field_data), the CRS itself in a comment; our reader takes it back.
  const fs::path v = temp("crs.vtu");
  write_mesh(v, m);
  EXPECT_EQ(read_mesh(v).crs, "EPSG:32616");
  if (have_meshio) {
    int code = 0;
    const std::string got = shell_output("/usr/bin/python3 -c \"import meshio; m=meshio.read('" + v.string() +
                                         "'); print(int(m.field_data['crs_epsg'][0]), len(m.points), sum(len(c.data) for c in m.cells if c.type=='quad'))\"",
                                         code);
    EXPECT_EQ(code, 0);
    EXPECT_EQ(got, "32616 " + std::to_string(m.nodes.size()) + " " + std::to_string(m.quads.size()) + "\n");
  }
  // Without a CRS neither file has one.
  m.crs.clear();
  const fs::path plain = temp("plain.msh");
  write_mesh(plain, m);
  write_mesh(v, m);
  std::ifstream pin(plain), vin(v);
  const std::string ptext((std::istreambuf_iterator<char>(pin)), std::istreambuf_iterator<char>());
  const std::string vtext((std::istreambuf_iterator<char>(vin)), std::istreambuf_iterator<char>());
  EXPECT_EQ(ptext.find("$Comments"), std::string::npos);
  EXPECT_EQ(vtext.find("FieldData"), std::string::npos);
  EXPECT_TRUE(read_mesh(v).crs.empty());
  fs::remove(plain);
  fs::remove(v);
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
