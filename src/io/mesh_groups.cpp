#include "polysquare/io/mesh_groups.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <set>
#include <sstream>

#include "polysquare/core/error.h"
#include "polysquare/io/solver_files.h"

namespace polysquare {
namespace {

// Position in `loop` of the node at p: exact if there is one, else the nearest (distance returned).
std::size_t node_in_loop(const QuadMesh& mesh, const BoundaryLoop& loop, Vec2 p, double& moved) {
  std::size_t best = 0;
  moved = INFINITY;
  for (std::size_t i = 0; i < loop.nodes.size(); ++i) {
    const double d = distance(mesh.nodes[static_cast<std::size_t>(loop.nodes[i])], p);
    if (d < moved) moved = d, best = i;
  }
  return best;
}

// Domain name of every quad: connected pieces of the mesh (parts are disjoint) take the name of the polygon part
// holding one of their quads' centre.
std::vector<std::string> quad_domain_names(const QuadMesh& mesh, const Region& region) {
  std::vector<std::int32_t> parent(mesh.nodes.size());
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](std::int32_t v) {
    while (parent[static_cast<std::size_t>(v)] != v) v = parent[static_cast<std::size_t>(v)] = parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(v)])];
    return v;
  };
  for (const auto& q : mesh.quads)
    for (int k = 1; k < 4; ++k) {
      const std::int32_t a = find(q[0]), b = find(q[static_cast<std::size_t>(k)]);
      if (a != b) parent[static_cast<std::size_t>(std::max(a, b))] = std::min(a, b);
    }
  std::map<std::int32_t, std::string> name_of_root;
  std::vector<std::string> out(mesh.quads.size());
  for (std::size_t q = 0; q < mesh.quads.size(); ++q) {
    const std::int32_t root = find(mesh.quads[q][0]);
    auto it = name_of_root.find(root);
    if (it == name_of_root.end()) {
      Vec2 c{0, 0};
      for (auto v : mesh.quads[q]) c = c + mesh.nodes[static_cast<std::size_t>(v)] * 0.25;
      int part = -1;
      for (const Ring& r : region.rings) {
        if (r.hole || !point_in_ring(c, r.points)) continue;
        bool in_hole = false;
        for (const Ring& h : region.rings) in_hole |= h.hole && h.part == r.part && point_in_ring(c, h.points);
        if (!in_hole) { part = r.part; break; }
      }
      std::string name;
      for (const Ring& r : region.rings)
        if (r.part == part && !r.hole) name = r.name;
      if (name.empty()) name = part < 0 ? "domain" : "domain_" + std::to_string(part);
      it = name_of_root.emplace(root, name).first;
    }
    out[q] = it->second;
  }
  return out;
}

// Surfaces: one "domain", or one per named domain (tag 1 for the first; the others are numbered last).
std::vector<SurfaceGroup> surface_groups(const QuadMesh& mesh, const Region* region) {
  std::vector<SurfaceGroup> surfaces;
  bool named_domains = false;
  if (region)
    for (const Ring& r : region->rings) named_domains |= !r.name.empty();
  if (!named_domains) {
    SurfaceGroup s{"domain", 1, {}};
    s.quads.resize(mesh.quads.size());
    std::iota(s.quads.begin(), s.quads.end(), 0);
    surfaces.push_back(std::move(s));
    return surfaces;
  }
  const std::vector<std::string> names = quad_domain_names(mesh, *region);
  std::map<std::string, std::size_t> index;
  for (std::size_t q = 0; q < names.size(); ++q) {
    auto [it, inserted] = index.try_emplace(names[q], surfaces.size());
    if (inserted) surfaces.push_back({names[q], 0, {}});
    surfaces[it->second].quads.push_back(static_cast<std::int32_t>(q));
  }
  if (surfaces.empty()) surfaces.push_back({"domain", 1, {}});
  surfaces[0].tag = 1;
  return surfaces;
}

const BoundaryLoop* loop_of(const std::vector<BoundaryLoop>& loops, int ring) {
  for (const BoundaryLoop& l : loops)
    if (l.ring == ring) return &l;
  return nullptr;
}

// Segment s covers loop positions [first, first + count) as edges (position i: node i to node i + 1).
struct Placed { int segment; int ring; std::size_t first, count; };

std::string segment_label(std::size_t s, const BoundarySegment& b) {
  return "boundary segment " + std::to_string(s) + (b.name.empty() ? "" : " (" + b.name + ")");
}

