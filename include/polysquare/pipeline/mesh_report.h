// The report of a meshing run, typed: one struct per section of the JSON report (schema/report.schema.json),
// filled by mesh_region (region_report.cpp) and completed by the caller (add_quality_to_report, the CLI's input
// notes and groups). Readers use the fields; the JSON is written in one place, mesh_report.cpp, by
// nlohmann::json(report), and read back by report.get<MeshReport>() (every key of a report has a field, so the
// two round-trip; a test checks it).
//
// A std::optional field is a key the JSON has only sometimes: absent when empty. Places (`at`) are [x, y] in the
// frame the region was meshed in. Counts are std::size_t, or int where -1 means "none".
#pragma once

#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "polysquare/core/geometry.h"
#include "polysquare/quality/quality.h"

namespace polysquare {

/// `summary`'s figures from the quality of the final mesh (add_quality_to_report), absent before.
struct SummaryQuality {
  double sj_min = 0.0;
  std::size_t singularities = 0, interior_singularities = 0, boundary_singularities = 0;
  double regular_quad_fraction = 0.0, sj_below_0_3_fraction = 0.0;
};

/// `summary`: the figures a user checks first (written first, see report_text).
struct ReportSummary {
  std::size_t quads = 0;
  double structured_fraction = 0.0;  ///< quads from poly-square maps / quads
  std::size_t subregions = 0, unstructured_subregions = 0, local_patch_quads = 0;
  std::size_t poor_quads = 0;  ///< accepted outside the gates (max_poor_fraction)
  std::size_t sj_below_0_3_pinned = 0;  ///< below SJ 0.3 in input corners or wedges sharper than 17.5 degrees
  double sj_below_0_3_unpinned_fraction = 0.0;
  double seconds = 0.0;  ///< wall time of mesh_region
  std::string version;
  std::optional<SummaryQuality> quality;  ///< written flat into `summary` (sj_min, singularities, ...)
  std::optional<int> processes;           ///< the CLI under MPI
};

/// `input`'s notes, added by the CLI: what reading the file changed.
struct InputNotesReport {
  std::vector<std::string> repairs, snapped, warnings;
  std::string input_crs;
  std::size_t boundary_segments = 0;
};

/// `input`: the region as read (before simplification).
struct InputReport {
  std::string source, crs, units;
  int parts = 0;
  std::size_t rings = 0, feature_curves = 0;
  double area = 0.0;
  std::optional<InputNotesReport> notes;  ///< written flat into `input`
  std::optional<Vec2> local_origin;       ///< the CLI meshed the region relative to this point
};

/// `counts` of the assembled mesh.
struct CountsReport {
  std::size_t nodes = 0, quads = 0, boundary_edges = 0, feature_edges = 0;
};

/// `parts[].subregions[]`: how one subregion was meshed.
struct SubregionReport {
  int subregion = 0;
  std::size_t quads = 0;
  std::string meshed_by;              ///< "map" or "patch"
  Vec2 at{};
  std::size_t local_patch_quads = 0;  ///< written only when > 0
  bool untangled = false;             ///< written only when true
  std::optional<std::string> reason;  ///< why its map failed (patches)
};

/// A map's split rounds (`parts[].split`, `candidates[][].split`).
struct SplitReport {
  int rounds = 0, subregions_split = 0, maps_tried = 0, pieces_mapped = 0;
  double seconds = 0.0;
  int after_joint_map = 0;
};

struct DeformReport {
  int iterations = 0;
  double energy_before = 0.0, energy_after = 0.0, alignment_before = 0.0, alignment_after = 0.0;
};

/// `parts[].seconds`: the kept map's stage times.
struct PartSecondsReport {
  double triangulate = 0.0, deform = 0.0, quantize = 0.0, snap = 0.0, extract = 0.0, joint_maps = 0.0;
};

struct MultipassReport {
  int passes = 0, colours = 0;
  double last_move = 0.0, seconds = 0.0;
};

/// `parts[]`: one polygon part's map (PartMapStats).
struct PartReport {
  int part = 0;
  std::size_t triangles = 0;
  double rotation_deg = 0.0;
  DeformReport deform;
  SplitReport split;
  std::size_t break_points = 0, segments = 0;
  double quantization_max_relative_deviation = 0.0;
  std::size_t quads = 0;
  PartSecondsReport seconds;
  int joint_maps = 0;
  std::size_t agreed_turns = 0;
  std::size_t transition_rows = 0;
  MultipassReport multipass;
  std::vector<SubregionReport> subregions;
};

struct PartitionEnergyReport {
  double separator_length = 0.0, angle_deviation = 0.0, feature_on_separators = 0.0, energy = 0.0;
};

/// `partition[]`: the partition of a part that has one.
struct PartitionReport {
  int part = 0, subregions = 0, faces = 0;
  std::size_t separators = 0;
  PartitionEnergyReport metis, final;
  double feature_fraction_metis = 0.0, feature_fraction_final = 0.0, balance_max_over_avg = 0.0;
  std::size_t mh_accepted = 0, mh_proposed = 0, repaired_triangles = 0;
  double seconds = 0.0;
};

/// `candidates[][].relax_valences`: the valence moves among unstructured quads, summed over repair rounds.
struct RelaxReport {
  std::size_t quads = 0, flips = 0, collapses = 0;
  double energy_before = 0.0, energy_after = 0.0;
};

/// `candidates[][].repair_rounds[]`: what one round left.
struct RepairRoundReport {
  std::size_t folded = 0, beside_cracks = 0, poor_kept = 0;  ///< beside_cracks: or overlapping another quad
  std::vector<int> remeshed;  ///< subregions meshed again in the next round
};

/// `candidates[][].stage_seconds.map_of`: the first round's map.
struct FirstMapReport {
  double partition = 0.0, split_rounds = 0.0;
  int joint_maps = 0;
  double joint_maps_seconds = 0.0;
};

/// `candidates[][].stage_seconds`: where a candidate's time went, summed over its repair rounds.
struct CandidateSecondsReport {
  double map = 0.0;  ///< the first round's map
  FirstMapReport map_of;
  double repair_maps = 0.0, repair_patches = 0.0, refine = 0.0, smooth = 0.0, local_patches = 0.0,
         relax_valences = 0.0, measure = 0.0;
};

/// `candidates[][].refused_mesh`: how far a candidate refused by the invariants got.
struct RefusedMeshReport {
  std::size_t subregions = 0, mapped = 0;
  double structured_fraction = 0.0;
  std::map<std::string, int> patch_reasons;  ///< reason, numbers blanked -> patched subregions
};

struct SingularitiesAtReport {
  std::size_t maps = 0, subregion_patches = 0, local_patches = 0;
};

struct LocalPatchesReport {
  std::size_t clusters = 0, patched = 0, quads_removed = 0, quads_added = 0;
};

/// A finished candidate's figures (measure_finished), written flat into the candidate.
struct CandidateMeasures {
  std::size_t quads = 0;
  double structured_fraction = 0.0, min_scaled_jacobian = 0.0, max_edge_ratio = 0.0;
  std::size_t interior_singularities = 0;
  double mean_area_over_size_squared = 0.0;
};

/// Quads pinned by input corners sharper than the SJ gate, written flat into the candidate.
struct PinnedReport {
  std::size_t quads_pinned_by_sharp_input = 0;
  double pinned_min_scaled_jacobian = 0.0;
  Vec2 pinned_worst_at{};
  double unpinned_min_scaled_jacobian = 0.0;
};

struct PoorQuadReport {
  Vec2 at{};
  double scaled_jacobian = 0.0, edge_ratio = 0.0;
  std::optional<int> subregion;
};

/// `candidates[][].poor_quads`: quads accepted outside the gates, the first 20 by place.
struct PoorQuadsReport {
  std::size_t count = 0;
  double fraction = 0.0;
  std::vector<PoorQuadReport> first;
};

/// `candidates[][]`: one way of meshing a part, tried (pipeline/candidates.cpp, finish_candidate.cpp). The
/// optional parts are written as the steps reach them; a failed candidate has `error`.
struct CandidateReport {
  int part = 0;
  int subregions = 0;                           ///< 0: the split-triangle fallback
  std::optional<double> parameterization_ratio;  ///< map candidates
  std::optional<bool> bent_interfaces;          ///< PPM candidates
  std::optional<int> split_rounds;              ///< PPM candidates
  std::optional<std::string> fallback;          ///< "split_triangles"
  std::optional<SplitReport> split;
  std::optional<std::size_t> flat_corners, flat_corners_collapsed;
  std::optional<std::size_t> feature_loops_flat, feature_loops_pillowed;
  std::optional<RelaxReport> relax_valences;
  std::optional<std::vector<RepairRoundReport>> repair_rounds;
  std::optional<CandidateSecondsReport> stage_seconds;
  std::optional<RefusedMeshReport> refused_mesh;
  std::optional<SingularitiesAtReport> interior_singularities_at;
  std::optional<LocalPatchesReport> local_patches;
  std::optional<CandidateMeasures> measures;
  std::optional<PinnedReport> pinned;
  std::optional<PoorQuadsReport> poor_quads;
  std::optional<std::string> error;
  std::optional<std::string> with_transitions_error;  ///< graded: why the candidate with transition rows failed;
                                                      ///< this one was made without them
  double seconds = 0.0;
  bool chosen = false;  ///< written only when true
};

/// `unstructured[]`: a subregion (or a whole part, subregion -1) not meshed by a poly-square map.
struct UnstructuredReport {
  int part = 0, subregion = 0;
  std::size_t quads = 0;
  std::string meshed_by;  ///< "patch" or "split_triangles"
  Vec2 at{};
  std::optional<std::string> reason;
};

/// `dropped_parts[]`: a polygon part smaller than one element, left out.
struct DroppedPartReport {
  int part = 0;
  double area = 0.0;
  Vec2 at{};
};

/// `dropped_curves[]`: a curve around a region narrower than the size, left out (input/simplify.h).
struct DroppedCurveReport {
  std::string kind;  ///< hole, feature_loop, feature_piece, wedge_stretch
  int input_feature = -1;
  double width = 0.0, area = 0.0, distance = 0.0;
  Vec2 at{};
};

/// `simplify`: what simplifying the curves changed.
struct SimplifyReport {
  double fraction_of_size = 0.0, smooth_curves_fraction_of_size = 0.0;
  std::size_t vertices_before = 0, vertices_after = 0, refused = 0;
  double max_distance = 0.0, max_distance_over_size = 0.0;
  std::size_t chord_pins = 0, end_points_snapped = 0;
  double largest_snap = 0.0, area_change = 0.0;
};

/// `size_field` (graded runs): the field asked for and made, and how the mesh follows it.
struct SizeFieldReport {
  double size_min = 0.0, size_max = 0.0, grade = 0.0, across = 0.0;  ///< the options
  double min = 0.0, max = 0.0;         ///< the field's least and largest size inside the domain
  double estimated_quads = 0.0;        ///< integral of 1 / h^2, said before meshing
  std::size_t quads = 0;               ///< made
  double cell = 0.0;                   ///< the field's grid spacing
  std::size_t cells = 0, limited_cells = 0;
  double narrowest_passage = 0.0;      ///< with across: the least passage width found (0 = none)
  double size_ratio_median = 0.0, size_ratio_p05 = 0.0, size_ratio_p95 = 0.0;  ///< sqrt(quad area) / h(centroid)
  double neighbour_ratio_p99 = 0.0, neighbour_ratio_max = 0.0;  ///< size jump between quads sharing an edge
};

struct UntangleReport {
  double target_sj = 0.0;
  std::size_t below_target_before = 0, below_target_after = 0, moves = 0;
};

/// `smooth`: the chosen candidates' smoothing, the most sweeps and the sums of the rest.
struct SmoothReport {
  int sweeps = 0;
  std::size_t moves = 0, curve_moves = 0;
  UntangleReport untangle;
};

/// `seconds`: the run's wall times (RegionTimes).
struct SecondsReport {
  double parts = 0.0;  ///< from the start through meshing the parts
};

/// `quality`: the final mesh's figures (add_quality_to_report).
struct QualitySection {
  QualityReport figures;
  FiniteVolumeQuality finite_volume;
};

/// Distances between the mesh and a region, and the feature distances over the size h.
struct DomainFigures {
  DomainDistance distance;
  double feature_max_distance_over_size = 0.0, feature_node_max_distance_over_size = 0.0;
};

/// `domain`: against the input; `simplified`, against the simplified curves the mesh conforms to.
struct DomainSection : DomainFigures {
  std::optional<DomainFigures> simplified;
};

/// `groups[]`: a named group of the output files (io/mesh_groups.h).
struct GroupReport {
  std::string name;
  int tag = 0, dimension = 0;
  std::string role;                  ///< domain, boundary, feature, boundary_segment
  std::optional<std::size_t> quads;  ///< domains
  std::optional<std::size_t> edges;  ///< curves
  std::optional<std::string> kind;
  std::optional<int> ring;
  bool island = false;               ///< written only when true
  std::optional<std::size_t> pieces;
};

struct MeshReport {
  ReportSummary summary;
  InputReport input;
  /// Every setting used, kept as JSON built by one function (region_report.cpp's options_json): MeshOptions is
  /// being regrouped by stage, and this section follows it.
  nlohmann::json options = nlohmann::json::object();
  CountsReport counts;
  std::vector<PartReport> parts;
  std::vector<PartitionReport> partition;
  std::vector<std::vector<CandidateReport>> candidates;  ///< per part, in the order tried
  std::vector<UnstructuredReport> unstructured;
  std::vector<DroppedPartReport> dropped_parts;
  std::vector<DroppedCurveReport> dropped_curves;
  SimplifyReport simplify;
  SmoothReport smooth;
  SecondsReport seconds;
  std::optional<SizeFieldReport> size_field;  ///< graded runs only
  // Added by the caller, absent from mesh_region's report:
  std::optional<QualitySection> quality;
  std::optional<DomainSection> domain;
  std::optional<std::vector<GroupReport>> groups;
};

// JSON conversions (nlohmann's ADL hooks), all in mesh_report.cpp.
void to_json(nlohmann::json& j, const Vec2& p);
void from_json(const nlohmann::json& j, Vec2& p);
void to_json(nlohmann::json& j, const CandidateReport& c);
void from_json(const nlohmann::json& j, CandidateReport& c);
void to_json(nlohmann::json& j, const GroupReport& g);
void from_json(const nlohmann::json& j, GroupReport& g);
void to_json(nlohmann::json& j, const MeshReport& r);
void from_json(const nlohmann::json& j, MeshReport& r);

}  // namespace polysquare
