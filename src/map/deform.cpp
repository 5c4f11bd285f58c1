#include "polysquare/map/deform.h"

#include "core/digest.h"
#include "map/untangle_triangles.h"

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>
#include <oneapi/tbb/parallel_reduce.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <deque>
#include <limits>
#include <map>
#include <mutex>
#include <optional>

namespace polysquare {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Precomputed rest-shape data of one triangle: inverse of the rest edge matrix and its weight.
struct RestTriangle {
  double r00, r01, r10, r11;  // inverse of [p1-p0, p2-p0]
  double weight;              // area / mean area, so the energy scale does not depend on units or resolution
};

struct Energy {
  const DeformProblem& problem;
  double c_angle, c_area;  // alpha*s/4 and (1-alpha)*s/2
  double expo_rest;        // exponent of AMIPS at a rigid motion
  double eps = 0.1;
  bool with_alignment = true;
  // Soft position constraints: anchor_weight * sum |x_v - anchor_v|^2 over the flagged vertices (none when null).
  const std::vector<Vec2>* anchor = nullptr;
  const std::vector<std::uint8_t>* anchor_mask = nullptr;
  double anchor_weight = 0.0;
  std::vector<RestTriangle> rest;
  std::vector<double> edge_scale;  // rest length / total rest length of aligned edges
  std::vector<double> rest_length; // rest length of each aligned edge
  // Scratch of the parallel evaluation (one Energy is never evaluated from two threads at once).
  mutable std::vector<double> values;
  mutable std::vector<Vec2> grads;
  static constexpr std::size_t kParallelTriangles = 8192;

  Energy(const DeformProblem& p, const DeformOptions& o)
      : problem(p), c_angle(o.amips_alpha * o.amips_s / 4.0), c_area((1.0 - o.amips_alpha) * o.amips_s / 2.0),
        expo_rest(2.0 * c_angle + 2.0 * c_area) {
    double total = 0.0;
    rest.reserve(p.triangles.size());
    for (std::size_t k = 0; k < p.triangles.size(); ++k) {
      const auto& t = p.triangles[k];
      const double scale = p.rest_scale.empty() ? 1.0 : p.rest_scale[k];
      const Vec2 e1 = scale * (p.rest[t[1]] - p.rest[t[0]]), e2 = scale * (p.rest[t[2]] - p.rest[t[0]]);
      const double det = cross(e1, e2);
      rest.push_back({e2.y / det, -e2.x / det, -e1.y / det, e1.x / det, 0.5 * det});
      total += 0.5 * det;
    }
    // E^D is the area-weighted mean distortion and the alignment terms are length-weighted means over all
    // aligned edges, so both are dimensionless and independent of the resolution: lambda = 5 then means what
    // the paper intends (alignment five times as important as distortion) on any mesh.
    for (auto& r : rest) r.weight /= total;
    double len = 0.0;
    for (const auto& e : p.aligned) len += distance(p.rest[e.a], p.rest[e.b]);
    for (const auto& e : p.aligned) {
      rest_length.push_back(std::max(distance(p.rest[e.a], p.rest[e.b]), 1e-12));
      edge_scale.push_back(rest_length.back() / len);
    }
  }

