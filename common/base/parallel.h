// The parallel algorithms of linespace: ls::parallel_for, ls::parallel_reduce and ls::parallel_invoke
// take the arguments of their tbb:: namesakes (index or range form; reduce in the functional form:
// range, identity, body, combine) and do the same.  Every parallel call of ours goes through them
// (tests/check_parallel_calls.cmake fails on a TBB algorithm, task group or arena used elsewhere).
//
// Why: Debian's libtbb.so is not built with ThreadSanitizer, so TSan cannot see the ordering TBB
// guarantees, and TBB's header code (compiled into our binaries, instrumented) hands task memory and
// counters between threads in ways TSan reports as races.  Under -fsanitize=thread these wrappers
//  - hide TBB from TSan: a thread's memory accesses are ignored while it runs TBB code, i.e. from
//    the start of a parallel call to its return, and on TBB's worker threads except inside our
//    bodies (an observer starts ignoring when a worker joins the arena);
//  - tell TSan what TBB orders and nothing more (__tsan_release / __tsan_acquire on two addresses of
//    each call): the caller's work before the call happens before every body, every body before the
//    caller's work after it.  Two bodies of one call stay unordered, so a race between them is
//    still reported (tests/tsan_race.cpp checks both).
// Our code in the bodies stays visible, with one rule that keeps it so: it never writes TBB's task
// memory (reduce values are copied in and out of it unseen).  In every other build all of this is
// empty inline functions and the calls are TBB's own (docs/robustness.md, "TSan and Debian's TBB").
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_reduce.h>

#include <utility>

#if defined(__SANITIZE_THREAD__)  // GCC
#define LINESPACE_TSAN 1
#elif defined(__has_feature)      // clang
#if __has_feature(thread_sanitizer)
#define LINESPACE_TSAN 1
#endif
#endif

#ifdef LINESPACE_TSAN
#include <sanitizer/tsan_interface.h>
#include <tbb/task_scheduler_observer.h>
extern "C" void __tsan_ignore_thread_begin();  // TSan's runtime has them; no header declares them
extern "C" void __tsan_ignore_thread_end();
#endif

namespace ls {
namespace parallel_detail {

#ifdef LINESPACE_TSAN
inline void acquire(const void* sync) { __tsan_acquire(const_cast<void*>(sync)); }
inline void release(const void* sync) { __tsan_release(const_cast<void*>(sync)); }
inline void unseen_begin() { __tsan_ignore_thread_begin(); }  // nests: a count per thread
inline void unseen_end() { __tsan_ignore_thread_end(); }

// TBB's workers run TBB's code, unseen, while they are in the arena; our bodies (Run) make
// themselves visible.  Installed before main, before TBB has started any worker.  TBB ends its
// workers at exit without an exit notice, and TSan refuses a thread that ends unseen: what is left
// is ended by a thread_local's destructor, which runs before TSan's end of the thread.
struct UnseenDepth {
  int count = 0;
  ~UnseenDepth() {
    for (; count > 0; --count) unseen_end();
  }
};
inline thread_local UnseenDepth unseen_depth;

class UnseenWorkers final : public tbb::task_scheduler_observer {
 public:
  UnseenWorkers() { observe(true); }
  void on_scheduler_entry(bool is_worker) override {
    if (!is_worker) return;
    unseen_begin();
    ++unseen_depth.count;
  }
  void on_scheduler_exit(bool is_worker) override {
    if (!is_worker || unseen_depth.count == 0) return;
    unseen_end();
    --unseen_depth.count;
  }
};
inline UnseenWorkers unseen_workers;

// A copy, taken unseen, of a value in TBB's memory (elsewhere the value itself, as TBB passes it).
template <class T>
T unseen_copy(const T& v) {
  return v;
}
#else
inline void acquire(const void*) {}
inline void release(const void*) {}
inline void unseen_begin() {}
inline void unseen_end() {}
template <class T>
const T& unseen_copy(const T& v) {
  return v;
}
#endif

// One parallel call, on the caller's stack, around the TBB call: releases `fork_` and hides the
// caller; at the end (also when the call throws) shows it again and acquires `join_`.
class Call {
 public:
  Call() {
    release(&fork_);
    unseen_begin();
  }
  Call(const Call&) = delete;
  Call& operator=(const Call&) = delete;
  ~Call() {
    unseen_end();
    acquire(&join_);
  }

