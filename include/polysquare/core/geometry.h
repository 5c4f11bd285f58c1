// Small 2D vector type and predicates shared by every stage.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace polysquare {

/// A point or vector in the plane (double precision, the region's units).
struct Vec2 {
  double x = 0.0;
  double y = 0.0;
};

/// Key of the undirected edge (a, b) between two vertex indices, for hash maps and sets.
inline std::uint64_t edge_key(std::int32_t a, std::int32_t b) {
  if (a > b) std::swap(a, b);
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) | static_cast<std::uint32_t>(b);
}

inline Vec2 operator+(Vec2 a, Vec2 b) { return {a.x + b.x, a.y + b.y}; }
inline Vec2 operator-(Vec2 a, Vec2 b) { return {a.x - b.x, a.y - b.y}; }
inline Vec2 operator*(double s, Vec2 a) { return {s * a.x, s * a.y}; }
inline Vec2 operator*(Vec2 a, double s) { return {s * a.x, s * a.y}; }
inline bool operator==(Vec2 a, Vec2 b) { return a.x == b.x && a.y == b.y; }
inline double dot(Vec2 a, Vec2 b) { return a.x * b.x + a.y * b.y; }
/// z component of the 3D cross product: positive when b is counter-clockwise of a.
inline double cross(Vec2 a, Vec2 b) { return a.x * b.y - a.y * b.x; }
inline double norm(Vec2 a) { return std::hypot(a.x, a.y); }
inline double distance(Vec2 a, Vec2 b) { return norm(a - b); }
/// Whether the polyline prev -> at -> next turns at `at` by more than threshold_deg (a corner that must be a node).
inline bool sharp_turn(Vec2 prev, Vec2 at, Vec2 next, double threshold_deg) {
  const Vec2 u = at - prev, w = next - at;
  return dot(u, w) < std::cos(threshold_deg * 3.14159265358979323846 / 180.0) * norm(u) * norm(w);
}

/// Scaled Jacobian of the corner at p of a counter-clockwise polygon whose neighbours of p are prev and next:
/// sin of the angle from p->next to p->prev, negative when the corner is inverted, -1 for a zero-length edge.
inline double corner_sj(Vec2 prev, Vec2 p, Vec2 next) {
  const Vec2 en = next - p, ep = prev - p;
  // One sqrt of the product of squared lengths, not two std::hypot: smoothing and the quality checks evaluate
  // millions of corners, and hypot's overflow guard was a third of a coast's meshing time (squares of lengths
  // up to the documented 1e15 coordinate limit stay far inside the double range).
  const double l = std::sqrt(dot(en, en) * dot(ep, ep));
  return l > 0 ? cross(en, ep) / l : -1.0;
}
/// Worst corner_sj of the counter-clockwise quad a b c d (the Verdict scaled Jacobian of the quad).
inline double quad_min_sj(Vec2 a, Vec2 b, Vec2 c, Vec2 d) {
  return std::min(std::min(corner_sj(d, a, b), corner_sj(a, b, c)), std::min(corner_sj(b, c, d), corner_sj(c, d, a)));
}

/// "(x, y)" with 12 significant digits: input places in messages, exact enough to find a vertex again.
inline std::string plain_point_text(Vec2 p) {
  std::ostringstream os;
  os.precision(12);
  os << "(" << p.x << ", " << p.y << ")";
  return os.str();
}

/// How a place of a projected region is written in messages: in the input's own coordinates (lon/lat), which
/// the user's file holds, not in the metres it is meshed in. Installed on a thread by ScopedPlaceText.
class PlaceTextHook {
 public:
  virtual ~PlaceTextHook() = default;
  virtual std::string text(Vec2 p) const = 0;
};
inline thread_local const PlaceTextHook* place_text_hook = nullptr;