  // Per-triangle AMIPS value and gradient with respect to its edge vectors d1, d2 (false if inverted or past
  // the overflow guard).
  bool triangle_term(const std::vector<Vec2>& x, std::size_t t, double& val, Vec2& gd1, Vec2& gd2, bool want_grad) const {
    const auto& tri = problem.triangles[t];
    const RestTriangle& r = rest[t];
    const Vec2 d1 = x[tri[1]] - x[tri[0]], d2 = x[tri[2]] - x[tri[0]];
    // J = D * R with D = [d1 d2] (columns).
    const double j00 = d1.x * r.r00 + d2.x * r.r10, j01 = d1.x * r.r01 + d2.x * r.r11;
    const double j10 = d1.y * r.r00 + d2.y * r.r10, j11 = d1.y * r.r01 + d2.y * r.r11;
    const double det = j00 * j11 - j01 * j10;
    if (!(det > 1e-300)) return false;
    const double fro = j00 * j00 + j01 * j01 + j10 * j10 + j11 * j11;
    const double expo = c_angle * fro / det + c_area * (det + 1.0 / det);
    if (expo - expo_rest > 600.0) return false;
    // Divided by the AMIPS of a rigid motion (exp(2 c_angle + 2 c_area)): a per-triangle distortion of 1 at
    // rest keeps the alignment weights of the paper (lambda = 5) meaningful whatever the mesh resolution.
    val = r.weight * std::exp(expo - expo_rest);
    if (!want_grad) return true;
    // dE/dJ = val * (c_angle (2J/det - fro/det^2 cof) + c_area (1 - 1/det^2) cof), cof = d det / dJ.
    const double a = val * c_angle * 2.0 / det;
    const double b = val * (-c_angle * fro / (det * det) + c_area * (1.0 - 1.0 / (det * det)));
    const double g00 = a * j00 + b * j11, g01 = a * j01 - b * j10;
    const double g10 = a * j10 - b * j01, g11 = a * j11 + b * j00;
    // dE/dD = dE/dJ * R^T.
    gd1 = {g00 * r.r00 + g01 * r.r01, g10 * r.r00 + g11 * r.r01};
    gd2 = {g00 * r.r10 + g01 * r.r11, g10 * r.r10 + g11 * r.r11};
    return true;
  }

