// Mesh pictures with Cairo (libcairo2): one drawing for both PNG (image surface) and SVG (SVG surface).
#include "polysquare/io/render.h"

#include "polysquare/core/quad_topology.h"

#include <cairo/cairo-svg.h>
#include <cairo/cairo.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <map>
#include <sstream>
#include <string>
#include <unordered_map>
#include <vector>

#include "polysquare/core/error.h"
#include "polysquare/io/atomic_file.h"
#include "polysquare/io/mesh_io.h"
#include "polysquare/quality/quality.h"
#include "polysquare/size/size_conformity.h"

namespace polysquare {

namespace {

using Rgb = std::array<double, 3>;

// Twelve colours for subregions, neighbours in index order far apart in hue.
constexpr std::array<Rgb, 12> kPalette{{{0.12, 0.47, 0.71}, {1.00, 0.50, 0.05}, {0.17, 0.63, 0.17},
                                        {0.84, 0.15, 0.16}, {0.58, 0.40, 0.74}, {0.55, 0.34, 0.29},
                                        {0.89, 0.47, 0.76}, {0.50, 0.50, 0.50}, {0.74, 0.74, 0.13},
                                        {0.09, 0.75, 0.81}, {0.68, 0.78, 0.91}, {1.00, 0.73, 0.47}}};

using ColourStops = std::array<std::pair<double, Rgb>, 5>;

// The colour at t in [0, 1] between `stops` (increasing t, the first at 0, the last at 1), linearly.
Rgb interpolate(const ColourStops& stops, double t) {
  t = std::clamp(std::isfinite(t) ? t : 0.0, 0.0, 1.0);
  for (std::size_t i = 1; i < stops.size(); ++i) {
    if (t <= stops[i].first) {
      const double u = (t - stops[i - 1].first) / (stops[i].first - stops[i - 1].first);
      Rgb c;
      for (int k = 0; k < 3; ++k) c[k] = stops[i - 1].second[k] + u * (stops[i].second[k] - stops[i - 1].second[k]);
      return c;
    }
  }
  return stops.back().second;
}

// Goodness t in [0, 1] (0 = worst): dark red, red, yellow, light green, green.
Rgb ramp(double t) {
  static constexpr ColourStops stops{{{0.0, {0.50, 0.00, 0.05}},
                                      {0.3, {0.89, 0.20, 0.11}},
                                      {0.6, {0.99, 0.80, 0.25}},
                                      {0.8, {0.60, 0.80, 0.35}},
                                      {1.0, {0.10, 0.55, 0.25}}}};
  return interpolate(stops, t);
}

// Too small (t = 0) blue, on target (0.5) pale green, not white (the background), too large (1) red: a
// diverging scale, so that both ways off the size read as strong colours.
Rgb diverging_ramp(double t) {
  static constexpr ColourStops stops{{{0.0, {0.10, 0.25, 0.65}},
                                      {0.25, {0.45, 0.68, 0.92}},
                                      {0.5, {0.80, 0.92, 0.72}},
                                      {0.75, {0.97, 0.60, 0.33}},
                                      {1.0, {0.72, 0.06, 0.10}}}};
  return interpolate(stops, t);
}

// Where a measure value lies on the colour bar, 0 (bottom) to 1 (top): sj and skew as they are, a size ratio on
// a log scale from 0.5 to 2, clamped (twice too small and twice too large equally strong colours).
double bar_position(RenderColor color, double value) {
  if (color != RenderColor::size_ratio) return value;
  return std::clamp(0.5 + 0.5 * std::log2(value), 0.0, 1.0);  // log2(0) = -inf: the bottom
}

// The measure value at a position on the colour bar (bar_position's inverse), for its scale's labels.
double bar_value(RenderColor color, double position) {
  return color == RenderColor::size_ratio ? std::exp2(2.0 * position - 1.0) : position;
}

// The colour at a position on the colour bar.
Rgb bar_color(RenderColor color, double position) {
  if (color == RenderColor::size_ratio) return diverging_ramp(position);
  return color == RenderColor::skew ? ramp(1.0 - position) : ramp(position);
}

const char* measure_name(RenderColor color) {
  if (color == RenderColor::size_ratio) return "size / h (log scale)";
  return color == RenderColor::sj ? "scaled Jacobian" : "skew";
}

cairo_status_t append_to_string(void* closure, const unsigned char* data, unsigned int length) {
  static_cast<std::string*>(closure)->append(reinterpret_cast<const char*>(data), length);
  return CAIRO_STATUS_SUCCESS;
}

void set(cairo_t* cr, const Rgb& c, double alpha = 1.0) { cairo_set_source_rgba(cr, c[0], c[1], c[2], alpha); }

void text(cairo_t* cr, double x, double y, const std::string& s) {
  cairo_move_to(cr, x, y);
  cairo_show_text(cr, s.c_str());
}

// Text that must end before x_max (the picture's right margin): drawn smaller when it would not.
void text_within(cairo_t* cr, double x, double y, const std::string& s, double x_max) {
  cairo_text_extents_t e;
  cairo_text_extents(cr, s.c_str(), &e);
  const double room = x_max - x, used = e.x_bearing + e.x_advance;
  if (used <= room || !(used > 0)) return text(cr, x, y, s);
  cairo_save(cr);
  cairo_matrix_t m;
  cairo_get_font_matrix(cr, &m);
  cairo_matrix_scale(&m, room / used, room / used);
  cairo_set_font_matrix(cr, &m);
  text(cr, x, y, s);
  cairo_restore(cr);
}

std::string fixed(double v, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}

}  // namespace

std::array<double, 3> valence_color(int valence, bool boundary) {
  const int extra = valence - (boundary ? 3 : 4);
  if (extra < 0) return {0.10, 0.30, 0.90};
  if (extra == 1) return {1.00, 0.55, 0.00};
  return {0.80, 0.00, 0.60};
}

std::array<double, 3> measure_color(RenderColor color, double value) {
  return bar_color(color, bar_position(color, value));
}

RenderColor parse_render_color(std::string_view text) {
  if (text == "sj") return RenderColor::sj;
  if (text == "skew") return RenderColor::skew;
  if (text == "part") return RenderColor::part;
  if (text == "singularities") return RenderColor::singularities;
  if (text == "size") return RenderColor::size_ratio;
  throw InputError("the picture's colour must be sj, skew, part, singularities or size, got '" + std::string(text) +
                   "'");
}

Box2 parse_window(std::string_view text) {
  std::istringstream is{std::string(text)};
  double v[4];
  char comma = 0;
  bool ok = static_cast<bool>(is >> v[0]);
  for (int i = 1; i < 4 && ok; ++i) ok = (is >> comma) && comma == ',' && (is >> v[i]);
  is >> std::ws;
  ok = ok && is.eof() && std::all_of(v, v + 4, [](double x) { return std::isfinite(x); });
  Box2 b;
  if (ok) {
    b.add({v[0], v[1]});
    b.add({v[2], v[3]});
  }
  if (!ok || !(b.hi.x > b.lo.x) || !(b.hi.y > b.lo.y))
    throw InputError("--window must be x0,y0,x1,y1 with x0 != x1 and y0 != y1, got '" + std::string(text) + "'");
  return b;
}

namespace {

// Layout: the plot on the left, the colour bar and legend in a 190 px column on the right.
constexpr double kPad = 10.0, kColumn = 190.0, kMaxHeight = 16000.0, kMinHeight = 400.0;

// Checks what is asked before any drawing; returns whether the picture is an SVG.
bool check_picture_request(const std::filesystem::path& path, const QuadMesh& mesh, const RenderOptions& options) {
  const std::string ext = lower_extension(path);
  const bool svg = ext == ".svg";
  if (!svg && ext != ".png") throw InputError(path.string() + ": pictures are .png or .svg");
  if (mesh.quads.empty()) throw InputError(path.string() + ": the mesh has no quads to draw");
  if (options.width_px < 300 || options.width_px > 16000)
    throw InputError("picture width must be between 300 and 16000 pixels, got " + std::to_string(options.width_px));
  if (options.color == RenderColor::size_ratio && (!options.size_field || options.size_field->empty()))
    throw InputError(path.string() + ": colouring by size ratio needs a graded run's size field");
  return svg;
}

// The window: requested, or every quad node with a 2 % margin.
Box2 picture_window(const QuadMesh& mesh, const RenderOptions& options) {
  if (options.window) return *options.window;
  Box2 window;
  for (const auto& q : mesh.quads)
    for (std::int32_t v : q) window.add(mesh.nodes[static_cast<std::size_t>(v)]);
  const double m = 0.02 * std::max(window.hi.x - window.lo.x, window.hi.y - window.lo.y);
  window.lo = {window.lo.x - m, window.lo.y - m};
  window.hi = {window.hi.x + m, window.hi.y + m};
  return window;
}

struct PlotSize {
  double w = 0, h = 0;  ///< the plot's size in pixels
};

// The picture's size and the plane's scale on it (into `st`) for a window of wx by wy.
PlotSize lay_out_picture(RenderStats& st, int width_px, double wx, double wy) {
  PlotSize plot;
  plot.w = width_px - kColumn - 2 * kPad;
  st.scale = plot.w / wx;
  plot.h = wy * st.scale;
  if (plot.h + 2 * kPad > kMaxHeight) {
    st.scale = (kMaxHeight - 2 * kPad) / wy;
    plot.h = wy * st.scale;
    plot.w = wx * st.scale;
  }
  st.width_px = width_px;
  st.height_px = static_cast<int>(std::ceil(std::max(kMinHeight, plot.h + 2 * kPad)));
  st.plot_x0 = kPad;
  st.plot_y0 = (st.height_px - plot.h) / 2.0;
  return plot;
}

// Quads meeting the window.
std::vector<std::size_t> quads_in_window(const QuadMesh& mesh, const Box2& window) {
  std::vector<std::size_t> visible;
  for (std::size_t i = 0; i < mesh.quads.size(); ++i) {
    Box2 b;
    for (std::int32_t v : mesh.quads[i]) b.add(mesh.nodes[static_cast<std::size_t>(v)]);
    if (b.hi.x >= window.lo.x && b.lo.x <= window.hi.x && b.hi.y >= window.lo.y && b.lo.y <= window.hi.y)
      visible.push_back(i);
  }
  return visible;
}

// Level of detail from the median edge length on the picture.
double median_edge_px(const QuadMesh& mesh, const std::vector<std::size_t>& visible, double scale) {
  std::vector<double> edge_px;
  edge_px.reserve(visible.size());
  for (std::size_t i : visible)
    edge_px.push_back(distance(mesh.nodes[static_cast<std::size_t>(mesh.quads[i][0])],
                               mesh.nodes[static_cast<std::size_t>(mesh.quads[i][1])]) * scale);
  if (edge_px.empty()) return 0.0;
  std::nth_element(edge_px.begin(), edge_px.begin() + static_cast<std::ptrdiff_t>(edge_px.size() / 2), edge_px.end());
  return edge_px[edge_px.size() / 2];
}

// The range of the measure over the quads drawn, into `st`.
void measure_range(RenderStats& st, const std::vector<std::size_t>& visible, const std::vector<double>& values) {
  st.value_min = INFINITY;
  st.value_max = -INFINITY;
  for (std::size_t i : visible) {
    st.value_min = std::min(st.value_min, values[i]);
    st.value_max = std::max(st.value_max, values[i]);
  }
  if (visible.empty()) st.value_min = st.value_max = 0.0;
}

bool colored_by_measure(RenderColor color) {
  return color == RenderColor::sj || color == RenderColor::skew || color == RenderColor::size_ratio;
}

// Each quad's measure: its shape (sj, skew; also for the colourings by subregion and valence, which need none), or
// its size against the field.
std::vector<double> quad_values(const QuadMesh& mesh, const RenderOptions& options) {
  if (options.color == RenderColor::size_ratio) {
    std::vector<double> ratio(mesh.quads.size());
    for (std::size_t q = 0; q < ratio.size(); ++q) ratio[q] = quad_size_ratio(mesh, q, *options.size_field);
    return ratio;
  }
  QuadMetrics metrics = quad_metrics(mesh);
  return options.color == RenderColor::skew ? std::move(metrics.skew) : std::move(metrics.sj);
}

// Drawing on the plot: plane (x, y) at RenderStats' pixel position.
struct Canvas {
  cairo_t* cr;
  const QuadMesh& mesh;
  const RenderStats& st;

