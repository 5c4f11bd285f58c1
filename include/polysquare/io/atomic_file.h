// Reading whole files, and writing outputs so that a target path never holds a partial file.
#pragma once

#include <filesystem>
#include <functional>
#include <ostream>
#include <string>

namespace polysquare {

/// Writes through `write` into a temporary file next to `target`, checks the stream, then renames it onto
/// `target`. On any failure the temporary is removed and the exception propagates; `target` is untouched.
void write_file_atomically(const std::filesystem::path& target, const std::function<void(std::ostream&)>& write,
                           bool binary);

/// The same for writers that need a path rather than a stream (netCDF): `write` creates the temporary path it is
/// given; it is renamed onto `target` when `write` returns, removed when it throws.
void write_path_atomically(const std::filesystem::path& target,
                           const std::function<void(const std::filesystem::path&)>& write);

/// The whole content of a file; throws InputError naming the path when it cannot be read.
std::string read_file(const std::filesystem::path& path);

/// Removes the temporaries of writes in flight (for SIGINT/SIGTERM handlers). Uses only unlink() on paths
/// prepared before the write started, so it is safe to call from a signal handler.
void remove_pending_temporaries() noexcept;

}  // namespace polysquare
