#pragma once
// The sampled reloading curves of yield-surface probes and their yield points, for every solver
// (issue 26: the network solver's probes and the explicit DEM's share them). Redanz & Fleck, Acta
// Mater. 49 (2001) 4325, section 3.4, Figs 9-10; docs/yield.md states the definitions.
//
// The curve functions (elastic_fit, yield_by_curvature, yield_by_offset) are pure functions of
// the sampled curve (x = probe strain magnitude |dE|, y = work-conjugate stress Sigma : E_hat),
// so they are unit-testable on synthetic curves.
#include <string>
#include <vector>

namespace netdem::sys {

/// A stress point (Sigma11, Sigma22) of the yield surface, tension positive; Sigma12 = 0.
struct YieldPoint {
  double S11 = 0.0, S22 = 0.0;
};

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

/// Linear interpolation of v at a fractional index.
double interpolate_at(const std::vector<double>& v, double position);


// ------------------------------------------------------------------------------------------------
// The settings of a surface's probes and the evaluation of one probe curve
struct ProbeSettings {
  int directions = 24;     ///< theta_k = 2 pi k / directions
  double offset = 1e-3;    ///< offset strain of the offset yield point
  double max_strain = 4e-3;
  double window = 0.1;     ///< curvature smoothing width
  double growth = 1.2;
  int fine = 20;
  double first_step = 1e-6;    ///< fine step (the command uses the unloading strain / 10)
  double loading_norm = 0;     ///< |Sigma| / sigma_y at the loading point (knee threshold 2 %)
  double sigma_y = 1;
};

/// One probe and its evaluation. S11/S22 (and *_offset) are NaN when the point was not found.
struct ProbeResult {
  int index = 0;
  double theta = 0;  ///< rad
  ProbeCurve curve;
  YieldEstimate curvature, offset;
  ElasticFit fit;
  double S11 = 0, S22 = 0, S11_offset = 0, S22_offset = 0;
  std::string status;  ///< "ok", or which point is missing and why, or "error: ..." if it threw
  double wall_s = 0;
};

/// The probe() options of the settings: the steps and the stop rule of a probe.
ProbeOptions probe_options(const ProbeSettings& settings);

/// The yield points (curvature, offset), the elastic fit and the status of a sampled probe curve:
/// run_probe's evaluation, also applied by demsolve yield to the explicit solver's curves.
ProbeResult evaluate_probe(ProbeCurve curve, int index, const ProbeSettings& settings);

}  // namespace netdem::sys
