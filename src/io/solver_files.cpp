// Boundary loops, SCHISM hgrid.gr3 / hgrid.ll, SMS .2dm, and the output path check.
#include "polysquare/io/solver_files.h"

#include <unistd.h>

#include <algorithm>
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
                    const MeshWriteOptions& options, const std::vector<BoundaryLoop>& loops) {
  os.precision(17);
  os << header << "\n" << mesh.quads.size() << " " << mesh.nodes.size() << "\n";
  for (std::size_t i = 0; i < xy.size(); ++i)
    os << i + 1 << " " << xy[i].x << " " << xy[i].y << " " << depth_at(options, i) << "\n";
  for (std::size_t q = 0; q < mesh.quads.size(); ++q) {
    os << q + 1 << " 4";
    for (auto v : mesh.quads[q]) os << " " << v + 1;
    os << "\n";
  }
  // No named open segments yet: every loop is a land boundary.
  os << "0 = Number of open boundaries\n0 = Total number of open boundary nodes\n";
  std::size_t listed = 0;
  for (const BoundaryLoop& l : loops) listed += l.nodes.size() + (l.inner ? 0 : 1);
  os << loops.size() << " = Number of land boundaries\n" << listed << " = Total number of land boundary nodes\n";
  for (std::size_t k = 0; k < loops.size(); ++k) {
    const BoundaryLoop& l = loops[k];
    os << l.nodes.size() + (l.inner ? 0 : 1) << " " << (l.inner ? 1 : 0) << " = Number of nodes for land boundary "
       << k + 1 << (l.inner ? " (island, ring " : " (ring ") << l.ring << ")\n";
    for (auto v : l.nodes) os << v + 1 << "\n";
    if (!l.inner) os << l.nodes.front() + 1 << "\n";
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

void write_gr3(const fs::path& path, const QuadMesh& mesh, const MeshWriteOptions& options) {
  check_depth(path, mesh, options);
  const std::vector<BoundaryLoop> loops = boundary_loops(mesh);
  const crs::CrsInfo input = crs::crs_info(options.input_crs);
  // The lon/lat companion first: a CRS that cannot be transformed fails before anything is written.
  std::vector<Vec2> lonlat;
  if (input.known && input.geographic) lonlat = crs::to_lonlat(mesh.nodes, mesh.crs);
  const std::string crs_text = mesh.crs.empty() ? "no CRS" : mesh.crs;
  write_file_atomically(path, [&](std::ostream& os) {
    write_gr3_text(os, mesh, mesh.nodes, "polysquare " + crs_text, options, loops);
  }, false);
  if (!lonlat.empty()) {
    fs::path ll = path;
    ll.replace_extension(".ll");
    write_file_atomically(ll, [&](std::ostream& os) {
      write_gr3_text(os, mesh, lonlat, "polysquare EPSG:4326 (lon/lat of " + crs_text + ")", options, loops);
    }, false);
  }
}

void write_2dm(const fs::path& path, const QuadMesh& mesh, const MeshWriteOptions& options) {
  check_depth(path, mesh, options);
  const std::vector<BoundaryLoop> loops = boundary_loops(mesh);
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
    for (const BoundaryLoop& l : loops) {
      std::vector<std::int32_t> ids(l.nodes.begin(), l.nodes.end());
      ids.push_back(l.nodes.front());
      for (std::size_t k = 0; k < ids.size(); ++k) {
        if (k % 10 == 0) os << (k ? "\n" : "") << "NS";
        os << " " << (k + 1 == ids.size() ? -(ids[k] + 1) : ids[k] + 1);
      }
      os << "\n";
    }
  }, false);
}

const std::vector<std::string>& output_extensions() {
  static const std::vector<std::string> known{".msh", ".vtu", ".gr3", ".nc", ".2dm"};
  return known;
}

void check_output_path(const fs::path& path) { check_output_file(path, "output", output_extensions()); }

}  // namespace polysquare
