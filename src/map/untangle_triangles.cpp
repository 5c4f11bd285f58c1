#include "map/untangle_triangles.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>

namespace polysquare {
namespace {

// The regularized denominator chi(D, eps) = (D + sqrt(eps^2 + D^2)) / 2: positive for every D when eps > 0, and
// D itself for D > 0 as eps -> 0.
double chi(double d, double eps) { return 0.5 * (d + std::sqrt(eps * eps + d * d)); }

struct Untangler {
  const DeformProblem& problem;
  const std::vector<std::uint8_t>& movable;
  std::vector<std::array<double, 5>> rest;  // inverse rest edge matrix (r00, r01, r10, r11) and the weight
  std::vector<std::int32_t> index;          // vertex -> unknown pair, -1 when fixed
  std::size_t unknowns = 0;
  double theta = 1.0 / 128.0;  // share of the area term against the shape term (the paper's choice)

  Untangler(const DeformProblem& p, const std::vector<std::uint8_t>& m) : problem(p), movable(m) {
    double total = 0.0;
    for (const auto& t : p.triangles) {
      const Vec2 a = p.rest[t[1]] - p.rest[t[0]], b = p.rest[t[2]] - p.rest[t[0]];
      const double det = cross(a, b);
      rest.push_back({b.y / det, -b.x / det, -a.y / det, a.x / det, 0.5 * std::abs(det)});
      total += 0.5 * std::abs(det);
    }
    const double mean = total / static_cast<double>(std::max<std::size_t>(1, rest.size()));
    for (auto& r : rest) r[4] /= mean;
    index.assign(p.rest.size(), -1);
    for (std::size_t v = 0; v < index.size(); ++v)
      if (movable[v]) index[v] = static_cast<std::int32_t>(unknowns++);
  }

  // J = E R^-1 for triangle t at positions x: J = [[j00, j01], [j10, j11]].
  std::array<double, 4> jacobian(std::size_t t, const std::vector<Vec2>& x) const {
    const auto& tr = problem.triangles[t];
    const Vec2 a = x[tr[1]] - x[tr[0]], b = x[tr[2]] - x[tr[0]];
    const auto& r = rest[t];
    return {a.x * r[0] + b.x * r[2], a.x * r[1] + b.x * r[3], a.y * r[0] + b.y * r[2], a.y * r[1] + b.y * r[3]};
  }

  double min_det(const std::vector<Vec2>& x) const {
    double m = std::numeric_limits<double>::infinity();
    for (std::size_t t = 0; t < rest.size(); ++t) {
      const auto j = jacobian(t, x);
      m = std::min(m, j[0] * j[3] - j[1] * j[2]);
    }
    return m;
  }

  // Energy at x (and its gradient over the unknowns when g is given).
  double energy(const std::vector<Vec2>& x, double eps, std::vector<double>* g) const {
    if (g) g->assign(2 * unknowns, 0.0);
    double e = 0.0;
    for (std::size_t t = 0; t < rest.size(); ++t) {
      const auto j = jacobian(t, x);
      const double d = j[0] * j[3] - j[1] * j[2];
      const double f = j[0] * j[0] + j[1] * j[1] + j[2] * j[2] + j[3] * j[3];
      const double root = std::sqrt(eps * eps + d * d);
      const double c = 0.5 * (d + root);
      const double w = rest[t][4];
      e += w * ((1.0 - theta) * f / c + theta * (d * d + 1.0) / c);
      if (!g) continue;
      const double dc = c / root;  // d chi / d D
      // dE/dJ = (1-theta) (2J / c - f dc / c^2 cof) + theta (2 d / c - (d^2 + 1) dc / c^2) cof
      const double kd = (1.0 - theta) * (-f * dc / (c * c)) + theta * (2.0 * d / c - (d * d + 1.0) * dc / (c * c));
      const double kj = (1.0 - theta) * 2.0 / c;
      const double cof[4] = {j[3], -j[2], -j[1], j[0]};
      double gj[4];
      for (int k = 0; k < 4; ++k) gj[k] = w * (kj * j[k] + kd * cof[k]);
      // dE/dE_edges = dE/dJ R^-T: columns are the gradients of the two edge vectors.
      const auto& r = rest[t];
      const double ga_x = gj[0] * r[0] + gj[1] * r[1], gb_x = gj[0] * r[2] + gj[1] * r[3];
      const double ga_y = gj[2] * r[0] + gj[3] * r[1], gb_y = gj[2] * r[2] + gj[3] * r[3];
      const auto& tr = problem.triangles[t];
      auto add = [&](std::int32_t v, double gx, double gy) {
        const std::int32_t i = index[static_cast<std::size_t>(v)];
        if (i < 0) return;
        (*g)[2 * static_cast<std::size_t>(i)] += gx;
        (*g)[2 * static_cast<std::size_t>(i) + 1] += gy;
      };
      add(tr[1], ga_x, ga_y);
      add(tr[2], gb_x, gb_y);
      add(tr[0], -ga_x - gb_x, -ga_y - gb_y);
    }
    return e;
  }

