// libFuzzer target: GeoJSON parsing, validation and feature splitting must reject bad input with InputError,
// never crash, hang or trip a sanitizer.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "polysquare/core/error.h"
#include "polysquare/input/read_region.h"
#include "polysquare/io/geojson.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    polysquare::Region region =
        polysquare::parse_geojson(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.geojson");
    polysquare::validate_region(region);
  } catch (const polysquare::InputError&) {
  }
  return 0;
}
