#include "polysquare/pipeline/report.h"

#include <array>
#include <string_view>

namespace polysquare {

void add_quality_to_report(nlohmann::json& report, const QualityReport& quality, const FiniteVolumeQuality& fv,
                           const DomainDistance& domain, double size, const DomainDistance* simplified) {
  report["quality"] = to_json(quality);
  report["quality"]["finite_volume"] = to_json(fv);
  report["domain"] = to_json(domain);
  report["domain"]["feature_max_distance_over_size"] = size > 0.0 ? domain.feature_max_distance / size : 0.0;
  report["domain"]["feature_node_max_distance_over_size"] = size > 0.0 ? domain.feature_node_max_distance / size : 0.0;
  if (simplified) {
    nlohmann::json& j = report["domain"]["simplified"] = to_json(*simplified);
    j["feature_max_distance_over_size"] = size > 0.0 ? simplified->feature_max_distance / size : 0.0;
    j["feature_node_max_distance_over_size"] = size > 0.0 ? simplified->feature_node_max_distance / size : 0.0;
  }
  nlohmann::json& summary = report["summary"];
  summary["sj_min"] = quality.sj.min;
  summary["singularities"] = quality.singularities;
  summary["interior_singularities"] = quality.interior_singularities;
  summary["boundary_singularities"] = quality.boundary_singularities;
  summary["regular_quad_fraction"] = quality.regular_quad_fraction;
  summary["sj_below_0_3_fraction"] = quality.sj_below_0_3_fraction;
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

}  // namespace polysquare
