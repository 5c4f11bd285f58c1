#include "polysquare/input/read_region.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include <CGAL/box_intersection_d.h>

#include "polysquare/core/error.h"
#include "polysquare/io/atomic_file.h"
#include "polysquare/io/geojson.h"
#include "polysquare/input/boundary_segments.h"
#include "polysquare/input/make_valid.h"
#include "polysquare/input/project_region.h"
#include "polysquare/input/read_gdal.h"
#include "polysquare/input/snap_points.h"
#include "polysquare/input/split_features.h"

namespace polysquare {
namespace {

struct Segment {
  Vec2 a, b;
  int owner;     // ring index, or -1 - feature index for features
  int index;     // segment index within its owner
  int count;     // number of segments of the owner (to detect cyclic neighbours)
  bool closed;
};

int sgn(double v) { return (v > 0) - (v < 0); }

std::string pt_number(double v) {
  std::ostringstream os;
  os.precision(6);
  os << v;
  return os.str();
}

// Intersection of two segments (touching included); writes a point of contact.
bool segments_meet(const Segment& s, const Segment& t, Vec2& at) {
  const int d1 = sgn(orient2(s.a, s.b, t.a)), d2 = sgn(orient2(s.a, s.b, t.b));
  const int d3 = sgn(orient2(t.a, t.b, s.a)), d4 = sgn(orient2(t.a, t.b, s.b));
  auto on = [](Vec2 p, Vec2 q, Vec2 r) {  // r on segment pq, given collinear
    return std::min(p.x, q.x) <= r.x && r.x <= std::max(p.x, q.x) && std::min(p.y, q.y) <= r.y && r.y <= std::max(p.y, q.y);
  };
  if (d1 != d2 && d3 != d4 && d1 * d2 <= 0 && d3 * d4 <= 0 && (d1 | d2 | d3 | d4) != 0) {
    if (d1 == 0) { at = t.a; return true; }
    if (d2 == 0) { at = t.b; return true; }
    if (d3 == 0) { at = s.a; return true; }
    if (d4 == 0) { at = s.b; return true; }
    const double u = orient2(t.a, t.b, s.a) / (orient2(t.a, t.b, s.a) - orient2(t.a, t.b, s.b));
    at = lerp(s.a, s.b, u);
    return true;
  }
  if (d1 == 0 && on(s.a, s.b, t.a)) { at = t.a; return true; }
  if (d2 == 0 && on(s.a, s.b, t.b)) { at = t.b; return true; }
  if (d3 == 0 && on(t.a, t.b, s.a)) { at = s.a; return true; }
  if (d4 == 0 && on(t.a, t.b, s.b)) { at = s.b; return true; }
  return false;
}

bool adjacent(const Segment& s, const Segment& t) {
  if (s.owner != t.owner) return false;
  const int d = std::abs(s.index - t.index);
  return d == 1 || (s.closed && d == s.count - 1);
}

// Every meeting pair that is not two consecutive segments of one chain, in a fixed order (segments sorted by
// their smallest x, then pairs by their first and second segment), so messages name the same place every run.
// Candidate pairs come from CGAL's box intersection (a segment tree: n log n plus the overlapping pairs; a sweep
// over x alone compared every pair of a comb's teeth when they run along x: 30,000 teeth took 50 s). Stops at
// the first pair for which report returns true.
template <typename F>
void for_each_meeting(std::vector<Segment>& segs, F report) {
  std::sort(segs.begin(), segs.end(), [](const Segment& s, const Segment& t) {
    return std::min(s.a.x, s.b.x) < std::min(t.a.x, t.b.x);
  });
  using Box = CGAL::Box_intersection_d::Box_with_info_d<double, 2, std::size_t, CGAL::Box_intersection_d::ID_EXPLICIT>;
  std::vector<Box> boxes;
  boxes.reserve(segs.size());
  for (std::size_t i = 0; i < segs.size(); ++i) {
    const Segment& s = segs[i];
    double lo[2] = {std::min(s.a.x, s.b.x), std::min(s.a.y, s.b.y)};
    double hi[2] = {std::max(s.a.x, s.b.x), std::max(s.a.y, s.b.y)};
    boxes.emplace_back(lo, hi, i);
  }
  std::vector<std::pair<std::size_t, std::size_t>> meets;
  // Closed boxes: segments that only touch at a box edge (a vertical meeting a horizontal at its end) are pairs.
  CGAL::box_self_intersection_d<CGAL::Sequential_tag>(
      boxes.begin(), boxes.end(),
      [&](const Box& p, const Box& q) {
        const std::size_t i = std::min(p.info(), q.info()), j = std::max(p.info(), q.info());
        if (adjacent(segs[i], segs[j])) return;
        Vec2 at;
        if (segments_meet(segs[i], segs[j], at)) meets.emplace_back(i, j);
      },
      std::ptrdiff_t(10), CGAL::Box_intersection_d::CLOSED);
  std::sort(meets.begin(), meets.end());
  for (const auto& [i, j] : meets) {
    Vec2 at;
    segments_meet(segs[i], segs[j], at);
    if (report(segs[i], segs[j], at)) return;
  }
}

void check_points(const std::vector<Vec2>& pts, const std::string& where, const InputOptions& o) {
  for (Vec2 p : pts) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y)) throw InputError(where + " has a non-finite coordinate " + point_text(p));
    if (std::abs(p.x) > o.max_abs_coordinate || std::abs(p.y) > o.max_abs_coordinate)
      throw InputError(where + " has a coordinate beyond the limit of " + pt_number(o.max_abs_coordinate) + ": " + point_text(p));
  }
}

