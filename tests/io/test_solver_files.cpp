// Solver files (SCHISM .gr3/.ll, D-Flow FM UGRID .nc, SMS .2dm) read back by readers that are not ours and compared
// node for node with the mesh; D-Flow FM's finite-volume figures on meshes whose answer follows from geometry.
//
// The gr3 and 2dm parsers (io/solver_parsers.h) follow the formats' documentation (SCHISM manual, "hgrid.gr3": NE NP, nodes
// "id x y depth", elements "id i34 n1..n4", then NOPE, NETA, per open segment its count and nodes, NBOU, NVEL, per
// land segment "count flag" and nodes; SMS 2dm: cards MESH2D, E4Q id n1..n4 mat, ND id x y z, NS node ids with the
// last one negative), not our writers. UGRID is read by python3-netcdf4.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include "polysquare/core/error.h"
#include "polysquare/input/read_region.h"
#include "polysquare/io/bathymetry.h"
#include "polysquare/io/mesh_io.h"
#include "polysquare/io/solver_files.h"
#include "polysquare/pipeline/mesh_region.h"
#include "polysquare/quality/quality.h"
#include "io/solver_parsers.h"

using namespace polysquare;
using namespace polysquare::test;
namespace fs = std::filesystem;

namespace {

fs::path temp(const std::string& name) { return scratch_file("polysquare_solver_", name); }

struct Case {
  Region region;
  QuadMesh mesh;
};
Case mesh_case(const std::string& name, double size) {
  Case c;
  c.region = read_region(std::string(POLYSQUARE_DATA_DIR) + "/cases/" + name + ".geojson");
  MeshOptions o;
  o.size.h = size;
  c.mesh = mesh_region(c.region, o).mesh;
  return c;
}
const Case& key_case() {  // one outer ring and one hole
  static const Case c = mesh_case("key", 2.0);
  return c;
}
const Case& dam_case() {  // one outer ring, feature curves
  static const Case c = mesh_case("dam_channel", 2.0);
  return c;
}

// Writes `mesh` by the extension of `name` (in the test folder) with a constant depth; returns the path.
fs::path write_with_depth(const std::string& name, const QuadMesh& mesh, double depth) {
  const fs::path p = temp(name);
  MeshWriteOptions o;
  o.depth.assign(mesh.nodes.size(), depth);
  write_mesh(p, mesh, o);
  return p;
}

std::set<Edge> all_edges(const QuadMesh& m) {
  std::set<Edge> out;
  for (const auto& q : m.quads)
    for (int k = 0; k < 4; ++k) out.insert(sorted(q[k], q[(k + 1) % 4]));
  return out;
}
double signed_area(const std::vector<Vec2>& p) {
  double s = 0;
  for (std::size_t i = 0; i < p.size(); ++i) s += cross(p[i], p[(i + 1) % p.size()]);
  return 0.5 * s;
}

void expect_gr3_matches(const Gr3& g, const Case& c, double depth, std::size_t holes) {
  const QuadMesh& m = c.mesh;
  ASSERT_EQ(g.xy.size(), m.nodes.size());
  ASSERT_EQ(g.elements.size(), m.quads.size());
  for (std::size_t i = 0; i < m.nodes.size(); ++i) {
    ASSERT_TRUE(g.xy[i] == m.nodes[i]) << "node " << i + 1;
    ASSERT_EQ(g.depth[i], depth) << "node " << i + 1;
  }
  for (std::size_t q = 0; q < m.quads.size(); ++q) {
    ASSERT_EQ(g.elements[q].size(), 4u) << "element " << q + 1;
    std::vector<Vec2> corners;
    for (int k = 0; k < 4; ++k) {
      ASSERT_EQ(g.elements[q][static_cast<std::size_t>(k)], m.quads[q][static_cast<std::size_t>(k)] + 1) << "element " << q + 1;
      corners.push_back(g.xy[static_cast<std::size_t>(g.elements[q][static_cast<std::size_t>(k)] - 1)]);
    }
    ASSERT_GT(signed_area(corners), 0.0) << "element " << q + 1 << " is not counter-clockwise";
  }
  // No named open segments yet: all land, one segment per ring, islands flagged and clockwise.
  EXPECT_TRUE(g.open.empty());
  EXPECT_EQ(g.neta, 0);
  long listed = 0;
  std::size_t islands = 0;
  std::set<Edge> covered;
  for (std::size_t k = 0; k < g.land.size(); ++k) {
    const auto& seg = g.land[k];
    listed += static_cast<long>(seg.size());
    ASSERT_TRUE(g.land_flag[k] == 0 || g.land_flag[k] == 1);
    // The loop's nodes once each: the outer land boundary is listed closed (its first node repeated at the end),
    // an island closes on itself.
    std::vector<std::int32_t> ring(seg.begin(), seg.end());
    if (g.land_flag[k] == 0) {
      ASSERT_EQ(seg.front(), seg.back()) << "land segment " << k + 1;
      ring.pop_back();
    } else {
      ++islands;
    }
    std::vector<Vec2> pts;
    for (auto v : ring) pts.push_back(g.xy[static_cast<std::size_t>(v - 1)]);
    if (g.land_flag[k] == 1) EXPECT_LT(signed_area(pts), 0.0) << "island " << k + 1 << " is not clockwise";
    else EXPECT_GT(signed_area(pts), 0.0) << "land boundary " << k + 1 << " is not counter-clockwise";
    for (std::size_t i = 0; i < ring.size(); ++i) {
      const Edge e = sorted(ring[i] - 1, ring[(i + 1) % ring.size()] - 1);
      EXPECT_TRUE(covered.insert(e).second) << "edge listed twice in land boundary " << k + 1;
    }
  }
  EXPECT_EQ(g.nvel, listed);
  EXPECT_EQ(islands, holes);
  EXPECT_EQ(g.land.size(), holes + 1);
  EXPECT_EQ(covered, one_quad_edges(m));  // every boundary edge, and nothing else, is on a land boundary
}

// Runs a shell command, returns its stdout (and stderr with `with_stderr`).
std::string output_of(const std::string& cmd, int* code = nullptr, bool with_stderr = false) {
  const fs::path out = temp("cmd.out");
  const int status = std::system((cmd + " > " + out.string() + (with_stderr ? " 2>&1" : "")).c_str());
  if (code) *code = WEXITSTATUS(status);
  std::ifstream in(out);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// `points` transformed by GDAL's own command-line tool gdaltransform (gdal-bin), e.g. from "EPSG:4326".
std::vector<Vec2> gdaltransform(const std::vector<Vec2>& points, const std::string& from, const std::string& to) {
  const fs::path in = temp("gdaltransform.txt");
  {
    std::ofstream os(in);
    os.precision(17);
    for (Vec2 p : points) os << p.x << " " << p.y << "\n";
  }
  int code = 0;
  std::istringstream out(output_of("gdaltransform -s_srs " + from + " -t_srs " + to + " -output_xy < " + in.string(), &code));
  if (code != 0) throw std::runtime_error("gdaltransform (gdal-bin) failed");
  std::vector<Vec2> result(points.size());
  for (Vec2& p : result)
    if (!(out >> p.x >> p.y)) throw std::runtime_error("gdaltransform gave fewer points than it was given");
  return result;
}

// python3-netcdf4 dumps what a UGRID reader needs as JSON (raw values: no masking, no start_index applied).
nlohmann::json read_ugrid_with_netcdf4(const fs::path& nc) {
  const fs::path script = temp("read_ugrid.py");
  std::ofstream(script) << R"(import json, sys
import netCDF4
ds = netCDF4.Dataset(sys.argv[1])
ds.set_auto_mask(False)
out = {"dimensions": {k: len(v) for k, v in ds.dimensions.items()}, "attributes": {}, "data": {}, "format": ds.data_model}
for name, var in ds.variables.items():
    out["attributes"][name] = {a: (var.getncattr(a).item() if hasattr(var.getncattr(a), "item") else var.getncattr(a)) for a in var.ncattrs()}
    out["data"][name] = var[...].tolist()
out["global"] = {a: ds.getncattr(a) for a in ds.ncattrs()}
print(json.dumps(out))
)";
  int code = 0;
  const std::string text = output_of("/usr/bin/python3 " + script.string() + " " + nc.string(), &code);
  if (code != 0) throw std::runtime_error("python3-netcdf4 could not read " + nc.string() + " (run scripts/install-deps)");
  return nlohmann::json::parse(text);
}

}  // namespace

