// Heat diffusion on a 2D MSH mesh, the problem of the paper's Sec. 6.4 (Table 3): dT/dt = D laplace(T) with
// T = 273 on every boundary curve (outer ring and holes), T = 0 on an interior feature circle, T = 0 inside at t = 0.
// Quads use FE_Q, triangles FE_SimplexP (Gmsh Delaunay meshes); Crank-Nicolson with a fixed step, CG + SSOR.
//
// usage: heat MESH.msh (--region REGION.geojson | --circle CX CY R) [--degree P] [--dt DT] [--diffusivity D]
//             [--times 1,10] [--euler-steps N] [--tolerance TOL] [--save PREFIX]
//             [--reference REF.msh REF_PREFIX [--reference-degree P]] [--residuals FILE.json] [--json FILE.json]
//             [--max-cg N] [--max-eps E]
// --save writes the solution at each report time (PREFIX.t<time>.vec); a run with --reference reads such vectors
// (made on a much finer mesh, same dt) and prints eps(t) = ||T - T_ref||_L2 / ||T_ref||_L2 over this mesh.
// The last line printed is a JSON object with every figure (cells, dofs, cg_mean, eps_t1, ...). Exit status 1
// when a check fails: a CG solve needing more than --max-cg iterations (default 10000) or not converging, or an eps
// that is not finite or above --max-eps (with --reference).
#include <deal.II/base/quadrature_lib.h>
#include <deal.II/boost_adaptors/bounding_box.h>
#include <deal.II/boost_adaptors/point.h>
#include <deal.II/dofs/dof_handler.h>
#include <deal.II/dofs/dof_tools.h>
#include <deal.II/fe/fe_q.h>
#include <deal.II/fe/fe_simplex_p.h>
#include <deal.II/fe/fe_values.h>
#include <deal.II/fe/mapping_fe.h>
#include <deal.II/fe/mapping_q.h>
#include <deal.II/grid/grid_in.h>
#include <deal.II/grid/grid_tools.h>
#include <deal.II/grid/grid_tools_cache.h>
#include <deal.II/grid/tria.h>
#include <deal.II/hp/fe_collection.h>
#include <deal.II/hp/fe_values.h>
#include <deal.II/hp/mapping_collection.h>
#include <deal.II/hp/q_collection.h>
#include <deal.II/lac/dynamic_sparsity_pattern.h>
#include <deal.II/lac/full_matrix.h>
#include <deal.II/lac/precondition.h>
#include <deal.II/lac/solver_cg.h>
#include <deal.II/lac/solver_control.h>
#include <deal.II/lac/sparse_matrix.h>
#include <deal.II/lac/sparsity_pattern.h>
#include <deal.II/lac/vector.h>
#include <deal.II/numerics/matrix_tools.h>

#include <boost/geometry/index/rtree.hpp>
#include <nlohmann/json.hpp>

#include "discretisation.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

using namespace dealii;
using simulate::Discretisation;
using simulate::fail;

