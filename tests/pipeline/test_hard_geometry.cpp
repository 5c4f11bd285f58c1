// Hard geometry (tests/data/hard, made by scripts/make-hard-cases): every case gives a mesh that holds every
// invariant and the quality floors, or a precise refusal naming the file; never an invalid mesh.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <numbers>
#include <fstream>
#include <nlohmann/json.hpp>

#include "polysquare/core/error.h"
#include "polysquare/input/read_region.h"
#include "polysquare/pipeline/check_options.h"
#include "polysquare/pipeline/invariants.h"
#include "polysquare/pipeline/mesh_region.h"
#include "polysquare/quality/quality.h"

using namespace polysquare;
namespace fs = std::filesystem;

class HardGeometry : public ::testing::TestWithParam<std::string> {};

namespace {
// The refusals the hard cases get at their size, by the precise reason (empty: the case must mesh). A channel
// 1 wide and a sliver 0.5 wide at size 1 or 2 are narrower than two elements, which the size check refuses
// before any work; every other case meshes.
std::string refusal(const std::string& name) {
  if (name == "thin_channel") return "size 2 is larger than half the region's extent (100 x 1)";
  if (name == "sliver") return "size 1 is larger than half the region's extent (100 x 0.5)";
  return "";
}

// The quads no mesher can lift above the gate, judged from the input alone (not by the pipeline's own
// quads_pinned_by_sharp_input): those with a node within `reach` of an input ring vertex whose interior angle
// has a sine below the gate (a wedge sharper than asin(gate): any quad in its tip is as sharp).
std::vector<std::uint8_t> pinned_by_input(const QuadMesh& mesh, const Region& region, double gate, double reach) {
  std::vector<Vec2> tips;
  for (const Ring& r : region.rings) {
    const std::size_t n = r.points.size();
    for (std::size_t i = 0; i < n; ++i) {
      const Vec2 a = r.points[(i + n - 1) % n] - r.points[i], b = r.points[(i + 1) % n] - r.points[i];
      const double angle = std::atan2(std::abs(cross(a, b)), dot(a, b));  // the smaller angle between the edges
      if (std::sin(angle) < gate && angle < std::numbers::pi / 2) tips.push_back(r.points[i]);
    }
  }
  std::vector<std::uint8_t> pinned(mesh.quads.size(), 0);
  for (std::size_t q = 0; q < mesh.quads.size(); ++q)
    for (std::int32_t v : mesh.quads[q])
      for (Vec2 t : tips)
        if (distance(mesh.nodes[static_cast<std::size_t>(v)], t) <= reach) pinned[q] = 1;
  return pinned;
}
}  // namespace

