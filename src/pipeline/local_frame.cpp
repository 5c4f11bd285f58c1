#include "polysquare/pipeline/local_frame.h"

#include <cmath>

namespace polysquare {

Vec2 local_origin(const Region& region) {
  const Box2 box = region.bounding_box();
  const double diag = box.diagonal();
  if (!(diag > 0) || !std::isfinite(diag)) return {0, 0};
  const Vec2 centre{0.5 * (box.lo.x + box.hi.x), 0.5 * (box.lo.y + box.hi.y)};
  if (std::max(std::abs(centre.x), std::abs(centre.y)) <= 1e4 * diag) return {0, 0};
  // A multiple of 2^k >= diag: every coordinate x of the region is a multiple of ulp(x) <= 2^k, so x - origin is
  // a multiple of ulp(x) smaller than |x| in magnitude, hence exact.
  const double step = std::exp2(std::ceil(std::log2(diag)));
  return {std::round(centre.x / step) * step, std::round(centre.y / step) * step};
}

void translate(Region& region, Vec2 offset) {
  for (std::vector<Ring>* rings : {&region.rings, &region.size_areas})
    for (Ring& r : *rings)
      for (Vec2& p : r.points) p = {p.x + offset.x, p.y + offset.y};
  for (FeatureCurve& c : region.features)
    for (Vec2& p : c.points) p = {p.x + offset.x, p.y + offset.y};
  for (Vec2& p : region.feature_points) p = {p.x + offset.x, p.y + offset.y};
}

void translate(QuadMesh& mesh, Vec2 offset) {
  for (Vec2& p : mesh.nodes) p = {p.x + offset.x, p.y + offset.y};
}

std::int64_t first_folded_quad(const QuadMesh& mesh) {
  for (std::size_t q = 0; q < mesh.quads.size(); ++q)
    for (int k = 0; k < 4; ++k) {
      const Vec2 p = mesh.nodes[static_cast<std::size_t>(mesh.quads[q][k])];
      const Vec2 next = mesh.nodes[static_cast<std::size_t>(mesh.quads[q][(k + 1) % 4])];
      const Vec2 prev = mesh.nodes[static_cast<std::size_t>(mesh.quads[q][(k + 3) % 4])];
      if (!(cross(next - p, prev - p) > 0)) return static_cast<std::int64_t>(q);
    }
  return -1;
}

}  // namespace polysquare
