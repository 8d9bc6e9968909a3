// The run loop of the staggered scheme (netdem/quasistatic/staggered_run.hpp; issue 26 item 3): the
// stopping rules and the summary's status, the observation points, the options checked once and
// named by their field, and a run split in two through a restart state equal to one run.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "netdem/field_error.hpp"
#include "netdem/quasistatic/staggered.hpp"
#include "netdem/quasistatic/staggered_run.hpp"
#include "staggered_test_util.hpp"

namespace {

namespace cs = netdem::contact::sinter;
namespace st = netdem::qs::staggered;
using netdem::test::cu;
using netdem::test::cubic;
using netdem::test::expect_same;
using netdem::test::jittered;
using netdem::test::kT;
using netdem::test::same_bits;

// Everything the observer sees, in order.
struct Log final : st::StaggeredObserver {
  std::vector<std::string> events;
  std::vector<st::StaggeredMeasures> rows;
  std::vector<std::pair<int, double>> snaps;
  std::vector<std::string> states;  // save() at each checkpoint
  std::vector<double> step_ends;
  void start(const st::Staggered& s, const st::StaggeredMeasures& m) override {
    events.push_back("start");
    rows.push_back(m);
    EXPECT_TRUE(same_bits(m.t, s.time()));
  }
  void step(const st::Staggered& s, long k, const st::StepRecord& r, const st::StaggeredMeasures& m) override {
    events.push_back("step " + std::to_string(k));
    rows.push_back(m);
    step_ends.push_back(s.time());
    EXPECT_TRUE(same_bits(r.t, s.time()));
    EXPECT_TRUE(same_bits(m.dt, r.dt));
  }
  void snapshot(const st::Staggered& s, int index) override {
    events.push_back("snapshot " + std::to_string(index));
    snaps.emplace_back(index, s.time());
  }
  void checkpoint(const st::Staggered& s, int index, long k) override {
    events.push_back("checkpoint " + std::to_string(index) + " at step " + std::to_string(k));
    states.push_back(s.save());
  }
};

template <class F>
std::string field_of(F&& f) {
  try {
    f();
  } catch (const netdem::FieldError& e) {
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
    return e.field() + ": " + e.what();
  }
  return "accepted";
}

// ----------------------------------------------------------------------------------------------

// A run to the end: the observer sees the start, every step, the snapshots at the first step end
// at or after each of the N equal times and the last; the summary adds up the step records and
// its measures are the sample's; snapshots do not change the steps.
TEST(StaggeredRun, ObservesEveryStepAndTheSnapshotTimes) {
  st::Staggered s = jittered(120e9);
  st::StaggeredRunOptions o;
  o.t_end = 200.0;
  o.snapshots = 4;
  Log log;
  const st::StaggeredRunSummary r = st::run(s, o, &log);
  EXPECT_EQ(r.status, st::StaggeredRunStatus::Ok);
  EXPECT_TRUE(r.completed());
  EXPECT_FALSE(r.failed());
  EXPECT_EQ(r.reason(), "every criterion met");
  EXPECT_EQ(r.t_stop, 200.0);
  EXPECT_EQ(r.accepted, s.steps());
  ASSERT_EQ(log.rows.size(), static_cast<std::size_t>(r.accepted) + 1);
  EXPECT_EQ(log.events.front(), "start");
  EXPECT_EQ(log.events[1], "snapshot 0") << "snapshot 0 is the start";
  EXPECT_EQ(log.events.back(), "snapshot 4") << "the last snapshot is the end";
  ASSERT_EQ(log.snaps.size(), 5u);
  EXPECT_EQ(r.snapshots, 5);
  for (int k = 1; k < 4; ++k) {
    const double at = log.snaps[static_cast<std::size_t>(k)].second;
    EXPECT_GE(at, 50.0 * k);
    // the first step end at or after 50 k: the step before ended before it
    std::size_t i = 0;
    while (log.step_ends[i] < at) ++i;
    ASSERT_GT(i, 0u);
    EXPECT_LT(log.step_ends[i - 1], 50.0 * k);
  }
  // the summary's counts and measures
  long contacts_new = 0;
  for (const auto& m : log.rows) EXPECT_TRUE(m.finite());
  EXPECT_EQ(r.new_contacts, static_cast<long>(s.contacts().size() - r.start.contacts));
  contacts_new = r.new_contacts;
  EXPECT_GT(contacts_new, 0) << "the jittered sample makes new contacts";
  EXPECT_EQ(r.linear_solves, r.accepted);  // one linear solve per step
  EXPECT_LE(r.max_shrink_error, st::kMaxShrinkError);
  const Eigen::Matrix3d F = s.homogeneous_strain();
  EXPECT_TRUE(same_bits(r.last.shrink_x, 0.0 - F(0, 0)));
  EXPECT_TRUE(same_bits(r.last.density, s.density()));
  EXPECT_GT(r.last.shrink_x, 1e-3) << "it sintered";
  EXPECT_GT(r.last.density, r.start.density);
  EXPECT_GT(r.last.neck_mean, r.start.neck_mean);
  // snapshots do not change the steps
  st::Staggered b = jittered(120e9);
  o.snapshots = 0;
  const st::StaggeredRunSummary rb = st::run(b, o);
  EXPECT_EQ(rb.snapshots, 1) << "only the last";
  expect_same(s, b);
}

// The step limit ends the run early: "incomplete", at a step boundary, the state valid.
TEST(StaggeredRun, StepLimitIsIncomplete) {
  st::Staggered s = jittered(120e9);
  st::StaggeredRunOptions o;
  o.t_end = 40.0;  // at least 4 steps of dt_max = 10 s; from dt_initial = 0.01 s many more
  o.max_steps = 5;
  Log log;
  const st::StaggeredRunSummary r = st::run(s, o, &log);
  EXPECT_EQ(r.status, st::StaggeredRunStatus::Incomplete);
  EXPECT_EQ(r.stop, st::StaggeredStop::StepLimit);
  EXPECT_FALSE(r.completed());
  EXPECT_FALSE(r.failed());
  EXPECT_EQ(r.accepted, 5);
  EXPECT_LT(r.t_stop, 40.0);
  ASSERT_EQ(r.reasons.size(), 1u);
  EXPECT_NE(r.reasons[0].find("step limit of 5 steps"), std::string::npos) << r.reasons[0];
  EXPECT_EQ(log.events.back(), "snapshot 5") << "the last snapshot, however the run ended";
  // continued, the run ends where one run ends
  st::Staggered c = st::Staggered::load(s.save(), "s");
  o.max_steps = 10'000'000;
  EXPECT_TRUE(st::run(c, o).completed());
  st::Staggered d = jittered(120e9);
  st::run(d, o);
  expect_same(c, d);
}

// A contact that reaches the freeze limit (the end of the two-particle model's range) stops
// sintering; the run goes on and is "ok". Every bond of the equal lattice freezes at once, and
// from then on the sample does not shrink: the bonds hold it.
TEST(StaggeredRun, FreezeLimitStopsTheShrinkageNotTheRun) {
  st::StaggeredOptions so;
  so.x_max_over_R = 0.05;
  st::Staggered s(cubic(3, 25e-6, 0.0, 1), cu(), cs::TemperatureProfile::constant(kT), so);
  const std::size_t n = s.contacts().size();
  ASSERT_EQ(n, 54u);
  st::StaggeredRunOptions o;
  o.t_end = 600.0;
  Log log;
  const st::StaggeredRunSummary r = st::run(s, o, &log);
  EXPECT_EQ(r.status, st::StaggeredRunStatus::Ok) << r.reason();
  EXPECT_TRUE(r.completed());
  EXPECT_EQ(r.frozen_contacts, n);
  EXPECT_EQ(r.newly_frozen, static_cast<long>(n));
  for (const auto& c : s.contacts()) {
    EXPECT_TRUE(c.frozen);
    EXPECT_EQ(c.pair.status, cs::PairStatus::NeckLimit);
  }
  // the row at which the last contact froze: the shrinkage is the same from there to the end
  std::size_t k = 0;
  while (k < log.rows.size() && log.rows[k].neck_mean < 0.05) ++k;
  ASSERT_LT(k + 2, log.rows.size()) << "the necks reached the limit before the end";
  EXPECT_GT(log.rows[k].shrink_x, 1e-4) << "it sintered up to the limit";
  for (std::size_t i = k + 1; i < log.rows.size(); ++i)
    EXPECT_NEAR(log.rows[i].shrink_x, log.rows[k].shrink_x, 1e-12) << "row " << i << " at t = " << log.rows[i].t;
  EXPECT_NEAR(r.last.neck_mean, log.rows[k].neck_mean, 1e-15);
}

// A step that cannot be made (every contact needs a sub-step below dt_min) ends the run
// "unstable" without throwing; the state is that of the last accepted step, a valid restart state.
TEST(StaggeredRun, FailedStepIsUnstableAndKeepsTheState) {
  st::StaggeredOptions so;
  so.eps_lim = 1e-300;  // no step is accurate enough
  so.dt_min = so.dt_initial;  // and none may be cut
  st::Staggered s(cubic(2, 25e-6, 0.0, 1), cu(), cs::TemperatureProfile::constant(kT), so);
  const std::string before = s.save();
  st::StaggeredRunOptions o;
  o.t_end = 10.0;
  o.snapshots = 1;
  Log log;
  const st::StaggeredRunSummary r = st::run(s, o, &log);
  EXPECT_EQ(r.status, st::StaggeredRunStatus::Unstable);
  EXPECT_EQ(r.stop, st::StaggeredStop::StepFailed);
  EXPECT_TRUE(r.failed());
  EXPECT_EQ(r.accepted, 0);
  EXPECT_NE(r.stop_message.find("step 1 from t = 0 s failed"), std::string::npos) << r.stop_message;
  EXPECT_NE(r.stop_message.find("dt_min"), std::string::npos) << r.stop_message;
  ASSERT_EQ(r.reasons.size(), 1u);
  EXPECT_EQ(r.reasons[0], "stopped: " + r.stop_message);
  EXPECT_EQ(s.time(), 0.0);
  EXPECT_EQ(s.steps(), 0);
  EXPECT_EQ(log.events, (std::vector<std::string>{"start", "snapshot 0", "snapshot 1"}));
  const st::Staggered again = st::Staggered::load(s.save(), "stopped");
  EXPECT_EQ(again.contacts().size(), st::Staggered::load(before, "before").contacts().size());
}

// A run split in two through the library's restart: the first half to t1 (its steps ending at t1)
// saved, loaded and run to the end, equals one run whose steps end at t1 (a checkpoint), bit for
// bit; the checkpoint's own state continues the same way.
TEST(StaggeredRun, TwoHalvesThroughARestartAreOneRun) {
  for (int strategy : {1, 2}) {
    st::Staggered one = jittered(120e9, strategy);
    st::StaggeredRunOptions o;
    o.t_end = 300.0;
    o.checkpoints = {80.0};
    Log log;
    const st::StaggeredRunSummary r1 = st::run(one, o, &log);
    ASSERT_TRUE(r1.completed());
    ASSERT_EQ(log.states.size(), 1u);
    EXPECT_EQ(r1.checkpoints, 1);

    st::Staggered first = jittered(120e9, strategy);
    st::StaggeredRunOptions half;
    half.t_end = 80.0;
    const st::StaggeredRunSummary ra = st::run(first, half);
    ASSERT_TRUE(ra.completed());
    EXPECT_EQ(ra.t_stop, 80.0);
    st::Staggered second = st::Staggered::load(first.save(), "half");
    st::StaggeredRunOptions rest;
    rest.t_end = 300.0;
    const st::StaggeredRunSummary rb = st::run(second, rest);
    ASSERT_TRUE(rb.completed());
    EXPECT_EQ(rb.t_start, 80.0);
    EXPECT_EQ(rb.steps_before, ra.accepted);
    EXPECT_EQ(ra.accepted + rb.accepted, r1.accepted) << "strategy " << strategy;
    EXPECT_EQ(ra.new_contacts + rb.new_contacts, r1.new_contacts);
    expect_same(one, second);
    EXPECT_TRUE(same_bits(rb.last.shrink_z, r1.last.shrink_z));
    EXPECT_TRUE(same_bits(rb.last.density, r1.last.density));

    st::Staggered from_checkpoint = st::Staggered::load(log.states[0], "checkpoint");
    EXPECT_EQ(from_checkpoint.time(), 80.0);
    st::run(from_checkpoint, rest);
    expect_same(one, from_checkpoint);
  }
}

// The options are checked once, by the library, and a bad one is named by its field (the command
// line reports it under its option); run() refuses before it steps.
TEST(StaggeredRun, BadOptionsAreNamedByTheirField) {
  st::StaggeredOptions so;
  auto scheme = [&](auto change) {
    st::StaggeredOptions b = so;
    change(b);
    return field_of([&] { b.validate(cu()); });
  };
  EXPECT_EQ(scheme([](auto&) {}), "accepted");
  EXPECT_EQ(scheme([](auto& b) { b.x0_over_R = 0.7; }).rfind("x0_over_R: the initial neck x0 / R_min must be in (0.0001, 0.5)", 0), 0u);
  EXPECT_EQ(scheme([](auto& b) { b.x0_over_R = 5e-5; }).rfind("x0_over_R: ", 0), 0u) << "below the vanished neck";
  EXPECT_EQ(scheme([](auto& b) { b.x0_over_R = 0.49; }), "accepted");
  EXPECT_EQ(scheme([](auto& b) { b.x_max_over_R = 0.005; }).rfind("x_max_over_R: ", 0), 0u);
  EXPECT_EQ(scheme([](auto& b) { b.strategy = 3; }).rfind("strategy: ", 0), 0u);
  EXPECT_EQ(scheme([](auto& b) { b.dt_initial = 1e-12; }).rfind("dt_initial: ", 0), 0u);
  EXPECT_EQ(scheme([](auto& b) { b.alpha = 1.0; }).rfind("alpha: ", 0), 0u);
  EXPECT_EQ(scheme([](auto& b) { b.nu = -0.2; }).rfind("nu: ", 0), 0u);
  EXPECT_EQ(scheme([](auto& b) { b.eps_lim = 1.0; }).rfind("eps_lim: ", 0), 0u);
  // what the options need of the material
  cs::SinterMaterial no_E = cu();
  no_E.youngs_modulus = 0.0;
  EXPECT_EQ(field_of([&] { so.validate(no_E); }).rfind("E: the bonds need a Young's modulus", 0), 0u);
  st::StaggeredOptions own_E = so;
  own_E.E = 1e11;
  EXPECT_EQ(field_of([&] { own_E.validate(no_E); }), "accepted");
  cs::SinterMaterial flat = cu();
  flat.gamma_gb = 1.98 * flat.gamma_s;  // dihedral limit sin(psi/2) ~ 0.14
  st::StaggeredOptions big_x0 = so;
  big_x0.x0_over_R = 0.2;
  EXPECT_EQ(field_of([&] { big_x0.validate(flat); }).rfind("x0_over_R: ", 0), 0u);
  EXPECT_THROW(st::Staggered(cubic(2, 25e-6, 0.0, 1), flat, cs::TemperatureProfile::constant(kT), big_x0), netdem::FieldError);

  // the run's options, against the state's time and largest step
  st::StaggeredRunOptions ro;
  ro.t_end = 100.0;
  EXPECT_EQ(field_of([&] { ro.validate(0.0, 10.0); }), "accepted");
  EXPECT_EQ(field_of([&] { ro.validate(100.0, 10.0); }).rfind("t_end: the end time must be after the start", 0), 0u);
  st::StaggeredRunOptions b = ro;
  b.max_steps = 5;
  EXPECT_EQ(field_of([&] { b.validate(0.0, 10.0); }).rfind("max_steps: the run of 100 s needs at least 10 steps", 0), 0u);
  b = ro;
  b.checkpoints = {50.0, 50.0};
  EXPECT_EQ(field_of([&] { b.validate(0.0, 10.0); }).rfind("checkpoints: the checkpoint times must increase", 0), 0u);
  b.checkpoints = {100.0};
  EXPECT_EQ(field_of([&] { b.validate(0.0, 10.0); }).rfind("checkpoints: 100 s is not between", 0), 0u);
  b = ro;
  b.snapshots = -1;
  EXPECT_EQ(field_of([&] { b.validate(0.0, 10.0); }).rfind("snapshots: ", 0), 0u);
  // each breakpoint of the temperature profile within the run ends a global step: 199 breakpoints
  // (every 0.5 s) within a run of 100 s take at least 200 steps, however large the step (10 s)
  std::vector<double> tb, Tb;
  for (int k = 0; k <= 200; ++k) {
    tb.push_back(0.5 * k);
    Tb.push_back(k % 2 ? kT : kT - 10.0);
  }
  const cs::TemperatureProfile saw(tb, Tb);
  b = ro;
  b.max_steps = 199;
  EXPECT_EQ(field_of([&] { b.validate(0.0, 10.0); }), "accepted") << "without the profile: 10 steps";
  EXPECT_EQ(field_of([&] { b.validate(0.0, 10.0, saw); }).rfind("max_steps: the run of 100 s needs at least 200 steps", 0), 0u);
  b.max_steps = 200;
  EXPECT_EQ(field_of([&] { b.validate(0.0, 10.0, saw); }), "accepted");
  EXPECT_EQ(field_of([&] { b.validate(0.0, 10.0, cs::TemperatureProfile::constant(kT)); }), "accepted");
  // run() checks against the state it is given, before any step
  st::Staggered s = jittered(120e9);
  st::run(s, ro);
  EXPECT_EQ(field_of([&] { st::run(s, ro); }).rfind("t_end: ", 0), 0u) << "the state is at t_end already";
  EXPECT_EQ(s.time(), 100.0);
}

}  // namespace
