// The input of the pipeline: a planar region (polygon parts with holes) and its feature curves.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "polysquare/core/geometry.h"

namespace polysquare {

/// A closed polygonal ring. The closing point is not repeated: points.front() != points.back().
/// After validation, outer rings are counter-clockwise and holes clockwise.
struct Ring {
  std::vector<Vec2> points;
  int part = 0;             ///< index of the polygon part this ring bounds
  bool hole = false;        ///< true for an inner ring (hole) of its part
  int source_feature = -1;  ///< index of the GeoJSON feature it came from (for error messages)
};

/// A feature curve the mesh must follow: a chain of mesh edges whose nodes lie on it.
/// After validation and splitting, a curve meets other curves and the boundary only at its end points,
/// and closed curves have points.front() != points.back() (the closing segment is implicit).
struct FeatureCurve {
  std::vector<Vec2> points;
  bool closed = false;
  int source_feature = -1;  ///< index of the GeoJSON feature it came from
};

/// A region to mesh. Coordinates are planar, in `units` of the CRS named by `crs` (empty when unknown).
struct Region {
  std::vector<Ring> rings;             ///< outer rings and holes of every part
  std::vector<FeatureCurve> features;  ///< feature curves (open or closed)
  std::vector<Vec2> feature_points;    ///< isolated points that must be mesh nodes
  int num_parts = 0;                   ///< number of polygon parts (disconnected pieces)
  std::string crs;                     ///< e.g. "EPSG:32616"; empty for arbitrary planar units
  std::string units;                   ///< e.g. "m"; empty when unknown
  std::string source;                  ///< path of the file it was read from (for messages)

  Box2 bounding_box() const {
    Box2 b;
    for (const Ring& r : rings)
      for (Vec2 p : r.points) b.add(p);
    return b;
  }
};

}  // namespace polysquare
