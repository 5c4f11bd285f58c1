// The size field: the target quad edge length h(x) over a region, for graded meshes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "polysquare/core/geometry.h"
#include "polysquare/core/region.h"

namespace polysquare {

/// A size term sampled at points (the CLI's rasters: --size-field, --per-wavelength): h <= the value at each
/// point, in region units; +inf leaves a point unbounded.
struct SizeTerm {
  std::string name;  ///< for messages: the flag and its file
  std::function<std::vector<double>(const std::vector<Vec2>&)> at;  ///< sizes at the points, in their order
};

/// What the size at a point is made of. Each term bounds h from above; the field is the least of the terms given,
/// clipped to [size_min, size_max], then limited in gradient so that |h(x) - h(y)| <= grade |x - y|.
/// The region's size attributes are terms too: h <= s inside a domain part (Ring::size) or a closed feature curve
/// (Region::size_areas) of size s, and h <= s + grade * (distance to the curve) for a feature curve of size s
/// (FeatureCurve::size), whose curves and rings then leave the distance term (their size takes HMIN's place).
/// The terms follow OceanMesh2D's `edgefx` (Roberts et al., GMD 12, 2019): `dis` is the distance term, `fs` the
/// passage-width term, `g` the gradient limit.
struct SizeFieldOptions {
  double size_min = 0.0;        ///< HMIN (> 0): the size at the domain boundary and the feature curves (distance
                                ///< term) and the least size anywhere
  double size_max = 0.0;        ///< HMAX (>= size_min): the largest size
  double grade = 0.15;          ///< G (> 0): the gradient limit, and the growth of the distance term
  bool distance_term = true;    ///< h <= size_min + grade * (distance to the rings and the feature curves that
                                ///< have no size attribute)
  double across = 0.0;          ///< N > 0: h <= (local passage width) / N, so that N quads cross every passage
                                ///< between two shores (rings); 0 = off
  double medial_angle_deg = 120.0;  ///< a point is on a passage's mid-line when the directions to its nearest shore
                                    ///< points on either side open by more than this; smaller openings are
                                    ///< corners of one shore, not passages (they would ask for h -> 0 at corners)
  std::vector<SizeTerm> terms;  ///< more terms, sampled at the grid's cell centres inside the domain
  double cell = 0.0;            ///< grid spacing in region units; 0 = size_min / 2, coarsened to max_cells
  std::size_t max_cells = 4'000'000;  ///< the grid's cell budget (memory: about 40 bytes a cell while building)
};

/// The size of the quads: uniform (`h`), or graded by a field when `field.size_min` is set.
struct SizeOptions {
  double h = 0.0;                      ///< target quad edge length, region units (> 0). Graded: the least size,
                                       ///< which scales the stages' tolerances (set from field.size_min)
  std::size_t max_quads = 50'000'000;  ///< refuse sizes whose estimated quad count exceeds this
  SizeFieldOptions field;              ///< graded meshes: the field's terms (size_min > 0 turns grading on)
  bool graded() const { return field.size_min > 0.0; }
};

/// A size field sampled at the centres of a regular grid, evaluated bilinearly between them.
class SizeField {
 public:
  SizeField() = default;
  /// `h` holds nx * ny values, row by row from `origin` (the lower-left cell's centre), spacing `cell`.
  SizeField(Vec2 origin, double cell, int nx, int ny, std::vector<double> h);

  /// h at p: bilinear between the four nearest cell centres; a point beyond the grid takes the nearest edge value.
  double at(Vec2 p) const;
  bool empty() const { return h_.empty(); }
  int nx() const { return nx_; }
  int ny() const { return ny_; }
  double cell() const { return cell_; }
  Vec2 origin() const { return origin_; }
  Vec2 centre(int i, int j) const { return {origin_.x + i * cell_, origin_.y + j * cell_}; }
  const std::vector<double>& values() const { return h_; }

 private:
  Vec2 origin_;
  double cell_ = 0.0;
  int nx_ = 0, ny_ = 0;
  std::vector<double> h_;
};

/// What a field came out as, for the report and the estimate said before meshing.
struct SizeFieldStats {
  double min = 0.0, max = 0.0;      ///< over the grid cells inside the domain
  double estimated_quads = 0.0;     ///< integral of 1 / h^2 over the domain (sum over the cells inside)
  std::size_t cells = 0;            ///< grid cells
  std::size_t inside_cells = 0;     ///< of them, centres inside the domain
  double cell = 0.0;                ///< the grid spacing used
  std::size_t medial_cells = 0;     ///< with `across`: cells found on a passage's mid-line
  double narrowest_passage = 0.0;   ///< with `across`: the least width found on a mid-line (0 = none found)
  std::size_t limited_cells = 0;    ///< cells whose size the gradient limit lowered
};

struct SizeFieldResult {
  SizeField field;
  SizeFieldStats stats;
  std::vector<std::uint8_t> inside;  ///< per grid cell: its centre lies inside the domain
  std::vector<std::string> warnings;  ///< one sentence per input feature whose size attribute lies outside
                                      ///< [size_min, size_max] (the field takes the bound instead)
};

/// Refuses bad field options with an InputError that names the flag: non-finite or non-positive sizes,
/// size_min > size_max, a grade that is not a finite positive number, a negative `across`.
void check_size_field_options(const SizeFieldOptions& options);

/// Whether any ring, feature curve or size area of the region has a size attribute (only graded runs follow them).
bool has_size_attributes(const Region& region);

/// Builds the field of `options` over `region` (validated: closed rings, holes inside their parts).
SizeFieldResult make_size_field(const Region& region, const SizeFieldOptions& options);

/// Quads of the field's sizes in the polygon of `rings` (indices into region.rings: a part's outer ring and
/// holes): the integral of 1 / h^2 over the grid cells whose centres lie inside.
double estimate_quads(const SizeField& field, const Region& region, const std::vector<int>& rings);

/// Lowers `h` (nx * ny values on a grid of spacing `cell`) to the largest field below it whose values at any two
/// 8-neighbour cells differ by at most grade times their distance: h(x) = min over y of h(y) + grade |x - y|,
/// propagated with each cell's source point (exact on the grid's edges). Returns the count of cells it lowered.
std::size_t limit_gradient(std::vector<double>& h, int nx, int ny, double cell, double grade);

}  // namespace polysquare
