// Tests of the solver state between steps (src/dynamic/state.cpp): exact restart through the state
// file, the temperature schedule (LMM05 Eq 9, 11-12), parameter switches and bad state files.
#include <gtest/gtest.h>

#include "test_scale.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>

#include "netdem/dynamic/solver.hpp"
#include "netdem/dynamic/schedule.hpp"
#include "netdem/dynamic/state.hpp"

using namespace netdem::dem;
using netdem::contact::LudingParams;

namespace {

using netdem::test::small_scale;

// side x side disks on a jittered lattice of pitch 2.05 a0, radii a0 (1 +- 0.3), random velocities.
Particles dense(const LudingParams& p, int side, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Particles P;
  const double pitch = 2.05 * p.a0;
  for (int j = 0; j < side; ++j)
    for (int i = 0; i < side; ++i) {
      const double r = p.a0 * (1.0 + 0.3 * u(rng));
      // the draws in a fixed order (GCC's: a call's arguments are evaluated in an unspecified order)
      const double vy = 0.02 * u(rng), vx = 0.02 * u(rng);
      const double y = (j + 0.5) * pitch + 0.1 * (pitch - 2 * r) * u(rng), x = (i + 0.5) * pitch + 0.1 * (pitch - 2 * r) * u(rng);
      P.add(x, y, r, p, vx, vy, 0.0);
    }
  return P;
}

Box stress_box(int side, const LudingParams& p, double pressure) {
  Box b;
  b.x_max = b.y_max = side * 2.05 * p.a0;
  for (MovingWall* w : {&b.right, &b.top}) {
    w->mode = WallMode::Stress;
    w->pressure = pressure;
    w->damping = 20.0;
  }
  return b;
}

// Heating ramp 80 -> 140 C over `ramp` seconds, then 140 C; t0 short so that k1(T, t) moves.
double schedule(double t, double ramp) { return t < ramp ? 80.0 + 60.0 * t / ramp : 140.0; }

void advance(DynamicSolver& s, std::size_t steps, double ramp) {
  for (std::size_t k = 0; k < steps; ++k) {
    s.advance_temperature(schedule(s.time() + s.dt(), ramp), s.dt(), 1e-3);
    s.step();
  }
}

}  // namespace

// The full law with friction, cohesion, hysteresis, moving stress-controlled walls and a moving
// temperature: a run restarted from the state file ends bit for bit where the uninterrupted run
// ends (positions, velocities, spins, walls, k1(T, t), contact histories).
TEST(DynamicState, RestartThroughStateFileIsBitwiseExact) {
  LudingParams p;  // Table 1
  const int side = small_scale() ? 5 : 8;
  DynamicOptions o;
  o.model = ContactModel::Full;
  DynamicSolver a(dense(p, side, 3), p, stress_box(side, p, 100.0), o);
  const std::size_t n1 = small_scale() ? 800 : 3000, n2 = small_scale() ? 800 : 3000;
  const double ramp = 0.8 * static_cast<double>(n1 + n2) * a.dt();
  advance(a, n1, ramp);
  const std::string text = format_state(a.state());
  std::istringstream in(text);
  DynamicSolver b(parse_state(in, "mem"), o);
  EXPECT_EQ(format_state(b.state()), text) << "state -> file -> state is not the identity";
  advance(a, n2, ramp);
  advance(b, n2, ramp);
  const Particles &A = a.particles(), &B = b.particles();
  std::size_t sliding = 0, cohesive = 0;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
  a.touching_pairs(pairs);
  for (auto [i, j] : pairs) {
    const auto* h = a.history(i, j);
    ASSERT_NE(h, nullptr);
    sliding += h->sliding;
    cohesive += h->delta0 > 0.0;
  }
  std::printf("  %zu disks, %zu + %zu steps, T %.1f C, k1(T,t)/k1 = %.4f, %zu contacts (%zu sliding,"
              " %zu with delta0 > 0)\n",
              A.size(), n1, n2, a.thermal().T, a.thermal().k1_Tt / p.k1(), pairs.size(), sliding,
              cohesive);
  EXPECT_GT(sliding + cohesive, 0u) << "the test must exercise the history";
  for (std::size_t i = 0; i < A.size(); ++i) {
    ASSERT_EQ(A.pos[2 * i], B.pos[2 * i]) << i;
    ASSERT_EQ(A.pos[2 * i + 1], B.pos[2 * i + 1]) << i;
    ASSERT_EQ(A.vel[2 * i], B.vel[2 * i]) << i;
    ASSERT_EQ(A.spin[i], B.spin[i]) << i;
    ASSERT_EQ(A.r[i], B.r[i]) << i;
  }
  EXPECT_EQ(a.box().x_max, b.box().x_max);
  EXPECT_EQ(a.box().y_max, b.box().y_max);
  EXPECT_EQ(a.wall_velocity_top(), b.wall_velocity_top());
  EXPECT_EQ(a.thermal().k1_Tt, b.thermal().k1_Tt);
  EXPECT_EQ(format_state(a.state()), format_state(b.state()));
}

