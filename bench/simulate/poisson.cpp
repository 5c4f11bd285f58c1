// A manufactured-solution Poisson problem on a 2D MSH mesh (issue 54): -laplace(u) = f with the exact solution
// u = sin(k x') sin(k y'), x' = (x - x0) / L and y' = (y - y0) / L over the case's bounding box (lower-left corner
// (x0, y0), larger side L), so k = 6 pi puts three wavelengths across the part. u exact on the whole boundary
// (Dirichlet). Feature curves need nothing here: u is smooth across them, so they matter only as the interior mesh
// edges every generator must follow, which is how they shape the mesh the error is measured on.
// Quads use FE_Q, triangles FE_SimplexP (hp collections when a mesh holds both); CG + SSOR.
//
// usage: poisson MESH.msh [--region REGION.geojson | --box X0 Y0 L] [--k K] [--degree P] [--tolerance TOL]
//                [--max-cg N] [--count] [--json FILE.json]
// The box comes from --region (the bounding box of every coordinate of the GeoJSON: the same exact solution for
// every mesh of a case, whatever each generator does to the boundary), --box, or else the mesh's own vertices.
// --count reads the mesh and prints cells and DoFs only (for searching sizes). The last line printed is a JSON
// object with every figure: cells, dofs, l2, h1 (seminorm), cg_iterations, the cells with the largest local errors
// (centre, share of the error squared, scaled Jacobian, edge ratio, irregular vertices), the mesh's worst shapes
// (per cell kind) and the spread of its cell areas (percentiles over the mean).
// Exit status 1 when CG does not reach the tolerance in --max-cg iterations, 2 on bad input.
#include <deal.II/base/function.h>
#include <deal.II/dofs/dof_tools.h>
#include <deal.II/fe/fe_values.h>
#include <deal.II/grid/grid_tools.h>
#include <deal.II/hp/fe_values.h>
#include <deal.II/lac/dynamic_sparsity_pattern.h>
#include <deal.II/lac/full_matrix.h>
#include <deal.II/lac/precondition.h>
#include <deal.II/lac/solver_cg.h>
#include <deal.II/lac/solver_control.h>
#include <deal.II/lac/sparse_matrix.h>
#include <deal.II/lac/sparsity_pattern.h>
#include <deal.II/lac/vector.h>
#include <deal.II/numerics/matrix_tools.h>
#include <deal.II/numerics/vector_tools.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <iostream>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "discretisation.h"

using namespace dealii;
using simulate::Discretisation;
using simulate::fail;

namespace {

struct Options {
  std::string mesh, region, json_out;
  bool have_box = false, count_only = false;
  double x0 = 0, y0 = 0, length = 1;
  double k = 6 * numbers::PI, tolerance = 1e-12;
  unsigned degree = 1, max_cg = 10000;
};

// The bounding box of every coordinate in a GeoJSON file (domain and features alike).
void box_from_region(Options& o) {
  std::ifstream in(o.region);
  if (!in) fail("cannot read " + o.region);
  const auto doc = nlohmann::json::parse(in);
  double lo[2] = {std::numeric_limits<double>::max(), std::numeric_limits<double>::max()};
  double hi[2] = {std::numeric_limits<double>::lowest(), std::numeric_limits<double>::lowest()};
  auto walk = [&](const nlohmann::json& c, const auto& self) -> void {
    if (c.is_array() && !c.empty() && c[0].is_number()) {
      for (int i = 0; i < 2; ++i) lo[i] = std::min(lo[i], c[i].get<double>()), hi[i] = std::max(hi[i], c[i].get<double>());
    } else if (c.is_array())
      for (const auto& e : c) self(e, self);
  };
  for (const auto& f : doc.at("features")) walk(f.at("geometry").at("coordinates"), walk);
  if (lo[0] > hi[0]) fail(o.region + " has no coordinates");
  o.x0 = lo[0], o.y0 = lo[1], o.length = std::max(hi[0] - lo[0], hi[1] - lo[1]), o.have_box = true;
}

Options parse(int argc, char** argv) {
  Options o;
  const simulate::Need need{argc, argv};
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--k") need(i, 1), o.k = std::stod(argv[++i]);
    else if (a == "--region") need(i, 1), o.region = argv[++i];
    else if (a == "--box") {
      need(i, 3);
      o.x0 = std::stod(argv[i + 1]), o.y0 = std::stod(argv[i + 2]), o.length = std::stod(argv[i + 3]);
      o.have_box = true, i += 3;
    } else if (a == "--degree") need(i, 1), o.degree = std::stoul(argv[++i]);
    else if (a == "--tolerance") need(i, 1), o.tolerance = std::stod(argv[++i]);
    else if (a == "--max-cg") need(i, 1), o.max_cg = std::stoul(argv[++i]);
    else if (a == "--json") need(i, 1), o.json_out = argv[++i];
    else if (a == "--count") o.count_only = true;
    else if (!a.empty() && a[0] == '-') fail("unknown option " + a);
    else if (o.mesh.empty()) o.mesh = a;
    else fail("one mesh only");
  }
  if (o.mesh.empty()) fail("usage: poisson MESH.msh [--region REGION.geojson | --box X0 Y0 L] [options]; see poisson.cpp");
  if (!o.have_box && !o.region.empty()) box_from_region(o);
  if (o.length <= 0) fail("the box's side must be positive");
  return o;
}

