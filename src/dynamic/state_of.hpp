#pragma once
// The SolverState fields of dimension D (the 2D ones, or the 3D ones of a sphere state), for
// solver_state.cpp and state.cpp. The histories are the law's and the dimension's alternative of
// SolverState::histories (SolverState::histories_of<H>()).
#include "netdem/dynamic/solver.hpp"

namespace netdem::dem {
// The SolverState fields of dimension D (the 2D ones, or the 3D ones of a sphere state).
template <int D>
struct StateOf;
template <>
struct StateOf<2> {
  static double* wall_velocity(SolverState& s) { return s.wall_velocity; }
  static const double* wall_velocity(const SolverState& s) { return s.wall_velocity; }
  static double* wall_force(SolverState& s) { return s.wall_force; }
  static const double* wall_force(const SolverState& s) { return s.wall_force; }
};
template <>
struct StateOf<3> {
  static double* wall_velocity(SolverState& s) { return s.wall_velocity3; }
  static const double* wall_velocity(const SolverState& s) { return s.wall_velocity3; }
  static double* wall_force(SolverState& s) { return s.wall_force3; }
  static const double* wall_force(const SolverState& s) { return s.wall_force3; }
};

}  // namespace netdem::dem
