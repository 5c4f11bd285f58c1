#include "polysquare/driver/mpi_driver.h"

#include <oneapi/tbb/info.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <functional>
#include <stdexcept>
#include <string>
#include <thread>

#ifdef POLYSQUARE_HAVE_MPI
#include <mpi.h>
#endif

namespace polysquare {
namespace {

// Set by Open MPI's launcher (OMPI_*) or any PMIx launcher (PMIX_RANK) in every process it starts.
bool launched_by_mpi() {
  return std::getenv("OMPI_COMM_WORLD_SIZE") != nullptr || std::getenv("PMIX_RANK") != nullptr;
}

#ifdef POLYSQUARE_HAVE_MPI

void check(int rc, const char* what) {
  if (rc != MPI_SUCCESS) throw std::runtime_error(std::string("MPI: ") + what + " failed");
}

class MpiSharing final : public WorkSharing {
 public:
  MpiSharing(MPI_Comm comm, int rank, int size) : comm_(comm), rank_(rank), size_(size), thread_(std::this_thread::get_id()) {}
  int processes() const override { return size_; }
  int rank() const override { return rank_; }

  void all_gather(std::vector<std::string>& items, const std::vector<int>& owner, std::string_view tag) const override {
    if (std::this_thread::get_id() != thread_)
      throw std::logic_error("work sharing: '" + std::string(tag) + "' called off the thread that started MPI");
    // Every process must be at the same loop: a process whose control flow differs would pair this exchange
    // with another one. The tag's hash and the item count are compared before any byte moves.
    const std::uint64_t mine[2] = {std::hash<std::string_view>{}(tag), items.size()};
    std::uint64_t lo[2], hi[2];
    check(MPI_Allreduce(mine, lo, 2, MPI_UINT64_T, MPI_MIN, comm_), "Allreduce");
    check(MPI_Allreduce(mine, hi, 2, MPI_UINT64_T, MPI_MAX, comm_), "Allreduce");
    if (lo[0] != hi[0] || lo[1] != hi[1])
      throw std::logic_error("work sharing: the processes reached different loops at '" + std::string(tag) +
                             "' (" + std::to_string(items.size()) + " items here)");
    // Each process's items in item order, each as its length and its bytes; one broadcast per process, in
    // pieces below MPI's int count.
    for (int r = 0; r < size_; ++r) {
      std::string buffer;
      if (r == rank_) {
        ByteWriter w(buffer);
        for (std::size_t i = 0; i < items.size(); ++i)
          if (owner[i] == r) w.put(items[i]);
      }
      std::uint64_t bytes = buffer.size();
      check(MPI_Bcast(&bytes, 1, MPI_UINT64_T, r, comm_), "Bcast");
      buffer.resize(bytes);
      constexpr std::uint64_t piece = std::uint64_t{1} << 30;
      for (std::uint64_t at = 0; at < bytes; at += piece)
        check(MPI_Bcast(buffer.data() + at, static_cast<int>(std::min(piece, bytes - at)), MPI_BYTE, r, comm_), "Bcast");
      if (r == rank_) continue;
      ByteReader reader(buffer);
      for (std::size_t i = 0; i < items.size(); ++i)
        if (owner[i] == r) reader.get(items[i]);
      if (!reader.done()) throw std::logic_error("work sharing: '" + std::string(tag) + "': bytes left over");
    }
  }

 private:
  MPI_Comm comm_;
  int rank_, size_;
  std::thread::id thread_;
};

#endif

}  // namespace

MpiDriver::MpiDriver(int& argc, char**& argv) {
#ifdef POLYSQUARE_HAVE_MPI
  if (!launched_by_mpi()) return;
  // Only the thread that starts MPI calls it (WorkSharing::all_gather checks); the stages' threads never do.
  int provided = 0;
  check(MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided), "Init_thread");
  started_ = true;
  check(MPI_Comm_rank(MPI_COMM_WORLD, &rank_), "Comm_rank");
  check(MPI_Comm_size(MPI_COMM_WORLD, &processes_), "Comm_size");
  MPI_Comm local;
  check(MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, rank_, MPI_INFO_NULL, &local), "Comm_split_type");
  check(MPI_Comm_size(local, &local_processes_), "Comm_size");
  MPI_Comm_free(&local);
  if (processes_ > 1) sharing_ = std::make_shared<MpiSharing>(MPI_COMM_WORLD, rank_, processes_);
#else
  (void)argc;
  (void)argv;
#endif
}

MpiDriver::~MpiDriver() {
#ifdef POLYSQUARE_HAVE_MPI
  if (started_) MPI_Finalize();
#endif
}

int MpiDriver::threads_per_process() const {
  return std::max(1, static_cast<int>(oneapi::tbb::info::default_concurrency()) / std::max(1, local_processes_));
}

void MpiDriver::abort(int code) const {
#ifdef POLYSQUARE_HAVE_MPI
  if (started_) MPI_Abort(MPI_COMM_WORLD, code);
#endif
  (void)code;
}

bool MpiDriver::built_with_mpi() {
#ifdef POLYSQUARE_HAVE_MPI
  return true;
#else
  return false;
#endif
}

}  // namespace polysquare
