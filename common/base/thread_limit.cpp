#include "common/base/thread_limit.h"

#include "common/model/scene.h"

#include <tbb/info.h>

#include <algorithm>
#include <string>

namespace ls {

int thread_count() {
  // active_value reports a limit above the CPUs as given; no more than the CPUs run at once.
  const size_t limit = tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism);
  return int(std::min(limit, size_t(tbb::info::default_concurrency())));
}

ThreadLimit::ThreadLimit(int threads) {
  const int cpus = tbb::info::default_concurrency();
  if (threads < 0 || threads > cpus)
    throw InputError("--threads " + std::to_string(threads) + ": give 1 to " + std::to_string(cpus) +
                     " (this process's CPUs), or 0 for all of them");
  if (threads > 0) control_.emplace(tbb::global_control::max_allowed_parallelism, size_t(threads));
}

ThreadLimit::~ThreadLimit() = default;

}  // namespace ls
