// Pictures of a mesh through Cairo: PNG for any size, SVG for small meshes. Quads are coloured by a measure with
// a colour bar giving its scale (shape, or size against a graded run's field) or by subregion, singular nodes are
// marked by valence, boundary and feature edges drawn on top; quad edges only where they are far enough apart on
// the picture to be seen.
#pragma once

#include <array>
#include <cstddef>
#include <filesystem>
#include <optional>
#include <string_view>

#include "polysquare/core/geometry.h"
#include "polysquare/core/quad_mesh.h"
#include "polysquare/core/region.h"

namespace polysquare {

class SizeField;

enum class RenderColor {
  sj,             ///< Verdict scaled Jacobian of each quad, [0, 1], red (bad) to green (1)
  skew,           ///< equiangle skew (paper eq. 16), [0, 1], green (0) to red (1)
  part,           ///< subregion (QuadMesh::quad_part), one of 12 colours each
  singularities,  ///< quads plain grey, so the valence marks stand out
  size_ratio,     ///< sqrt(quad area) / h(centroid) of RenderOptions::size_field (quad_size_ratio), log scale:
                  ///< 0.5 (or less) blue, 1 pale green, 2 (or more) red
};

struct RenderOptions {
  RenderColor color = RenderColor::sj;
  const SizeField* size_field = nullptr;  ///< the graded run's field, for size_ratio (required there), in the
                                          ///< mesh's coordinates; not owned
  std::optional<Box2> window;        ///< the part of the plane shown, region units; none = the whole mesh
  int width_px = 1600;               ///< picture width in pixels (PNG) or user units (SVG), colour bar included;
                                     ///< the height follows the window's aspect ratio (at most 16000)
  std::size_t svg_max_quads = 50'000;  ///< an SVG showing more quads than this is refused (InputError): use PNG
  double min_edge_px = 4.0;          ///< quad edges are drawn only when the median quad edge in the window is at
                                     ///< least this long on the picture (level of detail: big meshes read as
                                     ///< colour fields instead of black)
};

struct RenderStats {
  int width_px = 0, height_px = 0;
  double plot_x0 = 0, plot_y0 = 0, scale = 0;  ///< plane (x, y) is drawn at (plot_x0 + scale (x - window.lo.x),
                                               ///< plot_y0 + scale (window.hi.y - y)) pixels
  Box2 window;                       ///< the window drawn (the requested one, or the mesh's box with a margin)
  std::size_t quads_drawn = 0;       ///< quads meeting the window
  bool edges_drawn = false;          ///< quad edges drawn (level of detail)
  std::size_t singular_nodes_marked = 0;
  double mark_radius_px = 0;         ///< radius of the valence marks (discs, and rings along their stroke)
  double value_min = 0, value_max = 0;  ///< range of the measure over the quads drawn (sj, skew, size_ratio)
  double bar_x0 = 0, bar_y0 = 0, bar_w = 0, bar_h = 0;  ///< the colour bar's rectangle, pixels (0 without one):
                                                        ///< measure 0 at its bottom edge, 1 at its top edge
                                                        ///< (size_ratio: 0.5 and 2, log scale)
};

/// Colour (RGB in [0, 1]) marking a singular node: one edge fewer than regular (interior valence 3, boundary 2)
/// blue, one more (5; boundary 4) orange, two or more extra magenta. Interior nodes are filled discs, boundary
/// nodes rings; regular nodes (interior 4, boundary 3) are not marked.
std::array<double, 3> valence_color(int valence, bool boundary);

/// The colour of a measure value (sj, skew, or a size ratio) on the picture and its colour bar.
std::array<double, 3> measure_color(RenderColor color, double value);

/// Draws `mesh` (and `region`'s rings and feature curves as thin lines, when given) into `path`: .png or .svg,
/// written atomically. Throws InputError for another extension, an empty window, an SVG of too many quads, or
/// size_ratio without a size field.
RenderStats render_mesh(const std::filesystem::path& path, const QuadMesh& mesh, const Region* region = nullptr,
                        const RenderOptions& options = {});

/// "sj", "skew", "part", "singularities", "size" (size_ratio); throws InputError otherwise.
RenderColor parse_render_color(std::string_view text);
/// "x0,y0,x1,y1" (any two opposite corners); throws InputError unless four finite numbers spanning an area.
Box2 parse_window(std::string_view text);

}  // namespace polysquare
