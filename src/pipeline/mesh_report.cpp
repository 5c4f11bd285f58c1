// The report's JSON, written and read in this one place (include/polysquare/pipeline/mesh_report.h). Sections
// whose keys are always there use nlohmann's NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE; those with keys written only
// sometimes, or blocks written flat into their parent, are written by hand with put_if / put_flat.
#include "polysquare/pipeline/mesh_report.h"

namespace polysquare {
namespace {

using json = nlohmann::json;

// An optional key: written when set, read when present.
template <typename T>
void put_if(json& j, const char* key, const std::optional<T>& v) {
  if (v) j[key] = *v;
}

template <typename T>
void get_if(const json& j, const char* key, std::optional<T>& v) {
  if (const auto it = j.find(key); it != j.end()) v = it->template get<T>();
  else v.reset();
}

// An optional block written flat into its parent object; read back when its `first_key` is there.
template <typename T>
void put_flat(json& j, const std::optional<T>& v) {
  if (v) j.update(json(*v));
}

template <typename T>
void get_flat(const json& j, const char* first_key, std::optional<T>& v) {
  if (j.contains(first_key)) v = j.get<T>();
  else v.reset();
}

}  // namespace

void to_json(json& j, const Vec2& p) { j = json::array({p.x, p.y}); }
void from_json(const json& j, Vec2& p) { p = {j.at(0).get<double>(), j.at(1).get<double>()}; }

NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(SummaryQuality, sj_min, singularities, interior_singularities,
                                   boundary_singularities, regular_quad_fraction, sj_below_0_3_fraction)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(InputNotesReport, repairs, snapped, warnings, input_crs, boundary_segments)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(CountsReport, nodes, quads, boundary_edges, feature_edges)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(SplitReport, rounds, subregions_split, maps_tried, pieces_mapped, seconds,
                                   after_joint_map)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(DeformReport, iterations, energy_before, energy_after, alignment_before,
                                   alignment_after)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(PartSecondsReport, triangulate, deform, quantize, snap, extract, joint_maps)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(MultipassReport, passes, colours, last_move, seconds)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(PartitionEnergyReport, separator_length, angle_deviation, feature_on_separators,
                                   energy)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(PartitionReport, part, subregions, faces, separators, metis, final,
                                   feature_fraction_metis, feature_fraction_final, balance_max_over_avg,
                                   mh_accepted, mh_proposed, repaired_triangles, seconds)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(RelaxReport, quads, flips, collapses, energy_before, energy_after)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(RepairRoundReport, folded, beside_cracks, poor_kept, remeshed)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(FirstMapReport, partition, split_rounds, joint_maps, joint_maps_seconds)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(CandidateSecondsReport, map, map_of, repair_maps, repair_patches, refine, smooth,
                                   local_patches, relax_valences, measure)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(RefusedMeshReport, subregions, mapped, structured_fraction, patch_reasons)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(SingularitiesAtReport, maps, subregion_patches, local_patches)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(LocalPatchesReport, clusters, patched, quads_removed, quads_added)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(CandidateMeasures, quads, structured_fraction, min_scaled_jacobian, max_edge_ratio,
                                   interior_singularities, mean_area_over_size_squared)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(PinnedReport, quads_pinned_by_sharp_input, pinned_min_scaled_jacobian,
                                   pinned_worst_at, unpinned_min_scaled_jacobian)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(DroppedPartReport, part, area, at)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(DroppedCurveReport, kind, input_feature, width, area, distance, at)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(SimplifyReport, fraction_of_size, smooth_curves_fraction_of_size, vertices_before,
                                   vertices_after, refused, max_distance, max_distance_over_size, chord_pins,
                                   end_points_snapped, largest_snap, area_change)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(SizeFieldReport, size_min, size_max, grade, across, min, max, estimated_quads,
                                   quads, cell, cells, limited_cells, narrowest_passage, size_ratio_median,
                                   size_ratio_p05, size_ratio_p95, neighbour_ratio_p99, neighbour_ratio_max)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(UntangleReport, target_sj, below_target_before, below_target_after, moves)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(SmoothReport, sweeps, moves, curve_moves, untangle)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(SecondsReport, parts)

void to_json(json& j, const ReportSummary& s) {
  j = {{"quads", s.quads},
       {"structured_fraction", s.structured_fraction},
       {"subregions", s.subregions},
       {"unstructured_subregions", s.unstructured_subregions},
       {"local_patch_quads", s.local_patch_quads},
       {"poor_quads", s.poor_quads},
       {"sj_below_0_3_pinned", s.sj_below_0_3_pinned},
       {"sj_below_0_3_unpinned_fraction", s.sj_below_0_3_unpinned_fraction},
       {"seconds", s.seconds},
       {"version", s.version}};
  put_flat(j, s.quality);
  put_if(j, "processes", s.processes);
}

void from_json(const json& j, ReportSummary& s) {
  j.at("quads").get_to(s.quads);
  j.at("structured_fraction").get_to(s.structured_fraction);
  j.at("subregions").get_to(s.subregions);
  j.at("unstructured_subregions").get_to(s.unstructured_subregions);
  j.at("local_patch_quads").get_to(s.local_patch_quads);
  j.at("poor_quads").get_to(s.poor_quads);
  j.at("sj_below_0_3_pinned").get_to(s.sj_below_0_3_pinned);
  j.at("sj_below_0_3_unpinned_fraction").get_to(s.sj_below_0_3_unpinned_fraction);
  j.at("seconds").get_to(s.seconds);
  j.at("version").get_to(s.version);
  get_flat(j, "sj_min", s.quality);
  get_if(j, "processes", s.processes);
}

void to_json(json& j, const InputReport& in) {
  j = {{"source", in.source}, {"crs", in.crs},   {"units", in.units}, {"parts", in.parts},
       {"rings", in.rings},   {"feature_curves", in.feature_curves}, {"area", in.area}};
  put_flat(j, in.notes);
  put_if(j, "local_origin", in.local_origin);
}

void from_json(const json& j, InputReport& in) {
  j.at("source").get_to(in.source);
  j.at("crs").get_to(in.crs);
  j.at("units").get_to(in.units);
  j.at("parts").get_to(in.parts);
  j.at("rings").get_to(in.rings);
  j.at("feature_curves").get_to(in.feature_curves);
  j.at("area").get_to(in.area);
  get_flat(j, "input_crs", in.notes);
  get_if(j, "local_origin", in.local_origin);
}

void to_json(json& j, const SubregionReport& s) {
  j = {{"subregion", s.subregion}, {"quads", s.quads}, {"meshed_by", s.meshed_by}, {"at", s.at}};
  if (s.local_patch_quads > 0) j["local_patch_quads"] = s.local_patch_quads;
  if (s.untangled) j["untangled"] = true;
  put_if(j, "reason", s.reason);
}

void from_json(const json& j, SubregionReport& s) {
  j.at("subregion").get_to(s.subregion);
  j.at("quads").get_to(s.quads);
  j.at("meshed_by").get_to(s.meshed_by);
  j.at("at").get_to(s.at);
  s.local_patch_quads = j.value("local_patch_quads", std::size_t{0});
  s.untangled = j.value("untangled", false);
  get_if(j, "reason", s.reason);
}

NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(PartReport, part, triangles, rotation_deg, deform, split, break_points, segments,
                                   quantization_max_relative_deviation, quads, seconds, joint_maps, agreed_turns,
                                   transition_rows, multipass, subregions)

void to_json(json& j, const PoorQuadReport& p) {
  j = {{"at", p.at}, {"scaled_jacobian", p.scaled_jacobian}, {"edge_ratio", p.edge_ratio}};
  put_if(j, "subregion", p.subregion);
}

void from_json(const json& j, PoorQuadReport& p) {
  j.at("at").get_to(p.at);
  j.at("scaled_jacobian").get_to(p.scaled_jacobian);
  j.at("edge_ratio").get_to(p.edge_ratio);
  get_if(j, "subregion", p.subregion);
}

NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(PoorQuadsReport, count, fraction, first)

// The candidate's keys in one list, so that writing and reading them cannot drift apart.
template <typename Json, typename Candidate, typename Each>
void candidate_keys(Json& j, Candidate& c, Each&& each) {
  each(j, "parameterization_ratio", c.parameterization_ratio);
  each(j, "bent_interfaces", c.bent_interfaces);
  each(j, "split_rounds", c.split_rounds);
  each(j, "fallback", c.fallback);
  each(j, "split", c.split);
  each(j, "flat_corners", c.flat_corners);
  each(j, "flat_corners_collapsed", c.flat_corners_collapsed);
  each(j, "feature_loops_flat", c.feature_loops_flat);
  each(j, "feature_loops_pillowed", c.feature_loops_pillowed);
  each(j, "relax_valences", c.relax_valences);
  each(j, "repair_rounds", c.repair_rounds);
  each(j, "stage_seconds", c.stage_seconds);
  each(j, "refused_mesh", c.refused_mesh);
  each(j, "interior_singularities_at", c.interior_singularities_at);
  each(j, "local_patches", c.local_patches);
  each(j, "poor_quads", c.poor_quads);
  each(j, "error", c.error);
  each(j, "with_transitions_error", c.with_transitions_error);
}

void to_json(json& j, const CandidateReport& c) {
  j = {{"part", c.part}, {"subregions", c.subregions}, {"seconds", c.seconds}};
  candidate_keys(j, c, [](json& o, const char* key, const auto& v) { put_if(o, key, v); });
  put_flat(j, c.measures);
  put_flat(j, c.pinned);
  if (c.chosen) j["chosen"] = true;
}

void from_json(const json& j, CandidateReport& c) {
  j.at("part").get_to(c.part);
  j.at("subregions").get_to(c.subregions);
  j.at("seconds").get_to(c.seconds);
  candidate_keys(j, c, [](const json& o, const char* key, auto& v) { get_if(o, key, v); });
  get_flat(j, "min_scaled_jacobian", c.measures);
  get_flat(j, "quads_pinned_by_sharp_input", c.pinned);
  c.chosen = j.value("chosen", false);
}

void to_json(json& j, const UnstructuredReport& u) {
  j = {{"part", u.part}, {"subregion", u.subregion}, {"quads", u.quads}, {"meshed_by", u.meshed_by}, {"at", u.at}};
  put_if(j, "reason", u.reason);
}

void from_json(const json& j, UnstructuredReport& u) {
  j.at("part").get_to(u.part);
  j.at("subregion").get_to(u.subregion);
  j.at("quads").get_to(u.quads);
  j.at("meshed_by").get_to(u.meshed_by);
  j.at("at").get_to(u.at);
  get_if(j, "reason", u.reason);
}

void to_json(json& j, const QualitySection& q) {
  j = to_json(q.figures);
  j["finite_volume"] = to_json(q.finite_volume);
}

void from_json(const json& j, QualitySection& q) {
  from_json(j, q.figures);
  from_json(j.at("finite_volume"), q.finite_volume);
}

void to_json(json& j, const DomainFigures& d) {
  j = to_json(d.distance);
  j["feature_max_distance_over_size"] = d.feature_max_distance_over_size;
  j["feature_node_max_distance_over_size"] = d.feature_node_max_distance_over_size;
}

void from_json(const json& j, DomainFigures& d) {
  from_json(j, d.distance);
  j.at("feature_max_distance_over_size").get_to(d.feature_max_distance_over_size);
  j.at("feature_node_max_distance_over_size").get_to(d.feature_node_max_distance_over_size);
}

void to_json(json& j, const DomainSection& d) {
  to_json(j, static_cast<const DomainFigures&>(d));
  put_if(j, "simplified", d.simplified);
}

void from_json(const json& j, DomainSection& d) {
  from_json(j, static_cast<DomainFigures&>(d));
  get_if(j, "simplified", d.simplified);
}

void to_json(json& j, const GroupReport& g) {
  j = {{"name", g.name}, {"tag", g.tag}, {"dimension", g.dimension}, {"role", g.role}};
  put_if(j, "quads", g.quads);
  put_if(j, "edges", g.edges);
  put_if(j, "kind", g.kind);
  put_if(j, "ring", g.ring);
  if (g.island) j["island"] = true;
  put_if(j, "pieces", g.pieces);
}

void from_json(const json& j, GroupReport& g) {
  j.at("name").get_to(g.name);
  j.at("tag").get_to(g.tag);
  j.at("dimension").get_to(g.dimension);
  j.at("role").get_to(g.role);
  get_if(j, "quads", g.quads);
  get_if(j, "edges", g.edges);
  get_if(j, "kind", g.kind);
  get_if(j, "ring", g.ring);
  g.island = j.value("island", false);
  get_if(j, "pieces", g.pieces);
}

void to_json(json& j, const MeshReport& r) {
  j = {{"summary", r.summary},           {"input", r.input},
       {"options", r.options},           {"counts", r.counts},
       {"parts", r.parts},               {"partition", r.partition},
       {"candidates", r.candidates},     {"unstructured", r.unstructured},
       {"dropped_parts", r.dropped_parts}, {"dropped_curves", r.dropped_curves},
       {"simplify", r.simplify},         {"smooth", r.smooth},
       {"seconds", r.seconds}};
  put_if(j, "size_field", r.size_field);
  put_if(j, "quality", r.quality);
  put_if(j, "domain", r.domain);
  put_if(j, "groups", r.groups);
}

void from_json(const json& j, MeshReport& r) {
  j.at("summary").get_to(r.summary);
  j.at("input").get_to(r.input);
  r.options = j.at("options");
  j.at("counts").get_to(r.counts);
  j.at("parts").get_to(r.parts);
  j.at("partition").get_to(r.partition);
  j.at("candidates").get_to(r.candidates);
  j.at("unstructured").get_to(r.unstructured);
  j.at("dropped_parts").get_to(r.dropped_parts);
  j.at("dropped_curves").get_to(r.dropped_curves);
  j.at("simplify").get_to(r.simplify);
  j.at("smooth").get_to(r.smooth);
  j.at("seconds").get_to(r.seconds);
  get_if(j, "size_field", r.size_field);
  get_if(j, "quality", r.quality);
  get_if(j, "domain", r.domain);
  get_if(j, "groups", r.groups);
}

}  // namespace polysquare
