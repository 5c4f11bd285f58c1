// Named boundary segments (role "boundary" lines, --boundary files) and input names, through every writer:
// SCHISM gr3 open/land boundaries and SMS 2dm nodestrings read by the parsers written from the formats'
// documentation (io/solver_parsers.h), MSH physical groups and Exodus II read by python3-meshio (not our readers).
#include <gtest/gtest.h>

#include <cairo/cairo.h>
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

#include "io/solver_parsers.h"
#include "polysquare/core/error.h"
#include "polysquare/input/boundary_segments.h"
#include "polysquare/input/read_region.h"
#include "polysquare/io/mesh_groups.h"
#include "polysquare/io/mesh_io.h"
#include "polysquare/io/solver_files.h"
#include "polysquare/pipeline/mesh_region.h"

using namespace polysquare;
using namespace polysquare::test;
namespace fs = std::filesystem;

namespace {

fs::path temp(const std::string& name) { return scratch_file("polysquare_segments_", name); }

std::string output_of(const std::string& cmd, int* code = nullptr, bool with_stderr = false) {
  const fs::path out = temp("cmd.out");
  const int status = std::system((cmd + " > " + out.string() + (with_stderr ? " 2>&1" : "")).c_str());
  if (code) *code = WEXITSTATUS(status);
  std::ifstream in(out);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}


struct Meshed {
  MeshResult result;
  MeshGroups groups;
};
Meshed mesh_file(const fs::path& path, double size) {
  Meshed m;
  const Region region = read_region(path);
  MeshOptions o;
  o.size.h = size;
  m.result = mesh_region(region, o);
  m.groups = mesh_groups(m.result.mesh, &m.result.region);
  return m;
}
const Meshed& dam_open() {
  static const Meshed m = mesh_file(std::string(POLYSQUARE_DATA_DIR) + "/cases/dam_channel_open.geojson", 2.0);
  return m;
}

MeshWriteOptions with_groups(const MeshGroups& g) {
  MeshWriteOptions o;
  o.groups = g;
  return o;
}

const CurveGroup* find_group(const std::vector<CurveGroup>& groups, const std::string& name) {
  for (const CurveGroup& g : groups)
    if (g.name == name) return &g;
  return nullptr;
}

fs::path write_text(const std::string& name, const std::string& text) {
  const fs::path p = temp(name);
  std::ofstream(p) << text;
  return p;
}

// A 100 x 60 lake with a 20 x 20 island; `extra` features are appended to the collection.
std::string lake(const std::string& extra) {
  return R"({"type": "FeatureCollection", "features": [
{"type": "Feature", "properties": {"role": "domain", "name": "lake"}, "geometry": {"type": "Polygon", "coordinates":
 [[[0, 0], [100, 0], [100, 60], [0, 60], [0, 0]], [[40, 20], [40, 40], [60, 40], [60, 20], [40, 20]]]}})" +
         extra + "]}";
}

// python3-meshio reads `path`; the script prints JSON.
nlohmann::json meshio_json(const fs::path& path, const std::string& body) {
  const fs::path script = temp("read_meshio.py");
  std::ofstream(script) << "import json, sys\nimport meshio\nm = meshio.read(sys.argv[1])\n" << body;
  int code = 0;
  const std::string text = output_of("/usr/bin/python3 " + script.string() + " " + path.string(), &code, false);
  if (code != 0) throw std::runtime_error("python3-meshio could not read " + path.string() + " (run scripts/install-deps)");
  return nlohmann::json::parse(text);
}

}  // namespace

TEST(BoundarySegments, ReadingPlacesTheLinesOnTheRingInRingOrder) {
  const Region r = read_region(std::string(POLYSQUARE_DATA_DIR) + "/cases/dam_channel_open.geojson");
  ASSERT_EQ(r.boundary_segments.size(), 2u);
  EXPECT_EQ(r.rings[0].name, "channel");
  ASSERT_EQ(r.features.size(), 2u);
  EXPECT_EQ(r.features[0].name, "dam_lower");
  const BoundarySegment& in = r.boundary_segments[0];
  EXPECT_EQ(in.name, "inflow");
  EXPECT_EQ(in.kind, "open");
  EXPECT_EQ(in.ring, 0);
  // The outer ring runs counter-clockwise, so the bottom edge goes from (0, 0) to (80, 0) whatever the line says;
  // the top line was given from (80, 200) to (0, 200), which is ring order.
  EXPECT_TRUE(in.start == (Vec2{0, 0}) && in.end == (Vec2{80, 0}));
  const BoundarySegment& out = r.boundary_segments[1];
  EXPECT_TRUE(out.start == (Vec2{80, 200}) && out.end == (Vec2{0, 200}));
  EXPECT_EQ(segment_ring_vertices(r, in).size(), 2u);
}

