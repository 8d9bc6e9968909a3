#pragma once
// The implicit solver's part of the run status (README.md "Exit status"; docs/quasistatic.md "Run
// status"): what makes a finished compaction untrustworthy (exit 3) and the stop rule of a growing
// residual. The status itself and the exit codes: apps/common/run_status.hpp.
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "output.hpp"
#include "run_status.hpp"

namespace netdem::app::netsolve {

using netdem::app::activity;
using netdem::app::guarded;
using netdem::app::RunStatus;

/// Convergence record of a sequence of increments (compact, the yield precompaction) and the
/// criteria of exit 3. The residual is the RMS Newton residual `newton_residual` (contact force
/// minus viscous drag, / mean contact force): the quantity the convergence test compares with
/// --tol. The `residual` column (max out-of-balance contact force) includes the force the drag
/// holds, which is legitimately far above --tol in converged increments (0.16 in the default run).
struct ConvergenceRecord {
  double tol = 0.0;
  int increments = 0, unconverged = 0, first_unconverged = 0, worst_increment = 0, last_increment = 0;
  double max_newton_residual = 0.0;
  bool last_converged = true;

  // thresholds (documented in docs/quasistatic.md "Run status")
  static constexpr double kMaxUnconvergedFraction = 0.05;  ///< legacy drag: more than 5 % of the increments
  /// The fraction of unconverged increments a trustworthy run may have: kMaxUnconvergedFraction
  /// for the legacy drag, 0 for the pseudo-transient iteration (every increment must be accepted).
  double max_unconverged_fraction = kMaxUnconvergedFraction;
  static constexpr double kResidualFactor = 10.0;          ///< any residual above 10 x --tol

  void add(int increment, bool converged, double newton_residual) {
    ++increments;
    last_increment = increment;
    last_converged = converged;
    if (!converged) {
      ++unconverged;
      if (first_unconverged == 0) first_unconverged = increment;
    }
    if (!(newton_residual <= max_newton_residual)) {  // also a NaN
      max_newton_residual = newton_residual;
      worst_increment = increment;
    }
  }
  /// Adds the failed criteria to `st` (status "unconverged"); `what` names the phase.
  void judge(RunStatus& st, const std::string& what) const {
    if (increments == 0) return;
    const std::string pre = what.empty() ? "" : what + ": ";
    if (unconverged > max_unconverged_fraction * increments)
      st.add("unconverged", fmt::format("{}{} of {} increments unconverged (more than {:g} %), the first at increment {}",
                                        pre, unconverged, increments, 100 * max_unconverged_fraction, first_unconverged));
    if (!(max_newton_residual <= kResidualFactor * tol))
      st.add("unconverged", fmt::format("{}Newton residual {:.3g} at increment {} is above 10 x --tol = {:.3g}", pre,
                                        max_newton_residual, worst_increment, kResidualFactor * tol));
    if (!last_converged) st.add("unconverged", fmt::format("{}the last increment ({}) is unconverged", pre, last_increment));
  }
};

/// Equilibrium check of a compaction: at equilibrium the Eq 13 stress (reactions of the prescribed
/// particles, lever arms from the box centre: origin-free) equals the Love-Weber contact stress;
/// the viscous drag of a "converged" increment can hold the network away from it. The run is
/// "unconverged" if the two differ by more than 2 % (StateMeasures::eq13_vs_contacts: Frobenius
/// norm of the symmetric difference relative to the contact stress) at the end; the reason names
/// the increment from which on they have differed by more than that. It also keeps the net applied
/// force (StateMeasures::net_force_ratio) for summary.json.
struct EquilibriumRecord {
  static constexpr double kMaxDeviation = 0.02;
  double last = 0.0;   ///< deviation of the last increment
  double max = 0.0;    ///< largest deviation over the increments
  double last_net_force = 0.0, max_net_force = 0.0;  ///< net applied force ratio: last, largest
  int first_bad = 0;   ///< first increment of the final run of increments above kMaxDeviation
  int last_increment = 0;

  void add(int increment, double deviation, double net_force) {
    last = deviation;
    last_net_force = net_force;
    if (!(deviation <= max)) max = deviation;  // also a NaN
    if (!(net_force <= max_net_force)) max_net_force = net_force;
    last_increment = increment;
    if (!(last <= kMaxDeviation)) {
      if (first_bad == 0) first_bad = increment;
    } else {
      first_bad = 0;
    }
  }
  void judge(RunStatus& st) const {
    if (last_increment == 0 || last <= kMaxDeviation) return;
    st.add("unconverged", fmt::format("the Eq 13 stress differs from the contact (Love-Weber) stress by {:.3g} % at the "
                                      "end (increment {}), above 2 % from increment {} on: the drag holds the network "
                                      "out of equilibrium",
                                      100 * last, last_increment, first_bad));
  }
};

/// The stop rule of a growing residual: the run stops after the increment at which the RMS Newton
/// residual has been above 10 x --tol and has grown in each of 5 consecutive increments, to more
/// than 10 times its value before them (a growth of at least 1.58 per increment). A frictionless
/// run that never converges climbs to a level and stays there (W = 40: x 6 over its steepest 5
/// increments, then flat) and does not stop; a diverging iteration grows geometrically.
struct ResidualGrowth {
  double tol = 0.0;
  static constexpr int kIncrements = 5;
  static constexpr double kGrowth = 10.0;
  std::vector<double> history;  ///< residual of each increment so far
  int first_bad = 0;            ///< the first increment of the growing run of the stop

  /// Records the residual of `increment`; true if the run must stop here.
  bool add(int increment, double r) {
    history.push_back(r);
    const int n = static_cast<int>(history.size());
    if (n < kIncrements + 1) return false;
    for (int k = n - kIncrements; k < n; ++k)
      if (!(history[k] > ResidualFactor() * tol && history[k] > history[k - 1])) return false;
    if (!(history[n - 1] > kGrowth * history[n - 1 - kIncrements])) return false;
    first_bad = increment - kIncrements + 1;
    return true;
  }
  static constexpr double ResidualFactor() { return ConvergenceRecord::kResidualFactor; }
  /// The reason of a stop after `increment` with residual `r` (one line, names the first bad increment).
  std::string message(int increment, double r) const {
    return fmt::format("the Newton residual grew in each of increments {}..{} to {:.3g} (above 10 x --tol = {:.3g} and more "
                       "than 10 times its value before): the iteration diverges from increment {} on",
                       first_bad, increment, r, ResidualFactor() * tol, first_bad);
  }
};

/// Thrown from a compaction's row callback to stop it (the growing-residual rule).
struct StopRun {
  std::string reason;
};

}  // namespace netdem::app::netsolve
