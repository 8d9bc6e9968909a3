#pragma once
// The DEM's yield-surface protocol (issue 26: it lived in demsolve): the explicit solver with the
// plastic-indentation law driven through netsolve yield's phases (Redanz & Fleck 2001 section 3.4;
// docs/dynamic.md "demsolve yield"): (1) a precompaction in windows that match netsolve's
// increments; (2) the section 3.4 elastic branch switched on and the path reversed window by window
// with the secant prediction of the strain left to zero stress, each step a ramp and a hold at rest;
// (3) each probe on its own copy of the unloaded solver, one window per probe step of the shared
// schedule (sys::ProbeSchedule), its yield points by sys::evaluate_probe. 2D (disks).
//
// The library writes no files: the rows reach the caller through callbacks.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "netdem/dynamic/compaction.hpp"
#include "netdem/dynamic/solver.hpp"
#include "netdem/system/yield_curve.hpp"

namespace netdem::dem {

using YieldSample = CompactionSampleT<2>;
using YieldMeter = CompactionMeterT<2>;

/// A window: the solver advanced at its current strain rate until t_end; the mean of the samples
/// (about every `every` steps and at the end) and the steps taken.
struct Window {
  YieldSample mean;
  int samples = 0;
  std::int64_t steps = 0;
};

/// The hold after each strain increment of the unloading and the probes: the drag on until the
/// unbalanced contact force (RMS over the free particles) is below tol x f_ref (the mean contact
/// normal force at the loading point) and the kinetic energy below tol^2 x work_ref (the elastic
/// work at the loading point, so that an overdamped creep does not pass for rest), checked every 50
/// steps, or for at most t_max.
struct SettleOptions {
  double drag = 30.0, tol = 1e-3, f_ref = 0.0, work_ref = 0.0, t_max = 50.0;
};

/// Windows of a solver at its strain rate, with the strain accumulated across rate changes (the
/// Eq 16 measures use it).
class WindowRunner {
 public:
  WindowRunner(DynamicSolver& s, YieldMeter& meter) : s_(s), meter_(meter) {}
  /// Strain accumulated before the current rate was set.
  double E11 = 0.0, E22 = 0.0, t_rate = 0.0;
  void set_rate(double e11, double e22);
  double strain11() const { return E11 + s_.strain_rate_11() * (s_.time() - t_rate); }
  double strain22() const { return E22 + s_.strain_rate_22() * (s_.time() - t_rate); }
  YieldSample measure() { return meter_.measure(s_, {strain11(), strain22(), 0.0}); }
  /// Advances to t_end (at least one step) with about `target` samples.
  Window run(double t_end, int target = 10);
  /// Holds the strain (rate 0) with the drag on (SettleOptions), then the drag off and the rate
  /// back. Returns the state at the end (at rest: an equilibrium of the contact forces alone) and
  /// whether it settled; adds the steps to `steps`.
  YieldSample settle(const SettleOptions& o, bool& settled, std::int64_t& steps);

 private:
  DynamicSolver& s_;
  YieldMeter& meter_;
};

/// |Sigma| (Frobenius) of a sample's Eq 13 stress.
double stress_norm(const YieldSample& m);

/// The fabric-resolved affine bound on the explicit solver's contacts (docs/yield.md
/// "Fabric-resolved affine bound"): the stress if every load-bearing disk contact that the strain
/// rate (cos theta, sin theta) compresses keeps its normal force and every other one carries none.
sys::YieldPoint fabric_affine_point(const DynamicSolver& s, const std::vector<ContactInfo>& cs, double theta);

/// (2) The unloading along -direction (E'/|E'| at the probe rate gamma_p), netsolve's secant steps.
struct UnloadOptions {
  double tol = 1e-3;        ///< stop when |Sigma| < tol sigma_y (sigma_y = 1)
  int max_increments = 40;
  double first_step = 0.0;  ///< the first strain step (netsolve: 0.2 x the affine spring-back)
};
struct UnloadRow {
  int increment = 0;
  double strain = 0.0;
  YieldSample sample;
  double density = 0.0;
  std::int64_t steps = 0;
};
struct UnloadOutcome {
  YieldSample unloaded;  ///< the state the probes start from
  double strain = 0.0;   ///< the reversal strain
  int increments = 0, unsettled = 0;
  std::int64_t steps = 0;
  std::string message;  ///< why it stopped early; "unstable: ..." on an instability
  bool converged = false;
  double stress_norm = 0.0;
};
/// Unloads from `loaded` (the last precompaction window) with the rate already reversed by the
/// caller; on_row after each increment (increment 0: the loaded state).
UnloadOutcome unload(DynamicSolver& s, WindowRunner& win, const YieldSample& loaded, double gdot_p,
                     const SettleOptions& settle, const UnloadOptions& o, const std::function<void(const UnloadRow&)>& on_row);

/// (3) One probe on a copy of the unloaded solver.
struct DemProbeRun {
  sys::ProbeResult result;
  std::int64_t steps = 0;
  std::vector<double> kinetic;  ///< per sample: fluctuating kinetic energy / elastic work
};
DemProbeRun run_probe(const DynamicSolver& unloaded, const WindowRunner& ref, YieldMeter meter, int index,
                      const sys::ProbeSettings& ps, double gdot, const YieldSample& start, const SettleOptions& settle,
                      const std::function<void(double)>& on_increment = {});
/// The probes `indices` on `jobs` threads, each on its own copy of the unloaded solver (the result
/// does not depend on the thread count). A probe that throws gets status "error: ...". on_progress
/// gets (slot, fraction done) from any thread (serialised); on_done (index, run) likewise.
std::vector<DemProbeRun> run_probes(const DynamicSolver& unloaded, const WindowRunner& ref, const YieldMeter& meter,
                                    const std::vector<int>& indices, int jobs, const sys::ProbeSettings& ps,
                                    double gdot, const YieldSample& start, const SettleOptions& settle,
                                    const std::function<void(std::size_t, double)>& on_progress,
                                    const std::function<void(std::size_t, const DemProbeRun&)>& on_done);

}  // namespace netdem::dem