TEST(BoundarySegments, LineGivenAgainstTheRingIsTurnedAndEndsInsideEdgesAreInserted) {
  const fs::path p = write_text("lake_reversed.geojson", lake(R"(,
{"type": "Feature", "properties": {"role": "boundary", "name": "river", "kind": "open"}, "geometry": {"type": "LineString", "coordinates": [[100, 47], [100, 13]]}})"));
  const Region r = read_region(p);
  ASSERT_EQ(r.boundary_segments.size(), 1u);
  const BoundarySegment& b = r.boundary_segments[0];
  EXPECT_TRUE(b.start == (Vec2{100, 13}) && b.end == (Vec2{100, 47})) << "counter-clockwise: up the right side";
  const auto verts = segment_ring_vertices(r, b);
  ASSERT_EQ(verts.size(), 2u);
  EXPECT_TRUE(r.rings[0].points[verts[0]] == (Vec2{100, 13}));
  // Both end points are feature points, so the mesher keeps them as nodes.
  EXPECT_NE(std::find(r.feature_points.begin(), r.feature_points.end(), Vec2{100, 13}), r.feature_points.end());
  EXPECT_NE(std::find(r.feature_points.begin(), r.feature_points.end(), Vec2{100, 47}), r.feature_points.end());
}

TEST(BoundarySegments, LineNotOnTheBoundaryIsAnErrorNamingFileFeatureAndPoint) {
  auto message = [](const std::string& name, const std::string& extra) {
    const fs::path p = write_text(name, lake(extra));
    try {
      read_region(p);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string off = message("off.geojson", R"(,
{"type": "Feature", "properties": {"role": "boundary"}, "geometry": {"type": "LineString", "coordinates": [[100, 13], [101, 47]]}})");
  EXPECT_NE(off.find("off.geojson"), std::string::npos) << off;
  EXPECT_NE(off.find("feature 1"), std::string::npos) << off;
  EXPECT_NE(off.find("(101, 47)"), std::string::npos) << off;
  const std::string inside = message("inside.geojson", R"(,
{"type": "Feature", "properties": {"role": "boundary"}, "geometry": {"type": "LineString", "coordinates": [[10, 10], [20, 10]]}})");
  EXPECT_NE(inside.find("inside the domain"), std::string::npos) << inside;
  // A chord between two boundary points is not on the boundary: its middle is checked too.
  const std::string chord = message("chord.geojson", R"(,
{"type": "Feature", "properties": {"role": "boundary"}, "geometry": {"type": "LineString", "coordinates": [[0, 0], [100, 60]]}})");
  EXPECT_NE(chord.find("not on the domain boundary"), std::string::npos) << chord;
  const std::string overlap = message("overlap.geojson", R"(,
{"type": "Feature", "properties": {"role": "boundary"}, "geometry": {"type": "LineString", "coordinates": [[100, 10], [100, 30]]}},
{"type": "Feature", "properties": {"role": "boundary"}, "geometry": {"type": "LineString", "coordinates": [[100, 20], [100, 50]]}})");
  EXPECT_NE(overlap.find("overlaps boundary line 0"), std::string::npos) << overlap;
  // A feature curve wholly outside the domain is an error; one partly outside is clipped with a warning.
  const std::string away = message("away.geojson", R"(,
{"type": "Feature", "properties": {"role": "feature"}, "geometry": {"type": "LineString", "coordinates": [[200, 10], [220, 10]]}})");
  EXPECT_NE(away.find("outside the domain, at (210, 10)"), std::string::npos) << away;
  InputNotes notes;
  const Region partly = read_input(write_text("partly.geojson", lake(R"(,
{"type": "Feature", "properties": {"role": "feature"}, "geometry": {"type": "LineString", "coordinates": [[10, 10], [20, 10], [20, 70]]}})")), {}, notes);
  EXPECT_EQ(partly.features.size(), 1u);
  ASSERT_EQ(notes.warnings.size(), 1u);
  EXPECT_NE(notes.warnings[0].find("feature 1"), std::string::npos) << notes.warnings[0];
  EXPECT_NE(notes.warnings[0].find("outside the domain"), std::string::npos) << notes.warnings[0];
}

TEST(BoundarySegments, DamChannelOpenGr3HasTwoOpenBoundariesAndTheLandBetween) {
  const Meshed& m = dam_open();
  const QuadMesh& mesh = m.result.mesh;
  const fs::path p = temp("hgrid.gr3");
  write_mesh(p, mesh, with_groups(m.groups));
  const Gr3 g = parse_gr3(p);
  ASSERT_EQ(g.open.size(), 2u);
  ASSERT_EQ(g.land.size(), 2u);
  auto xy = [&](std::int32_t id) { return g.xy[static_cast<std::size_t>(id - 1)]; };
  // Open boundary 1 is the bottom end (y = 0) from corner to corner, open boundary 2 the top end (y = 200).
  for (int k = 0; k < 2; ++k) {
    const double y = k == 0 ? 0.0 : 200.0;
    for (auto v : g.open[static_cast<std::size_t>(k)]) EXPECT_EQ(xy(v).y, y) << "open boundary " << k + 1;
    EXPECT_EQ(std::abs(xy(g.open[static_cast<std::size_t>(k)].front()).x - xy(g.open[static_cast<std::size_t>(k)].back()).x), 80.0);
  }
  long open_nodes = 0, land_nodes = 0;
  for (const auto& o : g.open) open_nodes += static_cast<long>(o.size());
  for (const auto& l : g.land) land_nodes += static_cast<long>(l.size());
  EXPECT_EQ(g.neta, open_nodes);
  EXPECT_EQ(g.nvel, land_nodes);
  // Land boundaries: the two side walls, not islands, each running from the end of one open boundary to the
  // start of the other (SCHISM's land boundaries share their end nodes with the open ones).
  std::set<std::int32_t> open_ends{g.open[0].front(), g.open[0].back(), g.open[1].front(), g.open[1].back()};
  for (std::size_t k = 0; k < 2; ++k) {
    EXPECT_EQ(g.land_flag[k], 0);
    const double x = xy(g.land[k][1]).x;
    EXPECT_TRUE(x == 0.0 || x == 80.0);
    for (auto v : g.land[k]) EXPECT_EQ(xy(v).x, x) << "land boundary " << k + 1 << " leaves its wall";
    EXPECT_TRUE(open_ends.count(g.land[k].front()) && open_ends.count(g.land[k].back()));
  }
  // Open and land boundaries together hold every boundary edge exactly once.
  std::set<Edge> covered;
  for (const auto* list : {&g.open, &g.land})
    for (const auto& chain : *list)
      for (std::size_t i = 0; i + 1 < chain.size(); ++i)
        EXPECT_TRUE(covered.insert(sorted(chain[i] - 1, chain[i + 1] - 1)).second);
  EXPECT_EQ(covered, one_quad_edges(mesh));
}

TEST(BoundarySegments, DamChannelOpenMshGroupsAndTwoDmNodestringsCarryTheNames) {
  const Meshed& m = dam_open();
  const QuadMesh& mesh = m.result.mesh;
  for (const char* version : {"2.2", "4.1"}) {
    const fs::path p = temp(std::string("named_") + version + ".msh");
    MeshWriteOptions o = with_groups(m.groups);
    o.msh_version = std::string(version) == "4.1" ? MshVersion::v4_1 : MshVersion::v2_2;
    write_mesh(p, mesh, o);
    // meshio: field_data is name -> [tag, dimension]; per cell block its physical tags and its size.
    const nlohmann::json j = meshio_json(p, R"(
out = {"groups": {k: [int(v[0]), int(v[1])] for k, v in m.field_data.items()}, "blocks": []}
for block, tags in zip(m.cells, m.cell_data["gmsh:physical"]):
    for t in sorted(set(int(x) for x in tags)):
        nodes = sorted(set(int(n) for row, tag in zip(block.data, tags) if int(tag) == t for n in row))
        out["blocks"].append({"type": block.type, "tag": t, "count": int(sum(1 for x in tags if int(x) == t)), "ys": sorted(set(float(m.points[n][1]) for n in nodes))})
print(json.dumps(out))
)");
    const auto& groups = j["groups"];
    EXPECT_EQ(groups["channel"], nlohmann::json({1, 2})) << version;
    EXPECT_EQ(groups["boundary_ring_0"], nlohmann::json({2, 1})) << version;
    EXPECT_EQ(groups["dam_lower"], nlohmann::json({3, 0})) << version;
    EXPECT_EQ(groups["dam_upper"], nlohmann::json({4, 0})) << version;
    EXPECT_EQ(groups["inflow"], nlohmann::json({5, 1})) << version;
    EXPECT_EQ(groups["outflow"], nlohmann::json({6, 1})) << version;
    std::map<int, nlohmann::json> by_tag;
    for (const auto& b : j["blocks"]) {
      const int t = b["tag"].get<int>();
      if (by_tag.count(t)) by_tag[t]["count"] = by_tag[t]["count"].get<int>() + b["count"].get<int>();
      else by_tag[t] = b;
    }
    EXPECT_EQ(by_tag[1]["count"], mesh.quads.size());
    EXPECT_EQ(by_tag[5]["count"], 40) << "80 m of inflow at h = 2";
    EXPECT_EQ(by_tag[5]["ys"], nlohmann::json({0.0}));
    EXPECT_EQ(by_tag[6]["ys"], nlohmann::json({200.0}));
    EXPECT_EQ(by_tag[2]["count"], 200) << "the two 200 m side walls";
  }
  // 2dm: one nodestring per boundary piece, side walls first (the rest of ring 0), then inflow and outflow, in
  // the order of the report's groups; the open ones are the gr3's open boundaries node for node.
  const fs::path p2 = temp("named.2dm"), pg = temp("named.gr3");
  write_mesh(p2, mesh, with_groups(m.groups));
  write_mesh(pg, mesh, with_groups(m.groups));
  const Sms s = parse_2dm(p2);
  const Gr3 g = parse_gr3(pg);
  ASSERT_EQ(s.strings.size(), 4u);
  ASSERT_EQ(g.open.size(), 2u);
  for (std::size_t k = 0; k < 2; ++k) {
    const auto& ns = s.strings[2 + k];
    ASSERT_EQ(ns.size(), g.open[k].size());
    for (std::size_t i = 0; i < ns.size(); ++i) EXPECT_EQ(ns[i], g.open[k][i]);
  }
  for (std::size_t k = 0; k < 2; ++k) EXPECT_EQ(s.strings[k].size(), 101u) << "a 200 m wall at h = 2";
  // Each nodestring carries its group's name after its last node.
  EXPECT_EQ(s.string_names, (std::vector<std::string>{"boundary_ring_0", "boundary_ring_0", "inflow", "outflow"}));
  // The groups themselves: names from the input, tags in the documented order.
  ASSERT_EQ(m.groups.surfaces.size(), 1u);
  EXPECT_EQ(m.groups.surfaces[0].name, "channel");
  ASSERT_NE(find_group(m.groups.segments, "inflow"), nullptr);
  EXPECT_EQ(find_group(m.groups.segments, "inflow")->kind, "open");
  EXPECT_TRUE(m.groups.warnings.empty());
}

TEST(BoundarySegments, EndsInsideEdgesAndOnAnIslandAreMeshNodes) {
  const fs::path p = write_text("lake_segments.geojson", lake(R"(,
{"type": "Feature", "properties": {"role": "boundary", "name": "river", "kind": "open"}, "geometry": {"type": "LineString", "coordinates": [[100, 13], [100, 47]]}},
{"type": "Feature", "properties": {"role": "boundary", "name": "pier", "kind": "wall"}, "geometry": {"type": "LineString", "coordinates": [[40, 30], [40, 20], [50, 20]]}})"));
  const Meshed m = mesh_file(p, 2.0);
  const QuadMesh& mesh = m.result.mesh;
  EXPECT_TRUE(m.groups.warnings.empty()) << m.groups.warnings.front();
  for (Vec2 end : {Vec2{100, 13}, Vec2{100, 47}, Vec2{40, 30}, Vec2{50, 20}})
    EXPECT_NE(std::find(mesh.nodes.begin(), mesh.nodes.end(), end), mesh.nodes.end()) << end.x << " " << end.y;
  const CurveGroup* river = find_group(m.groups.segments, "river");
  const CurveGroup* pier = find_group(m.groups.segments, "pier");
  ASSERT_TRUE(river && pier);
  double river_length = 0, pier_length = 0;
  for (const auto& e : river->edges) {
    EXPECT_EQ(mesh.nodes[static_cast<std::size_t>(e[0])].x, 100.0);
    river_length += distance(mesh.nodes[static_cast<std::size_t>(e[0])], mesh.nodes[static_cast<std::size_t>(e[1])]);
  }
  for (const auto& e : pier->edges) pier_length += distance(mesh.nodes[static_cast<std::size_t>(e[0])], mesh.nodes[static_cast<std::size_t>(e[1])]);
  EXPECT_NEAR(river_length, 34.0, 1e-9);
  EXPECT_NEAR(pier_length, 20.0, 1e-9) << "the arc the line covers, not the other way round the island";
  // gr3: the river is the one open boundary; the island with a segment on it is no longer one closed island but
  // two land boundaries (the pier and the rest of its rim), so no land boundary is flagged an island.
  const fs::path g3 = temp("lake.gr3");
  write_mesh(g3, mesh, with_groups(m.groups));
  const Gr3 g = parse_gr3(g3);
  ASSERT_EQ(g.open.size(), 1u);
  EXPECT_EQ(g.open[0].size(), river->edges.size() + 1);
  EXPECT_EQ(g.land.size(), 3u);
  for (int f : g.land_flag) EXPECT_EQ(f, 0);
  // Without the pier the island is flagged 1 and closes on itself.
  const Meshed plain = mesh_file(write_text("lake_plain.geojson", lake("")), 4.0);
  const fs::path g4 = temp("lake_plain.gr3");
  write_mesh(g4, plain.result.mesh, with_groups(plain.groups));
  const Gr3 h = parse_gr3(g4);
  ASSERT_EQ(h.land.size(), 2u);
  EXPECT_EQ(h.land_flag[1], 1);
  EXPECT_NE(h.land[1].front(), h.land[1].back());
}

TEST(BoundarySegments, SegmentEndsSurviveSimplification) {
  // A circle of 720 vertices meshed at a size that simplifies it: the segment's end vertices stay.
  std::ostringstream ring;
  ring.precision(17);
  for (int i = 0; i <= 720; ++i) {
    const double t = 2 * std::numbers::pi * (i % 720) / 720.0;
    ring << (i ? ", " : "") << "[" << 50 * std::cos(t) << ", " << 50 * std::sin(t) << "]";
  }
  std::ostringstream seg;
  seg.precision(17);
  for (int i = 101; i <= 207; ++i) {
    const double t = 2 * std::numbers::pi * i / 720.0;
    seg << (i > 101 ? ", " : "") << "[" << 50 * std::cos(t) << ", " << 50 * std::sin(t) << "]";
  }
  const fs::path p = write_text("circle.geojson", R"({"type": "FeatureCollection", "features": [
{"type": "Feature", "properties": {"role": "domain"}, "geometry": {"type": "Polygon", "coordinates": [[)" + ring.str() + R"(]]}},
{"type": "Feature", "properties": {"role": "boundary", "name": "arc", "kind": "open"}, "geometry": {"type": "LineString", "coordinates": [)" + seg.str() + "]}}]}");
  const Region input = read_region(p);
  const Vec2 a = input.boundary_segments[0].start, b = input.boundary_segments[0].end;
  const Meshed m = mesh_file(p, 6.0);
  const Region& simplified = m.result.region;
  EXPECT_LT(simplified.rings[0].points.size(), input.rings[0].points.size()) << "the case must simplify";
  const auto& pts = simplified.rings[0].points;
  EXPECT_NE(std::find(pts.begin(), pts.end(), a), pts.end());
  EXPECT_NE(std::find(pts.begin(), pts.end(), b), pts.end());
  EXPECT_NE(std::find(m.result.mesh.nodes.begin(), m.result.mesh.nodes.end(), a), m.result.mesh.nodes.end());
  EXPECT_NE(std::find(m.result.mesh.nodes.begin(), m.result.mesh.nodes.end(), b), m.result.mesh.nodes.end());
  EXPECT_TRUE(m.groups.warnings.empty());
  ASSERT_EQ(m.groups.segments.size(), 1u);
  double length = 0;
  for (const auto& e : m.groups.segments[0].edges)
    length += distance(m.result.mesh.nodes[static_cast<std::size_t>(e[0])], m.result.mesh.nodes[static_cast<std::size_t>(e[1])]);
  EXPECT_NEAR(length, 50 * 2 * std::numbers::pi * 106 / 720, 0.5) << "the 53-degree arc";
}

TEST(Exodus, ReadBackByMeshioWithNamedSetsAndSideSets) {
  const Meshed& m = dam_open();
  const QuadMesh& mesh = m.result.mesh;
  const fs::path p = temp("dam.exo");
  write_mesh(p, mesh, with_groups(m.groups));
  const nlohmann::json j = meshio_json(p, R"(
import netCDF4
out = {"points": m.points[:, :2].tolist(), "cells": [[c.type, c.data.tolist()] for c in m.cells],
       "sets": {k.rstrip("\x00"): sorted(int(x) for x in v) for k, v in m.point_sets.items()}}
ds = netCDF4.Dataset(sys.argv[1])
ds.set_auto_mask(False)
def names(var):
    return [b"".join(row).decode().rstrip("\x00") for row in ds.variables[var][:]]
out["eb_names"] = names("eb_names")
out["ss"] = {}
for k, name in enumerate(names("ss_names")):
    out["ss"][name] = [ds.variables["elem_ss%d" % (k + 1)][:].tolist(), ds.variables["side_ss%d" % (k + 1)][:].tolist()]
out["ss_ids"] = ds.variables["ss_prop1"][:].tolist()
out["version"] = float(ds.getncattr("version"))
print(json.dumps(out))
)");
  ASSERT_EQ(j["points"].size(), mesh.nodes.size());
  for (std::size_t i = 0; i < mesh.nodes.size(); ++i) {
    ASSERT_EQ(j["points"][i][0].get<double>(), mesh.nodes[i].x);
    ASSERT_EQ(j["points"][i][1].get<double>(), mesh.nodes[i].y);
  }
  ASSERT_EQ(j["cells"].size(), 1u);
  EXPECT_EQ(j["cells"][0][0], "quad");
  const auto& quads = j["cells"][0][1];
  ASSERT_EQ(quads.size(), mesh.quads.size());
  for (std::size_t q = 0; q < mesh.quads.size(); ++q)
    for (std::size_t k = 0; k < 4; ++k) ASSERT_EQ(quads[q][k].get<int>(), mesh.quads[q][k]);
  EXPECT_EQ(j["eb_names"], nlohmann::json({"channel"}));
  // Node sets: every group by name, with its nodes.
  for (const auto* list : {&m.groups.rings, &m.groups.segments, &m.groups.features})
    for (const CurveGroup& g : *list) {
      std::set<int> nodes;
      for (const auto& e : g.edges) nodes.insert(e[0]), nodes.insert(e[1]);
      ASSERT_TRUE(j["sets"].contains(g.name)) << g.name;
      EXPECT_EQ(j["sets"][g.name].get<std::vector<int>>(), std::vector<int>(nodes.begin(), nodes.end())) << g.name;
    }
  // Side sets of the boundary groups: side k of element e joins its local nodes k and k + 1 (1-based, cyclic),
  // and those edges are the group's edges.
  for (const CurveGroup* g : {find_group(m.groups.segments, "inflow"), find_group(m.groups.rings, "boundary_ring_0")}) {
    ASSERT_NE(g, nullptr);
    ASSERT_TRUE(j["ss"].contains(g->name));
    const auto elements = j["ss"][g->name][0].get<std::vector<int>>(), sides = j["ss"][g->name][1].get<std::vector<int>>();
    std::set<Edge> from_file, expected;
    for (std::size_t i = 0; i < elements.size(); ++i) {
      const auto& q = mesh.quads[static_cast<std::size_t>(elements[i] - 1)];
      from_file.insert(sorted(q[static_cast<std::size_t>(sides[i] - 1)], q[static_cast<std::size_t>(sides[i] % 4)]));
    }
    for (const auto& e : g->edges) expected.insert(sorted(e[0], e[1]));
    EXPECT_EQ(from_file, expected) << g->name;
  }
  EXPECT_EQ(j["ss_ids"][0], 2) << "side set ids are the physical tags";
}

TEST(BoundarySegments, CliReadsBoundaryFileAndListsGroupsInTheReport) {
  // The ends of dam_channel given in a separate file through GDAL (--boundary), every line a segment.
  const fs::path lines = write_text("ends.geojson", R"({"type": "FeatureCollection", "features": [
{"type": "Feature", "properties": {"name": "south", "kind": "open"}, "geometry": {"type": "LineString", "coordinates": [[0, 0], [80, 0]]}},
{"type": "Feature", "properties": {"name": "north", "kind": "open"}, "geometry": {"type": "LineString", "coordinates": [[0, 200], [80, 200]]}}]})");
  const fs::path gr3 = temp("cli.gr3"), report = temp("cli_report.json");
  int code = 0;
  const std::string printed =
      output_of(std::string(POLYSQUARE_CLI) + " mesh " + POLYSQUARE_DATA_DIR + "/cases/dam_channel.geojson --size 4 --boundary " +
                    lines.string() + " -o " + gr3.string() + " --report " + report.string() + " --picture " +
                    temp("cli.png").string(), &code, true);
  ASSERT_EQ(code, 0) << printed;
  EXPECT_NE(printed.find("groups: domain (1), 1 boundary ring(s) (2), 2 unnamed feature curve(s), south (5, open), north (6, open)"),
            std::string::npos) << printed;
  const Gr3 g = parse_gr3(gr3);
  EXPECT_EQ(g.open.size(), 2u);
  EXPECT_EQ(g.land.size(), 2u);
  {  // the picture draws the open segments over the boundary, in magenta
    cairo_surface_t* png = cairo_image_surface_create_from_png(temp("cli.png").string().c_str());
    ASSERT_EQ(cairo_surface_status(png), CAIRO_STATUS_SUCCESS);
    const int w = cairo_image_surface_get_width(png), h = cairo_image_surface_get_height(png);
    const int stride = cairo_image_surface_get_stride(png);
    const unsigned char* px = cairo_image_surface_get_data(png);
    std::size_t magenta = 0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const auto* p = reinterpret_cast<const std::uint32_t*>(px + y * stride) + x;
        magenta += (*p & 0xffffffu) == 0xff00ffu;
      }
    cairo_surface_destroy(png);
    EXPECT_GT(magenta, 50u);
  }
  std::ifstream in(report);
  const nlohmann::json r = nlohmann::json::parse(in);
  std::map<std::string, int> tags;
  for (const auto& grp : r["groups"]) tags[grp["name"].get<std::string>()] = grp["tag"].get<int>();
  EXPECT_EQ(tags["domain"], 1);
  EXPECT_EQ(tags["boundary_ring_0"], 2);
  EXPECT_EQ(tags["feature_0"], 3);
  EXPECT_EQ(tags["feature_1"], 4);
  EXPECT_EQ(tags["south"], 5);
  EXPECT_EQ(tags["north"], 6);
  // A line off the boundary: exit 2, one error line naming the file and feature, no output.
  const fs::path bad = write_text("bad_ends.geojson", R"({"type": "FeatureCollection", "features": [
{"type": "Feature", "properties": {"name": "x"}, "geometry": {"type": "LineString", "coordinates": [[10, 50], [20, 50]]}}]})");
  const fs::path out = temp("bad.gr3");
  const std::string err = output_of(std::string(POLYSQUARE_CLI) + " mesh " + POLYSQUARE_DATA_DIR +
                                        "/cases/dam_channel.geojson --size 4 --boundary " + bad.string() + " -o " + out.string(),
                                    &code, true);
  EXPECT_EQ(code, 2);
  EXPECT_NE(err.find("error:"), std::string::npos) << err;
  EXPECT_NE(err.find("bad_ends.geojson"), std::string::npos) << err;
  EXPECT_NE(err.find("not on the domain boundary"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(out));
}

