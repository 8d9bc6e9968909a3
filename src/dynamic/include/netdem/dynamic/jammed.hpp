#pragma once
// The DEM and the jammed state both solvers share (netdem/system/jammed_state.hpp; issue 28 item
// 6): the state of a plastic-indentation run at rest, and the solver that starts from one.
#include <cstdint>

#include <Eigen/Core>

#include "netdem/dynamic/solver.hpp"
#include "netdem/system/jammed_state.hpp"

namespace netdem::dem {

/// The jammed state of a plastic-indentation run: its centres, rotations (2D the angle; 3D zeros:
/// the DEM keeps no orientation of a sphere), radii, box (walls: box.contact_walls), law and
/// wall friction, and the histories as the law leaves them at rest (the state's particles
/// stopped, their forces evaluated once more: a sliding contact's spring is held by the spring's
/// normal force, without the dashpot). `strain`: the macroscopic strain so far (the caller's).
/// Throws std::invalid_argument for a Luding run.
template <int D>
sys::JammedStateT<D> jammed_state(const DynamicSolverT<D>& s, const Eigen::Matrix<double, D, D>& strain,
                                  std::uint64_t seed);

/// The solver that starts from a jammed state at rest: particles of density rho, the state's box
/// (its contact walls: the state's) with the wall control of `control` (modes of the moving
/// walls), `options` with the state's law and wall friction (its dashpots kept), the histories of
/// the state, and the forces evaluated from them at the state's positions. Time starts at 0.
template <int D>
DynamicSolverT<D> solver_from_jammed(const sys::JammedStateT<D>& j, double rho, const Box& control, DynamicOptions options);

}  // namespace netdem::dem