  std::pair<double, double> px(Vec2 p) const {
    return {st.plot_x0 + st.scale * (p.x - st.window.lo.x), st.plot_y0 + st.scale * (st.window.hi.y - p.y)};
  }
  Vec2 node(std::int32_t v) const { return mesh.nodes[static_cast<std::size_t>(v)]; }
  // Adds quad i's outline to the path.
  void quad_path(std::size_t i) const {
    const auto& q = mesh.quads[i];
    for (int k = 0; k < 4; ++k) {
      const auto [x, y] = px(node(q[static_cast<std::size_t>(k)]));
      k == 0 ? cairo_move_to(cr, x, y) : cairo_line_to(cr, x, y);
    }
    cairo_close_path(cr);
  }
  // Adds a polyline to the path (not closed).
  void line_path(const std::vector<Vec2>& points) const {
    for (std::size_t i = 0; i < points.size(); ++i) {
      const auto [x, y] = px(points[i]);
      i == 0 ? cairo_move_to(cr, x, y) : cairo_line_to(cr, x, y);
    }
  }
};

// Quads, one path per colour (256 levels of the colour bar, or the subregion colour): a million quads fill fast,
// and the SVG holds a few paths instead of one element per quad.
void fill_quads(const Canvas& c, const std::vector<std::size_t>& visible, const std::vector<double>& values,
                RenderColor color) {
  std::map<int, std::vector<std::size_t>> buckets;
  for (std::size_t i : visible) {
    int key = 0;
    if (colored_by_measure(color))
      key = static_cast<int>(std::lround(std::clamp(bar_position(color, values[i]), 0.0, 1.0) * 255.0));
    else if (color == RenderColor::part)
      key = c.mesh.quad_part.size() == c.mesh.quads.size() ? static_cast<int>((c.mesh.quad_part[i] % 12 + 12) % 12) : 0;
    buckets[key].push_back(i);
  }
  // Without edges drawn, antialiased fills would leave faint seams between neighbouring quads.
  if (!c.st.edges_drawn) cairo_set_antialias(c.cr, CAIRO_ANTIALIAS_NONE);
  for (const auto& [key, quads] : buckets) {
    for (std::size_t i : quads) c.quad_path(i);
    if (colored_by_measure(color))
      set(c.cr, bar_color(color, key / 255.0));
    else if (color == RenderColor::part)
      set(c.cr, kPalette[static_cast<std::size_t>(key)]);
    else
      set(c.cr, {0.88, 0.88, 0.88});
    cairo_fill(c.cr);
  }
  cairo_set_antialias(c.cr, CAIRO_ANTIALIAS_DEFAULT);
}

void stroke_quad_edges(const Canvas& c, const std::vector<std::size_t>& visible, double median_px) {
  for (std::size_t i : visible) c.quad_path(i);
  cairo_set_source_rgba(c.cr, 0.2, 0.2, 0.2, 0.8);
  cairo_set_line_width(c.cr, std::clamp(0.05 * median_px, 0.4, 1.2));
  cairo_stroke(c.cr);
}

// The input region, thin and dashed under the mesh's own curves (it differs where curves were simplified).
void draw_region(const Canvas& c, const Region& region) {
  const double dash = 4.0;
  cairo_set_dash(c.cr, &dash, 1, 0.0);
  cairo_set_line_width(c.cr, 0.8);
  for (const Ring& r : region.rings) {
    c.line_path(r.points);
    cairo_close_path(c.cr);
  }
  cairo_set_source_rgb(c.cr, 0.35, 0.35, 0.35);
  cairo_stroke(c.cr);
  for (const FeatureCurve& f : region.features) {
    c.line_path(f.points);
    if (f.closed) cairo_close_path(c.cr);
  }
  cairo_set_source_rgb(c.cr, 0.3, 0.6, 1.0);
  cairo_stroke(c.cr);
  cairo_set_dash(c.cr, nullptr, 0, 0.0);
}

void stroke_edges(const Canvas& c, const std::vector<std::array<std::int32_t, 2>>& edges, const Rgb& colour,
                  double width) {
  for (const auto& e : edges) {
    const auto [x0, y0] = c.px(c.node(e[0]));
    const auto [x1, y1] = c.px(c.node(e[1]));
    cairo_move_to(c.cr, x0, y0);
    cairo_line_to(c.cr, x1, y1);
  }
  set(c.cr, colour);
  cairo_set_line_width(c.cr, width);
  cairo_set_line_cap(c.cr, CAIRO_LINE_CAP_ROUND);
  cairo_stroke(c.cr);
}

// Boundary (black) and feature (blue) edges; a mesh read without tags gets its one-quad edges as boundary.
// Named boundary segments over the boundary: open ones magenta, other kinds orange.
void draw_boundary_and_features(const Canvas& c, const Region* region, const EdgeCounts& edge_quads) {
  std::vector<std::array<std::int32_t, 2>> derived_boundary;
  for (const auto& [key, count] : edge_quads)
    if (count == 1) derived_boundary.push_back({static_cast<std::int32_t>(key >> 32), static_cast<std::int32_t>(key & 0xffffffffu)});
  stroke_edges(c, c.mesh.boundary_edges.empty() ? derived_boundary : c.mesh.boundary_edges, {0, 0, 0}, 2.0);
  if (region)
    for (const BoundarySegment& b : region->boundary_segments) {
      c.line_path(b.line);
      set(c.cr, b.kind == "open" ? Rgb{1.0, 0.0, 1.0} : Rgb{1.0, 0.55, 0.0});
      cairo_set_line_width(c.cr, 3.0);
      cairo_stroke(c.cr);
    }
  stroke_edges(c, c.mesh.feature_edges, {0.0, 0.35, 0.95}, 2.0);
}

// Singular nodes by valence: filled discs inside, rings on the boundary. Where they are dense on the picture
// (a big mesh seen whole), the marks shrink so that they cover at most a tenth of the plot. Returns the marks
// by extra valence (-1, 1, 2 for two or more); sets st's mark radius and count.
std::map<int, std::size_t> mark_singular_nodes(const Canvas& c, RenderStats& st, const NodeValences& nv,
                                               double median_px, const PlotSize& plot) {
  const std::vector<int>& valence = nv.valence;
  const std::vector<std::uint8_t>& on_boundary = nv.on_boundary;
  std::vector<std::size_t> singular;
  for (std::size_t v = 0; v < c.mesh.nodes.size(); ++v) {
    if (valence[v] == 0 || valence[v] == (on_boundary[v] ? 3 : 4)) continue;
    const Vec2 p = c.mesh.nodes[v];
    if (p.x < st.window.lo.x || p.x > st.window.hi.x || p.y < st.window.lo.y || p.y > st.window.hi.y) continue;
    singular.push_back(v);
  }
  double radius = std::clamp(0.3 * median_px, 2.0, 6.0);
  if (!singular.empty())
    radius = std::max(1.0, std::min(radius, std::sqrt(0.1 * plot.w * plot.h / (M_PI * static_cast<double>(singular.size())))));
  st.mark_radius_px = radius;
  std::map<int, std::size_t> marked_by_extra;
  for (std::size_t v : singular) {
    const bool b = on_boundary[v] != 0;
    const int extra = valence[v] - (b ? 3 : 4);
    const auto [x, y] = c.px(c.mesh.nodes[v]);
    cairo_new_sub_path(c.cr);
    cairo_arc(c.cr, x, y, radius, 0, 2 * M_PI);
    set(c.cr, valence_color(valence[v], b));
    if (b) {
      cairo_set_line_width(c.cr, std::max(1.0, radius / 2.5));
      cairo_stroke(c.cr);
    } else {
      cairo_fill_preserve(c.cr);
      cairo_set_source_rgb(c.cr, 1, 1, 1);
      cairo_set_line_width(c.cr, 0.6);
      cairo_stroke(c.cr);
    }
    ++st.singular_nodes_marked;
    ++marked_by_extra[std::clamp(extra, -1, 2)];
  }
  return marked_by_extra;
}

// The colour bar of the measure at (lx, ly) with its scale and the range drawn (into st's bar); returns the y
// below it.
double draw_colour_bar(cairo_t* cr, RenderStats& st, RenderColor color, double lx, double ly) {
  text_within(cr, lx, ly, measure_name(color), st.width_px - kPad);
  const double top = ly + 10, height = 200, bar_w = 20;
  st.bar_x0 = lx;
  st.bar_y0 = top;
  st.bar_w = bar_w;
  st.bar_h = height;
  constexpr int slices = 100;
  for (int s = 0; s < slices; ++s) {  // position 0 at the bottom, 1 at the top
    set(cr, bar_color(color, (s + 0.5) / slices));
    cairo_rectangle(cr, lx, top + height * (1.0 - (s + 1.0) / slices), bar_w, height / slices + 0.5);
    cairo_fill(cr);
  }
  cairo_set_source_rgb(cr, 0, 0, 0);
  cairo_set_line_width(cr, 1.0);
  cairo_rectangle(cr, lx, top, bar_w, height);
  cairo_stroke(cr);
  for (int t = 0; t <= 4; ++t) {
    const double y = top + height * (1.0 - t / 4.0);
    cairo_move_to(cr, lx + bar_w, y);
    cairo_line_to(cr, lx + bar_w + 5, y);
    cairo_stroke(cr);
    text(cr, lx + bar_w + 8, y + 4, fixed(bar_value(color, t / 4.0), 2));
  }
  // The range drawn: a bracket beside the bar from the smallest to the largest value.
  const double ymin = top + height * (1.0 - std::clamp(bar_position(color, st.value_min), 0.0, 1.0));
  const double ymax = top + height * (1.0 - std::clamp(bar_position(color, st.value_max), 0.0, 1.0));
  cairo_move_to(cr, lx - 3, ymin);
  cairo_line_to(cr, lx - 7, ymin);
  cairo_line_to(cr, lx - 7, ymax);
  cairo_line_to(cr, lx - 3, ymax);
  cairo_set_line_width(cr, 1.5);
  cairo_stroke(cr);
  ly = top + height + 20;
  text(cr, lx, ly, "min " + fixed(st.value_min, 3));
  ly += 16;
  text(cr, lx, ly, "max " + fixed(st.value_max, 3));
  return ly + 28;
}

// The valence legend at (lx, ly) with the count of each kind of mark.
void draw_valence_legend(cairo_t* cr, const RenderStats& st, const std::map<int, std::size_t>& marked_by_extra,
                         double lx, double ly) {
  text(cr, lx, ly, "singular nodes");
  ly += 18;
  const std::array<std::pair<int, const char*>, 3> legend{{{-1, "valence 3 (boundary 2)"}, {1, "5 (boundary 4)"},
                                                           {2, "6+ (boundary 5+)"}}};
  for (const auto& [extra, label] : legend) {
    cairo_new_sub_path(cr);
    cairo_arc(cr, lx + 5, ly - 4, 5, 0, 2 * M_PI);
    set(cr, valence_color(4 + extra, false));
    cairo_fill(cr);
    cairo_set_source_rgb(cr, 0, 0, 0);
    const auto it = marked_by_extra.find(extra);
    text_within(cr, lx + 15, ly, std::string(label) + ": " + std::to_string(it == marked_by_extra.end() ? 0 : it->second),
                st.width_px - kPad);
    ly += 16;
  }
  text(cr, lx, ly, "(rings: boundary nodes)");
  ly += 16;
  if (!st.edges_drawn) text(cr, lx, ly, "(quad edges hidden)");
}

// The colour bar with its scale (sj, skew, size ratio) or the subregion count, then the valence legend.
void draw_legend_column(const Canvas& c, RenderStats& st, RenderColor color, const std::vector<std::size_t>& visible,
                        const std::map<int, std::size_t>& marked_by_extra) {
  cairo_t* cr = c.cr;
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, 12);
  const double lx = st.width_px - kColumn + 10;
  double ly = kPad + 16;
  cairo_set_source_rgb(cr, 0, 0, 0);
  if (colored_by_measure(color)) {
    ly = draw_colour_bar(cr, st, color, lx, ly);
  } else if (color == RenderColor::part) {
    int parts = 0;
    for (std::size_t i : visible)
      parts = std::max(parts, c.mesh.quad_part.size() == c.mesh.quads.size() ? c.mesh.quad_part[i] + 1 : 1);
    text(cr, lx, ly, "subregions: " + std::to_string(parts));
    ly += 28;
  }
  draw_valence_legend(cr, st, marked_by_extra, lx, ly);
}

// Ends the drawing: the PNG or SVG in `bytes` (the SVG surface streams into it), or a runtime_error naming `path`.
void finish_surface(cairo_surface_t* surface, std::string& bytes, bool svg, const std::filesystem::path& path) {
  cairo_status_t status = cairo_surface_status(surface);
  if (svg) {
    cairo_surface_finish(surface);  // flushes the SVG into `bytes`
    status = cairo_surface_status(surface);
  } else if (status == CAIRO_STATUS_SUCCESS) {
    status = cairo_surface_write_to_png_stream(surface, append_to_string, &bytes);
  }
  cairo_surface_destroy(surface);
  if (status != CAIRO_STATUS_SUCCESS)
    throw std::runtime_error(path.string() + ": drawing failed: " + cairo_status_to_string(status));
}

}  // namespace

