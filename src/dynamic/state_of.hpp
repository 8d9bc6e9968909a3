#pragma once
// The SolverState fields of dimension D (the 2D ones, or the 3D ones of a sphere state), for
// solver_state.cpp and state.cpp.
#include <type_traits>

#include "netdem/dynamic/solver.hpp"

namespace netdem::dem {
// The SolverState fields of dimension D (the 2D ones, or the 3D ones of a sphere state).
template <int D>
struct StateOf;
template <>
struct StateOf<2> {
  static auto& pair(SolverState& s) { return s.pair_history; }
  static auto& wall(SolverState& s) { return s.wall_history; }
  static auto& pl_pair(SolverState& s) { return s.plastic_pair_history; }
  static auto& pl_wall(SolverState& s) { return s.plastic_wall_history; }
  static const auto& pair(const SolverState& s) { return s.pair_history; }
  static const auto& wall(const SolverState& s) { return s.wall_history; }
  static const auto& pl_pair(const SolverState& s) { return s.plastic_pair_history; }
  static const auto& pl_wall(const SolverState& s) { return s.plastic_wall_history; }
  // the histories of law history H (the SolverState's fields of each law: a new law adds its own)
  template <class H>
  static auto& pairs(SolverState& s) {
    if constexpr (std::is_same_v<H, contact::LudingHistoryT<2>>) return pair(s); else return pl_pair(s);
  }
  template <class H>
  static auto& walls(SolverState& s) {
    if constexpr (std::is_same_v<H, contact::LudingHistoryT<2>>) return wall(s); else return pl_wall(s);
  }
  template <class H>
  static const auto& pairs(const SolverState& s) {
    if constexpr (std::is_same_v<H, contact::LudingHistoryT<2>>) return pair(s); else return pl_pair(s);
  }
  template <class H>
  static const auto& walls(const SolverState& s) {
    if constexpr (std::is_same_v<H, contact::LudingHistoryT<2>>) return wall(s); else return pl_wall(s);
  }
  static double* wall_velocity(SolverState& s) { return s.wall_velocity; }
  static const double* wall_velocity(const SolverState& s) { return s.wall_velocity; }
  static double* wall_force(SolverState& s) { return s.wall_force; }
  static const double* wall_force(const SolverState& s) { return s.wall_force; }
};
template <>
struct StateOf<3> {
  static auto& pair(SolverState& s) { return s.pair_history3; }
  static auto& wall(SolverState& s) { return s.wall_history3; }
  static auto& pl_pair(SolverState& s) { return s.plastic_pair_history3; }
  static auto& pl_wall(SolverState& s) { return s.plastic_wall_history3; }
  static const auto& pair(const SolverState& s) { return s.pair_history3; }
  static const auto& wall(const SolverState& s) { return s.wall_history3; }
  static const auto& pl_pair(const SolverState& s) { return s.plastic_pair_history3; }
  static const auto& pl_wall(const SolverState& s) { return s.plastic_wall_history3; }
  // the histories of law history H (the SolverState's fields of each law: a new law adds its own)
  template <class H>
  static auto& pairs(SolverState& s) {
    if constexpr (std::is_same_v<H, contact::LudingHistoryT<3>>) return pair(s); else return pl_pair(s);
  }
  template <class H>
  static auto& walls(SolverState& s) {
    if constexpr (std::is_same_v<H, contact::LudingHistoryT<3>>) return wall(s); else return pl_wall(s);
  }
  template <class H>
  static const auto& pairs(const SolverState& s) {
    if constexpr (std::is_same_v<H, contact::LudingHistoryT<3>>) return pair(s); else return pl_pair(s);
  }
  template <class H>
  static const auto& walls(const SolverState& s) {
    if constexpr (std::is_same_v<H, contact::LudingHistoryT<3>>) return wall(s); else return pl_wall(s);
  }
  static double* wall_velocity(SolverState& s) { return s.wall_velocity3; }
  static const double* wall_velocity(const SolverState& s) { return s.wall_velocity3; }
  static double* wall_force(SolverState& s) { return s.wall_force3; }
  static const double* wall_force(const SolverState& s) { return s.wall_force3; }
};

}  // namespace netdem::dem
