#pragma once
// The yield-surface driver (Redanz & Fleck 2001 section 3.4; docs/yield.md): the boundary-mode
// hand-over after the precompaction, one probe with its two yield points, and the probes of a
// surface from one unloaded state. Each probe runs on its own solver restored from the same
// NetworkState, so a probe's result does not depend on the order in which the probes run or on
// the process that runs it: `netsolve yield --jobs J` runs them in J worker processes that each
// restore the saved state, `--probe i/N` + `yield-merge` spreads them over a job array.
//
// Not on threads: two solvers factorising at the same time in one process give different
// results (measured 2026-12-01: the default surface differs from probe 1 on with 2 threads, and
// is identical once the CHOLMOD calls are serialised; Debian's serial OpenBLAS and CHOLMOD 3 are
// not safe for concurrent calls here). docs/yield.md "Parallel probes".
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "netdem/packing/packing.hpp"
#include "netdem/quasistatic/network_solver.hpp"
#include "netdem/quasistatic/yield_probe.hpp"

namespace netdem::qs {

using sys::ProbeSettings;
using sys::ProbeResult;
using sys::probe_options;
using sys::evaluate_probe;


/// What the hand-over from one boundary mode to another did.
struct HandoverReport {
  int contacts = 0;                 ///< load-bearing contacts before
  int contacts_unloaded = 0;        ///< of those, on the elastic branch (below Eq 2) before
  double S11_before = 0, S22_before = 0, S11_after = 0, S22_after = 0;  ///< / sigma_y
  int zero_strain_increments = 0;   ///< increments that evaluated the new solver's forces
  int unconverged = 0;
  int centres_outside_box = 0;      ///< centres the die squeezed out of the deformed box
  double box_area_growth = 0;       ///< relative growth of the box that holds them all
  packing::Packing compacted;       ///< the packing the new solver was built from
};

/// A new solver in `next.mode` built from the current positions of `solver` as a packing in the
/// deformed initial box `box0` (grown to hold every centre), frictionless laws only (the
/// tangential forces are not carried over), followed by zero-strain increments that evaluate its
/// contact forces (and, affine -> die, let the interior relax): at most 10, stopping at the first
/// converged one after the first.
std::unique_ptr<NetworkSolver> switch_boundary_mode(const NetworkSolver& solver, const packing::Box& box0,
                                                    std::uint64_t seed, const SolverOptions& next, HandoverReport& report);

/// Runs probe `index` from the solver's current state (the solver is advanced).
ProbeResult run_probe(NetworkSolver& solver, int index, const ProbeSettings& settings);

/// Runs the probes `indices` one after the other, each on a solver restored from `start` with
/// `options`; on_done is called after each. A probe that throws gives a result with status
/// "error: <message>".
std::vector<ProbeResult> run_probes(const NetworkState& start, const SolverOptions& options,
                                    const std::vector<int>& indices, const ProbeSettings& settings,
                                    const std::function<void(const ProbeResult&)>& on_done = {});

}  // namespace netdem::qs
