#pragma once
// Yield-surface probing of a precompacted network (Redanz & Fleck, Acta Mater. 49 (2001) 4325,
// section 3.4, Figs 9-10): elastic unloading by reversing the compaction path, reloading along a
// strain-rate direction theta in the (E11, E22) plane, and the two yield-point definitions of a
// reloading curve (maximum curvature, offset strain). docs/yield.md states the definitions.
//
// The curve functions (elastic_fit, yield_by_curvature, yield_by_offset) are pure functions of
// the sampled curve (x = probe strain magnitude |dE|, y = work-conjugate stress Sigma : E_hat),
// so they are unit-testable on synthetic curves.
#include <string>
#include <vector>

#include <Eigen/Core>

#include "netdem/quasistatic/analytic_yield.hpp"
#include "netdem/quasistatic/network_solver.hpp"

namespace netdem::qs {

// ------------------------------------------------------------------------------------------------
// Unloading
struct UnloadOptions {
  double tol = 1e-3;        ///< stop when |Sigma| (Frobenius) < tol * sigma_y
  int max_increments = 40;  ///< give up after this many increments (reported, not thrown)
  /// First trial step (strain magnitude). <= 0: 0.2 * 2|E|/unload_ratio, a fifth of the elastic
  /// spring-back of an affine network (every contact gives back 2 u_max / unload_ratio of overlap).
  double first_step = 0.0;
};

struct UnloadStep {
  double strain = 0;  ///< accumulated reversal strain magnitude
  StateMeasures state;
  IncrementReport report;
};

struct UnloadResult {
  bool converged = false;
  double strain = 0;          ///< total reversal strain magnitude |dE|
  double stress_norm = 0;     ///< final |Sigma| / sigma_y
  double loading_norm = 0;    ///< |Sigma| / sigma_y before unloading
  std::vector<UnloadStep> path;  ///< the state before unloading (strain 0) and after each increment
  std::string message;        ///< empty, or why it stopped early
};

/// Unloads by increments along -direction (the compaction strain-rate direction, any magnitude)
/// until |Sigma| < tol sigma_y. Each step is the secant prediction of the strain left to
/// |Sigma| = 0 from the last two states (Sigma is projected on the stress before unloading; the
/// last positive secant is kept when noise makes the projection rise); unloading is convex
/// (contacts open one after another, the stiffness only drops), so the prediction undershoots and
/// no step has to be taken back. Stops early (converged = false, message says why) when |Sigma|
/// rises again below 5% of the loading stress (noise floor), the projection crosses zero or the
/// reversal reaches 3 x the linear spring-back of the first step, so that a noisy network is never
/// unloaded into a loose one. Never throws for non-convergence;
/// a solver exception propagates.
UnloadResult unload(NetworkSolver& solver, const Eigen::Matrix2d& direction, double sigma_y, double unload_ratio,
                    const UnloadOptions& options = {});

// ------------------------------------------------------------------------------------------------
// Probing
struct ProbeOptions {
  double first_step = 5e-6;  ///< strain magnitude of the fine steps (the app uses unload strain / 10)
  int fine_increments = 20;  ///< equal fine steps first (the elastic range and the knee) ...
  double growth = 1.2;       ///< ... then each step this much larger ...
  double max_step = 2.5e-4;  ///< ... up to this
  double max_strain = 4e-3;  ///< stop at this |dE|
  int max_increments = 200;
  double offset = 1e-3;      ///< offset strain of the offset yield definition
  /// Stop once the curve has crossed the offset line and |dE| >= past_offset * (its |dE| there).
  double past_offset = 1.3;
  int fit_points = 4;        ///< fine steps used for the elastic slope (online stop rule)
};

struct ProbeSample {
  double strain = 0;  ///< |dE| from the unloaded state
  double stress = 0;  ///< Sigma : E_hat / sigma_y (work-conjugate; positive when the probe compresses a loaded network)
  double S11 = 0, S22 = 0, S12 = 0;  ///< / sigma_y, tension positive
  double density = 0, Z = 0;
  int newton = 0;
  bool converged = true;
  double residual = 0;
};

struct ProbeCurve {
  double theta = 0;  ///< rad, strain-rate direction (cos theta, sin theta) in (E11, E22)
  std::vector<ProbeSample> samples;  ///< samples[0] = the unloaded state
  std::string end;   ///< why the probe stopped: "past offset", "max strain", "max increments", "singular: ..."
  int unconverged = 0;
};

/// Reloads along (cos theta, sin theta) from the solver's current state. Catches solver
/// exceptions (singular / indefinite tangent, e.g. localisation on dilatant probes): the curve
/// then ends there with end = "singular: <message>".
ProbeCurve probe(NetworkSolver& solver, double theta, double sigma_y, const ProbeOptions& options);

// ------------------------------------------------------------------------------------------------
// Yield point of a sampled reloading curve y(x), x = |dE| increasing from 0.
struct ElasticFit {
  bool ok = false;
  double y0 = 0, slope = 0;  ///< least squares y = y0 + slope x over the steepest window
};
/// Elastic line: the steepest least-squares line over fit_points + 1 consecutive samples (the
/// first window on a curve that starts linear; skips a toe).
ElasticFit elastic_fit(const std::vector<double>& x, const std::vector<double>& y, int fit_points = 4);

/// The step schedule and stop rule of a probe, shared by probe() and the explicit solver's probes
/// (demsolve yield): `fine_increments` equal steps of first_step, then each step `growth` times
/// larger up to max_step; the probe ends at max_strain, after max_increments, or once the curve has
/// crossed the offset line of its elastic fit (online, over the samples so far) and the strain is
/// past_offset times the strain there.
class ProbeSchedule {
 public:
  /// x0, y0: the sample of the unloaded state (strain 0).
  ProbeSchedule(const ProbeOptions& options, double x0, double y0);
  /// The strain of the next increment, or 0 when the probe ends before it (end() says why).
  double next();
  /// Records the sample (x, y) taken after an increment of strain h (h as given by next(); x is
  /// the sample's strain, which a windowed sample may place before the increment's end). false:
  /// the probe ends here (end() says why).
  bool record(double h, double x, double y);
  double strain() const { return strain_; }  ///< sum of the increments
  const std::string& end() const { return end_; }