// Eq 9 with constant mass: radii follow a(T) = a_ref [1 - da_T (T_melt - T)] / [1 - da_T (T_melt
// - T_ref)], masses stay, the density scales with a^2; k1(T, t) at constant T follows Eq 11.
TEST(DynamicState, TemperatureScalesRadiiEq9AndRelaxesK1Eq11) {
  LudingParams p;
  Particles P;
  P.add(0.003, 0.003, 1.0e-3, p);
  P.add(0.006, 0.003, 0.7e-3, p);
  Box box;
  box.x_max = box.y_max = 0.01;
  DynamicOptions o;
  o.temperature = 80.0;
  DynamicSolver s(P, p, box, o);
  auto a_of = [&](double ref, double T) {
    return ref * (1.0 - p.da_T * (p.T_melt - T)) / (1.0 - p.da_T * (p.T_melt - p.T_radius_ref));
  };
  EXPECT_DOUBLE_EQ(s.particles().r[1], a_of(0.7e-3, 80.0));
  const double nu80 = s.density(), m0 = s.particles().mass[0];
  s.advance_temperature(140.0, s.dt(), 1e3);
  EXPECT_DOUBLE_EQ(s.particles().r[0], a_of(1.0e-3, 140.0));
  EXPECT_DOUBLE_EQ(s.particles().mass[0], m0);
  EXPECT_NEAR(s.density() / nu80, std::pow(a_of(1.0, 140.0) / a_of(1.0, 80.0), 2), 1e-14);
  // hold at 140 C with t0 = 0.1 s: Eq 11 from the value after the jump
  const double k1T = netdem::contact::luding_k1_of_T(p, 140.0), k1s = s.thermal().k1_Tt;
  ASSERT_GT(k1s, k1T);
  const double t0 = 0.1, dt = 1e-4;
  const int steps = 2000;
  for (int k = 0; k < steps; ++k) s.advance_temperature(140.0, dt, t0);
  const double eq11 = netdem::contact::luding_k1_eq11(k1T, k1s, steps * dt, t0);
  std::printf("  k1(T,t)/k1 after %.2f s at 140 C: %.6f (Eq 11: %.6f)\n", steps * dt,
              s.thermal().k1_Tt / p.k1(), eq11 / p.k1());
  EXPECT_NEAR(s.thermal().k1_Tt / eq11, 1.0, 1e-10);
  // cooling with k1(T) above k1(T, t): the contact freezes at once (section 3.4)
  s.advance_temperature(80.0, dt, 1e3);
  EXPECT_DOUBLE_EQ(s.thermal().k1_Tt, netdem::contact::luding_k1_of_T(p, 80.0));
  EXPECT_DOUBLE_EQ(s.particles().r[0], a_of(1.0e-3, 80.0));
  // a temperature needs the full law
  o.model = ContactModel::Linear;
  DynamicSolver lin(P, p, box, o);
  EXPECT_THROW(lin.advance_temperature(100.0, 1e-4, 1.0), std::invalid_argument);
}

