// The version string lives in the library, where CMake defines it, so the CLI and the report agree.
#include "polysquare/core/version.h"

namespace polysquare {

const char* library_version() { return POLYSQUARE_VERSION; }

}  // namespace polysquare
