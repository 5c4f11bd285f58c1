// Files for shallow-water solvers: SCHISM hgrid.gr3 (+ hgrid.ll), D-Flow FM UGRID-1.0 netCDF net file, SMS .2dm.
// write_mesh (mesh_io.h) picks them by extension; check_output_path lets the CLI refuse a bad output before meshing.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "polysquare/core/geometry.h"
#include "polysquare/core/quad_mesh.h"
#include "polysquare/io/mesh_io.h"

namespace polysquare {

/// One closed loop of boundary edges (edges of one quad), walked with the domain on its left: an outer ring
/// counter-clockwise, an inner ring (the rim of a hole: an island in a coastal model) clockwise.
struct BoundaryLoop {
  std::int32_t ring = -1;           ///< input ring index of its edges (QuadMesh::boundary_edge_ring), -1 if untagged
  bool inner = false;               ///< clockwise: the loop bounds a hole of its part
  std::vector<std::int32_t> nodes;  ///< node indices along the loop, the first one not repeated at the end
};

/// Every boundary loop of the quads, ordered by ring index (untagged last), each starting at its smallest node
/// index. Throws MeshingError when the boundary is not a set of disjoint loops (a node with two boundary edges
/// leaving it).
std::vector<BoundaryLoop> boundary_loops(const QuadMesh& mesh);

/// SCHISM hgrid.gr3: a header line naming the CRS, "NE NP", NP lines "id x y depth", NE lines "id 4 n1 n2 n3 n4"
/// (1-based, counter-clockwise), then the open boundaries (NOPE = 0 and NETA = 0 until named open segments
/// exist) and the land boundaries: NBOU, NVEL, then per loop "count flag" and its nodes one a line. Outer loops
/// are land (flag 0), listed counter-clockwise from their first node back to it (the first node repeated, so
/// every edge of the closed loop is between two listed nodes); inner loops are islands (flag 1), clockwise, the
/// first node not repeated (an island closes on itself). NVEL counts every listed node.
/// When options.input_crs names a geographic CRS, also writes `<stem>.ll` next to it: the same file with
/// longitude/latitude (EPSG:4326, degrees) instead of x/y. Throws InputError when the mesh CRS cannot be
/// transformed.
void write_gr3(const std::filesystem::path& path, const QuadMesh& mesh, const MeshWriteOptions& options = {});

/// `name` with every character other than letters, digits, '-' and '_' replaced by '_' (for file names).
std::string file_safe(const std::string& name);

/// The boundary polyline write_ugrid writes beside `net_file` for the open segment group `name`:
/// `<stem>_<file_safe(name)>.pli` (mesh_net.nc, "ocean" -> mesh_net_ocean.pli).
std::filesystem::path pli_path(const std::filesystem::path& net_file, const std::string& name);

/// A boundary polyline write_ugrid writes: the open segment group's name and its file (pli_path).
struct PliFile {
  std::string segment;
  std::filesystem::path path;
};

/// The boundary polylines write_ugrid writes beside `net_file` for the open segment groups `open_segments`
/// (open_segment_names before meshing, the groups' names when writing). Two names that give one file (file_safe
/// maps them alike, "north sea" and "north/sea", or they differ only in letter case, which Windows and macOS,
/// where D-Flow FM models are often run, do not tell apart) are refused: InputError naming both segments and the
/// file. Refusing, rather than numbering one of them, keeps every file named after its segment, as the external
/// forcing file refers to it.
std::vector<PliFile> pli_files(const std::filesystem::path& net_file, const std::vector<std::string>& open_segments);

/// A file write_mesh writes beside its output, and what it is ("the .ll companion of -o").
struct CompanionFile {
  std::filesystem::path path;
  std::string what;
};

/// The companions write_mesh(path, ...) writes beside `path`: a .gr3's `<stem>.ll` when `input_crs` is
/// geographic, a .nc's .pli per open segment group (pli_files, which refuses two names giving one file). A
/// .pvtu's pieces depend on the mesh's size (pvtu_piece_path). For checking every output before meshing.
std::vector<CompanionFile> companion_files(const std::filesystem::path& path, const std::string& input_crs,
                                           const std::vector<std::string>& open_segments);

/// D-Flow FM UGRID-1.0 net file (netCDF classic, 64-bit offset), as Deltares' tools write it: topology variable
/// mesh2d (cf_role mesh_topology, topology_dimension 2), mesh2d_node_x/y, mesh2d_edge_nodes (edges in
/// edge_table order), mesh2d_face_nodes (counter-clockwise, start_index 1, _FillValue -999), edge midpoints and
/// face circumcentres (face_circumcentres) as edge/face coordinates, mesh2d_node_z = -depth when a depth is given,
/// and the CRS variable: `projected_coordinate_system` (epsg, EPSG_code "EPSG:n"; epsg 0 when the mesh names no
/// CRS) or `wgs84` for a geographic one. Written atomically. Every boundary segment group of kind "open" also
/// gets a D-Flow FM boundary polyline (pli_path) through its boundary nodes, for the
/// external forcing file.
void write_ugrid(const std::filesystem::path& path, const QuadMesh& mesh, const MeshWriteOptions& options = {});

/// SMS 2D mesh: MESH2D, one "E4Q id n1 n2 n3 n4 1" per quad (counter-clockwise), one "ND id x y z" per node
/// (z = depth, 0 without one), then one nodestring per boundary loop (NS lines of at most ten node ids, the loop
/// closed by repeating its first node, the last id negative).
void write_2dm(const std::filesystem::path& path, const QuadMesh& mesh, const MeshWriteOptions& options = {});

/// The output formats write_mesh knows, by lower-case extension.
const std::vector<std::string>& output_extensions();

/// Checks before meshing that `path` can be written: a known extension (output_extensions), not a directory, and
/// an existing, writable directory to hold it (and, for .gr3 with geographic input, its .ll companion).
/// Throws InputError naming the path and the reason.
void check_output_path(const std::filesystem::path& path);

}  // namespace polysquare
