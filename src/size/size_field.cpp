#include "polysquare/size/size_field.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <queue>
#include <set>
#include <sstream>
#include <string>

#include "polysquare/core/error.h"

namespace polysquare {

SizeField::SizeField(Vec2 origin, double cell, int nx, int ny, std::vector<double> h)
    : origin_(origin), cell_(cell), nx_(nx), ny_(ny), h_(std::move(h)) {}

double SizeField::at(Vec2 p) const {
  if (h_.empty()) return std::numeric_limits<double>::quiet_NaN();
  const double fx = std::clamp((p.x - origin_.x) / cell_, 0.0, static_cast<double>(nx_ - 1));
  const double fy = std::clamp((p.y - origin_.y) / cell_, 0.0, static_cast<double>(ny_ - 1));
  const int i = std::min(static_cast<int>(fx), std::max(nx_ - 2, 0));
  const int j = std::min(static_cast<int>(fy), std::max(ny_ - 2, 0));
  const int i1 = std::min(i + 1, nx_ - 1), j1 = std::min(j + 1, ny_ - 1);
  const double tx = fx - i, ty = fy - j;
  auto v = [&](int a, int b) { return h_[static_cast<std::size_t>(b) * nx_ + a]; };
  return (1 - ty) * ((1 - tx) * v(i, j) + tx * v(i1, j)) + ty * ((1 - tx) * v(i, j1) + tx * v(i1, j1));
}

namespace {

// The sampling grid: cell centres origin + (i, j) * cell.
struct Grid {
  Vec2 origin;
  double cell = 0.0;
  int nx = 0, ny = 0;
  std::size_t size() const { return static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny); }
  Vec2 centre(std::size_t c) const {
    return {origin.x + static_cast<double>(c % nx) * cell, origin.y + static_cast<double>(c / nx) * cell};
  }
  int column(double x) const { return std::clamp(static_cast<int>(std::lround((x - origin.x) / cell)), 0, nx - 1); }
  int row(double y) const { return std::clamp(static_cast<int>(std::lround((y - origin.y) / cell)), 0, ny - 1); }
};

struct Segment {
  Vec2 a, b;
};

Vec2 nearest_on_segment(Vec2 p, const Segment& s) {
  const Vec2 d = s.b - s.a;
  const double len2 = dot(d, d);
  const double t = len2 > 0.0 ? std::clamp(dot(p - s.a, d) / len2, 0.0, 1.0) : 0.0;
  return s.a + t * d;
}

void require(bool ok, const char* flag, double value, const char* range) {
  if (!ok) {
    std::ostringstream os;
    os.precision(6);
    os << flag << " must be " << range << ", got " << value;
    throw InputError(os.str());
  }
}

// A grid over the region's box with a cell of margin on every side, at the options' spacing or coarser.
Grid make_grid(const Region& region, const SizeFieldOptions& o) {
  const Box2 box = region.bounding_box();
  const double w = box.hi.x - box.lo.x, h = box.hi.y - box.lo.y;
  double cell = o.cell > 0.0 ? o.cell : 0.5 * o.size_min;
  const double budget = static_cast<double>(std::max<std::size_t>(o.max_cells, 16));
  if ((w / cell + 3.0) * (h / cell + 3.0) > budget) {
    // Solve (w / c + 3)(h / c + 3) = budget for c (the positive root), then round up slightly.
    const double a = budget - 9.0, b = -3.0 * (w + h), c = -w * h;
    cell = std::max(cell, 1.0001 * (-b + std::sqrt(b * b - 4.0 * a * c)) / (2.0 * a));
  }
  Grid g;
  g.cell = cell;
  g.origin = {box.lo.x - cell, box.lo.y - cell};
  g.nx = static_cast<int>(std::ceil(w / cell)) + 3;
  g.ny = static_cast<int>(std::ceil(h / cell)) + 3;
  return g;
}

// Per cell: whether its centre lies inside the domain (even-odd over every ring, scanline by scanline).
std::vector<std::uint8_t> inside_cells(const Grid& g, const std::vector<const Ring*>& rings) {
  std::vector<std::vector<double>> crossings(static_cast<std::size_t>(g.ny));
  for (const Ring* r : rings) {
    const Ring& ring = *r;
    const std::size_t n = ring.points.size();
    for (std::size_t k = 0; k < n; ++k) {
      const Vec2 a = ring.points[k], b = ring.points[(k + 1) % n];
      if (a.y == b.y) continue;
      const int j0 = std::max(0, static_cast<int>(std::floor((std::min(a.y, b.y) - g.origin.y) / g.cell)));
      const int j1 = std::min(g.ny - 1, static_cast<int>(std::ceil((std::max(a.y, b.y) - g.origin.y) / g.cell)));
      for (int j = j0; j <= j1; ++j) {
        const double y = g.origin.y + j * g.cell;
        if ((a.y > y) != (b.y > y)) crossings[static_cast<std::size_t>(j)].push_back(a.x + (y - a.y) * (b.x - a.x) / (b.y - a.y));
      }
    }
  }
  std::vector<std::uint8_t> inside(g.size(), 0);
  for (int j = 0; j < g.ny; ++j) {
    std::vector<double>& xs = crossings[static_cast<std::size_t>(j)];
    std::sort(xs.begin(), xs.end());
    for (std::size_t k = 0; k + 1 < xs.size(); k += 2) {
      const int i0 = std::max(0, static_cast<int>(std::ceil((xs[k] - g.origin.x) / g.cell)));
      const int i1 = std::min(g.nx - 1, static_cast<int>(std::ceil((xs[k + 1] - g.origin.x) / g.cell)) - 1);
      for (int i = i0; i <= i1; ++i) inside[static_cast<std::size_t>(j) * g.nx + i] = 1;
    }
  }
  return inside;
}

// A wave over the grid's 8-neighbour graph that carries a source: each cell keeps the least value(cell, source)
// of the sources its neighbours offer it, and offers its own on when that improved (label-correcting, so each
// pair of neighbours has offered each other its final source when the queue runs dry). Cells outside `allowed`
// (when given) neither take nor pass a source.
using Offer = std::function<double(std::size_t cell, std::int32_t source)>;
void propagate(const Grid& g, std::vector<double>& best, std::vector<std::int32_t>& source,
               const std::vector<std::uint8_t>* allowed, const Offer& value) {
  using Item = std::pair<double, std::int32_t>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
  for (std::size_t c = 0; c < g.size(); ++c)
    if (source[c] >= 0) queue.push({best[c], static_cast<std::int32_t>(c)});
  while (!queue.empty()) {
    const auto [v, c] = queue.top();
    queue.pop();
    if (v > best[static_cast<std::size_t>(c)]) continue;  // a stale entry
    const int i = c % g.nx, j = c / g.nx;
    for (int dj = -1; dj <= 1; ++dj)
      for (int di = -1; di <= 1; ++di) {
        const int a = i + di, b = j + dj;
        if ((di == 0 && dj == 0) || a < 0 || b < 0 || a >= g.nx || b >= g.ny) continue;
        const std::size_t n = static_cast<std::size_t>(b) * g.nx + a;
        if (allowed && !(*allowed)[n]) continue;
        const double offer = value(n, source[static_cast<std::size_t>(c)]);
        if (offer < best[n]) {
          best[n] = offer;
          source[n] = source[static_cast<std::size_t>(c)];
          queue.push({offer, static_cast<std::int32_t>(n)});
        }
      }
  }
}

// Calls visit(cell) for each cell that the segment passes through (sampled at half-cell steps).
template <class Visit>
void cells_along(const Grid& g, const Segment& seg, Visit visit) {
  const int steps = 1 + static_cast<int>(std::ceil(2.0 * distance(seg.a, seg.b) / g.cell));
  for (int k = 0; k <= steps; ++k) {
    const Vec2 p = lerp(seg.a, seg.b, static_cast<double>(k) / steps);
    visit(static_cast<std::size_t>(g.row(p.y)) * g.nx + g.column(p.x));
  }
}

struct Distances {
  std::vector<double> distance;      ///< per cell, to the nearest segment
  std::vector<std::int32_t> nearest;  ///< per cell, that segment (-1 when there is none)
};

// Distance from every cell centre to the nearest of `segments`: the cells along each segment are seeded with
// their exact distance, then the wave carries each nearest segment outwards.
Distances distance_to_segments(const Grid& g, const std::vector<Segment>& segments) {
  Distances d{std::vector<double>(g.size(), std::numeric_limits<double>::infinity()),
              std::vector<std::int32_t>(g.size(), -1)};
  for (std::size_t s = 0; s < segments.size(); ++s)
    cells_along(g, segments[s], [&](std::size_t c) {
      const double dist = distance(g.centre(c), nearest_on_segment(g.centre(c), segments[s]));
      if (dist < d.distance[c]) d.distance[c] = dist, d.nearest[c] = static_cast<std::int32_t>(s);
    });
  propagate(g, d.distance, d.nearest, nullptr, [&](std::size_t c, std::int32_t s) {
    const Vec2 p = g.centre(c);
    return distance(p, nearest_on_segment(p, segments[static_cast<std::size_t>(s)]));
  });
  return d;
}

void add_segments(const std::vector<Vec2>& points, bool closed, std::vector<Segment>& out) {
  const std::size_t n = points.size();
  for (std::size_t k = 0; k + 1 < n; ++k) out.push_back({points[k], points[k + 1]});
  if (closed && n > 2) out.push_back({points[n - 1], points[0]});
}

std::vector<Segment> ring_segments(const Region& region) {
  std::vector<Segment> out;
  for (const Ring& r : region.rings) add_segments(r.points, true, out);
  return out;
}

// The distance term's curves: the rings of parts and the feature curves that have no size attribute (a size
// takes HMIN's place along its own curves). `rings_only`: they are exactly the rings.
std::vector<Segment> hmin_segments(const Region& region, bool& rings_only) {
  std::vector<Segment> out;
  rings_only = true;
  for (const Ring& r : region.rings) {
    if (r.size > 0.0) rings_only = false;
    else add_segments(r.points, true, out);
  }
  for (const FeatureCurve& f : region.features)
    if (f.size <= 0.0) add_segments(f.points, f.closed, out), rings_only = false;
  return out;
}

struct Passages {
  std::vector<double> width;  ///< per cell: the width of the passage whose mid-line it is on, infinity elsewhere
  std::size_t medial_cells = 0;
  double narrowest = 0.0;
};

// Cells on a passage's mid-line: two neighbouring inside cells whose nearest shore points lie in directions that
// open by more than the medial angle (the shores face each other across them). The width there is both
// distances plus the step between the cells across the passage.
Passages find_passages(const Grid& g, const std::vector<std::uint8_t>& inside, const std::vector<Segment>& shores,
                       const Distances& d, double medial_angle_deg) {
  Passages p{std::vector<double>(g.size(), std::numeric_limits<double>::infinity()), 0, 0.0};
  const double cos_open = std::cos(medial_angle_deg * 3.14159265358979323846 / 180.0);
  auto direction = [&](std::size_t c) {
    const Vec2 at = g.centre(c);
    const Vec2 v = nearest_on_segment(at, shores[static_cast<std::size_t>(d.nearest[c])]) - at;
    const double n = norm(v);
    return n > 0.0 ? (1.0 / n) * v : Vec2{};
  };
  for (int j = 0; j < g.ny; ++j)
    for (int i = 0; i < g.nx; ++i) {
      const std::size_t c = static_cast<std::size_t>(j) * g.nx + i;
      if (!inside[c] || d.nearest[c] < 0 || d.distance[c] < 0.5 * g.cell) continue;
      for (const std::size_t n : {c + 1, c + static_cast<std::size_t>(g.nx)}) {
        if ((n == c + 1 && i + 1 >= g.nx) || n >= g.size() || !inside[n] || d.nearest[n] < 0 ||
            d.distance[n] < 0.5 * g.cell)
          continue;
        const Vec2 u = direction(c), w = direction(n);
        if (dot(u, w) >= cos_open) continue;
        const Vec2 across = w - u;  // from the one shore to the other, through both cells
        const double step = std::fabs(dot(g.centre(n) - g.centre(c), (1.0 / std::max(norm(across), 1e-300)) * across));
        const double width = d.distance[c] + d.distance[n] + step;
        p.width[c] = std::min(p.width[c], width);
        p.width[n] = std::min(p.width[n], width);
      }
    }
  for (std::size_t c = 0; c < g.size(); ++c)
    if (std::isfinite(p.width[c])) {
      ++p.medial_cells;
      p.narrowest = p.medial_cells == 1 ? p.width[c] : std::min(p.narrowest, p.width[c]);
    }
  return p;
}

// h <= 2 (distance to the shore + distance to the nearest mid-line) / N: the local feature size of OceanMesh2D's
// `fs`, which is about half the passage's width anywhere across it. The distance to the mid-lines runs inside the
// domain only, so a passage across a strip of land does not shrink a wide bay's sizes.
std::vector<double> across_term(const Grid& g, const std::vector<std::uint8_t>& inside, const Distances& shore,
                                const Passages& passages, double across) {
  std::vector<double> to_mid(g.size(), std::numeric_limits<double>::infinity());
  std::vector<std::int32_t> source(g.size(), -1);
  for (std::size_t c = 0; c < g.size(); ++c)
    if (std::isfinite(passages.width[c])) to_mid[c] = 0.0, source[c] = static_cast<std::int32_t>(c);
  propagate(g, to_mid, source, &inside,
            [&](std::size_t c, std::int32_t s) { return distance(g.centre(c), g.centre(static_cast<std::size_t>(s))); });
  std::vector<double> h(g.size(), std::numeric_limits<double>::infinity());
  for (std::size_t c = 0; c < g.size(); ++c)
    if (inside[c] && std::isfinite(to_mid[c])) h[c] = 2.0 * (shore.distance[c] + to_mid[c]) / across;
  return h;
}

}  // namespace