TEST(SolverFiles, BoundaryLoopsFollowTheRingsWithTheDomainOnTheLeft) {
  const QuadMesh& m = key_case().mesh;
  const std::vector<BoundaryLoop> loops = boundary_loops(m);
  ASSERT_EQ(loops.size(), 2u);
  std::set<Edge> covered;
  for (const BoundaryLoop& l : loops) {
    std::vector<Vec2> pts;
    for (auto v : l.nodes) pts.push_back(m.nodes[static_cast<std::size_t>(v)]);
    EXPECT_EQ(signed_area(pts) < 0, l.inner);
    for (std::size_t i = 0; i < l.nodes.size(); ++i) covered.insert(sorted(l.nodes[i], l.nodes[(i + 1) % l.nodes.size()]));
    // Each loop carries the ring index its tagged edges have, and the ring's kind.
    ASSERT_GE(l.ring, 0);
    EXPECT_EQ(key_case().region.rings[static_cast<std::size_t>(l.ring)].hole, l.inner);
  }
  EXPECT_EQ(loops[0].ring, 0);
  EXPECT_EQ(covered, one_quad_edges(m));
}

TEST(SolverFiles, Gr3ReadBackNodeForNodeWithLandBoundariesAndIsland) {
  const Case& c = key_case();
  const fs::path p = write_with_depth("hgrid.gr3", c.mesh, 7.5);
  expect_gr3_matches(parse_gr3(p), c, 7.5, 1);
  EXPECT_FALSE(fs::exists(temp("hgrid.ll"))) << "planar input gets no lon/lat companion";
  // Without a depth the column is 0.
  write_mesh(p, c.mesh);
  expect_gr3_matches(parse_gr3(p), c, 0.0, 1);
}

