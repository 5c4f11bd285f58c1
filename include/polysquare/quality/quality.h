// Stage 9: quality figures, defined below, for our meshes and for other tools' meshes.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "polysquare/core/geometry.h"
#include "polysquare/core/place_text.h"
#include "polysquare/core/quad_mesh.h"
#include "polysquare/core/region.h"

namespace polysquare {

struct Stats {
  double min = 0, avg = 0, max = 0, std = 0;  ///< std is the population standard deviation
  std::size_t count = 0;
};

/// Per-quad metrics (#quads each). Corner scaled Jacobian = cross(e_next, e_prev) / (|e_next| |e_prev|).
struct QuadMetrics {
  std::vector<double> sj;          ///< Verdict scaled Jacobian: minimum over the four corners
  std::vector<double> eta;         ///< paper's eta: mean over the four corners
  std::vector<double> skew;        ///< paper eq. 16 = Verdict quad_equiangle_skew
  std::vector<double> edge_ratio;  ///< longest / shortest edge
};
/// The metrics of every quad of `mesh` (triangles are left out).
QuadMetrics quad_metrics(const QuadMesh& mesh);

/// SCHISM's quality checks of quads, as SCHISM's own tools define them (the grid-generation chapter of the SCHISM
/// manual, https://schism-dev.github.io/schism/master/getting-started/grid-generation.html, "Mesh quality": quads
/// are checked in xmgredit5 with a cutoff of 0.5 on "the ratio between the min and max interior angles", and bad
/// quads are split by the pre-processing script fix_bad_quads.f90, whose inputs are a threshold for that angle
/// ratio (e.g. 0.5) and one for the quad aspect ratio, longest over shortest side (e.g. 5); a concave quad is
/// always split). Per quad: angle_ratio = smallest / largest interior angle (1 for a rectangle; 0 for a quad with a
/// reflex or inverted corner, which SCHISM splits whatever the thresholds); aspect_ratio = longest / shortest side
/// (the same figure as QualityReport::edge_ratio). A quad with a zero-length side has angle ratio 0 and aspect ratio
/// 1e300 (as edge_ratio).
struct SchismQuadQuality {
  double angle_ratio_limit = 0.5;     ///< quads below it fail (xmgredit5's and fix_bad_quads' example cutoff)
  double aspect_ratio_limit = 5.0;    ///< quads above it fail (fix_bad_quads' example threshold)
  Stats angle_ratio;                  ///< over quads, in [0, 1]
  Stats aspect_ratio;                 ///< over quads, >= 1
  std::size_t non_convex = 0;         ///< quads with a corner of 180 degrees or more (or inverted, or degenerate)
  std::size_t angle_ratio_below = 0;  ///< quads with angle_ratio < angle_ratio_limit (the non-convex ones included)
  std::size_t aspect_ratio_above = 0; ///< quads with aspect_ratio > aspect_ratio_limit
  std::size_t failing = 0;            ///< quads failing either check: those fix_bad_quads would split
  Vec2 angle_ratio_worst_at{};        ///< centre (mean of the nodes) of the quad with the smallest angle ratio
  Vec2 aspect_ratio_worst_at{};       ///< centre of the quad with the largest aspect ratio
};
/// #quads SCHISM angle ratio of each quad of `mesh` (see SchismQuadQuality).
std::vector<double> schism_angle_ratios(const QuadMesh& mesh);
/// SCHISM's quad checks over the quads of `mesh` (triangles are left out) with the given cutoffs.
SchismQuadQuality schism_quad_quality(const QuadMesh& mesh, double angle_ratio_limit = 0.5,
                                      double aspect_ratio_limit = 5.0);
/// The report's `quality.schism` block (keys in schema/report.schema.json) and its one-line text; `place`
/// writes its places (the CLI's lon/lat of reprojected input), empty: "x, y" as they are.
nlohmann::json to_json(const SchismQuadQuality& q);
std::string format_schism_text(const SchismQuadQuality& q, const PlaceWriter& place = {});

struct QualityReport {
  std::size_t nodes = 0, quads = 0, triangles = 0;
  std::size_t inverted = 0;            ///< quads with SJ <= 0
  std::size_t non_manifold_edges = 0;  ///< edges with more than two cells
  std::size_t boundary_edges = 0;      ///< edges with one cell
  Stats sj, eta, skew, edge_ratio;     ///< over quads
  std::size_t singularities = 0;            ///< paper: boundary valence != 3 plus interior valence != 4
  std::size_t interior_singularities = 0;   ///< interior vertices of valence != 4
  std::size_t boundary_singularities = 0;   ///< boundary vertices of valence != 3
  double regular_quad_fraction = 0;         ///< quads with no interior singular node among their four: how much
                                            ///< of the mesh is semi-structured, wherever its quads came from
  double sj_below_0_3_fraction = 0;         ///< quads whose scaled Jacobian is below 0.3
  SchismQuadQuality schism;                 ///< SCHISM's quad checks, default cutoffs (schism_quad_quality)
};
/// Valence counts the distinct quad edges at a vertex; triangles (from other tools) are not counted, as in the Gmsh
/// reference figures of data/cases/PROVENANCE.md. non_manifold_edges and boundary_edges are over the quads too.
QualityReport compute_quality(const QuadMesh& mesh);
/// Throws InputError naming `name` when `mesh` cannot be judged by compute_quality: it has no quadrilateral (no
/// cells, or triangles only: figures over no quads would read as a perfect or a zero mesh), or a node of a cell
/// has a non-finite coordinate (the node and its coordinate are named).
void check_judgeable(const QuadMesh& mesh, const std::string& name);
/// The same from per-quad metrics already computed for `mesh` (quad_metrics); `interior_singular`, when given,
/// gets #nodes flags of the nodes counted in interior_singularities.
QualityReport compute_quality(const QuadMesh& mesh, const QuadMetrics& metrics,
                              std::vector<std::uint8_t>* interior_singular = nullptr);

/// #quads: 1 for a quad with an acute corner at an input corner node (NodeKind::corner) whose two edges both lie
/// on input curves (tagged boundary or feature edges) and whose corner scaled Jacobian is below `below`. Such a
/// corner spans the angle the input gives (two curves crossing at 3 degrees allow no better than sin 3 degrees
/// in any conforming mesh), so quality gates leave these quads out and report them apart. With `reach` > 0, also
/// every quad whose centre lies inside such a wedge (two curves at a corner node, less than asin(below) apart,
/// no other curve between them) within `reach` of its tip, reached from the tip through such quads: the wedge is
/// narrower than below * reach there, so at element size `reach` the quads must span it.
std::vector<std::uint8_t> quads_pinned_by_sharp_input(const QuadMesh& mesh, double below, double reach = 0.0);

struct DomainDistanceOptions {
  double corner_threshold_deg = 30.0;  ///< input vertices turning more than this must be mesh nodes
  std::vector<int> skip_parts;         ///< polygon parts left out of the mesh (smaller than one element): their
                                       ///< rings count neither in the area nor as sharp vertices
};
struct DomainDistance {
  double boundary_max_distance = 0;  ///< max over mesh boundary nodes of the distance to the input rings
  double boundary_max_relative = 0;  ///< the same divided by the region's bounding-box diagonal
  double feature_max_distance = 0;   ///< max over samples of the feature curves of the distance to the mesh edges
  double feature_node_max_distance = 0;  ///< max over mesh feature nodes of the distance to the feature curves
  Vec2 feature_max_at{}, feature_node_max_at{};  ///< where those two maxima are (the curve sample, the node)
  double area_relative_change = 0;   ///< (mesh area - region area) / region area
  std::size_t sharp_vertices_total = 0, sharp_vertices_missing = 0;
};
/// How closely `mesh` follows `region` (the input before simplification, for the report): boundary and feature
/// distances, area change, sharp input vertices that are not mesh nodes.
DomainDistance domain_distance(const QuadMesh& mesh, const Region& region, const DomainDistanceOptions& options = {});

/// Sum of the quads' signed areas (counter-clockwise positive), each taken relative to its first node.
double mesh_area(const QuadMesh& mesh);
/// Area of the region's parts (outer rings minus holes), leaving out `skip_parts`; each ring summed relative to
/// its first point, so coordinates far from the origin keep their digits.
double domain_area(const Region& region, const std::vector<int>& skip_parts = {});
/// (mesh_area - domain_area) / domain_area of `region` without `skip_parts`. Mesh edges are chords of curved
/// input (0.05 % to 0.11 % on smile, key, mechanical_part at the README's sizes; more on a circle met by a few
/// chords with --simplify 0), so this is a check for a wrong region (a lake meshed as land), which callers warn
/// about above a bound of their choice (the CLI: 1 %).
double area_relative_mismatch(const QuadMesh& mesh, const Region& region, const std::vector<int>& skip_parts);

/// Faces are the quads (indices 0 .. #quads-1) then the triangles (#quads ..). Edges in order of first appearance
/// along the faces' sides, each oriented as the first face that has it walks it.
struct EdgeTable {
  std::vector<std::array<std::int32_t, 2>> nodes;  ///< #edges by 2 node indices
  std::vector<std::array<std::int32_t, 2>> faces;  ///< #edges by 2 face indices; faces[e][1] = -1 on the boundary
                                                   ///< (and for the third face of a non-manifold edge, not kept)
};
EdgeTable edge_table(const QuadMesh& mesh);

/// #faces cell centres as D-Flow FM and MeshKernel (MeshFaceCenters, default settings) define them, the points
/// the finite-volume fluxes are exchanged between: a triangle's circumcentre; a face with two or more interior
/// edges (edges shared with another face) starts at the mean of its nodes and takes 100 relaxation steps (or
/// until it moves less than 1e-15) that pull it a tenth of the way onto the perpendicular bisector of each interior
/// edge in turn, from the previous step's point (towards the least-squares point of those bisectors; the centre
/// of a parallelogram, where it starts, is that point); with
/// one interior edge the mean of its nodes, with none the centroid of its area. A centre that ends outside its
/// face is moved back along the line from the mean of the nodes to where that line leaves the face.
std::vector<Vec2> face_circumcentres(const QuadMesh& mesh, const EdgeTable& edges);

/// D-Flow FM's grid checks, per interior edge (MeshKernel's MeshOrthogonality and MeshSmoothness):
/// orthogonality = |cos| of the angle between the edge and the link joining the circumcentres of its two faces
/// (0 is ideal; D-Flow FM refuses nets above 0.5); smoothness = the larger over the smaller area of its two faces.
struct FiniteVolumeQuality {
  std::size_t interior_edges = 0;
  double orthogonality_limit = 0.5;
  Stats orthogonality;                  ///< over interior edges
  std::size_t orthogonality_above = 0;  ///< interior edges with orthogonality > orthogonality_limit
  Vec2 orthogonality_worst_at{};        ///< midpoint of the edge with the largest orthogonality
  Stats smoothness;                     ///< over interior edges
  Vec2 smoothness_worst_at{};           ///< midpoint of the edge with the largest smoothness
};
/// Orthogonality and smoothness over the interior edges of `mesh` (quads and triangles), worst places included.
FiniteVolumeQuality finite_volume_quality(const QuadMesh& mesh, double orthogonality_limit = 0.5);
/// #edges orthogonality of each edge of `edges` (-1 on boundary edges), from `centres` (face_circumcentres).
std::vector<double> edge_orthogonality(const QuadMesh& mesh, const EdgeTable& edges, const std::vector<Vec2>& centres);

/// The report's `quality.finite_volume` block (keys in schema/report.schema.json) and its one-line text; `place`
/// as format_schism_text's.
nlohmann::json to_json(const FiniteVolumeQuality& q);
std::string format_finite_volume_text(const FiniteVolumeQuality& q, const PlaceWriter& place = {});

/// The report's `quality` and `domain` blocks (see schema/report.schema.json; add_quality_to_report adds the
/// figures relative to the size).
nlohmann::json to_json(const QualityReport& q);
nlohmann::json to_json(const DomainDistance& d);
/// The blocks above read back (MeshReport's from_json; a Stats' count is not in the JSON and stays 0).
void from_json(const nlohmann::json& j, SchismQuadQuality& q);
void from_json(const nlohmann::json& j, FiniteVolumeQuality& q);
void from_json(const nlohmann::json& j, QualityReport& q);
void from_json(const nlohmann::json& j, DomainDistance& d);
/// Human-readable table, one figure per line; `place` writes its places, empty: as at_text.
std::string format_quality_text(const QualityReport& q, const DomainDistance* domain = nullptr,
                                const PlaceWriter& place = {});

}  // namespace polysquare
