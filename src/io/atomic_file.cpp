#include "polysquare/io/atomic_file.h"

#include <fcntl.h>
#include <limits.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <mutex>
#include <string>

#include "polysquare/core/error.h"
#include "polysquare/io/mesh_io.h"

namespace polysquare {
namespace fs = std::filesystem;
namespace {
// Fixed slots of C strings so a signal handler can unlink them without allocating.
constexpr std::size_t kSlots = 32, kPathMax = 4096;
char g_paths[kSlots][kPathMax];
std::atomic<bool> g_used[kSlots];

int claim_slot(const std::string& path) {
  for (std::size_t i = 0; i < kSlots; ++i) {
    bool expected = false;
    if (path.size() < kPathMax && g_used[i].compare_exchange_strong(expected, true)) {
      std::memcpy(g_paths[i], path.c_str(), path.size() + 1);
      return static_cast<int>(i);
    }
  }
  return -1;
}
void release_slot(int i) {
  if (i >= 0) g_used[i] = false;
}

// The open batch's temporaries, renamed onto their targets by commit().
struct Staged {
  fs::path tmp, target;
  int slot;
};
std::mutex g_batch_mutex;
bool g_batch_open = false;
std::vector<Staged> g_staged;

constexpr const char* kTmpPrefix = ".polysquare-";

std::string name_hash(const fs::path& target) {
  std::uint64_t h = 1469598103934665603ull;  // FNV-1a, stable across runs and builds
  for (unsigned char c : target.filename().string()) h = (h ^ c) * 1099511628211ull;
  static const char* hex = "0123456789abcdef";
  std::string s(16, '0');
  for (int i = 15; i >= 0; --i, h >>= 4) s[static_cast<std::size_t>(i)] = hex[h & 15];
  return s;
}

fs::path directory_of(const fs::path& target) {
  return target.parent_path().empty() ? fs::path(".") : target.parent_path();
}

// Temporaries of the same target left by processes that no longer run (killed while writing).
void remove_stale_temporaries(const fs::path& target) {
  const std::string prefix = kTmpPrefix + name_hash(target) + "-";
  std::error_code ec;
  for (fs::directory_iterator it(directory_of(target), ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.rfind(prefix, 0) != 0 || name.size() <= prefix.size() + 4 || name.substr(name.size() - 4) != ".tmp") continue;
    const std::string digits = name.substr(prefix.size(), name.size() - prefix.size() - 4);
    if (digits.empty() || digits.size() > 9 || !std::all_of(digits.begin(), digits.end(), ::isdigit)) continue;
    const pid_t pid = static_cast<pid_t>(std::stol(digits));
    if (pid == ::getpid() || pid <= 0) continue;
    if (::kill(pid, 0) != 0 && errno == ESRCH) {
      std::error_code rm;
      fs::remove(it->path(), rm);
    }
  }
}

// Data on disk before the rename makes it visible (a crash then leaves the old file or the new one, whole).
void sync_path(const fs::path& path, const fs::path& target, bool directory) {
  const int fd = ::open(path.c_str(), directory ? (O_RDONLY | O_DIRECTORY) : O_RDONLY);
  if (fd < 0) {
    if (directory) return;  // syncing a directory is best effort
    throw InputError(target.string() + ": cannot reopen the written temporary " + path.string() + ": " +
                     std::strerror(errno));
  }
  const int rc = ::fsync(fd);
  const int err = errno;
  ::close(fd);
  if (rc != 0 && !directory)
    throw InputError(target.string() + ": writing failed (fsync: " + std::strerror(err) + ")");
}

void rename_onto(const fs::path& tmp, const fs::path& target) {
  std::error_code ec;
  fs::rename(tmp, target, ec);
  if (ec) throw InputError(target.string() + ": cannot replace the file: " + ec.message());
}

}  // namespace

fs::path temporary_path(const fs::path& target) {
  return directory_of(target) / (kTmpPrefix + name_hash(target) + "-" + std::to_string(::getpid()) + ".tmp");
}

void write_path_atomically(const fs::path& target, const std::function<void(const fs::path&)>& write) {
  const fs::path tmp = temporary_path(target);
  remove_stale_temporaries(target);
  {
    std::lock_guard<std::mutex> lock(g_batch_mutex);
    for (const Staged& s : g_staged)
      if (s.tmp == tmp) throw InputError(target.string() + ": written twice in one run");
  }
  const int slot = claim_slot(tmp.string());
  try {
    write(tmp);
    sync_path(tmp, target, false);
    {
      std::lock_guard<std::mutex> lock(g_batch_mutex);
      if (g_batch_open) {
        g_staged.push_back({tmp, target, slot});
        return;
      }
    }
    rename_onto(tmp, target);
  } catch (...) {
    std::error_code ec;
    fs::remove(tmp, ec);
    release_slot(slot);
    throw;
  }
  sync_path(directory_of(target), target, true);
  release_slot(slot);
}

void write_file_atomically(const fs::path& target, const std::function<void(std::ostream&)>& write, bool binary) {
  write_path_atomically(target, [&](const fs::path& tmp) {
    std::ofstream out(tmp, binary ? std::ios::binary | std::ios::trunc : std::ios::trunc);
    if (!out) throw InputError(target.string() + ": cannot write the output file");
    write(out);
    out.close();
    if (!out) throw InputError(target.string() + ": writing failed (disk full?)");
  });
}

OutputBatch::OutputBatch() {
  std::lock_guard<std::mutex> lock(g_batch_mutex);
  if (g_batch_open) throw std::logic_error("OutputBatch: a batch is already open");
  g_batch_open = true;
}

OutputBatch::~OutputBatch() {
  std::lock_guard<std::mutex> lock(g_batch_mutex);
  for (const Staged& s : g_staged) {
    std::error_code ec;
    fs::remove(s.tmp, ec);
    release_slot(s.slot);
  }
  g_staged.clear();
  g_batch_open = false;
}

void OutputBatch::commit() {
  std::lock_guard<std::mutex> lock(g_batch_mutex);
  // Every temporary is written and synced; the renames are all that is left. A rename can still fail (the
  // directory removed meanwhile): the remaining temporaries are then removed by the destructor.
  std::vector<fs::path> dirs;
  while (!g_staged.empty()) {
    const Staged s = g_staged.front();
    rename_onto(s.tmp, s.target);
    g_staged.erase(g_staged.begin());
    release_slot(s.slot);
    dirs.push_back(directory_of(s.target));
  }
  std::sort(dirs.begin(), dirs.end());
  dirs.erase(std::unique(dirs.begin(), dirs.end()), dirs.end());
  for (const fs::path& d : dirs) sync_path(d, d, true);
}

void check_output_file(const fs::path& path, const std::string& what, const std::vector<std::string>& extensions) {
  const std::string name = path.string();
  if (name.empty()) throw InputError(what + ": the output path is empty");
  std::error_code ec;
  const std::string file = path.filename().string();
  if (file.empty() || file == "." || file == ".." || fs::is_directory(path, ec))
    throw InputError(name + ": is a directory, not an output file (" + what + ")");
  if (!extensions.empty() && std::find(extensions.begin(), extensions.end(), lower_extension(path)) == extensions.end()) {
    std::string list;
    for (const auto& k : extensions) list += (list.empty() ? "" : ", ") + k;
    throw InputError(name + ": unknown " + what + " format '" + lower_extension(path) + "' (known: " + list + ")");
  }
  const fs::path dir = directory_of(path);
  // Lengths first: a name the file system cannot hold would otherwise fail in the writer, after meshing (or read
  // as a missing directory). Every component within NAME_MAX bytes, the whole path and its temporary's within
  // PATH_MAX.
  const long fs_name_max = ::pathconf(fs::is_directory(dir, ec) ? dir.c_str() : ".", _PC_NAME_MAX);
  const std::size_t name_max = fs_name_max > 0 ? static_cast<std::size_t>(fs_name_max) : std::size_t{NAME_MAX};
  if (file.size() > name_max)
    throw InputError(name + ": the file name has " + std::to_string(file.size()) +
                     " characters, more than the file system allows (" + std::to_string(name_max) + ") (" + what + ")");
  for (const fs::path& part : path.parent_path())
    if (part.string().size() > name_max)
      throw InputError(name + ": a directory name in the path has " + std::to_string(part.string().size()) +
                       " characters, more than the file system allows (" + std::to_string(name_max) + ") (" + what +
                       ")");
  const std::size_t longest =
      std::max(fs::absolute(path, ec).string().size(), fs::absolute(temporary_path(path), ec).string().size());
  if (longest >= std::size_t{PATH_MAX})
    throw InputError(name + ": the path has " + std::to_string(longest) +
                     " characters (with its directory and temporary), more than the system allows (PATH_MAX " +
                     std::to_string(PATH_MAX) + ") (" + what + ")");
  if (!fs::is_directory(dir, ec))
    throw InputError(name + ": the directory " + dir.string() + " does not exist (" + what + ")");
  // Outputs are written to a temporary beside the target and renamed, so the directory must be writable.
  if (::access(dir.c_str(), W_OK | X_OK) != 0)
    throw InputError(name + ": the directory " + dir.string() + " is not writable (" + what + ")");
  if (fs::exists(path, ec)) {
    if (!fs::is_regular_file(path, ec))
      throw InputError(name + ": exists and is not a regular file (" + what + ")");
    if (::access(path.c_str(), W_OK) != 0) throw InputError(name + ": the file exists and is not writable (" + what + ")");
  }
}

void check_distinct_files(const std::vector<std::pair<fs::path, std::string>>& outputs,
                          const std::vector<std::pair<fs::path, std::string>>& inputs) {
  auto key = [](const fs::path& p) {
    std::error_code ec;
    fs::path k = fs::weakly_canonical(fs::absolute(p, ec), ec);
    return ec ? fs::absolute(p).lexically_normal() : k;
  };
  auto same = [&](const fs::path& a, const fs::path& b) {
    if (key(a) == key(b)) return true;
    std::error_code ec;
    return fs::exists(a, ec) && fs::exists(b, ec) && fs::equivalent(a, b, ec);
  };
  for (std::size_t i = 0; i < outputs.size(); ++i) {
    for (std::size_t j = i + 1; j < outputs.size(); ++j)
      if (same(outputs[i].first, outputs[j].first))
        throw InputError(outputs[j].first.string() + ": " + outputs[j].second + " names the same file as " +
                         outputs[i].second + " (" + outputs[i].first.string() + ")");
    for (const auto& in : inputs)
      if (same(outputs[i].first, in.first))
        throw InputError(outputs[i].first.string() + ": " + outputs[i].second + " would overwrite the " + in.second +
                         " it reads");
  }
}

std::string read_file(const fs::path& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) throw InputError(path.string() + ": is a directory, not a file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string() + ": cannot open the file");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw InputError(path.string() + ": reading failed");
  return text;
}

void remove_pending_temporaries() noexcept {
  for (std::size_t i = 0; i < kSlots; ++i)
    if (g_used[i]) ::unlink(g_paths[i]);
}

}  // namespace polysquare
