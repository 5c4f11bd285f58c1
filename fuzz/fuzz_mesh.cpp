// libFuzzer target: the MSH (2.2/4.1, ASCII/binary) and VTU readers. The first byte picks the reader, so one
// corpus drives both; bad input must end in InputError.
#include <cstddef>
#include <cstdint>
#include <string>

#include "polysquare/core/error.h"
#include "polysquare/io/mesh_io.h"
#include "polysquare/quality/quality.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::string text(reinterpret_cast<const char*>(data) + 1, size - 1);
  try {
    const polysquare::QuadMesh m = (data[0] & 1) ? polysquare::parse_vtu(text, "fuzz.vtu") : polysquare::parse_msh(text, "fuzz.msh");
    polysquare::compute_quality(m);  // what `polysquare quality` does next with the mesh
  } catch (const polysquare::InputError&) {
  }
  return 0;
}
