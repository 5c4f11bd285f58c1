// Mesh files: Gmsh MSH (read 2.2 and 4.1, ASCII and binary; write 2.2 and 4.1), VTK XML .vtu (write; read ASCII);
// solver files (write only): SCHISM .gr3, D-Flow FM UGRID .nc, SMS .2dm (solver_files.h).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "polysquare/core/quad_mesh.h"
#include "polysquare/core/region.h"
#include "polysquare/io/mesh_groups.h"

namespace polysquare {

/// How feature curves go into an MSH file. deal.II's GridIn::read_msh turns every line element into a boundary
/// face and refuses the file when one lies between two cells, whatever its physical tag (0 included), so interior
/// feature edges cannot be line elements in a file meant for every reader.
enum class MshFeatures {
  nodes,  ///< default: one physical point group "feature_<c>" per curve holding its nodes (type-15 elements);
          ///< deal.II and MFEM ignore points in 2D, Gmsh/meshio keep them, libMesh/MOOSE read them as node sets
  lines,  ///< physical curves "feature_<c>" of line elements (Gmsh, meshio, MFEM, MOOSE; deal.II refuses them)
  none,   ///< no feature information, boundary rings only
};

/// MSH version: 2.2 is the one every FEM reader takes (MFEM and DUNE read no other); 4.1 is Gmsh's current one.
enum class MshVersion { v2_2, v4_1 };

struct MeshWriteOptions {
  bool binary = false;                         ///< binary MSH instead of ASCII
  MshFeatures msh_features = MshFeatures::nodes;
  MshVersion msh_version = MshVersion::v2_2;
  /// #nodes water depth below the datum, positive down (empty: none). SCHISM .gr3 writes it as its depth column
  /// (0 when empty), UGRID .nc as mesh2d_node_z = -depth (bed level, positive up; left out when empty), .2dm as
  /// the ND z value (0 when empty).
  std::vector<double> depth;
  /// The CRS the input was read in (InputNotes::input_crs). When it is geographic, a .gr3 gets its lon/lat
  /// companion `<stem>.ll` (hgrid.gr3 -> hgrid.ll) next to it, nodes projected back from mesh.crs to EPSG:4326.
  std::string input_crs;
  /// Named groups (mesh_groups(mesh, &region)): physical names and tags in MSH, open/land boundaries in gr3,
  /// nodestrings in 2dm, side sets in Exodus. Empty: mesh_groups(mesh), the generated names.
  MeshGroups groups;
  /// .pvtu: the number of .vtu pieces (0: one per kQuadsPerPiece quads, at least one).
  std::size_t pieces = 0;
  /// .pvtu written by several processes: this one writes the pieces k with k % piece_processes == piece_rank,
  /// and the .pvtu itself when piece_rank is 0.
  std::size_t piece_rank = 0, piece_processes = 1;
};

/// Quads per piece of a .pvtu when MeshWriteOptions::pieces is 0.
inline constexpr std::size_t kQuadsPerPiece = 1000000;

/// Reads a mesh by extension (.msh, .vtu, .pvtu: its pieces, nodes merged where they coincide). Quads and triangles are kept; lines of physical curves named
/// "boundary*" / "feature*" become tagged edges, and so do the cell edges joining two nodes of one physical point
/// group named "feature*" (how MshFeatures::nodes writes a curve; exact unless a curve comes back within one
/// element of itself, where such an edge may join two nodes that are not consecutive along it). A mesh whose cells are mostly clockwise (a surface with normal
/// -z, as Gmsh makes from a clockwise outline) is reversed, so quads are counter-clockwise as QuadMesh requires.
/// Throws InputError on malformed or truncated files.
QuadMesh read_mesh(const std::filesystem::path& path);
/// read_mesh for one format, whatever the extension.
QuadMesh read_msh(const std::filesystem::path& path);
QuadMesh read_vtu(const std::filesystem::path& path);
QuadMesh read_pvtu(const std::filesystem::path& path);
/// The same readers on file contents already in memory; `name` is used in messages (fuzzing, pipes).
QuadMesh parse_msh(const std::string& data, const std::string& name);
QuadMesh parse_vtu(const std::string& xml, const std::string& name);

/// Writes by extension, atomically. .msh = Gmsh MSH 2.2 or 4.1 with the physical groups of options.groups
/// (mesh_groups.h): the quads are physical surface "domain" (tag 1; one surface per domain name when the input
/// names them), boundary ring r is physical curve "boundary_ring_<r>" of line elements (tags 2, 3, ... in ring
/// order, which deal.II and MFEM take as boundary ids; with segments, the part of the ring no segment covers),
/// feature curve c is "feature_<c>" or its name (the next tags) as options say, then every named boundary
/// segment a physical curve of line elements; .exo = Exodus II (write_exodus);
/// .vtu = VTK XML with per-cell quality fields; .pvtu = the same in pieces (write_pvtu); .gr3 = SCHISM hgrid (write_gr3), .nc = D-Flow FM UGRID-1.0 net
/// file (write_ugrid), .2dm = SMS (write_2dm), see solver_files.h.
void write_mesh(const std::filesystem::path& path, const QuadMesh& mesh, const MeshWriteOptions& options = {});
/// The extension of `path` in lower case, with its dot (".msh"; empty when there is none).
std::string lower_extension(const std::filesystem::path& path);

/// write_mesh for one format, whatever the extension.
void write_msh(const std::filesystem::path& path, const QuadMesh& mesh, const MeshWriteOptions& options = {});
void write_vtu(const std::filesystem::path& path, const QuadMesh& mesh);
/// A parallel VTK file: `pvtu_pieces(mesh, pieces)` pieces `<stem>_<k>.vtu` beside `path`: the quads in the order
/// of their subregion (quad_part) cut into runs of nearly equal length, each with the nodes its quads use (nodes
/// on a seam are in both pieces), written in parallel; `path` lists them. All are committed together.
void write_pvtu(const std::filesystem::path& path, const QuadMesh& mesh, std::size_t pieces, std::size_t piece_rank = 0,
                std::size_t piece_processes = 1);
/// Piece k of a .pvtu: `<stem>_<k>.vtu` beside it.
std::filesystem::path pvtu_piece_path(const std::filesystem::path& pvtu, std::size_t k);
/// The number of pieces write_pvtu makes of `mesh` when asked for `pieces` (0: automatic).
std::size_t pvtu_pieces(const QuadMesh& mesh, std::size_t pieces);
/// Exodus II (.exo) through netCDF (classic, 64-bit offset; no Debian package has an Exodus library): one element
/// block of QUAD4 per surface group (eb_names, ids = tags), one side set per boundary group (the rest of each ring
/// and every named segment; side k joins a quad's local nodes k-1 and k, 1-based), one node set per boundary and
/// feature group (ns_names, ids = tags); coordinates coordx/coordy. Written atomically.
void write_exodus(const std::filesystem::path& path, const QuadMesh& mesh, const MeshWriteOptions& options = {});

}  // namespace polysquare
