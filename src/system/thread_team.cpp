// ThreadTeam (thread_team.hpp): a generation counter starts a run, a count of pending workers ends
// it; both are waited on by spinning for a few microseconds, then sleeping on the atomic.
#include "netdem/system/thread_team.hpp"

#include <stdexcept>

namespace netdem::sys {
namespace {
// Spin iterations (pause instructions) before sleeping, about 20-40 microseconds. Measured on the
// 2-core VM (docs/performance.md "Issue 31, part 3"): with another process running, 100 to 1000
// cost two threads 1.8-2 times one thread's time, 4000 2.4 times, 20000 4.4 times; idle, the
// values were not resolved by the machine's scatter.
constexpr int kSpins = 1000;

inline void relax() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#endif
}

// Waits until a.load() != old (spin, then sleep); returns the new value.
template <class T>
T wait_change(const std::atomic<T>& a, T old) {
  for (int k = 0; k < kSpins; ++k) {
    const T v = a.load(std::memory_order_acquire);
    if (v != old) return v;
    relax();
  }
  for (;;) {
    a.wait(old, std::memory_order_acquire);
    const T v = a.load(std::memory_order_acquire);
    if (v != old) return v;
  }
}
}  // namespace

ThreadTeam::ThreadTeam(int threads) : n_(threads) {
  if (threads < 1) throw std::invalid_argument("ThreadTeam: threads must be >= 1");
  errors_.resize(static_cast<std::size_t>(threads));
  workers_.reserve(static_cast<std::size_t>(threads - 1));
  for (int t = 1; t < threads; ++t) workers_.emplace_back([this, t] { work(t); });
}

ThreadTeam::~ThreadTeam() {
  stop_.store(true, std::memory_order_relaxed);
  generation_.fetch_add(1, std::memory_order_release);
  generation_.notify_all();
  for (auto& w : workers_) w.join();
}

void ThreadTeam::work(int t) {
  std::uint64_t seen = 0;
  for (;;) {
    seen = wait_change(generation_, seen);
    if (stop_.load(std::memory_order_relaxed)) return;
    try {
      fn_(ctx_, t, n_);
    } catch (...) {
      errors_[static_cast<std::size_t>(t)] = std::current_exception();
    }
    if (pending_.fetch_sub(1, std::memory_order_acq_rel) == 1) pending_.notify_one();
  }
}

void ThreadTeam::barrier() {
  if (n_ == 1) return;
  const std::uint64_t phase = phase_.load(std::memory_order_acquire);
  if (arrived_.fetch_add(1, std::memory_order_acq_rel) == n_ - 1) {
    arrived_.store(0, std::memory_order_relaxed);
    phase_.fetch_add(1, std::memory_order_release);
    phase_.notify_all();
    return;
  }
  wait_change(phase_, phase);
}

void ThreadTeam::run_erased(void (*fn)(void*, int, int), void* ctx) {
  if (n_ == 1) {
    fn(ctx, 0, 1);
    return;
  }
  fn_ = fn;
  ctx_ = ctx;
  for (auto& e : errors_) e = nullptr;
  pending_.store(n_ - 1, std::memory_order_relaxed);
  generation_.fetch_add(1, std::memory_order_release);
  generation_.notify_all();
  try {
    fn(ctx, 0, n_);
  } catch (...) {
    errors_[0] = std::current_exception();
  }
  int left = pending_.load(std::memory_order_acquire);
  while (left != 0) left = wait_change(pending_, left);
  for (const auto& e : errors_)
    if (e) std::rethrow_exception(e);
}

}  // namespace netdem::sys