  // Energy and (optionally) gradient at x. Returns +inf if any triangle is inverted or degenerate.
  // Large meshes evaluate the triangles in parallel into per-triangle slots, then sum and scatter them in
  // triangle order, so the result is bit-identical for any thread count.
  double eval(const std::vector<Vec2>& x, std::vector<Vec2>* grad, double* alignment_part = nullptr) const {
    if (grad) std::fill(grad->begin(), grad->end(), Vec2{});
    double e = 0.0;
    const std::size_t nt = problem.triangles.size();
    if (nt >= kParallelTriangles) {
      values.resize(nt);
      grads.resize(grad ? 2 * nt : 0);
      std::atomic<bool> bad{false};
      oneapi::tbb::parallel_for(oneapi::tbb::blocked_range<std::size_t>(0, nt, 1024),
                                [&](const oneapi::tbb::blocked_range<std::size_t>& range) {
                                  for (std::size_t t = range.begin(); t != range.end(); ++t) {
                                    Vec2 g1, g2;
                                    if (!triangle_term(x, t, values[t], g1, g2, grad != nullptr)) {
                                      bad = true;
                                      return;
                                    }
                                    if (grad) { grads[2 * t] = g1; grads[2 * t + 1] = g2; }
                                  }
                                });
      if (bad) return kInf;
      for (std::size_t t = 0; t < nt; ++t) {
        e += values[t];
        if (!grad) continue;
        const auto& tri = problem.triangles[t];
        (*grad)[tri[1]] = (*grad)[tri[1]] + grads[2 * t];
        (*grad)[tri[2]] = (*grad)[tri[2]] + grads[2 * t + 1];
        (*grad)[tri[0]] = (*grad)[tri[0]] - grads[2 * t] - grads[2 * t + 1];
      }
    } else {
      for (std::size_t t = 0; t < nt; ++t) {
        double val;
        Vec2 gd1, gd2;
        if (!triangle_term(x, t, val, gd1, gd2, grad != nullptr)) return kInf;
        e += val;
        if (!grad) continue;
        const auto& tri = problem.triangles[t];
        (*grad)[tri[1]] = (*grad)[tri[1]] + gd1;
        (*grad)[tri[2]] = (*grad)[tri[2]] + gd2;
        (*grad)[tri[0]] = (*grad)[tri[0]] - gd1 - gd2;
      }
    }
    double align = 0.0;
    if (with_alignment) {
      const double eps2 = eps * eps;
      for (std::size_t k = 0; k < problem.aligned.size(); ++k) {
        const AlignedEdge& ed = problem.aligned[k];
        const Vec2 d = x[ed.b] - x[ed.a];
        const double w = ed.weight * edge_scale[k];
        if (ed.label >= 0) {
          // d in the label's frame: along (par) and across (perp) its direction, in units of the rest length.
          const Vec2 dir = ed.label == 0 ? Vec2{1, 0} : ed.label == 1 ? Vec2{0, 1} : ed.label == 2 ? Vec2{-1, 0} : Vec2{0, -1};
          const Vec2 nrm{-dir.y, dir.x};
          const double inv = 1.0 / rest_length[k];
          const double perp = dot(d, nrm) * inv, back = std::max(0.0, -dot(d, dir) * inv);
          align += w * (perp * perp + back * back);
          if (!grad) continue;
          const Vec2 g = (2.0 * w * inv) * (perp * nrm - back * dir);
          (*grad)[ed.b] = (*grad)[ed.b] + g;
          (*grad)[ed.a] = (*grad)[ed.a] - g;
          continue;
        }
        const double len = norm(d);
        if (!(len > 0.0)) return kInf;
        const Vec2 u = (1.0 / len) * d;
        const double sx = std::sqrt(u.x * u.x + eps2), sy = std::sqrt(u.y * u.y + eps2);
        // Smoothed ||n||_1 - 1 (the L1 norm of the unit normal equals that of the unit direction).
        align += w * (sx + sy - 1.0);
        if (!grad) continue;
        const Vec2 q{u.x / sx, u.y / sy};
        const double uq = dot(u, q);
        const Vec2 g = (w / len) * (q - uq * u);  // (I - u u^T) q / |d|
        (*grad)[ed.b] = (*grad)[ed.b] + g;
        (*grad)[ed.a] = (*grad)[ed.a] - g;
      }
    }
    if (anchor)
      for (std::size_t v = 0; v < x.size(); ++v) {
        if (!(*anchor_mask)[v]) continue;
        const Vec2 d = x[v] - (*anchor)[v];
        align += anchor_weight * dot(d, d);
        if (grad) (*grad)[v] = (*grad)[v] + (2.0 * anchor_weight) * d;
      }
    if (alignment_part) *alignment_part = align;
    if (grad && !problem.fixed.empty())
      for (std::size_t v = 0; v < grad->size(); ++v)
        if (problem.fixed[v]) (*grad)[v] = {};
    return e + align;
  }
};

// Largest step along p before triangle t's signed area reaches zero (inf if it never does).
double triangle_max_step(const std::array<std::int32_t, 3>& t, const std::vector<Vec2>& x, const std::vector<Vec2>& p) {
  const Vec2 a = x[t[1]] - x[t[0]], b = x[t[2]] - x[t[0]];
  const Vec2 da = p[t[1]] - p[t[0]], db = p[t[2]] - p[t[0]];
  // area(s) = c + s*bb + s^2*aa
  const double c = cross(a, b), bb = cross(a, db) + cross(da, b), aa = cross(da, db);
  if (c > 0 && bb >= 0 && aa >= 0) return kInf;  // every term stays >= 0 for s > 0: no root (and no sqrt)
  double root = kInf;
  if (std::abs(aa) < 1e-300) {
    if (bb < 0) root = -c / bb;
  } else {
    const double disc = bb * bb - 4 * aa * c;
    if (disc >= 0) {
      const double sq = std::sqrt(disc);
      // Numerically stable roots.
      const double q = -0.5 * (bb + (bb >= 0 ? sq : -sq));
      const double r1 = q / aa, r2 = (q != 0.0) ? c / q : kInf;
      for (double r : {r1, r2})
        if (r > 0 && r < root) root = r;
    }
  }
  return root;
}

// Largest step along p before some triangle's signed area reaches zero (inf if none does). Large meshes take
// the minimum over blocks in parallel: a minimum does not depend on the order, so neither does the step.
double max_feasible_step(const DeformProblem& pr, const std::vector<Vec2>& x, const std::vector<Vec2>& p) {
  const std::size_t nt = pr.triangles.size();
  auto block_min = [&](std::size_t begin, std::size_t end, double m) {
    for (std::size_t t = begin; t < end; ++t) m = std::min(m, triangle_max_step(pr.triangles[t], x, p));
    return m;
  };
  if (nt < Energy::kParallelTriangles) return block_min(0, nt, kInf);
  return oneapi::tbb::parallel_reduce(
      oneapi::tbb::blocked_range<std::size_t>(0, nt, 1024), kInf,
      [&](const oneapi::tbb::blocked_range<std::size_t>& r, double m) { return block_min(r.begin(), r.end(), m); },
      [](double a, double b) { return std::min(a, b); });
}

double dotv(const std::vector<Vec2>& a, const std::vector<Vec2>& b) {
  double s = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) s += dot(a[i], b[i]);
  return s;
}