RenderStats render_mesh(const std::filesystem::path& path, const QuadMesh& mesh, const Region* region,
                        const RenderOptions& options) {
  const bool svg = check_picture_request(path, mesh, options);
  RenderStats st;
  st.window = picture_window(mesh, options);
  const double wx = st.window.hi.x - st.window.lo.x, wy = st.window.hi.y - st.window.lo.y;
  if (!(wx > 0) || !(wy > 0)) throw InputError(path.string() + ": the picture window is empty");
  const PlotSize plot = lay_out_picture(st, options.width_px, wx, wy);

  const std::vector<std::size_t> visible = quads_in_window(mesh, st.window);
  st.quads_drawn = visible.size();
  if (svg && visible.size() > options.svg_max_quads)
    throw InputError(path.string() + ": " + std::to_string(visible.size()) + " quads are too many for an SVG (limit " +
                     std::to_string(options.svg_max_quads) + "); write a .png, or narrow the window");
  const double median_px = median_edge_px(mesh, visible, st.scale);
  st.edges_drawn = median_px >= options.min_edge_px;
  const std::vector<double> values = quad_values(mesh, options);
  measure_range(st, visible, values);

  std::string bytes;
  cairo_surface_t* surface =
      svg ? cairo_svg_surface_create_for_stream(append_to_string, &bytes, st.width_px, st.height_px)
          : cairo_image_surface_create(CAIRO_FORMAT_RGB24, st.width_px, st.height_px);
  cairo_t* cr = cairo_create(surface);
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_paint(cr);
  cairo_save(cr);
  cairo_rectangle(cr, st.plot_x0, st.plot_y0, plot.w, plot.h);
  cairo_clip(cr);
  const Canvas canvas{cr, mesh, st};
  fill_quads(canvas, visible, values, options.color);
  if (st.edges_drawn) stroke_quad_edges(canvas, visible, median_px);
  if (region) draw_region(canvas, *region);
  // Valence of every quad node and whether it is on the boundary (edges with one quad).
  const auto edge_quads = quad_edge_counts(mesh);
  const NodeValences nv = node_valences(mesh, edge_quads);
  draw_boundary_and_features(canvas, region, edge_quads);
  const std::map<int, std::size_t> marked_by_extra = mark_singular_nodes(canvas, st, nv, median_px, plot);
  cairo_restore(cr);
  draw_legend_column(canvas, st, options.color, visible, marked_by_extra);
  cairo_destroy(cr);

  finish_surface(surface, bytes, svg, path);
  write_file_atomically(path, [&](std::ostream& os) { os.write(bytes.data(), static_cast<std::streamsize>(bytes.size())); },
                        true);
  return st;
}

}  // namespace polysquare
