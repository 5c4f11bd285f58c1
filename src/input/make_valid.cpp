#include "polysquare/input/make_valid.h"

#include <ogr_geometry.h>

#include <memory>

namespace polysquare {
namespace {

std::unique_ptr<OGRPolygon> to_ogr(const Region& region, int part) {
  auto poly = std::make_unique<OGRPolygon>();
  // Outer ring first, as OGR expects.
  for (int pass = 0; pass < 2; ++pass)
    for (const Ring& r : region.rings) {
      if (r.part != part || r.hole != (pass == 1)) continue;
      OGRLinearRing ring;
      for (Vec2 p : r.points) ring.addPoint(p.x, p.y);
      ring.addPoint(r.points.front().x, r.points.front().y);
      poly->addRing(&ring);
    }
  return poly;
}

void add_polygon(const OGRPolygon& poly, int part, int source, std::vector<Ring>& out) {
  for (int k = 0; k <= poly.getNumInteriorRings(); ++k) {
    const OGRLinearRing* ring = k == 0 ? poly.getExteriorRing() : poly.getInteriorRing(k - 1);
    if (!ring) continue;
    Ring r;
    r.part = part;
    r.hole = k > 0;
    r.source_feature = source;
    for (int i = 0; i + 1 < ring->getNumPoints(); ++i) r.points.push_back({ring->getX(i), ring->getY(i)});
    out.push_back(std::move(r));
  }
}

}  // namespace

std::size_t make_parts_valid(Region& region, std::vector<std::string>* repairs) {
  std::vector<Ring> rings;
  int parts = 0;
  std::size_t repaired = 0;
  for (int part = 0; part < region.num_parts; ++part) {
    int source = -1;
    std::string name;
    double size = 0.0;
    for (const Ring& r : region.rings)
      if (r.part == part) source = r.source_feature, name = r.name, size = r.size;
    const auto poly = to_ogr(region, part);
    if (poly->IsValid()) {
      for (const Ring& r : region.rings)
        if (r.part == part) { rings.push_back(r); rings.back().part = parts; }
      ++parts;
      continue;
    }
    // STRUCTURE keeps the area inside the outer ring minus the holes (a hole poking out of its polygon cuts a
    // notch); the default LINEWORK would keep the outside part of the hole as a polygon of its own.
    const char* method[] = {"METHOD=STRUCTURE", nullptr};
    std::unique_ptr<OGRGeometry> fixed(poly->MakeValid(method));
    std::size_t made = 0;
    auto take = [&](const OGRGeometry* g) {
      if (!g || wkbFlatten(g->getGeometryType()) != wkbPolygon) return;  // lines and points of a collapse are dropped
      const auto* p = g->toPolygon();
      if (p->get_Area() <= 0.0) return;
      const std::size_t first = rings.size();
      add_polygon(*p, parts++, source, rings);
      for (std::size_t k = first; k < rings.size(); ++k) rings[k].name = name, rings[k].size = size;
      ++made;
    };
    if (fixed && wkbFlatten(fixed->getGeometryType()) == wkbPolygon) take(fixed.get());
    else if (fixed && OGR_GT_IsSubClassOf(wkbFlatten(fixed->getGeometryType()), wkbGeometryCollection))
      for (const OGRGeometry* g : *fixed->toGeometryCollection()) take(g);
    ++repaired;
    if (repairs)
      repairs->push_back(region.source + ": feature " + std::to_string(source) + ": polygon " + std::to_string(part) +
                         " was invalid (self-intersecting ring or crossing hole); made valid as " + std::to_string(made) + " polygon(s)");
  }
  region.rings = std::move(rings);
  region.num_parts = parts;
  return repaired;
}

}  // namespace polysquare