  void set(std::vector<Vec2>& x, const std::vector<double>& u) const {
    for (std::size_t v = 0; v < index.size(); ++v)
      if (index[v] >= 0) x[v] = {u[2 * static_cast<std::size_t>(index[v])], u[2 * static_cast<std::size_t>(index[v]) + 1]};
  }

  // L-BFGS with a backtracking (Armijo) line search at fixed eps.
  void minimize(std::vector<Vec2>& x, double eps, int max_iterations) const {
    std::vector<double> u(2 * unknowns), g, trial_g, dir(2 * unknowns);
    for (std::size_t v = 0; v < index.size(); ++v)
      if (index[v] >= 0) u[2 * static_cast<std::size_t>(index[v])] = x[v].x, u[2 * static_cast<std::size_t>(index[v]) + 1] = x[v].y;
    double e = energy(x, eps, &g);
    std::deque<std::pair<std::vector<double>, std::vector<double>>> history;  // (s, y)
    std::vector<double> trial_u(u.size());
    std::vector<Vec2> trial_x = x;
    auto dotp = [](const std::vector<double>& a, const std::vector<double>& b) {
      double s = 0.0;
      for (std::size_t i = 0; i < a.size(); ++i) s += a[i] * b[i];
      return s;
    };
    for (int it = 0; it < max_iterations; ++it) {
      dir = g;
      std::vector<double> alpha(history.size());
      for (std::size_t k = history.size(); k-- > 0;) {
        const auto& [s, y] = history[k];
        alpha[k] = dotp(s, dir) / dotp(y, s);
        for (std::size_t i = 0; i < dir.size(); ++i) dir[i] -= alpha[k] * y[i];
      }
      if (!history.empty()) {
        const auto& [s, y] = history.back();
        const double scale = dotp(s, y) / dotp(y, y);
        for (double& d : dir) d *= scale;
      } else {
        const double norm = std::sqrt(dotp(g, g));
        if (norm > 0.0) for (double& d : dir) d /= norm;
      }
      for (std::size_t k = 0; k < history.size(); ++k) {
        const auto& [s, y] = history[k];
        const double beta = dotp(y, dir) / dotp(y, s);
        for (std::size_t i = 0; i < dir.size(); ++i) dir[i] += (alpha[k] - beta) * s[i];
      }
      double slope = -dotp(g, dir);
      if (slope >= 0.0) {  // not a descent direction: restart from the gradient
        history.clear();
        dir = g;
        slope = -dotp(g, dir);
      }
      if (slope > -1e-14) return;
      double step = 1.0, e_new = e;
      bool moved = false;
      for (int ls = 0; ls < 40; ++ls, step *= 0.5) {
        for (std::size_t i = 0; i < u.size(); ++i) trial_u[i] = u[i] - step * dir[i];
        set(trial_x, trial_u);
        e_new = energy(trial_x, eps, nullptr);
        if (e_new <= e + 1e-4 * step * slope) {
          moved = true;
          break;
        }
      }
      if (!moved) return;
      energy(trial_x, eps, &trial_g);
      std::vector<double> s(u.size()), y(u.size());
      for (std::size_t i = 0; i < u.size(); ++i) s[i] = trial_u[i] - u[i], y[i] = trial_g[i] - g[i];
      if (dotp(s, y) > 1e-16) {
        history.emplace_back(std::move(s), std::move(y));
        if (history.size() > 10) history.pop_front();
      }
      const bool small = e - e_new < 1e-9 * std::abs(e);
      u.swap(trial_u);
      g.swap(trial_g);
      x = trial_x;
      e = e_new;
      if (small) return;
    }
  }
};

}  // namespace

bool untangle_triangles(const DeformProblem& problem, const std::vector<std::uint8_t>& movable, std::vector<Vec2>& x) {
  Untangler u(problem, movable);
  if (u.unknowns == 0) return u.min_det(x) > 0.0;
  double d = u.min_det(x);
  double eps = d > 0.0 ? 1e-9 : std::max(1e-3, 2.0 * std::abs(d));
  double e_prev = u.energy(x, eps, nullptr);
  for (int outer = 0; outer < 100; ++outer) {
    u.minimize(x, eps, 500);
    const double e = u.energy(x, eps, nullptr);
    d = u.min_det(x);
    if (d > 0.0 && std::abs(e_prev - e) <= 1e-5 * std::abs(e)) break;
    // The schedule of the paper: eps shrinks with the energy's relative decrease, faster as it stalls.
    const double sigma = std::max(1.0 - e / e_prev, 0.1);
    const double mu = (1.0 - sigma) * chi(d, eps);
    eps = d < mu ? 2.0 * std::sqrt(mu * (mu - d)) : 1e-9;
    e_prev = u.energy(x, eps, nullptr);
  }
  return u.min_det(x) > 0.0;
}

}  // namespace polysquare