// The region's boundary segments on the mesh's loops; those that cannot be placed are warnings.
std::vector<Placed> place_segments(const QuadMesh& mesh, const Region& region, const std::vector<BoundaryLoop>& loops,
                                   std::vector<std::string>& warnings) {
  std::vector<Placed> placed;
  for (std::size_t s = 0; s < region.boundary_segments.size(); ++s) {
    const BoundarySegment& b = region.boundary_segments[s];
    const BoundaryLoop* loop = loop_of(loops, b.ring);
    if (!loop || loop->nodes.size() < 2) {
      warnings.push_back(segment_label(s, b) + ": ring " + std::to_string(b.ring) +
                         " is not in the mesh (a part left out?)");
      continue;
    }
    double d0 = 0, d1 = 0;
    const std::size_t i0 = node_in_loop(mesh, *loop, b.start, d0), i1 = node_in_loop(mesh, *loop, b.end, d1);
    for (auto [d, p] : {std::pair{d0, b.start}, std::pair{d1, b.end}})
      if (d > 0)
        warnings.push_back(segment_label(s, b) + ": its end point " + point_text(p) +
                           " is not a mesh node; the nearest boundary node, " + std::to_string(d) + " away, is used");
    const std::size_t n = loop->nodes.size();
    const std::size_t count = b.start == b.end ? n : (i1 + n - i0) % n;
    if (count == 0) {
      warnings.push_back(segment_label(s, b) + " has no mesh edge (its end points meet the same node)");
      continue;
    }
    placed.push_back({static_cast<int>(s), b.ring, i0, count});
  }
  return placed;
}

// The edges of ring r's loop that no segment covers, into c's edges and chains.
void add_uncovered_runs(CurveGroup& c, const BoundaryLoop& loop, const std::vector<Placed>& placed, int r) {
  const std::size_t n = loop.nodes.size();
  std::vector<std::uint8_t> covered(n, 0);
  for (const Placed& p : placed)
    if (p.ring == r)
      for (std::size_t k = 0; k < p.count; ++k) covered[(p.first + k) % n] = 1;
  // Runs of uncovered edges, starting after a covered one so no run wraps around the start.
  std::size_t start = 0;
  while (!covered[start]) ++start;
  std::vector<std::int32_t> run;
  for (std::size_t k = 1; k <= n; ++k) {
    const std::size_t i = (start + k) % n;
    if (!covered[i]) {
      if (run.empty()) run.push_back(loop.nodes[i]);
      run.push_back(loop.nodes[(i + 1) % n]);
      c.edges.push_back({loop.nodes[i], loop.nodes[(i + 1) % n]});
    } else if (!run.empty()) {
      c.chains.push_back(std::move(run));
      run.clear();
    }
  }
  if (!run.empty()) c.chains.push_back(std::move(run));
}

// Rings: the tagged edges of each ring; with segments, the loop's edges that no segment covers.
std::vector<CurveGroup> ring_groups(const QuadMesh& mesh, const std::vector<BoundaryLoop>& loops,
                                    const std::vector<Placed>& placed, int& tag) {
  std::map<int, std::vector<std::array<std::int32_t, 2>>> ring_edges;
  for (std::size_t e = 0; e < mesh.boundary_edges.size() && e < mesh.boundary_edge_ring.size(); ++e)
    ring_edges[mesh.boundary_edge_ring[e]].push_back(mesh.boundary_edges[e]);
  std::vector<CurveGroup> rings;
  for (auto& [r, edges] : ring_edges) {
    CurveGroup c;
    c.name = "boundary_ring_" + std::to_string(r);
    c.tag = tag++;
    c.kind = "land";
    c.ring = r;
    const BoundaryLoop* loop = loop_of(loops, r);
    bool has_segment = false;
    for (const Placed& p : placed) has_segment |= p.ring == r;
    if (!has_segment) {
      c.edges = std::move(edges);
      c.island = loop && loop->inner;
      if (loop) {
        c.chains.push_back(loop->nodes);
        c.chains.back().push_back(loop->nodes.front());
      }
    } else {
      add_uncovered_runs(c, *loop, placed, r);
    }
    rings.push_back(std::move(c));
  }
  return rings;
}

// Features, merged by name.
std::vector<CurveGroup> feature_groups(const QuadMesh& mesh, const Region* region, int& tag) {
  std::map<int, std::vector<std::array<std::int32_t, 2>>> curve_edges;
  for (std::size_t e = 0; e < mesh.feature_edges.size() && e < mesh.feature_edge_curve.size(); ++e)
    curve_edges[mesh.feature_edge_curve[e]].push_back(mesh.feature_edges[e]);
  std::vector<CurveGroup> features;
  std::map<std::string, std::size_t> index;
  for (auto& [c, edges] : curve_edges) {
    const FeatureCurve* curve =
        region && c >= 0 && static_cast<std::size_t>(c) < region->features.size() ? &region->features[static_cast<std::size_t>(c)] : nullptr;
    const std::string name = curve && !curve->name.empty() ? curve->name : "feature_" + std::to_string(c);
    auto [it, inserted] = index.try_emplace(name, features.size());
    if (inserted) {
      CurveGroup f;
      f.name = name;
      f.tag = tag++;
      f.kind = curve ? curve->kind : std::string();
      features.push_back(std::move(f));
    }
    auto& dst = features[it->second].edges;
    dst.insert(dst.end(), edges.begin(), edges.end());
  }
  return features;
}

}  // namespace

