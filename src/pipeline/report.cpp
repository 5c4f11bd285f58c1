#include "polysquare/pipeline/report.h"

#include <algorithm>
#include <array>
#include <string_view>

namespace polysquare {

namespace {

// A distance with its feature distances over the size (0 without a size).
DomainFigures over_size(const DomainDistance& d, double size) {
  return {d, size > 0.0 ? d.feature_max_distance / size : 0.0, size > 0.0 ? d.feature_node_max_distance / size : 0.0};
}

}  // namespace

void add_quality_to_report(MeshReport& report, const QualityReport& quality, const FiniteVolumeQuality& fv,
                           const DomainDistance& domain, double size, const DomainDistance* simplified) {
  report.quality = QualitySection{quality, fv};
  DomainSection& d = report.domain.emplace();
  static_cast<DomainFigures&>(d) = over_size(domain, size);
  if (simplified) d.simplified = over_size(*simplified, size);
  report.summary.quality = SummaryQuality{quality.sj.min,         quality.singularities,
                                          quality.interior_singularities, quality.boundary_singularities,
                                          quality.regular_quad_fraction,  quality.sj_below_0_3_fraction};
}

std::vector<GroupReport> group_reports(const MeshGroups& groups) {
  std::vector<GroupReport> out;
  for (const SurfaceGroup& s : groups.surfaces) {
    GroupReport& g = out.emplace_back(GroupReport{s.name, s.tag, 2, "domain"});
    g.quads = s.quads.size();
  }
  auto curve = [&](const CurveGroup& c, const char* role) {
    GroupReport& g = out.emplace_back(GroupReport{c.name, c.tag, 1, role});
    g.edges = c.edges.size();
    if (!c.kind.empty()) g.kind = c.kind;
    if (c.ring >= 0) g.ring = c.ring;
    g.island = c.island;
    if (!c.chains.empty()) g.pieces = c.chains.size();
  };
  for (const CurveGroup& c : groups.rings) curve(c, "boundary");
  for (const CurveGroup& c : groups.features) curve(c, "feature");
  for (const CurveGroup& c : groups.segments) curve(c, "boundary_segment");
  std::stable_sort(out.begin(), out.end(), [](const GroupReport& a, const GroupReport& b) { return a.tag < b.tag; });
  return out;
}

std::string report_text(const nlohmann::json& report) {
  // nlohmann::json keeps object keys sorted; ordered_json keeps them as inserted, so the summary can lead.
  static constexpr std::array<std::string_view, 6> summary_first{"quads", "structured_fraction", "sj_min",
                                                                 "singularities", "seconds", "version"};
  nlohmann::ordered_json out = nlohmann::ordered_json::object();
  if (report.is_object() && report.contains("summary") && report["summary"].is_object()) {
    const nlohmann::json& summary = report["summary"];
    nlohmann::ordered_json s = nlohmann::ordered_json::object();
    for (std::string_view key : summary_first)
      if (summary.contains(key)) s[std::string(key)] = nlohmann::ordered_json(summary.at(std::string(key)));
    for (const auto& [key, value] : summary.items())
      if (!s.contains(key)) s[key] = nlohmann::ordered_json(value);
    out["summary"] = std::move(s);
  }
  if (report.is_object()) {
    for (const auto& [key, value] : report.items())
      if (!out.contains(key)) out[key] = nlohmann::ordered_json(value);
  } else {
    return report.dump(2) + "\n";
  }
  return out.dump(2) + "\n";
}

std::string report_text(const MeshReport& report) { return report_text(nlohmann::json(report)); }

}  // namespace polysquare
