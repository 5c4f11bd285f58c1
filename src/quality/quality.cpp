#include "polysquare/quality/quality.h"

#include "polysquare/core/quad_topology.h"

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>
#include <oneapi/tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <sstream>
#include <unordered_map>
#include <unordered_set>

#include "polysquare/core/error.h"

namespace polysquare {
namespace {

// f(i) for i in [0, n), in parallel on large meshes. Every f writes only its own element, so the results do not
// depend on the thread count; sums and extremes are taken afterwards in index order.
template <typename F>
void for_each_index(std::size_t n, F&& f) {
  constexpr std::size_t kParallel = 16384;
  if (n < kParallel) {
    for (std::size_t i = 0; i < n; ++i) f(i);
    return;
  }
  oneapi::tbb::parallel_for(oneapi::tbb::blocked_range<std::size_t>(0, n, 4096),
                            [&](const oneapi::tbb::blocked_range<std::size_t>& r) {
                              for (std::size_t i = r.begin(); i != r.end(); ++i) f(i);
                            });
}

Stats stats_of(const std::vector<double>& v) {
  Stats s;
  s.count = v.size();
  if (v.empty()) return s;
  s.min = *std::min_element(v.begin(), v.end());
  s.max = *std::max_element(v.begin(), v.end());
  double sum = 0.0;
  for (double x : v) sum += x;
  s.avg = sum / static_cast<double>(v.size());
  double var = 0.0;
  for (double x : v) var += (x - s.avg) * (x - s.avg);
  s.std = std::sqrt(var / static_cast<double>(v.size()));
  return s;
}

// Uniform grid of segments for nearest-segment queries. The cells' segments are one array (offsets per cell, in
// segment order), not a vector per cell: a mesh of millions of quads gave 16 million cells twice per distance.
struct SegmentGrid {
  std::vector<std::array<Vec2, 2>> segs;
  Box2 box;
  double cell = 1;
  long long nx = 1, ny = 1;
  std::vector<std::size_t> offset;  // cell c holds in_cell[offset[c] .. offset[c + 1])
  std::vector<std::int32_t> in_cell;
  explicit SegmentGrid(std::vector<std::array<Vec2, 2>> s) : segs(std::move(s)) {
    for (const auto& e : segs) { box.add(e[0]); box.add(e[1]); }
    double len = 0;
    for (const auto& e : segs) len += distance(e[0], e[1]);
    // About one cell per segment: cells no smaller than the mean segment, nor than area / count.
    const double n = static_cast<double>(std::max<std::size_t>(1, segs.size()));
    cell = std::max({box.diagonal() * 1e-6, 2.0 * len / n, std::sqrt((box.hi.x - box.lo.x) * (box.hi.y - box.lo.y) / n)});
    nx = std::min(4096LL, static_cast<long long>((box.hi.x - box.lo.x) / cell) + 1);
    ny = std::min(4096LL, static_cast<long long>((box.hi.y - box.lo.y) / cell) + 1);
    cell = std::max((box.hi.x - box.lo.x) / static_cast<double>(nx), (box.hi.y - box.lo.y) / static_cast<double>(ny)) * 1.000001 + 1e-300;
    offset.assign(static_cast<std::size_t>(nx * ny) + 1, 0);
    auto each_cell = [&](std::size_t k, auto&& f) {
      const auto [i0, j0] = idx({std::min(segs[k][0].x, segs[k][1].x), std::min(segs[k][0].y, segs[k][1].y)});
      const auto [i1, j1] = idx({std::max(segs[k][0].x, segs[k][1].x), std::max(segs[k][0].y, segs[k][1].y)});
      for (long long i = i0; i <= i1; ++i)
        for (long long j = j0; j <= j1; ++j) f(static_cast<std::size_t>(j * nx + i));
    };
    for (std::size_t k = 0; k < segs.size(); ++k) each_cell(k, [&](std::size_t c) { offset[c + 1]++; });
    for (std::size_t c = 0; c + 1 < offset.size(); ++c) offset[c + 1] += offset[c];
    in_cell.resize(offset.back());
    std::vector<std::size_t> fill(offset.begin(), offset.end() - 1);
    for (std::size_t k = 0; k < segs.size(); ++k) each_cell(k, [&](std::size_t c) { in_cell[fill[c]++] = static_cast<std::int32_t>(k); });
  }
  std::pair<long long, long long> idx(Vec2 p) const {
    return {std::clamp(static_cast<long long>((p.x - box.lo.x) / cell), 0LL, nx - 1),
            std::clamp(static_cast<long long>((p.y - box.lo.y) / cell), 0LL, ny - 1)};
  }
  // Distance to the nearest segment: grows rings of cells until the ring distance exceeds the best found.
  double nearest(Vec2 p) const {
    if (segs.empty()) return INFINITY;
    const auto [ci, cj] = idx(p);
    double best = INFINITY;
    for (long long r = 0; r <= std::max(nx, ny); ++r) {
      for (long long i = ci - r; i <= ci + r; ++i)
        for (long long j = cj - r; j <= cj + r; ++j) {
          if (std::max(std::llabs(i - ci), std::llabs(j - cj)) != r || i < 0 || j < 0 || i >= nx || j >= ny) continue;
          const auto c = static_cast<std::size_t>(j * nx + i);
          for (std::size_t at = offset[c]; at < offset[c + 1]; ++at) {
            const auto k = static_cast<std::size_t>(in_cell[at]);
            best = std::min(best, point_segment_distance(p, segs[k][0], segs[k][1]));
          }
        }
      // A segment not met yet crosses only cells of later rings, which are at least r cells away.
      if (best <= static_cast<double>(r) * cell) break;
    }
    return best;
  }
};

}  // namespace

QuadMetrics quad_metrics(const QuadMesh& mesh) {
  QuadMetrics m;
  const std::size_t n = mesh.quads.size();
  m.sj.resize(n); m.eta.resize(n); m.skew.resize(n); m.edge_ratio.resize(n);
  for_each_index(n, [&](std::size_t q) {
    const auto& quad = mesh.quads[q];
    double mn = INFINITY, sum = 0, amin = INFINITY, amax = -INFINITY, lmin = INFINITY, lmax = 0;
    bool degenerate = false;
    for (int k = 0; k < 4; ++k) {
      const Vec2 p = mesh.nodes[quad[k]];
      const Vec2 en = mesh.nodes[quad[(k + 1) % 4]] - p, ep = mesh.nodes[quad[(k + 3) % 4]] - p;
      const double ln = norm(en), lp = norm(ep);
      if (!std::isfinite(ln) || !std::isfinite(lp)) { degenerate = true; continue; }  // NaN compares false below
      lmin = std::min(lmin, ln);
      lmax = std::max(lmax, ln);
      if (ln == 0 || lp == 0) { degenerate = true; continue; }
      const double c = cross(en, ep) / (ln * lp);
      mn = std::min(mn, c);
      sum += c;
      // Interior angle in degrees, in (0, 360): reflex when the corner is inverted.
      double ang = std::atan2(cross(en, ep), dot(en, ep)) * 180.0 / std::numbers::pi;
      if (ang < 0) ang += 360.0;
      amin = std::min(amin, ang);
      amax = std::max(amax, ang);
    }
    if (degenerate) {
      m.sj[q] = m.eta[q] = -1.0;
      m.skew[q] = 1.0;
      m.edge_ratio[q] = 1e300;
      return;
    }
    m.sj[q] = mn;
    m.eta[q] = sum / 4.0;
    m.skew[q] = std::max((amax - 90.0) / 90.0, (90.0 - amin) / 90.0);
    m.edge_ratio[q] = lmax / lmin;
  });
  return m;
}

namespace {

// SCHISM's angle ratio of one quad (quality.h, SchismQuadQuality): smallest over largest interior angle when every
// corner turns counter-clockwise by less than 180 degrees, else 0 (fix_bad_quads.f90 splits such a quad anyway).
double schism_angle_ratio(const QuadMesh& mesh, const std::array<std::int32_t, 4>& quad) {
  double smallest = INFINITY, largest = 0.0;
  for (int k = 0; k < 4; ++k) {
    const Vec2 p = mesh.nodes[quad[k]];
    const Vec2 next = mesh.nodes[quad[(k + 1) % 4]] - p, prev = mesh.nodes[quad[(k + 3) % 4]] - p;
    if (!(norm(next) > 0) || !(norm(prev) > 0)) return 0.0;  // a zero-length (or non-finite) side
    const double turn = cross(next, prev);
    if (!(turn > 0)) return 0.0;  // a straight, reflex or inverted corner: not a convex quad
    const double angle = std::atan2(turn, dot(next, prev));  // in (0, pi)
    smallest = std::min(smallest, angle);
    largest = std::max(largest, angle);
  }
  return smallest / largest;
}

// Longest over shortest side; 1e300 for a zero-length or non-finite side (as QuadMetrics::edge_ratio).
double side_ratio(const QuadMesh& mesh, const std::array<std::int32_t, 4>& quad) {
  double shortest = INFINITY, longest = 0.0;
  for (int k = 0; k < 4; ++k) {
    const double l = distance(mesh.nodes[quad[k]], mesh.nodes[quad[(k + 1) % 4]]);
    if (!std::isfinite(l)) return 1e300;
    shortest = std::min(shortest, l);
    longest = std::max(longest, l);
  }
  return shortest > 0 ? longest / shortest : 1e300;
}

Vec2 quad_centre(const QuadMesh& mesh, const std::array<std::int32_t, 4>& quad) {
  return 0.25 * (mesh.nodes[quad[0]] + mesh.nodes[quad[1]] + mesh.nodes[quad[2]] + mesh.nodes[quad[3]]);
}

}  // namespace

std::vector<double> schism_angle_ratios(const QuadMesh& mesh) {
  std::vector<double> r(mesh.quads.size());
  for_each_index(mesh.quads.size(), [&](std::size_t q) { r[q] = schism_angle_ratio(mesh, mesh.quads[q]); });
  return r;
}

SchismQuadQuality schism_quad_quality(const QuadMesh& mesh, double angle_ratio_limit, double aspect_ratio_limit) {
  SchismQuadQuality r;
  r.angle_ratio_limit = angle_ratio_limit;
  r.aspect_ratio_limit = aspect_ratio_limit;
  const std::vector<double> angle = schism_angle_ratios(mesh);
  std::vector<double> aspect(mesh.quads.size());
  for_each_index(mesh.quads.size(), [&](std::size_t q) { aspect[q] = side_ratio(mesh, mesh.quads[q]); });
  double worst_angle = INFINITY, worst_aspect = -INFINITY;
  for (std::size_t q = 0; q < mesh.quads.size(); ++q) {
    const bool angle_fails = angle[q] < angle_ratio_limit, aspect_fails = aspect[q] > aspect_ratio_limit;
    r.non_convex += angle[q] == 0.0;
    r.angle_ratio_below += angle_fails;
    r.aspect_ratio_above += aspect_fails;
    r.failing += angle_fails || aspect_fails;
    if (angle[q] < worst_angle) { worst_angle = angle[q]; r.angle_ratio_worst_at = quad_centre(mesh, mesh.quads[q]); }
    if (aspect[q] > worst_aspect) { worst_aspect = aspect[q]; r.aspect_ratio_worst_at = quad_centre(mesh, mesh.quads[q]); }
  }
  r.angle_ratio = stats_of(angle);
  r.aspect_ratio = stats_of(aspect);
  return r;
}

nlohmann::json to_json(const SchismQuadQuality& q) {
  auto st = [](const Stats& s) { return nlohmann::json{{"min", s.min}, {"avg", s.avg}, {"max", s.max}, {"std", s.std}}; };
  return {{"angle_ratio", st(q.angle_ratio)}, {"angle_ratio_limit", q.angle_ratio_limit},
          {"angle_ratio_below_limit", q.angle_ratio_below},
          {"angle_ratio_worst_at", {q.angle_ratio_worst_at.x, q.angle_ratio_worst_at.y}},
          {"aspect_ratio", st(q.aspect_ratio)}, {"aspect_ratio_limit", q.aspect_ratio_limit},
          {"aspect_ratio_above_limit", q.aspect_ratio_above},
          {"aspect_ratio_worst_at", {q.aspect_ratio_worst_at.x, q.aspect_ratio_worst_at.y}},
          {"non_convex", q.non_convex}, {"failing", q.failing}};
}

namespace {

// A worst place of the one-line summaries: "x, y" with 10 significant digits, or as `place` writes it.
std::string bare_place(Vec2 p, const PlaceWriter& place) {
  if (place) return place(p);
  std::ostringstream os;
  os.precision(10);
  os << p.x << ", " << p.y;
  return os.str();
}

}  // namespace

std::string format_schism_text(const SchismQuadQuality& q, const PlaceWriter& place) {
  std::ostringstream os;
  os.precision(4);
  os << "  SCHISM quad checks: angle ratio (min / max interior angle) min " << q.angle_ratio.min << " avg "
     << q.angle_ratio.avg << ", " << q.angle_ratio_below << " below " << q.angle_ratio_limit;
  if (q.non_convex > 0) os << " (" << q.non_convex << " not convex)";
  os << "; aspect ratio (longest / shortest side) max " << q.aspect_ratio.max << ", " << q.aspect_ratio_above
     << " above " << q.aspect_ratio_limit << "; " << q.failing << " quads fail either";
  if (q.failing > 0) {
    if (q.angle_ratio_below > 0) os << " (worst angle ratio at " << bare_place(q.angle_ratio_worst_at, place) << ")";
    if (q.aspect_ratio_above > 0) os << " (worst aspect ratio at " << bare_place(q.aspect_ratio_worst_at, place) << ")";
  }
  os << "\n";
  return os.str();
}

QualityReport compute_quality(const QuadMesh& mesh) { return compute_quality(mesh, quad_metrics(mesh)); }

double mesh_area(const QuadMesh& mesh) {
  double a = 0.0;
  for (const auto& q : mesh.quads) {
    const Vec2 o = mesh.nodes[q[0]];
    a += 0.5 * cross(mesh.nodes[q[2]] - o, mesh.nodes[q[3]] - mesh.nodes[q[1]]);
  }
  return a;
}

double domain_area(const Region& region, const std::vector<int>& skip_parts) {
  double a = 0.0;
  for (const Ring& r : region.rings) {
    if (std::find(skip_parts.begin(), skip_parts.end(), r.part) != skip_parts.end() || r.points.empty()) continue;
    const double s = std::abs(ring_signed_area(r.points));
    a += r.hole ? -s : s;
  }
  return a;
}

double area_relative_mismatch(const QuadMesh& mesh, const Region& region, const std::vector<int>& skip_parts) {
  const double r = domain_area(region, skip_parts);
  return r != 0 ? (mesh_area(mesh) - r) / r : INFINITY;
}

void check_judgeable(const QuadMesh& mesh, const std::string& name) {
  auto check_node = [&](std::int32_t v) {
    const Vec2 p = mesh.nodes[static_cast<std::size_t>(v)];
    if (!std::isfinite(p.x) || !std::isfinite(p.y)) {
      std::ostringstream os;
      os << name << ": node " << v + 1 << " has a non-finite coordinate (" << p.x << ", " << p.y << ")";
      throw InputError(os.str());
    }
  };
  for (const auto& q : mesh.quads) for (auto v : q) check_node(v);
  for (const auto& t : mesh.triangles) for (auto v : t) check_node(v);
  if (mesh.quads.empty())
    throw InputError(name + ": the mesh has no quadrilaterals (" + std::to_string(mesh.triangles.size()) +
                     " triangles, " + std::to_string(mesh.nodes.size()) + " nodes): there is nothing to judge");
}

QualityReport compute_quality(const QuadMesh& mesh, const QuadMetrics& m, std::vector<std::uint8_t>* interior_singular) {
  QualityReport r;
  r.nodes = mesh.nodes.size();
  r.quads = mesh.quads.size();
  r.triangles = mesh.triangles.size();
  r.sj = stats_of(m.sj);
  r.eta = stats_of(m.eta);
  r.skew = stats_of(m.skew);
  r.edge_ratio = stats_of(m.edge_ratio);
  r.inverted = static_cast<std::size_t>(std::count_if(m.sj.begin(), m.sj.end(), [](double v) { return v <= 0; }));
  // Valence and boundary over the quads only, as the Gmsh reference figures of data/cases/PROVENANCE.md count
  // Gmsh's meshes (their few leftover triangles are reported separately, not counted into valences).
  const auto edge_counts = quad_edge_counts(mesh);
  for (const auto& [key, count] : edge_counts) {
    r.boundary_edges += count == 1;
    r.non_manifold_edges += count > 2;
  }
  const NodeValences nv = node_valences(mesh, edge_counts);
  const std::vector<int>& valence = nv.valence;
  const std::vector<std::uint8_t>& on_boundary = nv.on_boundary;
  if (interior_singular) interior_singular->assign(mesh.nodes.size(), 0);
  for (std::size_t v = 0; v < mesh.nodes.size(); ++v) {
    if (valence[v] == 0) continue;  // a node of no quad
    if (on_boundary[v] && valence[v] != 3) r.boundary_singularities++;
    if (!on_boundary[v] && valence[v] != 4) {
      r.interior_singularities++;
      if (interior_singular) (*interior_singular)[v] = 1;
    }
  }
  r.singularities = r.boundary_singularities + r.interior_singularities;
  std::size_t regular = 0;
  for (const auto& q : mesh.quads)
    regular += std::none_of(q.begin(), q.end(), [&](std::int32_t v) { return !on_boundary[v] && valence[v] != 4; });
  const double quads = static_cast<double>(std::max<std::size_t>(mesh.quads.size(), 1));
  r.regular_quad_fraction = static_cast<double>(regular) / quads;
  r.sj_below_0_3_fraction = static_cast<double>(std::count_if(m.sj.begin(), m.sj.end(), [](double v) { return v < 0.3; })) / quads;
  r.schism = schism_quad_quality(mesh);
  return r;
}

DomainDistance domain_distance(const QuadMesh& mesh, const Region& region, const DomainDistanceOptions& options) {
  DomainDistance d;
  std::vector<std::array<Vec2, 2>> ring_segs, feature_segs, mesh_edges;
  double region_area = 0;
  auto skipped = [&](const Ring& r) {
    return std::find(options.skip_parts.begin(), options.skip_parts.end(), r.part) != options.skip_parts.end();
  };
  for (const Ring& r : region.rings) {
    if (skipped(r)) continue;
    for (std::size_t i = 0; i < r.points.size(); ++i) ring_segs.push_back({r.points[i], r.points[(i + 1) % r.points.size()]});
    const double s = std::abs(ring_signed_area(r.points));
    region_area += r.hole ? -s : s;
  }
  for (const FeatureCurve& f : region.features) {
    const std::size_t m = f.closed ? f.points.size() : f.points.size() - 1;
    for (std::size_t i = 0; i < m; ++i) feature_segs.push_back({f.points[i], f.points[(i + 1) % f.points.size()]});
  }
  // Every edge once (the table the finite-volume checks use); an edge of one cell is on the boundary.
  const EdgeTable table = edge_table(mesh);
  std::vector<std::uint8_t> on_boundary(mesh.nodes.size(), 0);
  mesh_edges.reserve(table.nodes.size());
  for (std::size_t e = 0; e < table.nodes.size(); ++e) {
    const auto [a, b] = table.nodes[e];
    mesh_edges.push_back({mesh.nodes[static_cast<std::size_t>(a)], mesh.nodes[static_cast<std::size_t>(b)]});
    if (table.faces[e][1] < 0) on_boundary[static_cast<std::size_t>(a)] = on_boundary[static_cast<std::size_t>(b)] = 1;
  }
  const SegmentGrid rings(ring_segs);
  std::vector<double> boundary_distance(mesh.nodes.size(), 0.0);
  for_each_index(mesh.nodes.size(), [&](std::size_t v) {
    if (on_boundary[v]) boundary_distance[v] = rings.nearest(mesh.nodes[v]);
  });
  for (double dist : boundary_distance) d.boundary_max_distance = std::max(d.boundary_max_distance, dist);
  const double diag = region.bounding_box().diagonal();
  d.boundary_max_relative = diag > 0 ? d.boundary_max_distance / diag : 0;
  if (!feature_segs.empty()) {
    const SegmentGrid edges(std::move(mesh_edges));
    // Nine points along each feature segment, measured in parallel, the farthest taken in order.
    std::vector<double> dist(9 * feature_segs.size());
    auto sample = [&](std::size_t i) { return lerp(feature_segs[i / 9][0], feature_segs[i / 9][1], static_cast<double>(i % 9) / 8.0); };
    for_each_index(dist.size(), [&](std::size_t i) { dist[i] = edges.nearest(sample(i)); });
    for (std::size_t i = 0; i < dist.size(); ++i)
      if (dist[i] > d.feature_max_distance) { d.feature_max_distance = dist[i]; d.feature_max_at = sample(i); }
    const SegmentGrid features(feature_segs);
    for (const auto& e : mesh.feature_edges)
      for (auto v : e) {
        const double dist = features.nearest(mesh.nodes[v]);
        if (dist > d.feature_node_max_distance) { d.feature_node_max_distance = dist; d.feature_node_max_at = mesh.nodes[v]; }
      }
  }
  // Areas relative to a cell's own nodes: products of absolute coordinates far from the origin cancel.
  double mesh_area = polysquare::mesh_area(mesh);
  for (const auto& t : mesh.triangles) mesh_area += 0.5 * orient2(mesh.nodes[t[0]], mesh.nodes[t[1]], mesh.nodes[t[2]]);
  d.area_relative_change = region_area != 0 ? (mesh_area - region_area) / region_area : 0;
  // Sharp input vertices must coincide with a mesh node.
  std::vector<std::array<Vec2, 2>> node_points;
  for (Vec2 p : mesh.nodes) node_points.push_back({p, p});
  const SegmentGrid nodes(node_points);
  for (const Ring& r : region.rings) {
    if (skipped(r)) continue;
    const std::size_t n = r.points.size();
    for (std::size_t i = 0; i < n; ++i) {
      if (!sharp_turn(r.points[(i + n - 1) % n], r.points[i], r.points[(i + 1) % n], options.corner_threshold_deg)) continue;
      d.sharp_vertices_total++;
      if (nodes.nearest(r.points[i]) > 1e-9 * diag) d.sharp_vertices_missing++;
    }
  }
  return d;
}

std::vector<std::uint8_t> quads_pinned_by_sharp_input(const QuadMesh& mesh, double below, double reach) {
  std::vector<std::uint8_t> pinned(mesh.quads.size(), 0);
  if (mesh.node_kind.size() != mesh.nodes.size()) return pinned;
  std::unordered_set<std::uint64_t> curve;
  std::vector<std::vector<std::int32_t>> along(mesh.nodes.size());  // curve neighbours of corner nodes
  for (const auto* edges : {&mesh.boundary_edges, &mesh.feature_edges})
    for (const auto& e : *edges) {
      curve.insert(edge_key(e[0], e[1]));
      for (int s = 0; s < 2; ++s)
        if (mesh.node_kind[e[s]] == NodeKind::corner) along[e[s]].push_back(e[1 - s]);
    }
  for (std::size_t qi = 0; qi < mesh.quads.size(); ++qi) {
    const auto& q = mesh.quads[qi];
    for (int k = 0; k < 4 && !pinned[qi]; ++k) {
      const std::int32_t v = q[k], next = q[(k + 1) % 4], prev = q[(k + 3) % 4];
      if (mesh.node_kind[v] != NodeKind::corner) continue;
      // Only acute corners: an obtuse one could be split between two quads.
      const Vec2 p = mesh.nodes[v], en = mesh.nodes[next] - p, ep = mesh.nodes[prev] - p;
      const double l = norm(en) * norm(ep);
      if (!(l > 0) || dot(en, ep) <= 0.0 || cross(en, ep) / l >= below) continue;
      pinned[qi] = curve.count(edge_key(v, next)) && curve.count(edge_key(v, prev));
    }
  }
  if (!(reach > 0)) return pinned;
  // Inside a wedge between two curves meeting at less than asin(below), within `reach` of its tip, the gap is
  // narrower than below * reach: the quads there (a river meeting the shoreline at 3 degrees) span it whatever
  // the mesher does. Each wedge is walked from its tip through the quads whose centre lies inside it.
  std::vector<std::vector<std::int32_t>> quads_of(mesh.nodes.size());
  for (std::size_t qi = 0; qi < mesh.quads.size(); ++qi)
    for (auto v : mesh.quads[qi]) quads_of[v].push_back(static_cast<std::int32_t>(qi));
  auto centre = [&](std::int32_t qi) {
    const auto& q = mesh.quads[static_cast<std::size_t>(qi)];
    return 0.25 * (mesh.nodes[q[0]] + mesh.nodes[q[1]] + mesh.nodes[q[2]] + mesh.nodes[q[3]]);
  };
  std::vector<std::uint8_t> seen(mesh.quads.size(), 0);
  for (std::size_t v = 0; v < mesh.nodes.size(); ++v) {
    if (along[v].size() < 2) continue;
    const Vec2 tip = mesh.nodes[v];
    std::vector<double> dirs;
    for (auto w : along[v]) dirs.push_back(std::atan2(mesh.nodes[w].y - tip.y, mesh.nodes[w].x - tip.x));
    std::sort(dirs.begin(), dirs.end());
    for (std::size_t i = 0; i < dirs.size(); ++i) {
      const double from = dirs[i];
      double gap = (i + 1 < dirs.size() ? dirs[i + 1] : dirs[0] + 2 * std::numbers::pi) - from;
      if (!(gap > 0) || gap >= 0.5 * std::numbers::pi || std::sin(gap) >= below) continue;
      auto inside = [&](std::int32_t qi) {
        const Vec2 c = centre(qi) - tip;
        if (norm(c) > reach) return false;
        double a = std::atan2(c.y, c.x) - from;
        a -= 2 * std::numbers::pi * std::floor(a / (2 * std::numbers::pi));
        return a > 0 && a < gap;
      };
      std::vector<std::int32_t> stack, visited;
      for (auto qi : quads_of[v])
        if (inside(qi)) stack.push_back(qi);
      while (!stack.empty()) {
        const std::int32_t qi = stack.back();
        stack.pop_back();
        if (seen[static_cast<std::size_t>(qi)]) continue;
        seen[static_cast<std::size_t>(qi)] = 1;
        visited.push_back(qi);
        pinned[static_cast<std::size_t>(qi)] = 1;
        for (auto w : mesh.quads[static_cast<std::size_t>(qi)])
          for (auto qj : quads_of[w])
            if (!seen[static_cast<std::size_t>(qj)] && inside(qj)) stack.push_back(qj);
      }
      for (auto qi : visited) seen[static_cast<std::size_t>(qi)] = 0;
    }
  }
  return pinned;
}

namespace {
// Faces: quads first, then triangles.
std::size_t face_count(const QuadMesh& m) { return m.quads.size() + m.triangles.size(); }
int face_size(const QuadMesh& m, std::size_t f) { return f < m.quads.size() ? 4 : 3; }
std::int32_t face_node(const QuadMesh& m, std::size_t f, int k) {
  return f < m.quads.size() ? m.quads[f][static_cast<std::size_t>(k)]
                            : m.triangles[f - m.quads.size()][static_cast<std::size_t>(k)];
}
double face_area(const QuadMesh& m, std::size_t f) {
  const int n = face_size(m, f);
  double s = 0;
  for (int k = 0; k < n; ++k) s += cross(m.nodes[face_node(m, f, k)], m.nodes[face_node(m, f, (k + 1) % n)]);
  return 0.5 * s;
}
}  // namespace

EdgeTable edge_table(const QuadMesh& mesh) {
  // Every side of every face at its scan position (faces in order, sides in order), sorted by edge and position:
  // an edge's first entry is where it first appears (its node order and first face), its second entry the second
  // face. Then the edges in order of first appearance: the table a hash map filled in scan order gives, from
  // sorts that run in parallel and allocate nothing per edge.
  const std::size_t nq = mesh.quads.size(), nf = face_count(mesh);
  auto position = [&](std::size_t f) { return f < nq ? 4 * f : 4 * nq + 3 * (f - nq); };
  auto face_of = [&](std::size_t at) { return at < 4 * nq ? at / 4 : nq + (at - 4 * nq) / 3; };
  std::vector<std::pair<std::uint64_t, std::uint64_t>> sides(position(nf));  // (edge key, scan position)
  for_each_index(nf, [&](std::size_t f) {
    const int n = face_size(mesh, f);
    for (int k = 0; k < n; ++k)
      sides[position(f) + static_cast<std::size_t>(k)] = {edge_key(face_node(mesh, f, k), face_node(mesh, f, (k + 1) % n)),
                                                          position(f) + static_cast<std::size_t>(k)};
  });
  oneapi::tbb::parallel_sort(sides.begin(), sides.end());
  struct Edge {
    std::uint64_t first;  // scan position of the first appearance
    std::int32_t second;  // face of the second appearance, -1 when none
  };
  std::vector<Edge> edges;
  edges.reserve(sides.size() / 2 + 4);
  for (std::size_t i = 0; i < sides.size();) {
    std::size_t j = i + 1;
    while (j < sides.size() && sides[j].first == sides[i].first) ++j;
    edges.push_back({sides[i].second, j > i + 1 ? static_cast<std::int32_t>(face_of(sides[i + 1].second)) : -1});
    i = j;
  }
  oneapi::tbb::parallel_sort(edges.begin(), edges.end(), [](const Edge& a, const Edge& b) { return a.first < b.first; });
  EdgeTable t;
  t.nodes.resize(edges.size());
  t.faces.resize(edges.size());
  for_each_index(edges.size(), [&](std::size_t e) {
    const std::size_t at = edges[e].first, f = face_of(at);
    const int n = face_size(mesh, f), k = static_cast<int>(at - position(f));
    t.nodes[e] = {face_node(mesh, f, k), face_node(mesh, f, (k + 1) % n)};
    t.faces[e] = {static_cast<std::int32_t>(f), edges[e].second};
  });
  return t;
}

std::vector<Vec2> face_circumcentres(const QuadMesh& mesh, const EdgeTable& edges) {
  const std::size_t nf = face_count(mesh);
  // Interior sides of each face, as (midpoint, unit direction), in edge order: face f's are
  // side[first[f]] .. side[first[f + 1] - 1] (one array for all faces, not a list per face).
  std::vector<std::size_t> first(nf + 1, 0);
  // Each interior edge's length once (0 on the boundary): it decides which edges count and scales their direction.
  std::vector<double> length(edges.nodes.size(), 0.0);
  for_each_index(edges.nodes.size(), [&](std::size_t e) {
    if (edges.faces[e][1] >= 0) length[e] = distance(mesh.nodes[edges.nodes[e][0]], mesh.nodes[edges.nodes[e][1]]);
  });
  for (std::size_t e = 0; e < edges.nodes.size(); ++e)
    if (length[e] > 0)
      for (auto f : edges.faces[e]) first[static_cast<std::size_t>(f) + 1]++;
  for (std::size_t f = 0; f < nf; ++f) first[f + 1] += first[f];
  std::vector<std::pair<Vec2, Vec2>> side(first[nf]);
  {
    std::vector<std::size_t> fill(first.begin(), first.end() - 1);
    for (std::size_t e = 0; e < edges.nodes.size(); ++e) {
      if (!(length[e] > 0)) continue;
      const Vec2 a = mesh.nodes[edges.nodes[e][0]], b = mesh.nodes[edges.nodes[e][1]];
      for (auto f : edges.faces[e]) side[fill[static_cast<std::size_t>(f)]++] = {0.5 * (a + b), (1.0 / length[e]) * (b - a)};
    }
  }
  std::vector<Vec2> centres(nf);
  for_each_index(nf, [&](std::size_t f) {
    const int n = face_size(mesh, f);
    const std::size_t sides = first[f + 1] - first[f];
    std::array<Vec2, 4> poly;
    Vec2 mean{0, 0};
    for (int k = 0; k < n; ++k) {
      poly[static_cast<std::size_t>(k)] = mesh.nodes[face_node(mesh, f, k)];
      mean = mean + poly[static_cast<std::size_t>(k)];
    }
    mean = (1.0 / n) * mean;
    Vec2 c = mean;
    if (n == 3) {
      const Vec2 d1 = poly[1] - poly[0], d2 = poly[2] - poly[0];
      const double den = 2 * cross(d1, d2);
      if (den != 0)
        c = poly[0] + (1.0 / den) * Vec2{d2.y * dot(d1, d1) - d1.y * dot(d2, d2), d1.x * dot(d2, d2) - d2.x * dot(d1, d1)};
    } else if (sides == 0) {
      // Centroid of the area (a face with no neighbour carries no link).
      const double area = face_area(mesh, f);
      if (area != 0) {
        Vec2 s{0, 0};
        for (int k = 0; k < n; ++k) {
          const Vec2 p = poly[static_cast<std::size_t>(k)], q = poly[static_cast<std::size_t>((k + 1) % n)];
          s = s + cross(p, q) * (p + q);
        }
        c = (1.0 / (6 * area)) * s;
      }
    } else if (sides >= 2) {
      for (int iter = 0; iter < 100; ++iter) {
        const Vec2 previous = c;
        for (std::size_t i = first[f]; i < first[f + 1]; ++i) {
          const auto& [mid, dir] = side[i];
          c = c + (-0.1 * dot(previous - mid, dir)) * dir;
        }
        if (iter > 0 && distance(c, previous) < 1e-15) break;
      }
    }
    if (!point_in_ring(c, poly.data(), static_cast<std::size_t>(n))) {
      // Back along mean -> c to the first side it crosses.
      double best = INFINITY;
      const Vec2 d = c - mean;
      for (int k = 0; k < n; ++k) {
        const Vec2 p = poly[static_cast<std::size_t>(k)], q = poly[static_cast<std::size_t>((k + 1) % n)];
        const double den = cross(d, q - p);
        if (den == 0) continue;
        const double t = cross(p - mean, q - p) / den, u = cross(p - mean, d) / den;
        if (t >= 0 && t <= 1 && u >= 0 && u <= 1) best = std::min(best, t);
      }
      if (best <= 1) c = mean + best * d;
    }
    centres[f] = c;
  });
  return centres;
}

std::vector<double> edge_orthogonality(const QuadMesh& mesh, const EdgeTable& edges, const std::vector<Vec2>& centres) {
  std::vector<double> o(edges.nodes.size(), -1.0);
  for_each_index(edges.nodes.size(), [&](std::size_t e) {
    if (edges.faces[e][1] < 0) return;
    const Vec2 t = mesh.nodes[edges.nodes[e][1]] - mesh.nodes[edges.nodes[e][0]];
    const Vec2 link = centres[static_cast<std::size_t>(edges.faces[e][1])] - centres[static_cast<std::size_t>(edges.faces[e][0])];
    const double l = norm(t) * norm(link);
    // Coinciding centres give no direction: counted as the worst (1), as the solver cannot use that link.
    o[e] = l > 0 ? std::min(1.0, std::abs(dot(t, link)) / l) : 1.0;
  });
  return o;
}

FiniteVolumeQuality finite_volume_quality(const QuadMesh& mesh, double orthogonality_limit) {
  FiniteVolumeQuality r;
  r.orthogonality_limit = orthogonality_limit;
  const EdgeTable edges = edge_table(mesh);
  const std::vector<Vec2> centres = face_circumcentres(mesh, edges);
  const std::vector<double> ortho = edge_orthogonality(mesh, edges, centres);
  std::vector<double> o, s;
  double worst_o = -1, worst_s = -1;
  for (std::size_t e = 0; e < edges.nodes.size(); ++e) {
    if (edges.faces[e][1] < 0) continue;
    const Vec2 mid = 0.5 * (mesh.nodes[edges.nodes[e][0]] + mesh.nodes[edges.nodes[e][1]]);
    o.push_back(ortho[e]);
    if (ortho[e] > orthogonality_limit) r.orthogonality_above++;
    if (ortho[e] > worst_o) { worst_o = ortho[e]; r.orthogonality_worst_at = mid; }
    const double a = std::abs(face_area(mesh, static_cast<std::size_t>(edges.faces[e][0])));
    const double b = std::abs(face_area(mesh, static_cast<std::size_t>(edges.faces[e][1])));
    const double ratio = std::min(a, b) > 0 ? std::max(a, b) / std::min(a, b) : INFINITY;
    s.push_back(ratio);
    if (ratio > worst_s) { worst_s = ratio; r.smoothness_worst_at = mid; }
  }
  r.interior_edges = o.size();
  r.orthogonality = stats_of(o);
  r.smoothness = stats_of(s);
  return r;
}

nlohmann::json to_json(const FiniteVolumeQuality& q) {
  auto st = [](const Stats& s) { return nlohmann::json{{"min", s.min}, {"avg", s.avg}, {"max", s.max}, {"std", s.std}}; };
  return {{"interior_edges", q.interior_edges}, {"orthogonality", st(q.orthogonality)},
          {"orthogonality_limit", q.orthogonality_limit}, {"orthogonality_above_limit", q.orthogonality_above},
          {"orthogonality_worst_at", {q.orthogonality_worst_at.x, q.orthogonality_worst_at.y}},
          {"smoothness", st(q.smoothness)},
          {"smoothness_worst_at", {q.smoothness_worst_at.x, q.smoothness_worst_at.y}}};
}

std::string format_finite_volume_text(const FiniteVolumeQuality& q, const PlaceWriter& place) {
  std::ostringstream os;
  os.precision(4);
  os << "  finite volume (D-Flow FM, " << q.interior_edges << " interior edges): orthogonality max "
     << q.orthogonality.max << " avg " << q.orthogonality.avg << ", " << q.orthogonality_above << " above "
     << q.orthogonality_limit;
  os << " (worst at " << bare_place(q.orthogonality_worst_at, place) << ")";
  os << "; smoothness (area ratio) max " << q.smoothness.max << " avg " << q.smoothness.avg << "\n";
  return os.str();
}

nlohmann::json to_json(const QualityReport& q) {
  auto st = [](const Stats& s) { return nlohmann::json{{"min", s.min}, {"avg", s.avg}, {"max", s.max}, {"std", s.std}}; };
  return {{"nodes", q.nodes}, {"quads", q.quads}, {"triangles", q.triangles}, {"inverted", q.inverted},
          {"non_manifold_edges", q.non_manifold_edges}, {"boundary_edges", q.boundary_edges},
          {"sj", st(q.sj)}, {"eta", st(q.eta)}, {"skew", st(q.skew)}, {"edge_ratio", st(q.edge_ratio)},
          {"singularities", q.singularities}, {"interior_singularities", q.interior_singularities},
          {"boundary_singularities", q.boundary_singularities}, {"regular_quad_fraction", q.regular_quad_fraction},
          {"sj_below_0_3_fraction", q.sj_below_0_3_fraction}, {"schism", to_json(q.schism)}};
}

nlohmann::json to_json(const DomainDistance& d) {
  return {{"boundary_max_distance", d.boundary_max_distance}, {"boundary_max_relative", d.boundary_max_relative},
          {"feature_max_distance", d.feature_max_distance}, {"feature_node_max_distance", d.feature_node_max_distance},
          {"feature_max_at", {d.feature_max_at.x, d.feature_max_at.y}},
          {"feature_node_max_at", {d.feature_node_max_at.x, d.feature_node_max_at.y}},
          {"area_relative_change", d.area_relative_change}, {"sharp_vertices_total", d.sharp_vertices_total},
          {"sharp_vertices_missing", d.sharp_vertices_missing}};
}

namespace {

void read_stats(const nlohmann::json& j, Stats& s) {
  j.at("min").get_to(s.min), j.at("avg").get_to(s.avg), j.at("max").get_to(s.max), j.at("std").get_to(s.std);
}

void read_point(const nlohmann::json& j, Vec2& p) { p = {j.at(0).get<double>(), j.at(1).get<double>()}; }

}  // namespace

void from_json(const nlohmann::json& j, SchismQuadQuality& q) {
  read_stats(j.at("angle_ratio"), q.angle_ratio);
  j.at("angle_ratio_limit").get_to(q.angle_ratio_limit);
  j.at("angle_ratio_below_limit").get_to(q.angle_ratio_below);
  read_point(j.at("angle_ratio_worst_at"), q.angle_ratio_worst_at);
  read_stats(j.at("aspect_ratio"), q.aspect_ratio);
  j.at("aspect_ratio_limit").get_to(q.aspect_ratio_limit);
  j.at("aspect_ratio_above_limit").get_to(q.aspect_ratio_above);
  read_point(j.at("aspect_ratio_worst_at"), q.aspect_ratio_worst_at);
  j.at("non_convex").get_to(q.non_convex);
  j.at("failing").get_to(q.failing);
}

void from_json(const nlohmann::json& j, FiniteVolumeQuality& q) {
  j.at("interior_edges").get_to(q.interior_edges);
  read_stats(j.at("orthogonality"), q.orthogonality);
  j.at("orthogonality_limit").get_to(q.orthogonality_limit);
  j.at("orthogonality_above_limit").get_to(q.orthogonality_above);
  read_point(j.at("orthogonality_worst_at"), q.orthogonality_worst_at);
  read_stats(j.at("smoothness"), q.smoothness);
  read_point(j.at("smoothness_worst_at"), q.smoothness_worst_at);
}

void from_json(const nlohmann::json& j, QualityReport& q) {
  j.at("nodes").get_to(q.nodes), j.at("quads").get_to(q.quads), j.at("triangles").get_to(q.triangles);
  j.at("inverted").get_to(q.inverted), j.at("non_manifold_edges").get_to(q.non_manifold_edges);
  j.at("boundary_edges").get_to(q.boundary_edges);
  read_stats(j.at("sj"), q.sj), read_stats(j.at("eta"), q.eta), read_stats(j.at("skew"), q.skew);
  read_stats(j.at("edge_ratio"), q.edge_ratio);
  j.at("singularities").get_to(q.singularities);
  j.at("interior_singularities").get_to(q.interior_singularities);
  j.at("boundary_singularities").get_to(q.boundary_singularities);
  j.at("regular_quad_fraction").get_to(q.regular_quad_fraction);
  j.at("sj_below_0_3_fraction").get_to(q.sj_below_0_3_fraction);
  from_json(j.at("schism"), q.schism);
}

void from_json(const nlohmann::json& j, DomainDistance& d) {
  j.at("boundary_max_distance").get_to(d.boundary_max_distance);
  j.at("boundary_max_relative").get_to(d.boundary_max_relative);
  j.at("feature_max_distance").get_to(d.feature_max_distance);
  j.at("feature_node_max_distance").get_to(d.feature_node_max_distance);
  read_point(j.at("feature_max_at"), d.feature_max_at);
  read_point(j.at("feature_node_max_at"), d.feature_node_max_at);
  j.at("area_relative_change").get_to(d.area_relative_change);
  j.at("sharp_vertices_total").get_to(d.sharp_vertices_total);
  j.at("sharp_vertices_missing").get_to(d.sharp_vertices_missing);
}

std::string format_quality_text(const QualityReport& q, const DomainDistance* d, const PlaceWriter& place) {
  auto at = [&](Vec2 p) { return place ? place(p) : at_text(p); };
  std::ostringstream os;
  os.precision(4);
  auto line = [&](const char* name, const Stats& s) {
    os << "  " << name << ": min " << s.min << "  avg " << s.avg << "  max " << s.max << "  std " << s.std << "\n";
  };
  os << "  nodes " << q.nodes << ", quads " << q.quads << ", triangles " << q.triangles << ", inverted " << q.inverted
     << ", non-manifold edges " << q.non_manifold_edges << "\n";
  line("scaled Jacobian (Verdict, min corner)", q.sj);
  line("eta (paper, mean corner)            ", q.eta);
  line("skewness (eq. 16)                   ", q.skew);
  line("edge ratio                          ", q.edge_ratio);
  os << "  singularities: " << q.singularities << " (paper: boundary valence != 3 + interior valence != 4), interior "
     << q.interior_singularities << "; quads touching no interior singular node " << q.regular_quad_fraction
     << ", quads with scaled Jacobian below 0.3 " << q.sj_below_0_3_fraction << "\n";
  if (d) {
    os << "  boundary distance max " << d->boundary_max_distance << " (relative " << d->boundary_max_relative
       << "), area change " << d->area_relative_change << ", sharp vertices missing " << d->sharp_vertices_missing << " of "
       << d->sharp_vertices_total << "\n";
    os << "  feature distance to mesh edges max " << d->feature_max_distance;
    if (d->feature_max_distance > 0) os << " at " << at(d->feature_max_at);
    os << ", feature nodes off curves max " << d->feature_node_max_distance;
    if (d->feature_node_max_distance > 0) os << " at " << at(d->feature_node_max_at);
    os << "\n";
  }
  return os.str();
}

}  // namespace polysquare