// u = sin(k x') sin(k y') and its gradient; f = -laplace(u) = 2 (k / L)^2 u.
class Exact : public Function<2> {
 public:
  Exact(const Options& o) : o_(o), s_(o.k / o.length) {}
  double value(const Point<2>& p, unsigned = 0) const override {
    return std::sin(s_ * (p[0] - o_.x0)) * std::sin(s_ * (p[1] - o_.y0));
  }
  Tensor<1, 2> gradient(const Point<2>& p, unsigned = 0) const override {
    const double a = s_ * (p[0] - o_.x0), b = s_ * (p[1] - o_.y0);
    Tensor<1, 2> g;
    g[0] = s_ * std::cos(a) * std::sin(b), g[1] = s_ * std::sin(a) * std::cos(b);
    return g;
  }
  double source(const Point<2>& p) const { return 2 * s_ * s_ * value(p); }

 private:
  const Options& o_;
  double s_;
};

// A cell's corners counter-clockwise (deal.II numbers a quad's vertices lexicographically: 0 1 / 2 3).
std::vector<Point<2>> corners(const Triangulation<2>::active_cell_iterator& cell) {
  if (cell->n_vertices() == 3) return {cell->vertex(0), cell->vertex(1), cell->vertex(2)};
  return {cell->vertex(0), cell->vertex(1), cell->vertex(3), cell->vertex(2)};
}

// Scaled Jacobian (the smallest corner's sine between its two edges; 1 for a square, and for a triangle
// sqrt(3) / 2 at best) and edge ratio (longest over shortest edge).
std::pair<double, double> shape(const Triangulation<2>::active_cell_iterator& cell) {
  const auto c = corners(cell);
  const std::size_t n = c.size();
  double sj = std::numeric_limits<double>::max(), shortest = sj, longest = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const Tensor<1, 2> next = c[(i + 1) % n] - c[i], prev = c[(i + n - 1) % n] - c[i];
    sj = std::min(sj, (next[0] * prev[1] - next[1] * prev[0]) / (next.norm() * prev.norm()));
    shortest = std::min(shortest, next.norm()), longest = std::max(longest, next.norm());
  }
  return {sj, longest / shortest};
}

}  // namespace

