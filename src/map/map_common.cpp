#include "map/map_common.h"

#include <cmath>
#include <limits>
#include <complex>
#include <numbers>

#include "polysquare/core/error.h"
#include "polysquare/map/extract.h"
#include "polysquare/map/polysquare_map.h"
#include "polysquare/map/quantize.h"

namespace polysquare {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

std::string invalid_poly_square(const Layout& layout, const std::string& name) {
  const std::string problem = check_layout(layout);
  return problem.empty() ? std::string() : name + ": the quantized poly-square is not valid: " + problem;
}

double preorientation_angle(const std::vector<Vec2>& points, const std::vector<std::array<std::int32_t, 2>>& edges) {
  std::complex<double> sum{0.0, 0.0};
  for (const auto& e : edges) {
    const Vec2 d = points[e[1]] - points[e[0]];
    const double len = norm(d);
    if (len <= 0.0) continue;
    const double phi = std::atan2(d.y, d.x);  // direction angle; the normal differs by pi/2, same 4*phi class
    sum += len * std::polar(1.0, 4.0 * phi);
  }
  if (std::abs(sum) < 1e-12) return 0.0;
  return -std::arg(sum) / 4.0;
}

double local_size(const TriMesh& tri, const PolysquareMapOptions& options, std::vector<double>* ratios) {
  if (!options.size_field) return options.size;
  if (ratios) ratios->resize(tri.triangles.size());
  double area = 0.0, quads = 0.0;
  for (std::size_t t = 0; t < tri.triangles.size(); ++t) {
    const auto& k = tri.triangles[t];
    const Vec2 a = tri.vertices[k[0]], b = tri.vertices[k[1]], d = tri.vertices[k[2]];
    const double r = options.size_field->at((1.0 / 3.0) * (a + b + d)) / options.size;
    if (ratios) (*ratios)[t] = r;
    const double at = 0.5 * std::abs(orient2(a, b, d));
    area += at;
    quads += at / (r * r);
  }
  return quads > 0.0 ? options.size * std::sqrt(area / quads) : options.size;
}

double least_size(const TriMesh& tri, const PolysquareMapOptions& options) {
  if (!options.size_field) return options.size;
  double least = std::numeric_limits<double>::infinity();
  for (const auto& k : tri.triangles)
    least = std::min(least, options.size_field->at((1.0 / 3.0) * (tri.vertices[k[0]] + tri.vertices[k[1]] + tri.vertices[k[2]])));
  return std::isfinite(least) ? least : options.size;
}

namespace {

// Graded meshes: each triangle's rest shape in lattice units of the size at its centroid, as a scale of the
// rest positions (problem.rest_scale) laid out in units of the mean size (local_size), so that the start shape
// is near every scale. Returns that mean over options.size.
double graded_rest_scales(const TriMesh& tri, const PolysquareMapOptions& options, DeformProblem& problem) {
  if (!options.size_field) return 1.0;
  std::vector<double> ratio;
  const double mean = local_size(tri, options, &ratio) / options.size;
  problem.rest_scale.resize(ratio.size());
  for (std::size_t t = 0; t < ratio.size(); ++t) problem.rest_scale[t] = mean / ratio[t];
  return mean;
}

// The deformation problem of `tri` (rest shape centred, pre-oriented and in lattice units) and the edges its
// pre-orientation reads.
MappedMesh deformation_problem(const TriMesh& tri, const PolysquareMapOptions& options, bool orient_all_chains,
                               std::vector<std::array<std::int32_t, 2>>& orient_edges) {
  MappedMesh mm;
  DeformProblem& problem = mm.problem;
  problem.triangles = tri.triangles;
  for (const TriChain& ch : tri.chains) {
    const int n = static_cast<int>(ch.vertices.size());
    const int m = ch.closed ? n : n - 1;
    // Separators are pulled to the axes like the boundary: every subregion must become a poly-square.
    const double w = ch.kind == TriChain::Kind::feature ? options.deform.feature_weight : options.deform.boundary_weight;
    const bool orient = orient_all_chains ? ch.kind != TriChain::Kind::feature || ch.interface >= 0
                                          : ch.kind == TriChain::Kind::ring;
    for (int i = 0; i < m; ++i) {
      const std::int32_t a = ch.vertices[i], b = ch.vertices[(i + 1) % n];
      problem.aligned.push_back({a, b, w});
      if (orient) orient_edges.push_back({a, b});
    }
  }
  // Rest shape in lattice units (1 = one quad edge), centred and pre-oriented.
  const Box2 box = [&] { Box2 b; for (Vec2 p : tri.vertices) b.add(p); return b; }();
  const Vec2 centre = 0.5 * (box.lo + box.hi);
  const double theta = options.preorient ? preorientation_angle(tri.vertices, orient_edges) : 0.0;
  mm.rotation_deg = theta * 180.0 / std::numbers::pi;
  const double c = std::cos(theta), s = std::sin(theta), h = options.size * graded_rest_scales(tri, options, problem);
  problem.rest.reserve(tri.vertices.size());
  for (Vec2 p : tri.vertices) {
    const Vec2 q = p - centre;
    problem.rest.push_back({(c * q.x - s * q.y) / h, (s * q.x + c * q.y) / h});
  }
  return mm;
}

}  // namespace

MappedMesh deform_mesh(const TriMesh& tri, const PolysquareMapOptions& options, bool orient_all_chains) {
  std::vector<std::array<std::int32_t, 2>> orient_edges;
  MappedMesh mm = deformation_problem(tri, options, orient_all_chains, orient_edges);
  mm.x = mm.problem.rest;
  mm.stats = deform_to_polysquare(mm.problem, options.deform, mm.x);
  return mm;
}

MappedMesh deformed_mesh(const TriMesh& tri, const PolysquareMapOptions& options, std::vector<Vec2> deformed) {
  std::vector<std::array<std::int32_t, 2>> orient_edges;
  MappedMesh mm = deformation_problem(tri, options, true, orient_edges);
  // Turned so that its sides run along the axes, as a deformation from the rest shape would leave them.
  Vec2 centre{0.0, 0.0};
  for (Vec2 p : deformed) centre = centre + p;
  if (!deformed.empty()) centre = (1.0 / static_cast<double>(deformed.size())) * centre;
  const double theta = preorientation_angle(deformed, orient_edges), c = std::cos(theta), s = std::sin(theta);
  for (Vec2& p : deformed) {
    const Vec2 q = p - centre;
    p = {c * q.x - s * q.y, s * q.x + c * q.y};
  }
  mm.x = std::move(deformed);
  return mm;
}

void straighten_to_labels(MappedMesh& mm, Layout& layout, const TriMesh& tri, const PolysquareMapOptions& options) {
  if (options.label_weights.empty()) return;
  DeformProblem problem = mm.problem;
  problem.aligned.clear();
  for (std::size_t c = 0; c < tri.chains.size(); ++c) {
    const TriChain& ch = tri.chains[c];
    const int n = static_cast<int>(ch.vertices.size());
    const int m = ch.closed ? n : n - 1;
    for (int i = 0; i < m; ++i)
      problem.aligned.push_back({ch.vertices[i], ch.vertices[(i + 1) % n], 1.0, layout.chain_labels[c][i]});
  }
  DeformOptions o = options.deform;
  o.eps_schedule = {o.eps_schedule.empty() ? 0.01 : o.eps_schedule.back()};
  for (double w : options.label_weights) {
    for (AlignedEdge& e : problem.aligned) e.weight = w;
    const DeformStats s = deform_to_polysquare(problem, o, mm.x);
    mm.stats.iterations += s.iterations;
  }
  for (LayoutSegment& s : layout.segments)
    s.target = distance(mm.x[layout.break_vertex[s.break_a]], mm.x[layout.break_vertex[s.break_b]]);
}

bool snap_to_layout(const TriMesh& tri, MappedMesh& mm, const Layout& layout, const PolysquareMapOptions& options,
                    const std::string& name) {
  std::vector<Vec2> targets;
  std::vector<std::uint8_t> mask;
  polysquare_targets(tri, tri.vertices, mm.x, layout, targets, mask);
  bool untangled = false;
  if (!move_constrained_vertices(mm.problem, options.deform, mask, targets, mm.x, &untangled))
    throw MeshingError(name + ": the deformation cannot reach the quantized poly-square without inverting triangles [" +
                       std::to_string(layout.segments.size()) + " sides]");
  return untangled;
}

}  // namespace polysquare
