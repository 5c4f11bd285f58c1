// Stage 4: inversion-free deformation of a triangle mesh towards a poly-square (FPPM Sec. 4.1-4.2).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "polysquare/core/geometry.h"

namespace polysquare {

class DeformMemo;

struct DeformOptions {
  double amips_alpha = 0.5;      ///< AMIPS balance of angle (alpha) against area (1 - alpha) distortion; paper: 0.5
  double amips_s = 5.0;          ///< AMIPS penalty scale s; paper: 5
  double boundary_weight = 5.0;  ///< lambda of E^B (eq. 8 in eq. 9); paper: 5
  double feature_weight = 1.0;   ///< weight of E^F (eq. 10); paper: 1
  /// Smoothing of |x| in the L1 terms, sqrt(x^2 + eps^2), decreasing over the solve because |x| is not
  /// differentiable at axis-aligned edges.
  std::vector<double> eps_schedule{0.2, 0.08, 0.03, 0.01};
  int max_iterations = 1500;     ///< L-BFGS iterations per eps stage
  double relative_tolerance = 1e-6;  ///< stop when the energy decrease per iteration stays below this fraction
                                     ///< (letter_M: 784 iterations, SJ min 0.86; 1e-8: 2567 iterations, 0.80)
  int lbfgs_memory = 8;          ///< L-BFGS history length
  /// L-BFGS starts each step from the inverse of the rest shape's stiffness (a sparse Cholesky factor, built once
  /// per solve) instead of a multiple of the identity: 5-8 times fewer iterations to the same energy. Off by
  /// default: it converges to other minima, so the meshes change (see the README's measurements).
  bool precondition = false;
  /// move_constrained_vertices: when the straight path from the deformed to the target positions inverts a
  /// triangle, pull the constrained vertices to their targets by stiffening springs first, then try again.
  bool pull_when_path_fails = false;
  /// move_constrained_vertices: when no path reaches the targets and the harmonic embedding on them folds, untangle
  /// its folds with the constrained vertices on their targets (map/untangle_triangles.h) before giving up.
  bool untangle_when_path_fails = false;
  /// Results of solved problems, shared by the copies of these options within one run (the pipeline sets it;
  /// null = none): a repair round re-maps every subregion of a part, most of them exactly as before.
  std::shared_ptr<DeformMemo> memo;
};

/// An edge whose deformed direction is pulled towards a coordinate axis (boundary or feature edge).
struct AlignedEdge {
  std::int32_t a = 0, b = 0;
  double weight = 1.0;  ///< boundary_weight for boundary edges, feature_weight for feature edges
  /// -1: pulled to the nearest axis (smoothed L1 of the direction, eq. 8/10). 0..3 (+X, +Y, -X, -Y, the layout's
  /// labels): the edge must run along that direction; its slope off the axis and any backward run are
  /// penalized quadratically, whose gradient, unlike the L1 term's, does not vanish on an edge at 90 degrees.
  int label = -1;
};

/// The deformation problem: rest shape, triangles (counter-clockwise in the rest shape) and aligned edges.
struct DeformProblem {
  std::vector<Vec2> rest;                              ///< #V rest positions
  std::vector<double> rest_scale;  ///< #T or empty (= 1): triangle t's rest shape is its rest positions scaled by
                                   ///< this (graded meshes: lattice units of the local size, so the rest shapes
                                   ///< need not fit together in the plane)
  std::vector<std::array<std::int32_t, 3>> triangles;  ///< #T
  std::vector<AlignedEdge> aligned;                    ///< E^B and E^F edges
  std::vector<std::uint8_t> fixed;                     ///< #V, 1 = vertex does not move (may be empty)
};

struct DeformStats {
  int iterations = 0;
  double energy_before = 0.0;
  double energy_after = 0.0;
  double alignment_before = 0.0;  ///< E^B + E^F part (with the last eps), before and after
  double alignment_after = 0.0;
  bool untangled = false;  ///< move_constrained_vertices: the targets were reached only by untangling folds
};

/// Solved deformations by a 128-bit digest of everything a solve reads (problem, options, start positions,
/// targets), so that an identical problem is solved once per run; solves are deterministic, so a reused result
/// is the one a new solve would give. Thread-safe. Past `max_bytes` of stored positions it stops storing.
class DeformMemo {
 public:
  using Key = std::array<std::uint64_t, 2>;
  explicit DeformMemo(std::size_t max_bytes = std::size_t{256} << 20);
  ~DeformMemo();
  DeformMemo(const DeformMemo&) = delete;
  DeformMemo& operator=(const DeformMemo&) = delete;
  /// The stored result of `key` into x, stats and ok; false when there is none.
  bool find(const Key& key, std::vector<Vec2>& x, DeformStats& stats, bool& ok) const;
  void store(const Key& key, const std::vector<Vec2>& x, const DeformStats& stats, bool ok);
  std::size_t hits() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Minimizes E^D (AMIPS, area-weighted) + weighted alignment terms from `x` (which must be un-inverted),
/// never leaving the set of un-flipped triangles. Fixed vertices keep their positions.
DeformStats deform_to_polysquare(const DeformProblem& problem, const DeformOptions& options, std::vector<Vec2>& x);

/// Moves the vertices flagged in `target_mask` to `targets` along a path of un-inverted meshes: the displacement
/// is extended harmonically to the free vertices, applied in steps that never flip a triangle, with the free
/// vertices re-optimized for AMIPS after every step. Returns false when no valid path was found. `untangled`
/// (when given) tells whether the targets were reached only by untangling (DeformOptions::untangle_when_path_fails).
bool move_constrained_vertices(const DeformProblem& problem, const DeformOptions& options,
                               const std::vector<std::uint8_t>& target_mask, const std::vector<Vec2>& targets,
                               std::vector<Vec2>& x, bool* untangled = nullptr);

/// Smallest signed area over the triangles (negative means inverted).
double min_signed_area(const std::vector<std::array<std::int32_t, 3>>& triangles, const std::vector<Vec2>& x);

}  // namespace polysquare
