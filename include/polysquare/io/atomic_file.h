// Reading whole files, and writing outputs so that a target path never holds a partial file.
#pragma once

#include <filesystem>
#include <functional>
#include <ostream>
#include <string>
#include <vector>

namespace polysquare {

/// Writes through `write` into a temporary file next to `target`, checks the stream, syncs it to disk and renames
/// it onto `target` (inside an OutputBatch: keeps it for the batch's commit). On any failure the temporary is
/// removed and the exception propagates; `target` is untouched.
///
/// Temporaries are named `.polysquare-<16 hex digits of a hash of the target's file name>-<pid>.tmp` beside the
/// target, so the name is short whatever the target's length, and a later write of the same target removes the
/// temporaries that a killed run (a process id no longer alive) left behind.
void write_file_atomically(const std::filesystem::path& target, const std::function<void(std::ostream&)>& write,
                           bool binary);

/// The same for writers that need a path rather than a stream (netCDF): `write` creates the temporary path it is
/// given; it is synced and renamed onto `target` when `write` returns (or kept for the batch), removed when it
/// throws.
void write_path_atomically(const std::filesystem::path& target,
                           const std::function<void(const std::filesystem::path&)>& write);

/// The temporary a write of `target` by this process uses (see write_file_atomically).
std::filesystem::path temporary_path(const std::filesystem::path& target);

/// Several outputs committed together or not at all. While a batch is open (one at a time, per process), the
/// atomic writes above leave their synced temporaries in place instead of renaming them; commit() renames them
/// all onto their targets (after every one of them was written) and syncs their directories. A batch destroyed
/// without commit() (an exception, a refused mesh) removes every temporary it holds, so no target changes.
class OutputBatch {
 public:
  OutputBatch();
  ~OutputBatch();
  OutputBatch(const OutputBatch&) = delete;
  OutputBatch& operator=(const OutputBatch&) = delete;
  void commit();
};

/// Checks, before any work, that `path` can be written as an output: a file name (not a directory, not too long
/// for the file system), its directory exists and is writable, an existing file there is writable, and its
/// extension (lower case) is one of `extensions` when that list is not empty. `what` names the output in
/// messages ("--report"). Throws InputError naming the path.
void check_output_file(const std::filesystem::path& path, const std::string& what,
                       const std::vector<std::string>& extensions = {});

/// Throws InputError when two of `outputs` are the same file, or an output is one of `inputs` (the same path, or
/// an existing file that is the same file through a link). Pairs are (path, what it is: "-o", "--report", ...).
void check_distinct_files(const std::vector<std::pair<std::filesystem::path, std::string>>& outputs,
                          const std::vector<std::pair<std::filesystem::path, std::string>>& inputs);

/// The whole content of a file; throws InputError naming the path when it cannot be read (also for a directory).
std::string read_file(const std::filesystem::path& path);

/// Removes the temporaries of writes in flight (for SIGINT/SIGTERM handlers). Uses only unlink() on paths
/// prepared before the write started, so it is safe to call from a signal handler.
void remove_pending_temporaries() noexcept;

}  // namespace polysquare