// An approximation of the energy's Hessian at the rest shape, the same for both coordinates: the area-weighted
// Dirichlet stiffness of the triangles (what AMIPS is, to second order, at a rigid motion), the aligned edges'
// springs and the anchors; fixed vertices decoupled. L-BFGS started from its inverse instead of a multiple of
// the identity needs far fewer iterations on large meshes (the plain one's count grows with the mesh's width in
// triangles, since a step moves information about one ring of triangles).
class Preconditioner {
 public:
  Preconditioner(const Energy& energy, const DeformProblem& pr) {
    const std::size_t n = pr.rest.size();
    std::vector<Eigen::Triplet<double>> t;
    t.reserve(9 * pr.triangles.size() + 4 * pr.aligned.size() + n);
    std::vector<double> diag(n, 0.0);
    auto fixed = [&](std::int32_t v) { return !pr.fixed.empty() && pr.fixed[static_cast<std::size_t>(v)]; };
    auto spring = [&](std::int32_t a, std::int32_t b, double k) {
      if (!(k > 0.0)) return;
      diag[static_cast<std::size_t>(a)] += k;
      diag[static_cast<std::size_t>(b)] += k;
      if (!fixed(a) && !fixed(b)) {
        t.emplace_back(a, b, -k);
        t.emplace_back(b, a, -k);
      }
    };
    // AMIPS to second order at rest (J = I + H): c_angle ((h00 - h11)^2 + (h01 + h10)^2) + c_area tr(H)^2; its
    // isotropic part, mu |H|^2, summed over the triangles is the Dirichlet energy of the displacement.
    const double mu = 2.0 * (energy.c_angle + 0.5 * energy.c_area);
    for (std::size_t k = 0; k < pr.triangles.size(); ++k) {
      const auto& tri = pr.triangles[k];
      const RestTriangle& r = energy.rest[k];
      // Gradients of the three barycentric functions: rows of R (d/d x1, d/d x2), and minus their sum for x0.
      const Vec2 g1{r.r00, r.r01}, g2{r.r10, r.r11};
      const Vec2 g[3] = {-1.0 * (g1 + g2), g1, g2};
      for (int i = 0; i < 3; ++i)
        for (int j = i + 1; j < 3; ++j) spring(tri[i], tri[j], -mu * r.weight * dot(g[i], g[j]));
    }
    for (std::size_t k = 0; k < pr.aligned.size(); ++k) {
      const AlignedEdge& e = pr.aligned[k];
      spring(e.a, e.b, e.weight * energy.edge_scale[k] / (energy.rest_length[k] * energy.rest_length[k]));
    }
    if (energy.anchor)
      for (std::size_t v = 0; v < n; ++v)
        if ((*energy.anchor_mask)[v]) diag[v] += 2.0 * energy.anchor_weight;
    double mean = 0.0;
    for (double d : diag) mean += d;
    mean = n ? mean / static_cast<double>(n) : 1.0;
    if (!(mean > 0.0)) mean = 1.0;
    for (std::size_t v = 0; v < n; ++v)
      t.emplace_back(v, v, fixed(static_cast<std::int32_t>(v)) ? mean : diag[v] + 1e-6 * mean);
    Eigen::SparseMatrix<double> m(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
    m.setFromTriplets(t.begin(), t.end());
    solver_.compute(m);
    ok_ = solver_.info() == Eigen::Success;
    rhs_.resize(static_cast<Eigen::Index>(n), 2);
  }
  bool ok() const { return ok_; }
  // v <- M^-1 v, both coordinates.
  void apply(std::vector<Vec2>& v) const {
    for (std::size_t i = 0; i < v.size(); ++i) {
      rhs_(static_cast<Eigen::Index>(i), 0) = v[i].x;
      rhs_(static_cast<Eigen::Index>(i), 1) = v[i].y;
    }
    const Eigen::MatrixX2d out = solver_.solve(rhs_);
    for (std::size_t i = 0; i < v.size(); ++i) v[i] = {out(static_cast<Eigen::Index>(i), 0), out(static_cast<Eigen::Index>(i), 1)};
  }

 private:
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver_;
  mutable Eigen::MatrixX2d rhs_;
  bool ok_ = false;
};

// L-BFGS with an inversion-free backtracking line search (started from `pre`'s inverse when given). Returns the
// iteration count.
int minimize(const Energy& energy, const DeformProblem& pr, std::vector<Vec2>& x, int max_iter, double rtol, int memory,
             const Preconditioner* pre = nullptr) {
  const std::size_t n = x.size();
  std::vector<Vec2> g(n), g_new(n), p(n), x_new(n), s_new(n), y_new(n), my;
  double f = energy.eval(x, &g);
  if (!std::isfinite(f)) return 0;
  std::deque<std::vector<Vec2>> S, Y;
  std::deque<double> rho;
  int it = 0, small_steps = 0;
  for (; it < max_iter; ++it) {
    // Two-loop recursion: p = -H g.
    p = g;
    std::vector<double> alpha(S.size());
    for (int i = static_cast<int>(S.size()) - 1; i >= 0; --i) {
      alpha[i] = rho[i] * dotv(S[i], p);
      for (std::size_t v = 0; v < n; ++v) p[v] = p[v] - alpha[i] * Y[i][v];
    }
    if (pre) {
      // H0 = gamma M^-1 with gamma = s'y / y'M^-1 y (the identity's scaling, in M's inner product).
      pre->apply(p);
      if (!S.empty()) {
        my = Y.back();
        pre->apply(my);
        const double gamma = dotv(S.back(), Y.back()) / dotv(Y.back(), my);
        for (auto& v : p) v = gamma * v;
      }
    } else if (!S.empty()) {
      const double gamma = dotv(S.back(), Y.back()) / dotv(Y.back(), Y.back());
      for (auto& v : p) v = gamma * v;
    }
    for (std::size_t i = 0; i < S.size(); ++i) {
      const double beta = rho[i] * dotv(Y[i], p);
      for (std::size_t v = 0; v < n; ++v) p[v] = p[v] + (alpha[i] - beta) * S[i][v];
    }
    for (auto& v : p) v = -1.0 * v;
    double slope = dotv(g, p);
    if (!(slope < 0)) {  // not a descent direction: restart with steepest descent
      S.clear(); Y.clear(); rho.clear();
      for (std::size_t v = 0; v < n; ++v) p[v] = -1.0 * g[v];
      slope = dotv(g, p);
      if (!(slope < 0)) break;
    }
    double step = 1.0;
    if (S.empty()) {  // first step: limit the largest move to a fraction of the mean edge
      double pmax = 0.0;
      for (const auto& v : p) pmax = std::max(pmax, norm(v));
      if (pmax > 0) step = std::min(1.0, 0.1 / pmax);
    }
    step = std::min(step, 0.8 * max_feasible_step(pr, x, p));
    double f_new = kInf;
    bool ok = false;
    for (int ls = 0; ls < 50; ++ls) {
      for (std::size_t v = 0; v < n; ++v) x_new[v] = x[v] + step * p[v];
      f_new = energy.eval(x_new, &g_new);
      if (std::isfinite(f_new) && f_new <= f + 1e-4 * step * slope) { ok = true; break; }
      step *= 0.5;
    }
    if (!ok) {
      if (S.empty()) break;
      S.clear(); Y.clear(); rho.clear();
      continue;
    }
    for (std::size_t v = 0; v < n; ++v) { s_new[v] = x_new[v] - x[v]; y_new[v] = g_new[v] - g[v]; }
    const double sy = dotv(s_new, y_new);
    if (sy > 1e-300) {
      // A full history hands its oldest pair's storage to the next step: no allocation per iteration.
      std::vector<Vec2> free_s, free_y;
      S.push_back(std::move(s_new)); Y.push_back(std::move(y_new)); rho.push_back(1.0 / sy);
      if (static_cast<int>(S.size()) > memory) {
        free_s = std::move(S.front());
        free_y = std::move(Y.front());
        S.pop_front(); Y.pop_front(); rho.pop_front();
      }
      s_new = std::move(free_s);
      y_new = std::move(free_y);
      s_new.resize(n);
      y_new.resize(n);
    }
    const double decrease = f - f_new;
    x.swap(x_new);
    g.swap(g_new);
    f = f_new;
    small_steps = decrease < rtol * std::abs(f) ? small_steps + 1 : 0;
    if (small_steps >= 5) { ++it; break; }
  }
  return it;
}

// Everything a solve reads, into the memo's key.
void digest_problem(Digest& d, const DeformProblem& p, const DeformOptions& o, const std::vector<Vec2>& x) {
  for (double v : {o.amips_alpha, o.amips_s, o.relative_tolerance}) d.real(v);
  d.word(static_cast<std::uint64_t>(o.max_iterations));
  d.word(static_cast<std::uint64_t>(o.lbfgs_memory));
  d.word(o.precondition ? 1u : 0u);
  d.raw(o.eps_schedule);
  d.raw(p.rest);
  if (!p.rest_scale.empty()) d.raw(p.rest_scale);
  d.raw(p.triangles);
  d.word(p.aligned.size());
  for (const AlignedEdge& e : p.aligned) {  // field by field: the struct has padding
    d.word(static_cast<std::uint64_t>(static_cast<std::uint32_t>(e.a)) << 32 | static_cast<std::uint32_t>(e.b));
    d.real(e.weight);
    d.word(static_cast<std::uint64_t>(e.label + 1));
  }
  d.raw(p.fixed);
  d.raw(x);
}

}  // namespace