TEST(SolverFiles, Gr3WithGeographicInputGetsLonLatCompanion) {
  Case c = dam_case();
  c.mesh.crs = "EPSG:32616";
  const fs::path p = temp("geo/hgrid.gr3");
  fs::create_directories(p.parent_path());
  MeshWriteOptions o;
  o.input_crs = "EPSG:4326";
  write_mesh(p, c.mesh, o);
  const fs::path ll = temp("geo/hgrid.ll");
  ASSERT_TRUE(fs::exists(ll));
  const Gr3 g = parse_gr3(p), l = parse_gr3(ll);
  expect_gr3_matches(g, c, 0.0, 0);
  ASSERT_EQ(l.xy.size(), g.xy.size());
  EXPECT_EQ(l.elements, g.elements);
  EXPECT_EQ(l.land, g.land);
  // GDAL's own command-line tool takes the lon/lat back to UTM 16N: the nodes again.
  const std::vector<Vec2> back = gdaltransform(l.xy, "EPSG:4326", "EPSG:32616");
  for (std::size_t i = 0; i < g.xy.size(); ++i) {
    const Vec2 p2 = back[i];
    EXPECT_NEAR(p2.x, g.xy[i].x, 1e-5) << "node " << i + 1;
    EXPECT_NEAR(p2.y, g.xy[i].y, 1e-5) << "node " << i + 1;
    EXPECT_GT(l.xy[i].x, -96.0) << "longitude inside UTM zone 16";
    EXPECT_LT(l.xy[i].x, -84.0);
  }
}

TEST(SolverFiles, TwoDmReadBackNodeForNodeWithNodestrings) {
  const Case& c = key_case();
  const fs::path p = write_with_depth("mesh.2dm", c.mesh, 3.25);
  const Sms s = parse_2dm(p);
  EXPECT_TRUE(s.mesh2d);
  ASSERT_EQ(s.nodes.size(), c.mesh.nodes.size());
  ASSERT_EQ(s.e4q.size(), c.mesh.quads.size());
  for (std::size_t i = 0; i < c.mesh.nodes.size(); ++i) {
    ASSERT_TRUE(s.nodes.at(static_cast<long>(i + 1)) == c.mesh.nodes[i]) << "node " << i + 1;
    ASSERT_EQ(s.z.at(static_cast<long>(i + 1)), 3.25);
  }
  for (std::size_t q = 0; q < c.mesh.quads.size(); ++q)
    for (int k = 0; k < 4; ++k)
      ASSERT_EQ(s.e4q.at(static_cast<long>(q + 1))[static_cast<std::size_t>(k)], c.mesh.quads[q][static_cast<std::size_t>(k)] + 1);
  // One closed nodestring per boundary ring, together covering exactly the boundary edges.
  ASSERT_EQ(s.strings.size(), 2u);
  std::set<Edge> covered;
  for (const auto& ns : s.strings) {
    EXPECT_EQ(ns.front(), ns.back()) << "a ring's nodestring is closed";
    for (std::size_t i = 0; i + 1 < ns.size(); ++i)
      EXPECT_TRUE(covered.insert(sorted(static_cast<std::int32_t>(ns[i] - 1), static_cast<std::int32_t>(ns[i + 1] - 1))).second);
  }
  EXPECT_EQ(covered, one_quad_edges(c.mesh));
  EXPECT_EQ(s.string_names, (std::vector<std::string>{"boundary_ring_0", "boundary_ring_1"}));
}

