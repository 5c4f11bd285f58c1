// Real coastlines at default options (issue "Real coastlines, semi-structured"): the mesh is semi-structured,
// not a whole-part fallback, and what was left out as narrower than the size is reported.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "polysquare/input/read_region.h"
#include "polysquare/pipeline/invariants.h"
#include "polysquare/pipeline/mesh_region.h"
#include "polysquare/quality/quality.h"

using namespace polysquare;

namespace {

Region coast(const std::string& name) { return read_region(std::string(POLYSQUARE_DATA_DIR) + "/cases/" + name + ".geojson"); }

// The mesh at default options but the size, with its invariants and no inverted quad checked.
MeshResult mesh_checked(const Region& region, const MeshOptions& o, QualityReport& q) {
  MeshResult r = mesh_region(region, o);
  EXPECT_TRUE(check_invariants(r.mesh).ok()) << check_invariants(r.mesh).first_problem;
  q = compute_quality(r.mesh);
  EXPECT_EQ(q.inverted, 0u);
  // No quad is near-degenerate (below the untangling's target) unless an input corner sharper than the SJ gate pins it.
  const QuadMetrics m = quad_metrics(r.mesh);
  const std::vector<std::uint8_t> pinned = quads_pinned_by_sharp_input(r.mesh, o.gates.min_scaled_jacobian, o.size.h);
  for (std::size_t k = 0; k < m.sj.size(); ++k)
    if (!pinned[k]) EXPECT_GE(m.sj[k], o.smooth.untangle.target_sj) << "quad " << k;
  return r;
}

}  // namespace

TEST(Coasts, DeltaWaterAt200MetresIsSemiStructured) {
  const Region region = coast("delta_water");
  MeshOptions o;
  o.size.h = 200.0;
  QualityReport q;
  const MeshResult r = mesh_checked(region, o, q);
  const auto& summary = r.report.summary;
  // The floors: 95 % of the quads from poly-square maps and touching no interior singular node, at most
  // 20 singular nodes per 1000 quads (Gmsh: 212).
  EXPECT_GE(summary.structured_fraction, 0.95);
  EXPECT_GE(q.regular_quad_fraction, 0.95);
  EXPECT_LE(1000.0 * static_cast<double>(q.interior_singularities) / static_cast<double>(r.mesh.quads.size()), 20.0);
  // Quads under the SJ gate that no repair mended are few, kept in their mapped subregions, and each reported.
  const QuadMetrics m = quad_metrics(r.mesh);
  std::size_t below = 0, gated = 0;
  for (double sj : m.sj) {
    below += sj < 0.3;
    gated += sj < o.gates.min_scaled_jacobian;
  }
  // The floor: at most 0.1 % below 0.3 (valid quads there are mended by local patches that do better).
  EXPECT_LE(static_cast<double>(below), 0.001 * static_cast<double>(r.mesh.quads.size()));
  EXPECT_LE(summary.sj_below_0_3_pinned, below);
  EXPECT_NEAR(q.sj_below_0_3_fraction, static_cast<double>(below) / static_cast<double>(r.mesh.quads.size()), 1e-12);
  EXPECT_LE(static_cast<double>(summary.poor_quads), o.gates.max_poor_fraction * static_cast<double>(r.mesh.quads.size()));
  EXPECT_LE(gated, summary.poor_quads);
  // No whole part fell back to split triangles.
  for (const auto& u : r.report.unstructured) EXPECT_NE(u.meshed_by, "split_triangles") << "part " << u.part << " subregion " << u.subregion;
  // Islands narrower than the size are left out, each reported narrower than h; the mesh boundary stays within h
  // of the input and lies on the region it was meshed against.
  EXPECT_GT(r.report.dropped_curves.size(), 0u);
  for (const auto& d : r.report.dropped_curves) {
    EXPECT_EQ(d.kind, "hole");
    EXPECT_LT(d.width, o.size.h);
  }
  DomainDistanceOptions measure;
  for (const auto& d : r.report.dropped_parts) measure.skip_parts.push_back(d.part);
  EXPECT_LT(domain_distance(r.mesh, r.region, measure).boundary_max_relative, 1e-9);
  EXPECT_LE(domain_distance(r.mesh, region, measure).boundary_max_distance, o.size.h);
  EXPECT_LT(std::abs(domain_distance(r.mesh, region, measure).area_relative_change), 0.03);
}

