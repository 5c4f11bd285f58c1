#include "polysquare/partition/partition.h"

#include <metis.h>

#include <algorithm>
#include <mutex>
#include <cmath>
#include <deque>
#include <map>
#include <fstream>
#include <numbers>
#include <random>
#include <unordered_map>

#include "polysquare/core/error.h"
#include "polysquare/io/atomic_file.h"

namespace polysquare {
namespace {

// Edges of the triangulation with their one or two triangles, and the incidences the energy needs.
struct Topology {
  struct Edge {
    std::int32_t a, b;
    std::int32_t t0, t1;  // t1 = -1 on the boundary
    double length;        // in hundredths of the mean edge length
    bool feature;
  };
  std::vector<Edge> edges;
  std::vector<std::array<std::int32_t, 3>> tri_edges;
  std::vector<std::size_t> vert_off;
  std::vector<std::int32_t> vert_edges;
  std::vector<double> area;
  double feature_length = 0;

  // Graded meshes weigh each triangle's area by (size_ref / h)^2: every area below is then in quads of size_ref.
  Topology(const TriMesh& m, const PartitionOptions& o) : Topology(m) {
    if (!o.size_field) return;
    for (std::size_t t = 0; t < m.triangles.size(); ++t) {
      const auto& tri = m.triangles[t];
      const Vec2 c = (1.0 / 3.0) * (m.vertices[tri[0]] + m.vertices[tri[1]] + m.vertices[tri[2]]);
      const double r = o.size_ref / o.size_field->at(c);
      area[t] *= r * r;
    }
  }

