// A picture of a mesh: quads coloured by scaled Jacobian, boundary and feature edges drawn thick.
#pragma once

#include <filesystem>

#include "polysquare/core/quad_mesh.h"
#include "polysquare/core/region.h"

namespace polysquare {

struct SvgOptions {
  int width_px = 1200;  ///< picture width; the height follows the aspect ratio
};

/// Writes an SVG (atomically). `region`, when given, is drawn as a thin outline under the mesh.
void write_svg(const std::filesystem::path& path, const QuadMesh& mesh, const Region* region = nullptr,
               const SvgOptions& options = {});

}  // namespace polysquare
