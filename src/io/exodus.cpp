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

// Element numbers (1-based) follow the blocks: the quads of surface 0, then surface 1, ...
std::vector<int> element_numbers(const QuadMesh& mesh, const MeshGroups& groups) {
  std::vector<int> element_of(mesh.quads.size(), 0);
  int next = 1;
  for (const SurfaceGroup& s : groups.surfaces)
    for (auto q : s.quads) element_of[static_cast<std::size_t>(q)] = next++;
  return element_of;
}

struct SideSet { std::string name; int tag; std::vector<int> elements, sides; };
struct NodeSet { std::string name; int tag; std::vector<int> nodes; };

struct ExodusSets {
  std::vector<SideSet> side_sets;
  std::vector<NodeSet> node_sets;
};

// Side sets and node sets for the boundary groups (rings, then segments), node sets for the feature groups.
ExodusSets exodus_sets(const QuadMesh& mesh, const MeshGroups& groups) {
  const std::vector<int> element_of = element_numbers(mesh, groups);
  // Side k + 1 of a QUAD4 joins its local nodes k and k + 1 (the Exodus side numbering).
  std::unordered_map<std::uint64_t, std::pair<int, int>> side_of;
  for (std::size_t q = 0; q < mesh.quads.size(); ++q)
    for (int k = 0; k < 4; ++k)
      side_of[undirected(mesh.quads[q][static_cast<std::size_t>(k)], mesh.quads[q][static_cast<std::size_t>((k + 1) % 4)])] = {
          element_of[q], k + 1};
  ExodusSets sets;
  auto add_sets = [&](const CurveGroup& g, bool sides) {
    if (g.edges.empty()) return;
    NodeSet ns{g.name, g.tag, {}};
    std::unordered_map<std::int32_t, bool> seen;
    for (const auto& e : g.edges)
      for (auto v : e)
        if (seen.emplace(v, true).second) ns.nodes.push_back(v + 1);
    sets.node_sets.push_back(std::move(ns));
    if (!sides) return;
    SideSet ss{g.name, g.tag, {}, {}};
    for (const auto& e : g.edges) {
      const auto it = side_of.find(undirected(e[0], e[1]));
      if (it == side_of.end()) continue;
      ss.elements.push_back(it->second.first);
      ss.sides.push_back(it->second.second);
    }
    sets.side_sets.push_back(std::move(ss));
  };
  for (const CurveGroup& g : groups.rings) add_sets(g, true);
  for (const CurveGroup& g : groups.segments) add_sets(g, true);
  for (const CurveGroup& g : groups.features) add_sets(g, false);
  return sets;
}

// The names, status and ids of element blocks (eb), side sets (ss) or node sets (ns).
struct NamedTable { int names = -1, status = -1, prop1 = -1; };

NamedTable define_named_table(NcFile& f, const std::string& prefix, int count_dim, int len_name) {
  NamedTable t;
  t.names = f.var(prefix + "_names", NC_CHAR, {count_dim, len_name});
  t.status = f.var(prefix + "_status", NC_INT, {count_dim});
  t.prop1 = f.var(prefix + "_prop1", NC_INT, {count_dim});
  f.text(t.prop1, "name", "ID");
  return t;
}

// Blocks or sets: their names, ids (the group tags) and status 1.
template <class Set>
void put_named_table(NcFile& f, const NamedTable& t, const std::vector<Set>& sets) {
  std::vector<std::string> names;
  std::vector<int> ids, status;
  for (const Set& s : sets) names.push_back(s.name), ids.push_back(s.tag), status.push_back(1);
  f.put(t.names, name_array(names));
  f.put(t.prop1, ids);
  f.put(t.status, status);
}

// Variable ids of an Exodus file, from its definitions.
struct ExodusVars {
  int len_name = -1;  ///< the dimension of names
  int coor_names = -1, coordx = -1, coordy = -1;
  NamedTable blocks, side_sets, node_sets;
  std::vector<int> connect;
  std::vector<std::array<int, 2>> ss_vars;  ///< elem_ss<k>, side_ss<k>
  std::vector<int> ns_vars;
};

