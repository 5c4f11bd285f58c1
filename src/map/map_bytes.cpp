#include "polysquare/map/map_bytes.h"

namespace polysquare {

namespace {

// Each struct's fields listed once, for writing (io puts) and reading (io gets) alike.
template <class IO, class M>
void quad_fields(IO& io, M& m) {
  io(m.nodes), io(m.quads), io(m.triangles), io(m.quad_part), io(m.node_kind), io(m.boundary_edges);
  io(m.boundary_edge_ring), io(m.feature_edges), io(m.feature_edge_curve), io(m.crs), io(m.units);
}

template <class IO, class L>
void layout_fields(IO& io, L& l) {
  io(l.break_vertex), io(l.vertex_break), io(l.break_is_corner), io(l.segments), io(l.lattice), io(l.chain_labels), io(l.separations);
}

template <class IO, class M>
void mapped_fields(IO& io, M& mm, bool with_problem) {
  if (with_problem) io(mm.problem.rest), io(mm.problem.rest_scale), io(mm.problem.triangles), io(mm.problem.aligned), io(mm.problem.fixed), io(mm.rotation_deg);
  io(mm.x), io(mm.stats);
}

template <class IO, class Stats>
void stats_fields(IO& io, Stats& s) {
  io(s.part), io(s.triangles), io(s.triangle_vertices), io(s.rotation_deg), io(s.deform), io(s.break_points);
  io(s.segments), io(s.quantize), io(s.quads), io(s.separators), io(s.agreed_turns), io(s.transition_rows), io(s.split), io(s.joint_splits);
  io(s.seconds_partition), io(s.seconds_triangulate), io(s.seconds_deform), io(s.seconds_quantize);
  io(s.seconds_snap), io(s.seconds_extract), io(s.joint_maps), io(s.seconds_joint_maps);
  io(s.multipass.passes), io(s.multipass.colours), io(s.multipass.last_move), io(s.multipass.seconds);
}

template <class IO, class Partition>
void partition_fields(IO& io, Partition& p) {
  io(p.triangle_part), io(p.parts), io(p.faces), io(p.metis), io(p.final), io(p.feature_fraction_metis);
  io(p.feature_fraction_final), io(p.balance_max_over_avg), io(p.mh_proposed), io(p.mh_accepted);
  io(p.repaired_triangles);
}

struct Put {
  ByteWriter& w;
  template <class T>
  void operator()(const T& v) const { w.put(v); }
};

struct Get {
  ByteReader& r;
  template <class T>
  void operator()(T& v) const { r.get(v); }
};

}  // namespace

void put_bytes(ByteWriter& w, const QuadMesh& m) {
  Put io{w};
  quad_fields(io, m);
}

void get_bytes(ByteReader& r, QuadMesh& m) {
  Get io{r};
  quad_fields(io, m);
}

void put_bytes(ByteWriter& w, const TriMesh& m) {
  w.put(m.vertices);
  w.put(m.triangles);
  w.put(static_cast<std::uint64_t>(m.chains.size()));
  for (const TriChain& c : m.chains) {
    w.put(c.kind);
    w.put(c.index);
    w.put(c.closed);
    w.put(c.vertices);
    w.put(c.is_input);
    w.put(c.interface);
  }
  w.put(m.feature_point_vertices);
  w.put(m.loops);
}

void get_bytes(ByteReader& r, TriMesh& m) {
  r.get(m.vertices);
  r.get(m.triangles);
  std::uint64_t n = 0;
  r.get(n);
  m.chains.resize(n);
  for (TriChain& c : m.chains) {
    r.get(c.kind);
    r.get(c.index);
    r.get(c.closed);
    r.get(c.vertices);
    r.get(c.is_input);
    r.get(c.interface);
  }
  r.get(m.feature_point_vertices);
  r.get(m.loops);
}

void put_bytes(ByteWriter& w, const Layout& l) {
  Put io{w};
  layout_fields(io, l);
}

void get_bytes(ByteReader& r, Layout& l) {
  Get io{r};
  layout_fields(io, l);
}

void put_bytes(ByteWriter& w, const MappedMesh& mm, bool with_problem) {
  Put io{w};
  mapped_fields(io, mm, with_problem);
}

void get_bytes(ByteReader& r, MappedMesh& mm, bool with_problem) {
  Get io{r};
  mapped_fields(io, mm, with_problem);
}

void put_bytes(ByteWriter& w, const PartMapResult& result) {
  Put put{w};
  put_bytes(w, result.mesh);
  stats_fields(put, result.stats);
  w.put(static_cast<std::uint64_t>(result.stats.subregions.size()));
  for (const SubregionStats& s : result.stats.subregions) {
    w.put(s.subregion), w.put(s.mapped), w.put(s.untangled), w.put(s.quads), w.put(s.local_patch_quads), w.put(s.reason), w.put(s.at);
  }
  w.put(static_cast<std::uint64_t>(result.stats.failed_maps.size()));
  for (const auto& [a, b] : result.stats.failed_maps) w.put(a), w.put(b);
  w.put(static_cast<std::uint8_t>(result.partition.has_value()));
  if (result.partition) partition_fields(put, *result.partition);
  put_bytes(w, result.background);
}

void get_bytes(ByteReader& r, PartMapResult& result) {
  Get get{r};
  get_bytes(r, result.mesh);
  stats_fields(get, result.stats);
  std::uint64_t n = 0;
  r.get(n);
  result.stats.subregions.resize(n);
  for (SubregionStats& s : result.stats.subregions) {
    r.get(s.subregion), r.get(s.mapped), r.get(s.untangled), r.get(s.quads), r.get(s.local_patch_quads), r.get(s.reason), r.get(s.at);
  }
  r.get(n);
  result.stats.failed_maps.resize(n);
  for (auto& [a, b] : result.stats.failed_maps) r.get(a), r.get(b);
  std::uint8_t has = 0;
  r.get(has);
  result.partition.reset();
  if (has) partition_fields(get, result.partition.emplace());
  get_bytes(r, result.background);
}

}  // namespace polysquare
