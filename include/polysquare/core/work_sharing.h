// Processes that mesh one region together (MPI ranks, see driver/mpi_driver.h), seen by the stages without MPI.
//
// Every process runs the same pipeline on the same input. A loop over independent items (the subregions' maps,
// their split tests, their snaps) gives each item to one process, which computes it with its threads; the
// results are then shared, so that every process continues with all of them. An item's result is the same
// whichever process computes it (the stages are deterministic), so the mesh does not depend on the number of
// processes. Everything outside these loops runs on every process alike.
#pragma once

#include <cstdint>
#include <cstring>
#include <exception>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include <oneapi/tbb/parallel_for.h>

#include "polysquare/core/error.h"

namespace polysquare {

/// Bytes of one item's result, written and read in the same order (the processes run one binary on one machine
/// type, so values are copied as they are in memory).
class ByteWriter {
 public:
  explicit ByteWriter(std::string& out) : out_(out) {}
  template <class T>
    requires std::is_trivially_copyable_v<T>
  void put(const T& v) {
    out_.append(reinterpret_cast<const char*>(&v), sizeof(T));
  }
  template <class T>
    requires std::is_trivially_copyable_v<T>
  void put(const std::vector<T>& v) {
    put(static_cast<std::uint64_t>(v.size()));
    out_.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
  }
  void put(const std::string& s) {
    put(static_cast<std::uint64_t>(s.size()));
    out_.append(s);
  }
  template <class T>
  void put(const std::vector<std::vector<T>>& v) {
    put(static_cast<std::uint64_t>(v.size()));
    for (const auto& x : v) put(x);
  }
  void put(const std::vector<std::string>& v) {
    put(static_cast<std::uint64_t>(v.size()));
    for (const auto& x : v) put(x);
  }

 private:
  std::string& out_;
};

class ByteReader {
 public:
  explicit ByteReader(std::string_view in) : in_(in) {}
  template <class T>
    requires std::is_trivially_copyable_v<T>
  void get(T& v) {
    take(&v, sizeof(T));
  }
  template <class T>
    requires std::is_trivially_copyable_v<T>
  void get(std::vector<T>& v) {
    std::uint64_t n = 0;
    get(n);
    if (n > (in_.size() - pos_) / (sizeof(T) > 0 ? sizeof(T) : 1)) throw std::logic_error("work sharing: truncated item");
    v.resize(n);
    take(v.data(), n * sizeof(T));
  }
  void get(std::string& s) {
    std::uint64_t n = 0;
    get(n);
    if (n > in_.size() - pos_) throw std::logic_error("work sharing: truncated item");
    s.assign(in_.substr(pos_, n));
    pos_ += n;
  }
  template <class T>
  void get(std::vector<std::vector<T>>& v) {
    std::uint64_t n = 0;
    get(n);
    v.resize(n);
    for (auto& x : v) get(x);
  }
  void get(std::vector<std::string>& v) {
    std::uint64_t n = 0;
    get(n);
    if (n > in_.size() - pos_) throw std::logic_error("work sharing: truncated item");
    v.resize(n);
    for (auto& x : v) get(x);
  }
  bool done() const { return pos_ == in_.size(); }

 private:
  void take(void* dst, std::size_t n) {
    if (n > in_.size() - pos_) throw std::logic_error("work sharing: truncated item");
    if (n > 0) std::memcpy(dst, in_.data() + pos_, n);
    pos_ += n;
  }
  std::string_view in_;
  std::size_t pos_ = 0;
};

/// The processes meshing one region. The base class is this process alone.
class WorkSharing {
 public:
  virtual ~WorkSharing() = default;
  virtual int processes() const { return 1; }
  virtual int rank() const { return 0; }
  /// Collective (every process calls it with the same `tag`, the same owners, in the same order, from the thread
  /// that started the processes): on entry each process has filled the entries of `items` it owns; on return
  /// every entry holds its owner's bytes. A process whose loop differs (another tag or count) stops the run.
  virtual void all_gather(std::vector<std::string>& items, const std::vector<int>& owner, std::string_view tag) const {}
};

/// The process of each item: items by decreasing cost, each to the least loaded process (ties: the lower rank,
/// the earlier item), so every process computes the same assignment.
std::vector<int> item_owners(const std::vector<double>& cost, int processes);

namespace detail {
void put_error(ByteWriter& w, const std::exception_ptr& e);
std::exception_ptr get_error(ByteReader& r);
}  // namespace detail

/// Runs f(i) for every i < n in parallel on this process's threads; then the first failure in item order is
/// rethrown as it was thrown (a MeshingError fails a candidate; anything else is a bug and must not pass for one),
/// so which error surfaces does not depend on the thread count.
template <class F>
void for_each_item(std::size_t n, F&& f) {
  std::vector<std::exception_ptr> errors(n);
  oneapi::tbb::parallel_for(std::size_t{0}, n, [&](std::size_t i) {
    try {
      f(i);
    } catch (...) {
      errors[i] = std::current_exception();
    }
  });
  for (const std::exception_ptr& e : errors)
    if (e) std::rethrow_exception(e);
}

/// Runs compute(i) for every item i < n, in parallel on this process's threads for the items it owns, then
/// shares the results: pack(i, ByteWriter&) writes what compute(i) produced on its owner, unpack(i, ByteReader&)
/// reads it on every other process. `cost` (empty: all equal) balances the processes. The first item (in item
/// order) whose compute threw is rethrown on every process: MeshingError and InputError as they were, anything
/// else as std::runtime_error with its message. `sharing` null or of one process: compute alone, nothing copied.
template <class Compute, class Pack, class Unpack>
void shared_for(const WorkSharing* sharing, std::size_t n, const std::vector<double>& cost, std::string_view tag,
                Compute&& compute, Pack&& pack, Unpack&& unpack) {
  const bool alone = sharing == nullptr || sharing->processes() <= 1;
  if (alone) return for_each_item(n, compute);
  const std::vector<int> owner = item_owners(cost.empty() ? std::vector<double>(n, 1.0) : cost, sharing->processes());
  const int me = sharing->rank();
  // Each item's bytes: its error (none) and then what pack wrote; the owner keeps its exception as thrown.
  std::vector<std::exception_ptr> errors(n);
  std::vector<std::string> items(n);
  oneapi::tbb::parallel_for(std::size_t{0}, n, [&](std::size_t i) {
    if (owner[i] != me) return;
    try {
      compute(i);
    } catch (...) {
      errors[i] = std::current_exception();
    }
    ByteWriter w(items[i]);
    detail::put_error(w, errors[i]);
    if (!errors[i]) pack(i, w);
  });
  sharing->all_gather(items, owner, tag);
  oneapi::tbb::parallel_for(std::size_t{0}, n, [&](std::size_t i) {
    if (owner[i] == me) return;
    ByteReader r(items[i]);
    errors[i] = detail::get_error(r);
    if (!errors[i]) unpack(i, r);
  });
  for (const std::exception_ptr& e : errors)
    if (e) std::rethrow_exception(e);
}

}  // namespace polysquare