void check_size_field_options(const SizeFieldOptions& o) {
  require(std::isfinite(o.size_min) && o.size_min > 0, "--size-min", o.size_min, "a positive finite number");
  require(std::isfinite(o.size_max) && o.size_max > 0, "--size-max", o.size_max, "a positive finite number");
  require(o.size_max >= o.size_min, "--size-max", o.size_max, "at least --size-min");
  require(std::isfinite(o.grade) && o.grade > 0, "--grade", o.grade, "a positive finite number (0.15 to 0.35 is usual)");
  require(std::isfinite(o.across) && o.across >= 0, "--across", o.across, "a finite number of quads >= 0 (0 = off)");
  require(o.medial_angle_deg > 0 && o.medial_angle_deg < 180, "medial_angle_deg", o.medial_angle_deg,
          "in (0, 180) degrees");
  require(std::isfinite(o.cell) && o.cell >= 0, "cell", o.cell, "a finite number >= 0 (0 = automatic)");
}

std::size_t limit_gradient(std::vector<double>& h, int nx, int ny, double cell, double grade) {
  const Grid g{{0.0, 0.0}, cell, nx, ny};
  const std::vector<double> before = h;
  std::vector<std::int32_t> source(g.size());
  for (std::size_t c = 0; c < g.size(); ++c) source[c] = static_cast<std::int32_t>(c);
  propagate(g, h, source, nullptr, [&](std::size_t c, std::int32_t s) {
    const auto cs = static_cast<std::size_t>(s);
    return before[cs] + grade * distance(g.centre(c), g.centre(cs));
  });
  std::size_t lowered = 0;
  for (std::size_t c = 0; c < g.size(); ++c) lowered += h[c] < before[c];
  return lowered;
}

