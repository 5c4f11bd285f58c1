#include "time_limit.h"

#include <unistd.h>

#include <cstdio>

#include "polysquare/io/atomic_file.h"
#include "polysquare/pipeline/check_options.h"
#include "terminal_progress.h"

namespace polysquare::cli {

namespace {
constexpr const char* kReading = "read input";
constexpr int kSilentGrace = 5;  // seconds a silent process waits for the speaking one to end the job
}

TimeLimit::TimeLimit(double seconds, double read_seconds, std::string input, ProgressCallback next, bool speak)
    : seconds_(seconds), read_seconds_(read_seconds), speak_(speak), input_(std::move(input)), next_(std::move(next)) {
  if (seconds_ > 0 || read_seconds_ > 0) watcher_ = std::thread([this] { watch(); });
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
  if (e.kind == ProgressEvent::Kind::started) wake_.notify_all();  // the reading bound ends with its stage
  if (next_) next_(e);
}

void TimeLimit::watch() {
  using Clock = std::chrono::steady_clock;
  std::unique_lock<std::mutex> lock(mutex_);
  const auto start = Clock::now();
  // A limit beyond about a century is no limit: in the clock's nanoseconds 1e10 s would overflow to the past and
  // stop the run at once.
  auto after = [&](double s) {
    return s > 3e9 ? Clock::time_point::max()
                   : start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
  };
  const auto deadline = seconds_ > 0 ? after(seconds_) : Clock::time_point::max();
  const auto read_deadline = read_seconds_ > 0 ? after(read_seconds_) : Clock::time_point::max();  // reading starts now
  bool read_timeout = false;
  for (;;) {
    const bool reading = stage_ == kReading && read_deadline < deadline;
    const auto until = reading ? read_deadline : deadline;
    auto done = [&] { return stop_ || (reading && stage_ != kReading); };
    if (until == Clock::time_point::max()) {
      wake_.wait(lock, done);
    } else if (!wake_.wait_until(lock, until, done)) {
      read_timeout = reading;
      break;
    }
    if (stop_) return;
  }
  // Out of time on a process that does not speak (MPI rank > 0): rank 0, whose clock runs alike, prints the one
  // line and ends the job; this one ends itself only if that did not happen within the grace.
  if (!speak_) {
    if (wake_.wait_for(lock, std::chrono::seconds(kSilentGrace), [&] { return stop_; })) return;
    remove_pending_temporaries();
    ::_exit(3);
  }
  // Out of time: one line, the run's temporaries removed, exit 3 without unwinding the busy worker threads.
  std::string line = std::string(interactive_terminal(stderr) ? "\r\033[K" : "") + "error: " + input_ + ": ";
  if (read_timeout) {
    line += "reading did not finish within " + short_number(read_seconds_) +
            " s (--read-time-limit): its reader is stuck in the file or the file is far too large";
  } else {
    line += "did not finish within " + short_number(seconds_) + " s (--time-limit): in stage \"" + stage_ + "\"";
    if (total_ > 0) line += ", " + std::to_string(done_) + " of " + std::to_string(total_) + " polygon parts done";
  }
  line += "; nothing written\n";
  std::fputs(line.c_str(), stderr);
  std::fflush(stderr);
  remove_pending_temporaries();
  ::_exit(3);
}

}  // namespace polysquare::cli
