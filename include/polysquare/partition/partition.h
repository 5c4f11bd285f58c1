// Stage 3: feature-aware graph partitioning of a background triangulation (FPPM Sec. 3).
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <vector>

#include "polysquare/size/size_field.h"
#include "polysquare/triangulate/background_triangulation.h"

namespace polysquare {

struct PartitionOptions {
  int parts = 0;                                ///< k; 0 = from target_triangles_per_part
  std::size_t target_triangles_per_part = 2000; ///< used when parts = 0
  double lambda_angle = 1.0;                    ///< lambda1 of E = L_S + lambda1 D_theta - lambda2 D_f
  double lambda_feature = 1.0;                  ///< lambda2
  double lambda_mh = 0.01;                      ///< Metropolis-Hastings inverse temperature (Sec. 3.4)
  double balance = 0.1;                         ///< c1 = c2: every part's area within (1 +- balance) * mean (eq. 1)
  int mh_sweeps = 50;                           ///< sweeps over the triangles on part boundaries
  double mh_anneal = 100.0;                     ///< the inverse temperature grows from lambda_mh to this multiple
  std::uint64_t seed = 1;                       ///< METIS seed and the MH random stream
  /// Feature faces (connected components of triangles joined across edges that are not feature edges) below this
  /// area merge into the neighbouring face they share the most feature length with; 0 keeps every face that is
  /// not enclosed by a single other face. map_part sets 16 h^2 when it is 0 (a subregion of 4 x 4 quads).
  double min_face_area = 0;
  /// Graded meshes: triangles weigh their area times (size_ref / h)^2, h the field at their centroid, so that
  /// parts hold similar numbers of quads; every area above (balance, min_face_area) is then such a weight.
  std::shared_ptr<const SizeField> size_field;
  double size_ref = 1.0;
};

/// The terms of E (eqs. 2, 4, 6), with lengths in hundredths of the mean triangle edge length, so that the
/// paper's lambda_MH = 0.01 rejects a move that lengthens the separators by one edge with probability 1 - 1/e.
struct PartitionEnergy {
  double separator_length = 0;     ///< L_S: total length of edges between different parts
  double angle_deviation = 0;      ///< D_theta (radians, times 100): at every vertex, for every pair of incident
                                   ///< separator edges, and of a separator edge with a boundary edge, the angle
                                   ///< between them minus the nearest multiple of 90 degrees (eq. 3)
  double feature_on_separators = 0;///< D_f: total length of feature edges that are separator edges
  double energy = 0;               ///< L_S + lambda1 D_theta - lambda2 D_f
};

struct PartitionResult {
  std::vector<std::int32_t> triangle_part;  ///< #T part of each triangle, 0 .. parts-1
  int parts = 0;                            ///< max(k, faces): every face gets at least one part
  int faces = 1;                            ///< feature faces partitioned separately (after merging, see below)
  PartitionEnergy metis, final;             ///< energies of METIS's partition and after MH and repair
  double feature_fraction_metis = 0;        ///< feature length on separators / feature length, METIS alone
  double feature_fraction_final = 0;
  double balance_max_over_avg = 0;          ///< largest part area / mean part area of its face
  std::size_t mh_proposed = 0, mh_accepted = 0;
  std::size_t repaired_triangles = 0;       ///< triangles moved to make every part connected
};

/// Dual graph (node weight = triangle area, arc weight = shared edge length), METIS k-way partition, then
/// Metropolis-Hastings moves of boundary triangles on E under the balance constraint, never disconnecting a
/// part; the lowest-energy state seen is kept; finally every part is made connected. Deterministic given
/// options.seed, single-threaded.
///
/// Feature faces first: when feature curves cut the triangulation into several faces, each face is partitioned
/// on its own and no part ever spans two faces, so every face boundary (a feature between two faces) is a
/// separator. A face enclosed by a single other face (an island inside a closed feature loop: its loop has no
/// junction to close a poly-square on) merges into that face, and so does a face smaller than
/// options.min_face_area (into the neighbour it shares the most feature length with); repeatedly. The parts,
/// max(k, faces), are dealt to the faces by half their share of area and half their share of boundary length
/// (ring and feature edges), at least one each (largest remainders); METIS runs on each face's subgraph, and
/// Metropolis-Hastings moves and the connectivity repair stay inside faces, with the balance of eq. 1 measured
/// against the mean part area of each face. One face is exactly the whole-graph partition.
PartitionResult partition_triangles(const TriMesh& mesh, const PartitionOptions& options);

/// The full energy of a partition (the MH moves use local differences of the same terms).
PartitionEnergy partition_energy(const TriMesh& mesh, const std::vector<std::int32_t>& triangle_part,
                                 const PartitionOptions& options);

/// A picture of the partition: triangles coloured by part, separators black, feature edges red.
void write_partition_svg(const std::filesystem::path& path, const TriMesh& mesh, const PartitionResult& result,
                         int width_px = 1000);

}  // namespace polysquare