namespace {

// The sampled terms at the cell centres inside the domain: each lowers h there; a value that is not a positive
// number (NaN, zero, negative) is refused naming the term and the place.
void apply_sampled_terms(const Grid& g, const std::vector<std::uint8_t>& inside, const std::vector<SizeTerm>& terms,
                         std::vector<double>& h) {
  if (terms.empty()) return;
  std::vector<std::size_t> cells;
  std::vector<Vec2> points;
  for (std::size_t c = 0; c < g.size(); ++c)
    if (inside[c]) cells.push_back(c), points.push_back(g.centre(c));
  for (const SizeTerm& term : terms) {
    const std::vector<double> v = term.at(points);
    if (v.size() != points.size()) throw InputError(term.name + ": gave " + std::to_string(v.size()) + " sizes for " +
                                                    std::to_string(points.size()) + " points");
    for (std::size_t k = 0; k < v.size(); ++k) {
      if (!(v[k] > 0.0)) {
        std::ostringstream os;
        os.precision(12);
        os << term.name << ": the size " << v[k] << " at (" << points[k].x << ", " << points[k].y
           << ") is not a positive number";
        throw InputError(os.str());
      }
      h[cells[k]] = std::min(h[cells[k]], v[k]);
    }
  }
}

// The inputs' size attributes: h <= s inside a domain part or a closed feature curve of size s, and at the cells
// along a curve of size s. The gradient limit, run after them, grades the latter away as s + grade * (distance to
// the curve), as the distance term grades HMIN away.
void apply_size_attributes(const Grid& g, const Region& region, std::vector<double>& h) {
  auto bound_inside = [&](const std::vector<const Ring*>& rings, double size) {
    const std::vector<std::uint8_t> inside = inside_cells(g, rings);
    for (std::size_t c = 0; c < g.size(); ++c)
      if (inside[c]) h[c] = std::min(h[c], size);
  };
  std::map<double, std::vector<const Ring*>> parts_by_size;  // parts do not overlap: one even-odd pass per size
  for (const Ring& r : region.rings)
    if (r.size > 0.0) parts_by_size[r.size].push_back(&r);
  for (const auto& [size, rings] : parts_by_size) bound_inside(rings, size);
  for (const Ring& area : region.size_areas) bound_inside({&area}, area.size);
  for (const FeatureCurve& f : region.features) {
    if (f.size <= 0.0) continue;
    std::vector<Segment> segments;
    add_segments(f.points, f.closed, segments);
    for (const Segment& seg : segments) cells_along(g, seg, [&](std::size_t c) { h[c] = std::min(h[c], f.size); });
  }
}

// One sentence per input feature whose size attribute lies outside [size_min, size_max], which the clip changes.
std::vector<std::string> clipped_size_warnings(const Region& region, const SizeFieldOptions& o) {
  std::vector<std::string> out;
  std::set<int> said;  // a feature's rings, pieces and area carry one size: one sentence each
  auto check = [&](double size, int source, const std::string& name) {
    if (size <= 0.0 || (size >= o.size_min && size <= o.size_max) || !said.insert(source).second) return;
    std::ostringstream os;
    os.precision(6);
    os << region.source << (region.source.empty() ? "" : ": ") << "feature " << source
       << (name.empty() ? std::string() : " ('" + name + "')") << ": its size " << size
       << (size < o.size_min ? " is below --size-min " : " is above --size-max ")
       << (size < o.size_min ? o.size_min : o.size_max) << ", which the field takes instead";
    out.push_back(os.str());
  };
  for (const Ring& r : region.rings) check(r.size, r.source_feature, r.name);
  for (const FeatureCurve& f : region.features) check(f.size, f.source_feature, f.name);
  for (const Ring& a : region.size_areas) check(a.size, a.source_feature, a.name);
  return out;
}

}  // namespace