// Repeated consecutive points: refused, or dropped and reported with repair.
void dedupe(std::vector<Vec2>& pts, bool closed, const std::string& where, bool repair, std::vector<std::string>* repairs) {
  const std::size_t before = pts.size();
  Vec2 first_repeat{};
  for (std::size_t i = 0; i < pts.size(); ++i)
    if (pts[i] == pts[(i + 1) % pts.size()] && (closed || i + 1 < pts.size())) { first_repeat = pts[i]; break; }
  pts.erase(std::unique(pts.begin(), pts.end()), pts.end());
  while (closed && pts.size() > 1 && pts.front() == pts.back()) pts.pop_back();
  if (pts.size() == before) return;
  if (!repair) throw InputError(where + " repeats the point " + point_text(first_repeat) + " (--repair drops repeated points)");
  if (repairs) repairs->push_back(where + ": dropped " + std::to_string(before - pts.size()) + " repeated point(s), first at " + point_text(first_repeat));
}

std::string ring_name(const Region& region, std::size_t r) {
  return region.source + ": feature " + std::to_string(region.rings[r].source_feature) + ": ring " + std::to_string(r);
}

std::string feature_name(const Region& region, std::size_t f) {
  return region.source + ": feature " + std::to_string(region.features[f].source_feature) + " (curve " + std::to_string(f) + ")";
}

// Finite coordinates within the limit, no repeated points (or dropped with repair), enough points per line.
void check_line_points(Region& region, const InputOptions& options, std::vector<std::string>* repairs) {
  for (std::size_t r = 0; r < region.rings.size(); ++r) {
    Ring& ring = region.rings[r];
    check_points(ring.points, ring_name(region, r), options);
    dedupe(ring.points, true, ring_name(region, r), options.repair, repairs);
    if (ring.points.size() < 3)
      throw InputError(ring_name(region, r) + " has fewer than 3 distinct points, at " + point_text(ring.points.front()));
    // A ring that turns back on itself (two consecutive edges along one line, the second going back over the
    // first) encloses a spike of no width there; the crossing test skips consecutive edges, so it is refused here
    // (a lon/lat cap to a pole run there and back along one meridian is one, once projected). A ring of no
    // area at all is left to orient_rings, which says so.
    const std::vector<Vec2>& p = ring.points;
    const bool flat = ring_signed_area(p) == 0.0;
    for (std::size_t i = 0; i < p.size() && !options.repair && !flat; ++i) {
      const Vec2 a = p[(i + p.size() - 1) % p.size()], b = p[i], c = p[(i + 1) % p.size()];
      if (orient2(a, b, c) == 0.0 && dot(b - a, c - b) < 0.0)
        throw InputError(ring_name(region, r) + " turns back on itself at " + point_text(b) +
                         " (a spike of no width: two consecutive edges along one line)");
    }
  }
  for (std::size_t f = 0; f < region.features.size(); ++f) {
    FeatureCurve& c = region.features[f];
    check_points(c.points, feature_name(region, f), options);
    // A line that ends where it starts is a closed loop (an island's shoreline), whatever geometry type carried it.
    if (!c.closed && c.points.size() >= 4 && c.points.front() == c.points.back()) {
      c.closed = true;
      c.points.pop_back();
    }
    dedupe(c.points, c.closed, feature_name(region, f), options.repair, repairs);
    if (c.points.size() < 2 || (c.closed && c.points.size() < 3))
      throw InputError(feature_name(region, f) + " has too few distinct points" +
                       (c.points.empty() ? std::string() : ", at " + point_text(c.points.front())));
  }
  check_points(region.feature_points, region.source + ": feature points", options);
}

