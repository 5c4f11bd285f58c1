#include "polysquare/triangulate/background_triangulation.h"

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Delaunay_mesh_face_base_2.h>
#include <CGAL/Delaunay_mesh_size_criteria_2.h>
#include <CGAL/Delaunay_mesh_vertex_base_2.h>
#include <CGAL/Delaunay_mesher_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <algorithm>
#include <deque>
#include <unordered_map>
#include <string>
#include <unordered_set>

#include "polysquare/core/error.h"

namespace polysquare {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Vb0 = CGAL::Delaunay_mesh_vertex_base_2<K>;
using Vb = CGAL::Triangulation_vertex_base_with_info_2<std::int32_t, K, Vb0>;
using Fb = CGAL::Delaunay_mesh_face_base_2<K>;
using Tds = CGAL::Triangulation_data_structure_2<Vb, Fb>;
using CDT = CGAL::Constrained_Delaunay_triangulation_2<K, Tds, CGAL::Exact_predicates_tag>;
using Criteria = CGAL::Delaunay_mesh_size_criteria_2<CDT>;
using Mesher = CGAL::Delaunay_mesher_2<CDT, Criteria>;
using VH = CDT::Vertex_handle;
using FH = CDT::Face_handle;

// A point to decide which part a feature belongs to: the midpoint of its first segment (its end points may
// lie on the boundary, its interior never does after splitting).
Vec2 feature_probe(const FeatureCurve& f) {
  return f.points.size() >= 2 ? lerp(f.points[0], f.points[1], 0.5) : f.points.front();
}

struct PairHash {
  std::size_t operator()(std::pair<const void*, const void*> p) const {
    return std::hash<const void*>()(p.first) * 31u ^ std::hash<const void*>()(p.second);
  }
};

}  // namespace

double part_area(const Region& region, const RegionPart& part) {
  double a = 0.0;
  for (int r : part.rings) a += ring_signed_area(region.rings[static_cast<std::size_t>(r)].points);
  return a;
}

std::unordered_map<std::uint64_t, std::array<std::int32_t, 2>> edge_owners(const TriMesh& mesh) {
  std::unordered_map<std::uint64_t, std::array<std::int32_t, 2>> owners;
  owners.reserve(mesh.triangles.size() * 2);
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      auto [it, inserted] = owners.try_emplace(edge_key(mesh.triangles[t][k], mesh.triangles[t][(k + 1) % 3]),
                                               std::array<std::int32_t, 2>{static_cast<std::int32_t>(t), -1});
      if (!inserted) it->second[1] = static_cast<std::int32_t>(t);
    }
  return owners;
}

// Triangles with one, two or three split edges are subdivided into two, three or four, keeping
// counter-clockwise order; the midpoint vertex of a split edge is free to move inwards.
void split_constrained_interior_edges(TriMesh& mesh, std::vector<std::int32_t>* parent) {
  std::vector<std::uint8_t> on_chain(mesh.vertices.size(), 0);
  std::unordered_set<std::uint64_t> chain_edges;
  for (const TriChain& ch : mesh.chains) {
    const std::size_t n = ch.vertices.size();
    for (std::size_t i = 0; i < n; ++i) {
      on_chain[ch.vertices[i]] = 1;
      if (ch.closed || i + 1 < n) chain_edges.insert(edge_key(ch.vertices[i], ch.vertices[(i + 1) % n]));
    }
  }
  for (auto v : mesh.feature_point_vertices) on_chain[v] = 1;
  std::unordered_map<std::uint64_t, std::int32_t> midpoint;
  auto mid = [&](std::int32_t a, std::int32_t b) -> std::int32_t {
    if (!on_chain[a] || !on_chain[b] || chain_edges.count(edge_key(a, b))) return -1;
    auto [it, inserted] = midpoint.try_emplace(edge_key(a, b), static_cast<std::int32_t>(mesh.vertices.size()));
    if (inserted) mesh.vertices.push_back(lerp(mesh.vertices[a], mesh.vertices[b], 0.5));
    return it->second;
  };
  std::vector<std::array<std::int32_t, 3>> out;
  out.reserve(mesh.triangles.size());
  if (parent) parent->clear();
  for (std::size_t ti = 0; ti < mesh.triangles.size(); ++ti) {
    const auto t = mesh.triangles[ti];
    const std::array<std::int32_t, 3> m{mid(t[0], t[1]), mid(t[1], t[2]), mid(t[2], t[0])};
    const int count = (m[0] >= 0) + (m[1] >= 0) + (m[2] >= 0);
    if (count == 0) {
      out.push_back(t);
    } else if (count == 3) {
      out.push_back({t[0], m[0], m[2]});
      out.push_back({t[1], m[1], m[0]});
      out.push_back({t[2], m[2], m[1]});
      out.push_back({m[0], m[1], m[2]});
    } else {
      // Rotate so that edge 0 (t0 t1) is split; with two splits, edge 2 is the unsplit one.
      const int r = count == 1 ? (m[0] >= 0 ? 0 : (m[1] >= 0 ? 1 : 2)) : (m[2] < 0 ? 0 : (m[0] < 0 ? 1 : 2));
      const std::int32_t a = t[r], b = t[(r + 1) % 3], c = t[(r + 2) % 3];
      const std::int32_t mab = m[r], mbc = m[(r + 1) % 3];
      out.push_back({a, mab, c});
      if (count == 1) {
        out.push_back({mab, b, c});
      } else {
        out.push_back({mab, b, mbc});
        out.push_back({mab, mbc, c});
      }
    }
    if (parent) parent->resize(out.size(), static_cast<std::int32_t>(ti));
  }
  mesh.triangles = std::move(out);
}

