// Pictures (render_mesh): colours where the quads are, the colour bar's scale, boundary edges, valence marks,
// the window, the level of detail, SVG only for small meshes, colours by size against a graded run's field, and
// the CLI's render command and mesh --picture.
#include <gtest/gtest.h>

#include <cairo/cairo.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <sys/wait.h>
#include <unistd.h>

#include "polysquare/core/error.h"
#include "polysquare/input/read_region.h"
#include "polysquare/io/render.h"
#include "polysquare/pipeline/mesh_region.h"
#include "polysquare/quality/quality.h"
#include "polysquare/size/size_conformity.h"
#include "polysquare/size/size_field.h"

namespace fs = std::filesystem;
using namespace polysquare;

namespace {

// A PNG read back through Cairo; pixel(x, y) as RGB in 0..255.
class Png {
 public:
  explicit Png(const fs::path& p) : s_(cairo_image_surface_create_from_png(p.c_str())) {}
  ~Png() { cairo_surface_destroy(s_); }
  bool ok() const { return cairo_surface_status(s_) == CAIRO_STATUS_SUCCESS; }
  int width() const { return cairo_image_surface_get_width(s_); }
  int height() const { return cairo_image_surface_get_height(s_); }
  std::array<int, 3> pixel(double x, double y) const {
    const unsigned char* data = cairo_image_surface_get_data(s_);
    const int stride = cairo_image_surface_get_stride(s_);
    const auto v = *reinterpret_cast<const std::uint32_t*>(data + static_cast<int>(y) * stride + 4 * static_cast<int>(x));
    return {static_cast<int>((v >> 16) & 0xff), static_cast<int>((v >> 8) & 0xff), static_cast<int>(v & 0xff)};
  }

 private:
  cairo_surface_t* s_;
};

std::array<double, 2> to_px(const RenderStats& st, Vec2 p) {
  return {st.plot_x0 + st.scale * (p.x - st.window.lo.x), st.plot_y0 + st.scale * (st.window.hi.y - p.y)};
}

void expect_color(const std::array<int, 3>& got, const std::array<double, 3>& want, int tol, const std::string& what) {
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(got[k], std::lround(want[k] * 255), tol) << what << " channel " << k;
}

// A unit square beside a sheared quad sharing its right edge (scaled Jacobian about 0.27).
QuadMesh square_and_sheared() {
  QuadMesh m;
  m.nodes = {{0, 0}, {1, 0}, {1, 1}, {0, 1}, {2, 3.5}, {2, 4.5}};
  m.quads = {{0, 1, 2, 3}, {1, 4, 5, 2}};
  m.boundary_edges = {{0, 1}, {1, 4}, {4, 5}, {5, 2}, {2, 3}, {3, 0}};
  m.boundary_edge_ring = {0, 0, 0, 0, 0, 0};
  return m;
}

// A triangle split into three quads: the centre is an interior node of valence 3, the corners boundary nodes
// of valence 2.
QuadMesh split_triangle() {
  QuadMesh m;
  const Vec2 a{0, 0}, b{6, 0}, c{3, 5.196};
  const Vec2 g{3, 1.732};
  m.nodes = {a, b, c, {3, 0}, {4.5, 2.598}, {1.5, 2.598}, g};
  m.quads = {{0, 3, 6, 5}, {3, 1, 4, 6}, {6, 4, 2, 5}};
  return m;
}

QuadMesh grid(int n) {
  QuadMesh m;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) m.nodes.push_back({static_cast<double>(i), static_cast<double>(j)});
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int v = j * (n + 1) + i;
      m.quads.push_back({v, v + 1, v + n + 2, v + n + 1});
    }
  return m;
}

// Squares of side 1, 2, 4 and 8 in a row, apart: against a field of h = 2 everywhere, size ratios 0.5, 1, 2, 4.
QuadMesh squares_of_sides_1_2_4_8() {
  QuadMesh m;
  double x = 0.0;
  for (double side : {1.0, 2.0, 4.0, 8.0}) {
    const auto base = static_cast<std::int32_t>(m.nodes.size());
    m.nodes.insert(m.nodes.end(), {{x, 0}, {x + side, 0}, {x + side, side}, {x, side}});
    m.quads.push_back({base, base + 1, base + 2, base + 3});
    x += side + 0.5;
  }
  return m;
}

