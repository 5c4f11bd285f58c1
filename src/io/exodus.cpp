// Exodus II through the netCDF C library (Debian packages no Exodus library), written from the Exodus II file
// format description (Sandia's "EXODUS II: A Finite Element Data Model", netCDF mapping): dimensions num_dim,
// num_nodes, num_elem, num_el_blk, num_node_sets, num_side_sets; coordx/coordy; one element block per named
// domain (connect<k>, elem_type QUAD4); side sets and node sets for the named boundary groups, node sets for the
// feature groups; names in eb_names / ss_names / ns_names, ids in *_prop1 (attribute name = "ID").
#include <netcdf.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

#include "nc_file.h"
#include "polysquare/core/error.h"
#include "polysquare/core/version.h"
#include "polysquare/io/atomic_file.h"
#include "polysquare/io/mesh_io.h"
#include "polysquare/io/mesh_groups.h"

namespace polysquare {
namespace {

constexpr std::size_t kNameLength = 32;  // maximum_name_length; len_name = 33 holds the terminating NUL

// Names as a (count, len_name) character array, NUL padded (longer names are cut to 32 characters).
std::vector<char> name_array(const std::vector<std::string>& names) {
  std::vector<char> out(names.size() * (kNameLength + 1), '\0');
  for (std::size_t i = 0; i < names.size(); ++i)
    for (std::size_t k = 0; k < names[i].size() && k < kNameLength; ++k) out[i * (kNameLength + 1) + k] = names[i][k];
  return out;
}

std::uint64_t undirected(std::int32_t a, std::int32_t b) {
  const auto lo = static_cast<std::uint64_t>(std::min(a, b)), hi = static_cast<std::uint64_t>(std::max(a, b));
  return lo << 32 | hi;
}

}  // namespace

void write_exodus(const std::filesystem::path& path, const QuadMesh& mesh, const MeshWriteOptions& options) {
  if (!mesh.triangles.empty())
    throw InputError(path.string() + ": the mesh has " + std::to_string(mesh.triangles.size()) +
                     " triangles; the Exodus writer takes all-quad meshes");
  const MeshGroups groups = options.groups.empty() ? mesh_groups(mesh) : options.groups;
  // Element numbers (1-based) follow the blocks: the quads of surface 0, then surface 1, ...
  std::vector<int> element_of(mesh.quads.size(), 0);
  {
    int next = 1;
    for (const SurfaceGroup& s : groups.surfaces)
      for (auto q : s.quads) element_of[static_cast<std::size_t>(q)] = next++;
  }
  // Side k + 1 of a QUAD4 joins its local nodes k and k + 1 (the Exodus side numbering).
  std::unordered_map<std::uint64_t, std::pair<int, int>> side_of;
  for (std::size_t q = 0; q < mesh.quads.size(); ++q)
    for (int k = 0; k < 4; ++k)
      side_of[undirected(mesh.quads[q][static_cast<std::size_t>(k)], mesh.quads[q][static_cast<std::size_t>((k + 1) % 4)])] = {
          element_of[q], k + 1};
  struct SideSet { std::string name; int id; std::vector<int> elements, sides; };
  struct NodeSet { std::string name; int id; std::vector<int> nodes; };
  std::vector<SideSet> side_sets;
  std::vector<NodeSet> node_sets;
  auto add_sets = [&](const CurveGroup& g, bool sides) {
    if (g.edges.empty()) return;
    NodeSet ns{g.name, g.tag, {}};
    std::unordered_map<std::int32_t, bool> seen;
    for (const auto& e : g.edges)
      for (auto v : e)
        if (seen.emplace(v, true).second) ns.nodes.push_back(v + 1);
    node_sets.push_back(std::move(ns));
    if (!sides) return;
    SideSet ss{g.name, g.tag, {}, {}};
    for (const auto& e : g.edges) {
      const auto it = side_of.find(undirected(e[0], e[1]));
      if (it == side_of.end()) continue;
      ss.elements.push_back(it->second.first);
      ss.sides.push_back(it->second.second);
    }
    side_sets.push_back(std::move(ss));
  };
  for (const CurveGroup& g : groups.rings) add_sets(g, true);
  for (const CurveGroup& g : groups.segments) add_sets(g, true);
  for (const CurveGroup& g : groups.features) add_sets(g, false);

  write_path_atomically(path, [&](const std::filesystem::path& tmp) {
    NcFile f(tmp, path.string(), NC_64BIT_OFFSET);
    const int id = f.id();
    f.text(NC_GLOBAL, "title", "polysquare " + std::string(library_version()) + (mesh.crs.empty() ? "" : ", " + mesh.crs));
    f.global_float("api_version", 8.0f);
    f.global_float("version", 8.0f);
    f.integer(NC_GLOBAL, "floating_point_word_size", 8);
    f.integer(NC_GLOBAL, "file_size", 1);
    f.integer(NC_GLOBAL, "maximum_name_length", static_cast<int>(kNameLength));
    f.integer(NC_GLOBAL, "int64_status", 0);
    f.dim("len_string", 33);
    f.dim("len_line", 81);
    f.dim("four", 4);
    const int len_name = f.dim("len_name", kNameLength + 1);
    int time_step = 0;
    f.check(nc_def_dim(id, "time_step", NC_UNLIMITED, &time_step), "dimension time_step");
    const int num_dim = f.dim("num_dim", 2);
    const int num_nodes = f.dim("num_nodes", mesh.nodes.size());
    f.dim("num_elem", mesh.quads.size());
    const int num_el_blk = f.dim("num_el_blk", groups.surfaces.size());
    f.var("time_whole", NC_DOUBLE, {time_step});
    const int coor_names = f.var("coor_names", NC_CHAR, {num_dim, len_name});
    const int coordx = f.var("coordx", NC_DOUBLE, {num_nodes});
    const int coordy = f.var("coordy", NC_DOUBLE, {num_nodes});
    const int eb_names = f.var("eb_names", NC_CHAR, {num_el_blk, len_name});
    const int eb_status = f.var("eb_status", NC_INT, {num_el_blk});
    const int eb_prop1 = f.var("eb_prop1", NC_INT, {num_el_blk});
    f.text(eb_prop1, "name", "ID");
    std::vector<int> connect;
    for (std::size_t k = 0; k < groups.surfaces.size(); ++k) {
      const std::string n = std::to_string(k + 1);
      const int el = f.dim("num_el_in_blk" + n, groups.surfaces[k].quads.size());
      const int per = f.dim("num_nod_per_el" + n, 4);
      connect.push_back(f.var("connect" + n, NC_INT, {el, per}));
      f.text(connect.back(), "elem_type", "QUAD4");
    }
    int ss_names = -1, ss_status = -1, ss_prop1 = -1, ns_names = -1, ns_status = -1, ns_prop1 = -1;
    std::vector<std::array<int, 2>> ss_vars;
    std::vector<int> ns_vars;
    if (!side_sets.empty()) {
      const int num = f.dim("num_side_sets", side_sets.size());
      ss_names = f.var("ss_names", NC_CHAR, {num, len_name});
      ss_status = f.var("ss_status", NC_INT, {num});
      ss_prop1 = f.var("ss_prop1", NC_INT, {num});
      f.text(ss_prop1, "name", "ID");
      for (std::size_t k = 0; k < side_sets.size(); ++k) {
        const std::string n = std::to_string(k + 1);
        const int len = f.dim("num_side_ss" + n, side_sets[k].elements.size());
        ss_vars.push_back({f.var("elem_ss" + n, NC_INT, {len}), f.var("side_ss" + n, NC_INT, {len})});
      }
    }
    if (!node_sets.empty()) {
      const int num = f.dim("num_node_sets", node_sets.size());
      ns_names = f.var("ns_names", NC_CHAR, {num, len_name});
      ns_status = f.var("ns_status", NC_INT, {num});
      ns_prop1 = f.var("ns_prop1", NC_INT, {num});
      f.text(ns_prop1, "name", "ID");
      for (std::size_t k = 0; k < node_sets.size(); ++k) {
        const std::string n = std::to_string(k + 1);
        ns_vars.push_back(f.var("node_ns" + n, NC_INT, {f.dim("num_nod_ns" + n, node_sets[k].nodes.size())}));
      }
    }
    f.end_definitions();

    f.put(coor_names, name_array({"x", "y"}));
    std::vector<double> x(mesh.nodes.size()), y(mesh.nodes.size());
    for (std::size_t i = 0; i < mesh.nodes.size(); ++i) x[i] = mesh.nodes[i].x, y[i] = mesh.nodes[i].y;
    f.put(coordx, x);
    f.put(coordy, y);
    std::vector<std::string> names;
    std::vector<int> ids, status;
    for (const SurfaceGroup& s : groups.surfaces) names.push_back(s.name), ids.push_back(s.tag), status.push_back(1);
    f.put(eb_names, name_array(names));
    f.put(eb_prop1, ids);
    f.put(eb_status, status);
    for (std::size_t k = 0; k < groups.surfaces.size(); ++k) {
      std::vector<int> c;
      c.reserve(groups.surfaces[k].quads.size() * 4);
      for (auto q : groups.surfaces[k].quads)
        for (auto v : mesh.quads[static_cast<std::size_t>(q)]) c.push_back(v + 1);
      f.put(connect[k], c);
    }
    if (!side_sets.empty()) {
      names.clear(), ids.clear(), status.clear();
      for (const SideSet& s : side_sets) names.push_back(s.name), ids.push_back(s.id), status.push_back(1);
      f.put(ss_names, name_array(names));
      f.put(ss_prop1, ids);
      f.put(ss_status, status);
      for (std::size_t k = 0; k < side_sets.size(); ++k) {
        f.put(ss_vars[k][0], side_sets[k].elements);
        f.put(ss_vars[k][1], side_sets[k].sides);
      }
    }
    if (!node_sets.empty()) {
      names.clear(), ids.clear(), status.clear();
      for (const NodeSet& s : node_sets) names.push_back(s.name), ids.push_back(s.id), status.push_back(1);
      f.put(ns_names, name_array(names));
      f.put(ns_prop1, ids);
      f.put(ns_status, status);
      for (std::size_t k = 0; k < node_sets.size(); ++k) f.put(ns_vars[k], node_sets[k].nodes);
    }
    f.close();
  });
}

}  // namespace polysquare
