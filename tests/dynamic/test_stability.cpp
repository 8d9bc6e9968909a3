// Numerical stability stress tests of the explicit solver (issue 13 item 7, DEM side): time steps
// up to and beyond the stability limit, k2/k1 up to 10^3, strong cohesion, very high pressure.
// Each case either gives the right answer, checked against an invariant, or stops with the
// InstabilityError of the run-time checks (docs/dynamic.md "Instability detection"); none ends
// with a non-finite state and no error.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <utility>

#include "netdem/dynamic/solver.hpp"

using namespace netdem::dem;
using netdem::contact::LudingParams;

namespace {

// n x n disks on a jittered lattice of pitch 2.02 a0 (radii a0 (1 +- 0.2)), random velocities v.
Particles lattice(const LudingParams& p, int n, double v, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Particles P;
  const double pitch = 2.02 * 1.2 * p.a0;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
    {  // the draws in a fixed order (GCC's: a call's arguments are evaluated in an unspecified order)
      const double vy = v * u(rng), vx = v * u(rng), r = p.a0 * (1.0 + 0.2 * u(rng));
      P.add((i + 0.5) * pitch, (j + 0.5) * pitch, r, p, vx, vy);
    }
  return P;
}

Box stress_box(const LudingParams& p, int n, double pressure) {
  Box b;
  b.x_min = b.y_min = 0.0;
  b.x_max = b.y_max = n * 2.02 * 1.2 * p.a0;
  for (MovingWall* w : {&b.right, &b.top}) {
    w->mode = WallMode::Stress;
    w->pressure = pressure;
    w->mass = p.m_wall;
    w->damping = p.gamma_wall;
  }
  return b;
}

bool finite_state(const DynamicSolver& s) {
  const Particles& P = s.particles();
  for (std::size_t i = 0; i < P.size(); ++i)
    if (!(std::isfinite(P.pos[2 * i]) && std::isfinite(P.pos[2 * i + 1]) && std::isfinite(P.vel[2 * i]) && std::isfinite(P.vel[2 * i + 1])))
      return false;
  return std::isfinite(s.box().x_max) && std::isfinite(s.box().y_max);
}

/// Runs `steps`; "ok" (then the state is finite and passes check_health) or the quantity breached.
std::string run(DynamicSolver& s, int steps) {
  try {
    for (int k = 0; k < steps; ++k) s.step();
    s.check_health();
  } catch (const InstabilityError& e) {
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("likely cause"), std::string::npos) << e.what();
    EXPECT_NE(s.last_good(), nullptr);
    return e.quantity();
  }
  EXPECT_TRUE(finite_state(s));
  return "ok";
}

/// 6 x 6 disks (velocities v) under stress walls at `pressure`, 20000 steps: "ok" with
/// 0 < nu <= 1.25, or the breached quantity. `what` = `value` names the case in the log.
std::string pressed(const LudingParams& p, double v, unsigned seed, double pressure, const char* what, double value) {
  DynamicOptions o;
  o.check_every = 100;
  DynamicSolver s(lattice(p, 6, v, seed), p, stress_box(p, 6, pressure), o);
  const std::string got = run(s, 20000);
  std::printf("%s = %g: %s, nu = %.4g\n", what, value, got.c_str(), s.density());
  if (got == "ok") {
    EXPECT_GT(s.density(), 0.0) << what << " = " << value;
    EXPECT_LE(s.density(), HealthLimits::kMaxDensity) << what << " = " << value;
  }
  return got;
}

LudingParams elastic() {
  LudingParams p;
  p.k1_ratio = 1.0;
  p.kc_ratio = 0.0;
  p.gamma_n = p.gamma_t = 0.0;
  p.mu = p.mu_wall = 0.0;
  return p;
}

}  // namespace