TEST(BoundarySegments, NetFileGetsOnePolylinePerOpenSegment) {
  const Meshed& m = dam_open();
  const fs::path nc = temp("dam_net.nc");
  write_mesh(nc, m.result.mesh, with_groups(m.groups));
  const fs::path gr3 = temp("dam_for_pli.gr3");
  write_mesh(gr3, m.result.mesh, with_groups(m.groups));
  const Gr3 g = parse_gr3(gr3);
  ASSERT_EQ(g.open.size(), 2u);
  // Tekal blocks as D-Flow FM reads them: a name line, "rows columns", then one "x y" line per row.
  const char* names[] = {"inflow", "outflow"};
  for (std::size_t k = 0; k < 2; ++k) {
    const fs::path pli = temp(std::string("dam_net_") + names[k] + ".pli");
    ASSERT_EQ(pli, pli_path(nc, names[k]));
    std::ifstream in(pli);
    ASSERT_TRUE(in) << pli;
    std::string name;
    std::getline(in, name);
    EXPECT_EQ(name, names[k]);
    std::size_t rows = 0, cols = 0;
    in >> rows >> cols;
    EXPECT_EQ(cols, 2u);
    ASSERT_EQ(rows, g.open[k].size());
    for (std::size_t i = 0; i < rows; ++i) {
      std::string x, y;
      in >> x >> y;
      EXPECT_TRUE((Vec2{std::strtod(x.c_str(), nullptr), std::strtod(y.c_str(), nullptr)}) ==
                  g.xy[static_cast<std::size_t>(g.open[k][i] - 1)]) << names[k] << " row " << i;
    }
  }
  // Land segments get no polyline.
  EXPECT_FALSE(fs::exists(temp("dam_net_boundary_ring_0.pli")));
}

