// Boundary loops, SCHISM hgrid.gr3 / hgrid.ll, SMS .2dm, and the output path check.
#include "polysquare/io/solver_files.h"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <ostream>
#include <unordered_map>

#include "crs_info.h"
#include "polysquare/core/error.h"
#include "polysquare/io/atomic_file.h"
#include "polysquare/quality/quality.h"

namespace polysquare {
namespace {

namespace fs = std::filesystem;

double depth_at(const MeshWriteOptions& options, std::size_t node) {
  return options.depth.empty() ? 0.0 : options.depth[node];
}

void check_depth(const fs::path& path, const QuadMesh& mesh, const MeshWriteOptions& options) {
  if (!options.depth.empty() && options.depth.size() != mesh.nodes.size())
    throw InputError(path.string() + ": " + std::to_string(options.depth.size()) + " depths given for " +
                     std::to_string(mesh.nodes.size()) + " nodes");
  if (!mesh.triangles.empty())
    throw InputError(path.string() + ": the mesh has " + std::to_string(mesh.triangles.size()) +
                     " triangles; the solver writers take all-quad meshes");
}

// The gr3 body with node coordinates `xy` (projected or lon/lat).
void write_gr3_text(std::ostream& os, const QuadMesh& mesh, const std::vector<Vec2>& xy, const std::string& header,
                    const MeshWriteOptions& options, const MeshGroups& groups) {
  os.precision(17);
  os << header << "\n" << mesh.quads.size() << " " << mesh.nodes.size() << "\n";
  for (std::size_t i = 0; i < xy.size(); ++i)
    os << i + 1 << " " << xy[i].x << " " << xy[i].y << " " << depth_at(options, i) << "\n";
  for (std::size_t q = 0; q < mesh.quads.size(); ++q) {
    os << q + 1 << " 4";
    for (auto v : mesh.quads[q]) os << " " << v + 1;
    os << "\n";
  }
  // Open boundaries: the chains of segments of kind "open". Land boundaries: every other boundary chain (named
  // segments of another kind, and the rest of each ring); the rim of a hole without segments is an island.
  struct Listed { const CurveGroup* group; const std::vector<std::int32_t>* nodes; };
  std::vector<Listed> open, land;
  for (const CurveGroup& g : groups.segments)
    for (const auto& chain : g.chains) (g.kind == "open" ? open : land).push_back({&g, &chain});
  for (const CurveGroup& g : groups.rings)
    for (const auto& chain : g.chains) land.push_back({&g, &chain});
  // Segments in ring order along the boundary, as SCHISM users list them.
  std::stable_sort(land.begin(), land.end(), [](const Listed& a, const Listed& b) { return a.group->ring < b.group->ring; });
  // An island closes on itself: its first node is not repeated.
  auto count = [](const Listed& l) { return l.nodes->size() - (l.group->island ? 1 : 0); };
  std::size_t open_nodes = 0, land_nodes = 0;
  for (const Listed& l : open) open_nodes += count(l);
  for (const Listed& l : land) land_nodes += count(l);
  os << open.size() << " = Number of open boundaries\n" << open_nodes << " = Total number of open boundary nodes\n";
  for (std::size_t k = 0; k < open.size(); ++k) {
    os << count(open[k]) << " = Number of nodes for open boundary " << k + 1 << " (" << open[k].group->name << ")\n";
    for (std::size_t i = 0; i < count(open[k]); ++i) os << (*open[k].nodes)[i] + 1 << "\n";
  }
  os << land.size() << " = Number of land boundaries\n" << land_nodes << " = Total number of land boundary nodes\n";
  for (std::size_t k = 0; k < land.size(); ++k) {
    const Listed& l = land[k];
    os << count(l) << " " << (l.group->island ? 1 : 0) << " = Number of nodes for land boundary " << k + 1 << " ("
       << (l.group->island ? "island, " : "") << l.group->name << ", ring " << l.group->ring << ")\n";
    for (std::size_t i = 0; i < count(l); ++i) os << (*l.nodes)[i] + 1 << "\n";
  }
}

}  // namespace

std::vector<BoundaryLoop> boundary_loops(const QuadMesh& mesh) {
  const EdgeTable edges = edge_table(mesh);
  std::unordered_map<std::uint64_t, std::int32_t> ring_of;
  for (std::size_t e = 0; e < mesh.boundary_edges.size() && e < mesh.boundary_edge_ring.size(); ++e)
    ring_of[edge_key(mesh.boundary_edges[e][0], mesh.boundary_edges[e][1])] = mesh.boundary_edge_ring[e];
  // Each boundary edge is oriented as its one face walks it, so the domain is on its left.
  std::vector<std::int32_t> next(mesh.nodes.size(), -1);
  for (std::size_t e = 0; e < edges.nodes.size(); ++e) {
    if (edges.faces[e][1] >= 0) continue;
    const auto [a, b] = edges.nodes[e];
    if (next[static_cast<std::size_t>(a)] >= 0)
      throw MeshingError("boundary: node " + std::to_string(a + 1) + " at " + at_text(mesh.nodes[static_cast<std::size_t>(a)]) +
                         " has two boundary edges leaving it (the boundary is not a set of disjoint loops)");
    next[static_cast<std::size_t>(a)] = b;
  }
  std::vector<BoundaryLoop> loops;
  std::vector<std::uint8_t> seen(mesh.nodes.size(), 0);
  for (std::size_t start = 0; start < mesh.nodes.size(); ++start) {
    if (next[start] < 0 || seen[start]) continue;
    BoundaryLoop loop;
    double area2 = 0;
    for (auto v = static_cast<std::int32_t>(start);;) {
      seen[static_cast<std::size_t>(v)] = 1;
      loop.nodes.push_back(v);
      const std::int32_t w = next[static_cast<std::size_t>(v)];
      if (w < 0)
        throw MeshingError("boundary: the boundary chain stops at node " + std::to_string(v + 1) + " at " +
                           at_text(mesh.nodes[static_cast<std::size_t>(v)]));
      area2 += cross(mesh.nodes[static_cast<std::size_t>(v)], mesh.nodes[static_cast<std::size_t>(w)]);
      if (w == static_cast<std::int32_t>(start)) break;
      if (seen[static_cast<std::size_t>(w)])
        throw MeshingError("boundary: the boundary loop from node " + std::to_string(start + 1) + " runs into another at node " +
                           std::to_string(w + 1));
      v = w;
    }
    loop.inner = area2 < 0;
    const auto it = ring_of.find(edge_key(loop.nodes[0], next[start]));
    loop.ring = it == ring_of.end() ? -1 : it->second;
    loops.push_back(std::move(loop));
  }
  std::stable_sort(loops.begin(), loops.end(), [](const BoundaryLoop& a, const BoundaryLoop& b) {
    const auto key = [](const BoundaryLoop& l) { return l.ring < 0 ? INT32_MAX : l.ring; };
    return key(a) < key(b);
  });
  return loops;
}

namespace {
// A .gr3 of geographic input gets its lon/lat twin (.ll).
bool gr3_has_lonlat(const std::string& input_crs) {
  const crs::CrsInfo input = crs::crs_info(input_crs);
  return input.known && input.geographic;
}
}  // namespace

// The groups to write: the caller's, else the generated ones; every boundary edge must be in a chain.
MeshGroups groups_for(const QuadMesh& mesh, const MeshWriteOptions& options) {
  boundary_loops(mesh);  // throws when the boundary is not a set of loops
  return options.groups.empty() ? mesh_groups(mesh) : options.groups;
}

void write_gr3(const fs::path& path, const QuadMesh& mesh, const MeshWriteOptions& options) {
  check_depth(path, mesh, options);
  const MeshGroups groups = groups_for(mesh, options);
  // The lon/lat companion first: a CRS that cannot be transformed fails before anything is written.
  std::vector<Vec2> lonlat;
  if (gr3_has_lonlat(options.input_crs)) lonlat = crs::to_lonlat(mesh.nodes, mesh.crs);
  const std::string crs_text = mesh.crs.empty() ? "no CRS" : mesh.crs;
  write_file_atomically(path, [&](std::ostream& os) {
    write_gr3_text(os, mesh, mesh.nodes, "polysquare " + crs_text, options, groups);
  }, false);
  if (!lonlat.empty()) {
    fs::path ll = path;
    ll.replace_extension(".ll");
    write_file_atomically(ll, [&](std::ostream& os) {
      write_gr3_text(os, mesh, lonlat, "polysquare EPSG:4326 (lon/lat of " + crs_text + ")", options, groups);
    }, false);
  }
}

void write_2dm(const fs::path& path, const QuadMesh& mesh, const MeshWriteOptions& options) {
  check_depth(path, mesh, options);
  const MeshGroups groups = groups_for(mesh, options);
  write_file_atomically(path, [&](std::ostream& os) {
    os.precision(17);
    os << "MESH2D\nMESHNAME \"polysquare\"\n";
    for (std::size_t q = 0; q < mesh.quads.size(); ++q) {
      os << "E4Q " << q + 1;
      for (auto v : mesh.quads[q]) os << " " << v + 1;
      os << " 1\n";
    }
    for (std::size_t i = 0; i < mesh.nodes.size(); ++i)
      os << "ND " << i + 1 << " " << mesh.nodes[i].x << " " << mesh.nodes[i].y << " " << depth_at(options, i) << "\n";
    // One nodestring per boundary chain: the rest of each ring (a ring without segments closed, its first node
    // repeated), then every named segment, in the order of the groups' tags.
    // The group's name follows the last (negative) node id, blanks made '_' so it stays one field.
    std::vector<std::pair<const std::vector<std::int32_t>*, const CurveGroup*>> strings;
    for (const CurveGroup& g : groups.rings)
      for (const auto& chain : g.chains) strings.emplace_back(&chain, &g);
    for (const CurveGroup& g : groups.segments)
      for (const auto& chain : g.chains) strings.emplace_back(&chain, &g);
    for (const auto& [chain, group] : strings) {
      const std::vector<std::int32_t>& ids = *chain;
      for (std::size_t k = 0; k < ids.size(); ++k) {
        if (k % 10 == 0) os << (k ? "\n" : "") << "NS";
        os << " " << (k + 1 == ids.size() ? -(ids[k] + 1) : ids[k] + 1);
      }
      std::string name = group->name;
      for (char& ch : name)
        if (std::isspace(static_cast<unsigned char>(ch))) ch = '_';
      os << (name.empty() ? "" : " ") << name << "\n";
    }
  }, false);
}

const std::vector<std::string>& output_extensions() {
  static const std::vector<std::string> known{".msh", ".vtu", ".pvtu", ".gr3", ".nc", ".2dm", ".exo"};
  return known;
}

std::vector<CompanionFile> companion_files(const fs::path& path, const std::string& input_crs,
                                           const std::vector<std::string>& open_segments) {
  std::vector<CompanionFile> companions;
  const std::string ext = lower_extension(path);
  if (ext == ".gr3" && gr3_has_lonlat(input_crs))
    companions.push_back({fs::path(path).replace_extension(".ll"), "the .ll companion of -o (lon/lat of the nodes)"});
  if (ext == ".nc")
    for (PliFile& f : pli_files(path, open_segments))
      companions.push_back({std::move(f.path), "the boundary polyline of open segment \"" + f.segment + "\""});
  return companions;
}

void check_output_path(const fs::path& path) { check_output_file(path, "output", output_extensions()); }

}  // namespace polysquare