TEST(SolverFiles, UgridReadBackByNetcdf4NodeForNode) {
  Case c = dam_case();
  c.mesh.crs = "EPSG:32616";
  const fs::path p = write_with_depth("dam_net.nc", c.mesh, 4.0);
  const nlohmann::json j = read_ugrid_with_netcdf4(p);
  const QuadMesh& m = c.mesh;
  EXPECT_EQ(j["format"], "NETCDF3_64BIT_OFFSET");
  EXPECT_EQ(j["dimensions"]["mesh2d_nNodes"], m.nodes.size());
  EXPECT_EQ(j["dimensions"]["mesh2d_nFaces"], m.quads.size());
  EXPECT_EQ(j["dimensions"]["mesh2d_nMax_face_nodes"], 4);
  const std::set<Edge> edges = all_edges(m);
  EXPECT_EQ(j["dimensions"]["mesh2d_nEdges"], edges.size());
  const auto& topo = j["attributes"]["mesh2d"];
  EXPECT_EQ(topo["cf_role"], "mesh_topology");
  EXPECT_EQ(topo["topology_dimension"], 2);
  EXPECT_EQ(topo["node_coordinates"], "mesh2d_node_x mesh2d_node_y");
  EXPECT_EQ(topo["face_node_connectivity"], "mesh2d_face_nodes");
  EXPECT_EQ(topo["edge_node_connectivity"], "mesh2d_edge_nodes");
  EXPECT_EQ(topo["face_coordinates"], "mesh2d_face_x mesh2d_face_y");
  EXPECT_EQ(topo["edge_coordinates"], "mesh2d_edge_x mesh2d_edge_y");
  const auto& crs = j["attributes"]["projected_coordinate_system"];
  EXPECT_EQ(crs["epsg"], 32616);
  EXPECT_EQ(crs["EPSG_code"], "EPSG:32616");
  EXPECT_FALSE(j["attributes"].contains("wgs84"));
  // Nodes, faces and edges node for node.
  const auto& x = j["data"]["mesh2d_node_x"];
  const auto& y = j["data"]["mesh2d_node_y"];
  const auto& z = j["data"]["mesh2d_node_z"];
  ASSERT_EQ(x.size(), m.nodes.size());
  for (std::size_t i = 0; i < m.nodes.size(); ++i) {
    ASSERT_EQ(x[i].get<double>(), m.nodes[i].x);
    ASSERT_EQ(y[i].get<double>(), m.nodes[i].y);
    ASSERT_EQ(z[i].get<double>(), -4.0) << "bed level is minus the depth";
  }
  EXPECT_EQ(j["attributes"]["mesh2d_node_z"]["standard_name"], "altitude");
  const auto& fn_att = j["attributes"]["mesh2d_face_nodes"];
  EXPECT_EQ(fn_att["cf_role"], "face_node_connectivity");
  EXPECT_EQ(fn_att["_FillValue"], -999);
  const int start = fn_att["start_index"].get<int>();
  EXPECT_EQ(start, 1);
  const auto& fn = j["data"]["mesh2d_face_nodes"];
  ASSERT_EQ(fn.size(), m.quads.size());
  for (std::size_t q = 0; q < m.quads.size(); ++q) {
    std::vector<Vec2> corners;
    for (int k = 0; k < 4; ++k) {
      const int v = fn[q][static_cast<std::size_t>(k)].get<int>() - start;
      ASSERT_EQ(v, m.quads[q][static_cast<std::size_t>(k)]) << "face " << q;
      corners.push_back({x[static_cast<std::size_t>(v)].get<double>(), y[static_cast<std::size_t>(v)].get<double>()});
    }
    ASSERT_GT(signed_area(corners), 0.0) << "face " << q << " is not counter-clockwise";
  }
  const int edge_start = j["attributes"]["mesh2d_edge_nodes"]["start_index"].get<int>();
  std::set<Edge> read_edges;
  for (const auto& e : j["data"]["mesh2d_edge_nodes"])
    EXPECT_TRUE(read_edges.insert(sorted(e[0].get<int>() - edge_start, e[1].get<int>() - edge_start)).second);
  EXPECT_EQ(read_edges, edges);
  EXPECT_NE(j["global"]["Conventions"].get<std::string>().find("UGRID-1.0"), std::string::npos);
}