bool has_size_attributes(const Region& region) {
  auto sized = [](const auto& item) { return item.size > 0.0; };
  return std::any_of(region.rings.begin(), region.rings.end(), sized) ||
         std::any_of(region.features.begin(), region.features.end(), sized) || !region.size_areas.empty();
}

SizeFieldResult make_size_field(const Region& region, const SizeFieldOptions& o) {
  check_size_field_options(o);
  const Grid g = make_grid(region, o);
  SizeFieldResult out;
  std::vector<const Ring*> rings;
  for (const Ring& r : region.rings) rings.push_back(&r);
  out.inside = inside_cells(g, rings);
  std::vector<double> h(g.size(), o.size_max);
  const std::vector<Segment> shores = ring_segments(region);
  bool rings_only = false;
  const std::vector<Segment> curves = hmin_segments(region, rings_only);
  // The distance to the rings is the passage term's, and the distance term's too when its curves are the rings:
  // each wave over the grid runs once, and only for a term that asks for it.
  Distances shore, to_curves;
  if (o.across > 0 || (o.distance_term && rings_only)) shore = distance_to_segments(g, shores);
  if (o.distance_term && !curves.empty()) {
    if (!rings_only) to_curves = distance_to_segments(g, curves);
    const std::vector<double>& d = rings_only ? shore.distance : to_curves.distance;
    for (std::size_t c = 0; c < g.size(); ++c) h[c] = std::min(h[c], o.size_min + o.grade * d[c]);
  }
  if (o.across > 0) {
    const Passages passages = find_passages(g, out.inside, shores, shore, o.medial_angle_deg);
    const std::vector<double> fs = across_term(g, out.inside, shore, passages, o.across);
    for (std::size_t c = 0; c < g.size(); ++c) h[c] = std::min(h[c], fs[c]);
    out.stats.medial_cells = passages.medial_cells;
    out.stats.narrowest_passage = passages.narrowest;
  }
  apply_sampled_terms(g, out.inside, o.terms, h);
  apply_size_attributes(g, region, h);
  out.warnings = clipped_size_warnings(region, o);
  for (double& v : h) v = std::clamp(v, o.size_min, o.size_max);
  out.stats.limited_cells = limit_gradient(h, g.nx, g.ny, g.cell, o.grade);
  out.stats.cells = g.size();
  out.stats.cell = g.cell;
  bool first = true;
  for (std::size_t c = 0; c < g.size(); ++c) {
    if (!out.inside[c]) continue;
    ++out.stats.inside_cells;
    out.stats.estimated_quads += g.cell * g.cell / (h[c] * h[c]);
    out.stats.min = first ? h[c] : std::min(out.stats.min, h[c]);
    out.stats.max = first ? h[c] : std::max(out.stats.max, h[c]);
    first = false;
  }
  out.field = SizeField(g.origin, g.cell, g.nx, g.ny, std::move(h));
  return out;
}

double estimate_quads(const SizeField& field, const Region& region, const std::vector<int>& rings) {
  if (field.empty()) return 0.0;
  const Grid g{field.origin(), field.cell(), field.nx(), field.ny()};
  std::vector<const Ring*> chosen;
  for (int r : rings) chosen.push_back(&region.rings[static_cast<std::size_t>(r)]);
  const std::vector<std::uint8_t> inside = inside_cells(g, chosen);
  double quads = 0.0;
  for (std::size_t c = 0; c < inside.size(); ++c)
    if (inside[c]) quads += g.cell * g.cell / (field.values()[c] * field.values()[c]);
  return quads;
}

}  // namespace polysquare