namespace {

struct Options {
  std::string mesh, region, save, ref_mesh, ref_prefix, residuals, json_out;
  bool have_circle = false;
  Point<2> centre;
  double radius = 0;
  unsigned degree = 1, ref_degree = 2, euler_steps = 2;
  double dt = 0.01, diffusivity = 1.0, tolerance = 1e-8, max_eps = std::numeric_limits<double>::infinity();
  unsigned max_cg = 10000;
  std::vector<double> times{1.0, 10.0};
};

// The feature circle of a region: the one closed ring with role "feature" (centre = vertex mean, radius = mean distance).
void circle_from_region(Options& o) {
  std::ifstream in(o.region);
  if (!in) fail("cannot read " + o.region);
  const auto doc = nlohmann::json::parse(in);
  int rings = 0;
  for (const auto& f : doc.at("features")) {
    if (f.value("properties", nlohmann::json::object()).value("role", "") != "feature") continue;
    const auto& g = f.at("geometry");
    const std::string type = g.at("type");
    const auto& coords = type == "Polygon" ? g.at("coordinates").at(0) : g.at("coordinates");
    if (type != "Polygon" && type != "LinearRing" && !(type == "LineString" && coords.front() == coords.back())) continue;
    std::vector<Point<2>> pts;
    for (std::size_t i = 0; i + 1 < coords.size(); ++i)  // the closing vertex repeats the first
      pts.emplace_back(coords[i][0].get<double>(), coords[i][1].get<double>());
    Point<2> c;
    for (const auto& p : pts) c += p / double(pts.size());
    double r = 0;
    for (const auto& p : pts) r += p.distance(c) / double(pts.size());
    o.centre = c, o.radius = r, ++rings;
  }
  if (rings != 1) fail(o.region + ": expected one closed feature ring, found " + std::to_string(rings));
  o.have_circle = true;
}

Options parse(int argc, char** argv) {
  Options o;
  const simulate::Need need{argc, argv};
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--region") need(i, 1), o.region = argv[++i];
    else if (a == "--circle") {
      need(i, 3);
      o.centre = Point<2>(std::stod(argv[i + 1]), std::stod(argv[i + 2]));
      o.radius = std::stod(argv[i + 3]), o.have_circle = true, i += 3;
    } else if (a == "--degree") need(i, 1), o.degree = std::stoul(argv[++i]);
    else if (a == "--dt") need(i, 1), o.dt = std::stod(argv[++i]);
    else if (a == "--diffusivity") need(i, 1), o.diffusivity = std::stod(argv[++i]);
    else if (a == "--euler-steps") need(i, 1), o.euler_steps = std::stoul(argv[++i]);
    else if (a == "--tolerance") need(i, 1), o.tolerance = std::stod(argv[++i]);
    else if (a == "--max-cg") need(i, 1), o.max_cg = std::stoul(argv[++i]);
    else if (a == "--max-eps") need(i, 1), o.max_eps = std::stod(argv[++i]);
    else if (a == "--save") need(i, 1), o.save = argv[++i];
    else if (a == "--residuals") need(i, 1), o.residuals = argv[++i];
    else if (a == "--json") need(i, 1), o.json_out = argv[++i];
    else if (a == "--reference-degree") need(i, 1), o.ref_degree = std::stoul(argv[++i]);
    else if (a == "--reference") need(i, 2), o.ref_mesh = argv[i + 1], o.ref_prefix = argv[i + 2], i += 2;
    else if (a == "--times") {
      need(i, 1);
      o.times.clear();
      std::stringstream s(argv[++i]);
      for (std::string t; std::getline(s, t, ',');) o.times.push_back(std::stod(t));
    } else if (!a.empty() && a[0] == '-') fail("unknown option " + a);
    else if (o.mesh.empty()) o.mesh = a;
    else fail("one mesh only");
  }
  std::sort(o.times.begin(), o.times.end());
  if (o.mesh.empty()) fail("usage: heat MESH.msh (--region REGION.geojson | --circle CX CY R) [options]; see heat.cpp");
  if (!o.have_circle && !o.region.empty()) circle_from_region(o);
  if (!o.have_circle) fail("the feature circle is needed: --region or --circle");
  return o;
}

// The point of the unit cell (square or triangle) nearest to unit.
Point<2> clamp_to_unit_cell(Point<2> unit, bool simplex) {
  for (unsigned c = 0; c < 2; ++c) unit[c] = std::clamp(unit[c], 0.0, 1.0);
  if (simplex && unit[0] + unit[1] > 1) {
    const double excess = (unit[0] + unit[1] - 1) / 2;
    unit = Point<2>(std::clamp(unit[0] - excess, 0.0, 1.0), std::clamp(unit[1] - excess, 0.0, 1.0));
  }
  return unit;
}

std::string time_tag(double t) {
  std::ostringstream s;
  s << t;
  return s.str();
}

// A solution saved by --save on the reference mesh, evaluated at arbitrary points of the coarse mesh.
struct Reference {
  Discretisation disc;
  std::vector<Vector<double>> fields;  // one per report time
  GridTools::Cache<2> cache;
  Triangulation<2>::active_cell_iterator hint;
  unsigned outside = 0;  // points found in no reference cell (coarse chords across a hole's polygon)

