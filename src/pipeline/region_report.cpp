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

SubregionReport subregion_report(const SubregionStats& r) {
  SubregionReport out{r.subregion, r.quads, r.mapped ? "map" : "patch", r.at, r.local_patch_quads, r.untangled, {}};
  if (!r.mapped) out.reason = r.reason;
  return out;
}

PartReport part_report(const PartMapStats& s) {
  PartReport out;
  out.part = s.part;
  out.triangles = s.triangles;
  out.rotation_deg = s.rotation_deg;
  out.deform = {s.deform.iterations, s.deform.energy_before, s.deform.energy_after, s.deform.alignment_before,
                s.deform.alignment_after};
  out.split = split_report(s);
  out.break_points = s.break_points;
  out.segments = s.segments;
  out.quantization_max_relative_deviation = s.quantize.max_relative_deviation;
  out.quads = s.quads;
  out.seconds = {s.seconds_triangulate, s.seconds_deform, s.seconds_quantize, s.seconds_snap, s.seconds_extract,
                 s.seconds_joint_maps};
  out.joint_maps = s.joint_maps;
  out.agreed_turns = s.agreed_turns;
  out.transition_rows = s.transition_rows;
  out.multipass = {s.multipass.passes, s.multipass.colours, s.multipass.last_move, s.multipass.seconds};
  for (const SubregionStats& r : s.subregions) out.subregions.push_back(subregion_report(r));
  return out;
}

std::vector<DroppedCurveReport> dropped_curves_report(const std::vector<DroppedCurve>& curves) {
  std::vector<DroppedCurveReport> out;
  for (const DroppedCurve& d : curves) {
    const char* kind = d.kind == DroppedCurve::Kind::hole           ? "hole"
                       : d.kind == DroppedCurve::Kind::feature_loop  ? "feature_loop"
                       : d.kind == DroppedCurve::Kind::feature_piece ? "feature_piece"
                                                                     : "wedge_stretch";
    out.push_back({kind, d.source_feature, d.width, d.area, d.distance, d.at});
  }
  return out;
}

PartitionEnergyReport energy_report(const PartitionEnergy& e) {
  return {e.separator_length, e.angle_deviation, e.feature_on_separators, e.energy};
}

// The partitions of the parts that have one, in part order.
std::vector<PartitionReport> partition_report(const std::vector<PartOutcome>& outcomes) {
  std::vector<PartitionReport> out;
  for (const PartOutcome& p : outcomes) {
    const PartMapResult& r = *p.result;
    if (!r.partition) continue;
    const PartitionResult& pr = *r.partition;
    out.push_back({r.stats.part, pr.parts, pr.faces, r.stats.separators, energy_report(pr.metis),
                   energy_report(pr.final), pr.feature_fraction_metis, pr.feature_fraction_final,
                   pr.balance_max_over_avg, pr.mh_accepted, pr.mh_proposed, pr.repaired_triangles,
                   r.stats.seconds_partition});
  }
  return out;
}

// How much of the mesh is semi-structured, and where it is not: the summary outside checks read.
struct Structure {
  double structured_quads = 0.0;
  std::size_t subregion_count = 0, local_patch_quads = 0;
  std::vector<UnstructuredReport> unstructured;
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
        out.unstructured.push_back({st.part, -1, result.mesh.quads.size(), "split_triangles", at, {}});
      }
    }
    for (const SubregionStats& sr : st.subregions) {
      ++out.subregion_count;
      out.local_patch_quads += sr.mapped ? sr.local_patch_quads : 0;
      if (!sr.mapped)
        out.unstructured.push_back({st.part, sr.subregion, sr.quads, "patch", sr.at, sr.reason});
    }
  }
  return out;
}