TEST(SolverFiles, UgridWithoutDepthOrCrs) {
  const Case& c = key_case();  // planar: no CRS
  const fs::path p = temp("key_net.nc");
  write_mesh(p, c.mesh);
  const nlohmann::json j = read_ugrid_with_netcdf4(p);
  EXPECT_FALSE(j["data"].contains("mesh2d_node_z"));
  EXPECT_EQ(j["attributes"]["projected_coordinate_system"]["epsg"], 0);
}

TEST(SolverFiles, OutputPathCheckedBeforeMeshing) {
  EXPECT_NO_THROW(check_output_path(temp("ok.gr3")));
  EXPECT_NO_THROW(check_output_path(temp("ok_net.nc")));
  EXPECT_NO_THROW(check_output_path(temp("OK.2DM")));
  EXPECT_THROW(check_output_path(temp("mesh.foo")), InputError);
  EXPECT_THROW(check_output_path(temp("no_such_dir/mesh.nc")), InputError);
  EXPECT_THROW(check_output_path(temp("mesh")), InputError);  // no extension
  const fs::path ro = temp("read_only");
  fs::create_directories(ro);
  fs::permissions(ro, fs::perms::owner_read | fs::perms::owner_exec);
  if (::geteuid() != 0) EXPECT_THROW(check_output_path(ro / "mesh.gr3"), InputError);  // root writes anyway
  fs::permissions(ro, fs::perms::owner_all);
  // The CLI refuses at once, with one error line and exit code 2, before reading the input.
  int code = 0;
  const std::string err = output_of(std::string(POLYSQUARE_CLI) + " mesh " + POLYSQUARE_DATA_DIR +
                                    "/cases/delta_box.geojson --size 200 -o " + temp("no_such_dir/x.nc").string(),
                                    &code, true);
  EXPECT_EQ(code, 2);
  EXPECT_EQ(err.rfind("error: ", 0), 0u) << err;
  EXPECT_NE(err.find("does not exist"), std::string::npos) << err;
  // So is a bathymetry raster that is not there, and --depth beside --bathymetry.
  const std::string mesh_cmd = std::string(POLYSQUARE_CLI) + " mesh " + POLYSQUARE_DATA_DIR +
                               "/cases/delta_box.geojson --size 200 -o " + temp("x.gr3").string();
  output_of(mesh_cmd + " --bathymetry " + temp("no_raster.tif").string(), &code, true);
  EXPECT_EQ(code, 2);
  output_of(mesh_cmd + " --depth 3 --bathymetry " + temp("no_raster.tif").string(), &code, true);
  EXPECT_EQ(code, 2);
  EXPECT_FALSE(fs::exists(temp("x.gr3")));
}

