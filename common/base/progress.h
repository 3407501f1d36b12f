// One line of progress on stderr for the commands that run long (build with a large Line Space,
// render, the validator's studies): only when stderr is a terminal, redrawn in place ('\r') at most
// a few times a second, so that the hot loops pay nothing for it, and ended when the work is done.
// Anywhere else (a pipe, a file, ctest) it prints nothing.
#pragma once

#include <cstddef>
#include <functional>
#include <memory>
#include <string>

namespace ls {

bool stderr_is_terminal();

// What a finished line leaves: a newline (the line stays), or nothing (erased: the steps of a study,
// whose own log lines say what was done).
enum class ProgressEnd { Keep, Erase };

// A shared handle: copies (inside std::function callbacks) report to the same line.  Thread-safe:
// a caller that finds another drawing skips its tick.
class ProgressLine {
 public:
  // `label` names the work ("render"), `unit` what done/total count ("samples").  Disabled: silent.
  ProgressLine(std::string label, std::string unit, bool enabled = stderr_is_terminal(),
               ProgressEnd end = ProgressEnd::Keep);
  // Draws when done == total (and ends the line: a later update starts a new one) or when the last
  // draw is 0.2 s old.  Callers give done == total once.
  void update(size_t done, size_t total) const;
  bool enabled() const { return state_ != nullptr; }

 private:
  struct State;
  std::shared_ptr<State> state_;
};

}  // namespace ls
