// The run loop of the staggered scheme (staggered_run.hpp; docs/staggered.md "The run").
#include "netdem/quasistatic/staggered_run.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <new>

#include <fmt/format.h>

#include "netdem/field_error.hpp"

namespace netdem::qs::staggered {

namespace {

/// Mean and population standard deviation of the contacts' necks x / R_min0.
void neck_stats(const std::vector<Contact>& cs, double& mean, double& sd) {
  mean = sd = 0.0;
  if (cs.empty()) return;
  for (const auto& c : cs) mean += c.pair.x_over_R();
  mean /= static_cast<double>(cs.size());
  for (const auto& c : cs) sd += (c.pair.x_over_R() - mean) * (c.pair.x_over_R() - mean);
  sd = std::sqrt(sd / static_cast<double>(cs.size()));
}

// What the loop adds up over the accepted steps.
void add(StaggeredRunSummary& r, const StepRecord& rec) {
  ++r.accepted;
  r.rejected += rec.rejected;
  r.substeps += rec.substeps;
  r.new_contacts += rec.new_contacts;
  r.newly_frozen += rec.newly_frozen;
  r.gmres_iterations += rec.gmres_iterations;
  r.refactorisations += rec.refactorised ? 1 : 0;
  r.linear_solves += rec.solves;
  r.max_error = std::max(r.max_error, rec.max_error);
  if (!(rec.max_shrink_error <= r.max_shrink_error)) r.max_shrink_error = rec.max_shrink_error;  // also a NaN
}

// The findings of a run that has ended, in order: how the loop ended, then the shrinkage
// correction; the status is the worst of them.
void judge(StaggeredRunSummary& r, long max_steps) {
  auto add_finding = [&](StaggeredRunStatus s, std::string reason) {
    if (static_cast<int>(s) > static_cast<int>(r.status)) r.status = s;
    r.reasons.push_back(std::move(reason));
  };
  if (r.stop == StaggeredStop::StepLimit)
    add_finding(StaggeredRunStatus::Incomplete, fmt::format("the step limit of {} steps reached at t = {:.6g} s", max_steps, r.t_stop));
  else if (r.stop != StaggeredStop::EndTime)
    add_finding(StaggeredRunStatus::Unstable, "stopped: " + r.stop_message);
  // the shrinkage correction leaves y4 + y7 = |x_B - x_A| to rounding: more is not trusted
  if (!(r.max_shrink_error <= kMaxShrinkError))
    add_finding(StaggeredRunStatus::Unconverged,
                fmt::format("shrinkage correction error {:.3g} above {:g} (y4 + y7 against the centre distance)",
                            r.max_shrink_error, kMaxShrinkError));
}

}  // namespace

bool StaggeredMeasures::finite() const {
  for (double v : {t, T, dt, shrink_x, shrink_y, shrink_z, density, neck_mean, neck_std})
    if (!std::isfinite(v)) return false;
  return true;
}

StaggeredMeasures measure(const Staggered& s, const StepRecord* step) {
  StaggeredMeasures m;
  m.t = s.time();
  m.T = step ? step->T : s.temperature()(s.time());
  m.dt = step ? step->dt : 0.0;
  const Eigen::Matrix3d F = s.homogeneous_strain();
  m.shrink_x = 0.0 - F(0, 0);  // not -F: no "-0" in a file
  m.shrink_y = 0.0 - F(1, 1);
  m.shrink_z = 0.0 - F(2, 2);
  m.density = s.density();
  neck_stats(s.contacts(), m.neck_mean, m.neck_std);
  m.contacts = s.contacts().size();
  m.solves = step ? step->solves : 0;
  m.substeps = step ? step->substeps : 0;
  return m;
}

void StaggeredRunOptions::validate(double t_start, double dt_max) const {
  if (!(std::isfinite(t_end) && t_end > t_start))
    throw FieldError("t_end", fmt::format("the end time must be after the start ({:.17g} s), got {} s", t_start, t_end));
  if (max_steps < 1) throw FieldError("max_steps", fmt::format("the step limit must be at least 1, got {}", max_steps));
  if (snapshots < 0 || snapshots > 10000)
    throw FieldError("snapshots", fmt::format("the number of snapshots must be in [0, 10000], got {}", snapshots));
  for (std::size_t k = 0; k < checkpoints.size(); ++k) {
    const double c = checkpoints[k];
    if (!(c > t_start && c < t_end))
      throw FieldError("checkpoints", fmt::format("{} s is not between the start ({} s) and the end time ({} s)", c, t_start, t_end));
    if (k > 0 && !(c > checkpoints[k - 1]))
      throw FieldError("checkpoints", fmt::format("the checkpoint times must increase: {} s after {} s", c, checkpoints[k - 1]));
  }
  // the work estimate: the run takes at least (t_end - t_start) / dt_max steps
  const double span = t_end - t_start, min_steps = span / dt_max;
  if (!(min_steps <= static_cast<double>(max_steps)))
    throw FieldError("max_steps", fmt::format("the run of {:.6g} s needs at least {:.3g} steps of at most {:.6g} s (the largest "
                                              "global step), more than the step limit {}: shorten the run or raise the limit",
                                              span, min_steps, dt_max, max_steps));
}

void StaggeredRunOptions::validate(double t_start, double dt_max, const cs::TemperatureProfile& T) const {
  validate(t_start, dt_max);
  double steps = 0.0, prev = t_start;
  long breakpoints = 0;
  for (double b : T.times()) {
    if (!(b > prev && b < t_end)) continue;  // outside the run, or a jump's second row
    steps += std::ceil((b - prev) / dt_max);
    prev = b;
    ++breakpoints;
  }
  if (breakpoints == 0) return;
  steps += std::ceil((t_end - prev) / dt_max);
  if (!(steps <= static_cast<double>(max_steps)))
    throw FieldError("max_steps", fmt::format("the run of {:.6g} s needs at least {:.3g} steps of at most {:.6g} s (the "
                                              "largest global step; each of the {} breakpoints of the temperature profile "
                                              "within the run ends one), more than the step limit {}: shorten the run or "
                                              "the profile, or raise the limit",
                                              t_end - t_start, steps, dt_max, breakpoints, max_steps));
}

const char* to_string(StaggeredRunStatus s) {
  switch (s) {
    case StaggeredRunStatus::Ok: return "ok";
    case StaggeredRunStatus::Incomplete: return "incomplete";
    case StaggeredRunStatus::Unconverged: return "unconverged";
    case StaggeredRunStatus::Unstable: return "unstable";
  }
  return "unknown";
}

std::string StaggeredRunSummary::reason() const {
  if (reasons.empty()) return "every criterion met";
  std::string s;
  for (const auto& r : reasons) s += (s.empty() ? "" : "; ") + r;
  return s;
}

StaggeredRunSummary run(Staggered& s, const StaggeredRunOptions& o, StaggeredObserver* observer) {
  o.validate(s.time(), s.options().dt_max, s.temperature());
  StaggeredObserver none;
  StaggeredObserver& obs = observer ? *observer : none;
  const auto w0 = std::chrono::steady_clock::now();
  StaggeredRunSummary r;
  r.t_start = s.time();
  r.steps_before = s.steps();
  r.start = r.last = measure(s);
  obs.start(s, r.start);
  const int N = o.snapshots;
  auto snap_time = [&](int k) { return r.t_start + (o.t_end - r.t_start) * static_cast<double>(k) / static_cast<double>(N); };
  auto take_snapshots = [&]() {
    while (r.snapshots < N && s.time() >= snap_time(r.snapshots)) obs.snapshot(s, r.snapshots++);
  };
  take_snapshots();
  const std::vector<double>& ck = o.checkpoints;
  while (s.time() < o.t_end) {
    if (r.accepted >= o.max_steps) {
      r.stop = StaggeredStop::StepLimit;
      break;
    }
    StepRecord rec;
    try {
      // a checkpoint is a step boundary: the steps end on it, as those of a run that stops there
      rec = s.step(static_cast<std::size_t>(r.checkpoints) < ck.size() ? ck[static_cast<std::size_t>(r.checkpoints)] : o.t_end);
    } catch (const std::bad_alloc&) {
      throw;
    } catch (const std::exception& e) {
      r.stop = StaggeredStop::StepFailed;
      r.stop_message = fmt::format("step {} from t = {:.6g} s failed: {}", r.accepted + 1, s.time(), e.what());
      break;
    }
    add(r, rec);
    r.last = measure(s, &rec);
    obs.step(s, r.accepted, rec, r.last);
    if (!r.last.finite()) {
      r.stop = StaggeredStop::NonFinite;
      r.stop_message = fmt::format("non-finite values at step {} (t = {:.6g} s)", r.accepted, s.time());
      break;
    }
    take_snapshots();
    if (static_cast<std::size_t>(r.checkpoints) < ck.size() && s.time() >= ck[static_cast<std::size_t>(r.checkpoints)])
      obs.checkpoint(s, ++r.checkpoints, r.accepted);
  }
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
  r.t_stop = s.time();
  obs.snapshot(s, N);  // the last: the state at the end, however the run ended
  ++r.snapshots;
  for (const auto& c : s.contacts()) r.frozen_contacts += c.frozen ? 1 : 0;
  judge(r, o.max_steps);
  return r;
}

}  // namespace netdem::qs::staggered