struct DeformMemo::Impl {
  struct Entry {
    std::vector<Vec2> x;
    DeformStats stats;
    bool ok = false;
  };
  mutable std::mutex mutex;
  std::map<Key, Entry> entries;
  std::size_t max_bytes = 0, bytes = 0;
  mutable std::size_t hits = 0;
};

DeformMemo::DeformMemo(std::size_t max_bytes) : impl_(std::make_unique<Impl>()) { impl_->max_bytes = max_bytes; }
DeformMemo::~DeformMemo() = default;

bool DeformMemo::find(const Key& key, std::vector<Vec2>& x, DeformStats& stats, bool& ok) const {
  const std::lock_guard<std::mutex> lock(impl_->mutex);
  const auto it = impl_->entries.find(key);
  if (it == impl_->entries.end()) return false;
  x = it->second.x;
  stats = it->second.stats;
  ok = it->second.ok;
  ++impl_->hits;
  return true;
}

void DeformMemo::store(const Key& key, const std::vector<Vec2>& x, const DeformStats& stats, bool ok) {
  const std::lock_guard<std::mutex> lock(impl_->mutex);
  const std::size_t b = x.size() * sizeof(Vec2);
  if (impl_->bytes + b > impl_->max_bytes) return;
  if (impl_->entries.try_emplace(key, Impl::Entry{x, stats, ok}).second) impl_->bytes += b;
}

