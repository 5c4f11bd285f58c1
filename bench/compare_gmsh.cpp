// Side-by-side with Gmsh 4.8.4 (Frontal-Delaunay + Blossom, the Gmsh baseline of data/cases/PROVENANCE.md) on the bundled cases, in
// the same run: wall time (median of --repeat runs), quads, SJ min, eta min, skew max, edge ratio max, interior
// singularities, and ratios. Usage: compare_gmsh [--repeat N] [case:size[:gmsh_size] ...]; with gmsh_size, Gmsh
// meshes at that size instead (delta_water:40:200 sets polysquare at 40 m against Gmsh's ~100k quads at 200 m).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "polysquare/core/error.h"
#include "polysquare/input/read_region.h"
#include "polysquare/io/mesh_io.h"
#include "polysquare/pipeline/mesh_region.h"
#include "polysquare/quality/quality.h"

using namespace polysquare;
namespace fs = std::filesystem;

namespace {
double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}
double seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}
}  // namespace

int main(int argc, char** argv) {
  int repeat = 3;
  std::vector<std::string> cases;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--repeat" && i + 1 < argc) repeat = std::max(1, std::atoi(argv[++i]));
    else cases.push_back(a);
  }
  if (cases.empty())
    cases = {"letter_I:2", "letter_M:2", "letter_R:2", "pentagon:3", "triangle:3", "square_feature:3", "rect_feature:3",
             "smile:2.5", "turtle_shell:2.5", "mechanical_part:3", "dam_channel:2", "key:2"};
  const fs::path tmp = fs::temp_directory_path() / ("polysquare_bench_" + std::to_string(::getpid()));
  fs::create_directories(tmp);
  std::printf("%-16s %4s | %-9s %7s %6s %6s %6s %7s %5s | %7s %7s %6s %5s | %9s %9s\n", "case", "h", "tool", "quads",
              "SJmin", "etamin", "skew", "edgeR", "intS", "time s", "", "", "", "time x", "intS x");
  for (const std::string& spec : cases) {
    const std::string name = spec.substr(0, spec.find(':'));
    const std::string sizes = spec.substr(spec.find(':') + 1);
    const double h = std::stod(sizes);
    const double gmsh_h = sizes.find(':') == std::string::npos ? h : std::stod(sizes.substr(sizes.find(':') + 1));
    const std::string input = std::string(POLYSQUARE_DATA_DIR) + "/cases/" + name + ".geojson";
    // polysquare
    std::vector<double> ours_t;
    QualityReport ours{};
    std::string ours_error;
    for (int r = 0; r < repeat && ours_error.empty(); ++r) {
      const auto t0 = std::chrono::steady_clock::now();
      try {
        const Region region = read_region(input);
        MeshOptions o;
        o.size.h = h;
        const MeshResult res = mesh_region(region, o);
        ours_t.push_back(seconds(t0));
        ours = compute_quality(res.mesh);
      } catch (const std::exception& e) {
        ours_error = e.what();
      }
    }
    // Gmsh
    const fs::path geo = tmp / (name + ".geo"), msh = tmp / (name + ".msh");
    const std::string make = std::string(POLYSQUARE_SOURCE_DIR) + "/scripts/make-gmsh-geo " + input + " " + std::to_string(gmsh_h) + " " + geo.string();
    std::vector<double> gmsh_t;
    QualityReport theirs{};
    bool gmsh_ok = std::system(make.c_str()) == 0;
    for (int r = 0; r < repeat && gmsh_ok; ++r) {
      const std::string cmd = "gmsh " + geo.string() + " -2 -nt 2 -format msh41 -o " + msh.string() + " > /dev/null 2>&1";
      const auto t0 = std::chrono::steady_clock::now();
      gmsh_ok = std::system(cmd.c_str()) == 0;
      gmsh_t.push_back(seconds(t0));
    }
    if (gmsh_ok) theirs = compute_quality(read_mesh(msh));
    auto row = [&](const char* tool, double size, const QualityReport& q, double t) {
      std::printf("%-16s %4.1f | %-9s %7zu %6.3f %6.3f %6.3f %7.2f %5zu | %7.3f", name.c_str(), size, tool, q.quads, q.sj.min,
                  q.eta.min, q.skew.max, q.edge_ratio.max, q.interior_singularities, t);
    };
    if (gmsh_ok) { row("gmsh", gmsh_h, theirs, median(gmsh_t)); std::printf("  (%zu triangles left)\n", theirs.triangles); }
    else std::printf("%-16s %4.1f | gmsh failed on this input (e.g. Blossom found no perfect matching)\n", name.c_str(), gmsh_h);
    if (!ours_error.empty()) {
      std::printf("%-16s %4.1f | polysquare refused: %.150s\n", name.c_str(), h, ours_error.c_str());
      continue;
    }
    row("polysquare", h, ours, median(ours_t));
    if (gmsh_ok)
      std::printf("  %29s %8.2f %9.3f\n", "ratio polysquare/gmsh:", median(ours_t) / median(gmsh_t),
                  theirs.interior_singularities ? double(ours.interior_singularities) / double(theirs.interior_singularities) : 0.0);
    else
      std::printf("\n");
  }
  fs::remove_all(tmp);
  return 0;
}
