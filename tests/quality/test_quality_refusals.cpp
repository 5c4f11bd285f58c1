// polysquare quality must not hide bad meshes: no quads, non-finite nodes, 3D cells are refused; a degenerate or
// non-finite quad counts as inverted rather than vanishing from the minimum.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>

#include "polysquare/core/error.h"
#include "polysquare/io/mesh_io.h"
#include "polysquare/quality/quality.h"

using namespace polysquare;
namespace fs = std::filesystem;

namespace {
std::string adversarial(const std::string& name) {
  return (fs::path(POLYSQUARE_TEST_DATA_DIR) / "adversarial" / name).string();
}
QuadMesh unit_quads() {
  QuadMesh m;
  m.nodes = {{0, 0}, {1, 0}, {1, 1}, {0, 1}, {2, 0}, {2, 1}};
  m.quads = {{0, 1, 2, 3}, {1, 4, 5, 2}};
  return m;
}
}  // namespace

TEST(QualityRefusals, NonFiniteNodesAreRefusedAndCountAsInverted) {
  for (const char* f : {"quality_nan.msh", "quality_inf.msh"}) {
    const QuadMesh m = read_mesh(adversarial(f));
    // Judged anyway (as the library may be), the quad is inverted and the minimum is not 1.
    const QualityReport q = compute_quality(m);
    EXPECT_EQ(q.inverted, 1u) << f;
    EXPECT_LE(q.sj.min, 0.0) << f;
    try {
      check_judgeable(m, f);
      ADD_FAILURE() << f << " judged";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("node 4 has a non-finite coordinate"), std::string::npos) << e.what();
    }
  }
}

TEST(QualityRefusals, MeshesWithoutQuadsAreRefused) {
  for (const char* f : {"quality_no_cells.vtu", "quality_triangles_only.msh"}) {
    const QuadMesh m = read_mesh(adversarial(f));
    EXPECT_TRUE(m.quads.empty());
    EXPECT_THROW(check_judgeable(m, f), InputError) << f;
  }
  EXPECT_NO_THROW(check_judgeable(unit_quads(), "two quads"));
}

TEST(QualityRefusals, VolumeCellsAreRefusedByTheReaders) {
  try {
    read_mesh(adversarial("quality_hexahedra.vtu"));
    ADD_FAILURE() << "hexahedra read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("VTK type 12"), std::string::npos) << e.what();
  }
  const std::string hex_msh = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n8\n1 0 0 0\n2 1 0 0\n3 1 1 0\n4 0 1 0\n"
                              "5 0 0 1\n6 1 0 1\n7 1 1 1\n8 0 1 1\n$EndNodes\n$Elements\n1\n1 5 2 1 1 1 2 3 4 5 6 7 8\n"
                              "$EndElements\n";
  EXPECT_THROW(parse_msh(hex_msh, "hex.msh"), InputError);
}

TEST(QualityRefusals, AreaMismatchMeasuresAWrongRegion) {
  const QuadMesh m = unit_quads();
  EXPECT_DOUBLE_EQ(mesh_area(m), 2.0);
  Region r;
  r.rings.push_back({{{0, 0}, {2, 0}, {2, 1}, {0, 1}}, 0, false, 0});
  r.num_parts = 1;
  EXPECT_NEAR(area_relative_mismatch(m, r, {}), 0.0, 1e-15);
  r.rings.push_back({{{0.5, 0.25}, {0.5, 0.75}, {1.5, 0.75}, {1.5, 0.25}}, 0, true, 0});  // a lake of 0.5
  EXPECT_NEAR(area_relative_mismatch(m, r, {}), 2.0 / 1.5 - 1.0, 1e-12);
  // Far from the origin the areas keep their digits.
  QuadMesh far = m;
  for (Vec2& p : far.nodes) p = {p.x + 1e11, p.y + 1e11};
  EXPECT_NEAR(mesh_area(far), 2.0, 1e-4);
}
