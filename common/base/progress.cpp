#include "common/base/progress.h"

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <mutex>

namespace ls {

bool stderr_is_terminal() { return isatty(STDERR_FILENO) == 1; }

struct ProgressLine::State {
  std::string label, unit;
  ProgressEnd end;
  std::mutex mutex;
  std::chrono::steady_clock::time_point last{};
  bool drawn = false;  // since the line began
  size_t width = 0;  // characters of the longest line drawn, to erase it
};

ProgressLine::ProgressLine(std::string label, std::string unit, bool enabled, ProgressEnd end) {
  if (!enabled) return;
  state_ = std::make_shared<State>();
  state_->label = std::move(label);
  state_->unit = std::move(unit);
  state_->end = end;
}

void ProgressLine::update(size_t done, size_t total) const {
  if (!state_ || total == 0) return;
  State& s = *state_;
  const bool last = done >= total;
  std::unique_lock<std::mutex> lock(s.mutex, std::defer_lock);
  if (last) lock.lock();  // the end is never skipped
  else if (!lock.try_lock()) return;
  const auto now = std::chrono::steady_clock::now();
  if (!last && s.drawn && now - s.last < std::chrono::milliseconds(200)) return;
  s.last = now;
  s.drawn = true;
  const size_t bar = 30, filled = (last ? total : done) * bar / total;
  const std::string line = s.label + " [" + std::string(filled, '#') + std::string(bar - filled, ' ') + "] " +
                           std::to_string(last ? total : done) + "/" + std::to_string(total) + " " + s.unit;
  if (line.size() > s.width) s.width = line.size();
  std::fprintf(stderr, "\r%s", line.c_str());
  if (last) {  // the next update begins a new line (render --frames: one per frame)
    if (s.end == ProgressEnd::Keep) std::fprintf(stderr, "\n");
    else std::fprintf(stderr, "\r%s\r", std::string(s.width, ' ').c_str());
    s.drawn = false;
    s.width = 0;
  }
  std::fflush(stderr);
}

}  // namespace ls
