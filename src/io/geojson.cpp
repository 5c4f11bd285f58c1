#include "polysquare/io/geojson.h"

#include <nlohmann/json.hpp>

#include <cctype>
#include <cmath>
#include <cstdint>

#include "polysquare/core/error.h"

namespace polysquare {
namespace {

using json = nlohmann::json;

constexpr int kMaxNesting = 32;

struct Context {
  const std::string& source;
  std::size_t feature = 0;
  // Third coordinates of the current feature: polysquare meshes in 2D, so varying z is dropped with a warning.
  double z_min = INFINITY, z_max = -INFINITY;
  [[noreturn]] void fail(const std::string& what) const {
    throw InputError(source + ": feature " + std::to_string(feature) + ": " + what);
  }
};

Vec2 position(const json& p, Context& ctx) {
  if (!p.is_array() || p.size() < 2 || !p[0].is_number() || !p[1].is_number())
    ctx.fail("a position must be an array of at least two numbers, got " + p.dump().substr(0, 80));
  if (p.size() > 2 && p[2].is_number()) {
    const double z = p[2].get<double>();
    ctx.z_min = std::fmin(ctx.z_min, z);
    ctx.z_max = std::fmax(ctx.z_max, z);
  }
  return {p[0].get<double>(), p[1].get<double>()};
}

std::vector<Vec2> positions(const json& arr, Context& ctx) {
  if (!arr.is_array()) ctx.fail("expected an array of positions");
  std::vector<Vec2> out;
  out.reserve(arr.size());
  for (const json& p : arr) out.push_back(position(p, ctx));
  return out;
}

// A GeoJSON ring repeats its first point at the end; the closing point is dropped here.
std::vector<Vec2> ring(const json& arr, Context& ctx, std::size_t ring_index) {
  std::vector<Vec2> pts = positions(arr, ctx);
  if (pts.size() < 4)
    ctx.fail("ring " + std::to_string(ring_index) + " has " + std::to_string(pts.size()) +
             " positions; a closed ring needs at least 4");
  if (!(pts.front() == pts.back())) {
    const Vec2 a = pts.front(), b = pts.back();
    ctx.fail("ring " + std::to_string(ring_index) + " is not closed: first point (" + std::to_string(a.x) + ", " +
             std::to_string(a.y) + ") differs from last point (" + std::to_string(b.x) + ", " + std::to_string(b.y) + ")");
  }
  pts.pop_back();
  return pts;
}

void add_polygon(Region& region, const json& rings, Context& ctx, const std::string& name, double size) {
  if (!rings.is_array()) ctx.fail("a Polygon's coordinates must be an array of rings, got " + rings.dump().substr(0, 80));
  if (rings.empty()) ctx.fail("a Polygon needs at least one ring, got []");
  const int part = region.num_parts++;
  for (std::size_t r = 0; r < rings.size(); ++r)
    region.rings.push_back({ring(rings[r], ctx, r), part, r > 0, static_cast<int>(ctx.feature), name, size});
}

// A string property (numbers are spelled out, so `"name": 3` names the group "3"); empty when absent.
std::string text_property(const json& feature, const char* key) {
  if (!feature.contains("properties") || !feature["properties"].is_object()) return {};
  const json& props = feature["properties"];
  if (!props.contains(key)) return {};
  const json& v = props[key];
  if (v.is_string()) return v.get<std::string>();
  if (v.is_number()) return v.dump();
  return {};
}

// The `size` property (a quad size in region units); 0 when absent or null. A string, a boolean or a size that is
// not positive is refused: a size taken wrongly would grade the whole mesh without a word.
double size_property(const json& feature, const Context& ctx, const std::string& name) {
  if (!feature.contains("properties") || !feature["properties"].is_object()) return 0.0;
  const json& props = feature["properties"];
  if (!props.contains("size") || props["size"].is_null()) return 0.0;
  const json& v = props["size"];
  if (!v.is_number() || !(v.get<double>() > 0.0))  // JSON numbers are finite (1e400 fails to parse)
    ctx.fail("size " + v.dump().substr(0, 80) + (name.empty() ? std::string() : " of '" + name + "'") +
             " is not a positive number (the quad size, in the region's units)");
  return v.get<double>();
}

std::string crs_of(const json& doc) {
  if (!doc.contains("crs") || !doc["crs"].is_object()) return {};
  const json& c = doc["crs"];
  std::string name;
  if (c.contains("properties") && c["properties"].is_object() && c["properties"].contains("name") &&
      c["properties"]["name"].is_string())
    name = c["properties"]["name"].get<std::string>();
  // "EPSG:32616", "urn:ogc:def:crs:EPSG::32616": a plain scan (std::regex recurses per character and a fuzzed
  // name of thousands of digits overflows the stack). Codes have at most 6 digits; longer runs are not codes.
  for (std::size_t at = 0; at + 4 < name.size(); ++at) {
    if ((name.compare(at, 4, "EPSG") != 0 && name.compare(at, 4, "epsg") != 0)) continue;
    std::size_t i = at + 4, colons = 0;
    while (i < name.size() && name[i] == ':' && colons < 2) { ++i; ++colons; }
    std::size_t digits = 0;
    while (i + digits < name.size() && std::isdigit(static_cast<unsigned char>(name[i + digits]))) ++digits;
    if (colons > 0 && digits > 0 && digits <= 6) return "EPSG:" + name.substr(i, digits);
  }
  return name.size() <= 200 ? name : std::string();
}

}  // namespace

Region parse_geojson(std::string_view text, const std::string& source_name, std::vector<std::string>* warnings) {
  // GeoJSON needs about six levels of nesting; a bound keeps the recursive JSON parser's stack small whatever
  // the input (brackets inside strings are skipped).
  {
    int depth = 0;
    bool in_string = false;
    for (std::size_t i = 0; i < text.size(); ++i) {
      const char ch = text[i];
      if (in_string) {
        if (ch == '\\') ++i;
        else if (ch == '"') in_string = false;
      } else if (ch == '"') {
        in_string = true;
      } else if (ch == '[' || ch == '{') {
        if (++depth > kMaxNesting)
          throw InputError(source_name + ": JSON nested deeper than " + std::to_string(kMaxNesting) + " levels at byte " +
                           std::to_string(i));
      } else if (ch == ']' || ch == '}') {
        --depth;
      }
    }
  }
  json doc;
  try {
    doc = json::parse(text.begin(), text.end());
  } catch (const json::exception& e) {  // syntax errors and numbers out of range (1e400)
    throw InputError(source_name + ": not valid JSON: " + e.what());
  }
  if (!doc.is_object() || doc.value("type", json()) != "FeatureCollection" || !doc.contains("features") ||
      !doc["features"].is_array())
    throw InputError(source_name + ": expected a GeoJSON FeatureCollection with a \"features\" array");
  Region region;
  region.source = source_name;
  region.crs = crs_of(doc);
  if (!region.crs.empty()) region.units = "m";
  Context ctx{source_name};
  std::size_t varying_z = 0, first_varying_z = SIZE_MAX;
  for (const json& feature : doc["features"]) {
    if (!feature.is_object() || !feature.contains("geometry") || !feature["geometry"].is_object())
      ctx.fail("expected a Feature object with a geometry");
    const json& g = feature["geometry"];
    if (!g.contains("type") || !g["type"].is_string() || !g.contains("coordinates"))
      ctx.fail("geometry needs a string \"type\" and \"coordinates\"");
    const std::string type = g["type"].get<std::string>();
    const json& coords = g["coordinates"];
    std::string role;
    if (feature.contains("properties") && feature["properties"].is_object() &&
        feature["properties"].contains("role") && feature["properties"]["role"].is_string())
      role = feature["properties"]["role"].get<std::string>();
    if (role.empty()) role = (type == "Polygon" || type == "MultiPolygon") ? "domain" : "feature";
    const int src = static_cast<int>(ctx.feature);
    const std::string name = text_property(feature, "name"), kind = text_property(feature, "kind");
    const double size = size_property(feature, ctx, name);
    if (role == "domain") {
      if (type == "Polygon") add_polygon(region, coords, ctx, name, size);
      else if (type == "MultiPolygon" && coords.is_array()) for (const json& poly : coords) add_polygon(region, poly, ctx, name, size);
      else if (type == "MultiPolygon") ctx.fail("a MultiPolygon's coordinates must be an array of polygons, got " + coords.dump().substr(0, 80));
      else ctx.fail("a domain must be a Polygon or MultiPolygon, got " + type);
    } else if (role == "feature") {
      auto curve = [&](std::vector<Vec2> pts, bool closed) { region.features.push_back({std::move(pts), closed, src, name, kind, size}); };
      if (type == "LineString") curve(positions(coords, ctx), false);
      else if (type == "MultiLineString" && coords.is_array())
        for (const json& line : coords) curve(positions(line, ctx), false);
      else if (type == "Polygon" && coords.is_array() && !coords.empty())  // every ring a closed curve
        for (std::size_t r = 0; r < coords.size(); ++r) curve(ring(coords[r], ctx, r), true);
      else if (type == "LinearRing")  // not in RFC 7946, but written by some tools for closed curves
        curve(ring(coords, ctx, 0), true);
      else if (type == "Point") region.feature_points.push_back(position(coords, ctx));
      else if (type == "MultiPoint") for (Vec2 p : positions(coords, ctx)) region.feature_points.push_back(p);
      else ctx.fail("a feature must be a LineString, MultiLineString, Polygon, LinearRing, Point or MultiPoint, got " + type);
    } else if (role == "boundary") {
      auto segment = [&](std::vector<Vec2> pts) {
        BoundarySegment b;
        b.name = name;
        b.kind = kind;
        b.source_feature = src;
        b.line = std::move(pts);
        region.boundary_segments.push_back(std::move(b));
      };
      if (type == "LineString") segment(positions(coords, ctx));
      else if (type == "MultiLineString" && coords.is_array()) for (const json& line : coords) segment(positions(line, ctx));
      else ctx.fail("a boundary segment must be a LineString or MultiLineString lying on the domain boundary, got " + type);
    } else {
      ctx.fail("unknown role \"" + role + "\" (expected \"domain\", \"feature\" or \"boundary\")");
    }
    if (size > 0.0 && (role == "boundary" || type == "Point" || type == "MultiPoint") && warnings)
      warnings->push_back(source_name + ": feature " + std::to_string(ctx.feature) + ": its size is not used (sizes " +
                          "hold inside domain polygons and along feature lines and polygons, not on " +
                          (role == "boundary" ? "boundary segments)" : "points)"));
    if (ctx.z_min < ctx.z_max) ++varying_z, first_varying_z = std::min(first_varying_z, ctx.feature);
    ctx.z_min = INFINITY, ctx.z_max = -INFINITY;
    ++ctx.feature;
  }
  if (region.rings.empty())
    throw InputError(source_name + ": no domain: the collection has no Polygon or MultiPolygon with role \"domain\"");
  if (varying_z > 0 && warnings)
    warnings->push_back(source_name + (varying_z > 1 ? ": features " : ": feature ") + std::to_string(first_varying_z) +
                        (varying_z > 1 ? " and " + std::to_string(varying_z - 1) + " more have" : std::string(" has")) +
                        " positions whose third coordinate (z) varies; the mesh is 2D and z is dropped");
  return region;
}

}  // namespace polysquare
