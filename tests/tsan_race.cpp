// Built in the TSan preset only (tests/CMakeLists.txt).  Checks the TSan setup itself: Debian's
// uninstrumented TBB with the annotations of common/base/parallel.h must still
// report a real race, and must not report what TBB orders.
//
//   tsan_race threads | parallel_for | parallel_reduce | parallel_invoke
//       two threads (two bodies of one ls:: call) write one int, in three rounds: TSan must report a
//       race here
//   tsan_race ordered
//       the caller writes, bodies of each ls:: algorithm read it and write their own results, the
//       caller reads those: all ordered by TBB, so TSan must report nothing (exit 0)
//
// In every mode the bodies first wait for each other, with relaxed atomics (which order nothing for
// TSan), so they surely run at the same time on two threads; if they never meet, exit 1.
#include "common/base/parallel.h"

#include <atomic>
#include <chrono>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

namespace {

std::atomic<bool> alone{false};

// Two callers of arrive() wait for each other (at most 60 s, then `alone` is set).
class Meeting {
 public:
  void arrive() {
    arrived_.fetch_add(1, std::memory_order_relaxed);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (arrived_.load(std::memory_order_relaxed) < 2) {
      if (std::chrono::steady_clock::now() > deadline) {
        alone.store(true, std::memory_order_relaxed);
        return;
      }
      std::this_thread::yield();
    }
  }

 private:
  std::atomic<int> arrived_{0};
};

int shared = 0;  // what the racy modes write from two threads

void racy_write(Meeting& m) {
  m.arrive();
  shared = shared + 1;
}

int ordered() {
  Meeting warm_up;  // the workers' creation would order everything before it: start them first
  ls::parallel_for(0, 2, [&](int) { warm_up.arrive(); });

  const std::vector<int> in = {3, 4};  // written after the workers exist
  std::vector<int> out(2, 0);
  Meeting m1, m2, m3;
  ls::parallel_for(0, 2, [&](int i) {
    m1.arrive();
    out[size_t(i)] = 2 * in[size_t(i)];
  });
  const int sum = ls::parallel_reduce(
      tbb::blocked_range<int>(0, 2, 1), 0,
      [&](const tbb::blocked_range<int>& r, int v) {
        for (int i = r.begin(); i != r.end(); ++i) {
          m2.arrive();
          v += out[size_t(i)];
        }
        return v;
      },
      [](int a, int b) { return a + b; });
  ls::parallel_invoke([&] { m3.arrive(); out[0] += sum; }, [&] { m3.arrive(); out[1] += sum; });
  return out[0] == 20 && out[1] == 22 ? 0 : 1;
}

// One racy run of `mode` (false: no such mode): two bodies meet, then both write `shared`.
bool race_once(const std::string& mode) {
  Meeting m;
  if (mode == "threads") {
    std::thread a([&] { racy_write(m); }), b([&] { racy_write(m); });
    a.join();
    b.join();
  } else if (mode == "parallel_for") {
    ls::parallel_for(0, 2, [&](int) { racy_write(m); });
  } else if (mode == "parallel_reduce") {
    ls::parallel_reduce(
        tbb::blocked_range<int>(0, 2, 1), 0,
        [&](const tbb::blocked_range<int>& r, int v) {
          for (int i = r.begin(); i != r.end(); ++i) racy_write(m);
          return v;
        },
        [](int a, int b) { return a + b; });
  } else if (mode == "parallel_invoke") {
    ls::parallel_invoke([&] { racy_write(m); }, [&] { racy_write(m); });
  } else {
    return false;
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string mode = argc == 2 ? argv[1] : "";
  int status = 0;
  if (mode == "ordered") {
    status = ordered();
  } else {
    // Three rounds: in about 1 run of 100 of the TBB modes, TSan reported no race although the two
    // bodies met and both wrote (measured; why, not found).  One report is all the test asks for.
    for (int round = 0; round < 3; ++round) {
      if (!race_once(mode)) {
        std::fprintf(stderr, "usage: tsan_race threads|parallel_for|parallel_reduce|parallel_invoke|ordered\n");
        return 2;
      }
    }
  }
  if (alone) {
    std::fprintf(stderr, "tsan_race %s: the bodies never ran on two threads at once\n", mode.c_str());
    return 1;
  }
  std::printf("tsan_race %s: done (status %d)\n", mode.c_str(), status);
  return status;
}
