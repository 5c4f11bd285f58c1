// Mesh files: Gmsh MSH (read 2.2 and 4.1, ASCII and binary; write 4.1), VTK XML .vtu (write; read ASCII).
#pragma once

#include <filesystem>
#include <string>

#include "polysquare/core/quad_mesh.h"
#include "polysquare/core/region.h"

namespace polysquare {

struct MeshWriteOptions {
  bool binary = false;  ///< binary MSH 4.1 instead of ASCII
};

/// Reads a mesh by extension (.msh, .vtu). Quads and triangles are kept; lines of physical curves named
/// "boundary*" / "feature*" become tagged edges. A mesh whose cells are mostly clockwise (a surface with normal
/// -z, as Gmsh makes from a clockwise outline) is reversed, so quads are counter-clockwise as QuadMesh requires.
/// Throws InputError on malformed or truncated files.
QuadMesh read_mesh(const std::filesystem::path& path);
QuadMesh read_msh(const std::filesystem::path& path);
QuadMesh read_vtu(const std::filesystem::path& path);
/// The same readers on file contents already in memory; `name` is used in messages (fuzzing, pipes).
QuadMesh parse_msh(const std::string& data, const std::string& name);
QuadMesh parse_vtu(const std::string& xml, const std::string& name);

/// Writes by extension, atomically: .msh = Gmsh MSH 4.1 with the quads as physical surface "domain" and tagged
/// physical curves "boundary_ring_<r>" and "feature_<c>"; .vtu = VTK XML with per-cell quality fields.
void write_mesh(const std::filesystem::path& path, const QuadMesh& mesh, const MeshWriteOptions& options = {});
void write_msh(const std::filesystem::path& path, const QuadMesh& mesh, const MeshWriteOptions& options = {});
void write_vtu(const std::filesystem::path& path, const QuadMesh& mesh);

}  // namespace polysquare