// Global attributes, dimensions, coordinates and element blocks.
ExodusVars define_exodus_mesh(NcFile& f, const QuadMesh& mesh, const MeshGroups& groups) {
  ExodusVars v;
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
  const int len_name = v.len_name = f.dim("len_name", kNameLength + 1);
  int time_step = 0;
  f.check(nc_def_dim(f.id(), "time_step", NC_UNLIMITED, &time_step), "dimension time_step");
  const int num_dim = f.dim("num_dim", 2);
  const int num_nodes = f.dim("num_nodes", mesh.nodes.size());
  f.dim("num_elem", mesh.quads.size());
  const int num_el_blk = f.dim("num_el_blk", groups.surfaces.size());
  f.var("time_whole", NC_DOUBLE, {time_step});
  v.coor_names = f.var("coor_names", NC_CHAR, {num_dim, len_name});
  v.coordx = f.var("coordx", NC_DOUBLE, {num_nodes});
  v.coordy = f.var("coordy", NC_DOUBLE, {num_nodes});
  v.blocks = define_named_table(f, "eb", num_el_blk, len_name);
  for (std::size_t k = 0; k < groups.surfaces.size(); ++k) {
    const std::string n = std::to_string(k + 1);
    const int el = f.dim("num_el_in_blk" + n, groups.surfaces[k].quads.size());
    const int per = f.dim("num_nod_per_el" + n, 4);
    v.connect.push_back(f.var("connect" + n, NC_INT, {el, per}));
    f.text(v.connect.back(), "elem_type", "QUAD4");
  }
  return v;
}

// The side sets' and node sets' dimensions and variables.
void define_exodus_sets(NcFile& f, const ExodusSets& sets, ExodusVars& v) {
  const int len_name = v.len_name;
  if (!sets.side_sets.empty()) {
    v.side_sets = define_named_table(f, "ss", f.dim("num_side_sets", sets.side_sets.size()), len_name);
    for (std::size_t k = 0; k < sets.side_sets.size(); ++k) {
      const std::string n = std::to_string(k + 1);
      const int len = f.dim("num_side_ss" + n, sets.side_sets[k].elements.size());
      v.ss_vars.push_back({f.var("elem_ss" + n, NC_INT, {len}), f.var("side_ss" + n, NC_INT, {len})});
    }
  }
  if (!sets.node_sets.empty()) {
    v.node_sets = define_named_table(f, "ns", f.dim("num_node_sets", sets.node_sets.size()), len_name);
    for (std::size_t k = 0; k < sets.node_sets.size(); ++k) {
      const std::string n = std::to_string(k + 1);
      v.ns_vars.push_back(f.var("node_ns" + n, NC_INT, {f.dim("num_nod_ns" + n, sets.node_sets[k].nodes.size())}));
    }
  }
}

void put_exodus(NcFile& f, const ExodusVars& v, const QuadMesh& mesh, const MeshGroups& groups, const ExodusSets& sets) {
  f.put(v.coor_names, name_array({"x", "y"}));
  std::vector<double> x(mesh.nodes.size()), y(mesh.nodes.size());
  for (std::size_t i = 0; i < mesh.nodes.size(); ++i) x[i] = mesh.nodes[i].x, y[i] = mesh.nodes[i].y;
  f.put(v.coordx, x);
  f.put(v.coordy, y);
  put_named_table(f, v.blocks, groups.surfaces);
  for (std::size_t k = 0; k < groups.surfaces.size(); ++k) {
    std::vector<int> c;
    c.reserve(groups.surfaces[k].quads.size() * 4);
    for (auto q : groups.surfaces[k].quads)
      for (auto n : mesh.quads[static_cast<std::size_t>(q)]) c.push_back(n + 1);
    f.put(v.connect[k], c);
  }
  if (!sets.side_sets.empty()) {
    put_named_table(f, v.side_sets, sets.side_sets);
    for (std::size_t k = 0; k < sets.side_sets.size(); ++k) {
      f.put(v.ss_vars[k][0], sets.side_sets[k].elements);
      f.put(v.ss_vars[k][1], sets.side_sets[k].sides);
    }
  }
  if (!sets.node_sets.empty()) {
    put_named_table(f, v.node_sets, sets.node_sets);
    for (std::size_t k = 0; k < sets.node_sets.size(); ++k) f.put(v.ns_vars[k], sets.node_sets[k].nodes);
  }
}

}  // namespace

void write_exodus(const std::filesystem::path& path, const QuadMesh& mesh, const MeshWriteOptions& options) {
  if (!mesh.triangles.empty())
    throw InputError(path.string() + ": the mesh has " + std::to_string(mesh.triangles.size()) +
                     " triangles; the Exodus writer takes all-quad meshes");
  const MeshGroups groups = options.groups.empty() ? mesh_groups(mesh) : options.groups;
  const ExodusSets sets = exodus_sets(mesh, groups);
  write_path_atomically(path, [&](const std::filesystem::path& tmp) {
    NcFile f(tmp, path.string(), NC_64BIT_OFFSET);
    ExodusVars vars = define_exodus_mesh(f, mesh, groups);
    define_exodus_sets(f, sets, vars);
    f.end_definitions();
    put_exodus(f, vars, mesh, groups, sets);
    f.close();
  });
}

}  // namespace polysquare
