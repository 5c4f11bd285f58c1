#include "polysquare/input/boundary_segments.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "polysquare/core/error.h"

namespace polysquare {
namespace {

double distance_to_ring(Vec2 p, const std::vector<Vec2>& ring) {
  double d = INFINITY;
  for (std::size_t i = 0; i < ring.size(); ++i) d = std::min(d, point_segment_distance(p, ring[i], ring[(i + 1) % ring.size()]));
  return d;
}

// Arc length from vertex 0 to the point of the ring nearest to p.
double arc_position(Vec2 p, const std::vector<Vec2>& ring) {
  double best = INFINITY, at = 0.0, run = 0.0;
  for (std::size_t i = 0; i < ring.size(); ++i) {
    const Vec2 a = ring[i], b = ring[(i + 1) % ring.size()];
    const Vec2 d = b - a;
    const double len = std::sqrt(dot(d, d));
    const double t = len > 0 ? std::clamp(dot(p - a, d) / (len * len), 0.0, 1.0) : 0.0;
    const double dist = distance(p, lerp(a, b, t));
    if (dist < best) best = dist, at = run + t * len;
    run += len;
  }
  return at;
}

double ring_length(const std::vector<Vec2>& ring) {
  double s = 0.0;
  for (std::size_t i = 0; i < ring.size(); ++i) s += distance(ring[i], ring[(i + 1) % ring.size()]);
  return s;
}

// The ring vertex p becomes: an existing vertex within tol, else p projected onto the nearest edge and inserted.
Vec2 put_on_ring(Vec2 p, std::vector<Vec2>& ring, double tol) {
  std::size_t best_vertex = 0;
  for (std::size_t i = 1; i < ring.size(); ++i)
    if (distance(p, ring[i]) < distance(p, ring[best_vertex])) best_vertex = i;
  if (distance(p, ring[best_vertex]) <= tol) return ring[best_vertex];
  std::size_t edge = 0;
  double best = INFINITY;
  for (std::size_t i = 0; i < ring.size(); ++i) {
    const double d = point_segment_distance(p, ring[i], ring[(i + 1) % ring.size()]);
    if (d < best) best = d, edge = i;
  }
  const Vec2 a = ring[edge], b = ring[(edge + 1) % ring.size()], d = b - a;
  const Vec2 q = lerp(a, b, std::clamp(dot(p - a, d) / dot(d, d), 0.0, 1.0));
  ring.insert(ring.begin() + static_cast<std::ptrdiff_t>(edge + 1), q);
  return q;
}

std::size_t vertex_index(const std::vector<Vec2>& ring, Vec2 p) {
  return static_cast<std::size_t>(std::find(ring.begin(), ring.end(), p) - ring.begin());
}

}  // namespace

void place_boundary_segments(Region& region, double tolerance) {
  const std::string& src = region.source;
  for (std::size_t s = 0; s < region.boundary_segments.size(); ++s) {
    BoundarySegment& b = region.boundary_segments[s];
    const std::string what = src + ": feature " + std::to_string(b.source_feature) + " (boundary line " + std::to_string(s) + ")";
    std::vector<Vec2> line = b.line;
    line.erase(std::unique(line.begin(), line.end()), line.end());
    for (Vec2 p : line)
      if (!std::isfinite(p.x) || !std::isfinite(p.y)) throw InputError(what + " has a non-finite coordinate " + point_text(p));
    if (line.size() < 2) throw InputError(what + " has fewer than 2 distinct points" + (line.empty() ? std::string() : ", at " + point_text(line.front())));
    const bool closed = line.size() >= 3 && line.front() == line.back();
    // Probe points: every vertex and the middle of every segment of the line.
    std::vector<Vec2> probes;
    for (std::size_t i = 0; i < line.size(); ++i) {
      probes.push_back(line[i]);
      if (i + 1 < line.size()) probes.push_back(lerp(line[i], line[i + 1], 0.5));
    }
    int ring = -1;
    double best_far = INFINITY;
    Vec2 best_at = line.front();
    int best_ring = -1;
    for (std::size_t r = 0; r < region.rings.size() && ring < 0; ++r) {
      double far = 0.0;
      Vec2 at = line.front();
      for (Vec2 p : probes) {
        const double d = distance_to_ring(p, region.rings[r].points);
        if (d > far) far = d, at = p;
      }
      if (far <= tolerance) ring = static_cast<int>(r);
      else if (far < best_far) best_far = far, best_at = at, best_ring = static_cast<int>(r);
    }
    if (ring < 0) {
      bool inside = true;
      for (Vec2 p : probes) {
        bool in = false;
        for (const Ring& r : region.rings)
          if (point_in_ring(p, r.points)) in = !in;
        inside = inside && in;
      }
      std::ostringstream far;
      far.precision(6);
      far << best_far;
      throw InputError(what + " is not on the domain boundary: its point " + point_text(best_at) + " is " + far.str() +
                       " from ring " + std::to_string(best_ring) +
                       (inside ? " (it lies inside the domain: give it the role \"feature\" to make it a feature curve)"
                               : " (a boundary segment must lie along one ring)"));
    }
    auto& pts = region.rings[static_cast<std::size_t>(ring)].points;
    b.ring = ring;
    b.start = put_on_ring(line.front(), pts, tolerance);
    b.end = closed ? b.start : put_on_ring(line.back(), pts, tolerance);
    if (!closed && b.start == b.end) throw InputError(what + " is shorter than the tolerance, at " + point_text(line.front()));
    if (!closed) {
      // The covered arc is the one holding the line's first middle point.
      const double length = ring_length(pts);
      auto ahead = [&](double from, double to) { return std::fmod(to - from + 2.0 * length, length); };
      const double s0 = arc_position(b.start, pts), s1 = arc_position(b.end, pts);
      const double sp = arc_position(lerp(line[0], line[1], 0.5), pts);
      if (ahead(s0, sp) > ahead(s0, s1)) std::swap(b.start, b.end);
    }
    for (Vec2 p : {b.start, b.end})
      if (std::find(region.feature_points.begin(), region.feature_points.end(), p) == region.feature_points.end())
        region.feature_points.push_back(p);
  }
  // Segments of one ring may share end points but not edges.
  std::vector<std::vector<int>> owner(region.rings.size());
  for (std::size_t r = 0; r < region.rings.size(); ++r) owner[r].assign(region.rings[r].points.size(), -1);
  for (std::size_t s = 0; s < region.boundary_segments.size(); ++s) {
    const BoundarySegment& b = region.boundary_segments[s];
    const auto verts = segment_ring_vertices(region, b);
    const auto& pts = region.rings[static_cast<std::size_t>(b.ring)].points;
    for (std::size_t k = 0; k + 1 < verts.size(); ++k) {
      int& o = owner[static_cast<std::size_t>(b.ring)][verts[k]];  // the edge from verts[k] to the next vertex
      if (o >= 0)
        throw InputError(src + ": feature " + std::to_string(b.source_feature) + " (boundary line " + std::to_string(s) +
                         ") overlaps boundary line " + std::to_string(o) + " (feature " +
                         std::to_string(region.boundary_segments[static_cast<std::size_t>(o)].source_feature) + ") along ring " +
                         std::to_string(b.ring) + " at " + point_text(lerp(pts[verts[k]], pts[verts[k + 1]], 0.5)));
      o = static_cast<int>(s);
    }
  }
}

std::vector<std::size_t> segment_ring_vertices(const Region& region, const BoundarySegment& segment) {
  if (segment.ring < 0 || static_cast<std::size_t>(segment.ring) >= region.rings.size()) return {};
  const auto& pts = region.rings[static_cast<std::size_t>(segment.ring)].points;
  const std::size_t a = vertex_index(pts, segment.start), b = vertex_index(pts, segment.end);
  if (a >= pts.size() || b >= pts.size()) return {};
  std::vector<std::size_t> out{a};
  for (std::size_t i = (a + 1) % pts.size();; i = (i + 1) % pts.size()) {
    out.push_back(i);
    if (i == b) break;
  }
  return out;
}

}  // namespace polysquare
