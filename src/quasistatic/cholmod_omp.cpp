// CHOLMOD's OpenMP regions, run inline inside LinearSolver calls, with a guard.
//
// Why: Debian's CHOLMOD 3 opens an OpenMP region (num_threads(4), usually with a false
// if-clause) for several loops of every supernode: ~4000 regions per numeric factorisation of the
// default scene. Even serial (omp_set_max_active_levels(0)) each inactive region costs a team
// allocation and a futex syscall in libgomp (3.4 M syscalls, 1.5 s of a 6.5 s default compaction;
// docs/performance.md, 2026-11-26). The solver is serial by design, so while a LinearSolver is
// inside CHOLMOD, the outlined body of a region that CHOLMOD opens is called directly on this
// thread: outside a team omp_get_num_threads() = 1 and omp_get_thread_num() = 0, which is what the
// static-schedule loops of CHOLMOD need (its only OpenMP entry points: GOMP_parallel,
// omp_get_num_threads, omp_get_thread_num). The supernodal factorisation also reads the clock
// (SuiteSparse_time) around every BLAS call, only for statistics nothing here reads: 0 is returned.
//
// The guard (this rests on libgomp's entry point and on how CHOLMOD 3 uses it):
//  * only regions opened from CHOLMOD's own code are inlined: the return address of the
//    GOMP_parallel call must lie in the executable segment of the object that holds
//    cholmod_factorize. A region of an OpenMP BLAS called by CHOLMOD (update-alternatives), whose
//    threads may wait for each other, goes to libgomp as usual;
//  * a self-test, once per process before the first LinearSolver: the CHOLMOD loaded at run time
//    must be the major.minor version compiled against; a supernodal factorisation and solve of a
//    test matrix must open at least one region that is inlined, and give a solution identical to
//    the bit with inlining off. If a check fails, inlining stays off for the process (results are
//    the same, CHOLMOD is slower) and one warning line is printed on stderr;
//  * NETDEM_CHOLMOD_INLINE_OMP=0 in the environment turns it off without a warning; the CMake
//    option of the same name (default ON) leaves the definitions out of the build.
#include "cholmod_omp.hpp"
#include "linear_solver_impl.hpp"
#include "netdem/quasistatic/linear_solver.hpp"

#include <dlfcn.h>
#include <link.h>

#include <atomic>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <vector>

#include <cholmod.h>
#include <fmt/format.h>