  explicit Topology(const TriMesh& m) {
    std::unordered_map<std::uint64_t, std::int32_t> index;
    tri_edges.resize(m.triangles.size());
    double total_len = 0;
    for (std::size_t t = 0; t < m.triangles.size(); ++t) {
      const auto& tri = m.triangles[t];
      area.push_back(0.5 * orient2(m.vertices[tri[0]], m.vertices[tri[1]], m.vertices[tri[2]]));
      for (int k = 0; k < 3; ++k) {
        const std::int32_t a = tri[k], b = tri[(k + 1) % 3];
        auto [it, inserted] = index.try_emplace(edge_key(a, b), static_cast<std::int32_t>(edges.size()));
        if (inserted) {
          edges.push_back({a, b, static_cast<std::int32_t>(t), -1, distance(m.vertices[a], m.vertices[b]), false});
          total_len += edges.back().length;
        } else {
          edges[it->second].t1 = static_cast<std::int32_t>(t);
        }
        tri_edges[t][k] = it->second;
      }
    }
    const double unit = edges.empty() ? 1.0 : total_len / static_cast<double>(edges.size()) / 100.0;
    for (auto& e : edges) e.length /= unit;
    for (const TriChain& ch : m.chains) {
      if (ch.kind != TriChain::Kind::feature) continue;
      const std::size_t n = ch.vertices.size(), segs = ch.closed ? n : n - 1;
      for (std::size_t i = 0; i < segs; ++i) {
        auto it = index.find(edge_key(ch.vertices[i], ch.vertices[(i + 1) % n]));
        if (it == index.end() || edges[it->second].feature) continue;
        edges[it->second].feature = true;
        feature_length += edges[it->second].length;
      }
    }
    vert_off.assign(m.vertices.size() + 1, 0);
    for (const auto& e : edges) { vert_off[e.a + 1]++; vert_off[e.b + 1]++; }
    for (std::size_t v = 0; v < m.vertices.size(); ++v) vert_off[v + 1] += vert_off[v];
    vert_edges.resize(vert_off.back());
    std::vector<std::size_t> fill(vert_off.begin(), vert_off.end() - 1);
    for (std::size_t e = 0; e < edges.size(); ++e) {
      vert_edges[fill[edges[e].a]++] = static_cast<std::int32_t>(e);
      vert_edges[fill[edges[e].b]++] = static_cast<std::int32_t>(e);
    }
  }
  bool separator(std::size_t e, const std::vector<std::int32_t>& part) const {
    return edges[e].t1 >= 0 && part[edges[e].t0] != part[edges[e].t1];
  }
  std::int32_t neighbour(std::size_t t, int k) const {
    const Edge& e = edges[tri_edges[t][k]];
    return e.t0 == static_cast<std::int32_t>(t) ? e.t1 : e.t0;
  }
};

// Angle term at one vertex (eq. 3, times 100): pairs of incident separator edges, and separator-boundary pairs.
double vertex_angle_term(const TriMesh& m, const Topology& topo, std::int32_t v, const std::vector<std::int32_t>& part) {
  double sum = 0;
  const std::size_t b0 = topo.vert_off[v], b1 = topo.vert_off[v + 1];
  for (std::size_t i = b0; i < b1; ++i) {
    const auto& ei = topo.edges[topo.vert_edges[i]];
    const bool si = topo.separator(topo.vert_edges[i], part), bi = ei.t1 < 0;
    if (!si && !bi) continue;
    for (std::size_t j = i + 1; j < b1; ++j) {
      const auto& ej = topo.edges[topo.vert_edges[j]];
      const bool sj = topo.separator(topo.vert_edges[j], part), bj = ej.t1 < 0;
      if (!(si && (sj || bj)) && !(sj && bi)) continue;
      const Vec2 di = m.vertices[ei.a == v ? ei.b : ei.a] - m.vertices[v];
      const Vec2 dj = m.vertices[ej.a == v ? ej.b : ej.a] - m.vertices[v];
      const double theta = std::abs(std::atan2(cross(di, dj), dot(di, dj)));  // in [0, pi]
      const double q = std::numbers::pi / 2;
      sum += 100.0 * std::min(std::abs(theta - q), std::abs(theta - 2 * q));
    }
  }
  return sum;
}

PartitionEnergy energy_of(const TriMesh& m, const Topology& topo, const std::vector<std::int32_t>& part,
                          const PartitionOptions& o) {
  PartitionEnergy en;
  for (std::size_t e = 0; e < topo.edges.size(); ++e) {
    if (!topo.separator(e, part)) continue;
    en.separator_length += topo.edges[e].length;
    if (topo.edges[e].feature) en.feature_on_separators += topo.edges[e].length;
  }
  for (std::size_t v = 0; v + 1 < topo.vert_off.size(); ++v)
    en.angle_deviation += vertex_angle_term(m, topo, static_cast<std::int32_t>(v), part);
  en.energy = en.separator_length + o.lambda_angle * en.angle_deviation - o.lambda_feature * en.feature_on_separators;
  return en;
}

// Is part `p` still connected after removing triangle t? Bounded search between t's same-part neighbours.
bool stays_connected(const Topology& topo, const std::vector<std::int32_t>& part, std::int32_t t, int limit) {
  const std::int32_t p = part[t];
  std::vector<std::int32_t> nb;
  for (int k = 0; k < 3; ++k) {
    const std::int32_t n = topo.neighbour(static_cast<std::size_t>(t), k);
    if (n >= 0 && part[n] == p) nb.push_back(n);
  }
  if (nb.size() <= 1) return true;
  std::vector<std::int32_t> seen{t, nb[0]}, queue{nb[0]};
  std::size_t found = 1;
  for (std::size_t qi = 0; qi < queue.size() && static_cast<int>(queue.size()) < limit; ++qi) {
    for (int k = 0; k < 3; ++k) {
      const std::int32_t n = topo.neighbour(static_cast<std::size_t>(queue[qi]), k);
      if (n < 0 || part[n] != p || std::find(seen.begin(), seen.end(), n) != seen.end()) continue;
      seen.push_back(n);
      queue.push_back(n);
      if (std::find(nb.begin() + 1, nb.end(), n) != nb.end() && ++found == nb.size()) return true;
    }
  }
  return false;
}

// Moves every triangle outside its part's largest component to the neighbouring part it shares most edge with,
// among the parts of the same face (part_face[p]: the face of part p).
std::size_t make_parts_connected(const Topology& topo, std::vector<std::int32_t>& part, int k,
                                 const std::vector<std::int32_t>& part_face) {
  std::size_t moved = 0;
  for (int round = 0; round < 100; ++round) {
    const std::size_t nt = part.size();
    std::vector<std::int32_t> comp(nt, -1);
    std::vector<double> comp_area;
    std::vector<std::int32_t> comp_part;
    for (std::size_t s = 0; s < nt; ++s) {
      if (comp[s] >= 0) continue;
      const auto c = static_cast<std::int32_t>(comp_area.size());
      comp_area.push_back(0);
      comp_part.push_back(part[s]);
      std::deque<std::int32_t> q{static_cast<std::int32_t>(s)};
      comp[s] = c;
      while (!q.empty()) {
        const std::int32_t t = q.front();
        q.pop_front();
        comp_area[c] += topo.area[t];
        for (int e = 0; e < 3; ++e) {
          const std::int32_t n = topo.neighbour(static_cast<std::size_t>(t), e);
          if (n >= 0 && comp[n] < 0 && part[n] == part[t]) { comp[n] = c; q.push_back(n); }
        }
      }
    }
    std::vector<std::int32_t> largest(static_cast<std::size_t>(k), -1);
    for (std::size_t c = 0; c < comp_area.size(); ++c) {
      auto& best = largest[static_cast<std::size_t>(comp_part[c])];
      if (best < 0 || comp_area[c] > comp_area[static_cast<std::size_t>(best)]) best = static_cast<std::int32_t>(c);
    }
    bool changed = false;
    for (std::size_t c = 0; c < comp_area.size(); ++c) {
      if (largest[static_cast<std::size_t>(comp_part[c])] == static_cast<std::int32_t>(c)) continue;
      std::unordered_map<std::int32_t, double> shared;
      for (std::size_t t = 0; t < nt; ++t) {
        if (comp[t] != static_cast<std::int32_t>(c)) continue;
        for (int e = 0; e < 3; ++e) {
          const std::int32_t n = topo.neighbour(t, e);
          if (n >= 0 && comp[n] != static_cast<std::int32_t>(c)) shared[part[n]] += topo.edges[topo.tri_edges[t][e]].length;
        }
      }
      std::int32_t target = -1;
      double best = -1;
      for (const auto& [p, len] : shared)
        if (part_face[static_cast<std::size_t>(p)] == part_face[static_cast<std::size_t>(comp_part[c])] &&
            (len > best || (len == best && p < target))) { best = len; target = p; }
      if (target < 0) continue;
      for (std::size_t t = 0; t < nt; ++t)
        if (comp[t] == static_cast<std::int32_t>(c)) { part[t] = target; ++moved; }
      changed = true;
    }
    if (!changed) break;
  }
  return moved;
}

// Feature faces: components of triangles joined across edges that are not feature edges. A face enclosed by one
// other face (no ring edge, one neighbour) or smaller than min_area merges into the neighbour it shares the most
// feature length with, repeatedly. Faces are numbered by their first triangle.
std::vector<std::int32_t> feature_faces(const Topology& topo, double min_area, int& count) {
  const std::size_t nt = topo.area.size();
  std::vector<std::int32_t> comp(nt, -1);
  int nc = 0;
  for (std::size_t s = 0; s < nt; ++s) {
    if (comp[s] >= 0) continue;
    std::vector<std::int32_t> stack{static_cast<std::int32_t>(s)};
    comp[s] = nc;
    while (!stack.empty()) {
      const std::int32_t t = stack.back();
      stack.pop_back();
      for (int e = 0; e < 3; ++e) {
        const std::int32_t n = topo.neighbour(static_cast<std::size_t>(t), e);
        if (n >= 0 && comp[n] < 0 && !topo.edges[topo.tri_edges[t][e]].feature) { comp[n] = nc; stack.push_back(n); }
      }
    }
    ++nc;
  }
  std::vector<std::int32_t> parent(static_cast<std::size_t>(nc));
  for (int c = 0; c < nc; ++c) parent[c] = c;
  auto find = [&](std::int32_t c) {
    while (parent[c] != c) c = parent[c] = parent[parent[c]];
    return c;
  };
  for (bool changed = nc > 1; changed;) {
    changed = false;
    std::vector<double> area(static_cast<std::size_t>(nc), 0.0);
    std::vector<std::uint8_t> ring(static_cast<std::size_t>(nc), 0);
    std::vector<std::map<std::int32_t, double>> shared(static_cast<std::size_t>(nc));  // neighbour -> feature length
    for (std::size_t t = 0; t < nt; ++t) area[find(comp[t])] += topo.area[t];
    for (const auto& e : topo.edges) {
      if (e.t1 < 0) { ring[find(comp[e.t0])] = 1; continue; }
      const std::int32_t a = find(comp[e.t0]), b = find(comp[e.t1]);
      if (a == b) continue;
      shared[a][b] += e.length;
      shared[b][a] += e.length;
    }
    std::vector<std::int32_t> order;
    for (int c = 0; c < nc; ++c)
      if (find(c) == c && !shared[c].empty()) order.push_back(c);
    std::sort(order.begin(), order.end(), [&](std::int32_t a, std::int32_t b) {
      return area[a] < area[b] || (area[a] == area[b] && a < b);
    });
    std::vector<std::uint8_t> received(static_cast<std::size_t>(nc), 0);
    for (std::int32_t c : order) {
      const bool enclosed = !ring[c] && shared[c].size() == 1;
      if (!enclosed && !(area[c] < min_area)) continue;
      std::int32_t target = -1;
      double best = -1;
      for (const auto& [n, len] : shared[c])
        if (len > best) { best = len; target = n; }
      // A face that took others in, or merged away, waits for the next pass (its figures are stale).
      if (received[c] || find(target) != target) continue;
      parent[c] = target;
      received[target] = 1;
      changed = true;
    }
  }
  std::vector<std::int32_t> number(static_cast<std::size_t>(nc), -1), face(nt);
  count = 0;
  for (std::size_t t = 0; t < nt; ++t) {
    auto& f = number[find(comp[t])];
    if (f < 0) f = count++;
    face[t] = f;
  }
  return face;
}

// Feature faces with their triangles, areas and boundary lengths (ring and feature edges, seen from each side).
struct Faces {
  int count = 1;
  std::vector<std::int32_t> of_triangle;
  std::vector<std::vector<std::int32_t>> triangles;
  std::vector<double> area, length;
  double total_area = 0, total_length = 0;
};

Faces faces_of(const Topology& topo, double min_face_area, std::size_t nt) {
  Faces faces;
  faces.of_triangle = feature_faces(topo, min_face_area, faces.count);
  const int nf = faces.count;
  const std::vector<std::int32_t>& face = faces.of_triangle;
  faces.triangles.resize(static_cast<std::size_t>(nf));
  for (std::size_t t = 0; t < nt; ++t) faces.triangles[face[t]].push_back(static_cast<std::int32_t>(t));
  faces.area.assign(static_cast<std::size_t>(nf), 0.0);
  faces.length.assign(static_cast<std::size_t>(nf), 0.0);
  for (std::size_t t = 0; t < nt; ++t) {
    faces.area[face[t]] += topo.area[t];
    faces.total_area += topo.area[t];
    for (int e = 0; e < 3; ++e) {
      const auto& ed = topo.edges[topo.tri_edges[t][e]];
      if (ed.t1 < 0 || ed.feature) { faces.length[face[t]] += ed.length; faces.total_length += ed.length; }
    }
  }
  return faces;
}

// The parts dealt to the faces: face f has parts first[f] .. first[f + 1] - 1.
struct FaceParts {
  int k = 1;                          ///< all parts
  std::vector<int> count, first;      ///< per face
  std::vector<std::int32_t> face_of;  ///< per part
};

// k parts (at least one per face) dealt to the faces by half their share of area and half their share of
// boundary length.
FaceParts deal_parts(const Faces& faces, int k) {
  const int nf = faces.count;
  FaceParts dealt;
  k = std::max(k, nf);
  std::vector<int>& face_parts = dealt.count;
  face_parts.assign(static_cast<std::size_t>(nf), k);
  if (nf > 1) {
    std::vector<double> quota(static_cast<std::size_t>(nf));
    int sum = 0;
    for (int f = 0; f < nf; ++f) {
      const double share = 0.5 * faces.area[f] / std::max(faces.total_area, 1e-300) +
                           0.5 * (faces.total_length > 0 ? faces.length[f] / faces.total_length
                                                         : faces.area[f] / std::max(faces.total_area, 1e-300));
      quota[f] = k * share;
      face_parts[f] = std::clamp(static_cast<int>(std::floor(quota[f])), 1, static_cast<int>(faces.triangles[f].size()));
      sum += face_parts[f];
    }
    // Largest remainders up to k; a face over its quota (the minimum of one) is paid by the smallest remainders.
    while (sum != k) {
      int pick = -1;
      for (int f = 0; f < nf; ++f) {
        const double r = quota[f] - face_parts[f];
        if (sum < k ? face_parts[f] < static_cast<int>(faces.triangles[f].size()) &&
                          (pick < 0 || r > quota[pick] - face_parts[pick])
                    : face_parts[f] > 1 && (pick < 0 || r < quota[pick] - face_parts[pick]))
          pick = f;
      }
      if (pick < 0) break;
      face_parts[pick] += sum < k ? 1 : -1;
      sum += sum < k ? 1 : -1;
    }
    k = sum;
  }
  dealt.k = k;
  dealt.first.assign(static_cast<std::size_t>(nf) + 1, 0);
  for (int f = 0; f < nf; ++f) dealt.first[f + 1] = dealt.first[f] + face_parts[f];
  dealt.face_of.resize(static_cast<std::size_t>(k));
  for (int f = 0; f < nf; ++f)
    for (int p = dealt.first[f]; p < dealt.first[f + 1]; ++p) dealt.face_of[p] = f;
  return dealt;
}

// METIS's k-way partition of each face dealt two or more parts, written into part.
void metis_partition_faces(const Topology& topo, const Faces& faces, const FaceParts& dealt, std::uint64_t seed,
                           std::vector<std::int32_t>& part) {
  const std::size_t nt = part.size();
  const std::vector<std::int32_t>& face = faces.of_triangle;
  // METIS wants integer weights: areas and lengths relative to their means, in hundredths.
  double mean_area = 0;
  for (double a : topo.area) mean_area += a;
  mean_area /= static_cast<double>(nt);
  // METIS draws from one process-wide random state (GKlib): concurrent calls (parts and candidates are
  // partitioned from several threads) would make the partition depend on timing, so they are serialized.
  static std::mutex metis_mutex;
  std::vector<std::int32_t> local(nt, -1);
  for (int f = 0; f < faces.count; ++f) {
    if (dealt.count[f] < 2) continue;
    const auto& tris = faces.triangles[f];
    for (std::size_t i = 0; i < tris.size(); ++i) local[tris[i]] = static_cast<std::int32_t>(i);
    std::vector<idx_t> xadj{0}, adjncy, vwgt, adjwgt;
    for (std::int32_t t : tris) {
      vwgt.push_back(std::max<idx_t>(1, static_cast<idx_t>(std::lround(100.0 * topo.area[t] / mean_area))));
      for (int e = 0; e < 3; ++e) {
        const std::int32_t n = topo.neighbour(static_cast<std::size_t>(t), e);
        if (n < 0 || face[n] != f) continue;
        adjncy.push_back(local[n]);
        adjwgt.push_back(std::max<idx_t>(1, static_cast<idx_t>(std::lround(topo.edges[topo.tri_edges[t][e]].length))));
      }
      xadj.push_back(static_cast<idx_t>(adjncy.size()));
    }
    idx_t nv = static_cast<idx_t>(tris.size()), ncon = 1, nparts = dealt.count[f], objval = 0;
    idx_t opts[METIS_NOPTIONS];
    METIS_SetDefaultOptions(opts);
    opts[METIS_OPTION_SEED] = static_cast<idx_t>(seed % 1000003);
    opts[METIS_OPTION_CONTIG] = 1;
    std::vector<idx_t> face_part(tris.size(), 0);
    const std::lock_guard<std::mutex> lock(metis_mutex);
    const int status = METIS_PartGraphKway(&nv, &ncon, xadj.data(), adjncy.data(), vwgt.data(), nullptr, adjwgt.data(),
                                           &nparts, nullptr, nullptr, opts, &objval, face_part.data());
    if (status != METIS_OK) throw MeshingError("partitioning: METIS failed with status " + std::to_string(status));
    for (std::size_t i = 0; i < tris.size(); ++i) part[tris[i]] = dealt.first[f] + static_cast<std::int32_t>(face_part[i]);
  }
}

// The energy terms that a move of t can change.
double local_energy(const TriMesh& mesh, const Topology& topo, const std::vector<std::int32_t>& part,
                    const PartitionOptions& options, std::int32_t t) {
  double e = 0;
  for (int j = 0; j < 3; ++j) {
    const std::size_t ed = static_cast<std::size_t>(topo.tri_edges[t][j]);
    if (topo.separator(ed, part))
      e += topo.edges[ed].length - (topo.edges[ed].feature ? options.lambda_feature * topo.edges[ed].length : 0.0);
    e += options.lambda_angle * vertex_angle_term(mesh, topo, mesh.triangles[t][j], part);
  }
  return e;
}

// Metropolis-Hastings on E under the balance constraint (eq. 1), keeping the best state: res.triangle_part
// becomes the lowest-energy partition seen; counts the moves in res. The balance is measured against each
// part's mean, the mean part area of its face.
void metropolis_hastings(const TriMesh& mesh, const Topology& topo, const FaceParts& dealt, int nf,
                         const std::vector<double>& mean, const PartitionOptions& options, PartitionResult& res) {
  const int k = dealt.k;
  const std::size_t nt = mesh.triangles.size();
  std::vector<double> part_area(static_cast<std::size_t>(k), 0.0), lo(static_cast<std::size_t>(k)), hi(static_cast<std::size_t>(k));
  for (std::size_t t = 0; t < nt; ++t) part_area[res.triangle_part[t]] += topo.area[t];
  for (int p = 0; p < k; ++p) {
    lo[p] = (1 - options.balance) * mean[p];
    hi[p] = (1 + options.balance) * mean[p];
  }
  std::vector<std::int32_t>& part = res.triangle_part;
  std::vector<std::int32_t> best = part;
  double energy = res.metis.energy, best_energy = energy;
  std::mt19937_64 rng(options.seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<std::int32_t> order(nt);
  for (std::size_t t = 0; t < nt; ++t) order[t] = static_cast<std::int32_t>(t);
  for (int sweep = 0; sweep < options.mh_sweeps && k > nf; ++sweep) {
    // Annealing: the inverse temperature grows from lambda_mh by mh_anneal over the sweeps, so the walk explores
    // first and settles into a low-energy state at the end.
    const double beta = options.lambda_mh *
                        std::pow(options.mh_anneal, options.mh_sweeps > 1 ? double(sweep) / (options.mh_sweeps - 1) : 1.0);
    std::shuffle(order.begin(), order.end(), rng);
    for (std::int32_t t : order) {
      const std::int32_t a = part[t];
      std::int32_t cand[3];
      int nc = 0;
      for (int j = 0; j < 3; ++j) {
        const std::int32_t n = topo.neighbour(static_cast<std::size_t>(t), j);
        if (n >= 0 && part[n] != a && dealt.face_of[part[n]] == dealt.face_of[a] && std::find(cand, cand + nc, part[n]) == cand + nc)
          cand[nc++] = part[n];
      }
      if (nc == 0) continue;
      const std::int32_t b = cand[std::min(nc - 1, static_cast<int>(unit(rng) * nc))];
      ++res.mh_proposed;
      // Balance: never create or worsen a violation of eq. 1.
      const double na = part_area[a] - topo.area[t], nb = part_area[b] + topo.area[t];
      if (na < std::min(lo[a], part_area[a]) || nb > std::max(hi[b], part_area[b])) continue;
      if (!stays_connected(topo, part, t, 256)) continue;
      const double before = local_energy(mesh, topo, part, options, t);
      part[t] = b;
      const double delta = local_energy(mesh, topo, part, options, t) - before;
      if (delta <= 0 || unit(rng) < std::exp(-beta * delta)) {
        part_area[a] = na;
        part_area[b] = nb;
        energy += delta;
        ++res.mh_accepted;
      } else {
        part[t] = a;
      }
    }
    if (energy < best_energy) { best_energy = energy; best = part; }
  }
  part = best;
}

}  // namespace

PartitionEnergy partition_energy(const TriMesh& mesh, const std::vector<std::int32_t>& triangle_part,
                                 const PartitionOptions& options) {
  return energy_of(mesh, Topology(mesh, options), triangle_part, options);
}

PartitionResult partition_triangles(const TriMesh& mesh, const PartitionOptions& options) {
  const Topology topo(mesh, options);
  const std::size_t nt = mesh.triangles.size();
  PartitionResult res;
  int k = options.parts > 0 ? options.parts
                            : static_cast<int>(std::max<std::size_t>(1, (nt + options.target_triangles_per_part / 2) /
                                                                           std::max<std::size_t>(1, options.target_triangles_per_part)));
  k = std::max(1, std::min<int>(k, static_cast<int>(nt)));
  // Feature faces, each partitioned on its own: k parts dealt to them by half their share of area and half their
  // share of boundary length (ring and feature edges, seen from each side), at least one part per face.
  const Faces faces = faces_of(topo, options.min_face_area, nt);
  const int nf = faces.count;
  const FaceParts dealt = deal_parts(faces, k);
  k = dealt.k;
  res.parts = k;
  res.faces = nf;
  res.triangle_part.assign(nt, 0);
  for (std::size_t t = 0; t < nt; ++t) res.triangle_part[t] = dealt.first[faces.of_triangle[t]];
  if (k > nf) {
    metis_partition_faces(topo, faces, dealt, options.seed, res.triangle_part);
    make_parts_connected(topo, res.triangle_part, k, dealt.face_of);
  }
  res.metis = energy_of(mesh, topo, res.triangle_part, options);

  std::vector<double> mean(static_cast<std::size_t>(k));
  for (int p = 0; p < k; ++p) mean[p] = faces.area[dealt.face_of[p]] / dealt.count[dealt.face_of[p]];
  metropolis_hastings(mesh, topo, dealt, nf, mean, options, res);
  std::vector<std::int32_t>& part = res.triangle_part;
  res.repaired_triangles = k > nf ? make_parts_connected(topo, part, k, dealt.face_of) : 0;
  res.final = energy_of(mesh, topo, part, options);
  std::vector<double> part_area(static_cast<std::size_t>(k), 0.0);
  for (std::size_t t = 0; t < nt; ++t) part_area[part[t]] += topo.area[t];
  for (int p = 0; p < k; ++p) res.balance_max_over_avg = std::max(res.balance_max_over_avg, part_area[p] / mean[p]);
  if (topo.feature_length > 0) {
    res.feature_fraction_metis = res.metis.feature_on_separators / topo.feature_length;
    res.feature_fraction_final = res.final.feature_on_separators / topo.feature_length;
  }
  return res;
}

void write_partition_svg(const std::filesystem::path& path, const TriMesh& mesh, const PartitionResult& result, int width_px) {
  const Topology topo(mesh);
  Box2 box;
  for (Vec2 p : mesh.vertices) box.add(p);
  // No triangles (every part was meshed without a partition): a picture that says so, not an unbounded box.
  const bool empty = mesh.vertices.empty();
  const double scale = empty ? 1.0 : (width_px - 20) / std::max(box.hi.x - box.lo.x, 1e-300);
  const int height = empty ? 40 : static_cast<int>((box.hi.y - box.lo.y) * scale) + 20;
  auto X = [&](Vec2 p) { return 10 + (p.x - box.lo.x) * scale; };
  auto Y = [&](Vec2 p) { return 10 + (box.hi.y - p.y) * scale; };
  static const char* palette[] = {"#8dd3c7", "#ffffb3", "#bebada", "#fb8072", "#80b1d3", "#fdb462",
                                  "#b3de69", "#fccde5", "#d9d9d9", "#bc80bd", "#ccebc5", "#ffed6f"};
  write_file_atomically(path, [&](std::ostream& os) {
    os << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width_px << "\" height=\"" << height << "\">\n";
    if (empty) os << "<text x=\"10\" y=\"25\">no partition: no part was meshed by subregions</text>\n";
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      os << "<polygon points=\"";
      for (auto v : mesh.triangles[t]) os << X(mesh.vertices[v]) << "," << Y(mesh.vertices[v]) << " ";
      os << "\" fill=\"" << palette[result.triangle_part[t] % 12] << "\" stroke=\"" << palette[result.triangle_part[t] % 12] << "\"/>\n";
    }
    for (std::size_t e = 0; e < topo.edges.size(); ++e) {
      const auto& ed = topo.edges[e];
      const bool sep = topo.separator(e, result.triangle_part), border = ed.t1 < 0;
      if (!sep && !border && !ed.feature) continue;
      const char* colour = ed.feature ? "red" : "black";
      os << "<line x1=\"" << X(mesh.vertices[ed.a]) << "\" y1=\"" << Y(mesh.vertices[ed.a]) << "\" x2=\"" << X(mesh.vertices[ed.b])
         << "\" y2=\"" << Y(mesh.vertices[ed.b]) << "\" stroke=\"" << colour << "\" stroke-width=\"" << (sep ? 2.5 : 1.2) << "\"/>\n";
    }
    os << "</svg>\n";
  }, false);
}

}  // namespace polysquare