class Render : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("polysquare_render_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

}  // namespace

TEST_F(Render, PngColoursEachQuadByItsMeasureWithBarAndBoundary) {
  const QuadMesh mesh = square_and_sheared();
  const QuadMetrics metrics = quad_metrics(mesh);
  ASSERT_GT(metrics.sj[0], 0.99);
  ASSERT_LT(metrics.sj[1], 0.3);
  RenderOptions ro;
  ro.width_px = 800;
  const RenderStats st = render_mesh(dir_ / "q.png", mesh, nullptr, ro);
  const Png png(dir_ / "q.png");
  ASSERT_TRUE(png.ok());
  EXPECT_EQ(png.width(), 800);
  EXPECT_EQ(png.height(), st.height_px);
  EXPECT_EQ(st.quads_drawn, 2u);
  EXPECT_TRUE(st.edges_drawn);
  EXPECT_NEAR(st.value_min, metrics.sj[1], 1e-12);
  // Inside each quad, the colour of its own scaled Jacobian: green for the square, red for the sheared one.
  const auto [gx, gy] = to_px(st, {0.5, 0.5});
  const auto [rx, ry] = to_px(st, {1.5, 2.25});
  const auto good = png.pixel(gx, gy), bad = png.pixel(rx, ry);
  expect_color(good, measure_color(RenderColor::sj, metrics.sj[0]), 4, "square");
  expect_color(bad, measure_color(RenderColor::sj, metrics.sj[1]), 4, "sheared");
  EXPECT_GT(good[1], good[0]);
  EXPECT_GT(bad[0], bad[1]);
  // The boundary is drawn black over the fill.
  const auto [bx, by] = to_px(st, {0.5, 0.0});
  for (int c : png.pixel(bx, by)) EXPECT_LT(c, 90);
  // Outside the mesh: white.
  const auto [wx, wy] = to_px(st, {0.2, 3.0});
  for (int c : png.pixel(wx, wy)) EXPECT_EQ(c, 255);
  // The colour bar: measure 0.1 near its bottom, 0.9 near its top, in the picture's colours.
  ASSERT_GT(st.bar_h, 0.0);
  const double bar_mid_x = st.bar_x0 + st.bar_w / 2;
  expect_color(png.pixel(bar_mid_x, st.bar_y0 + 0.9 * st.bar_h), measure_color(RenderColor::sj, 0.1), 8, "bar 0.1");
  expect_color(png.pixel(bar_mid_x, st.bar_y0 + 0.1 * st.bar_h), measure_color(RenderColor::sj, 0.9), 8, "bar 0.9");

  // Skew turns the scale around: the sheared quad is the bad one again, now as a high skew.
  RenderOptions skew = ro;
  skew.color = RenderColor::skew;
  const RenderStats ss = render_mesh(dir_ / "s.png", mesh, nullptr, skew);
  const Png sp(dir_ / "s.png");
  expect_color(sp.pixel(to_px(ss, {1.5, 2.25})[0], to_px(ss, {1.5, 2.25})[1]),
               measure_color(RenderColor::skew, metrics.skew[1]), 4, "skew sheared");
  EXPECT_GT(sp.pixel(to_px(ss, {1.5, 2.25})[0], to_px(ss, {1.5, 2.25})[1])[0],
            sp.pixel(to_px(ss, {0.5, 0.5})[0], to_px(ss, {0.5, 0.5})[1])[0]);
}

