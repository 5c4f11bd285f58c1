#pragma once

namespace polysquare {

/// The library version (CMake project version), as `polysquare --version` and the report's summary give it.
const char* library_version();

}  // namespace polysquare
