// A picture of a graded run's size field: the size at every point of the domain on a log colour scale (small
// sizes dark blue, large ones yellow), the domain's rings on top, and a colour bar with the least and largest size.
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

#include "polysquare/core/region.h"
#include "polysquare/size/size_field.h"

namespace polysquare {

/// Writes the PNG (atomically) of `field` over `region`, `inside` the field grid's per-cell domain flags
/// (SizeFieldResult::inside); cells outside the domain are white. `width_px` includes the colour bar. Throws
/// InputError unless `path` ends in .png.
void render_size_field(const std::filesystem::path& path, const SizeField& field,
                       const std::vector<std::uint8_t>& inside, const Region& region, int width_px = 1200);

}  // namespace polysquare
