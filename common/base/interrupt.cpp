#include "common/base/interrupt.h"


#include <atomic>
#include <csignal>
#include <cstring>
#include <unistd.h>

namespace ls {
namespace {

std::atomic<int> pending_signal{0};
static_assert(std::atomic<int>::is_always_lock_free, "the signal handler needs a lock-free flag");

// The partial file's path for the handler: written only while no signal is being handled.
char partial_path[4096];
std::atomic<bool> partial_set{false};

extern "C" void on_signal(int signal) {
  int expected = 0;
  if (pending_signal.compare_exchange_strong(expected, signal)) return;  // first: ask the loops to stop
  // Second signal: the user insists.  Only async-signal-safe calls from here.
  if (partial_set.load()) ::unlink(partial_path);
  static const char msg[] = "linespace: interrupted again, stopping now\n";
  ssize_t ignored = ::write(2, msg, sizeof(msg) - 1);
  (void)ignored;
  ::_exit(128 + signal);
}

}  // namespace

void install_interrupt_handlers() {
  struct sigaction sa;
  std::memset(&sa, 0, sizeof(sa));
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

bool interrupt_requested() { return pending_signal.load(std::memory_order_relaxed) != 0; }
int interrupt_signal() { return pending_signal.load(); }
void request_interrupt(int signal) { pending_signal.store(signal); }
void clear_interrupt() { pending_signal.store(0); }

void throw_if_interrupted() {
  const int s = pending_signal.load();
  if (s == 0) return;
  throw Interrupted(std::string("interrupted by ") + (s == SIGINT ? "SIGINT" : s == SIGTERM ? "SIGTERM" : "a signal"));
}

void set_partial_file(const std::string* path) {
  partial_set.store(false);
  if (!path || path->size() >= sizeof(partial_path)) return;
  std::memcpy(partial_path, path->c_str(), path->size() + 1);
  partial_set.store(true);
}

}  // namespace ls