TEST_F(Render, SingularNodesAreMarkedByValence) {
  const QuadMesh mesh = split_triangle();
  RenderOptions ro;
  ro.width_px = 700;
  ro.color = RenderColor::singularities;
  const RenderStats st = render_mesh(dir_ / "v.png", mesh, nullptr, ro);
  // The same nodes the quality report counts: three corners of valence 2 and the centre of valence 3.
  EXPECT_EQ(st.singular_nodes_marked, compute_quality(mesh).singularities);
  EXPECT_EQ(st.singular_nodes_marked, 4u);
  const Png png(dir_ / "v.png");
  const auto [cx, cy] = to_px(st, mesh.nodes[6]);
  expect_color(png.pixel(cx, cy), valence_color(3, false), 6, "valence-3 centre");
  // Corners (boundary, valence 2) get a ring: a point on it is blue; the same offset from a side's midpoint
  // (boundary, valence 3, regular) shows the quads' plain grey.
  const double d = st.mark_radius_px / std::sqrt(2.0);
  ASSERT_GE(d, 2.0);
  const auto [ax, ay] = to_px(st, mesh.nodes[0]);
  expect_color(png.pixel(ax + d, ay - d), valence_color(2, true), 40, "ring at a corner");
  const auto [mx, my] = to_px(st, mesh.nodes[3]);
  expect_color(png.pixel(mx + d, my - d), {0.88, 0.88, 0.88}, 6, "beside a regular boundary node");
  EXPECT_EQ(st.bar_h, 0.0);
}

TEST_F(Render, LegendWithLargeCountsStaysInsideThePicture) {
  // 40,000 valence marks of one kind (delta_box has 5,600): "valence 3 (boundary 2): 40000" is wider than the
  // legend column at the normal font and ran past the picture's right edge.
  QuadMesh mesh;
  const QuadMesh one = split_triangle();
  for (int k = 0; k < 10000; ++k) {
    const auto base = static_cast<std::int32_t>(mesh.nodes.size());
    const Vec2 shift{7.0 * (k % 100), 6.0 * (k / 100)};
    for (const Vec2& p : one.nodes) mesh.nodes.push_back({p.x + shift.x, p.y + shift.y});
    for (auto q : one.quads) {
      for (auto& v : q) v += base;
      mesh.quads.push_back(q);
    }
  }
  RenderOptions ro;
  ro.width_px = 400;
  ro.color = RenderColor::singularities;
  const RenderStats st = render_mesh(dir_ / "l.png", mesh, nullptr, ro);
  EXPECT_EQ(st.singular_nodes_marked, 40000u);
  const Png png(dir_ / "l.png");
  ASSERT_TRUE(png.ok());
  // The legend lies right of the plot; its last 5 px columns (the margin) stay white on every row, while the
  // legend itself writes dark text into the column.
  int margin_marked = 0, legend_dark = 0;
  for (int y = 0; y < png.height(); ++y) {
    for (int x = png.width() - 5; x < png.width(); ++x)
      if (png.pixel(x, y)[0] < 250) ++margin_marked;
    for (int x = static_cast<int>(st.plot_x0 + st.scale * (st.window.hi.x - st.window.lo.x)) + 20; x < png.width() - 5; ++x)
      if (png.pixel(x, y)[0] < 100 && png.pixel(x, y)[2] < 100) ++legend_dark;
  }
  EXPECT_EQ(margin_marked, 0);
  EXPECT_GT(legend_dark, 100);
}

TEST_F(Render, WindowShowsOnlyItsPart) {
  const QuadMesh mesh = square_and_sheared();
  RenderOptions ro;
  ro.width_px = 600;
  ro.window = parse_window("0.1,0.1,0.9,0.9");
  const RenderStats st = render_mesh(dir_ / "w.png", mesh, nullptr, ro);
  EXPECT_EQ(st.quads_drawn, 1u);
  EXPECT_NEAR(st.scale * 0.8, 600 - 190 - 20, 1e-9);
  const Png png(dir_ / "w.png");
  // The window's corners are inside the square, so the whole plot is its colour.
  const std::array<double, 3> want = measure_color(RenderColor::sj, 1.0);
  for (const Vec2 p : {Vec2{0.12, 0.12}, Vec2{0.88, 0.5}, Vec2{0.5, 0.88}})
    expect_color(png.pixel(to_px(st, p)[0], to_px(st, p)[1]), want, 4, "inside the window");
  EXPECT_THROW(parse_window("1,2,3"), InputError);
  EXPECT_THROW(parse_window("0,0,0,1"), InputError);
  EXPECT_THROW(parse_window("0,0,1,nan"), InputError);
}

