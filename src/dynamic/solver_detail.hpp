#pragma once
// Private helpers shared by the solver's source files (solver.cpp, solver_setup.cpp,
// solver_table.cpp, solver_affine.cpp, solver_observe.cpp).
#include <algorithm>
#include <stdexcept>
#include <string>

namespace netdem::dem::detail {

[[noreturn]] inline void fail(const std::string& msg) { throw std::invalid_argument(msg); }

// Two particles each moving d and each growing by g (Eq 9) close a gap by 2 d + 2 g: the table
// (range r_i + r_j + skin at the build) stays complete while d < skin / 2 - g. Returns that limit
// on d (<= 0: rebuild now).
inline double displacement_limit(double skin, double radius_ref_max, double scale, double scale_build) {
  const double grow = radius_ref_max * std::max(0.0, scale - scale_build);
  return 0.5 * skin - grow;
}

}  // namespace netdem::dem::detail