std::string chain_name(const TriChain& chain) {
  const char* kind = chain.kind == TriChain::Kind::ring ? "ring " : (chain.kind == TriChain::Kind::feature ? "feature " : "separator ");
  return kind + std::to_string(chain.index);
}

std::vector<RegionPart> split_into_parts(const Region& region) {
  std::vector<RegionPart> parts(static_cast<std::size_t>(region.num_parts));
  std::vector<int> outer(parts.size(), -1);
  for (std::size_t p = 0; p < parts.size(); ++p) parts[p].part = static_cast<int>(p);
  for (std::size_t r = 0; r < region.rings.size(); ++r) {
    const Ring& ring = region.rings[r];
    parts.at(static_cast<std::size_t>(ring.part)).rings.push_back(static_cast<int>(r));
    if (!ring.hole) outer[static_cast<std::size_t>(ring.part)] = static_cast<int>(r);
  }
  // A point belongs to the part whose outer ring contains it and none of whose holes does.
  auto owner = [&](Vec2 p) {
    for (std::size_t k = 0; k < parts.size(); ++k) {
      if (outer[k] < 0 || !point_in_ring(p, region.rings[static_cast<std::size_t>(outer[k])].points)) continue;
      bool in_hole = false;
      for (int r : parts[k].rings)
        if (region.rings[static_cast<std::size_t>(r)].hole && point_in_ring(p, region.rings[static_cast<std::size_t>(r)].points))
          in_hole = true;
      if (!in_hole) return static_cast<int>(k);
    }
    return -1;
  };
  for (std::size_t f = 0; f < region.features.size(); ++f) {
    const int k = owner(feature_probe(region.features[f]));
    if (k < 0)
      throw InputError(region.source + ": feature curve " + std::to_string(region.features[f].source_feature) +
                       " does not lie inside the domain");
    parts[static_cast<std::size_t>(k)].features.push_back(static_cast<int>(f));
  }
  // A point on a ring (a boundary segment's end point is a ring vertex) belongs to that ring's part; the
  // even-odd test is undecided there.
  auto ring_owner = [&](Vec2 p) {
    for (const Ring& ring : region.rings)
      if (std::find(ring.points.begin(), ring.points.end(), p) != ring.points.end()) return ring.part;
    return owner(p);
  };
  for (std::size_t f = 0; f < region.feature_points.size(); ++f) {
    const int k = ring_owner(region.feature_points[f]);
    if (k >= 0) parts[static_cast<std::size_t>(k)].feature_points.push_back(static_cast<int>(f));
  }
  return parts;
}

namespace {

using EdgeKey = std::pair<const void*, const void*>;
using EdgeSet = std::unordered_set<EdgeKey, PairHash>;

EdgeKey handle_pair(VH a, VH b) {
  const void* pa = &*a;
  const void* pb = &*b;
  return pa < pb ? std::make_pair(pa, pb) : std::make_pair(pb, pa);
}

// A part's constrained triangulation with the handles of every inserted polyline's vertices (input vertices
// flagged), kept to trace the chains after refinement.
struct PartCdt {
  CDT cdt;
  int part = 0;  // for messages
  std::vector<std::vector<VH>> chain_handles;
  std::vector<std::vector<std::uint8_t>> handle_is_input;

  VH insert(Vec2 p) { return cdt.insert(K::Point_2(p.x, p.y)); }

