// Internal to the partition module and its tests: the triangulation's edges as the arcs of its dual graph, the
// terms of E = L_S + lambda1 D_theta - lambda2 D_f (FPPM eqs. 2-6), and what moving one triangle changes.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "polysquare/partition/partition.h"

namespace polysquare::partition_detail {

/// The unique edges of a TriMesh with the triangles on either side, the edges around every vertex, and the
/// triangle areas. Lengths are in mean edge lengths (see PartitionEnergy).
struct PartitionGraph {
  struct Edge {
    std::int32_t a = -1, b = -1;    ///< end vertices
    std::int32_t t0 = -1, t1 = -1;  ///< the triangles on either side; t1 = -1 on the mesh boundary
    double length = 0;              ///< in mean edge lengths
    bool feature = false;           ///< a segment of a feature chain
  };
  std::vector<std::array<std::int32_t, 3>> triangles;  ///< #T x 3 vertex ids (copied from the mesh)
  std::vector<Edge> edges;                             ///< #E, in order of first appearance in the triangles
  std::vector<std::array<std::int32_t, 3>> tri_edges;  ///< #T x 3: edge k of triangle t joins its vertices k, k+1
  std::vector<std::size_t> vertex_offset;  ///< #V + 1: the incidences of vertex v are [offset[v], offset[v + 1])
  std::vector<std::int32_t> incident_edge;        ///< per incidence: the edge
  std::vector<double> incident_direction;         ///< per incidence: direction (radians) of the edge leaving v
  std::vector<double> area;                       ///< #T triangle areas, region units squared
  double unit_length = 1;                         ///< the mean edge length in region units
  double feature_length = 0;                      ///< total length of the feature edges, in mean edge lengths

  explicit PartitionGraph(const TriMesh& mesh);

  bool separator(std::size_t e, const std::vector<std::int32_t>& part) const {
    return edges[e].t1 >= 0 && part[edges[e].t0] != part[edges[e].t1];
  }
  /// The triangle across edge k of t, or -1 on the boundary.
  std::int32_t neighbour(std::size_t t, int k) const {
    const Edge& e = edges[tri_edges[t][k]];
    return e.t0 == static_cast<std::int32_t>(t) ? e.t1 : e.t0;
  }
  std::size_t vertex_count() const { return vertex_offset.size() - 1; }
};

/// delta_theta of eq. 3 for the angle theta in [0, pi] between two edges leaving one vertex: the distance to the
/// nearer of pi/2 and pi (k pi/2 with k >= 1, as in eq. 3; so a spike, theta near 0, costs up to pi/2).
double angle_deviation(double theta);

/// The D_theta terms at vertex v: every pair of separator edges leaving v, and with options.angle_at_rings every
/// pair of a separator edge and a mesh boundary edge leaving v.
double vertex_angle_term(const PartitionGraph& graph, std::int32_t v, const std::vector<std::int32_t>& part,
                         const PartitionOptions& options);

/// The full energy of a partition (#T part ids).
PartitionEnergy energy_of(const PartitionGraph& graph, const std::vector<std::int32_t>& part,
                          const PartitionOptions& options);

/// The change of E when triangle t moves to part `to`, from t's three edges and the angle terms at its three
/// vertices only (nothing else changes). `part` is modified during the call and restored.
double move_delta(const PartitionGraph& graph, std::vector<std::int32_t>& part, std::int32_t t, std::int32_t to,
                  const PartitionOptions& options);

/// Whether moving t to part `to` keeps both affected parts locally disk-like: around each vertex of t, the
/// triangles of t's old part, and those of `to`, form at most one edge-connected fan each afterwards. If the old
/// part was edge-connected it stays so (t's same-part neighbours stay joined through the fan at their common
/// vertex), and no part comes to touch itself at a single vertex.
bool move_keeps_parts_simple(const PartitionGraph& graph, const std::vector<std::int32_t>& part, std::int32_t t,
                             std::int32_t to);

}  // namespace polysquare::partition_detail