// Issue 52: the boundary polylines of a net file, named after their segments, are known before meshing; two open
// segments whose names give one file (file_safe maps them alike, or they differ in letter case only) are refused
// naming both, and the companions of each format are listed for the CLI's check.
TEST(SolverFiles, PliFilesAreNamedBeforeMeshingAndNamesThatGiveOneFileAreRefused) {
  const std::vector<PliFile> files = pli_files("d/m.nc", {"north sea", "Elbe-river", "segment_2"});
  ASSERT_EQ(files.size(), 3u);
  EXPECT_EQ(files[0].path, std::filesystem::path("d/m_north_sea.pli"));
  EXPECT_EQ(files[1].path, std::filesystem::path("d/m_Elbe-river.pli"));
  EXPECT_EQ(files[1].segment, "Elbe-river");
  const std::vector<std::pair<std::string, std::string>> alike{
      {"north sea", "north/sea"}, {"Elbe (Nord)", "Elbe [Nord]"}, {"Ocean", "ocean"}, {"S\u00fcd", "S\u00f8d"},
      {"segment 1", "segment_1"}};
  for (const auto& [a, b] : alike) {
    try {
      pli_files("m.nc", {"other", a, b});
      ADD_FAILURE() << a << " and " << b << " were not refused";
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("\"" + a + "\" and \"" + b + "\""), std::string::npos) << what;
    }
  }
  EXPECT_TRUE(companion_files("m.msh", "EPSG:4326", {"a"}).empty());
  EXPECT_TRUE(companion_files("m.gr3", "EPSG:32632", {"a"}).empty());  // projected input: no .ll
  ASSERT_EQ(companion_files("m.gr3", "EPSG:4326", {}).size(), 1u);
  EXPECT_EQ(companion_files("m.gr3", "EPSG:4326", {})[0].path, std::filesystem::path("m.ll"));
  ASSERT_EQ(companion_files("m.nc", "", {"a", "b"}).size(), 2u);
  EXPECT_THROW(companion_files("m.nc", "", {"a b", "a/b"}), InputError);
}

TEST(SolverFiles, CliWritesNetFileWithDepthAndReportsFiniteVolumeQuality) {
  const fs::path nc = temp("cli_net.nc"), report = temp("cli_report.json");
  int code = 0;
  const std::string out = output_of(std::string(POLYSQUARE_CLI) + " mesh " + POLYSQUARE_DATA_DIR +
                                    "/cases/letter_M.geojson --size 2 --depth 12 -o " + nc.string() + " --report " +
                                    report.string(), &code);
  ASSERT_EQ(code, 0);
  EXPECT_NE(out.find("orthogonality"), std::string::npos) << out;
  const nlohmann::json j = read_ugrid_with_netcdf4(nc);
  for (const auto& z : j["data"]["mesh2d_node_z"]) EXPECT_EQ(z.get<double>(), -12.0);
  std::ifstream in(report);
  const nlohmann::json r = nlohmann::json::parse(in);
  const auto& fv = r["quality"]["finite_volume"];
  EXPECT_GT(fv["interior_edges"].get<int>(), 0);
  EXPECT_LE(fv["orthogonality"]["max"].get<double>(), 1.0);
  EXPECT_GE(fv["smoothness"]["min"].get<double>(), 1.0);
  // The quality command reads a mesh file and gives the same figures.
  const fs::path msh = temp("cli.msh");
  ASSERT_EQ(std::system((std::string(POLYSQUARE_CLI) + " mesh " + POLYSQUARE_DATA_DIR + "/cases/letter_M.geojson --size 2 -o " +
                         msh.string() + " > /dev/null").c_str()), 0);
  const nlohmann::json q = nlohmann::json::parse(output_of(std::string(POLYSQUARE_CLI) + " quality --json " + msh.string()));
  EXPECT_EQ(q["finite_volume"]["interior_edges"], fv["interior_edges"]);
  EXPECT_NEAR(q["finite_volume"]["orthogonality"]["max"].get<double>(), fv["orthogonality"]["max"].get<double>(), 1e-9);
}

// ---- D-Flow FM finite-volume figures on lattices whose answer is known ----
namespace {
// nx by ny cells with corner (i, j) at i * a + j * b (+ column widths for `widths`).
QuadMesh lattice(int nx, int ny, Vec2 a, Vec2 b, const std::vector<double>& widths = {}) {
  QuadMesh m;
  std::vector<double> xs{0};
  for (int i = 0; i < nx; ++i) xs.push_back(xs.back() + (widths.empty() ? 1.0 : widths[static_cast<std::size_t>(i)]));
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) m.nodes.push_back(xs[static_cast<std::size_t>(i)] * a + static_cast<double>(j) * b);
  auto id = [&](int i, int j) { return static_cast<std::int32_t>(j * (nx + 1) + i); };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) m.quads.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
  return m;
}
}  // namespace