  // Each polyline is inserted with its segments pre-split to boundary_edge, so curves are resolved at the
  // element size while the mesher may grade the interior up to max_edge.
  void insert_polyline(const std::vector<Vec2>& pts, bool closed, double boundary_edge) {
    std::vector<VH> hs;
    std::vector<std::uint8_t> flags;
    const std::size_t nseg = closed ? pts.size() : pts.size() - 1;
    for (std::size_t i = 0; i < pts.size(); ++i) {
      hs.push_back(insert(pts[i]));
      flags.push_back(1);
      if (i >= nseg) continue;
      const Vec2 a = pts[i], b = pts[(i + 1) % pts.size()];
      const auto pieces = static_cast<std::size_t>(std::ceil(distance(a, b) / boundary_edge));
      for (std::size_t k = 1; k < pieces; ++k) {
        hs.push_back(insert(lerp(a, b, static_cast<double>(k) / static_cast<double>(pieces))));
        flags.push_back(0);
      }
    }
    const std::size_t n = closed ? hs.size() : hs.size() - 1;
    for (std::size_t i = 0; i < n; ++i) cdt.insert_constraint(hs[i], hs[(i + 1) % hs.size()]);
    chain_handles.push_back(std::move(hs));
    handle_is_input.push_back(std::move(flags));
  }

  // Trace an input segment through the vertices lying on it (other constraints' end points before refinement,
  // Steiner points after): the constrained edges collinear with it, from a to b.
  void trace(VH a, VH b, std::uint8_t a_is_input, std::vector<VH>& verts, std::vector<std::uint8_t>& is_input) {
    const Vec2 pa{a->point().x(), a->point().y()}, pb{b->point().x(), b->point().y()};
    const double len = distance(pa, pb);
    VH cur = a, prev;
    verts.push_back(a);
    is_input.push_back(a_is_input);
    while (cur != b) {
      VH best;
      double best_d = distance(Vec2{cur->point().x(), cur->point().y()}, pb);
      auto circ = cdt.incident_edges(cur), end = circ;
      do {
        if (cdt.is_infinite(circ) || !cdt.is_constrained(*circ)) continue;
        FH fh = circ->first;
        const int i = circ->second;
        VH w = fh->vertex(CDT::cw(i)) == cur ? fh->vertex(CDT::ccw(i)) : fh->vertex(CDT::cw(i));
        const Vec2 pw{w->point().x(), w->point().y()};
        if (point_segment_distance(pw, pa, pb) > 1e-9 * len) continue;
        const double dw = distance(pw, pb);
        if (dw < best_d) { best_d = dw; best = w; }
      } while (++circ != end);
      if (best == VH())
        throw MeshingError("triangulation of part " + std::to_string(part) + ": lost a constrained segment");
      cur = best;
      if (cur != b) { verts.push_back(cur); is_input.push_back(0); }
    }
  }

  void trace_chain(std::size_t c, bool closed, std::vector<VH>& verts, std::vector<std::uint8_t>& is_input) {
    const auto& hs = chain_handles[c];
    const std::size_t nseg = closed ? hs.size() : hs.size() - 1;
    for (std::size_t i = 0; i < nseg; ++i) trace(hs[i], hs[(i + 1) % hs.size()], handle_is_input[c][i], verts, is_input);
    if (!closed) { verts.push_back(hs.back()); is_input.push_back(1); }
  }

  // Ring edges as they are in the triangulation: a feature ending on a ring splits that ring's segment.
  EdgeSet ring_edges(const std::vector<TriChain>& chains) {
    EdgeSet edges;
    for (std::size_t c = 0; c < chains.size(); ++c) {
      if (chains[c].kind != TriChain::Kind::ring) continue;
      std::vector<VH> verts;
      std::vector<std::uint8_t> flags;
      trace_chain(c, true, verts, flags);
      for (std::size_t i = 0; i < verts.size(); ++i) edges.insert(handle_pair(verts[i], verts[(i + 1) % verts.size()]));
    }
    return edges;
  }

  // Domain = odd nesting depth, counting ring constraints only (feature constraints do not change sides).
  void mark_domain(const EdgeSet& ring_edges) {
    for (auto f = cdt.all_faces_begin(); f != cdt.all_faces_end(); ++f) f->set_in_domain(false);
    std::unordered_map<const void*, int> depth;
    std::deque<std::pair<FH, int>> queue{{cdt.infinite_face(), 0}};
    depth[&*cdt.infinite_face()] = 0;
    while (!queue.empty()) {
      auto [fh, d] = queue.front();
      queue.pop_front();
      fh->set_in_domain(d % 2 == 1);
      for (int i = 0; i < 3; ++i) {
        FH n = fh->neighbor(i);
        if (depth.count(&*n)) continue;
        const bool crosses_ring = fh->is_constrained(i) &&
                                  ring_edges.count(handle_pair(fh->vertex(CDT::cw(i)), fh->vertex(CDT::ccw(i))));
        const int nd = crosses_ring ? d + 1 : d;
        depth[&*n] = nd;
        // Breadth-first by depth: same-depth neighbours first keeps depths minimal.
        if (crosses_ring) queue.emplace_back(n, nd); else queue.emplace_front(n, nd);
      }
    }
  }