 private:
  ProbeOptions o_;
  int k_ = 0;
  double strain_ = 0.0, step_ = 0.0, x_cross_ = -1.0;
  ElasticFit fit_;
  std::vector<double> xs_, ys_;
  std::string end_;
};

struct YieldOptions {
  int fit_points = 4;     ///< samples after the first used for the elastic line
  double offset = 1e-3;   ///< offset strain
  /// Gaussian smoothing width of the turning angle, in normalised arc length (see docs/yield.md).
  double window = 0.1;
  /// A curve whose stress never rises by min_rise (same units as y) above y0 has no yield point,
  /// and a curvature knee below that rise does not count.
  double min_rise = 0.0;
};

struct YieldEstimate {
  bool found = false;
  double position = 0;   ///< fractional sample index (interpolate other columns with it)
  double strain = 0, stress = 0;
  double curvature = 0;  ///< smoothed curvature there (normalised units; negative = knee)
  std::string reason;    ///< when not found
};

/// Knee = the most negative smoothed curvature of the curve scaled so that the elastic line has
/// slope 1 and the largest stress rise is 1, before the peak stress (docs/yield.md).
YieldEstimate yield_by_curvature(const std::vector<double>& x, const std::vector<double>& y, const YieldOptions& options = {});
/// First crossing of the curve with the elastic line shifted by the offset strain.
YieldEstimate yield_by_offset(const std::vector<double>& x, const std::vector<double>& y, const YieldOptions& options = {});

// ------------------------------------------------------------------------------------------------
// Fabric-resolved affine bound (our addition; docs/yield.md "Fabric-resolved affine bound")

/// The stress (/ sigma_y, tension positive) of the solver's current state if every load-bearing
/// contact that the strain rate (cos theta, sin theta) in (E11dot, E22dot) compresses
/// (n . Edot . n < 0) keeps its normal force and every other contact carries none:
/// Sigma = -(1/A) sum f_N L n n over those contacts (A = current box area, L = centre distance).
/// This is Appendix A's rigid-plastic affine surface evaluated on the packing's own contacts,
/// branch vectors and forces instead of an isotropic distribution of equal disks with a common
/// force; called at the loading point it gives the affine-affine surface that the probes should
/// reach. Tangential forces are left out (frictionless surface).
YieldPoint fabric_affine_point(const NetworkSolver& solver, double theta, double sigma_y);

/// Linear interpolation of v at a fractional index.
double interpolate_at(const std::vector<double>& v, double position);

}  // namespace netdem::qs