// Undamped linear elastic gas in free space: below the limit the energy is conserved; far beyond
// it (dt >= t_c, omega dt >= pi > 2) the run is stopped; in between either holds.
TEST(Stability, TimeStepUpToAndBeyondTheLimit) {
  const LudingParams p = elastic();
  for (double spc : {50.0, 10.0, 3.0, 1.5, 1.0, 0.5, 0.2}) {
    Box free;
    free.enabled = false;
    DynamicOptions o;
    o.model = ContactModel::Linear;
    o.steps_per_contact = spc;
    o.min_steps_per_contact = 0.0;  // past the door, on purpose
    o.check_every = 50;
    DynamicSolver s(lattice(p, 8, 0.5, 3), p, free, o);
    const double e0 = s.energies().total();
    const std::string got = run(s, 4000);
    std::printf("steps per contact %g: %s, E/E0 = %.6g\n", spc, got.c_str(), s.energies().total() / e0);
    if (spc >= 10.0) {
      ASSERT_EQ(got, "ok") << spc;
      EXPECT_NEAR(s.energies().total() / e0, 1.0, spc >= 50.0 ? 2e-3 : 2e-2) << spc;
    } else if (spc <= 1.0) {
      EXPECT_NE(got, "ok") << "steps per contact " << spc << ": an unstable run went undetected";
    } else if (got == "ok") {
      EXPECT_NEAR(s.energies().total() / e0, 1.0, 0.2) << spc;
    }
  }
}

// Hysteretic loading with k2/k1 = 2 ... 1000 under wall pressure: nu stays below 1.25 and the
// state finite, or the run is stopped.
TEST(Stability, StiffnessRatioUpTo1000) {
  for (double k1r : {0.5, 0.1, 0.01, 0.001}) {
    LudingParams p;
    p.k1_ratio = k1r;
    const std::string got = pressed(p, 0.01, 5, 100.0, "k2/k1", 1.0 / k1r);
    if (k1r >= 0.1) {
      EXPECT_EQ(got, "ok") << k1r;
    }
  }
}

// Cohesion k_c/k2 from Table 1 up to 100: attractive contacts pull the sample together; finite
// and nu <= 1.25, or stopped.
TEST(Stability, StrongCohesion) {
  for (double kc : {0.5, 5.0, 100.0}) {
    LudingParams p;
    p.kc_ratio = kc;
    const std::string got = pressed(p, 0.05, 7, 100.0, "k_c/k2", kc);
    if (kc <= 0.5) {
      EXPECT_EQ(got, "ok");
    }
  }
}

// Wall pressure up to 2p/k2 = 10 (the door of demsolve refuses above 0.1; the library runs it):
// the small ratio runs, the large ones are stopped before anything is non-finite.
TEST(Stability, VeryHighPressure) {
  for (double ratio : {1e-3, 0.1, 1.0, 10.0}) {
    LudingParams p;
    const std::string got = pressed(p, 0.0, 9, 0.5 * ratio * p.k2, "2p/k2", ratio);
    if (ratio <= 1e-3) {
      EXPECT_EQ(got, "ok");
    }
    if (ratio >= 1.0) {
      EXPECT_NE(got, "ok") << "2p/k2 = " << ratio;
    }
  }
}

// The checks only read: a run with them is bit-identical to one without (check_every = 0), and
// last_good() is a state that passed a check, at most 1000 + 500 steps old.
TEST(Stability, ChecksDoNotChangeTheRun) {
  LudingParams p;
  DynamicOptions on, off;
  on.check_every = 500;
  off.check_every = 0;
  DynamicSolver a(lattice(p, 6, 0.01, 11), p, stress_box(p, 6, 100.0), on);
  DynamicSolver b(lattice(p, 6, 0.01, 11), p, stress_box(p, 6, 100.0), off);
  for (int k = 0; k < 3700; ++k) {
    a.step();
    b.step();
  }
  const auto& A = a.particles();
  const auto& B = b.particles();
  for (std::size_t i = 0; i < A.size(); ++i) {
    ASSERT_EQ(A.pos[2 * i], B.pos[2 * i]);
    ASSERT_EQ(A.vel[2 * i + 1], B.vel[2 * i + 1]);
  }
  EXPECT_EQ(a.box().x_max, b.box().x_max);
  ASSERT_NE(a.last_good(), nullptr);
  EXPECT_EQ(b.last_good(), nullptr);
  const double age = (a.time() - a.last_good()->time) / a.dt();
  EXPECT_GT(age, 0.0);
  EXPECT_LE(age, 1500.5);
}
