#include "polysquare/io/atomic_file.h"

#include <unistd.h>

#include <array>
#include <atomic>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>

#include "polysquare/core/error.h"

namespace polysquare {
namespace {
// Fixed slots of C strings so a signal handler can unlink them without allocating.
constexpr std::size_t kSlots = 16, kPathMax = 4096;
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
}  // namespace

void write_path_atomically(const std::filesystem::path& target,
                           const std::function<void(const std::filesystem::path&)>& write) {
  const std::filesystem::path tmp = target.string() + ".tmp." + std::to_string(::getpid());
  const int slot = claim_slot(tmp.string());
  try {
    write(tmp);
    std::filesystem::rename(tmp, target);
  } catch (...) {
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    release_slot(slot);
    throw;
  }
  release_slot(slot);
}

void write_file_atomically(const std::filesystem::path& target, const std::function<void(std::ostream&)>& write,
                           bool binary) {
  write_path_atomically(target, [&](const std::filesystem::path& tmp) {
    std::ofstream out(tmp, binary ? std::ios::binary | std::ios::trunc : std::ios::trunc);
    if (!out) throw InputError(target.string() + ": cannot write the output file");
    write(out);
    out.flush();
    if (!out) throw InputError(target.string() + ": writing failed (disk full?)");
  });
}

std::string read_file(const std::filesystem::path& path) {
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