// Friction switched on between steps (LMM05 section 4.1: mu on at t_heat) builds tangential
// springs; switched off again (mu = 0, mu_w = 0), the frictionless force loop leaves none.
TEST(DynamicState, FrictionSwitchBetweenSteps) {
  LudingParams p;
  p.mu = 0.0;
  const int side = small_scale() ? 5 : 7;
  DynamicOptions o;
  DynamicSolver s(dense(p, side, 4), p, stress_box(side, p, 100.0), o);
  s.run(1000);
  auto max_xi = [&] {
    std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
    s.touching_pairs(pairs);
    double m = 0.0;
    for (auto [i, j] : pairs) m = std::max(m, std::fabs(s.history(i, j)->xi));
    return m;
  };
  EXPECT_EQ(max_xi(), 0.0);
  LudingParams q = p;
  q.mu = 0.5;
  s.set_params(q);
  s.run(500);
  EXPECT_GT(max_xi(), 0.0);
  s.set_params(p);
  s.run(1);
  EXPECT_EQ(max_xi(), 0.0);
}

// A frictionless instantiation equals the full law with mu = 0 for any input (it only skips work).
TEST(DynamicState, FrictionlessFeatureEqualsMuZero) {
  using namespace netdem::contact;
  LudingParams p;
  p.mu = 0.0;
  constexpr LudingFeatures kNoFriction{true, true, true, false};
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int k = 0; k < 2000; ++k) {
    LudingHistory h;
    h.delta_max = 1e-4 * u(rng);
    h.k2_line = luding_k2_of(p, h.delta_max);
    h.delta0 = (1.0 - 0.5 * p.k1() / h.k2_line) * h.delta_max * u(rng);
    h.k1_seen = p.k1() * u(rng);
    LudingInput in;
    in.delta = 1.2e-4 * u(rng);
    in.delta_dot = 1e-2 * (u(rng) - 0.5);
    in.xi_dot = 1e-2 * (u(rng) - 0.5);
    in.dxi = 1e-7 * in.xi_dot;
    in.k1_Tt = p.k1() * u(rng);
    const LudingResult a = luding_evaluate<kLudingFull>(p, h, in);
    const LudingResult b = luding_evaluate<kNoFriction>(p, h, in);
    ASSERT_EQ(a.f_n, b.f_n);
    ASSERT_EQ(a.f_t, b.f_t);
    ASSERT_EQ(a.history.xi, b.history.xi);
    ASSERT_EQ(a.history.delta0, b.history.delta0);
    ASSERT_EQ(a.dfn_ddelta, b.dfn_ddelta);
  }
}

TEST(DynamicState, WallContactsCounted) {
  LudingParams p;
  Particles P;
  P.add(0.9e-3, 0.9e-3, 1e-3, p);    // corner: left and bottom
  P.add(5e-3, 9.5e-3, 1e-3, p);      // top
  P.add(5e-3, 5e-3, 1e-3, p);        // free
  Box box;
  box.x_max = box.y_max = 0.01;
  DynamicOptions o;
  o.model = ContactModel::Linear;
  DynamicSolver s(P, p, box, o);
  EXPECT_EQ(s.wall_contacts(), 3u);
}

TEST(DynamicState, BadStateFilesGiveOneLineErrors) {
  LudingParams p;
  DynamicOptions o;
  DynamicSolver s(dense(p, 3, 1), p, stress_box(3, p, 100.0), o);
  s.run(100);
  const std::string good = format_state(s.state());
  auto parse = [](const std::string& t) {
    std::istringstream in(t);
    return parse_state(in, "f");
  };
  EXPECT_NO_THROW(parse(good));
  auto expect_error = [&](const std::string& t, const std::string& needle) {
    try {
      parse(t);
      ADD_FAILURE() << "no error for: " << needle;
    } catch (const std::invalid_argument& e) {
      const std::string m = e.what();
      EXPECT_NE(m.find(needle), std::string::npos) << m;
      EXPECT_EQ(m.find('\n'), std::string::npos) << m;
    }
  };
  expect_error(good.substr(0, good.size() - 4), "f: /: not a JSON state archive (syntax error at byte");  // truncated
  expect_error("hello\n", "not a JSON state archive");
  expect_error("# demsolve state v2 (docs/dynamic.md)\ntime 0\n", "convert it with apps/scripts/convert_state.py");
  auto edit = [&](const std::string& from, const std::string& to) {
    std::string t = good;
    const auto at = t.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return t.replace(at, from.size(), to);
  };
  expect_error(edit("\"x\":[", "\"x\":[\"nan\","), "f: /particles/x/0: expected a number, found string \"nan\"");
  expect_error(edit("\"k2\":200000.0", "\"k2\":-200000.0"), "f: /luding: luding contact law: k2 must be positive");
  expect_error(edit("\"k2\":200000.0", "\"zz\":1.0,\"k2\":200000.0"), "f: /luding/zz: unknown member");
  expect_error(edit("\"k2\":200000.0", "\"k2\":\"inf\""), "f: /luding/k2: must be a finite number");
  expect_error(edit("\"kind\":\"dem\"", "\"kind\":\"network\""), "f: /kind: a network state, expected a dem state");
  expect_error(edit("\"version\":1", "\"version\":2"), "f: /version: 2 is outside [1, 1]");
  EXPECT_THROW(read_state_file("/nonexistent/state.txt"), std::invalid_argument);
  // parameters by name: every field round-trips
  LudingParams q;
  for (const auto& name : luding_param_names()) {
    set_luding_param(q, name, get_luding_param(p, name) * 1.0);
    EXPECT_EQ(get_luding_param(q, name), get_luding_param(p, name)) << name;
  }
}

