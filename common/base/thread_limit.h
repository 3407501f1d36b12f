// --threads N: how many threads the whole run may use.  Every parallel call of ours (parallel.h) and
// Embree's builds and traces run on the one TBB library, so one tbb::global_control limits them all:
// benchmarks at a chosen core count ("2 cores") on a larger machine, and runs whose figures (thread
// reports, memory peaks that grow with threads) must not depend on the machine.
#pragma once

#include <tbb/global_control.h>

#include <optional>

namespace ls {

// The threads a parallel call may use now: the process's CPUs (its affinity mask, e.g. under
// taskset), or fewer while a ThreadLimit is alive.
int thread_count();

// Limits every parallel call to `threads` for its lifetime; 0 leaves the default (all the process's
// CPUs).  Throws InputError for a negative count or one above the process's CPUs: more threads than
// CPUs would only time-slice, and a report would name threads that never ran at once.
class ThreadLimit {
 public:
  explicit ThreadLimit(int threads);
  ~ThreadLimit();
  ThreadLimit(const ThreadLimit&) = delete;
  ThreadLimit& operator=(const ThreadLimit&) = delete;

 private:
  std::optional<tbb::global_control> control_;
};

}  // namespace ls
