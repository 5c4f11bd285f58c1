#include "polysquare/pipeline/check_options.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>

#include "polysquare/core/error.h"

namespace polysquare {

std::string short_number(double v) {
  std::ostringstream os;
  os.precision(6);
  os << v;
  return os.str();
}

namespace {

void require(bool ok, const char* flag, const char* field, double value, const char* range) {
  if (ok) return;
  throw InputError(std::string(flag) + " (" + field + ") must be " + range + ", got " + short_number(value));
}

// `lo <= v <= hi`, false for NaN.
bool within(double v, double lo, double hi) { return v >= lo && v <= hi; }

// "350 GB", "1.2 MB": a memory size in messages.
std::string memory_text(double bytes) {
  const char* units[] = {"bytes", "kB", "MB", "GB", "TB", "PB"};
  int u = 0;
  while (bytes >= 1000.0 && u < 5) bytes /= 1000.0, ++u;
  std::ostringstream os;
  os.precision(3);
  os << bytes << " " << units[u];
  return os.str();
}

}  // namespace

double available_memory_bytes() {
  // MemAvailable counts the page cache the kernel would give back, which free memory alone does not; free swap
  // is added (slow, but a run fitting there ends).
  std::ifstream in("/proc/meminfo");
  std::string key;
  double kb = 0.0, total = 0.0;
  bool found = false;
  while (in >> key >> kb) {
    if (key == "MemAvailable:" || key == "SwapFree:") total += kb * 1024.0, found = found || key == "MemAvailable:";
    in.ignore(256, '\n');
  }
  if (found) return total;
  const long pages = sysconf(_SC_AVPHYS_PAGES), page = sysconf(_SC_PAGESIZE);
  return pages > 0 && page > 0 ? static_cast<double>(pages) * static_cast<double>(page) : 0.0;
}

void check_quad_memory(double estimated_quads, double available_bytes, const std::string& what) {
  const double need = estimated_quads * kBytesPerQuad;
  if (!(available_bytes > 0.0) || need <= available_bytes) return;
  throw InputError(what + " would need about " + short_number(estimated_quads) + " quads and about " +
                   memory_text(need) + " of memory to mesh them (" + short_number(kBytesPerQuad) +
                   " bytes per quad at least), more than the " + memory_text(available_bytes) +
                   " this machine has available; --max-quads does not lift this: give a larger size");
}

MeshOptions resolve_sizes(const MeshOptions& options) {
  MeshOptions o = options;
  if (!o.size.graded()) return o;
  if (o.size.h != 0.0 && o.size.h != o.size.field.size_min)
    throw InputError("--size and --size-min exclude each other: a graded mesh takes its least size from --size-min");
  o.size.h = o.size.field.size_min;
  return o;
}

void check_mesh_options(const MeshOptions& options) {
  if (options.size.graded()) check_size_field_options(options.size.field);
  const MeshOptions o = resolve_sizes(options);
  require(std::isfinite(o.size.h) && o.size.h > 0, "--size", "size", o.size.h, "a positive finite number");
  require(within(o.gates.min_scaled_jacobian, 0.0, 1.0), "--min-sj", "min_scaled_jacobian", o.gates.min_scaled_jacobian,
          "in [0, 1]");
  require(std::isfinite(o.gates.max_edge_ratio) && o.gates.max_edge_ratio >= 1.0, "--max-edge-ratio", "max_edge_ratio",
          o.gates.max_edge_ratio, "a finite number >= 1 (the longest edge of a quad over its shortest)");
  require(within(o.gates.max_poor_fraction, 0.0, 1.0), "--max-poor-fraction", "max_poor_fraction",
          o.gates.max_poor_fraction, "in [0, 1]");
  require(within(o.curves.corner_threshold_deg, 0.0, 180.0), "--corner-angle", "corner_threshold_deg",
          o.curves.corner_threshold_deg, "in [0, 180] degrees");
  require(within(o.refine.flat_corner_deg, 0.0, 180.0), "--flat-corner-angle", "refine.flat_corner_deg",
          o.refine.flat_corner_deg, "in [0, 180] degrees (180 = off)");
  require(within(o.refine.loop_corner_deg, 0.0, 180.0), "--loop-corner-angle", "refine.loop_corner_deg",
          o.refine.loop_corner_deg, "in [0, 180] degrees (180 = off)");
  require(std::isfinite(o.curves.simplify) && o.curves.simplify >= 0, "--simplify", "simplify", o.curves.simplify,
          "a finite number >= 0 (0 = off)");
  require(std::isfinite(o.curves.smooth_curves) && o.curves.smooth_curves >= 0, "--smooth-curves", "smooth_curves",
          o.curves.smooth_curves, "a finite fraction of the size, at least 0");
  require(std::isfinite(o.curves.min_island_width) && o.curves.min_island_width >= 0, "--min-island-width",
          "min_island_width", o.curves.min_island_width, "a finite fraction of the size, at least 0");
  require(std::isfinite(o.map.deform.boundary_weight) && o.map.deform.boundary_weight >= 0, "--boundary-weight",
          "map.deform.boundary_weight", o.map.deform.boundary_weight, "a finite number >= 0");
  require(std::isfinite(o.map.deform.feature_weight) && o.map.deform.feature_weight >= 0, "--feature-weight",
          "map.deform.feature_weight", o.map.deform.feature_weight, "a finite number >= 0");
  require(std::isfinite(o.gates.feature_tolerance) && o.gates.feature_tolerance >= 0, "--feature-tolerance",
          "feature_tolerance", o.gates.feature_tolerance, "a finite fraction of the size, at least 0 (0: unbounded)");
  require(std::isfinite(o.map.layout.agree_turn_elements) && o.map.layout.agree_turn_elements >= 0, "--agree-turns",
          "map.layout.agree_turn_elements", o.map.layout.agree_turn_elements, "a finite number of elements >= 0 (0 = off)");
  require(o.size.max_quads >= 1, "--max-quads", "max_quads", static_cast<double>(o.size.max_quads), "at least 1");
  require(o.run.threads >= 0 && o.run.threads <= kMaxThreads, "--threads", "threads", o.run.threads,
          "in [0, 4096] (0 = all cores)");
  require(o.subregions.parts >= 0, "--parts", "parts", o.subregions.parts, ">= 0 (0 = automatic)");
}

void check_mesh_size(const Region& region, const MeshOptions& options) {
  check_mesh_options(options);
  const MeshOptions o = resolve_sizes(options);
  const std::string src = region.source.empty() ? std::string("region") : region.source;
  const Box2 box = region.bounding_box();
  const double w = box.hi.x - box.lo.x, h = box.hi.y - box.lo.y;
  if (!(std::isfinite(w) && std::isfinite(h) && w > 0 && h > 0))
    throw InputError(src + ": the domain's extent is not a finite positive size (" + short_number(w) + " x " +
                     short_number(h) + ")");
  double area = 0.0;
  std::map<int, double> part_areas;  // by Ring::part
  for (const Ring& r : region.rings) {
    double s = 0.0;
    const auto& p = r.points;
    // Relative to the box corner, so that coordinates far from the origin keep their digits.
    for (std::size_t i = 0; i < p.size(); ++i) {
      const Vec2 a{p[i].x - box.lo.x, p[i].y - box.lo.y};
      const Vec2 b{p[(i + 1) % p.size()].x - box.lo.x, p[(i + 1) % p.size()].y - box.lo.y};
      s += a.x * b.y - a.y * b.x;
    }
    area += r.hole ? -std::abs(0.5 * s) : std::abs(0.5 * s);
    part_areas[r.part] += r.hole ? -std::abs(0.5 * s) : std::abs(0.5 * s);
  }
  if (!(std::isfinite(area) && area > 0))
    throw InputError(src + ": the domain's area is not a finite positive number (" + short_number(area) + ")");
  const std::string flag = o.size.graded() ? "--size-min " : "--size ";
  const std::string extent = short_number(w) + " x " + short_number(h);
  if (o.size.h > 0.5 * std::min(w, h))
    throw InputError(src + ": " + flag + short_number(o.size.h) + " is larger than half the region's extent (" +
                     extent + ")");
  // Parts smaller than one quad are left out (and reported); when that is every part, the size is what is wrong
  // (a region of scattered islets, a thin diagonal sliver), said before meshing rather than after.
  double largest = 0.0;
  for (const auto& [part, a] : part_areas) largest = std::max(largest, a);
  if (o.curves.drop_small_parts && largest < o.size.h * o.size.h)
    throw InputError(src + ": " + flag + short_number(o.size.h) + " is larger than every polygon part: the largest has area " +
                     short_number(largest) + ", less than one quad (" + short_number(o.size.h * o.size.h) +
                     "), in a region of extent " + extent + "; the size must be below the square root of that area, " +
                     short_number(std::sqrt(largest)));
  // A graded run's estimate comes from its field (the size stage of mesh_region refuses it there).
  const double estimate = o.size.graded() ? 0.0 : area / (o.size.h * o.size.h);
  if (!(estimate <= static_cast<double>(o.size.max_quads)))
    throw InputError(src + ": size " + short_number(o.size.h) + " would need about " + short_number(estimate) +
                     " quads (area " + short_number(area) + " / size^2), more than the limit of " +
                     std::to_string(o.size.max_quads) + " (raise --max-quads)");
  if (!o.size.graded())
    check_quad_memory(estimate, available_memory_bytes(), src + ": " + flag + short_number(o.size.h));
  // Far from the origin the region is meshed in a local frame, but the mesh is written back in the input's
  // coordinates, which there step by the spacing of doubles (ulp): 0.125 at 9e14, 1.2e-4 at 1e12. A size of
  // fewer than kMinSizeInSteps such steps would come back with its quads bent or folded (a 1 x 1 square at 9e14
  // meshed at size 0.1 was written with 36 inverted quads), so it is refused before any work.
  const double far = std::max({std::abs(box.lo.x), std::abs(box.hi.x), std::abs(box.lo.y), std::abs(box.hi.y)});
  const double step = std::nextafter(far, INFINITY) - far;
  if (!(o.size.h >= kMinSizeInSteps * step))
    throw InputError(src + ": size " + short_number(o.size.h) + " is too fine for coordinates as large as " +
                     short_number(far) + ", which step by " + short_number(step) +
                     " there (double precision): the mesh written back in them would lose its shape; the size must "
                     "be at least " +
                     short_number(kMinSizeInSteps * step) + " (" + std::to_string(static_cast<int>(kMinSizeInSteps)) +
                     " steps, at most 2.3e-13 times the largest coordinate), or move the input nearer the origin");
}

void check_field_estimate(double estimated_quads, const MeshOptions& options, const std::string& source) {
  if (!(estimated_quads <= static_cast<double>(options.size.max_quads)))
    throw InputError(source + ": the size field would need about " + short_number(estimated_quads) +
                     " quads, more than the limit of " + std::to_string(options.size.max_quads) +
                     " (raise --max-quads or --size-min)");
  check_quad_memory(estimated_quads, available_memory_bytes(),
                    source + ": the size field (--size-min " + short_number(options.size.field.size_min) + ")");
}

}  // namespace polysquare