int main(int argc, char** argv) {
  simulate::program = "poisson";
  Options o = parse(argc, argv);
  Discretisation d(o.mesh, o.degree);
  const unsigned n = d.dofs.n_dofs();
  nlohmann::json out;
  out["mesh"] = o.mesh;
  out["quads"] = d.quads;
  out["triangles"] = d.triangles;
  out["cells"] = d.tria.n_active_cells();
  out["dofs"] = n;
  out["degree"] = o.degree;
  if (o.count_only) {
    std::cout << out.dump() << "\n";
    return 0;
  }
  if (!o.have_box) {  // no case given: the mesh's own box (then each mesh of a case has its own exact solution)
    const auto box = GridTools::compute_bounding_box(d.tria);
    o.x0 = box.lower_bound(0), o.y0 = box.lower_bound(1);
    o.length = std::max(box.side_length(0), box.side_length(1));
  }
  const Exact exact(o);

  // Stiffness matrix and load vector.
  DynamicSparsityPattern dsp(n);
  DoFTools::make_sparsity_pattern(d.dofs, dsp);
  SparsityPattern pattern;
  pattern.copy_from(dsp);
  SparseMatrix<double> matrix(pattern);
  Vector<double> u(n), rhs(n);
  {
    hp::FEValues<2> hp_fv(d.mapping, d.fe, d.assembly_quadrature,
                          update_values | update_gradients | update_quadrature_points | update_JxW_values);
    FullMatrix<double> a;
    Vector<double> b;
    std::vector<types::global_dof_index> idx;
    for (const auto& cell : d.dofs.active_cell_iterators()) {
      hp_fv.reinit(cell);
      const FEValues<2>& fv = hp_fv.get_present_fe_values();
      const unsigned m = cell->get_fe().n_dofs_per_cell();
      a.reinit(m, m), b.reinit(m);
      for (unsigned q = 0; q < fv.n_quadrature_points; ++q) {
        const double f = exact.source(fv.quadrature_point(q));
        for (unsigned i = 0; i < m; ++i) {
          for (unsigned j = 0; j < m; ++j) a(i, j) += fv.shape_grad(i, q) * fv.shape_grad(j, q) * fv.JxW(q);
          b(i) += fv.shape_value(i, q) * f * fv.JxW(q);
        }
      }
      idx.resize(m);
      cell->get_dof_indices(idx);
      matrix.add(idx, a);
      for (unsigned i = 0; i < m; ++i) rhs(idx[i]) += b(i);
    }
  }

  // u exact on every boundary, whatever its id (polysquare tags curves, Gmsh's surface-only files tag none).
  std::map<types::global_dof_index, double> fixed;
  {
    std::map<types::boundary_id, const Function<2>*> functions;
    for (const auto id : d.tria.get_boundary_ids()) functions[id] = &exact;
    VectorTools::interpolate_boundary_values(d.mapping, d.dofs, functions, fixed);
  }
  MatrixTools::apply_boundary_values(fixed, matrix, u, rhs);

  SolverControl control(o.max_cg, o.tolerance * rhs.l2_norm(), false, false);
  SolverCG<Vector<double>> cg(control);
  PreconditionSSOR<SparseMatrix<double>> ssor;
  ssor.initialize(matrix, 1.2);
  try {
    cg.solve(matrix, u, rhs, ssor);
  } catch (const SolverControl::NoConvergence& e) {
    std::cerr << "poisson: CG did not reach the tolerance in " << o.max_cg << " iterations (residual "
              << e.last_residual << ")\n";
    return 1;
  }

  // Errors against u, cell by cell, so the cells holding the most of them can be named.
  hp::FEValues<2> hp_fv(d.mapping, d.fe, d.error_quadrature,
                        update_values | update_gradients | update_quadrature_points | update_JxW_values);
  const unsigned cells = d.tria.n_active_cells();
  std::vector<double> cell_l2(cells, 0.0), cell_h1(cells, 0.0);
  double l2 = 0, h1 = 0, u_l2 = 0, u_h1 = 0, area = 0;
  std::vector<double> values;
  std::vector<Tensor<1, 2>> gradients;
  for (const auto& cell : d.dofs.active_cell_iterators()) {
    hp_fv.reinit(cell);
    const FEValues<2>& fv = hp_fv.get_present_fe_values();
    values.resize(fv.n_quadrature_points), gradients.resize(fv.n_quadrature_points);
    fv.get_function_values(u, values);
    fv.get_function_gradients(u, gradients);
    const unsigned c = cell->active_cell_index();
    for (unsigned q = 0; q < fv.n_quadrature_points; ++q) {
      const Point<2>& p = fv.quadrature_point(q);
      const double v = exact.value(p);
      const Tensor<1, 2> g = exact.gradient(p);
      cell_l2[c] += std::pow(values[q] - v, 2) * fv.JxW(q);
      cell_h1[c] += (gradients[q] - g).norm_square() * fv.JxW(q);
      u_l2 += v * v * fv.JxW(q), u_h1 += g.norm_square() * fv.JxW(q), area += fv.JxW(q);
    }
    l2 += cell_l2[c], h1 += cell_h1[c];
  }

  // The mesh's shapes, and which interior vertices are irregular (not 4 quads, or a triangle's corner): the
  // places a semi-structured mesh is meant to have few of.
  std::vector<unsigned> valence(d.tria.n_vertices(), 0);
  std::vector<bool> on_boundary(d.tria.n_vertices(), false), near_triangle(d.tria.n_vertices(), false);
  for (const auto& cell : d.tria.active_cell_iterators()) {
    for (unsigned v = 0; v < cell->n_vertices(); ++v) {
      ++valence[cell->vertex_index(v)];
      if (cell->n_vertices() == 3) near_triangle[cell->vertex_index(v)] = true;
    }
    for (unsigned f = 0; f < cell->n_faces(); ++f)
      if (cell->at_boundary(f))
        for (unsigned v = 0; v < 2; ++v) on_boundary[cell->face(f)->vertex_index(v)] = true;
  }
  auto irregular = [&](unsigned v) { return !on_boundary[v] && (valence[v] != 4 || near_triangle[v]); };
  // Shapes by cell kind (index 0 quads, 1 triangles): a quad mesh's few leftover triangles are no quad's shape.
  std::array<double, 2> sj_min{2, 2}, ratio_max{0, 0};
  for (const auto& cell : d.tria.active_cell_iterators()) {
    const auto [sj, ratio] = shape(cell);
    const unsigned kind = cell->n_vertices() == 3;
    sj_min[kind] = std::min(sj_min[kind], sj), ratio_max[kind] = std::max(ratio_max[kind], ratio);
  }
  // How far cell sizes spread: a mesh whose cells are much larger than its mean in places has its error there.
  std::vector<double> areas;
  for (const auto& cell : d.tria.active_cell_iterators()) areas.push_back(cell->measure() * cells / area);
  std::sort(areas.begin(), areas.end());
  auto percentile = [&](double p) { return areas[std::min<std::size_t>(areas.size() - 1, p * areas.size())]; };
  unsigned irregular_vertices = 0;
  for (unsigned v = 0; v < d.tria.n_vertices(); ++v) irregular_vertices += valence[v] > 0 && irregular(v);

  // The cells with the largest local L2 and H1 errors: where they are, their shapes and their irregular corners.
  auto describe = [&](const std::vector<double>& local, double total) {
    nlohmann::json worst = nlohmann::json::array();
    std::vector<unsigned> order(cells);
    for (unsigned c = 0; c < cells; ++c) order[c] = c;
    const unsigned top = std::min(3u, cells);
    std::partial_sort(order.begin(), order.begin() + top, order.end(),
                      [&](unsigned a, unsigned b) { return local[a] > local[b]; });
    for (unsigned r = 0; r < top; ++r) {
      // Level 0 and the active index agree: the mesh is read, never refined.
      const Triangulation<2>::active_cell_iterator cell(&d.tria, 0, order[r]);
      const auto [sj, ratio] = shape(cell);
      unsigned corners_irregular = 0;
      for (unsigned v = 0; v < cell->n_vertices(); ++v) corners_irregular += irregular(cell->vertex_index(v));
      worst.push_back({{"centre", {cell->center()[0], cell->center()[1]}},
                       {"share", local[order[r]] / total},
                       {"vertices", cell->n_vertices()},
                       {"sj", sj},
                       {"edge_ratio", ratio},
                       {"area_ratio", cell->measure() * cells / area},
                       {"irregular_corners", corners_irregular},
                       {"at_boundary", cell->at_boundary()}});
    }
    return worst;
  };

  out["k"] = o.k;
  out["box"] = {o.x0, o.y0, o.length};
  out["area"] = area;
  out["cg_iterations"] = control.last_step();
  out["tolerance"] = o.tolerance;
  out["boundary_dofs"] = fixed.size();
  out["l2"] = std::sqrt(l2);
  out["h1"] = std::sqrt(h1);
  out["u_l2"] = std::sqrt(u_l2);
  out["u_h1"] = std::sqrt(u_h1);
  for (unsigned kind = 0; kind < 2; ++kind)
    if (kind == 0 ? d.quads : d.triangles) {
      const std::string name = kind == 0 ? "quads" : "triangles";
      out["sj_min_" + name] = sj_min[kind];
      out["edge_ratio_max_" + name] = ratio_max[kind];
    }
  out["irregular_vertices"] = irregular_vertices;
  out["area_ratio_p05"] = percentile(0.05);
  out["area_ratio_p95"] = percentile(0.95);
  out["area_ratio_max"] = areas.back();
  // The share of the L2 error (squared) in the cells over twice the mean area, and how many cells those are.
  double large_l2 = 0;
  unsigned large = 0;
  for (const auto& cell : d.tria.active_cell_iterators())
    if (cell->measure() * cells / area > 2) large_l2 += cell_l2[cell->active_cell_index()], ++large;
  out["large_cells_fraction"] = double(large) / cells;
  out["large_cells_l2_share"] = large_l2 / l2;
  out["worst_l2"] = describe(cell_l2, l2);
  out["worst_h1"] = describe(cell_h1, h1);
  std::cout << "poisson: k " << o.k << ", " << out["cells"] << " cells, " << n << " DoFs, L2 error " << out["l2"]
            << ", H1 seminorm error " << out["h1"] << ", " << control.last_step() << " CG iterations\n";
  if (!o.json_out.empty()) std::ofstream(o.json_out) << out.dump(1) << "\n";
  std::cout << out.dump() << "\n";
  return 0;
}