std::size_t DeformMemo::hits() const {
  const std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->hits;
}

double min_signed_area(const std::vector<std::array<std::int32_t, 3>>& triangles, const std::vector<Vec2>& x) {
  double m = kInf;
  for (const auto& t : triangles) m = std::min(m, 0.5 * orient2(x[t[0]], x[t[1]], x[t[2]]));
  return m;
}

DeformStats deform_to_polysquare(const DeformProblem& problem, const DeformOptions& options, std::vector<Vec2>& x) {
  DeformStats stats;
  DeformMemo::Key key{};
  if (options.memo) {
    Digest d;
    d.word(1);  // which solve
    digest_problem(d, problem, options, x);
    key = d.key();
    bool ok = false;
    if (options.memo->find(key, x, stats, ok)) return stats;
  }
  Energy energy(problem, options);
  energy.eps = options.eps_schedule.empty() ? 0.01 : options.eps_schedule.back();
  stats.energy_before = energy.eval(x, nullptr, &stats.alignment_before);
  std::optional<Preconditioner> pre;
  if (options.precondition) {
    pre.emplace(energy, problem);
    if (!pre->ok()) pre.reset();
  }
  for (double eps : options.eps_schedule) {
    energy.eps = eps;
    stats.iterations += minimize(energy, problem, x, options.max_iterations, options.relative_tolerance,
                                 options.lbfgs_memory, pre ? &*pre : nullptr);
  }
  stats.energy_after = energy.eval(x, nullptr, &stats.alignment_after);
  if (options.memo) options.memo->store(key, x, stats, true);
  return stats;
}

