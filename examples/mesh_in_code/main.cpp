// Meshes a region built in code with the polysquare library: a 100 x 60 plate with a square hole and a feature
// curve across it (a seam the mesh must follow), at element size 4. Writes the mesh (Gmsh MSH, or whatever the
// output's extension names) and prints its quality.
//
//   mesh_in_code [OUTPUT.msh]      exit 0 when the mesh holds the invariants, 1 otherwise
#include <exception>
#include <iostream>

#include "polysquare/core/error.h"
#include "polysquare/core/region.h"
#include "polysquare/core/version.h"
#include "polysquare/input/read_region.h"
#include "polysquare/io/mesh_io.h"
#include "polysquare/pipeline/invariants.h"
#include "polysquare/pipeline/mesh_region.h"
#include "polysquare/quality/quality.h"

int main(int argc, char** argv) {
  using namespace polysquare;
  try {
    Region region;
    // Outer ring counter-clockwise, the hole clockwise (validate_region orients them anyway).
    region.rings.push_back({{{0, 0}, {100, 0}, {100, 60}, {0, 60}}, /*part=*/0, /*hole=*/false});
    region.rings.push_back({{{60, 20}, {60, 40}, {80, 40}, {80, 20}}, /*part=*/0, /*hole=*/true});
    // A seam from the bottom edge to the top edge, left of the hole: it must become a chain of mesh edges.
    region.features.push_back({{{30, 0}, {30, 60}}, /*closed=*/false});
    region.num_parts = 1;
    region.units = "mm";
    region.source = "plate built in code";
    validate_region(region);  // throws InputError naming what is wrong

    MeshOptions options;
    options.size.h = 4.0;  // target quad edge length, in region units
    options.run.threads = 2;
    const MeshResult result = mesh_region(region, options);

    const InvariantReport invariants = check_invariants(result.mesh);
    const QualityReport quality = compute_quality(result.mesh);
    const DomainDistance distance = domain_distance(result.mesh, result.region);
    std::cout << "polysquare " << library_version() << ": " << quality.quads << " quads, " << quality.triangles
              << " triangles, scaled Jacobian min " << quality.sj.min << ", " << quality.interior_singularities
              << " interior singularities, structured fraction " << result.report.summary.structured_fraction
              << ", feature max distance " << distance.feature_max_distance << "\n";
    if (argc > 1) write_mesh(argv[1], result.mesh);
    if (!invariants.ok()) {
      std::cerr << "invariant broken: " << invariants.first_problem << "\n";
      return 1;
    }
    if (quality.quads == 0 || quality.triangles != 0 || result.mesh.feature_edges.empty()) {
      std::cerr << "unexpected mesh: " << quality.quads << " quads, " << quality.triangles << " triangles, "
                << result.mesh.feature_edges.size() << " feature edges\n";
      return 1;
    }
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 1;
  }
}