  Reference(const Options& o) : disc(o.ref_mesh, o.ref_degree), cache(disc.tria, disc.single_mapping("the reference mesh")) {
    for (double t : o.times) {
      const std::string path = o.ref_prefix + ".t" + time_tag(t) + ".vec";
      std::ifstream in(path, std::ios::binary);
      if (!in) fail("cannot read the reference solution " + path);
      Vector<double> v;
      v.block_read(in);
      if (v.size() != disc.dofs.n_dofs())
        fail(path + " has " + std::to_string(v.size()) + " values, the reference mesh at degree " +
             std::to_string(o.ref_degree) + " has " + std::to_string(disc.dofs.n_dofs()) + " DoFs");
      fields.push_back(std::move(v));
    }
  }

  // The reference cell and unit point of p; outside the reference mesh (a coarse mesh's chords across a hole's
  // polygon), the closest point of a cell next to the nearest vertex. Candidates come from the cache's R-trees:
  // deal.II's own search falls back to trying every cell for a point outside, far too slow for many points.
  std::pair<Triangulation<2>::active_cell_iterator, Point<2>> locate(const Point<2>& p) {
    namespace bgi = boost::geometry::index;
    const Mapping<2>& mapping = cache.get_mapping();
    auto inside = [&](const Triangulation<2>::active_cell_iterator& cell, Point<2>& unit) {
      try {
        unit = mapping.transform_real_to_unit_cell(cell, p);
        return cell->reference_cell().contains_point(unit, 1e-10);
      } catch (const std::exception&) {
        return false;  // the mapping cannot invert at p: p is not in this cell
      }
    };
    Point<2> unit;
    if (hint.state() == IteratorState::valid && inside(hint, unit)) return {hint, unit};
    std::vector<std::pair<BoundingBox<2>, Triangulation<2>::active_cell_iterator>> boxes;
    cache.get_cell_bounding_boxes_rtree().query(bgi::intersects(p), std::back_inserter(boxes));
    for (const auto& [box, cell] : boxes)
      if (inside(cell, unit)) return {hint = cell, unit};
    ++outside;
    std::vector<std::pair<Point<2>, unsigned>> nearest;
    cache.get_used_vertices_rtree().query(bgi::nearest(p, 1), std::back_inserter(nearest));
    std::pair<Triangulation<2>::active_cell_iterator, Point<2>> found;
    double best = std::numeric_limits<double>::max();
    for (const auto& cell : cache.get_vertex_to_cell_map()[nearest.at(0).second]) {
      try {
        const Point<2> clamped = clamp_to_unit_cell(mapping.transform_real_to_unit_cell(cell, p), disc.triangles > 0);
        const double d = mapping.transform_unit_to_real_cell(cell, clamped).distance(p);
        if (d < best) best = d, found = {cell, clamped};
      } catch (const std::exception&) {
        // no inverse at p for this cell: another adjacent cell will do
      }
    }
    if (best == std::numeric_limits<double>::max()) fail("a coarse quadrature point is far outside the reference mesh");
    return found;
  }

  // Values of every report-time field at p.
  std::vector<double> values(const Point<2>& p) {
    const auto [cell, unit] = locate(p);
    const DoFHandler<2>::active_cell_iterator dcell(&disc.tria, cell->level(), cell->index(), &disc.dofs);
    std::vector<types::global_dof_index> idx(dcell->get_fe().n_dofs_per_cell());
    dcell->get_dof_indices(idx);
    std::vector<double> out(fields.size(), 0.0);
    for (unsigned i = 0; i < idx.size(); ++i) {
      const double phi = dcell->get_fe().shape_value(i, unit);
      for (std::size_t k = 0; k < fields.size(); ++k) out[k] += phi * fields[k][idx[i]];
    }
    return out;
  }
};

// Records every residual of a CG solve when asked (the iteration-residual plot of the paper's Fig. 17).
class RecordingControl : public SolverControl {
 public:
  using SolverControl::SolverControl;
  std::vector<double>* record = nullptr;
  State check(const unsigned step, const double value) override {
    if (record) record->push_back(value);
    return SolverControl::check(step, value);
  }
};

}  // namespace

