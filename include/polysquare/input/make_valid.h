// Stage 1 (input, with --repair): invalid polygon parts (self-intersecting or bow-tie rings, holes crossing
// their outer ring) made valid by GEOS through GDAL/OGR.
#pragma once

#include <string>
#include <vector>

#include "polysquare/core/region.h"

namespace polysquare {

/// Replaces every polygon part that OGR finds invalid by the polygons of its OGR MakeValid() result (a bow-tie
/// becomes two triangles), keeping the part's feature index for messages; appends one sentence per repaired
/// part to `repairs`. Parts are renumbered when a part splits. Returns the number of parts repaired.
std::size_t make_parts_valid(Region& region, std::vector<std::string>* repairs);

}  // namespace polysquare