TEST_F(Render, BigMeshesHideQuadEdgesWithoutSeams) {
  const QuadMesh big = grid(300);  // 90,000 unit squares on 400 px: a third of a pixel each
  RenderOptions ro;
  ro.width_px = 600;
  const RenderStats st = render_mesh(dir_ / "big.png", big, nullptr, ro);
  EXPECT_FALSE(st.edges_drawn);
  EXPECT_EQ(st.quads_drawn, 90000u);
  const Png png(dir_ / "big.png");
  // Every pixel well inside the mesh has exactly the fill colour: no edge lines, no seams between fills.
  const std::array<double, 3> want = measure_color(RenderColor::sj, 1.0);
  std::size_t off = 0, total = 0;
  for (double y = 10; y < 290; y += 3.7)
    for (double x = 10; x < 290; x += 3.3) {
      const auto p = png.pixel(to_px(st, {x, y})[0], to_px(st, {x, y})[1]);
      ++total;
      for (int k = 0; k < 3; ++k) off += std::abs(p[k] - std::lround(want[k] * 255)) > 2 ? 1 : 0;
    }
  EXPECT_GT(total, 1000u);
  EXPECT_EQ(off, 0u);
  // The same mesh seen through a window of 10 x 10 squares shows its edges.
  ro.window = parse_window("100,100,110,110");
  EXPECT_TRUE(render_mesh(dir_ / "zoom.png", big, nullptr, ro).edges_drawn);
}

TEST_F(Render, SvgOnlyForSmallMeshes) {
  const RenderStats st = render_mesh(dir_ / "q.svg", square_and_sheared());
  std::ifstream in(dir_ / "q.svg");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("<svg"), std::string::npos);
  EXPECT_NE(text.find("width=\"" + std::to_string(st.width_px)), std::string::npos);
  RenderOptions ro;
  ro.svg_max_quads = 1000;
  EXPECT_THROW(render_mesh(dir_ / "big.svg", grid(40), nullptr, ro), InputError);
  EXPECT_FALSE(fs::exists(dir_ / "big.svg"));
  EXPECT_THROW(render_mesh(dir_ / "q.jpg", square_and_sheared()), InputError);
}

TEST_F(Render, CliRenderAndMeshPicture) {
  auto run = [&](const std::string& args) {
    const std::string cmd = std::string(POLYSQUARE_CLI) + " " + args + " > /dev/null 2> " + (dir_ / "err").string();
    return WEXITSTATUS(std::system(cmd.c_str()));
  };
  const std::string msh = (dir_ / "m.msh").string();
  ASSERT_EQ(run("mesh " + std::string(POLYSQUARE_DATA_DIR) + "/cases/letter_I.geojson --size 2 -o " + msh +
                " --picture " + (dir_ / "m.png").string()),
            0);
  EXPECT_TRUE(Png(dir_ / "m.png").ok());
  EXPECT_EQ(Png(dir_ / "m.png").width(), 1600);
  ASSERT_EQ(run("render " + msh + " -o " + (dir_ / "p.png").string() + " --color part --width 500"), 0);
  const Png p(dir_ / "p.png");
  ASSERT_TRUE(p.ok());
  EXPECT_EQ(p.width(), 500);
  EXPECT_EQ(run("render " + msh + " -o " + (dir_ / "s.svg").string() + " --color singularities"), 0);
  EXPECT_GT(fs::file_size(dir_ / "s.svg"), 1000u);
  EXPECT_EQ(run("render " + msh + " -o " + (dir_ / "x.png").string() + " --color bogus"), 2);
  EXPECT_EQ(run("render " + msh + " -o " + (dir_ / "x.png").string() + " --window 1,2,3"), 2);
  EXPECT_EQ(run("render " + msh + " -o " + (dir_ / "x.gif").string()), 2);
  EXPECT_FALSE(fs::exists(dir_ / "x.png"));
}

