// Stage 4b: from a deformed triangulation to a poly-square layout: axis labels on every boundary and feature
// edge (a 1D dynamic program per chain that trades label changes against deviation), and break points where
// labels change or where an input vertex must become a mesh node.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "polysquare/core/geometry.h"
#include "polysquare/triangulate/background_triangulation.h"

namespace polysquare {

struct LayoutOptions {
  double corner_threshold_deg = 30.0;  ///< input vertices turning by more than this become mesh nodes
  double label_change_cost = 6.0;      ///< cost of a label change (element lengths) away from sharp vertices;
                                       ///< 6 keeps smooth features straight (square_feature: SJ min 0.58 vs 0.11 at 3)
  bool straight_interfaces = true;     ///< PPM interfaces get one label (one straight side) on each side; false
                                       ///< lets them bend, the two sides then sharing every break point
  double interface_change_cost = 1.5;  ///< label change cost on a bendable interface (smile meshes at 1.5, not
                                       ///< at 6 or 0.5)
  double agree_turn_elements = 0.0;    ///< PPM: where a feature between two subregions turns on one side only, a
                                       ///< stretch of at most this many elements between two such breaks of
                                       ///< opposite sense is turned a quarter on one side (map/interface_turns.h)
                                       ///< so both sides agree; 0 = off
};

/// Axis labels: 0 = +X, 1 = +Y, 2 = -X, 3 = -Y (the direction of travel along the chain).
inline int label_axis(int label) { return label % 2; }
inline int label_sign(int label) { return label < 2 ? 1 : -1; }

/// A straight side of the poly-square between two break points of one chain.
struct LayoutSegment {
  int chain = 0;      ///< index into TriMesh::chains
  int first = 0;      ///< index of the first chain vertex
  int count = 0;      ///< number of chain edges in the segment (chain vertices first .. first+count, cyclic)
  int label = 0;      ///< axis label of every edge in the segment
  double target = 0;  ///< deformed chord length, in elements
  int break_a = -1, break_b = -1;  ///< break point indices of the two ends
};

struct Layout {
  std::vector<std::int32_t> break_vertex;   ///< #B triangulation vertex of each break point
  std::vector<std::int32_t> vertex_break;   ///< #V break point of each vertex, or -1
  std::vector<std::uint8_t> break_is_corner;///< #B 1 if an input vertex that must be a node (sharp, ends, crossings)
  std::vector<LayoutSegment> segments;
  std::vector<std::array<long long, 2>> lattice;  ///< #B integer lattice position (after quantization)
  std::vector<std::vector<int>> chain_labels;     ///< per chain, the cleaned label of each edge
  /// Joint quantization: the separations (axis, lo, hi: break point hi's lattice coordinate along the axis at
  /// least lo's + 1) that this layout's last joint quantization ended with; the next one starts from them.
  std::vector<std::array<int, 3>> separations;
};

/// Labels and break points of every chain of `mesh` deformed to `deformed` (lattice units: 1 = one element).
/// `original` holds the input coordinates used for turning angles. Throws MeshingError (naming `part_name`)
/// when a closed chain's labels do not turn by +-4 quarter turns.
Layout build_layout(const TriMesh& mesh, const std::vector<Vec2>& original, const std::vector<Vec2>& deformed,
                    const LayoutOptions& options, const std::string& part_name);

/// Adds break points that do not turn (flags `extra`, #V) to a built layout and rebuilds its sides from the
/// labels already chosen: where the other side of a bent interface has a corner, this side gets a break too.
void add_straight_breaks(Layout& layout, const TriMesh& mesh, const std::vector<Vec2>& deformed,
                         const std::vector<std::uint8_t>& extra, const std::string& part_name);

}  // namespace polysquare
