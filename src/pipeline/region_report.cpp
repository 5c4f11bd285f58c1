// Stage "report": MeshResult::report, written from what every stage of mesh_region returned.
#include <algorithm>
#include <cmath>
#include <numeric>

#include "pipeline/candidate.h"
#include "pipeline/region_stages.h"
#include "polysquare/core/version.h"
#include "polysquare/quality/quality.h"
#include "polysquare/size/size_conformity.h"

namespace polysquare::pipeline {
namespace {

double region_area(const Region& region) {
  double a = 0.0;
  for (const Ring& r : region.rings) a += ring_signed_area(r.points);  // outer rings counter-clockwise (+), holes (-)
  return a;
}

nlohmann::json part_json(const PartMapStats& s) {
  nlohmann::json subregions = nlohmann::json::array();
  for (const SubregionStats& r : s.subregions) {
    nlohmann::json j = {{"subregion", r.subregion}, {"quads", r.quads}, {"meshed_by", r.mapped ? "map" : "patch"},
                        {"at", {r.at.x, r.at.y}}};
    if (r.local_patch_quads > 0) j["local_patch_quads"] = r.local_patch_quads;
    if (r.untangled) j["untangled"] = true;
    if (!r.mapped) j["reason"] = r.reason;
    subregions.push_back(std::move(j));
  }
  return {{"subregions", subregions},
          {"part", s.part},
          {"triangles", s.triangles},
          {"rotation_deg", s.rotation_deg},
          {"deform", {{"iterations", s.deform.iterations},
                      {"energy_before", s.deform.energy_before},
                      {"energy_after", s.deform.energy_after},
                      {"alignment_before", s.deform.alignment_before},
                      {"alignment_after", s.deform.alignment_after}}},
          {"split", split_json(s)},
          {"break_points", s.break_points},
          {"segments", s.segments},
          {"quantization_max_relative_deviation", s.quantize.max_relative_deviation},
          {"quads", s.quads},
          {"seconds", {{"triangulate", s.seconds_triangulate},
                       {"deform", s.seconds_deform},
                       {"quantize", s.seconds_quantize},
                       {"snap", s.seconds_snap},
                       {"extract", s.seconds_extract},
                       {"joint_maps", s.seconds_joint_maps}}},
          {"joint_maps", s.joint_maps},
          {"agreed_turns", s.agreed_turns},
          {"multipass", {{"passes", s.multipass.passes}, {"colours", s.multipass.colours},
                         {"last_move", s.multipass.last_move}, {"seconds", s.multipass.seconds}}}};
}

nlohmann::json dropped_json(const std::vector<DroppedCurve>& curves) {
  nlohmann::json out = nlohmann::json::array();
  for (const DroppedCurve& d : curves) {
    const char* kind = d.kind == DroppedCurve::Kind::hole           ? "hole"
                       : d.kind == DroppedCurve::Kind::feature_loop  ? "feature_loop"
                       : d.kind == DroppedCurve::Kind::feature_piece ? "feature_piece"
                                                                     : "wedge_stretch";
    out.push_back({{"kind", kind}, {"input_feature", d.source_feature}, {"width", d.width}, {"area", d.area},
                   {"distance", d.distance}, {"at", {d.at.x, d.at.y}}});
  }
  return out;
}

// The partitions of the parts that have one, in part order.
nlohmann::json partition_json(const std::vector<PartOutcome>& outcomes) {
  nlohmann::json out = nlohmann::json::array();
  auto energy = [](const PartitionEnergy& e) {
    return nlohmann::json{{"separator_length", e.separator_length}, {"angle_deviation", e.angle_deviation},
                          {"feature_on_separators", e.feature_on_separators}, {"energy", e.energy}};
  };
  for (const PartOutcome& p : outcomes) {
    const PartMapResult& r = *p.result;
    if (!r.partition) continue;
    const PartitionResult& pr = *r.partition;
    out.push_back({{"part", r.stats.part}, {"subregions", pr.parts}, {"faces", pr.faces}, {"separators", r.stats.separators},
                   {"metis", energy(pr.metis)}, {"final", energy(pr.final)},
                   {"feature_fraction_metis", pr.feature_fraction_metis},
                   {"feature_fraction_final", pr.feature_fraction_final},
                   {"balance_max_over_avg", pr.balance_max_over_avg},
                   {"mh_accepted", pr.mh_accepted}, {"mh_proposed", pr.mh_proposed},
                   {"repaired_triangles", pr.repaired_triangles}, {"seconds", r.stats.seconds_partition}});
  }
  return out;
}

// How much of the mesh is semi-structured, and where it is not: the summary outside checks read.
struct Structure {
  double structured_quads = 0.0;
  std::size_t subregion_count = 0, local_patch_quads = 0;
  nlohmann::json unstructured = nlohmann::json::array();
};

Structure structure_of(const ReportInput& in) {
  Structure out;
  const std::vector<RegionPart>& parts = in.parts.parts;
  for (std::size_t k = 0; k < parts.size(); ++k) {
    const PartMapResult& result = *in.outcomes[k].result;
    const double structured = in.outcomes[k].structured;
    const PartMapStats& st = result.stats;
    out.structured_quads += structured * static_cast<double>(result.mesh.quads.size());
    if (st.subregions.empty()) {
      ++out.subregion_count;
      // One map for the whole part: what is not structured there was made by local patches.
      if (structured > 0.0)
        out.local_patch_quads += static_cast<std::size_t>(
            std::llround((1.0 - structured) * static_cast<double>(result.mesh.quads.size())));
      if (structured == 0.0) {
        const Vec2 at = in.simplified.region.rings[static_cast<std::size_t>(parts[k].rings.front())].points.front();
        out.unstructured.push_back({{"part", st.part}, {"subregion", -1}, {"quads", result.mesh.quads.size()},
                                    {"meshed_by", "split_triangles"}, {"at", {at.x, at.y}}});
      }
    }
    for (const SubregionStats& sr : st.subregions) {
      ++out.subregion_count;
      out.local_patch_quads += sr.mapped ? sr.local_patch_quads : 0;
      if (!sr.mapped)
        out.unstructured.push_back({{"part", st.part}, {"subregion", sr.subregion}, {"quads", sr.quads},
                                    {"meshed_by", "patch"}, {"at", {sr.at.x, sr.at.y}}, {"reason", sr.reason}});
    }
  }
  return out;
}

nlohmann::json summary_json(const ReportInput& in, const Structure& structure) {
  const QuadMesh& mesh = in.result.mesh;
  // Quads below SJ 0.3 that no conforming mesh avoids: at an input corner, or inside a wedge between two curves,
  // sharper than asin(0.3) (17.5 degrees) and within a size of it. Reported apart from the rest below 0.3.
  std::size_t below_0_3 = 0, pinned_below_0_3 = 0;
  {
    const std::vector<std::uint8_t> pinned = quads_pinned_by_sharp_input(mesh, 0.3, in.options.size.h);
    for (std::size_t q = 0; q < mesh.quads.size(); ++q)
      if (quad_min_corner_sj(mesh, q) < 0.3) {
        ++below_0_3;
        pinned_below_0_3 += pinned[q];
      }
  }
  std::size_t poor_quads = 0;
  for (const PartOutcome& p : in.outcomes) poor_quads += p.poor_quads;
  return {
      {"quads", mesh.quads.size()},
      {"sj_below_0_3_pinned", pinned_below_0_3},
      {"sj_below_0_3_unpinned_fraction",
       mesh.quads.empty() ? 0.0 : static_cast<double>(below_0_3 - pinned_below_0_3) / static_cast<double>(mesh.quads.size())},
      {"structured_fraction", mesh.quads.empty() ? 0.0 : structure.structured_quads / static_cast<double>(mesh.quads.size())},
      {"subregions", structure.subregion_count},
      {"unstructured_subregions", structure.unstructured.size()},
      {"local_patch_quads", structure.local_patch_quads},
      {"poor_quads", poor_quads},
      {"seconds", in.times.elapsed()},
      {"version", library_version()}};
}

nlohmann::json input_json(const Region& region) {
  return {{"source", region.source}, {"crs", region.crs}, {"units", region.units},
          {"parts", region.num_parts}, {"rings", region.rings.size()}, {"feature_curves", region.features.size()},
          {"area", region_area(region)}};
}

nlohmann::json options_json(const MeshOptions& options, const PolysquareMapOptions& map) {
  return {{"size", options.size.h},
          {"threads", options.run.threads},
          {"seed", options.run.seed},
          {"corner_threshold_deg", options.curves.corner_threshold_deg},
          {"max_quads", options.size.max_quads},
          {"min_scaled_jacobian", options.gates.min_scaled_jacobian},
          {"max_edge_ratio", options.gates.max_edge_ratio},
          {"map", options.subregions.parts == 1 ? "single poly-square per part"
                                                : (map.composition == MapComposition::gpm ? "gpm" : "ppm")},
          {"subregions_per_part", options.subregions.parts},
          {"amips_alpha", map.deform.amips_alpha},
          {"amips_s", map.deform.amips_s},
          {"boundary_weight", map.deform.boundary_weight},
          {"feature_weight", map.deform.feature_weight},
          {"parameterization_ratio", map.parameterization_ratio},
          {"feature_tolerance", options.gates.feature_tolerance},
          {"flat_corner_deg", options.refine.enabled ? options.refine.flat_corner_deg : 180.0},
          {"loop_corner_deg", options.refine.enabled ? options.refine.loop_corner_deg : 180.0}};
}

nlohmann::json simplify_json(const ReportInput& in) {
  const MeshOptions& options = in.options;
  const SimplifyStats& simplify_stats = in.simplified.stats;
  const SnapStats& end_snaps = in.simplified.end_snaps;
  const double area = region_area(in.region);
  return {{"fraction_of_size", options.curves.simplify},
          {"smooth_curves_fraction_of_size", options.curves.smooth_curves},
          {"vertices_before", simplify_stats.vertices_before},
          {"vertices_after", simplify_stats.vertices_after},
          {"refused", simplify_stats.refused},
          {"max_distance", simplify_stats.max_distance},
          {"max_distance_over_size", simplify_stats.max_distance / options.size.h},
          {"chord_pins", simplify_stats.chord_pins},
          {"end_points_snapped", end_snaps.to_vertex + end_snaps.to_segment},
          {"largest_snap", end_snaps.largest_move},
          {"area_change", area != 0.0 ? region_area(in.simplified.region) / area - 1.0 : 0.0}};
}

// The parts' smoothing figures together: the most sweeps, the sums of the rest.
// A graded run's field and how the mesh follows it.
nlohmann::json size_field_json(const ReportInput& in) {
  const SizeFieldOptions& o = in.options.size.field;
  const SizeFieldStats& s = in.sized.stats;
  const SizeConformity c = size_conformity(in.result.mesh, *in.sized.field);
  nlohmann::json j = {{"size_min", o.size_min}, {"size_max", o.size_max}, {"grade", o.grade},
                      {"across", o.across}, {"min", s.min}, {"max", s.max},
                      {"estimated_quads", s.estimated_quads}, {"quads", in.result.mesh.quads.size()},
                      {"cell", s.cell}, {"cells", s.cells}, {"limited_cells", s.limited_cells},
                      {"size_ratio", {{"median", c.median}, {"p05", c.p05}, {"p95", c.p95}}},
                      {"neighbour_ratio", {{"p99", c.neighbour_p99}, {"max", c.neighbour_max}}}};
  if (o.across > 0) j["narrowest_passage"] = s.narrowest_passage;
  return j;
}

nlohmann::json smooth_json(const ReportInput& in) {
  SmoothStats smooth;
  for (const PartOutcome& p : in.outcomes) {
    const SmoothStats& st = p.smoothed;
    smooth.sweeps = std::max(smooth.sweeps, st.sweeps);
    smooth.moves += st.moves;
    smooth.curve_moves += st.curve_moves;
    smooth.untangle.folded_before += st.untangle.folded_before;
    smooth.untangle.folded_after += st.untangle.folded_after;
    smooth.untangle.moves += st.untangle.moves;
  }
  return {{"sweeps", smooth.sweeps}, {"moves", smooth.moves}, {"curve_moves", smooth.curve_moves},
          {"untangle", {{"target_sj", in.options.smooth.untangle.target_sj},
                        {"below_target_before", smooth.untangle.folded_before},
                        {"below_target_after", smooth.untangle.folded_after},
                        {"moves", smooth.untangle.moves}}}};
}

}  // namespace

nlohmann::json split_json(const PartMapStats& s) {
  return {{"rounds", s.split.rounds}, {"subregions_split", s.split.split},
          {"maps_tried", s.split.tested}, {"pieces_mapped", s.split.pieces_mapped},
          {"seconds", s.split.seconds}, {"after_joint_map", s.joint_splits}};
}

nlohmann::json region_report(const ReportInput& in) {
  const QuadMesh& mesh = in.result.mesh;
  nlohmann::json parts_json = nlohmann::json::array();
  for (const auto& s : in.result.parts) parts_json.push_back(part_json(s));
  nlohmann::json tried = nlohmann::json::array();
  for (const PartOutcome& p : in.outcomes) tried.push_back(p.tried);
  Structure structure = structure_of(in);
  const nlohmann::json summary = summary_json(in, structure);
  nlohmann::json report = {
      {"summary", summary},
      {"unstructured", std::move(structure.unstructured)},
      {"input", input_json(in.region)},
      {"options", options_json(in.options, in.map)},
      {"counts", {{"nodes", mesh.nodes.size()}, {"quads", mesh.quads.size()},
                  {"boundary_edges", mesh.boundary_edges.size()}, {"feature_edges", mesh.feature_edges.size()}}},
      {"parts", parts_json},
      {"partition", partition_json(in.outcomes)},
      {"candidates", tried},
      {"dropped_parts", in.parts.dropped},
      {"dropped_curves", dropped_json(in.simplified.dropped_curves)},
      {"simplify", simplify_json(in)},
      {"smooth", smooth_json(in)},
      {"seconds", {{"parts", in.times.parts}}},
  };
  if (in.sized.field) report["size_field"] = size_field_json(in);
  return report;
}

}  // namespace polysquare::pipeline
