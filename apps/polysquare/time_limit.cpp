#include "time_limit.h"

#include <unistd.h>

#include <cstdio>

#include "polysquare/io/atomic_file.h"
#include "polysquare/pipeline/check_options.h"
#include "terminal_progress.h"

namespace polysquare::cli {

TimeLimit::TimeLimit(double seconds, std::string input, ProgressCallback next)
    : seconds_(seconds), input_(std::move(input)), next_(std::move(next)) {
  if (seconds_ > 0) watcher_ = std::thread([this] { watch(); });
}

void TimeLimit::stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  if (watcher_.joinable()) watcher_.join();
}

void TimeLimit::on_event(const ProgressEvent& e) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (e.kind == ProgressEvent::Kind::started) stage_ = e.stage, done_ = 0, total_ = 0;
    if (e.kind == ProgressEvent::Kind::advanced && e.stage == stage_) done_ = e.done, total_ = e.total;
  }
  if (next_) next_(e);
}

void TimeLimit::watch() {
  std::unique_lock<std::mutex> lock(mutex_);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds_);
  if (wake_.wait_until(lock, deadline, [this] { return stop_; })) return;
  // Out of time: one line, the run's temporaries removed, exit 3 without unwinding the busy worker threads.
  std::string line = std::string(interactive_terminal(stderr) ? "\r\033[K" : "") + "error: " + input_ + ": did not finish within " + short_number(seconds_) +
                     " s (--time-limit): in stage \"" + stage_ + "\"";
  if (total_ > 0) line += ", " + std::to_string(done_) + " of " + std::to_string(total_) + " polygon parts done";
  line += "; nothing written\n";
  std::fputs(line.c_str(), stderr);
  std::fflush(stderr);
  remove_pending_temporaries();
  ::_exit(3);
}

}  // namespace polysquare::cli