TEST_F(Render, SizeRatioColoursQuadsOnADivergingLogScale) {
  const QuadMesh mesh = squares_of_sides_1_2_4_8();
  const SizeField field({0, 0}, 10.0, 2, 2, {2.0, 2.0, 2.0, 2.0});
  const std::array<double, 4> ratio{0.5, 1.0, 2.0, 4.0};
  for (std::size_t q = 0; q < 4; ++q) ASSERT_NEAR(quad_size_ratio(mesh, q, field), ratio[q], 1e-12);
  RenderOptions ro;
  ro.width_px = 800;
  ro.color = RenderColor::size_ratio;
  ro.size_field = &field;
  const RenderStats st = render_mesh(dir_ / "r.png", mesh, nullptr, ro);
  const Png png(dir_ / "r.png");
  ASSERT_TRUE(png.ok());
  EXPECT_EQ(png.width(), 800);
  EXPECT_EQ(png.height(), st.height_px);
  EXPECT_DOUBLE_EQ(st.value_min, 0.5);
  EXPECT_DOUBLE_EQ(st.value_max, 4.0);
  std::array<std::array<int, 3>, 4> centre;
  for (std::size_t q = 0; q < 4; ++q) {
    const double side = mesh.nodes[static_cast<std::size_t>(mesh.quads[q][1])].x -
                        mesh.nodes[static_cast<std::size_t>(mesh.quads[q][0])].x;
    const auto [x, y] = to_px(st, mesh.nodes[static_cast<std::size_t>(mesh.quads[q][0])] + Vec2{side / 2, side / 2});
    centre[q] = png.pixel(x, y);
    expect_color(centre[q], measure_color(RenderColor::size_ratio, ratio[q]), 4, "ratio " + std::to_string(ratio[q]));
  }
  // Twice too small blue, on target pale green (not the white background), twice too large red, and four times
  // as red as twice: the scale ends at 2.
  EXPECT_GT(centre[0][2], centre[0][0] + 80);
  EXPECT_GT(centre[1][1], centre[1][0]);
  EXPECT_GT(centre[1][1], centre[1][2]);
  EXPECT_LT(centre[1][0], 235);
  EXPECT_GT(centre[2][0], centre[2][2] + 80);
  EXPECT_EQ(centre[3], centre[2]);
  // The colour bar: ratio 1 at its middle, 2^-0.8 near its bottom, 2^0.8 near its top.
  ASSERT_GT(st.bar_h, 0.0);
  const double bx = st.bar_x0 + st.bar_w / 2;
  expect_color(png.pixel(bx, st.bar_y0 + 0.5 * st.bar_h), measure_color(RenderColor::size_ratio, 1.0), 8, "bar 1");
  expect_color(png.pixel(bx, st.bar_y0 + 0.9 * st.bar_h), measure_color(RenderColor::size_ratio, std::exp2(-0.8)), 8,
               "bar 0.57");
  expect_color(png.pixel(bx, st.bar_y0 + 0.1 * st.bar_h), measure_color(RenderColor::size_ratio, std::exp2(0.8)), 8,
               "bar 1.74");
  EXPECT_EQ(parse_render_color("size"), RenderColor::size_ratio);
  // Without a field there is nothing to measure the size against: refused, nothing written.
  ro.size_field = nullptr;
  EXPECT_THROW(render_mesh(dir_ / "none.png", mesh, nullptr, ro), InputError);
  const SizeField empty;
  ro.size_field = &empty;
  EXPECT_THROW(render_mesh(dir_ / "none.png", mesh, nullptr, ro), InputError);
  EXPECT_FALSE(fs::exists(dir_ / "none.png"));
}