ReportSummary summary_report(const ReportInput& in, const Structure& structure) {
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
  ReportSummary out;
  const double quads = static_cast<double>(mesh.quads.size());
  out.quads = mesh.quads.size();
  out.sj_below_0_3_pinned = pinned_below_0_3;
  out.sj_below_0_3_unpinned_fraction = mesh.quads.empty() ? 0.0 : static_cast<double>(below_0_3 - pinned_below_0_3) / quads;
  out.structured_fraction = mesh.quads.empty() ? 0.0 : structure.structured_quads / quads;
  out.subregions = structure.subregion_count;
  out.unstructured_subregions = structure.unstructured.size();
  out.local_patch_quads = structure.local_patch_quads;
  out.poor_quads = poor_quads;
  out.seconds = in.times.elapsed();
  out.version = library_version();
  return out;
}

InputReport input_report(const Region& region) {
  InputReport out;
  out.source = region.source;
  out.crs = region.crs;
  out.units = region.units;
  out.parts = region.num_parts;
  out.rings = region.rings.size();
  out.feature_curves = region.features.size();
  out.area = region_area(region);
  return out;
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

SimplifyReport simplify_report(const ReportInput& in) {
  const MeshOptions& options = in.options;
  const SimplifyStats& st = in.simplified.stats;
  const SnapStats& end_snaps = in.simplified.end_snaps;
  const double area = region_area(in.region);
  return {options.curves.simplify, options.curves.smooth_curves, st.vertices_before, st.vertices_after, st.refused,
          st.max_distance, st.max_distance / options.size.h, st.chord_pins, end_snaps.to_vertex + end_snaps.to_segment,
          end_snaps.largest_move, area != 0.0 ? region_area(in.simplified.region) / area - 1.0 : 0.0};
}

// A graded run's field and how the mesh follows it.
SizeFieldReport size_field_report(const ReportInput& in) {
  const SizeFieldOptions& o = in.options.size.field;
  const SizeFieldStats& s = in.sized.stats;
  const SizeConformity c = size_conformity(in.result.mesh, *in.sized.field);
  return {o.size_min, o.size_max, o.grade, o.across, s.min, s.max, s.estimated_quads, in.result.mesh.quads.size(),
          s.cell, s.cells, s.limited_cells, s.narrowest_passage, c.median, c.p05, c.p95, c.neighbour_p99,
          c.neighbour_max};
}

// The parts' smoothing figures together: the most sweeps, the sums of the rest.
SmoothReport smooth_report(const ReportInput& in) {
  SmoothReport out;
  out.untangle.target_sj = in.options.smooth.untangle.target_sj;
  for (const PartOutcome& p : in.outcomes) {
    const SmoothStats& st = p.smoothed;
    out.sweeps = std::max(out.sweeps, st.sweeps);
    out.moves += st.moves;
    out.curve_moves += st.curve_moves;
    out.untangle.below_target_before += st.untangle.folded_before;
    out.untangle.below_target_after += st.untangle.folded_after;
    out.untangle.moves += st.untangle.moves;
  }
  return out;
}

}  // namespace

SplitReport split_report(const PartMapStats& s) {
  return {s.split.rounds, s.split.split, s.split.tested, s.split.pieces_mapped, s.split.seconds, s.joint_splits};
}

MeshReport region_report(const ReportInput& in) {
  const QuadMesh& mesh = in.result.mesh;
  MeshReport out;
  Structure structure = structure_of(in);
  out.summary = summary_report(in, structure);
  out.unstructured = std::move(structure.unstructured);
  out.input = input_report(in.region);
  out.options = options_json(in.options, in.map);
  out.counts = {mesh.nodes.size(), mesh.quads.size(), mesh.boundary_edges.size(), mesh.feature_edges.size()};
  for (const PartMapStats& s : in.result.parts) out.parts.push_back(part_report(s));
  out.partition = partition_report(in.outcomes);
  for (const PartOutcome& p : in.outcomes) out.candidates.push_back(p.tried);
  out.dropped_parts = in.parts.dropped;
  out.dropped_curves = dropped_curves_report(in.simplified.dropped_curves);
  out.simplify = simplify_report(in);
  out.smooth = smooth_report(in);
  out.seconds = {in.times.parts};
  if (in.sized.field) out.size_field = size_field_report(in);
  return out;
}

}  // namespace polysquare::pipeline