std::vector<Segment> ring_segments(const Region& region) {
  std::vector<Segment> segs;
  for (std::size_t r = 0; r < region.rings.size(); ++r) {
    const auto& p = region.rings[r].points;
    for (std::size_t i = 0; i < p.size(); ++i)
      segs.push_back({p[i], p[(i + 1) % p.size()], static_cast<int>(r), static_cast<int>(i), static_cast<int>(p.size()), true});
  }
  return segs;
}

// Rings must not cross or touch themselves or each other.
void refuse_meeting_rings(const Region& region) {
  std::vector<Segment> segs = ring_segments(region);
  for_each_meeting(segs, [&](const Segment& s, const Segment& t, Vec2 at) -> bool {
    if (s.owner == t.owner) throw InputError(ring_name(region, static_cast<std::size_t>(s.owner)) + " intersects itself at " + point_text(at));
    throw InputError(ring_name(region, static_cast<std::size_t>(s.owner)) + " meets ring " + std::to_string(t.owner) + " at " + point_text(at));
  });
}

// A hole inside another hole of its polygon (a third ring of a GeoJSON Polygon) is an island in a lake: it
// becomes a part of its own, said in a warning; a ring inside that island too is refused (rings no longer
// cross, so one point tells where a ring lies). Meshed as given, the island was domain and its lake too.
void make_islands_in_lakes_parts(Region& region, std::vector<std::string>* warnings) {
  std::vector<int> depth(region.rings.size(), 0), container(region.rings.size(), -1);
  for (std::size_t r = 0; r < region.rings.size(); ++r)
    for (std::size_t h = 0; h < region.rings.size() && region.rings[r].hole; ++h)
      if (h != r && region.rings[h].hole && region.rings[h].part == region.rings[r].part &&
          point_in_ring(region.rings[r].points.front(), region.rings[h].points))
        ++depth[r], container[r] = static_cast<int>(h);
  for (std::size_t r = 0; r < region.rings.size(); ++r) {
    if (depth[r] > 1)
      throw InputError(ring_name(region, r) + " lies inside ring " + std::to_string(container[r]) +
                       ", which lies inside another hole of the same polygon: give islands in lakes as polygons of "
                       "their own, at " + point_text(region.rings[r].points.front()));
    if (depth[r] == 1) {
      region.rings[r].hole = false;
      region.rings[r].part = region.num_parts++;
      if (warnings)
        warnings->push_back(ring_name(region, r) + " lies inside hole ring " + std::to_string(container[r]) +
                            " of the same polygon: meshed as an island (polygon part " +
                            std::to_string(region.rings[r].part) + "), at " + point_text(region.rings[r].points.front()));
    }
  }
}

// Orientation after the crossing check, so a bow-tie is reported as what it is rather than as zero area.
void orient_rings(Region& region) {
  for (std::size_t r = 0; r < region.rings.size(); ++r) {
    Ring& ring = region.rings[r];
    const double a = ring_signed_area(ring.points);
    if (a == 0.0) throw InputError(ring_name(region, r) + " has zero area, at " + point_text(ring.points.front()));
    if ((a > 0) == ring.hole) std::reverse(ring.points.begin(), ring.points.end());
  }
}

// Each part's outer ring.
struct PartRings {
  const Region& region;
  std::vector<int> outer;

  explicit PartRings(const Region& r) : region(r), outer(static_cast<std::size_t>(r.num_parts), -1) {
    for (std::size_t k = 0; k < region.rings.size(); ++k)
      if (!region.rings[k].hole) outer[static_cast<std::size_t>(region.rings[k].part)] = static_cast<int>(k);
  }
  const std::vector<Vec2>& outer_ring(int part) const {
    return region.rings[static_cast<std::size_t>(outer[static_cast<std::size_t>(part)])].points;
  }
  bool in_domain_of_part(Vec2 p, int part) const {
    if (!point_in_ring(p, outer_ring(part))) return false;
    for (const Ring& h : region.rings)
      if (h.part == part && h.hole && point_in_ring(p, h.points)) return false;
    return true;
  }
};