/// While alive, point_text on this thread writes places through `hook` (nullptr: as they are).
class ScopedPlaceText {
 public:
  explicit ScopedPlaceText(const PlaceTextHook* hook) : previous_(place_text_hook) { place_text_hook = hook; }
  ~ScopedPlaceText() { place_text_hook = previous_; }
  ScopedPlaceText(const ScopedPlaceText&) = delete;
  ScopedPlaceText& operator=(const ScopedPlaceText&) = delete;

 private:
  const PlaceTextHook* previous_;
};

/// "(x, y)" for messages that say where something is: plain_point_text, or the input's coordinates of a
/// projected region while a ScopedPlaceText is alive.
inline std::string point_text(Vec2 p) { return place_text_hook ? place_text_hook->text(p) : plain_point_text(p); }

inline std::string at_text(Vec2 p) { return "(" + std::to_string(p.x) + ", " + std::to_string(p.y) + ")"; }

inline Vec2 lerp(Vec2 a, Vec2 b, double t) { return {a.x + t * (b.x - a.x), a.y + t * (b.y - a.y)}; }

/// Twice the signed area of triangle abc (positive when counter-clockwise).
inline double orient2(Vec2 a, Vec2 b, Vec2 c) { return cross(b - a, c - a); }

/// Whether segments [a, b] and [c, d] cross at a point inside both (touching or collinear is no crossing).
inline bool segments_cross(Vec2 a, Vec2 b, Vec2 c, Vec2 d) {
  const double o1 = orient2(a, b, c), o2 = orient2(a, b, d), o3 = orient2(c, d, a), o4 = orient2(c, d, b);
  return ((o1 > 0 && o2 < 0) || (o1 < 0 && o2 > 0)) && ((o3 > 0 && o4 < 0) || (o3 < 0 && o4 > 0));
}

/// Distance from p to the segment [a, b].
inline double point_segment_distance(Vec2 p, Vec2 a, Vec2 b) {
  const Vec2 d = b - a;
  const double len2 = dot(d, d);
  double t = len2 > 0.0 ? dot(p - a, d) / len2 : 0.0;
  t = t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t);
  return distance(p, a + t * d);
}

/// Signed area of a closed ring (closing point not repeated), positive when counter-clockwise. Summed relative to
/// its first point: far from the origin (1e11) products of absolute coordinates cancel to zero.
inline double ring_signed_area(const std::vector<Vec2>& ring) {
  double s = 0.0;
  for (std::size_t i = 0; i < ring.size(); ++i) s += cross(ring[i] - ring[0], ring[(i + 1) % ring.size()] - ring[0]);
  return 0.5 * s;
}

/// Even-odd test of p against the closed ring ring[0..n) (closing point not repeated). Points on the ring may go
/// either way.
inline bool point_in_ring(Vec2 p, const Vec2* ring, std::size_t n) {
  bool inside = false;
  for (std::size_t i = 0, j = n - 1; i < n; j = i++) {
    const Vec2 a = ring[i], b = ring[j];
    if ((a.y > p.y) != (b.y > p.y) && p.x < (b.x - a.x) * (p.y - a.y) / (b.y - a.y) + a.x) inside = !inside;
  }
  return inside;
}
inline bool point_in_ring(Vec2 p, const std::vector<Vec2>& ring) { return point_in_ring(p, ring.data(), ring.size()); }

/// Axis-aligned bounding box.
struct Box2 {
  Vec2 lo{INFINITY, INFINITY};
  Vec2 hi{-INFINITY, -INFINITY};
  void add(Vec2 p) {
    lo = {std::fmin(lo.x, p.x), std::fmin(lo.y, p.y)};
    hi = {std::fmax(hi.x, p.x), std::fmax(hi.y, p.y)};
  }
  double diagonal() const { return lo.x <= hi.x ? distance(lo, hi) : 0.0; }
  bool contains(Vec2 p) const { return p.x >= lo.x && p.x <= hi.x && p.y >= lo.y && p.y <= hi.y; }
};

}  // namespace polysquare