// A graded mesh of a small case (the dam channel, 2-10 m) coloured by its field: each quad's pixel has the colour
// of its own size ratio, the same figure the report's size conformity summarises.
TEST_F(Render, GradedMeshColouredBySizeRatio) {
  const Region region = read_region(std::string(POLYSQUARE_DATA_DIR) + "/cases/dam_channel.geojson");
  MeshOptions options;
  options.size.field.size_min = 2.0;
  options.size.field.size_max = 10.0;
  const MeshResult r = mesh_region(region, options);
  const SizeField field = make_size_field(region, options.size.field).field;
  RenderOptions ro;
  ro.width_px = 1000;
  ro.color = RenderColor::size_ratio;
  ro.size_field = &field;
  const RenderStats st = render_mesh(dir_ / "g.png", r.mesh, nullptr, ro);
  const Png png(dir_ / "g.png");
  ASSERT_TRUE(png.ok());
  EXPECT_EQ(png.width(), 1000);
  EXPECT_EQ(png.height(), st.height_px);
  EXPECT_EQ(st.quads_drawn, r.mesh.quads.size());
  // The quads with the least and the largest ratio among those big enough on the picture that their centre is
  // clear of edges and valence marks.
  const QuadMetrics metrics = quad_metrics(r.mesh);
  std::vector<std::size_t> big;
  for (std::size_t q = 0; q < r.mesh.quads.size(); ++q)
    if (quad_size(r.mesh, q) * st.scale > 40.0 && metrics.sj[q] > 0.8) big.push_back(q);
  ASSERT_GE(big.size(), 10u);
  const auto by_ratio = [&](std::size_t a, std::size_t b) {
    return quad_size_ratio(r.mesh, a, field) < quad_size_ratio(r.mesh, b, field);
  };
  const std::size_t lo = *std::min_element(big.begin(), big.end(), by_ratio);
  const std::size_t hi = *std::max_element(big.begin(), big.end(), by_ratio);
  // Far enough apart on the scale that the two colours tell them apart (a picture coloured by anything else fails).
  const auto lo_colour = measure_color(RenderColor::size_ratio, quad_size_ratio(r.mesh, lo, field));
  const auto hi_colour = measure_color(RenderColor::size_ratio, quad_size_ratio(r.mesh, hi, field));
  ASSERT_GT(std::abs(lo_colour[0] - hi_colour[0]) + std::abs(lo_colour[2] - hi_colour[2]), 0.1);
  for (std::size_t q : {lo, hi, big[big.size() / 2]}) {
    Vec2 c{0, 0};
    for (std::int32_t v : r.mesh.quads[q]) c = c + 0.25 * r.mesh.nodes[static_cast<std::size_t>(v)];
    const auto [x, y] = to_px(st, c);
    expect_color(png.pixel(x, y), measure_color(RenderColor::size_ratio, quad_size_ratio(r.mesh, q, field)), 4,
                 "quad " + std::to_string(q));
  }
}

// --picture-color size: a graded run's picture by size ratio; a uniform run has no field to colour by: exit 2
// naming the flag, before meshing, nothing written.
TEST_F(Render, CliPictureColorSizeNeedsAGradedRun) {
  auto run = [&](const std::string& args) {
    const std::string cmd = std::string(POLYSQUARE_CLI) + " " + args + " > /dev/null 2> " + (dir_ / "err").string();
    return WEXITSTATUS(std::system(cmd.c_str()));
  };
  auto err = [&] {
    std::ifstream in(dir_ / "err");
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  };
  const std::string in = std::string(POLYSQUARE_DATA_DIR) + "/cases/dam_channel.geojson";
  ASSERT_EQ(run("mesh " + in + " --size-min 2 --size-max 10 -o " + (dir_ / "g.msh").string() + " --picture " +
                (dir_ / "g.png").string() + " --picture-color size"),
            0)
      << err();
  const Png g(dir_ / "g.png");
  ASSERT_TRUE(g.ok());
  EXPECT_EQ(g.width(), 1600);
  EXPECT_EQ(run("mesh " + in + " --size 4 -o " + (dir_ / "u.msh").string() + " --picture " + (dir_ / "u.png").string() +
                " --picture-color size"),
            2);
  // One line, the error: refused before reading and meshing, which would say more first.
  const std::string e = err();
  EXPECT_EQ(e.rfind("error: ", 0), 0u) << e;
  EXPECT_NE(e.find("--picture-color"), std::string::npos) << e;
  EXPECT_EQ(std::count(e.begin(), e.end(), '\n'), 1) << e;
  EXPECT_FALSE(fs::exists(dir_ / "u.png"));
  EXPECT_FALSE(fs::exists(dir_ / "u.msh"));
  // Without --picture there is nothing to colour; a colour not in the list is refused by name.
  EXPECT_EQ(run("mesh " + in + " --size 4 -o " + (dir_ / "u.msh").string() + " --picture-color sj"), 2);
  EXPECT_EQ(run("mesh " + in + " --size 4 -o " + (dir_ / "u.msh").string() + " --picture " +
                (dir_ / "u.png").string() + " --picture-color bogus"),
            2);
  EXPECT_FALSE(fs::exists(dir_ / "u.msh"));
}
