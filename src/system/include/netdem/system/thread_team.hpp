#pragma once
// A team of threads for the fork-join loops of a solver (the explicit DEM's DynamicOptions::threads).
// run(f) calls f(t, n) for t = 0 .. n - 1, t = 0 on the calling thread, and returns when every call
// has returned; an exception thrown by a call is rethrown by run() (that of the lowest t).
//
// Idle members spin briefly, then sleep on an atomic (std::atomic::wait: a futex on Linux). A team
// that only spins, as OpenMP's default active wait does, made two threads 60 times slower than one
// on a 2-core machine with one other process running (docs/performance.md "Issue 31, part 3").
//
// A team belongs to one owner and is used from one thread at a time. TeamHandle holds one for an
// object that may be copied: a copy starts without a team (a copy run on another thread must not
// share its original's team).
#include <atomic>
#include <cstdint>
#include <exception>
#include <memory>
#include <thread>
#include <vector>

namespace netdem::sys {

class ThreadTeam {
 public:
  explicit ThreadTeam(int threads);  ///< threads >= 1 (1: run() calls f on the calling thread)
  ~ThreadTeam();
  ThreadTeam(const ThreadTeam&) = delete;
  ThreadTeam& operator=(const ThreadTeam&) = delete;
  int size() const { return n_; }
  /// Inside a run: every member waits here until all have arrived (then all go on).
  void barrier();
  template <class F>
  void run(F& f) {
    run_erased(&call<F>, &f);
  }

 private:
  template <class F>
  static void call(void* f, int t, int n) {
    (*static_cast<F*>(f))(t, n);
  }
  void run_erased(void (*fn)(void*, int, int), void* ctx);
  void work(int t);

  int n_;
  std::vector<std::thread> workers_;
  std::vector<std::exception_ptr> errors_;  ///< per member, of the last run
  std::atomic<std::uint64_t> generation_{0};  ///< one more per run (and at shutdown)
  std::atomic<int> pending_{0};               ///< workers still in the current run
  std::atomic<bool> stop_{false};
  std::atomic<int> arrived_{0};               ///< members at the barrier
  std::atomic<std::uint64_t> phase_{0};       ///< one more per completed barrier
  void (*fn_)(void*, int, int) = nullptr;
  void* ctx_ = nullptr;
};

/// A ThreadTeam made on first use with the size asked for; copies start empty.
class TeamHandle {
 public:
  TeamHandle() = default;
  TeamHandle(const TeamHandle&) {}
  TeamHandle& operator=(const TeamHandle&) { return *this; }
  TeamHandle(TeamHandle&&) noexcept = default;
  TeamHandle& operator=(TeamHandle&&) noexcept = default;
  ThreadTeam& get(int threads) {
    if (!team_ || team_->size() != threads) team_ = std::make_unique<ThreadTeam>(threads);
    return *team_;
  }

 private:
  std::unique_ptr<ThreadTeam> team_;
};

}  // namespace netdem::sys