int main(int argc, char** argv) {
  simulate::program = "heat";
  const Options o = parse(argc, argv);
  Discretisation d(o.mesh, o.degree);
  const unsigned n = d.dofs.n_dofs();

  // Dirichlet values: 273 on every boundary DoF, 0 on every DoF of the feature circle. Both mesh generators put the
  // circle on mesh edges, so the circle's faces are those between a cell whose centre is inside it and one whose
  // centre is outside. A distance test on the nodes would not do: polysquare's nodes follow the simplified circle
  // (up to a third of a cell off it at coarse sizes) while other nodes can come closer than that.
  std::map<types::global_dof_index, double> fixed;
  const IndexSet boundary = DoFTools::extract_boundary_dofs(d.dofs);
  for (auto i : boundary) fixed[i] = 273.0;
  auto inside = [&](const auto& cell) { return cell->center().distance(o.centre) < o.radius; };
  unsigned circle_faces = 0;
  std::vector<bool> on_curve(d.tria.n_active_cells(), false);  // cells touching the boundary or the circle
  for (const auto& cell : d.tria.active_cell_iterators()) on_curve[cell->active_cell_index()] = cell->at_boundary();
  double circle_length = 0, circle_offset = 0;
  std::vector<types::global_dof_index> idx;
  for (const auto& cell : d.dofs.active_cell_iterators())
    for (unsigned f = 0; f < cell->n_faces(); ++f) {
      if (cell->at_boundary(f) || !inside(cell) || inside(cell->neighbor(f))) continue;
      const auto face = cell->face(f);
      idx.resize(cell->get_fe().n_dofs_per_face(f));
      face->get_dof_indices(idx, cell->active_fe_index());
      for (auto i : idx)
        if (!boundary.is_element(i)) fixed[i] = 0.0;
      ++circle_faces, circle_length += face->measure();
      for (unsigned v = 0; v < 2; ++v)  // every cell sharing a circle vertex touches the circle
        for (const auto& c : GridTools::find_cells_adjacent_to_vertex(d.tria, face->vertex_index(v)))
          on_curve[c->active_cell_index()] = true;
      for (unsigned v = 0; v < 2; ++v)
        circle_offset = std::max(circle_offset, std::abs(face->vertex(v).distance(o.centre) - o.radius));
    }
  // The faces found must go round the circle once: their length within 5 % of its perimeter.
  if (std::abs(circle_length - 2 * numbers::PI * o.radius) > 0.05 * 2 * numbers::PI * o.radius)
    fail("the faces between cells inside and outside the feature circle are " + std::to_string(circle_length) +
         " long, not its perimeter: is the circle embedded in the mesh as edges?");
  unsigned circle_dofs = 0;
  for (const auto& [i, v] : fixed) circle_dofs += v == 0.0;

  // How far the cells on the boundary reach inwards (length-weighted mean height of their boundary faces: area over
  // face length, twice that for triangles): at t = 0 the nodal 273 K ramps down across this height, so with a thin
  // early layer it weighs on eps(t) whatever the mesh's quality.
  double boundary_length = 0, boundary_height = 0;
  for (const auto& cell : d.dofs.active_cell_iterators())
    for (unsigned f = 0; f < cell->n_faces(); ++f)
      if (cell->at_boundary(f)) {
        const double len = cell->face(f)->measure(), height = (cell->n_vertices() == 3 ? 2 : 1) * cell->measure() / len;
        boundary_length += len, boundary_height += height * len;
      }
  boundary_height /= boundary_length;

  // Mass and stiffness matrices, assembled once.
  DynamicSparsityPattern dsp(n);
  DoFTools::make_sparsity_pattern(d.dofs, dsp);
  SparsityPattern pattern;
  pattern.copy_from(dsp);
  SparseMatrix<double> mass(pattern), stiffness(pattern);
  {
    hp::FEValues<2> hp_fv(d.mapping, d.fe, d.assembly_quadrature, update_values | update_gradients | update_JxW_values);
    FullMatrix<double> m, s;
    for (const auto& cell : d.dofs.active_cell_iterators()) {
      hp_fv.reinit(cell);
      const FEValues<2>& fv = hp_fv.get_present_fe_values();
      const unsigned k = cell->get_fe().n_dofs_per_cell();
      m.reinit(k, k), s.reinit(k, k);
      for (unsigned q = 0; q < fv.n_quadrature_points; ++q)
        for (unsigned i = 0; i < k; ++i)
          for (unsigned j = 0; j < k; ++j) {
            m(i, j) += fv.shape_value(i, q) * fv.shape_value(j, q) * fv.JxW(q);
            s(i, j) += fv.shape_grad(i, q) * fv.shape_grad(j, q) * fv.JxW(q);
          }
      idx.resize(k);
      cell->get_dof_indices(idx);
      mass.add(idx, m);
      stiffness.add(idx, s);
    }
  }

  // theta-scheme: (M + theta dt D K) T_new = (M - (1 - theta) dt D K) T_old. Backward Euler (theta = 1) for the first
  // steps damps the jump between the 273 K boundary and the 0 K interior at t = 0, which Crank-Nicolson alone keeps
  // as a slowly decaying oscillation. The Dirichlet rows are eliminated once: lift holds what the elimination adds
  // to every right-hand side (the boundary values are constant in time).
  struct Step {
    SparseMatrix<double> lhs, rhs_matrix;
    Vector<double> lift;
  };
  auto make_step = [&](double theta) {
    auto st = std::make_unique<Step>();
    st->lhs.reinit(pattern), st->rhs_matrix.reinit(pattern);
    st->lhs.copy_from(mass), st->lhs.add(theta * o.dt * o.diffusivity, stiffness);
    st->rhs_matrix.copy_from(mass), st->rhs_matrix.add(-(1 - theta) * o.dt * o.diffusivity, stiffness);
    Vector<double> dummy(n);
    st->lift.reinit(n);
    MatrixTools::apply_boundary_values(fixed, st->lhs, dummy, st->lift, true);
    return st;
  };
  const auto euler = make_step(1.0), crank_nicolson = make_step(0.5);

  Vector<double> T(n), rhs(n);
  for (const auto& [i, v] : fixed) T[i] = v;

  std::vector<long> report_steps;
  for (double t : o.times) {
    const long s = std::lround(t / o.dt);
    if (std::abs(s * o.dt - t) > 1e-9 * std::max(1.0, t)) fail("report time " + time_tag(t) + " is not a multiple of dt");
    report_steps.push_back(s);
  }
  const long steps = *std::max_element(report_steps.begin(), report_steps.end());

  Reference* ref = nullptr;
  std::unique_ptr<Reference> ref_owner;
  if (!o.ref_mesh.empty()) ref_owner = std::make_unique<Reference>(o), ref = ref_owner.get();

  nlohmann::json out, residuals;
  unsigned long total_iterations = 0, max_iterations = 0;
  std::vector<Vector<double>> snapshots;
  for (long step = 1; step <= steps; ++step) {
    const Step& st = step <= long(o.euler_steps) ? *euler : *crank_nicolson;
    st.rhs_matrix.vmult(rhs, T);
    for (const auto& [i, v] : fixed) rhs[i] = 0;
    rhs += st.lift;
    std::vector<double> history;
    const bool reported = std::find(report_steps.begin(), report_steps.end(), step) != report_steps.end();
    RecordingControl control(o.max_cg, o.tolerance * rhs.l2_norm(), false, false);
    if (reported && !o.residuals.empty()) control.record = &history;
    SolverCG<Vector<double>> cg(control);
    PreconditionSSOR<SparseMatrix<double>> ssor;
    ssor.initialize(st.lhs, 1.2);
    try {
      cg.solve(st.lhs, T, rhs, ssor);
    } catch (const SolverControl::NoConvergence& e) {
      std::cerr << "heat: CG did not reach the tolerance in " << o.max_cg << " iterations at step " << step
                << " (residual " << e.last_residual << ")\n";
      return 1;
    }
    total_iterations += control.last_step();
    max_iterations = std::max<unsigned long>(max_iterations, control.last_step());
    if (reported) {
      snapshots.push_back(T);
      if (!o.residuals.empty()) residuals["t" + time_tag(step * o.dt)] = history;
    }
  }

  out["mesh"] = o.mesh;
  out["quads"] = d.quads;
  out["triangles"] = d.triangles;
  out["degree"] = o.degree;
  out["cells"] = d.tria.n_active_cells();
  out["dofs"] = n;
  out["boundary_dofs"] = boundary.n_elements();
  out["circle_dofs"] = circle_dofs;
  out["circle_faces"] = circle_faces;
  out["boundary_cell_height"] = boundary_height;
  out["circle_length"] = circle_length;
  out["circle_offset_max"] = circle_offset;
  out["dt"] = o.dt;
  out["steps"] = steps;
  out["euler_steps"] = o.euler_steps;
  out["diffusivity"] = o.diffusivity;
  out["tolerance"] = o.tolerance;
  out["cg_mean"] = double(total_iterations) / double(steps);
  out["cg_max"] = max_iterations;

  for (std::size_t k = 0; k < o.times.size(); ++k) {
    if (!o.save.empty()) {
      std::ofstream f(o.save + ".t" + time_tag(o.times[k]) + ".vec", std::ios::binary);
      snapshots[k].block_write(f);
    }
    out["max_t" + time_tag(o.times[k])] = snapshots[k].linfty_norm();
  }

  if (ref) {
    // eps(t) over this mesh, with a quadrature two orders above the element's so the reference's finer detail counts.
    hp::FEValues<2> hp_fv(d.mapping, d.fe, d.error_quadrature,
                          update_values | update_quadrature_points | update_JxW_values);
    std::vector<double> diff2(o.times.size(), 0.0), ref2(o.times.size(), 0.0), curve2(o.times.size(), 0.0);
    std::vector<double> worst(o.times.size(), 0.0);
    std::vector<Point<2>> worst_at(o.times.size());
    std::vector<double> worst_area(o.times.size(), 0.0);
    for (const auto& cell : d.dofs.active_cell_iterators()) {
      std::vector<double> cell2(o.times.size(), 0.0);
      hp_fv.reinit(cell);
      const FEValues<2>& fv = hp_fv.get_present_fe_values();
      std::vector<std::vector<double>> mine(o.times.size(), std::vector<double>(fv.n_quadrature_points));
      for (std::size_t k = 0; k < o.times.size(); ++k) fv.get_function_values(snapshots[k], mine[k]);
      for (unsigned q = 0; q < fv.n_quadrature_points; ++q) {
        const auto theirs = ref->values(fv.quadrature_point(q));
        for (std::size_t k = 0; k < o.times.size(); ++k) {
          cell2[k] += std::pow(mine[k][q] - theirs[k], 2) * fv.JxW(q);
          ref2[k] += theirs[k] * theirs[k] * fv.JxW(q);
        }
      }
      for (std::size_t k = 0; k < o.times.size(); ++k) {
        diff2[k] += cell2[k];
        if (on_curve[cell->active_cell_index()]) curve2[k] += cell2[k];
        if (cell2[k] > worst[k]) worst[k] = cell2[k], worst_at[k] = cell->center(), worst_area[k] = cell->measure();
      }
    }
    double area = 0;  // GridTools::volume's default mapping is for quads only
    for (const auto& cell : d.tria.active_cell_iterators()) area += cell->measure();
    // Where the error is: its share in the cells touching the boundary or the circle, and the worst cell.
    out["curve_cells_fraction"] =
        double(std::count(on_curve.begin(), on_curve.end(), true)) / double(d.tria.n_active_cells());
    for (std::size_t k = 0; k < o.times.size(); ++k) {
      const std::string t = time_tag(o.times[k]);
      out["eps_t" + t] = std::sqrt(diff2[k] / ref2[k]);
      out["curve_error_share_t" + t] = curve2[k] / diff2[k];
      out["worst_cell_t" + t] = {worst_at[k][0], worst_at[k][1]};
      out["worst_cell_share_t" + t] = worst[k] / diff2[k];
      out["worst_cell_area_ratio_t" + t] = worst_area[k] * d.tria.n_active_cells() / area;
    }
    out["reference"] = o.ref_mesh;
    out["reference_dofs"] = ref->disc.dofs.n_dofs();
    out["points_outside_reference"] = ref->outside;
  }

  bool ok = true;
  if (ref)
    for (double t : o.times) {
      const double e = out["eps_t" + time_tag(t)];
      if (!std::isfinite(e) || e > o.max_eps) {
        std::cerr << "heat: eps(t=" << t << ") = " << e << " is not finite or above --max-eps " << o.max_eps << "\n";
        ok = false;
      }
    }
  if (!o.residuals.empty()) std::ofstream(o.residuals) << residuals.dump() << "\n";
  if (!o.json_out.empty()) std::ofstream(o.json_out) << out.dump(1) << "\n";
  std::cout << out.dump() << "\n";
  return ok ? 0 : 1;
}
