// Points along a closed polygon by arc length, for tests that move a boundary along itself.
#pragma once

#include <cmath>
#include <vector>

#include "polysquare/core/geometry.h"

namespace polysquare {

/// The point at arc length s (modulo the perimeter) round the closed polygon `loop`, from its first vertex.
inline Vec2 point_on_loop(const std::vector<Vec2>& loop, double s) {
  double perimeter = 0.0;
  for (std::size_t k = 0; k < loop.size(); ++k) perimeter += distance(loop[k], loop[(k + 1) % loop.size()]);
  s = std::fmod(s, perimeter);
  for (std::size_t k = 0; k < loop.size(); ++k) {
    const Vec2 a = loop[k], b = loop[(k + 1) % loop.size()];
    const double len = distance(a, b);
    if (s <= len) return a + (s / len) * (b - a);
    s -= len;
  }
  return loop.front();
}

}  // namespace polysquare