TEST(Coasts, FjordCoastAt400MetresIsSemiStructured) {
  // A coast nobody tuned the mesher to: its small parts' thin subregions fail their snaps or fold on the default
  // background triangulation, so a round on a finer one (MeshOptions::fine_parameterization_ratio) is tried.
  const Region region = coast("fjord_coast");
  MeshOptions o;
  o.size.h = 400.0;
  QualityReport q;
  const MeshResult r = mesh_checked(region, o, q);
  EXPECT_GE(r.report.summary.structured_fraction, 0.95);
  EXPECT_GE(q.regular_quad_fraction, 0.95);
  EXPECT_LE(1000.0 * static_cast<double>(q.interior_singularities) / static_cast<double>(r.mesh.quads.size()), 20.0);
  // The fine round runs exactly for the parts that no candidate of the default background meshes fully
  // structured, and this coast has such a part.
  int parts_fine = 0;
  for (const auto& part : r.report.candidates) {
    bool full = false, fine = false;
    for (const auto& c : part) {
      const bool on_fine = c.parameterization_ratio.value_or(0.0) == o.subregions.fine_parameterization_ratio;
      fine = fine || on_fine;
      full = full || (!on_fine && (c.measures ? c.measures->structured_fraction : 0.0) == 1.0);
    }
    EXPECT_EQ(fine, !full) << nlohmann::json(part).dump();
    parts_fine += fine;
  }
  EXPECT_GT(parts_fine, 0);
  for (const auto& u : r.report.unstructured) EXPECT_NE(u.meshed_by, "split_triangles") << "part " << u.part << " subregion " << u.subregion;
  DomainDistanceOptions measure;
  for (const auto& d : r.report.dropped_parts) measure.skip_parts.push_back(d.part);
  EXPECT_LT(domain_distance(r.mesh, r.region, measure).boundary_max_relative, 1e-9);
  EXPECT_LE(domain_distance(r.mesh, region, measure).boundary_max_distance, o.size.h);
}

TEST(Coasts, FjordCoastAt200MetresIsSemiStructured) {
  // The finer of the fjord's two sizes: its thin subregions fold near the shore before smoothing; untangling
  // (smooth/untangle.h) keeps them mapped instead of sending them to patches.
  const Region region = coast("fjord_coast");
  MeshOptions o;
  o.size.h = 200.0;
  QualityReport q;
  const MeshResult r = mesh_checked(region, o, q);
  EXPECT_GE(r.report.summary.structured_fraction, 0.95);
  EXPECT_GE(q.regular_quad_fraction, 0.95);
  EXPECT_LE(1000.0 * static_cast<double>(q.interior_singularities) / static_cast<double>(r.mesh.quads.size()), 20.0);
  // The floor of 0.1 % below SJ 0.3 (5 quads of 4,701 before local patches mended valid quads too).
  const QuadMetrics m = quad_metrics(r.mesh);
  EXPECT_LE(static_cast<double>(std::count_if(m.sj.begin(), m.sj.end(), [](double sj) { return sj < 0.3; })),
            0.001 * static_cast<double>(r.mesh.quads.size()));
  // The chosen mesh had folded or near-folded quads before its last smoothing, and fewer after untangling.
  const auto& untangle = r.report.smooth.untangle;
  EXPECT_GT(untangle.below_target_before, 0u);
  EXPECT_LT(untangle.below_target_after, untangle.below_target_before);
}
