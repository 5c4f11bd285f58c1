// The JSON report of a meshing run: mesh_region's report completed with the quality figures, and its text.
// Its shape is described by schema/report.schema.json (JSON Schema 2020-12), which a test checks reports against.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "polysquare/io/mesh_groups.h"
#include "polysquare/pipeline/mesh_report.h"
#include "polysquare/quality/quality.h"

namespace polysquare {

/// Adds the quality figures of the final mesh to `report` (MeshResult::report): `quality` (with
/// `quality.finite_volume`), `domain` (with `feature_max_distance_over_size` and
/// `feature_node_max_distance_over_size`, the distances divided by `size`, the target edge length h), and the
/// summary's `sj_min`, `singularities`, `interior_singularities` and `boundary_singularities`. `domain` measures
/// the mesh against the input; `simplified`, when the curves were simplified, against the curves the mesh
/// conforms to (MeshResult::region; design invariant 4), as `domain.simplified`.
void add_quality_to_report(MeshReport& report, const QualityReport& quality, const FiniteVolumeQuality& fv,
                           const DomainDistance& domain, double size,
                           const DomainDistance* simplified = nullptr);

/// The report's `groups`: per group its name, tag, dimension, role and counts (quads or edges), by tag.
std::vector<GroupReport> group_reports(const MeshGroups& groups);

/// The report as indented JSON text (2 spaces, ending in a newline) with `summary` first and, inside it,
/// quads, structured_fraction, sj_min, singularities, seconds and version in that order; the other blocks and
/// keys follow in alphabetical order.
std::string report_text(const nlohmann::json& report);
/// The typed report's text: report_text(nlohmann::json(report)).
std::string report_text(const MeshReport& report);

}  // namespace polysquare
