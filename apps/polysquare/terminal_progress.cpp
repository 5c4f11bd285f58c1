#include "terminal_progress.h"

#include <cstdlib>
#include <cstring>
#include <unistd.h>

namespace polysquare::cli {

bool interactive_terminal(std::FILE* out) {
  const char* term = std::getenv("TERM");
  return ::isatty(::fileno(out)) && std::getenv("CI") == nullptr && !(term && std::strcmp(term, "dumb") == 0);
}

TerminalProgress::TerminalProgress(Verbosity verbosity, std::FILE* out)
    : verbosity_(verbosity), out_(out), line_(verbosity != Verbosity::quiet && interactive_terminal(out)) {
  if (!line_) return;
  ticker_ = std::thread([this] {
    std::unique_lock<std::mutex> lock(mutex_);
    while (!wake_.wait_for(lock, std::chrono::milliseconds(500), [this] { return stop_; }))
      if (!text_.empty()) draw();
  });
}

TerminalProgress::~TerminalProgress() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
    erase();
  }
  wake_.notify_all();
  if (ticker_.joinable()) ticker_.join();
}

void TerminalProgress::erase() {
  if (!drawn_) return;
  std::fputs("\r\033[K", out_);
  std::fflush(out_);
  drawn_ = false;
}

void TerminalProgress::draw() {
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  erase();
  std::fprintf(out_, "polysquare: %s ... %.1f s", text_.c_str(), seconds);
  std::fflush(out_);
  drawn_ = true;
}

void TerminalProgress::operator()(const ProgressEvent& e) {
  if (verbosity_ == Verbosity::quiet) return;
  std::lock_guard<std::mutex> lock(mutex_);
  if (e.kind == ProgressEvent::Kind::finished) {
    erase();
    text_.clear();
    if (verbosity_ == Verbosity::verbose) {
      std::fprintf(out_, "stage %-12s %8.2f s", e.stage.c_str(), e.seconds);
      if (e.done > 0) std::fprintf(out_, "  (%zu items)", e.done);
      std::fprintf(out_, "\n");
      std::fflush(out_);
    }
    return;
  }
  if (!line_) return;
  text_ = e.stage;
  if (e.kind == ProgressEvent::Kind::advanced && e.total > 0)
    text_ += " " + std::to_string(e.done) + "/" + std::to_string(e.total);
  draw();
}

}  // namespace polysquare::cli