 private:
  friend class Run;
  char fork_ = 0, join_ = 0;  // only their addresses are used
};

// One run of a body of a call, on whichever thread TBB chose: visible, after the caller's work
// before the call and before the caller's work after it (also when the body throws).
class Run {
 public:
  explicit Run(const Call& call) : call_(call) {
    unseen_end();
    acquire(&call_.fork_);
  }
  Run(const Run&) = delete;
  Run& operator=(const Run&) = delete;
  ~Run() {
    release(&call_.join_);
    unseen_begin();
  }

 private:
  const Call& call_;
};

// A body handed to TBB, which copies it into its task memory; read there unseen, before Run.
template <class F>
class Body {
 public:
  Body(const F& f, const Call& call) : f_(f), call_(call) {}

  template <class... Args>
  void operator()(Args&&... args) const {
    const F& f = f_;
    const Run run(call_);
    f(std::forward<Args>(args)...);
  }

 private:
  const F& f_;
  const Call& call_;
};

// parallel_reduce's body: a running value, which lives in TBB's task memory (right-hand copies are
// made there, and TBB recycles that memory between threads unseen), so under TSan it is only copied
// there and back unseen, and the body and combine functions work on copies on their own stack.
template <class Value, class F, class Combine>
class ReduceBody {
 public:
  ReduceBody(const Value& identity, const F& f, const Combine& combine, const Call& call)
      : identity_(identity), f_(f), combine_(combine), call_(call), value_(identity) {}
  ReduceBody(ReduceBody& other, tbb::split)
      : identity_(other.identity_), f_(other.f_), combine_(other.combine_), call_(other.call_),
        value_(other.identity_) {}
  ReduceBody& operator=(const ReduceBody&) = delete;

  template <class Range>
  void operator()(const Range& range) {
    const F& f = f_;
    const auto& in = unseen_copy(value_);
    value_ = visible([&] { return f(range, in); });
  }
  void join(ReduceBody& right) {
    const Combine& combine = combine_;
    const auto& left = unseen_copy(value_);
    const auto& right_value = unseen_copy(right.value_);
    value_ = visible([&] { return combine(left, right_value); });
  }
  const Value& value() const { return value_; }

 private:
  template <class G>
  Value visible(const G& g) const {
    const Run run(call_);
    return g();
  }

  const Value& identity_;
  const F& f_;
  const Combine& combine_;
  const Call& call_;
  Value value_;
};

}  // namespace parallel_detail

// tbb::parallel_for(range, body): body(range) for subranges.
template <class Range, class F>
void parallel_for(const Range& range, const F& f) {
  const parallel_detail::Call call;
  tbb::parallel_for(range, parallel_detail::Body<F>(f, call));
}

// tbb::parallel_for(first, last, body): body(i) for i in [first, last), split as TBB splits it.
template <class Index, class F>
void parallel_for(Index first, Index last, const F& f) {
  if (!(first < last)) return;
  // Qualified: unqualified, argument-dependent lookup would pick TBB's (more constrained) overload.
  ls::parallel_for(tbb::blocked_range<Index>(first, last), [&f](const tbb::blocked_range<Index>& r) {
    for (Index i = r.begin(); i != r.end(); ++i) f(i);
  });
}

// tbb::parallel_reduce(range, identity, body, combine): body(subrange, value) -> value, combined
// left to right with combine(left, right) -> value.
template <class Range, class Value, class F, class Combine>
Value parallel_reduce(const Range& range, const Value& identity, const F& f, const Combine& combine) {
  const parallel_detail::Call call;
  parallel_detail::ReduceBody<Value, F, Combine> body(identity, f, combine, call);
  tbb::parallel_reduce(range, body);
  return body.value();
}

// tbb::parallel_invoke(f, g, ...): runs them all, possibly at once.
template <class... F>
void parallel_invoke(const F&... f) {
  const parallel_detail::Call call;
  tbb::parallel_invoke(parallel_detail::Body<F>(f, call)...);
}

}  // namespace ls