TEST(FiniteVolumeQuality, SquaresAreOrthogonalAndSmooth) {
  const FiniteVolumeQuality q = finite_volume_quality(lattice(6, 5, {1, 0}, {0, 1}));
  EXPECT_EQ(q.interior_edges, static_cast<std::size_t>(5 * 5 + 6 * 4));
  EXPECT_LT(q.orthogonality.max, 1e-12);
  EXPECT_EQ(q.orthogonality_above, 0u);
  EXPECT_NEAR(q.smoothness.max, 1.0, 1e-12);
}

TEST(FiniteVolumeQuality, ParallelogramsGiveTheCosineOfTheirAngle) {
  // Sheared cells: between two cells away from the boundary the centres (by symmetry, the cells' centres) are one
  // step `a` apart across a side along `b`, so the orthogonality there is |cos| of the angle between a and b.
  const double angle = 50.0 * std::numbers::pi / 180.0;
  const Vec2 a{1, 0}, b{std::cos(angle), std::sin(angle)};
  const QuadMesh m = lattice(7, 7, a, b);
  const EdgeTable edges = edge_table(m);
  const std::vector<Vec2> centres = face_circumcentres(m, edges);
  // Cell (3, 3) and its centre.
  const std::size_t cell = 3 * 7 + 3;
  const Vec2 expected = 3.5 * a + 3.5 * b;
  EXPECT_NEAR(centres[cell].x, expected.x, 1e-9);
  EXPECT_NEAR(centres[cell].y, expected.y, 1e-9);
  const std::vector<double> ortho = edge_orthogonality(m, edges, centres);
  bool found = false;
  for (std::size_t e = 0; e < edges.nodes.size(); ++e) {
    const auto f = edges.faces[e];
    if ((f[0] == static_cast<std::int32_t>(cell) && f[1] == static_cast<std::int32_t>(cell + 1)) ||
        (f[1] == static_cast<std::int32_t>(cell) && f[0] == static_cast<std::int32_t>(cell + 1))) {
      EXPECT_NEAR(ortho[e], std::abs(std::cos(angle)), 1e-9);
      found = true;
    }
  }
  EXPECT_TRUE(found);
  const FiniteVolumeQuality q = finite_volume_quality(m);
  EXPECT_GE(q.orthogonality.max, std::abs(std::cos(angle)) - 1e-9);
  EXPECT_GT(q.orthogonality_above, 0u);  // cos 50 degrees = 0.64 > 0.5
}

TEST(FiniteVolumeQuality, SmoothnessIsTheAreaRatioOfNeighbours) {
  const FiniteVolumeQuality q = finite_volume_quality(lattice(4, 3, {1, 0}, {0, 1}, {1, 1, 3, 3}));
  EXPECT_NEAR(q.smoothness.max, 3.0, 1e-12);
  EXPECT_NEAR(q.smoothness_worst_at.x, 2.0, 1e-12);  // on the line between the widths 1 and 3
  EXPECT_LT(q.orthogonality.max, 1e-12);            // rectangles stay orthogonal
}

TEST(FiniteVolumeQuality, TrianglesUseTheirCircumcentre) {
  // Two equilateral triangles sharing an edge: the circumcentres' link is perpendicular to it.
  QuadMesh m;
  m.nodes = {{0, 0}, {1, 0}, {0.5, std::sqrt(3.0) / 2}, {0.5, -std::sqrt(3.0) / 2}};
  m.triangles = {{0, 1, 2}, {1, 0, 3}};
  const FiniteVolumeQuality q = finite_volume_quality(m);
  EXPECT_EQ(q.interior_edges, 1u);
  EXPECT_LT(q.orthogonality.max, 1e-12);
  const EdgeTable edges = edge_table(m);
  const std::vector<Vec2> c = face_circumcentres(m, edges);
  EXPECT_NEAR(c[0].y, std::sqrt(3.0) / 6, 1e-12);
}

