// The map stage's results as bytes, for processes that share the work of one run (core/work_sharing.h): what a
// process computed is copied as it is to the others, so every process continues from identical values.
#pragma once

#include "polysquare/core/quad_mesh.h"
#include "polysquare/core/work_sharing.h"
#include "polysquare/map/layout.h"
#include "polysquare/map/polysquare_map.h"
#include "polysquare/triangulate/background_triangulation.h"

namespace polysquare {

void put_bytes(ByteWriter& w, const QuadMesh& m);
void get_bytes(ByteReader& r, QuadMesh& m);
void put_bytes(ByteWriter& w, const TriMesh& m);
void get_bytes(ByteReader& r, TriMesh& m);
void put_bytes(ByteWriter& w, const Layout& l);
void get_bytes(ByteReader& r, Layout& l);
/// A map's positions and statistics; with `with_problem` also its deformation problem and rotation.
void put_bytes(ByteWriter& w, const MappedMesh& mm, bool with_problem);
void get_bytes(ByteReader& r, MappedMesh& mm, bool with_problem);
void put_bytes(ByteWriter& w, const PartMapResult& result);
void get_bytes(ByteReader& r, PartMapResult& result);

}  // namespace polysquare
