// Reads MSH files with deal.II's GridIn::read_msh, as a deal.II user would, and prints per file
// "<cells> <boundary faces> <boundary id>:<faces> ..."; exits 1 with deal.II's message when a file is refused.
#include <deal.II/grid/grid_in.h>
#include <deal.II/grid/tria.h>

#include <fstream>
#include <iostream>
#include <map>

int main(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    dealii::Triangulation<2> tria;
    dealii::GridIn<2> in;
    in.attach_triangulation(tria);
    std::ifstream file(argv[i]);
    try {
      in.read_msh(file);
    } catch (const std::exception& e) {
      std::cerr << argv[i] << ": " << e.what() << "\n";
      return 1;
    }
    std::map<unsigned, unsigned> faces_by_id;
    unsigned boundary_faces = 0;
    for (const auto& face : tria.active_face_iterators())
      if (face->at_boundary()) ++boundary_faces, ++faces_by_id[face->boundary_id()];
    std::cout << tria.n_active_cells() << " " << boundary_faces;
    for (const auto& [id, n] : faces_by_id) std::cout << " " << id << ":" << n;
    std::cout << "\n";
  }
  return 0;
}
