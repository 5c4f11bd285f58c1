// What the map stage's two paths share: the single poly-square map of a part (polysquare_map.cpp) and the
// Piecewise Poly-square Map of a partitioned part (piecewise_map.cpp) both deform, label, snap and check
// through this module (map_common.cpp) instead of calling into each other. The deformation, labelled
// deformation and snap are public (polysquare/map/polysquare_map.h: deform_mesh, deformed_mesh,
// straighten_to_labels, snap_to_layout, preorientation_angle); the helpers below are internal.
#pragma once

#include <chrono>
#include <string>

#include <vector>

#include "polysquare/map/layout.h"
#include "polysquare/map/polysquare_map.h"

namespace polysquare {

/// Seconds since `t0`: the time of a stage, for the part's figures.
double seconds_since(std::chrono::steady_clock::time_point t0);

/// Empty when the quantized `layout` is a valid poly-square (check_layout), else why not, naming `name`.
std::string invalid_poly_square(const Layout& layout, const std::string& name);

/// The size a mesh of `tri` has on average: options.size, or with a size field the size whose square is the
/// mean area per quad (area over the integral of 1 / h^2). `ratios` (when given) receives each triangle's size
/// at its centroid over options.size.
double local_size(const TriMesh& tri, const PolysquareMapOptions& options, std::vector<double>* ratios = nullptr);

/// The least size over `tri` (the field at its triangles' centroids; options.size without a field): the size of
/// an unstructured patch, whose boundary nodes come at its neighbours' finest spacing.
double least_size(const TriMesh& tri, const PolysquareMapOptions& options);

}  // namespace polysquare
