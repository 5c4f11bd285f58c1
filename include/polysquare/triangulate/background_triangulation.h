// Stage 2: the background triangulation of one polygon part, conforming to its rings and feature curves.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

#include "polysquare/core/geometry.h"
#include "polysquare/core/region.h"

namespace polysquare {

struct TriangulationOptions {
  double boundary_edge = 1.0; ///< rings and feature curves are split into pieces no longer than this (region units)
  double max_edge = 1.0;      ///< longest edge of an interior triangle; the mesher grades from boundary_edge up
  double shape_bound = 0.125; ///< CGAL bound B on circumradius / shortest edge squared / 4: 0.125 = 20.7 degrees
  std::size_t max_triangles = 20'000'000;  ///< refuse to refine beyond this (memory guard)
  bool split_constrained_edges = true;  ///< split interior edges joining two constrained vertices (corner ears)
};

/// A constrained chain of triangulation vertices: an input ring (closed) or a feature curve (closed or open),
/// with the Steiner points CGAL inserted on it, in input order.
struct TriChain {
  enum class Kind : std::uint8_t { ring, feature, separator };  ///< separator: between two partition parts
  Kind kind = Kind::ring;
  int index = -1;            ///< ring or feature index in the Region
  bool closed = false;       ///< closed chains do not repeat their first vertex
  std::vector<std::int32_t> vertices;
  std::vector<std::uint8_t> is_input;  ///< per chain vertex: 1 if it is an input vertex (not a Steiner point)
  int interface = -1;        ///< PPM subregion meshes: the neighbouring subregion across this piece of the
                             ///< boundary (both sides must get the same nodes); -1 elsewhere
};

/// A triangle mesh of one part in flat arrays.
struct TriMesh {
  std::vector<Vec2> vertices;                          ///< #V positions
  std::vector<std::array<std::int32_t, 3>> triangles;  ///< #T vertex indices, counter-clockwise
  std::vector<TriChain> chains;                        ///< rings of the part, then its feature curves
  std::vector<std::int32_t> feature_point_vertices;    ///< vertices of isolated feature points
  /// Closed boundary loops made of several open chains (PPM subregions: ring pieces and interfaces), each a
  /// cyclic list of chain indices traversed forward; the labelling closes every loop as one poly-square loop.
  std::vector<std::vector<int>> loops;
};

/// One polygon part of a region: the indices of its rings and of the feature curves and points inside it.
struct RegionPart {
  int part = 0;
  std::vector<int> rings;
  std::vector<int> features;
  std::vector<int> feature_points;
};

/// The one or two triangles of every edge (second -1 on the boundary), by edge_key.
std::unordered_map<std::uint64_t, std::array<std::int32_t, 2>> edge_owners(const TriMesh& mesh);

/// Splits every interior edge whose two end points lie on chains (e.g. the edge cutting off a corner ear), so
/// that straightening the chains never squeezes a triangle to zero area. When `parent` is given it receives,
/// for every triangle after the split, the index of the triangle it came from.
void split_constrained_interior_edges(TriMesh& mesh, std::vector<std::int32_t>* parent = nullptr);

/// #V: 1 for every vertex that must be a mesh node whatever the map does: open chain ends, input vertices
/// turning by more than `corner_threshold_deg` at `positions` (input coordinates), isolated feature points and
/// vertices where chains meet (crossings, features ending on the boundary).
std::vector<std::uint8_t> corner_vertices(const TriMesh& mesh, const std::vector<Vec2>& positions,
                                          double corner_threshold_deg);

/// Name of a chain for messages: "ring 2", "feature 5", "separator 1".
std::string chain_name(const TriChain& chain);

/// Area of a polygon part: its outer ring minus its holes (rings are oriented that way by validation).
double part_area(const Region& region, const RegionPart& part);

/// Groups the rings, features and feature points of a validated region by polygon part.
std::vector<RegionPart> split_into_parts(const Region& region);

/// Constrained Delaunay triangulation of `part`, refined by CGAL's Delaunay mesher to `options.max_edge`.
/// Rings and feature curves are constraints; they come back as chains of triangulation vertices.
/// Throws MeshingError when refinement would exceed options.max_triangles.
TriMesh triangulate_part(const Region& region, const RegionPart& part, const TriangulationOptions& options);

}  // namespace polysquare