TEST(BoundarySegments, GdalReaderGivesTheSameSegmentsAndNames) {
  const fs::path p = std::string(POLYSQUARE_DATA_DIR) + "/cases/dam_channel_open.geojson";
  const Region native = read_region(p);
  InputOptions through_ogr;
  through_ogr.where = "1 = 1";  // a filter sends the file through GDAL/OGR
  InputNotes notes;
  const Region ogr = read_input(p, through_ogr, notes);
  ASSERT_EQ(ogr.boundary_segments.size(), native.boundary_segments.size());
  for (std::size_t s = 0; s < native.boundary_segments.size(); ++s) {
    const BoundarySegment &a = native.boundary_segments[s], &b = ogr.boundary_segments[s];
    EXPECT_EQ(a.name, b.name);
    EXPECT_EQ(a.kind, b.kind);
    EXPECT_EQ(a.ring, b.ring);
    EXPECT_TRUE(a.start == b.start && a.end == b.end) << s;
  }
  ASSERT_EQ(ogr.rings.size(), 1u);
  EXPECT_EQ(ogr.rings[0].name, "channel");
  ASSERT_EQ(ogr.features.size(), 2u);
  EXPECT_EQ(ogr.features[1].name, "dam_upper");
}

TEST(BoundarySegments, NamedDomainsBecomeSurfacesAndExodusBlocks) {
  const fs::path p = write_text("two_basins.geojson", R"({"type": "FeatureCollection", "features": [
{"type": "Feature", "properties": {"role": "domain", "name": "west"}, "geometry": {"type": "Polygon", "coordinates": [[[0, 0], [20, 0], [20, 20], [0, 20], [0, 0]]]}},
{"type": "Feature", "properties": {"role": "domain", "name": "east"}, "geometry": {"type": "Polygon", "coordinates": [[[30, 0], [60, 0], [60, 20], [30, 20], [30, 0]]]}},
{"type": "Feature", "properties": {"role": "boundary", "name": "sluice", "kind": "open"}, "geometry": {"type": "LineString", "coordinates": [[30, 5], [30, 15]]}}]})");
  const Meshed m = mesh_file(p, 2.0);
  const QuadMesh& mesh = m.result.mesh;
  ASSERT_EQ(m.groups.surfaces.size(), 2u);
  // Tags: the first surface 1, rings 2 and 3, the segment 4, the second surface after it.
  EXPECT_EQ(m.groups.surfaces[0].tag, 1);
  EXPECT_EQ(m.groups.rings.size(), 2u);
  ASSERT_EQ(m.groups.segments.size(), 1u);
  EXPECT_EQ(m.groups.segments[0].tag, 4);
  EXPECT_EQ(m.groups.surfaces[1].tag, 5);
  std::map<std::string, double> area;
  for (const SurfaceGroup& s : m.groups.surfaces)
    for (auto q : s.quads) {
      const auto& c = mesh.quads[static_cast<std::size_t>(q)];
      double a = 0;
      for (int k = 0; k < 4; ++k) a += cross(mesh.nodes[static_cast<std::size_t>(c[k])], mesh.nodes[static_cast<std::size_t>(c[(k + 1) % 4])]);
      area[s.name] += 0.5 * a;
    }
  EXPECT_NEAR(area["west"], 400.0, 1e-6);
  EXPECT_NEAR(area["east"], 600.0, 1e-6);
  // The segment's quads are on the west side of the east basin: x = 30, y from 5 to 15.
  for (const auto& e : m.groups.segments[0].edges)
    for (auto v : e) {
      EXPECT_EQ(mesh.nodes[static_cast<std::size_t>(v)].x, 30.0);
      EXPECT_GE(mesh.nodes[static_cast<std::size_t>(v)].y, 5.0);
      EXPECT_LE(mesh.nodes[static_cast<std::size_t>(v)].y, 15.0);
    }
  // MSH 4.1 read by meshio: one quad block per basin with its own physical tag.
  const fs::path msh = temp("two.msh");
  MeshWriteOptions o = with_groups(m.groups);
  o.msh_version = MshVersion::v4_1;
  write_mesh(msh, mesh, o);
  const nlohmann::json j = meshio_json(msh, R"(
quads = {}
for block, tags in zip(m.cells, m.cell_data["gmsh:physical"]):
    if block.type == "quad":
        for t in tags:
            quads[str(int(t))] = quads.get(str(int(t)), 0) + 1
print(json.dumps({"groups": {k: [int(v[0]), int(v[1])] for k, v in m.field_data.items()}, "quads": quads}))
)");
  EXPECT_EQ(j["groups"]["west"], nlohmann::json({1, 2}));
  EXPECT_EQ(j["groups"]["east"], nlohmann::json({5, 2}));
  EXPECT_EQ(j["groups"]["sluice"], nlohmann::json({4, 1}));
  EXPECT_EQ(j["quads"]["1"].get<std::size_t>(), m.groups.surfaces[0].quads.size());
  EXPECT_EQ(j["quads"]["5"].get<std::size_t>(), m.groups.surfaces[1].quads.size());
  // Exodus: two element blocks named after the basins, read by meshio as two quad blocks.
  const fs::path exo = temp("two.exo");
  write_mesh(exo, mesh, with_groups(m.groups));
  const nlohmann::json e = meshio_json(exo, R"(
import netCDF4
ds = netCDF4.Dataset(sys.argv[1])
ds.set_auto_mask(False)
print(json.dumps({"blocks": [len(c.data) for c in m.cells],
                  "names": [b"".join(r).decode().rstrip("\x00") for r in ds.variables["eb_names"][:]],
                  "ids": ds.variables["eb_prop1"][:].tolist()}))
)");
  EXPECT_EQ(e["names"], nlohmann::json({"west", "east"}));
  EXPECT_EQ(e["ids"], nlohmann::json({1, 5}));
  EXPECT_EQ(e["blocks"], nlohmann::json({m.groups.surfaces[0].quads.size(), m.groups.surfaces[1].quads.size()}));
}

TEST(BoundarySegments, OurMshReaderTakesNamedGroupsBack) {
  // Named segments are boundary edges, named feature curves feature edges, whatever their names, in both modes.
  const Meshed& m = dam_open();
  const QuadMesh& mesh = m.result.mesh;
  for (MshFeatures mode : {MshFeatures::lines, MshFeatures::nodes}) {
    const fs::path p = temp("named_back.msh");
    MeshWriteOptions o = with_groups(m.groups);
    o.msh_features = mode;
    write_mesh(p, mesh, o);
    const QuadMesh back = read_msh(p);
    std::set<Edge> boundary, feature, expected_feature;
    for (const auto& e : back.boundary_edges) boundary.insert(sorted(e[0], e[1]));
    for (const auto& e : back.feature_edges) feature.insert(sorted(e[0], e[1]));
    for (const auto& e : mesh.feature_edges) expected_feature.insert(sorted(e[0], e[1]));
    EXPECT_EQ(boundary, one_quad_edges(mesh));
    EXPECT_EQ(feature, expected_feature);
    std::set<std::int32_t> curves(back.feature_edge_curve.begin(), back.feature_edge_curve.end());
    EXPECT_EQ(curves.size(), 2u) << "dam_lower and dam_upper";
  }
}