std::string segment_group_name(const Region& region, std::size_t s) {
  const std::string& name = region.boundary_segments.at(s).name;
  return name.empty() ? "segment_" + std::to_string(s) : name;
}

std::vector<std::string> open_segment_names(const Region& region) {
  std::vector<std::string> open;
  std::set<std::string> seen;
  for (std::size_t s = 0; s < region.boundary_segments.size(); ++s) {
    const std::string name = segment_group_name(region, s);
    if (seen.insert(name).second && region.boundary_segments[s].kind == "open") open.push_back(name);
  }
  return open;
}

namespace {

// Segments, merged by name.
std::vector<CurveGroup> segment_groups(const Region* region, const std::vector<BoundaryLoop>& loops,
                                       const std::vector<Placed>& placed, int& tag) {
  std::vector<CurveGroup> segments;
  std::map<std::string, std::size_t> index;
  for (const Placed& p : placed) {
    const BoundarySegment& b = region->boundary_segments[static_cast<std::size_t>(p.segment)];
    const std::string name = segment_group_name(*region, static_cast<std::size_t>(p.segment));
    auto [it, inserted] = index.try_emplace(name, segments.size());
    if (inserted) {
      CurveGroup s;
      s.name = name;
      s.tag = tag++;
      s.kind = b.kind.empty() ? "land" : b.kind;
      s.ring = p.ring;
      s.segment = true;
      segments.push_back(std::move(s));
    }
    CurveGroup& s = segments[it->second];
    const BoundaryLoop& loop = *loop_of(loops, p.ring);
    const std::size_t n = loop.nodes.size();
    std::vector<std::int32_t> chain{loop.nodes[p.first % n]};
    for (std::size_t k = 0; k < p.count; ++k) {
      const std::int32_t a = loop.nodes[(p.first + k) % n], b2 = loop.nodes[(p.first + k + 1) % n];
      chain.push_back(b2);
      s.edges.push_back({a, b2});
    }
    s.chains.push_back(std::move(chain));
  }
  return segments;
}

}  // namespace

MeshGroups mesh_groups(const QuadMesh& mesh, const Region* region) {
  MeshGroups g;
  g.surfaces = surface_groups(mesh, region);
  std::vector<BoundaryLoop> loops;
  try {
    loops = boundary_loops(mesh);
  } catch (const MeshingError&) {
    loops.clear();  // not a set of loops (another tool's mesh): groups from the tags only, no chains
  }
  std::vector<Placed> placed;
  if (region) placed = place_segments(mesh, *region, loops, g.warnings);
  int tag = 2;
  g.rings = ring_groups(mesh, loops, placed, tag);
  g.features = feature_groups(mesh, region, tag);
  g.segments = segment_groups(region, loops, placed, tag);
  for (std::size_t k = 1; k < g.surfaces.size(); ++k) g.surfaces[k].tag = tag++;
  return g;
}

// One line naming the physical groups with their tags: domains, segments and named features in full, the rings
// (which may be hundreds on a coast) as a tag range.
std::string format_groups_text(const MeshGroups& g) {
  std::string out = "  groups:";
  for (const SurfaceGroup& s : g.surfaces) out += " " + s.name + " (" + std::to_string(s.tag) + "),";
  if (!g.rings.empty())
    out += " " + std::to_string(g.rings.size()) + " boundary ring(s) (" + std::to_string(g.rings.front().tag) +
           (g.rings.size() > 1 ? "-" + std::to_string(g.rings.back().tag) : std::string()) + "),";
  std::size_t unnamed = 0;
  for (const CurveGroup& c : g.features) {
    if (c.name.rfind("feature_", 0) == 0) ++unnamed;
    else out += " " + c.name + " (" + std::to_string(c.tag) + "),";
  }
  if (unnamed) out += " " + std::to_string(unnamed) + " unnamed feature curve(s),";
  for (const CurveGroup& c : g.segments) out += " " + c.name + " (" + std::to_string(c.tag) + ", " + c.kind + "),";
  out.back() = '\n';
  return out;
}

}  // namespace polysquare
