// Progress of a meshing run, stage by stage, for a caller that shows it (the CLI's terminal line, --verbose).
#pragma once

#include <chrono>
#include <cstddef>
#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <string_view>

namespace polysquare {

/// One step of a run: a stage starts, finishes, or one more of its items (polygon parts) is done.
struct ProgressEvent {
  enum class Kind { started, advanced, finished };
  Kind kind = Kind::started;
  std::string stage;             ///< "simplify", "mesh parts", "assemble" (mesh_region); callers add their own
  std::size_t done = 0, total = 0;  ///< advanced: items of the stage done so far, of total
  double seconds = 0.0;          ///< finished: wall time of the stage, seconds
};

/// Receives progress events. Calls are serialized (never two at once) but may come from worker threads.
using ProgressCallback = std::function<void(const ProgressEvent&)>;

/// Sends a run's events to a ProgressCallback (an empty one: does nothing) and times each stage. Thread-safe.
class ProgressReporter {
 public:
  explicit ProgressReporter(ProgressCallback callback) : callback_(std::move(callback)) {}

  void start(std::string_view stage) {
    if (!callback_) return;
    std::lock_guard<std::mutex> lock(mutex_);
    started_[std::string(stage)] = Clock::now();
    done_[std::string(stage)] = 0;
    callback_({ProgressEvent::Kind::started, std::string(stage), 0, 0, 0.0});
  }

  /// Reports the stage's wall time since start(stage) (0 when it was not started).
  void finish(std::string_view stage) {
    if (!callback_) return;
    std::lock_guard<std::mutex> lock(mutex_);
    const auto it = started_.find(std::string(stage));
    const double seconds =
        it == started_.end() ? 0.0 : std::chrono::duration<double>(Clock::now() - it->second).count();
    callback_({ProgressEvent::Kind::finished, std::string(stage), done_[std::string(stage)], 0, seconds});
  }

  /// One more of the stage's `total` items is done.
  void advance(std::string_view stage, std::size_t total) {
    if (!callback_) return;
    std::lock_guard<std::mutex> lock(mutex_);
    const std::size_t done = ++done_[std::string(stage)];
    callback_({ProgressEvent::Kind::advanced, std::string(stage), done, total, 0.0});
  }

  /// advance(stage, total) when the returned object goes out of scope, however the scope is left.
  class Item {
   public:
    Item(ProgressReporter& r, std::string_view stage, std::size_t total) : r_(r), stage_(stage), total_(total) {}
    Item(const Item&) = delete;
    Item& operator=(const Item&) = delete;
    ~Item() { r_.advance(stage_, total_); }

   private:
    ProgressReporter& r_;
    std::string_view stage_;
    std::size_t total_;
  };

 private:
  using Clock = std::chrono::steady_clock;
  ProgressCallback callback_;
  std::mutex mutex_;
  std::map<std::string, Clock::time_point> started_;
  std::map<std::string, std::size_t> done_;
};

}  // namespace polysquare