// Nesting: holes inside their own outer ring, parts not inside each other (outside their holes).
void check_nesting(const PartRings& parts) {
  const Region& region = parts.region;
  for (std::size_t r = 0; r < region.rings.size(); ++r) {
    const Ring& ring = region.rings[r];
    const Vec2 p = ring.points.front();
    if (ring.hole && !point_in_ring(p, parts.outer_ring(ring.part)))
      throw InputError(ring_name(region, r) + " is a hole outside its polygon, at " + point_text(p));
    if (!ring.hole)
      for (int k = 0; k < region.num_parts; ++k)
        if (k != ring.part && parts.in_domain_of_part(p, k))
          throw InputError(ring_name(region, r) + " lies inside polygon part " + std::to_string(k) + " (overlapping parts), at " + point_text(p));
  }
}

// Feature points must lie in the domain or on its boundary, like curves (with --repair, points in holes or
// outside are dropped and reported).
void keep_feature_points_in_domain(Region& region, const PartRings& parts, const InputOptions& options,
                                   std::vector<std::string>* repairs) {
  const double tol = options.snap_relative * region.bounding_box().diagonal();
  std::vector<Vec2> kept;
  for (Vec2 p : region.feature_points) {
    bool inside = false;
    for (int k = 0; k < region.num_parts && !inside; ++k) inside = parts.in_domain_of_part(p, k);
    double d = INFINITY;
    for (std::size_t r = 0; r < region.rings.size() && !inside && d > tol; ++r) {
      const auto& q = region.rings[r].points;
      for (std::size_t i = 0; i < q.size(); ++i) d = std::min(d, point_segment_distance(p, q[i], q[(i + 1) % q.size()]));
    }
    if (inside || d <= tol) {
      kept.push_back(p);
      continue;
    }
    bool in_hole = false;
    for (int k = 0; k < region.num_parts; ++k) in_hole |= point_in_ring(p, parts.outer_ring(k));
    const std::string what = region.source + ": feature point " + point_text(p) + (in_hole ? " lies in a hole" : " lies outside the domain");
    if (!options.repair) throw InputError(what + " (--repair drops it)");
    if (repairs) repairs->push_back(what + ": dropped");
  }
  region.feature_points = std::move(kept);
}

// After the split no curve may cross the boundary or another curve except at end points (this catches
// self-crossing curves, which are not split).
void refuse_feature_crossings(const Region& region) {
  std::vector<Segment> all = ring_segments(region);
  for (std::size_t f = 0; f < region.features.size(); ++f) {
    const auto& p = region.features[f].points;
    const bool closed = region.features[f].closed;
    const std::size_t m = closed ? p.size() : p.size() - 1;
    for (std::size_t i = 0; i < m; ++i)
      all.push_back({p[i], p[(i + 1) % p.size()], -1 - static_cast<int>(f), static_cast<int>(i), static_cast<int>(m), closed});
  }
  for_each_meeting(all, [&](const Segment& s, const Segment& t, Vec2 at) -> bool {
    if (s.owner >= 0 && t.owner >= 0) return false;  // ring pairs were checked above
    const Segment& fs = s.owner < 0 ? s : t;
    const Segment& other = s.owner < 0 ? t : s;
    const std::size_t f = static_cast<std::size_t>(-1 - fs.owner);
    const auto& pts = region.features[f].points;
    const bool at_end = !region.features[f].closed && (at == pts.front() || at == pts.back());
    if (other.owner >= 0) {
      // A feature may end on the boundary; it may not cross it.
      if (at_end) return false;
      throw InputError(feature_name(region, f) + " crosses the boundary (ring " + std::to_string(other.owner) + ") at " + point_text(at));
    }
    const std::size_t g = static_cast<std::size_t>(-1 - other.owner);
    const auto& q = region.features[g].points;
    const bool other_end = !region.features[g].closed && (at == q.front() || at == q.back());
    if (at_end && other_end) return false;  // curves meeting at their end points
    throw InputError(feature_name(region, f) + (f == g ? " crosses itself" : " crosses feature curve " + std::to_string(g)) +
                     " at " + point_text(at));
  });
}

}  // namespace