  // Refined step by step under a budget: the triangle count follows the geometry (curves split at
  // boundary_edge, interior graded up to max_edge), so no closed-form estimate bounds it; tiny gaps between
  // curves would otherwise refine without end.
  void refine(double area, const TriangulationOptions& options) {
    Mesher mesher(cdt, Criteria(options.shape_bound, options.max_edge));
    mesher.init(true);
    // A graded mesh has a few dozen triangles per curve vertex at most; far more means curves closer than the
    // size (a hole touching a ring), where refinement would run to the memory guard first.
    const double graded = 64.0 * (static_cast<double>(cdt.number_of_vertices()) +
                                  area / (options.max_edge * options.max_edge)) + 10000.0;
    const std::size_t vertex_budget =
        static_cast<std::size_t>(std::min(graded, static_cast<double>(options.max_triangles))) / 2 + 3;
    for (std::size_t step = 1; mesher.try_one_step_refine_mesh(); ++step)
      if (step % 4096 == 0 && cdt.number_of_vertices() > vertex_budget)
        throw MeshingError("triangulation of part " + std::to_string(part) + " needs more than " +
                           std::to_string(2 * vertex_budget) + " triangles (its budget; about " +
                           std::to_string(cdt.number_of_vertices()) + " vertices so far): curves closer to each " +
                           "other than the size, or a size too small for the region");
  }

  // The vertices (numbered into their info) and the domain's triangles.
  TriMesh domain_mesh() {
    TriMesh out;
    std::int32_t next = 0;
    for (auto v = cdt.finite_vertices_begin(); v != cdt.finite_vertices_end(); ++v) {
      v->info() = next++;
      out.vertices.push_back({v->point().x(), v->point().y()});
    }
    for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f) {
      if (!f->is_in_domain()) continue;
      out.triangles.push_back({f->vertex(0)->info(), f->vertex(1)->info(), f->vertex(2)->info()});
    }
    return out;
  }
};

}  // namespace

TriMesh triangulate_part(const Region& region, const RegionPart& part, const TriangulationOptions& options) {
  PartCdt pc;
  pc.part = part.part;
  // Insert every input point once; keep the handles to trace the chains after refinement.
  std::vector<TriChain> chains;
  for (int r : part.rings) {
    pc.insert_polyline(region.rings[static_cast<std::size_t>(r)].points, true, options.boundary_edge);
    chains.push_back({TriChain::Kind::ring, r, true, {}, {}});
  }
  for (int f : part.features) {
    const FeatureCurve& curve = region.features[static_cast<std::size_t>(f)];
    pc.insert_polyline(curve.points, curve.closed, options.boundary_edge);
    chains.push_back({TriChain::Kind::feature, f, curve.closed, {}, {}});
  }
  std::vector<VH> point_handles;
  for (int f : part.feature_points) point_handles.push_back(pc.insert(region.feature_points[static_cast<std::size_t>(f)]));

  pc.mark_domain(pc.ring_edges(chains));
  pc.refine(part_area(region, part), options);
  TriMesh out = pc.domain_mesh();
  for (std::size_t c = 0; c < chains.size(); ++c) {
    std::vector<VH> verts;
    pc.trace_chain(c, chains[c].closed, verts, chains[c].is_input);
    for (VH v : verts) chains[c].vertices.push_back(v->info());
  }
  out.chains = std::move(chains);
  for (VH h : point_handles) out.feature_point_vertices.push_back(h->info());
  if (options.split_constrained_edges) split_constrained_interior_edges(out);
  return out;
}

std::vector<std::uint8_t> corner_vertices(const TriMesh& mesh, const std::vector<Vec2>& positions,
                                          double corner_threshold_deg) {
  std::vector<std::uint8_t> corner(mesh.vertices.size(), 0);
  std::vector<int> appearances(mesh.vertices.size(), 0);
  for (const TriChain& ch : mesh.chains) {
    const int n = static_cast<int>(ch.vertices.size());
    for (int i = 0; i < n; ++i) {
      const std::int32_t v = ch.vertices[i];
      appearances[v]++;
      if (!ch.closed && (i == 0 || i == n - 1)) corner[v] = 1;
      else if (ch.is_input[i] && sharp_turn(positions[ch.vertices[(i + n - 1) % n]], positions[v],
                                            positions[ch.vertices[(i + 1) % n]], corner_threshold_deg))
        corner[v] = 1;
    }
  }
  for (std::int32_t v : mesh.feature_point_vertices) corner[v] = 1;
  for (std::size_t v = 0; v < corner.size(); ++v)
    if (appearances[v] > 1) corner[v] = 1;  // chains meet: a crossing or a feature ending on the boundary
  return corner;
}

}  // namespace polysquare