namespace {
bool move_along_path(const DeformProblem& problem, const DeformOptions& options,
                     const std::vector<std::uint8_t>& target_mask, const std::vector<Vec2>& targets,
                     std::vector<Vec2>& x, bool& untangled);
}  // namespace

bool move_constrained_vertices(const DeformProblem& problem, const DeformOptions& options,
                               const std::vector<std::uint8_t>& target_mask, const std::vector<Vec2>& targets,
                               std::vector<Vec2>& x, bool* untangled) {
  DeformStats path;
  if (!options.memo) {
    const bool ok = move_along_path(problem, options, target_mask, targets, x, path.untangled);
    if (untangled) *untangled = path.untangled;
    return ok;
  }
  Digest d;
  d.word(2);  // which solve
  d.word(options.pull_when_path_fails ? 1 : 0);
  d.word(options.untangle_when_path_fails ? 1 : 0);
  digest_problem(d, problem, options, x);
  d.raw(target_mask);
  d.raw(targets);
  const DeformMemo::Key key = d.key();
  bool ok = false;
  if (!options.memo->find(key, x, path, ok)) {
    ok = move_along_path(problem, options, target_mask, targets, x, path.untangled);
    options.memo->store(key, x, path, ok);
  }
  if (untangled) *untangled = path.untangled;
  return ok;
}

