// What the bench/simulate programs (heat, poisson) share: checking option values, reading a Gmsh MSH 4.1 mesh of quads, triangles or both
// into deal.II, with an element, mapping and quadratures for each cell kind.
#pragma once

#include <deal.II/base/quadrature_lib.h>
#include <deal.II/dofs/dof_handler.h>
#include <deal.II/fe/fe_q.h>
#include <deal.II/fe/fe_simplex_p.h>
#include <deal.II/fe/mapping_fe.h>
#include <deal.II/fe/mapping_q.h>
#include <deal.II/grid/grid_in.h>
#include <deal.II/grid/tria.h>
#include <deal.II/hp/fe_collection.h>
#include <deal.II/hp/mapping_collection.h>
#include <deal.II/hp/q_collection.h>

#include <cstdlib>
#include <fstream>
#include <iostream>
#include <string>

namespace simulate {

inline std::string program = "simulate";  // set by main: the name error messages start with

// Bad input or options: exit status 2 (1 is kept for a failed check).
[[noreturn]] inline void fail(const std::string& why) {
  std::cerr << program << ": " << why << "\n";
  std::exit(2);
}

// need(i, n): the option at argv[i] must be followed by n values.
struct Need {
  int argc;
  char** argv;
  void operator()(int i, int n) const {
    if (i + n >= argc) fail(std::string(argv[i]) + " needs " + std::to_string(n) + " value(s)");
  }
};

// A mesh with an element, mapping and quadratures for each of its cell kinds: index 0 quads (FE_Q), 1 triangles
// (FE_SimplexP). Gmsh's Blossom recombination leaves a few triangles among its quads, so a mesh may hold both.
struct Discretisation {
  dealii::Triangulation<2> tria;
  dealii::hp::FECollection<2> fe;
  dealii::hp::MappingCollection<2> mapping;
  dealii::hp::QCollection<2> assembly_quadrature, error_quadrature;
  dealii::DoFHandler<2> dofs;
  unsigned quads = 0, triangles = 0;

  Discretisation(const std::string& path, unsigned degree) {
    using namespace dealii;
    GridIn<2> in;
    in.attach_triangulation(tria);
    std::ifstream file(path);
    if (!file) fail("cannot read " + path);
    in.read_msh(file);
    fe.push_back(FE_Q<2>(degree)), fe.push_back(FE_SimplexP<2>(degree));
    mapping.push_back(MappingQ<2>(1)), mapping.push_back(MappingFE<2>(FE_SimplexP<2>(1)));
    assembly_quadrature.push_back(QGauss<2>(degree + 1)), assembly_quadrature.push_back(QGaussSimplex<2>(degree + 1));
    // Errors against a finer field or an exact solution: above the element's order, so the other side's detail
    // counts (Gauss with degree + 3 points a side on quads, degree + 2 on triangles).
    error_quadrature.push_back(QGauss<2>(degree + 3)), error_quadrature.push_back(QGaussSimplex<2>(degree + 2));
    dofs.reinit(tria);
    for (const auto& cell : dofs.active_cell_iterators()) {
      const bool triangle = cell->reference_cell() == ReferenceCells::Triangle;
      cell->set_active_fe_index(triangle ? 1 : 0);
      ++(triangle ? triangles : quads);
    }
    dofs.distribute_dofs(fe);
  }

  // The one mapping of a mesh of one cell kind (point location needs a single mapping).
  const dealii::Mapping<2>& single_mapping(const std::string& what) const {
    if (quads && triangles) fail(what + " must be all quads or all triangles");
    return mapping[triangles ? 1 : 0];
  }
};

}  // namespace simulate
