// The CLI's progress display on stderr: one updating line per run on a terminal, stage timings with --verbose.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <mutex>
#include <string>
#include <thread>

#include "polysquare/pipeline/progress.h"

namespace polysquare::cli {

enum class Verbosity { quiet, normal, verbose };

/// Shows a run's ProgressEvents on `out` (stderr). The updating line ("\r" + erase to the end of the line, the
/// stage, parts done of total, seconds since the start, redrawn twice a second) is drawn only when `out` is a
/// terminal, TERM is not "dumb" and the CI environment variable is unset (CI logs would keep every frame), and
/// never when quiet. Verbose prints "stage NAME  S s" as each stage finishes, on a terminal or not.
class TerminalProgress {
 public:
  explicit TerminalProgress(Verbosity verbosity, std::FILE* out = stderr);
  ~TerminalProgress();  ///< erases the line, so what follows (warnings, errors) starts clean
  TerminalProgress(const TerminalProgress&) = delete;
  TerminalProgress& operator=(const TerminalProgress&) = delete;

  void operator()(const ProgressEvent& event);
  ProgressCallback callback() { return [this](const ProgressEvent& e) { (*this)(e); }; }

 private:
  void erase();  // with mutex_ held
  void draw();   // with mutex_ held
  Verbosity verbosity_;
  std::FILE* out_;
  bool line_ = false;   ///< the updating line is shown at all
  bool drawn_ = false;  ///< something is on the line now
  std::string text_;    ///< what the line says, without the time; empty: nothing to show
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stop_ = false;
  std::thread ticker_;  ///< redraws the line so its seconds keep counting during a long stage
};

/// True when `out` is a terminal, TERM is not "dumb" and CI is unset.
bool interactive_terminal(std::FILE* out);

}  // namespace polysquare::cli
