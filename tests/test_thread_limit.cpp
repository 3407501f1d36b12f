// --threads (common/base/thread_limit.h): a limit applies to every parallel call while it lives, is lifted
// after, and counts outside [0, the process's CPUs] are refused.
#include "common/base/parallel.h"
#include "common/base/thread_limit.h"
#include "common/model/scene.h"

#include <catch2/catch.hpp>
#include <tbb/info.h>

#include <chrono>
#include <mutex>
#include <set>
#include <thread>

namespace {

// The threads that ran the bodies of one parallel call whose 64 bodies each take 2 ms: long enough
// that every thread allowed joins in.
size_t threads_taking_part() {
  std::mutex m;
  std::set<std::thread::id> ids;
  ls::parallel_for(tbb::blocked_range<size_t>(0, 64, 1), [&](const tbb::blocked_range<size_t>&) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
    const std::lock_guard<std::mutex> lock(m);
    ids.insert(std::this_thread::get_id());
  });
  return ids.size();
}

}  // namespace

TEST_CASE("a thread limit holds every parallel call to its count while it lives", "[parallel]") {
  const int cpus = tbb::info::default_concurrency();
  CHECK(ls::thread_count() == cpus);
  {
    const ls::ThreadLimit one(1);
    CHECK(ls::thread_count() == 1);
    CHECK(threads_taking_part() == 1u);
  }
  CHECK(ls::thread_count() == cpus);
  {
    const ls::ThreadLimit all(0);  // 0: no limit
    CHECK(ls::thread_count() == cpus);
  }
  // Without a limit the same call spreads over the CPUs: what shows that the check under the limit
  // can fail (a one-CPU machine cannot show it).
  if (cpus > 1) CHECK(threads_taking_part() > 1u);
}

TEST_CASE("a thread count outside 0 to the process's CPUs is refused, naming the range", "[parallel]") {
  const int cpus = tbb::info::default_concurrency();
  for (int bad : {-1, cpus + 1, 1 << 20}) {
    INFO(bad);
    try {
      const ls::ThreadLimit limit(bad);
      FAIL("no error");
    } catch (const ls::InputError& e) {
      const std::string what = e.what();
      CHECK(what.find("--threads " + std::to_string(bad)) == 0);
      CHECK(what.find("1 to " + std::to_string(cpus)) != std::string::npos);
    }
    CHECK(ls::thread_count() == cpus);  // a refused limit leaves none behind
  }
}