namespace netdem::qs::detail {

namespace {

thread_local int serial_depth = 0;        // SerialCholmod nesting on this thread
thread_local long inlined_regions = 0;    // regions run inline on this thread (self-test)
std::atomic<int> g_mode{0};               // 0: not tested yet (never inline), 1: active, 2: off
std::atomic<bool> g_testing{false};       // the self-test's "inline on" run
std::uintptr_t g_text_lo = 0, g_text_hi = 0;  // CHOLMOD's executable segment

bool in_cholmod(const void* addr) {
  const auto a = reinterpret_cast<std::uintptr_t>(addr);
  return a >= g_text_lo && a < g_text_hi;
}

bool may_inline(const void* caller) {
  if (serial_depth <= 0) return false;
  const int m = g_mode.load(std::memory_order_relaxed);
  return (m == 1 || (m == 0 && g_testing.load(std::memory_order_relaxed))) && in_cholmod(caller);
}

struct Segment {
  std::uintptr_t target, lo = 0, hi = 0;
};

int find_segment(dl_phdr_info* info, std::size_t, void* data) {
  auto* s = static_cast<Segment*>(data);
  for (int k = 0; k < info->dlpi_phnum; ++k) {
    const auto& ph = info->dlpi_phdr[k];
    if (ph.p_type != PT_LOAD || !(ph.p_flags & PF_X)) continue;
    const std::uintptr_t lo = info->dlpi_addr + ph.p_vaddr, hi = lo + ph.p_memsz;
    if (s->target >= lo && s->target < hi) {
      s->lo = lo;
      s->hi = hi;
      return 1;
    }
  }
  return 0;
}

/// Supernodal factorisation and solve of a 2D 5-point Laplacian (+ shift) on a g x g grid; the
/// solution of A x = 1. Returns false (with a message) if CHOLMOD fails.
bool test_solve(int g, std::vector<double>& x, std::string& why) {
  const int n = g * g;
  std::vector<int> p(n + 1, 0), i;
  std::vector<double> v;
  for (int c = 0; c < n; ++c) {  // lower triangle, column c
    const int cx = c % g, cy = c / g;
    i.push_back(c);
    v.push_back(4.01);
    if (cx + 1 < g) {
      i.push_back(c + 1);
      v.push_back(-1.0);
    }
    if (cy + 1 < g) {
      i.push_back(c + g);
      v.push_back(-1.0);
    }
    p[c + 1] = static_cast<int>(i.size());
  }
  cholmod_common cm;
  cholmod_start(&cm);
  cm.supernodal = CHOLMOD_SUPERNODAL;
  cholmod_sparse A = lower_view(n, i.size(), p.data(), i.data(), v.data());
  bool ok = false;
  cholmod_factor* L = cholmod_analyze(&A, &cm);
  if (L != nullptr) {
    SerialCholmod serial;
    if (cholmod_factorize(&A, L, &cm) && cm.status == CHOLMOD_OK) {
      cholmod_dense* b = cholmod_ones(A.nrow, 1, CHOLMOD_REAL, &cm);
      cholmod_dense* s = b ? cholmod_solve(CHOLMOD_A, L, b, &cm) : nullptr;
      if (s != nullptr) {
        const auto* sx = static_cast<const double*>(s->x);
        x.assign(sx, sx + n);
        ok = true;
      }
      cholmod_free_dense(&s, &cm);
      cholmod_free_dense(&b, &cm);
    }
  }
  if (!ok) why = fmt::format("the test factorisation failed (CHOLMOD status {})", cm.status);
  cholmod_free_factor(&L, &cm);
  cholmod_finish(&cm);
  return ok;
}

/// The self-test; empty string = passed.
std::string self_test() {
  int v[3] = {0, 0, 0};
  cholmod_version(v);
  if (v[0] != CHOLMOD_MAIN_VERSION || v[1] != CHOLMOD_SUB_VERSION)
    return fmt::format("CHOLMOD {}.{}.{} is loaded but netdem was built against {}.{}.{}", v[0], v[1], v[2],
                       CHOLMOD_MAIN_VERSION, CHOLMOD_SUB_VERSION, CHOLMOD_SUBSUB_VERSION);
  Segment seg{reinterpret_cast<std::uintptr_t>(&cholmod_factorize)};
  dl_iterate_phdr(find_segment, &seg);
  if (seg.hi <= seg.lo) return "CHOLMOD's code segment was not found";
  g_text_lo = seg.lo;
  g_text_hi = seg.hi;
  std::vector<double> off, on;
  std::string why;
  if (!test_solve(60, off, why)) return why;
  inlined_regions = 0;
  g_testing = true;
  const bool ok = test_solve(60, on, why);
  g_testing = false;
  if (!ok) return why + " with inline OpenMP regions";
  if (inlined_regions == 0) return "CHOLMOD opened no OpenMP region through GOMP_parallel (nothing to inline)";
  if (on != off) return "inline OpenMP regions changed CHOLMOD's solution";
  return {};
}

std::once_flag g_once;
std::string g_why;

void run_self_test() {
  const char* env = std::getenv("NETDEM_CHOLMOD_INLINE_OMP");
  if (env != nullptr && std::strcmp(env, "0") == 0) {
    g_why = "turned off by NETDEM_CHOLMOD_INLINE_OMP=0";
    g_mode = 2;
    return;
  }
#if NETDEM_CHOLMOD_INLINE_OMP
  g_why = self_test();
  g_mode = g_why.empty() ? 1 : 2;
  if (!g_why.empty())
    std::fprintf(stderr, "netdem: warning: CHOLMOD's OpenMP regions run through libgomp (slower, same results): %s\n",
                 g_why.c_str());
#else
  g_why = "built with NETDEM_CHOLMOD_INLINE_OMP=OFF";
  g_mode = 2;
#endif
}

}  // namespace

SerialCholmod::SerialCholmod() { ++serial_depth; }
SerialCholmod::~SerialCholmod() { --serial_depth; }

bool inline_omp_active(std::string* why) {
  std::call_once(g_once, run_self_test);
  if (why != nullptr) *why = g_why;
  return g_mode.load() == 1;
}

}  // namespace netdem::qs::detail

namespace netdem::qs {
bool cholmod_inline_openmp(std::string* why) { return detail::inline_omp_active(why); }
}  // namespace netdem::qs

#if NETDEM_CHOLMOD_INLINE_OMP
// The definitions that take precedence over libgomp's and libsuitesparseconfig's (the executable
// links this library statically; in a shared-library build they may not, and then nothing is
// inlined: the self-test says so).
extern "C" void GOMP_parallel(void (*fn)(void*), void* data, unsigned num_threads, unsigned flags) {
  if (netdem::qs::detail::may_inline(__builtin_return_address(0))) {
    ++netdem::qs::detail::inlined_regions;
    fn(data);
    return;
  }
  using Real = void (*)(void (*)(void*), void*, unsigned, unsigned);
  static const Real real = reinterpret_cast<Real>(dlsym(RTLD_NEXT, "GOMP_parallel"));
  if (real == nullptr) {  // no libgomp behind us: run the region on this thread
    fn(data);
    return;
  }
  real(fn, data, num_threads, flags);
}

extern "C" double SuiteSparse_time(void) {
  if (netdem::qs::detail::serial_depth > 0 && netdem::qs::detail::g_mode.load(std::memory_order_relaxed) == 1) return 0.0;
  using Real = double (*)();
  static const Real real = reinterpret_cast<Real>(dlsym(RTLD_NEXT, "SuiteSparse_time"));
  if (real == nullptr) return 0.0;
  return real();
}
#endif  // NETDEM_CHOLMOD_INLINE_OMP