namespace polysquare {

/// Adds the separators of a triangle partition to `mesh` as chains of kind separator: the edges between
/// triangles of different parts, cut into open chains at junctions (vertices where separators branch or meet a
/// ring or feature chain); separator loops without junctions become closed chains. Returns the number added.
std::size_t add_separator_chains(TriMesh& mesh, const std::vector<std::int32_t>& triangle_part);

/// Keeps each part in one piece when its feature curves count as walls: every smaller piece a feature cuts off
/// (a sliver between a feature and a separator, part of a feature loop's inside) moves to the neighbouring part
/// it shares the most non-feature edge length with; repeated until nothing moves (at most max_rounds). Pieces
/// enclosed by features alone stay. Returns the number of triangle moves.
std::size_t absorb_pieces_cut_off_by_features(const TriMesh& mesh, std::vector<std::int32_t>& triangle_part,
                                              int max_rounds = 10);

/// Merges every part whose outer loop faces one other part only, touching no third part and no ring (a part
/// enclosed by another: that loop has no corner to close a poly-square on), into that part, repeatedly, whatever
/// the part holds inside; renumbers the parts 0 .. k-1 keeping their order. Returns the new number of parts.
int merge_enclosed_parts(const TriMesh& mesh, std::vector<std::int32_t>& triangle_part);

/// Gives every closed feature loop, its inside and the triangles touching it to the part that holds most of that
/// area, so no separator touches the loop (a loop cut by a separator leaves two-sided faces no poly-square can
/// hold); a move that would disconnect a part is undone. Returns the number of triangles moved.
std::size_t keep_feature_loops_whole(const TriMesh& mesh, std::vector<std::int32_t>& triangle_part);

/// Makes every part meet each vertex in one fan: where a part's triangles around a vertex form two or more
/// fans (the part touches itself there, and its boundary is no simple loop), a smaller fan moves to the part it
/// borders most if the part stays one piece without it; otherwise the part takes the smallest fan of another
/// part there that stays one piece without it; otherwise the smallest part around the vertex joins it whole
/// (part numbers then have gaps: renumber, e.g. with merge_enclosed_parts). At most max_rounds passes.
/// Returns the number of triangles moved.
std::size_t separate_pinched_parts(const TriMesh& mesh, std::vector<std::int32_t>& triangle_part, int max_rounds = 3);
/// Moves separator ends that meet a ring within `max_edges` ring edges of a sharp corner (an input vertex turning
/// by more than corner_threshold_deg) onto the corner, by handing the triangles around the ring vertices in
/// between to the neighbouring part (kept only if both parts stay connected): otherwise the corner and the end
/// make a side far shorter than one element. An end where a feature meets the ring stays (the separator runs
/// along the feature). Returns the number of triangles moved.
std::size_t snap_separator_ends_to_corners(const TriMesh& mesh, std::vector<std::int32_t>& triangle_part,
                                           double corner_threshold_deg, int max_edges = 2);

/// Straightens the zig-zag of separator chains (paths of triangle edges): their free vertices move half-way to
/// the midpoint of their chain neighbours, `iterations` times, each move kept only while every incident
/// triangle keeps at least a tenth of its area. Vertices on rings, features and junctions never move.
/// Returns the number of moves.
std::size_t straighten_separator_chains(TriMesh& mesh, int iterations);

}  // namespace polysquare
