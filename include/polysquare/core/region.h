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
  std::string name;         ///< the domain's `name` attribute (empty when none is given)
  double size = 0.0;        ///< the polygon's `size` attribute: the quad size inside its part, region units (0 = none)
};

/// A feature curve the mesh must follow: a chain of mesh edges whose nodes lie on it.
/// After validation and splitting, a curve meets other curves and the boundary only at its end points,
/// and closed curves have points.front() != points.back() (the closing segment is implicit).
struct FeatureCurve {
  std::vector<Vec2> points;
  bool closed = false;
  int source_feature = -1;  ///< index of the GeoJSON feature it came from
  std::string name;         ///< the input's `name` attribute (empty: a name is generated, "feature_<c>")
  std::string kind;         ///< the input's `kind` attribute (free text; empty when none is given)
  double size = 0.0;        ///< the input's `size` attribute: the quad size along the curve, region units (0 = none)
};

/// A named piece of a boundary ring, from a line with role "boundary" (or a --boundary file) lying on it.
/// The piece runs forward along the ring (its validated orientation: the domain on its left) from `start` to
/// `end`, both vertices of the ring; start == end means the whole ring. Reading checks that the line lies on the
/// ring, inserts its end points as ring vertices and adds them to Region::feature_points, so they survive
/// simplification and are mesh nodes. Segments of one ring do not overlap.
struct BoundarySegment {
  int ring = -1;            ///< index into Region::rings
  Vec2 start, end;          ///< end points (ring vertices), in ring order
  std::string name;         ///< the input's `name` attribute (empty: "segment_<s>")
  std::string kind;         ///< "open", "land" or anything else the input says (empty: "land")
  int source_feature = -1;  ///< index of the input feature it came from
  std::vector<Vec2> line;   ///< the input line as read (kept for messages); validation sets ring, start and end
};

/// A region to mesh. Coordinates are planar, in `units` of the CRS named by `crs` (empty when unknown).
struct Region {
  std::vector<Ring> rings;             ///< outer rings and holes of every part
  std::vector<FeatureCurve> features;  ///< feature curves (open or closed)
  std::vector<Vec2> feature_points;    ///< isolated points that must be mesh nodes
  std::vector<BoundarySegment> boundary_segments;  ///< named pieces of the rings (open boundaries and others)
  std::vector<Ring> size_areas;        ///< closed feature curves with a size, as validation found them: the size
                                       ///< holds inside them (splitting cuts the curves themselves into open pieces)
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