// LMM05 Fig 8 / section 4.1.1: k1(T, t)/k1 at the end of sintering for t_s = 1e-4, 0.01, 0.02,
// 0.1, 1 is 0.95, 0.17, 0.10, 0.036, 0.0198 (the protocol with Table 1, Eq 10-12). Driven through
// the solver's temperature path with the paper's mean-pair time step; tolerance: half a unit of
// the paper's last printed digit.
TEST(DynamicState, ProtocolK1AtEndOfSinteringFig8) {
  LudingParams p;
  Particles P;
  P.add(0.003, 0.003, 1.0e-3, p);
  Box box;
  box.x_max = box.y_max = 0.01;
  DynamicOptions o;
  const double ts[5] = {1e-4, 0.01, 0.02, 0.1, 1.0};
  const double paper[5] = {0.95, 0.17, 0.10, 0.036, 0.0198};
  const double tol[5] = {0.005, 0.005, 0.005, 0.0005, 0.00005};
  const double dt = 6.1e-7;  // LMM05 section 3.1.2
  for (int c = 0; c < 5; ++c) {
    if (small_scale() && c == 4) continue;
    SinterProtocol prot;
    prot.sinter = ts[c];
    const auto ph = prot.phases();
    DynamicSolver s(P, p, box, o);
    const double t_end = phase_end(ph, 2);
    double t = 0.0;
    for (std::size_t k = 1; t < t_end - 0.5 * dt; ++k) {
      t = static_cast<double>(k) * dt;
      const ScheduleAt at = schedule_at(ph, t);
      s.advance_temperature(at.T, dt, at.t0);
    }
    const double k1 = s.thermal().k1_Tt / p.k1();
    std::printf("  t_s = %-6g: k1(T,t)/k1 = %.5f at t = %.4f (paper %.4g)\n", ts[c], k1, t,
                paper[c]);
    EXPECT_NEAR(k1, paper[c], tol[c]) << "t_s = " << ts[c];
  }
  // the schedule itself: T and t0 per phase
  const auto ph = SinterProtocol{}.phases();
  EXPECT_DOUBLE_EQ(schedule_at(ph, 0.1).T, 80.0);
  EXPECT_FALSE(schedule_at(ph, 0.1).friction);
  EXPECT_DOUBLE_EQ(schedule_at(ph, 0.25).T, 110.0);
  EXPECT_TRUE(schedule_at(ph, 0.25).friction);
  EXPECT_DOUBLE_EQ(schedule_at(ph, 0.8).t0, 0.1);
  EXPECT_DOUBLE_EQ(schedule_at(ph, 1.35).T, 110.0);
  EXPECT_DOUBLE_EQ(schedule_at(ph, 1.45).T, 80.0);
  EXPECT_DOUBLE_EQ(phase_end(ph, 4), 1.5);
  SinterProtocol bad;
  bad.sinter = -1.0;
  EXPECT_THROW(bad.phases(), std::invalid_argument);
}