namespace {

bool straight_path(const DeformProblem& problem, const DeformOptions& options,
                   const std::vector<std::uint8_t>& target_mask, const std::vector<Vec2>& targets,
                   std::vector<Vec2>& x, bool& untangled);

// The constrained vertices are first pulled towards their targets by springs of growing stiffness, the
// barrier keeping every triangle valid: unlike the straight path, each vertex may take its own way round.
void pull_towards(const DeformProblem& problem, const DeformOptions& options,
                  const std::vector<std::uint8_t>& target_mask, const std::vector<Vec2>& targets,
                  std::vector<Vec2>& x) {
  Energy energy(problem, options);
  energy.with_alignment = false;  // AMIPS and the springs only; every vertex but problem.fixed moves
  energy.anchor = &targets;
  energy.anchor_mask = &target_mask;
  const double constrained = static_cast<double>(std::max<std::size_t>(
      1, static_cast<std::size_t>(std::count(target_mask.begin(), target_mask.end(), std::uint8_t{1}))));
  for (double w = 1.0; w <= 1e8; w *= 10.0) {
    energy.anchor_weight = w / constrained;
    minimize(energy, problem, x, 300, 1e-9, options.lbfgs_memory);
  }
}

bool move_along_path(const DeformProblem& problem, const DeformOptions& options,
                     const std::vector<std::uint8_t>& target_mask, const std::vector<Vec2>& targets,
                     std::vector<Vec2>& x, bool& untangled) {
  if (!options.pull_when_path_fails) return straight_path(problem, options, target_mask, targets, x, untangled);
  const std::vector<Vec2> start = x;
  if (straight_path(problem, options, target_mask, targets, x, untangled)) return true;
  x = start;
  pull_towards(problem, options, target_mask, targets, x);
  return straight_path(problem, options, target_mask, targets, x, untangled);
}

bool straight_path(const DeformProblem& problem, const DeformOptions& options,
                   const std::vector<std::uint8_t>& target_mask, const std::vector<Vec2>& targets,
                   std::vector<Vec2>& x, bool& untangled) {
  untangled = false;
  const std::size_t n = x.size();
  // Harmonic (uniform graph Laplacian) extension of the constrained displacement to the free vertices, so a
  // step moves the interior along with the boundary instead of crushing the first ring of triangles.
  std::vector<int> free_index(n, -1);
  int nfree = 0;
  for (std::size_t v = 0; v < n; ++v)
    if (!target_mask[v]) free_index[v] = nfree++;
  std::vector<Vec2> disp(n);
  for (std::size_t v = 0; v < n; ++v)
    if (target_mask[v]) disp[v] = targets[v] - x[v];
  // Uniform graph Laplacian over the free vertices; `harmonic(values)` extends values given on the constrained
  // vertices harmonically (each interior edge appears twice: weights stay symmetric).
  std::vector<Eigen::Triplet<double>> trip;
  for (const auto& t : problem.triangles)
    for (int k = 0; k < 3; ++k)
      for (auto [u, w] : {std::pair{t[k], t[(k + 1) % 3]}, std::pair{t[(k + 1) % 3], t[k]}}) {
        if (free_index[u] < 0) continue;
        trip.emplace_back(free_index[u], free_index[u], 1.0);
        if (free_index[w] >= 0) trip.emplace_back(free_index[u], free_index[w], -1.0);
      }
  Eigen::SparseMatrix<double> L(nfree, nfree);
  L.setFromTriplets(trip.begin(), trip.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver;
  if (nfree > 0) solver.compute(L);
  const bool solvable = nfree > 0 && solver.info() == Eigen::Success;
  auto harmonic = [&](std::vector<Vec2>& values) {  // values[v] given where target_mask[v]; fills the others
    if (!solvable) return false;
    Eigen::VectorXd bx = Eigen::VectorXd::Zero(nfree), by = Eigen::VectorXd::Zero(nfree);
    for (const auto& t : problem.triangles)
      for (int k = 0; k < 3; ++k)
        for (auto [u, w] : {std::pair{t[k], t[(k + 1) % 3]}, std::pair{t[(k + 1) % 3], t[k]}})
          if (free_index[u] >= 0 && free_index[w] < 0) { bx[free_index[u]] += values[w].x; by[free_index[u]] += values[w].y; }
    const Eigen::VectorXd sx = solver.solve(bx), sy = solver.solve(by);
    for (std::size_t v = 0; v < n; ++v)
      if (free_index[v] >= 0) values[v] = {sx[free_index[v]], sy[free_index[v]]};
    return true;
  };
  harmonic(disp);
  DeformProblem inner = problem;
  inner.aligned.clear();
  inner.fixed.assign(n, 0);
  for (std::size_t v = 0; v < n; ++v) inner.fixed[v] = target_mask[v] || (!problem.fixed.empty() && problem.fixed[v]);
  Energy energy(inner, options);
  energy.with_alignment = false;

  const std::vector<Vec2> start = x;
  double t = 0.0, step = 1.0;
  std::vector<Vec2> trial(n);
  while (t < 1.0) {
    const double t_new = std::min(1.0, t + step);
    for (std::size_t v = 0; v < n; ++v)
      trial[v] = target_mask[v] ? lerp(start[v], targets[v], t_new) : x[v] + (t_new - t) * disp[v];
    if (min_signed_area(problem.triangles, trial) <= 0.0) {
      step *= 0.5;
      if (step < 1e-7) {
        // The straight-line path swept the boundary through itself (the quantized shape is far from the
        // deformed one). The uniform harmonic (Tutte) embedding with every constrained vertex on its target is
        // bijective when they bound a convex polygon (Tutte's theorem: a rectangle, the common subregion), and
        // is accepted in any case only if no triangle is inverted; AMIPS then improves it.
        // Otherwise the folds of the Tutte embedding are untangled with the boundary on its targets.
        std::vector<Vec2> tutte = targets;
        if (!harmonic(tutte)) return false;
        if (min_signed_area(problem.triangles, tutte) <= 0.0) {
          if (!options.untangle_when_path_fails) return false;
          std::vector<std::uint8_t> movable(n, 0);
          for (std::size_t v = 0; v < n; ++v) movable[v] = !inner.fixed[v];
          if (!untangle_triangles(problem, movable, tutte)) return false;
          untangled = true;
        }
        x = tutte;
        break;
      }
      continue;
    }
    x.swap(trial);
    minimize(energy, inner, x, 200, 1e-7, options.lbfgs_memory);
    t = t_new;
    step = std::min(1.0, step * 2.0);
  }
  for (std::size_t v = 0; v < n; ++v)
    if (target_mask[v]) x[v] = targets[v];
  minimize(energy, inner, x, options.max_iterations, options.relative_tolerance, options.lbfgs_memory);
  return min_signed_area(problem.triangles, x) > 0.0;
}

}  // namespace

}  // namespace polysquare
