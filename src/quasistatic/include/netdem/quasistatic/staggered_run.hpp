#pragma once
// The run loop of the staggered scheme (netdem/quasistatic/staggered.hpp; docs/staggered.md "The
// run"): a Staggered, new or loaded from a restart state, is stepped to an end time. Ceres style:
// StaggeredRunOptions in, StaggeredRunSummary out.
//   * Stopping rules: the end time (completed); the step limit (incomplete); a step that fails or
//     measures that are not finite (unstable: the state is that of the last accepted step, a
//     valid restart state). A run whose shrinkage correction leaves y4 + y7 off the centre
//     distance by more than kMaxShrinkError is "unconverged".
//   * Observation points: the measures at the start and after every accepted step; snapshots at
//     the first step end at or after each of N equally spaced times, and at the end; checkpoints,
//     times at which the steps end (as those of a run that stops there: a run continued from a
//     checkpoint's state is bit-identical to the uninterrupted one).
// A StaggeredObserver sees them all; the library writes no file and knows no command line
// (netsolve sinter writes its history, snapshots and states from the observer).
#include <cstddef>
#include <string>
#include <vector>

#include "netdem/quasistatic/staggered.hpp"

namespace netdem::qs::staggered {

/// What the run measures of the sample at one time (a row of netsolve sinter's history.csv).
struct StaggeredMeasures {
  double t = 0.0;   ///< time [s]
  double T = 0.0;   ///< temperature [K]
  double dt = 0.0;  ///< the step that ended here [s] (0 at the start)
  double shrink_x = 0.0, shrink_y = 0.0, shrink_z = 0.0;  ///< -F_ii of homogeneous_strain()
  double density = 0.0;                                     ///< density()
  double neck_mean = 0.0, neck_std = 0.0;  ///< x / R_min0 over the contacts: mean, population std
  std::size_t contacts = 0;
  int solves = 0;      ///< StepRecord::solves (0 at the start)
  long substeps = 0;   ///< StepRecord::substeps (0 at the start)
  bool finite() const;
};

/// The measures of s now; `step` is the step that just ended (nullptr: the start, no step).
StaggeredMeasures measure(const Staggered& s, const StepRecord* step = nullptr);

struct StaggeredRunOptions {
  double t_end = 5000.0;        ///< end time [s], after the state's time
  long max_steps = 10'000'000;  ///< step limit of this run (reached: "incomplete")
  /// Times [s] at which the steps end and StaggeredObserver::checkpoint is called: increasing,
  /// strictly between the state's time and t_end.
  std::vector<double> checkpoints;
  /// Snapshots K = 0 .. N-1 at the first step end at or after t_start + K (t_end - t_start) / N,
  /// and snapshot N at the end (N in [0, 10000]). Snapshots do not change the steps.
  int snapshots = 5;
  /// Throws netdem::FieldError (field: t_end, max_steps, checkpoints or snapshots) for a bad value
  /// or for a run that needs more than max_steps steps of at most dt_max (it would end
  /// "incomplete" after hours; refused at the door instead). t_start: the state's time.
  void validate(double t_start, double dt_max) const;
  /// validate(t_start, dt_max), and the estimate with the breakpoints of the temperature profile T
  /// within the run: each ends a global step, so the run takes at least the sum over the pieces
  /// between them of ceil(piece / dt_max) steps (FieldError max_steps when that exceeds max_steps).
  void validate(double t_start, double dt_max, const cs::TemperatureProfile& T) const;
};

enum class StaggeredRunStatus { Ok, Incomplete, Unconverged, Unstable };  ///< in this order of rank
/// "ok", "incomplete", "unconverged", "unstable" (the words of summary.json's status).
const char* to_string(StaggeredRunStatus s);

/// Why the loop ended.
enum class StaggeredStop { EndTime, StepLimit, StepFailed, NonFinite };

/// The largest relative error of the shrinkage correction (|y4 + y7 - d| / d) that a run trusts.
inline constexpr double kMaxShrinkError = 1e-9;

struct StaggeredRunSummary {
  StaggeredRunStatus status = StaggeredRunStatus::Ok;  ///< the worst of the findings below
  std::vector<std::string> reasons;  ///< one line per finding, in order (empty: every criterion met)
  StaggeredStop stop = StaggeredStop::EndTime;
  std::string stop_message;  ///< StepFailed, NonFinite: what happened, at which step and time
  bool completed() const { return stop == StaggeredStop::EndTime; }
  /// A step failed or its measures were not finite ("unstable"; the state is a valid restart state).
  bool failed() const { return stop == StaggeredStop::StepFailed || stop == StaggeredStop::NonFinite; }
  std::string reason() const;  ///< the reasons joined by "; ", or "every criterion met"

  double t_start = 0.0, t_stop = 0.0;  ///< [s]
  long steps_before = 0;  ///< the state's steps at the start (of earlier runs)
  long accepted = 0;      ///< steps of this run
  long rejected = 0, substeps = 0, linear_solves = 0, gmres_iterations = 0, refactorisations = 0;
  long new_contacts = 0, newly_frozen = 0;
  double max_error = 0.0;         ///< largest StepRecord::max_error (error / eps_lim)
  double max_shrink_error = 0.0;  ///< largest StepRecord::max_shrink_error (NaN if one was NaN)
  StaggeredMeasures start, last;  ///< the measures at the start and of the last step (or the start)
  std::size_t frozen_contacts = 0;  ///< at the end
  int snapshots = 0;    ///< snapshots taken, the last (index N) included
  int checkpoints = 0;  ///< checkpoints reached
  double wall_s = 0.0;  ///< the loop's wall time, observer calls included [s]
};

/// Sees the observation points of a run (every method does nothing by default). An exception
/// thrown by a method ends the run and propagates (the state is that of the last step).
class StaggeredObserver {
 public:
  virtual ~StaggeredObserver() = default;
  /// Before the first step (at the state's time).
  virtual void start(const Staggered& /*s*/, const StaggeredMeasures& /*m*/) {}
  /// After accepted step k (1, 2, ... of this run), before its finiteness is judged.
  virtual void step(const Staggered& /*s*/, long /*k*/, const StepRecord& /*r*/, const StaggeredMeasures& /*m*/) {}
  /// Snapshot `index` (0 .. N) at s.time().
  virtual void snapshot(const Staggered& /*s*/, int /*index*/) {}
  /// Checkpoint `index` (1, 2, ...) reached at step k: s.time() is the checkpoint's time.
  virtual void checkpoint(const Staggered& /*s*/, int /*index*/, long /*k*/) {}
};

/// Steps s to o.t_end (o.validate(s.time(), s.options().dt_max, s.temperature()) first:
/// FieldError), calling the
/// observer (may be nullptr) at the observation points. Returns how it ended; a step that throws
/// (except std::bad_alloc) ends the run "unstable" and is not rethrown.
StaggeredRunSummary run(Staggered& s, const StaggeredRunOptions& o, StaggeredObserver* observer = nullptr);

}  // namespace netdem::qs::staggered
