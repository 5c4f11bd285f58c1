// polysquare judges Gmsh's meshes with the same code as its own: the Gmsh 4.8.4 mesh of letter_R, in every
// format, reproduces its row of the Gmsh reference figures in data/cases/PROVENANCE.md.
#include <gtest/gtest.h>

#include <string>

#include "polysquare/io/mesh_io.h"
#include "polysquare/quality/quality.h"

using namespace polysquare;

class GmshReference : public ::testing::TestWithParam<const char*> {};

TEST_P(GmshReference, ReproducesTheAnchorsRowOfLetterR) {
  const QuadMesh m = read_mesh(std::string(POLYSQUARE_TEST_DATA_DIR) + "/gmsh/" + GetParam());
  const QualityReport q = compute_quality(m);
  EXPECT_EQ(q.quads, 1036u);
  EXPECT_EQ(q.triangles, 4u);
  EXPECT_EQ(q.inverted, 0u);  // Gmsh's clockwise surface is read counter-clockwise
  EXPECT_NEAR(q.sj.min, 0.62, 0.01);
  EXPECT_NEAR(q.eta.min, 0.82, 0.01);
  EXPECT_NEAR(q.skew.max, 0.57, 0.01);
  EXPECT_NEAR(q.edge_ratio.max, 2.58, 0.01);
  EXPECT_EQ(q.interior_singularities, 152u);
}

INSTANTIATE_TEST_SUITE_P(Formats, GmshReference,
                         ::testing::Values("letter_R_msh22_ascii.msh", "letter_R_msh22_binary.msh",
                                           "letter_R_msh41_ascii.msh", "letter_R_msh41_binary.msh",
                                           "letter_R_meshio.vtu"),
                         [](const auto& info) {
                           std::string n = info.param;
                           for (char& c : n) if (c == '.') c = '_';
                           return n;
                         });