// ---- Bathymetry rasters ----
namespace {
// A raster of z = a x + b y + c sampled at the cell centres, covering `box` with two cells to spare on every side:
// written as an ESRI ASCII grid, made a Float64 GeoTIFF (in `srs` when given) by GDAL's gdal_translate.
fs::path linear_grid(const std::string& name, Box2 box, double cell, double a, double b, double c, bool hole = false,
                     const std::string& srs = "") {
  const fs::path p = temp(name + ".asc"), tif = temp(name + ".tif");
  const double x0 = box.lo.x - 2 * cell, y0 = box.lo.y - 2 * cell;
  const int nx = static_cast<int>(std::ceil((box.hi.x - x0) / cell)) + 2;
  const int ny = static_cast<int>(std::ceil((box.hi.y - y0) / cell)) + 2;
  std::ofstream os(p);
  os.precision(17);
  os << "ncols " << nx << "\nnrows " << ny << "\nxllcorner " << x0 << "\nyllcorner " << y0 << "\ncellsize " << cell
     << "\nNODATA_value -9999\n";
  for (int j = 0; j < ny; ++j) {  // rows from the top
    for (int i = 0; i < nx; ++i) {
      const double x = x0 + (i + 0.5) * cell, y = y0 + (ny - j - 0.5) * cell;
      os << ((hole && i == nx / 2 && j == ny / 2) ? -9999.0 : a * x + b * y + c) << " ";
    }
    os << "\n";
  }
  os.close();
  const std::string cmd = "gdal_translate -q -oo DATATYPE=Float64 -ot Float64 " + (srs.empty() ? "" : "-a_srs " + srs + " ") +
                          p.string() + " " + tif.string();
  if (std::system(cmd.c_str()) != 0) throw std::runtime_error("gdal_translate failed: " + cmd);
  return tif;
}
Box2 box_of(const std::vector<Vec2>& pts) {
  Box2 b;
  for (Vec2 p : pts) b.add(p);
  return b;
}
}  // namespace

TEST(Bathymetry, BilinearReproducesALinearSurfaceAtEveryNode) {
  const QuadMesh& m = key_case().mesh;
  const fs::path grid = linear_grid("linear", box_of(m.nodes), 0.7, 0.5, -0.25, -3.0);
  const std::vector<double> up = sample_bathymetry(grid, m.nodes, "");
  const std::vector<double> down = sample_bathymetry(grid, m.nodes, "", {true});
  ASSERT_EQ(up.size(), m.nodes.size());
  for (std::size_t i = 0; i < m.nodes.size(); ++i) {
    const double z = 0.5 * m.nodes[i].x - 0.25 * m.nodes[i].y - 3.0;
    EXPECT_NEAR(up[i], -z, 1e-9) << "node " << i + 1;  // elevations: depth = -z
    EXPECT_NEAR(down[i], z, 1e-9) << "node " << i + 1;
  }
  // A no-data cell is left out, not read as a depth of 9999.
  const fs::path holed = linear_grid("holed", box_of(m.nodes), 0.7, 0.5, -0.25, -3.0, true);
  for (double d : sample_bathymetry(holed, m.nodes, "")) EXPECT_LT(std::abs(d), 100.0);
  // Nodes outside the raster are an error naming the node.
  Box2 small = box_of(m.nodes);
  small.hi.x = 0.5 * (small.lo.x + small.hi.x);
  const fs::path half = linear_grid("half", small, 0.7, 0.5, -0.25, -3.0);
  EXPECT_THROW(sample_bathymetry(half, m.nodes, ""), InputError);
  EXPECT_THROW(sample_bathymetry(temp("missing.tif"), m.nodes, ""), InputError);
}

TEST(Bathymetry, NodesAreTransformedIntoTheRastersCrs) {
  // The mesh in UTM 16N, the raster in lon/lat (GeoTIFF made by gdal_translate): a surface linear in lon/lat is
  // reproduced at the nodes' lon/lat as GDAL's own gdaltransform computes them.
  QuadMesh m = dam_case().mesh;
  for (Vec2& p : m.nodes) p = p + Vec2{400000.0, 3200000.0};
  const std::vector<Vec2> lonlat = gdaltransform(m.nodes, "EPSG:32616", "EPSG:4326");
  const fs::path tif = linear_grid("lonlat", box_of(lonlat), 1e-4, 2000.0, -1000.0, 5.0, false, "EPSG:4326");
  const std::vector<double> d = sample_bathymetry(tif, m.nodes, "EPSG:32616", {true});
  for (std::size_t i = 0; i < m.nodes.size(); ++i)
    EXPECT_NEAR(d[i], 2000.0 * lonlat[i].x - 1000.0 * lonlat[i].y + 5.0, 1e-6) << "node " << i + 1;
}
