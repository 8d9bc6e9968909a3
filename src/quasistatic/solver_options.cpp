// SolverOptions: validation and the presets (values and reasons: solver_options.hpp and
// docs/quasistatic.md "Presets").
#include "netdem/quasistatic/solver_options.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <fmt/format.h>

namespace netdem::qs {

namespace {
void require(bool ok, const std::string& msg) {
  if (!ok) throw std::invalid_argument(msg);
}
}  // namespace

Iteration default_iteration(BoundaryMode compaction, BoundaryMode probing) {
  return compaction == BoundaryMode::Die || probing == BoundaryMode::Die ? Iteration::LegacyDrag
                                                                         : Iteration::PseudoTransient;
}

void IterationOptions::validate() const {
  require(!affine_centres || mode == BoundaryMode::Periodic,
          "solver: affine_centres (every centre prescribed) is an option of the periodic boundary mode");
  require(std::isfinite(skin) && skin > 0.0, fmt::format("solver: skin must be positive, got {}", skin));
  require(max_newton >= 0 && max_newton <= 1000, fmt::format("solver: max_newton must be in [0, 1000], got {}", max_newton));
  require(!std::isnan(max_residual_tol) && max_residual_tol > 0.0,
          fmt::format("solver: max residual tolerance must be positive, got {}", max_residual_tol));
  require(std::isfinite(residual_tol) && residual_tol > 0.0,
          fmt::format("solver: residual tolerance must be positive, got {}", residual_tol));
  require(std::isfinite(max_step) && max_step > 0.0, fmt::format("solver: max_step must be positive, got {}", max_step));
  require(std::isfinite(max_rotation_step) && max_rotation_step > 0.0,
          fmt::format("solver: max_rotation_step must be positive, got {}", max_rotation_step));
  require(std::isfinite(regularisation) && regularisation >= 0.0 && regularisation < 1e-2,
          fmt::format("solver: regularisation must be in [0, 1e-2), got {}", regularisation));
  require(std::isfinite(linear_tolerance) && linear_tolerance > 0.0 && linear_tolerance < 1.0,
          fmt::format("solver: linear tolerance must be in (0, 1), got {}", linear_tolerance));
  require(std::isfinite(viscosity) && viscosity >= 0.0 && viscosity <= 1e3,
          fmt::format("solver: viscosity must be in [0, 1e3], got {}", viscosity));
  require(std::isfinite(regularisation_scale) && regularisation_scale >= 1e-6 && regularisation_scale <= 1e6,
          fmt::format("solver: regularisation scale must be in [1e-6, 1e6], got {}", regularisation_scale));
  require(std::isfinite(max_residual_factor) && max_residual_factor >= 1.0,
          fmt::format("solver: max residual factor must be >= 1, got {}", max_residual_factor));
  require(std::isfinite(drag_floor) && drag_floor > 0.0 && drag_floor <= 1.0 && std::isfinite(drag_ceiling) &&
              drag_ceiling >= 1.0,
          fmt::format("solver: drag bounds must satisfy 0 < floor <= 1 <= ceiling, got {} and {}", drag_floor, drag_ceiling));
  require(max_cuts >= 0 && max_cuts <= 20, fmt::format("solver: max_cuts must be in [0, 20], got {}", max_cuts));
  require(freeze_after >= 1 && freeze_after <= 100, fmt::format("solver: freeze_after must be in [1, 100], got {}", freeze_after));
  require(local_sweeps >= 0 && local_sweeps <= 100, fmt::format("solver: local_sweeps must be in [0, 100], got {}", local_sweeps));
  require(local_iterations >= 1 && local_iterations <= 100,
          fmt::format("solver: local_iterations must be in [1, 100], got {}", local_iterations));
  require(std::isfinite(local_threshold) && local_threshold >= 0.0,
          fmt::format("solver: local_threshold must be non-negative, got {}", local_threshold));
  require(backtracks >= 1 && backtracks <= 30, fmt::format("solver: backtracks must be in [1, 30], got {}", backtracks));
  require(threads >= 1 && threads <= 256, fmt::format("solver: threads must be in [1, 256], got {}", threads));
  require(chord_steps >= 0 && chord_steps <= 100, fmt::format("solver: chord_steps must be in [0, 100], got {}", chord_steps));
  require(factor_reuse >= 0 && factor_reuse <= 1000,
          fmt::format("solver: factor_reuse must be in [0, 1000], got {}", factor_reuse));
  require(std::isfinite(viscosity_strain) && viscosity_strain >= 0.0 && viscosity_strain <= 1.0,
          fmt::format("solver: viscosity_strain must be in [0, 1], got {}", viscosity_strain));
  require(std::isfinite(slide_stiffness_fraction) && slide_stiffness_fraction >= 0.0 && slide_stiffness_fraction <= 1.0,
          fmt::format("solver: slide_stiffness_fraction must be in [0, 1], got {}", slide_stiffness_fraction));
}

template <class P>
SolverOptionsT<P> SolverOptionsT<P>::compact() {
  static_assert(kPlastic, "the presets are the plastic-indentation law's");
  SolverOptionsT o;
  o.law.mu = std::numeric_limits<double>::infinity();
  o.law.reversible = true;     // the paper's compaction law (sections 2-3.3)
  o.residual_tol = 3e-3;       // S22 moves 0.1 % against 1e-3 (W = 80), 0.2 % at W = 640; 1e-2: 1.5 %
  o.viscosity = 0.01;
  o.viscosity_strain = 3.57e-4;  // = the per-increment drag of the 100-increment default run
  o.chord_steps = 3;           // each tangent and factor serve four iterations
  o.linear_tolerance = 0.3;    // GMRES: usually one iteration
  o.backtracks = 3;            // line search 1, 1/2, 1/4
  return o;
}

template <class P>
SolverOptionsT<P> SolverOptionsT<P>::yield_precompaction() {
  static_assert(kPlastic, "the presets are the plastic-indentation law's");
  return compact();
}

template <class P>
SolverOptionsT<P> SolverOptionsT<P>::yield_probe() {
  static_assert(kPlastic, "the presets are the plastic-indentation law's");
  SolverOptionsT o;
  o.law.mu = std::numeric_limits<double>::infinity();
  o.law.reversible = false;  // section 3.4: elastic un/reloading with 10^3 x the loading tangent
  return o;
}

template struct SolverOptionsT<contact::PlasticIndentationParams>;

}  // namespace netdem::qs
