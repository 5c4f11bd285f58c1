// The CLI's --time-limit: a run that has not finished within its budget ends in exit 3 naming where it was.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <mutex>
#include <string>
#include <thread>

#include "polysquare/pipeline/progress.h"

namespace polysquare::cli {

/// Watches a run for `seconds` of wall time (0: no limit). It follows the run's ProgressEvents (callback()
/// forwards each to `next`) and, when the budget is spent before the object is destroyed, prints one line
/// "error: INPUT: did not finish within S s (--time-limit): in stage NAME, D of T items done; nothing written",
/// removes the run's pending temporaries (io/atomic_file.h) and ends the process with exit code 3. Outputs are
/// committed only after meshing, so nothing half-written is left. A safety net for every stage at once; the
/// stages' own budgets (triangle counts, LP time limits) end earlier and say more. Reading the input has a bound
/// of its own, `read_seconds` (0: none), since a reader stuck in a malformed file (a GDAL driver) has no other.
class TimeLimit {
 public:
  /// `speak` false: another process (MPI rank 0) prints the line; this one waits 5 s for that process
  /// to end the job, then ends itself with exit 3 without a word.
  TimeLimit(double seconds, double read_seconds, std::string input, ProgressCallback next, bool speak = true);
  ~TimeLimit() { stop(); }
  /// Stops watching (before the outputs are committed: a run is never cut between two renames).
  void stop();
  TimeLimit(const TimeLimit&) = delete;
  TimeLimit& operator=(const TimeLimit&) = delete;

  ProgressCallback callback() { return [this](const ProgressEvent& e) { on_event(e); }; }

 private:
  void on_event(const ProgressEvent& e);
  void watch();
  double seconds_, read_seconds_;
  bool speak_;
  std::string input_;
  ProgressCallback next_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stop_ = false;
  std::string stage_ = "read input";  ///< the stage last started (the CLI's own stages included)
  std::size_t done_ = 0, total_ = 0;  ///< its items done, of total, when it reports items
  std::thread watcher_;
};

}  // namespace polysquare::cli
