// D-Flow FM UGRID-1.0 net file through the netCDF C library.
#include <netcdf.h>

#include <array>
#include <cctype>
#include <initializer_list>
#include <map>
#include <utility>
#include <string>
#include <vector>

#include "crs_info.h"
#include "nc_file.h"
#include "polysquare/core/error.h"
#include "polysquare/core/version.h"
#include "polysquare/io/atomic_file.h"
#include "polysquare/io/solver_files.h"
#include "polysquare/quality/quality.h"

namespace polysquare {
namespace fs = std::filesystem;
namespace {

constexpr int kFillInt = -999;  // D-Flow FM's fill value for connectivity
constexpr double kFillDouble = -999.0;

void define_topology(NcFile& f) {
  const int topo = f.var("mesh2d", NC_INT, {});
  f.integer(topo, "topology_dimension", 2);
  f.texts(topo, {{"cf_role", "mesh_topology"},
                 {"long_name", "Topology data of 2D mesh"},
                 {"node_coordinates", "mesh2d_node_x mesh2d_node_y"},
                 {"node_dimension", "mesh2d_nNodes"},
                 {"max_face_nodes_dimension", "mesh2d_nMax_face_nodes"},
                 {"edge_node_connectivity", "mesh2d_edge_nodes"},
                 {"edge_dimension", "mesh2d_nEdges"},
                 {"edge_coordinates", "mesh2d_edge_x mesh2d_edge_y"},
                 {"face_node_connectivity", "mesh2d_face_nodes"},
                 {"face_dimension", "mesh2d_nFaces"},
                 {"face_coordinates", "mesh2d_face_x mesh2d_face_y"}});
}

// The CRS as D-Flow FM reads it: the epsg attribute (0 = unknown projected).
void define_crs(NcFile& f, const crs::CrsInfo& info, const std::string& crs_var, bool geographic) {
  const int crs = f.var(crs_var, NC_INT, {});
  f.text(crs, "name", info.known ? info.name : "Unknown projected");
  f.integer(crs, "epsg", info.epsg);
  f.text(crs, "grid_mapping_name", geographic ? "latitude_longitude" : "Unknown projected");
  f.real(crs, "longitude_of_prime_meridian", 0.0);
  f.real(crs, "semi_major_axis", info.semi_major);
  f.real(crs, "semi_minor_axis", info.semi_minor);
  f.real(crs, "inverse_flattening", info.inverse_flattening);
  f.text(crs, "EPSG_code", "EPSG:" + std::to_string(info.epsg));
  f.text(crs, "value", "value is equal to EPSG code");
  f.text(crs, "proj4_params", info.proj4);
  if (!info.wkt.empty()) f.text(crs, "wkt", info.wkt);
}

int define_coordinate(NcFile& f, bool geographic, const std::string& name, int dim, const char* location, char axis,
                      const std::string& what) {
  const int v = f.var(name, NC_DOUBLE, {dim});
  f.text(v, "units", geographic ? (axis == 'x' ? "degrees_east" : "degrees_north") : "m");
  f.text(v, "standard_name", geographic ? (axis == 'x' ? "longitude" : "latitude")
                                        : (axis == 'x' ? "projection_x_coordinate" : "projection_y_coordinate"));
  f.text(v, "long_name", std::string(1, axis) + "-coordinate of " + what);
  f.text(v, "mesh", "mesh2d");
  f.text(v, "location", location);
  return v;
}

// Connectivity, 1-based as D-Flow FM writes it.
int define_connectivity(NcFile& f, const std::string& name, std::vector<int> dims, const char* location,
                        const char* long_name) {
  const int v = f.var(name, NC_INT, std::move(dims));
  f.text(v, "cf_role", std::string(location) + "_node_connectivity");
  f.text(v, "mesh", "mesh2d");
  f.text(v, "location", location);
  f.text(v, "long_name", long_name);
  f.integer(v, "start_index", 1);
  f.integer(v, "_FillValue", kFillInt);
  return v;
}

int define_node_z(NcFile& f, int d_nodes, const std::string& crs_var) {
  const int node_z = f.var("mesh2d_node_z", NC_DOUBLE, {d_nodes});
  f.texts(node_z, {{"mesh", "mesh2d"},
                   {"location", "node"},
                   {"coordinates", "mesh2d_node_x mesh2d_node_y"},
                   {"standard_name", "altitude"},
                   {"long_name", "z-coordinate of mesh nodes"},
                   {"units", "m"},
                   {"positive", "up"},
                   {"grid_mapping", crs_var}});
  f.real(node_z, "_FillValue", kFillDouble);
  return node_z;
}

// Variable ids of a net file, from its definitions.
struct UgridVars {
  int node_x = -1, node_y = -1, node_z = -1;  ///< node_z: -1 without depths
  int edge_x = -1, edge_y = -1, edge_nodes = -1;
  int face_x = -1, face_y = -1, face_nodes = -1;
};

struct UgridSizes {
  std::size_t nodes = 0, edges = 0, faces = 0;
};

UgridVars define_ugrid(NcFile& f, const UgridSizes& n, const crs::CrsInfo& info, bool with_depth, const QuadMesh& mesh) {
  const bool geographic = info.known && info.geographic;
  const std::string crs_var = geographic ? "wgs84" : "projected_coordinate_system";
  const int d_nodes = f.dim("mesh2d_nNodes", n.nodes), d_edges = f.dim("mesh2d_nEdges", n.edges),
            d_faces = f.dim("mesh2d_nFaces", n.faces), d_max = f.dim("mesh2d_nMax_face_nodes", 4), d_two = f.dim("Two", 2);
  define_topology(f);
  define_crs(f, info, crs_var, geographic);
  UgridVars v;
  v.node_x = define_coordinate(f, geographic, "mesh2d_node_x", d_nodes, "node", 'x', "mesh nodes");
  v.node_y = define_coordinate(f, geographic, "mesh2d_node_y", d_nodes, "node", 'y', "mesh nodes");
  if (with_depth) v.node_z = define_node_z(f, d_nodes, crs_var);
  v.edge_x = define_coordinate(f, geographic, "mesh2d_edge_x", d_edges, "edge", 'x', "the mesh edges (midpoint)");
  v.edge_y = define_coordinate(f, geographic, "mesh2d_edge_y", d_edges, "edge", 'y', "the mesh edges (midpoint)");
  v.edge_nodes =
      define_connectivity(f, "mesh2d_edge_nodes", {d_edges, d_two}, "edge", "Start and end nodes of mesh edges");
  v.face_x = define_coordinate(f, geographic, "mesh2d_face_x", d_faces, "face", 'x', "the mesh faces (circumcentre)");
  v.face_y = define_coordinate(f, geographic, "mesh2d_face_y", d_faces, "face", 'y', "the mesh faces (circumcentre)");
  v.face_nodes = define_connectivity(f, "mesh2d_face_nodes", {d_faces, d_max}, "face",
                                     "Vertex nodes of mesh faces (counterclockwise)");

  f.text(NC_GLOBAL, "Conventions", "CF-1.8 UGRID-1.0 Deltares-0.10");
  f.text(NC_GLOBAL, "title", "D-Flow FM net file (all quadrilaterals)");
  f.text(NC_GLOBAL, "source", std::string("polysquare ") + library_version());
  f.text(NC_GLOBAL, "crs", mesh.crs);
  return v;
}

void put_ugrid(NcFile& f, const UgridVars& v, const QuadMesh& mesh, const EdgeTable& edges,
               const std::vector<Vec2>& centres, const std::vector<double>& depth) {
  const std::size_t nn = mesh.nodes.size(), ne = edges.nodes.size(), nf = mesh.quads.size();
  std::vector<double> xs(nn), ys(nn);
  for (std::size_t i = 0; i < nn; ++i) xs[i] = mesh.nodes[i].x, ys[i] = mesh.nodes[i].y;
  f.put(v.node_x, xs);
  f.put(v.node_y, ys);
  if (v.node_z >= 0) {
    std::vector<double> z(nn);
    for (std::size_t i = 0; i < nn; ++i) z[i] = -depth[i];
    f.put(v.node_z, z);
  }
  std::vector<double> ex(ne), ey(ne);
  std::vector<int> en(2 * ne);
  for (std::size_t e = 0; e < ne; ++e) {
    const Vec2 m = 0.5 * (mesh.nodes[edges.nodes[e][0]] + mesh.nodes[edges.nodes[e][1]]);
    ex[e] = m.x, ey[e] = m.y;
    en[2 * e] = edges.nodes[e][0] + 1;
    en[2 * e + 1] = edges.nodes[e][1] + 1;
  }
  f.put(v.edge_x, ex);
  f.put(v.edge_y, ey);
  f.put(v.edge_nodes, en);
  std::vector<double> fx(nf), fy(nf);
  std::vector<int> fn(4 * nf);
  for (std::size_t q = 0; q < nf; ++q) {
    fx[q] = centres[q].x, fy[q] = centres[q].y;
    for (int k = 0; k < 4; ++k) fn[4 * q + static_cast<std::size_t>(k)] = mesh.quads[q][static_cast<std::size_t>(k)] + 1;
  }
  f.put(v.face_x, fx);
  f.put(v.face_y, fy);
  f.put(v.face_nodes, fn);
}

// D-Flow FM takes boundary conditions on polylines (.pli, Tekal blocks: name, "rows 2", then x y per row)
// named in its external forcing file; each open segment gets one along its boundary nodes.
void write_pli_files(const std::filesystem::path& path, const QuadMesh& mesh, const MeshGroups& groups) {
  for (const CurveGroup& g : groups.segments) {
    if (g.kind != "open") continue;
    write_file_atomically(pli_path(path, g.name), [&](std::ostream& os) {
      os.precision(17);
      for (std::size_t k = 0; k < g.chains.size(); ++k) {
        os << g.name << (g.chains.size() > 1 ? "_" + std::to_string(k + 1) : std::string()) << "\n"
           << g.chains[k].size() << " 2\n";
        for (auto v : g.chains[k]) os << mesh.nodes[static_cast<std::size_t>(v)].x << " " << mesh.nodes[static_cast<std::size_t>(v)].y << "\n";
      }
    }, false);
  }
}

}  // namespace

void write_ugrid(const std::filesystem::path& path, const QuadMesh& mesh, const MeshWriteOptions& options) {
  if (!options.depth.empty() && options.depth.size() != mesh.nodes.size())
    throw InputError(path.string() + ": " + std::to_string(options.depth.size()) + " depths given for " +
                     std::to_string(mesh.nodes.size()) + " nodes");
  if (!mesh.triangles.empty())
    throw InputError(path.string() + ": the mesh has triangles; the solver writers take all-quad meshes");
  const EdgeTable edges = edge_table(mesh);
  const std::vector<Vec2> centres = face_circumcentres(mesh, edges);
  const crs::CrsInfo info = crs::crs_info(mesh.crs);
  const UgridSizes sizes{mesh.nodes.size(), edges.nodes.size(), mesh.quads.size()};
  // Two open groups whose names give one .pli are refused before any file is written.
  const MeshGroups groups = options.groups.empty() ? mesh_groups(mesh) : options.groups;
  std::vector<std::string> open;
  for (const CurveGroup& g : groups.segments)
    if (g.kind == "open") open.push_back(g.name);
  pli_files(path, open);
  write_path_atomically(path, [&](const std::filesystem::path& tmp) {
    NcFile f(tmp, path.string());
    const UgridVars vars = define_ugrid(f, sizes, info, !options.depth.empty(), mesh);
    f.end_definitions();
    put_ugrid(f, vars, mesh, edges, centres, options.depth);
    f.close();
  });
  write_pli_files(path, mesh, groups);
}

std::string file_safe(const std::string& name) {
  std::string out;
  for (char ch : name)
    out += (std::isalnum(static_cast<unsigned char>(ch)) || ch == '-' || ch == '_') ? ch : '_';
  return out.empty() ? std::string("_") : out;
}

fs::path pli_path(const fs::path& net_file, const std::string& name) {
  return net_file.parent_path() / (net_file.stem().string() + "_" + file_safe(name) + ".pli");
}

std::vector<PliFile> pli_files(const fs::path& net_file, const std::vector<std::string>& open_segments) {
  std::vector<PliFile> files;
  std::map<std::string, std::size_t> by_name;  // file name in lower case -> index in files
  for (const std::string& name : open_segments) {
    PliFile f{name, pli_path(net_file, name)};
    std::string key = f.path.filename().string();
    for (char& ch : key) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    const auto [it, inserted] = by_name.try_emplace(key, files.size());
    if (!inserted) {
      const PliFile& first = files[it->second];
      throw InputError(f.path.string() + ": the open boundary segments \"" + first.segment + "\" and \"" + name +
                       "\" would both be written to this boundary polyline (file names keep letters, digits, '-' "
                       "and '_', the others become '_', and letter case does not tell files apart on Windows and "
                       "macOS); rename one of them");
    }
    files.push_back(std::move(f));
  }
  return files;
}

}  // namespace polysquare
