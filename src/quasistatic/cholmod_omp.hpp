#pragma once
// Private: CHOLMOD's OpenMP regions run inline inside LinearSolver calls, guarded by a start-up
// self-test (cholmod_omp.cpp; docs/quasistatic.md "CHOLMOD and OpenMP").
#include <string>

namespace netdem::qs::detail {

/// RAII: while alive on this thread, the OpenMP regions that CHOLMOD itself opens run inline on
/// this thread (when the self-test passed); every other region (a BLAS, the caller's) is untouched.
struct SerialCholmod {
  SerialCholmod();
  ~SerialCholmod();
  SerialCholmod(const SerialCholmod&) = delete;
  SerialCholmod& operator=(const SerialCholmod&) = delete;
};

/// Runs the self-test once per process (thread-safe) and says whether inlining is active; when it
/// is not, `why` says why (also printed once on stderr as a warning when the test failed).
bool inline_omp_active(std::string* why = nullptr);

}  // namespace netdem::qs::detail