void validate_region(Region& region, const InputOptions& options, std::vector<std::string>* repairs,
                     std::vector<std::string>* warnings) {
  const std::string& src = region.source;
  if (options.repair) {
    // Finite coordinates first: GEOS must not see NaN.
    for (const Ring& ring : region.rings)
      check_points(ring.points, src + ": feature " + std::to_string(ring.source_feature), options);
    make_parts_valid(region, repairs);
  }
  check_line_points(region, options, repairs);
  refuse_meeting_rings(region);
  make_islands_in_lakes_parts(region, warnings);
  orient_rings(region);
  const PartRings parts(region);
  check_nesting(parts);
  // Boundary segments: on a ring, their end points ring vertices (and feature points, so they become nodes).
  place_boundary_segments(region, options.boundary_snap_relative * region.bounding_box().diagonal());
  keep_feature_points_in_domain(region, parts, options, repairs);
  // Features: cut at crossings and clipped to the domain; then checked for crossings left.
  FeatureSplitOptions split;
  split.clip_holes = options.repair;
  const FeatureSplitStats split_stats = split_features(region, split);
  if (warnings) warnings->insert(warnings->end(), split_stats.warnings.begin(), split_stats.warnings.end());
  if (repairs && split_stats.pieces_in_holes > 0)
    repairs->push_back(src + ": clipped " + std::to_string(split_stats.pieces_in_holes) + " feature piece(s) inside holes");
  refuse_feature_crossings(region);
}

namespace {

// Validation names a feature by its index in reading order; for GDAL input that index is spelled out as the
// file, layer and FID it came from.
std::string name_feature(const std::string& message, const std::vector<std::string>& names) {
  const std::size_t at = message.find("feature ");
  if (at == std::string::npos) return message;
  std::size_t i = at + 8, index = 0, digits = 0;
  while (i < message.size() && std::isdigit(static_cast<unsigned char>(message[i])) && digits < 12)
    index = index * 10 + static_cast<std::size_t>(message[i++] - '0'), ++digits;
  if (digits == 0 || index >= names.size()) return message;
  return message + " [feature " + std::to_string(index) + " is " + names[index] + "]";
}

}  // namespace

Region read_input(const std::filesystem::path& path, const InputOptions& options, InputNotes& notes) {
  const std::string name = path.string();
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  const bool selects = !options.domain_layer.empty() || !options.feature_layers.empty() || !options.where.empty();
  Region region;
  std::vector<std::string> names;  // per source_feature, for GDAL input only
  if ((ext == ".geojson" || ext == ".json") && !selects) {
    region = parse_geojson(read_file(path), name, &notes.warnings);
  } else {
    region.source = name;
    read_gdal(path, LayerRole::by_geometry, options, region, names, notes);
  }
  if ((!options.feature_files.empty() || !options.boundary_files.empty()) && names.empty()) {
    // The native reader's features keep their index; the feature files' features are numbered after them.
    int next = 0;
    for (const Ring& r : region.rings) next = std::max(next, r.source_feature + 1);
    for (const FeatureCurve& c : region.features) next = std::max(next, c.source_feature + 1);
    for (int k = 0; k < next; ++k) names.push_back(name + ", feature " + std::to_string(k));
  }
  for (const std::filesystem::path& f : options.feature_files) read_gdal(f, LayerRole::feature, options, region, names, notes);
  for (const std::filesystem::path& f : options.boundary_files) read_gdal(f, LayerRole::boundary, options, region, names, notes);
  for (const std::string& layer : options.feature_layers) {
    bool found = false;
    for (const std::string& n : names) found |= n.find(", layer '" + layer + "', ") != std::string::npos;
    if (!found) throw InputError(name + ": no feature read from a layer '" + layer + "' (--feature-layer)");
  }
  if (region.rings.empty())
    throw InputError(name + ": no domain: no polygon with role \"domain\" was read" +
                     (names.empty() ? std::string() : " from " + std::to_string(names.size()) + " feature(s)"));
  try {
    project_region(region, options.crs, notes);
    // Places in messages from here on are in the input's own coordinates (lon/lat), not the projected metres.
    const std::unique_ptr<PlaceTextHook> places = input_place_text(region, notes);
    const ScopedPlaceText scoped(places.get());
    snap_near_coincident(region, options.snap_relative, &notes.snaps);
    validate_region(region, options, &notes.repairs, &notes.warnings);
  } catch (const InputError& e) {
    if (names.empty()) throw;
    throw InputError(name_feature(e.what(), names));
  }
  return region;
}

Region read_region(const std::filesystem::path& path, const InputOptions& options, std::vector<std::string>* repairs) {
  InputNotes notes;
  Region region = read_input(path, options, notes);
  if (repairs) repairs->insert(repairs->end(), notes.repairs.begin(), notes.repairs.end());
  return region;
}

}  // namespace polysquare
