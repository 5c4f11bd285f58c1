#include "polysquare/io/render_size_field.h"

#include <cairo/cairo.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>
#include <string>

#include "polysquare/core/error.h"
#include "polysquare/io/atomic_file.h"

namespace polysquare {
namespace {

constexpr int kBarWidth = 160;  // pixels right of the plot: the colour bar and its labels

cairo_status_t append_bytes(void* closure, const unsigned char* data, unsigned int length) {
  static_cast<std::string*>(closure)->append(reinterpret_cast<const char*>(data), length);
  return CAIRO_STATUS_SUCCESS;
}

// Dark blue (t = 0) through teal and green to yellow (t = 1): readable in grey too (lightness grows with t).
std::array<double, 3> ramp(double t) {
  static const std::array<std::array<double, 3>, 4> stops{
      {{0.18, 0.09, 0.42}, {0.13, 0.45, 0.56}, {0.30, 0.73, 0.40}, {0.99, 0.91, 0.15}}};
  t = std::clamp(t, 0.0, 1.0) * 3.0;
  const int k = std::min(static_cast<int>(t), 2);
  const double f = t - k;
  std::array<double, 3> c{};
  for (int i = 0; i < 3; ++i) c[i] = stops[k][i] + f * (stops[k + 1][i] - stops[k][i]);
  return c;
}

std::string label(double v) {
  std::ostringstream os;
  os.precision(4);
  os << v;
  return os.str();
}

// The least and largest size over the cells inside the domain.
std::array<double, 2> inside_range(const SizeField& f, const std::vector<std::uint8_t>& inside) {
  std::array<double, 2> r{HUGE_VAL, -HUGE_VAL};
  for (std::size_t c = 0; c < inside.size(); ++c)
    if (inside[c]) r = {std::min(r[0], f.values()[c]), std::max(r[1], f.values()[c])};
  return r[0] <= r[1] ? r : std::array<double, 2>{1.0, 1.0};
}

void draw_bar(cairo_t* cr, int x0, int height, std::array<double, 2> range) {
  const int top = 40, bottom = height - 40, w = 24;
  for (int y = top; y < bottom; ++y) {
    const auto c = ramp(1.0 - static_cast<double>(y - top) / std::max(bottom - top - 1, 1));
    cairo_set_source_rgb(cr, c[0], c[1], c[2]);
    cairo_rectangle(cr, x0, y, w, 1);
    cairo_fill(cr);
  }
  cairo_set_source_rgb(cr, 0, 0, 0);
  cairo_set_font_size(cr, 14);
  cairo_move_to(cr, x0, top - 12);
  cairo_show_text(cr, "size (log scale)");
  cairo_move_to(cr, x0 + w + 6, top + 10);
  cairo_show_text(cr, label(range[1]).c_str());
  cairo_move_to(cr, x0 + w + 6, bottom);
  cairo_show_text(cr, label(range[0]).c_str());
}

}  // namespace

void render_size_field(const std::filesystem::path& path, const SizeField& field,
                       const std::vector<std::uint8_t>& inside, const Region& region, int width_px) {
  if (path.extension() != ".png") throw InputError(path.string() + ": the size picture is a .png");
  if (field.empty()) throw InputError(path.string() + ": no size field to draw");
  // The grid spans the region's box with a cell of margin; the plot keeps its aspect ratio.
  const double cell = field.cell();
  const Vec2 lo = field.origin() - Vec2{0.5 * cell, 0.5 * cell};
  const double wx = field.nx() * cell, wy = field.ny() * cell;
  const int plot_w = std::max(width_px - kBarWidth, 100);
  const double scale = plot_w / wx;
  const int plot_h = std::clamp(static_cast<int>(std::lround(wy * scale)), 100, 16000);
  cairo_surface_t* surface = cairo_image_surface_create(CAIRO_FORMAT_RGB24, plot_w + kBarWidth, plot_h);
  cairo_surface_flush(surface);
  unsigned char* data = cairo_image_surface_get_data(surface);
  const int stride = cairo_image_surface_get_stride(surface);
  const std::array<double, 2> range = inside_range(field, inside);
  const double span = std::log(range[1] / range[0]);
  for (int y = 0; y < plot_h; ++y) {
    auto* row = reinterpret_cast<std::uint32_t*>(data + static_cast<std::ptrdiff_t>(y) * stride);
    for (int x = 0; x < plot_w + kBarWidth; ++x) {
      const Vec2 p{lo.x + (x + 0.5) / scale, lo.y + wy - (y + 0.5) / scale};
      const int i = static_cast<int>(std::floor((p.x - lo.x) / cell)), j = static_cast<int>(std::floor((p.y - lo.y) / cell));
      const bool in = x < plot_w && i >= 0 && j >= 0 && i < field.nx() && j < field.ny() &&
                      inside[static_cast<std::size_t>(j) * field.nx() + i];
      const auto c = in ? ramp(span > 0 ? std::log(field.at(p) / range[0]) / span : 0.5) : std::array<double, 3>{1, 1, 1};
      row[x] = static_cast<std::uint32_t>(std::lround(255 * c[0])) << 16 |
               static_cast<std::uint32_t>(std::lround(255 * c[1])) << 8 | static_cast<std::uint32_t>(std::lround(255 * c[2]));
    }
  }
  cairo_surface_mark_dirty(surface);
  cairo_t* cr = cairo_create(surface);
  cairo_set_source_rgb(cr, 0, 0, 0);
  cairo_set_line_width(cr, 1.0);
  for (const Ring& ring : region.rings) {
    for (std::size_t k = 0; k <= ring.points.size(); ++k) {
      const Vec2 q = ring.points[k % ring.points.size()];
      const double px = (q.x - lo.x) * scale, py = (lo.y + wy - q.y) * scale;
      if (k == 0) cairo_move_to(cr, px, py);
      else cairo_line_to(cr, px, py);
    }
    cairo_stroke(cr);
  }
  draw_bar(cr, plot_w + 20, plot_h, range);
  cairo_destroy(cr);
  std::string bytes;
  const cairo_status_t status = cairo_surface_write_to_png_stream(surface, append_bytes, &bytes);
  cairo_surface_destroy(surface);
  if (status != CAIRO_STATUS_SUCCESS)
    throw std::runtime_error(path.string() + ": drawing failed: " + cairo_status_to_string(status));
  write_file_atomically(path, [&](std::ostream& os) { os << bytes; }, true);
}

}  // namespace polysquare