TEST_P(HardGeometry, ValidMeshOrPreciseRefusal) {
  const fs::path path = fs::path(POLYSQUARE_TEST_DATA_DIR) / "hard" / (GetParam() + ".geojson");
  std::ifstream in(path);
  const double size = nlohmann::json::parse(in)["features"][0]["properties"]["size"].get<double>();
  MeshOptions options;
  options.size.h = size;
  try {
    const Region region = read_region(path);
    check_mesh_size(region, options);  // as the CLI does before meshing
    const MeshResult result = mesh_region(region, options);
    const InvariantReport inv = check_invariants(result.mesh);
    EXPECT_TRUE(inv.ok()) << inv.first_problem;
    // The gates judge every quad but those an input corner sharper than the gate pins (wedge_5deg's tip).
    const QuadMetrics metrics = quad_metrics(result.mesh);
    const auto pinned = pinned_by_input(result.mesh, region, options.gates.min_scaled_jacobian, options.size.h);
    // Quads outside the gates that no repair mended are accepted only within max_poor_fraction, and reported.
    std::size_t outside = 0;
    for (std::size_t k = 0; k < metrics.sj.size(); ++k)
      outside += !pinned[k] && (metrics.sj[k] < options.gates.min_scaled_jacobian || metrics.edge_ratio[k] > options.gates.max_edge_ratio);
    EXPECT_LE(static_cast<double>(outside), options.gates.max_poor_fraction * static_cast<double>(metrics.sj.size()));
    EXPECT_LE(result.report.summary.poor_quads,
              options.gates.max_poor_fraction * static_cast<double>(metrics.sj.size()));
    EXPECT_EQ(compute_quality(result.mesh).inverted, 0u);
    EXPECT_LT(domain_distance(result.mesh, result.region).boundary_max_relative, 1e-9);
    EXPECT_EQ(refusal(GetParam()), "") << GetParam() << " was expected to be refused";
  } catch (const InputError& e) {
    // Only the cases listed in refusal() may be refused, and only for the reason given there.
    EXPECT_NE(refusal(GetParam()), "") << GetParam() << " must mesh, was refused: " << e.what();
    EXPECT_NE(std::string(e.what()).find(path.filename().string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(refusal(GetParam())), std::string::npos) << e.what();
  } catch (const MeshingError& e) {
    ADD_FAILURE() << GetParam() << ": no hard case may end in a meshing failure: " << e.what();
  }
}

INSTANTIATE_TEST_SUITE_P(Cases, HardGeometry,
                         ::testing::Values("thin_channel", "wedge_5deg", "comb_50", "islands_200", "hole_near_boundary",
                                           "feature_near_boundary", "spiral_arm", "tiny_hole", "sliver"));

TEST(HardGeometry, CombAndIslandsAreMeshed) {
  // One poly-square serves a comb (50 teeth) and a square with 200 square islands well.
  for (const char* name : {"comb_50", "islands_200"}) {
    const fs::path path = fs::path(POLYSQUARE_TEST_DATA_DIR) / "hard" / (std::string(name) + ".geojson");
    MeshOptions options;
    options.size.h = std::string(name) == "comb_50" ? 0.5 : 1.0;
    const QuadMesh m = mesh_region(read_region(path), options).mesh;
    const QualityReport q = compute_quality(m);
    EXPECT_GT(q.sj.min, 0.5) << name;
    EXPECT_EQ(q.interior_singularities, 0u) << name;
  }
}

TEST(HardGeometry, ALargeConvolutedPartTriesOnePolySquareBesideItsPartitionOnlyUpToSingleMapQuads) {
  // comb_50 at 0.5 (about 20,000 quads, its boundary convoluted): one poly-square beside the partition, and it
  // wins (no singular node). With single_map_quads below its size the one poly-square is not meshed, since the
  // partition succeeds: the part is meshed one way.
  const fs::path path = fs::path(POLYSQUARE_TEST_DATA_DIR) / "hard" / "comb_50.geojson";
  const Region region = read_region(path);
  auto tried = [&](std::size_t single_map_quads, std::size_t& singles, bool& single_chosen) {
    MeshOptions options;
    options.size.h = 0.5;
    options.subregions.single_map_quads = single_map_quads;
    const MeshResult r = mesh_region(region, options);
    EXPECT_TRUE(check_invariants(r.mesh).ok());
    singles = 0;
    single_chosen = false;
    std::size_t all = 0;
    for (const auto& part : r.report.candidates)
      for (const auto& c : part) {
        ++all;
        if (c.subregions != 1) continue;
        ++singles;
        single_chosen = single_chosen || c.chosen;
      }
    return all;
  };
  std::size_t singles = 0;
  bool chosen = false;
  EXPECT_EQ(tried(MeshOptions{}.subregions.single_map_quads, singles, chosen), 2u);
  EXPECT_EQ(singles, 1u);
  EXPECT_TRUE(chosen);
  EXPECT_EQ(tried(10'000, singles, chosen), 1u);
  EXPECT_EQ(singles, 0u);
}

TEST(HardGeometry, APartFinerThanTheSizeThroughoutIsMeshedByTheFallbackWithoutMaps) {
  // 64 spikes, each 0.5 h wide at its base and 20 h long: about 33,000 background triangles for 393 quads.
  // Deforming them is what every map candidate would do for minutes; past max_triangles_per_quad none is tried.
  const fs::path path = fs::path(POLYSQUARE_TEST_DATA_DIR) / "adversarial" / "star_64_spikes.geojson";
  const Region region = read_region(path);
  MeshOptions options;
  options.size.h = 2;
  const MeshResult r = mesh_region(region, options);
  EXPECT_TRUE(check_invariants(r.mesh).ok());
  EXPECT_EQ(compute_quality(r.mesh).inverted, 0u);
  EXPECT_EQ(r.report.summary.structured_fraction, 0.0);
  std::size_t maps = 0;
  for (const auto& part : r.report.candidates)
    for (const auto& c : part) {
      if (c.chosen) continue;  // the fallback
      ++maps;
      EXPECT_NE(c.error.value_or("").find("per quad"), std::string::npos) << nlohmann::json(c).dump();
    }
  EXPECT_GT(maps, 0u);
}
