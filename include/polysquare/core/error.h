// Error types. The CLI maps them to exit codes: InputError -> 2, MeshingError -> 3, anything else -> 1.
#pragma once

#include <stdexcept>
#include <string>

namespace polysquare {

/// The input (file, geometry or options) is invalid. The message names the file, the feature index and the
/// coordinate where that makes sense, e.g. "case.geojson: feature 3: ring 0 is not closed at (1.5, 2)".
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A stage could not produce a valid result for valid input (e.g. a map that inverts, an infeasible
/// quantization). The message names the stage and the part.
class MeshingError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace polysquare
