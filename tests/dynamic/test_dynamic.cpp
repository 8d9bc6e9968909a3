// Tests of the explicit DEM solver (src/dynamic): LMM05 Eq 1, 2, 5, 6 (see docs/dynamic.md).
#include <gtest/gtest.h>

#include "test_scale.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "netdem/contact/luding_law.hpp"
#include "netdem/dynamic/solver.hpp"

using namespace netdem::dem;
using netdem::contact::LudingParams;

namespace {

using netdem::test::small_scale;

LudingParams elastic_params() {  // k1 = k2, k_c = 0, no damping, frictionless
  LudingParams p;
  p.k1_ratio = 1.0;
  p.kc_ratio = 0.0;
  p.gamma_n = 0.0;
  p.gamma_t = 0.0;
  p.mu = 0.0;
  p.mu_wall = 0.0;
  return p;
}

// Disks on a jittered square lattice (nx x ny sites of pitch `pitch`), radii a0 (1 +- w),
// random velocities of scale v.
Particles lattice(const LudingParams& p, int nx, int ny, double pitch, double w, double v,
                  unsigned seed, double x0 = 0.0, double y0 = 0.0) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Particles P;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const double r = p.a0 * (1.0 + w * u(rng));
      const double slack = 0.5 * pitch - r;
      // the draws in a fixed order: the order of a call's arguments is unspecified (GCC took them
      // last to first, clang first to last); this is GCC's, which the tests' numbers were set with
      const double vy = v * u(rng), vx = v * u(rng);
      const double y = y0 + (j + 0.5) * pitch + 0.5 * slack * u(rng), x = x0 + (i + 0.5) * pitch + 0.5 * slack * u(rng);
      P.add(x, y, r, p, vx, vy, 0.0);
    }
  return P;
}

struct Collision {
  double e = 0.0;   // restitution
  double tc = 0.0;  // contact duration
};

// Head-on collision of two equal disks in free space, relative speed v0.
Collision two_disk(const LudingParams& p, ContactModel model, double steps_per_contact) {
  Particles P;
  const double a = p.a0, v0 = 0.1;
  P.add(0.0, 0.0, a, p, 0.5 * v0, 0.0);
  P.add(2.0 * a + 1e-6, 0.0, a, p, -0.5 * v0, 0.0);
  Box box;
  box.enabled = false;
  DynamicOptions o;
  o.model = model;
  o.steps_per_contact = steps_per_contact;
  DynamicSolver s(std::move(P), p, box, o);
  auto overlap = [&] {
    const auto& q = s.particles();
    return 2.0 * a - (q.pos[2] - q.pos[0]);
  };
  double d_prev = overlap(), t_in = -1.0, t_out = -1.0;
  for (int k = 0; k < 1000000 && t_out < 0.0; ++k) {
    s.step();
    const double d = overlap();
    const double t_cross = s.time() - s.dt() * d / (d - d_prev);  // linear interpolation of 0
    if (d_prev <= 0.0 && d > 0.0) t_in = t_cross;
    if (t_in >= 0.0 && d_prev > 0.0 && d <= 0.0) t_out = t_cross;
    d_prev = d;
  }
  EXPECT_GT(t_out, 0.0);
  s.run(5);  // free flight
  const auto& q = s.particles();
  return {(q.vel[2] - q.vel[0]) / v0, t_out - t_in};
}

}  // namespace

namespace {
// The law of a Luding time step (the bound is k2 for every feature set).
netdem::contact::LudingLaw<netdem::contact::kLudingFull, 2> luding(const LudingParams& p) { return {p, 0.0}; }
}  // namespace

// ---- time step rule (Eq 6)
// ------------------------------------------------------------------------
TEST(Dynamic, TimeStepRuleEq6AndRefusal) {
  LudingParams p;
  Particles P;
  P.add(0.0, 0.0, 0.5e-3, p);  // lightest
  P.add(1.0, 0.0, 1.0e-3, p);
  P.add(2.0, 0.0, 1.5e-3, p);
  DynamicOptions o;
  const TimeStepInfo ts = choose_time_step(P, luding(p), o);
  const double mmean = (P.mass[0] + P.mass[1] + P.mass[2]) / 3.0, m12 = 0.5 * mmean;
  const double eta = p.gamma_n / (2.0 * m12);
  const double w = std::sqrt(p.k2 / m12 - eta * eta);
  EXPECT_NEAR(ts.dt, std::numbers::pi / (50.0 * w), 1e-12 * ts.dt);  // t_MD = pi / (50 omega)
  const double ml = P.mass[0] * P.mass[1] / (P.mass[0] + P.mass[1]);
  EXPECT_NEAR(ts.tc_lightest, contact_duration(p.k2, p.gamma_n, ml), 1e-15);
  EXPECT_LT(ts.steps_per_contact_lightest, 50.0);
  std::printf("  Table 1 tri-disperse: dt = %.3e s, lightest pair %.1f steps per contact\n", ts.dt,
              ts.steps_per_contact_lightest);
  o.rule = TimeStepRule::LightestPair;
  EXPECT_NEAR(choose_time_step(P, luding(p), o).steps_per_contact_lightest, 50.0, 1e-9);
  o.rule = TimeStepRule::MeanPair;
  o.dt = ts.tc_lightest / 9.0;  // 9 steps per lightest contact: refused
  try {
    (void)choose_time_step(P, luding(p), o);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("steps per contact"), std::string::npos) << e.what();
  }
  o.dt = ts.tc_lightest / 11.0;
  EXPECT_NO_THROW((void)choose_time_step(P, luding(p), o));
}

TEST(Dynamic, InvalidInputsThrow) {
  LudingParams p;
  Particles P;
  P.add(0.002, 0.002, p.a0, p);
  Box box;
  DynamicOptions o;
  o.steps_per_contact = 0.0;
  EXPECT_THROW(DynamicSolver(P, p, box, o), std::invalid_argument);
  o = DynamicOptions{};
  Box bad = box;
  bad.x_max = -1.0;
  EXPECT_THROW(DynamicSolver(P, p, bad, o), std::invalid_argument);
  bad = box;
  bad.right.mode = WallMode::Stress;
  bad.right.mass = 0.0;
  EXPECT_THROW(DynamicSolver(P, p, bad, o), std::invalid_argument);
  EXPECT_THROW(choose_time_step(Particles{}, luding(p), o), std::invalid_argument);
  EXPECT_NO_THROW(DynamicSolver(P, p, box, o));
}

// ---- two-disk collisions
// ------------------------------------------------------------------------- Linear spring-dashpot
// closed forms (LMM05 Eq 5, 6): t_c = pi / sqrt(w0^2 - eta^2), e = exp(-eta t_c), eta = gamma0 / (2
// m12). Velocity Verlet with the damping force taken at the half-step velocity is first order in
// the damping: the error of e is O(eta dt) and that of t_c is O(dt^2) (spring) plus O(eta dt) t_c.
// With 50 steps per contact, eta t_c = 0.16 (Table 1 gamma0 = 0.2 kg/s, a = 1 mm): eta dt = 3e-3;
// we allow |de| <= eta dt and |dt_c| <= eta dt t_c, and check that both errors shrink ~4x... at
// least 2x for 4x smaller dt (first order).
TEST(Dynamic, TwoDiskSpringDashpotRestitutionAndDuration) {
  LudingParams p;
  p.k1_ratio = 1.0;
  p.kc_ratio = 0.0;
  p.mu = 0.0;
  const double m = netdem::contact::luding_mass(p, p.a0), m12 = 0.5 * m;
  const double eta = p.gamma_n / (2.0 * m12);
  const double tc = std::numbers::pi / std::sqrt(p.k2 / m12 - eta * eta);
  const double e = std::exp(-eta * tc);
  double err_e[2], err_t[2];
  int k = 0;
  for (double spc : {50.0, 200.0}) {
    const Collision c = two_disk(p, ContactModel::Linear, spc);
    const double dt = tc / spc;
    err_e[k] = std::fabs(c.e - e);
    err_t[k] = std::fabs(c.tc - tc) / tc;
    std::printf(
        "  %3.0f steps/contact: e = %.6f (closed form %.6f), t_c = %.6e s (%.6e), "
        "eta dt = %.2e\n",
        spc, c.e, e, c.tc, tc, eta * dt);
    EXPECT_LE(err_e[k], eta * dt);
    EXPECT_LE(err_t[k], eta * dt);
    ++k;
  }
  EXPECT_GT(err_e[0], 2.0 * err_e[1]);
  // and the full law instantiation with k1 = k2, k_c = 0 gives the same collision
  const Collision cf = two_disk(p, ContactModel::Hysteretic, 50.0);
  const Collision cl = two_disk(p, ContactModel::Linear, 50.0);
  EXPECT_NEAR(cf.e, cl.e, 1e-12);
}

// k_c = 0, Eq 7 off (constant k2), no damping: e = sqrt(k1/k2) (LMM05 Eq 4).
TEST(Dynamic, TwoDiskHystereticRestitutionSqrtK1OverK2) {
  for (double ratio : {0.5, 0.8}) {
    LudingParams p = elastic_params();
    p.k1_ratio = ratio;
    p.stiffness_growth = false;
    const Collision c = two_disk(p, ContactModel::Hysteretic, 50.0);
    std::printf("  k1/k2 = %.1f: e = %.6f, sqrt(k1/k2) = %.6f\n", ratio, c.e, std::sqrt(ratio));
    // 50 steps per contact: the kink at delta_max costs O(dt^2) ~ (pi/50)^2 = 4e-3 at most
    EXPECT_NEAR(c.e, std::sqrt(ratio), 4e-3);
  }
}

// ---- conservation ------------------------------------------------------------------------------
namespace {
// Max relative energy error max_t |E(t) - E(0)| / E(0) of an elastic system (k1 = k2, k_c = 0,
// no damping, mu = 0) of side x side disks on a jittered lattice of pitch `pitch` a0 in a fixed
// box, random velocities of scale v, over `duration` seconds.
double energy_error(double pitch, double v, double steps_per_contact, double duration, int side) {
  LudingParams p = elastic_params();
  Particles P = lattice(p, side, side, pitch * p.a0, 0.05, v, 7);
  Box box;
  box.x_max = side * pitch * p.a0;
  box.y_max = box.x_max;
  DynamicOptions o;
  o.model = ContactModel::Linear;
  o.steps_per_contact = steps_per_contact;
  DynamicSolver s(std::move(P), p, box, o);
  const double e0 = s.energies().total();
  double err = 0.0;
  const std::size_t n = static_cast<std::size_t>(duration / s.dt());
  for (std::size_t k = 0; k < n; ++k) {
    s.step();
    err = std::max(err, std::fabs(s.energies().total() - e0) / e0);
  }
  return err;
}
double mean_pair_tc(const LudingParams& p) {
  return contact_duration(p.k2, 0.0, 0.5 * netdem::contact::luding_mass(p, p.a0));
}
}  // namespace

// Dense random packing whose contacts never open (pitch 1.85 a0 < 2 a_min; velocities small
// against the overlaps): a smooth Hamiltonian, on which velocity Verlet's energy error is
// O(dt^2) (bounded, no drift). The horizon (5 contact times) is short enough that the runs at
// different dt follow the same trajectory, so the ratio of errors is deterministic.
TEST(Dynamic, EnergyConservedSecondOrder) {
  const int side = small_scale() ? 7 : 10;
  const LudingParams p = elastic_params();
  const double duration = 5.0 * mean_pair_tc(p);
  const double e1 = energy_error(1.85, 0.3, 25.0, duration, side);
  const double e2 = energy_error(1.85, 0.3, 50.0, duration, side);
  const double e3 = energy_error(1.85, 0.3, 100.0, duration, side);
  const double o1 = std::log2(e1 / e2), o2 = std::log2(e2 / e3);
  std::printf(
      "  %d disks, persistent contacts: max |dE|/E = %.3e, %.3e, %.3e at 25, 50, 100 "
      "steps/contact; observed orders %.3f, %.3f\n",
      side * side, e1, e2, e3, o1, o2);
  EXPECT_GE(o1, 1.8);
  EXPECT_LE(o1, 2.2);
  EXPECT_GE(o2, 1.8);
  EXPECT_LE(o2, 2.2);
}

// A collision adds a non-telescoping error where the force law has its kink (delta = 0): the
// energy after an elastic two-disk collision is off by O(dt^3) (one step straddles each kink).
TEST(Dynamic, CollisionEnergyErrorThirdOrder) {
  const LudingParams p = elastic_params();
  double err[3];
  int k = 0;
  for (double spc : {50.0, 100.0, 200.0}) {
    double mx = 0.0;
    for (int phase = 0; phase < 7; ++phase) {  // several positions of the kink in a step
      Particles P;
      P.add(0.0, 0.0, p.a0, p, 0.05, 0.0);
      P.add(2.0 * p.a0 + 1e-6 * (1.0 + 0.13 * phase), 0.0, p.a0, p, -0.05, 0.0);
      Box box;
      box.enabled = false;
      DynamicOptions o;
      o.model = ContactModel::Linear;
      o.steps_per_contact = spc;
      DynamicSolver s(std::move(P), p, box, o);
      const double e0 = s.energies().total();
      s.run(static_cast<std::size_t>(3.0 * spc));
      ASSERT_EQ(s.energies().elastic, 0.0);  // separated again
      mx = std::max(mx, std::fabs(s.energies().total() / e0 - 1.0));
    }
    err[k++] = mx;
  }
  const double o1 = std::log2(err[0] / err[1]), o2 = std::log2(err[1] / err[2]);
  std::printf(
      "  after one collision: max |dE|/E = %.3e, %.3e, %.3e at 50, 100, 200 steps/contact;"
      " orders %.2f, %.2f\n",
      err[0], err[1], err[2], o1, o2);
  EXPECT_GT(o1, 2.7);
  EXPECT_GT(o2, 2.7);
}

// Dense random gas (contacts open and close): the energy error is bounded (reported); its
// dependence on dt mixes the O(dt^2) in-contact term and the O(dt^3) collision kinks, whose
// signs vary from collision to collision of a chaotic trajectory, so no order is asserted.
TEST(Dynamic, DenseGasEnergyBounded) {
  const int side = small_scale() ? 7 : 10;
  const LudingParams p = elastic_params();
  const double duration = (small_scale() ? 20.0 : 100.0) * mean_pair_tc(p);
  const double e50 = energy_error(2.1, 1.0, 50.0, duration, side);
  std::printf(
      "  %d-disk gas (nu ~ 0.7), %.0f contact times at 50 steps/contact: "
      "max |dE|/E = %.3e\n",
      side * side, duration / mean_pair_tc(p), e50);
  EXPECT_LT(e50, 1e-3);  // observed 3.5e-4
}

TEST(Dynamic, FreeSetConservesMomentum) {
  for (bool friction : {false, true}) {
    LudingParams p;  // Table 1 (hysteresis, cohesion, damping, friction)
    if (!friction) p = elastic_params();
    // an overlapping cluster flying apart and colliding: 64 disks, pitch < 2a
    Particles P = lattice(p, 8, 8, 2.1 * p.a0, 0.1, 0.5, 11);
    for (std::size_t i = 0; i < P.size(); ++i) P.spin[i] = 200.0 * std::sin(1.0 + i);
    Box box;
    box.enabled = false;
    DynamicOptions o;
    o.model = friction ? ContactModel::Full : ContactModel::Linear;
    o.temperature = 80.0;
    DynamicSolver s(std::move(P), p, box, o);
    auto moments = [&](double& px, double& py, double& L, double& scale, double& lscale) {
      const auto& q = s.particles();
      px = py = L = scale = lscale = 0.0;
      for (std::size_t i = 0; i < q.size(); ++i) {
        px += q.mass[i] * q.vel[2 * i];
        py += q.mass[i] * q.vel[2 * i + 1];
        const double li =
            q.mass[i] * (q.pos[2 * i] * q.vel[2 * i + 1] - q.pos[2 * i + 1] * q.vel[2 * i]) + q.inertia[i] * q.spin[i];
        L += li;
        scale += q.mass[i] * std::hypot(q.vel[2 * i], q.vel[2 * i + 1]);
        lscale += std::fabs(li);
      }
    };
    double px0, py0, L0, sc, lsc;
    moments(px0, py0, L0, sc, lsc);
    s.run(small_scale() ? 1000 : 4000);
    double px, py, L, sc1, lsc1;
    moments(px, py, L, sc1, lsc1);
    const double dp = std::hypot(px - px0, py - py0) / sc, dL = std::fabs(L - L0) / lsc;
    std::printf("  %s: |dP|/sum m|v| = %.2e, |dL|/sum|L_i| = %.2e (%zu table builds)\n",
                friction ? "Table 1 law, friction" : "frictionless elastic", dp, dL, s.rebuilds());
    EXPECT_LT(dp, 1e-13);
    // Verlet conserves L to round-off: the drift keeps x x v, each kick adds sum x x f + torque,
    // which cancels pairwise (the pair torques -d_i f_t - d_j f_t = -L f_t cancel l x f = L f_t)
    EXPECT_LT(dL, 1e-12);
  }
}

// ---- neighbour search ---------------------------------------------------------------------------
// The Verlet table (on the shared packing::CellGrid) holds exactly the pairs within
// a_i + a_j + skin for radius ratios up to 100, in a free system and in a walled box.
TEST(Dynamic, VerletTableExactForRadiusRatio100) {
  LudingParams p;
  for (unsigned seed : {1u, 2u}) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    Particles P;
    const double L = 60.0 * p.a0;
    for (int i = 0; i < 400; ++i) {  // radii log-uniform in a0 [0.02, 2], overlaps allowed
      const double r = i == 0 ? 2.0 * p.a0 : i == 1 ? 0.02 * p.a0 : 0.02 * p.a0 * std::exp(std::log(100.0) * u(rng));
      const double y = r + (L - 2 * r) * u(rng), x = r + (L - 2 * r) * u(rng);  // (GCC's order, as lattice())
      P.add(x, y, r, p);
    }
    for (bool walls : {false, true}) {
      Box box;
      box.enabled = walls;
      box.x_max = box.y_max = L;
      DynamicOptions o;
      o.model = ContactModel::Linear;
      o.skin = 0.05 * p.a0;
      o.min_steps_per_contact = 0.0;  // the radius ratio makes the lightest pair stiff
      const DynamicSolver s(P, p, box, o);
      std::size_t in_range = 0;
      std::vector<std::pair<std::uint32_t, std::uint32_t>> touching, found;
      for (std::uint32_t i = 0; i < P.size(); ++i)
        for (std::uint32_t j = i + 1; j < P.size(); ++j) {
          const double dx = P.pos[2 * j] - P.pos[2 * i], dy = P.pos[2 * j + 1] - P.pos[2 * i + 1], r = P.r[i] + P.r[j];
          if (dx * dx + dy * dy < (r + o.skin) * (r + o.skin)) {
            ++in_range;
            EXPECT_NE(s.history(i, j), nullptr) << i << " " << j;
          }
          if (dx * dx + dy * dy < r * r) touching.emplace_back(i, j);
        }
      EXPECT_EQ(s.table_size(), in_range);
      s.touching_pairs(found);
      EXPECT_EQ(found, touching);
      EXPECT_GT(touching.size(), 50u);
    }
  }
}

TEST(Dynamic, VerletTableMatchesAllPairs) {
  LudingParams p;
  const int side = small_scale() ? 8 : 14;
  Particles P = lattice(p, side, side, 2.0 * p.a0, 0.4, 0.5, 3);
  Box box;
  box.x_max = side * 2.0 * p.a0;
  box.y_max = box.x_max;
  box.right.mode = WallMode::Strain;
  box.right.velocity = -0.2;
  box.top.mode = WallMode::Strain;
  box.top.velocity = -0.2;
  DynamicOptions o;
  DynamicSolver s(std::move(P), p, box, o);
  std::vector<std::pair<std::uint32_t, std::uint32_t>> found, ref;
  const int steps = 3000;
  std::size_t checked = 0, max_contacts = 0, carried = 0;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> prev;
  std::vector<double> prev_dmax;
  for (int k = 0; k < steps; ++k) {
    const std::size_t builds = s.rebuilds();
    s.step();
    s.touching_pairs(found);
    const auto& q = s.particles();
    ref.clear();
    for (std::uint32_t i = 0; i < q.size(); ++i)
      for (std::uint32_t j = i + 1; j < q.size(); ++j) {
        const double dx = q.pos[2 * j] - q.pos[2 * i], dy = q.pos[2 * j + 1] - q.pos[2 * i + 1], r = q.r[i] + q.r[j];
        if (dx * dx + dy * dy < r * r) ref.emplace_back(i, j);
      }
    ASSERT_EQ(found, ref) << "step " << k;
    // history lifecycle: a pair touching in consecutive steps keeps its history through a table
    // rebuild (at constant temperature delta_max never decreases while the contact lasts)
    std::vector<double> dmax(ref.size());
    for (std::size_t c = 0; c < ref.size(); ++c) {
      const auto* h = s.history(ref[c].first, ref[c].second);
      ASSERT_NE(h, nullptr);
      dmax[c] = h->delta_max;
      auto it = std::lower_bound(prev.begin(), prev.end(), ref[c]);
      if (it != prev.end() && *it == ref[c]) {
        ASSERT_GE(dmax[c], prev_dmax[static_cast<std::size_t>(it - prev.begin())]) << "step " << k;
        if (s.rebuilds() != builds) ++carried;
      }
    }
    prev = ref;
    prev_dmax = dmax;
    max_contacts = std::max(max_contacts, ref.size());
    ++checked;
  }
  std::printf(
      "  %d disks: %zu checks, %zu rebuilds, up to %zu contacts, %zu histories carried "
      "through rebuilds, nu = %.3f\n",
      side * side, checked, s.rebuilds(), max_contacts, carried, s.density());
  EXPECT_GT(s.rebuilds(), 10u);
  EXPECT_GT(carried, 100u);
  EXPECT_GT(max_contacts, static_cast<std::size_t>(side * side));
}

// ---- stress-controlled walls (Eq 1)
// --------------------------------------------------------------
TEST(Dynamic, StressControlledWallsSettleToPressure) {
  LudingParams p;
  p.k1_ratio = 1.0;
  p.kc_ratio = 0.0;
  p.mu = 0.0;
  p.mu_wall = 0.0;
  p.gamma_n = 1.0;  // ~ 1/4 of critical damping of a mean pair
  const int side = small_scale() ? 6 : 10;
  const double pitch = 2.2 * p.a0;
  Particles P = lattice(p, side, side, pitch, 0.2, 0.0, 5);
  Box box;
  box.x_max = side * pitch;
  box.y_max = side * pitch;
  const double pressure = 100.0;  // N/m (LMM05 p = 100)
  for (MovingWall* w : {&box.right, &box.top}) {
    w->mode = WallMode::Stress;
    w->pressure = pressure;
    w->mass = 0.01;
    w->damping = 20.0;
  }
  DynamicOptions o;
  o.model = ContactModel::Linear;
  DynamicSolver s(std::move(P), p, box, o);
  const double nu0 = s.density();
  const std::size_t steps = static_cast<std::size_t>(0.06 / s.dt());
  s.run(steps);
  const double Lx = s.box().x_max - s.box().x_min, Ly = s.box().y_max - s.box().y_min;
  const double Fx = s.wall_force_right(), Fy = s.wall_force_top();
  const Stress2 sw = s.wall_stress(), sc = s.contact_stress();
  std::printf(
      "  %d disks, %zu steps: nu %.3f -> %.3f; F_right/(p Ly) = %.5f, F_top/(p Lx) = %.5f;"
      " contact stress xx %.2f yy %.2f xy %.2e N/m; E_kin = %.2e J\n",
      side * side, steps, nu0, s.density(), Fx / (pressure * Ly), Fy / (pressure * Lx), sc.xx,
      sc.yy, sc.xy, s.energies().kinetic);
  EXPECT_NEAR(Fx / (pressure * Ly), 1.0, 1e-3);
  EXPECT_NEAR(Fy / (pressure * Lx), 1.0, 1e-3);
  EXPECT_NEAR(sw.xx, pressure, 0.1);
  // the contact network carries the same stress (static equilibrium)
  EXPECT_NEAR(sc.xx / pressure, 1.0, 1e-2);
  EXPECT_NEAR(sc.yy / pressure, 1.0, 1e-2);
  EXPECT_GT(s.density(), nu0);
}

// ---- gravity ------------------------------------------------------------------------------------
// One disk dropped on the bottom wall (damped) comes to rest at k2 delta = m g.
TEST(Dynamic, GravityRestingDiskOnBottomWall) {
  LudingParams p;
  p.k1_ratio = 1.0;
  p.kc_ratio = 0.0;
  p.gamma_n = 2.0;
  Particles P;
  P.add(0.005, p.a0 + 1e-4, p.a0, p);
  Box box;
  box.x_max = 0.01;
  box.y_max = 0.01;
  DynamicOptions o;
  o.model = ContactModel::Linear;
  o.gravity_y = -9.81;
  DynamicSolver s(std::move(P), p, box, o);
  s.run(static_cast<std::size_t>(0.05 / s.dt()));
  const auto& q = s.particles();
  const double delta = q.r[0] - q.pos[1];
  std::printf("  resting overlap %.6e m, m g / k2 = %.6e m\n", delta, q.mass[0] * 9.81 / p.k2);
  EXPECT_NEAR(delta * p.k2 / (q.mass[0] * 9.81), 1.0, 1e-6);
}

// Table 1 law (hysteresis, Eq 7, cohesion, friction, damping, k1(T = 80 C)) under the same
// stress-controlled walls: the preparation step of LMM05 section 4 settles to p as well.
TEST(Dynamic, Table1LawCompactionSettles) {
  LudingParams p;  // Table 1
  const int side = small_scale() ? 6 : 8;
  const double pitch = 2.2 * p.a0;
  Particles P = lattice(p, side, side, pitch, 0.5, 0.0, 9);
  Box box;
  box.x_max = side * pitch;
  box.y_max = side * pitch;
  const double pressure = 100.0;
  for (MovingWall* w : {&box.right, &box.top}) {
    w->mode = WallMode::Stress;
    w->pressure = pressure;
    w->damping = 20.0;
  }
  DynamicOptions o;
  o.model = ContactModel::Full;
  DynamicSolver s(std::move(P), p, box, o);
  const std::size_t steps = static_cast<std::size_t>(0.06 / s.dt());
  s.run(steps);
  const double Lx = s.box().x_max - s.box().x_min, Ly = s.box().y_max - s.box().y_min;
  const Stress2 sc = s.contact_stress();
  std::printf(
      "  %d disks, %zu steps: nu = %.3f, F_right/(p Ly) = %.5f, F_top/(p Lx) = %.5f, "
      "contact stress xx %.2f yy %.2f N/m\n",
      side * side, steps, s.density(), s.wall_force_right() / (pressure * Ly),
      s.wall_force_top() / (pressure * Lx), sc.xx, sc.yy);
  EXPECT_NEAR(s.wall_force_right() / (pressure * Ly), 1.0, 1e-2);
  EXPECT_NEAR(s.wall_force_top() / (pressure * Lx), 1.0, 1e-2);
  EXPECT_NEAR(sc.xx / pressure, 1.0, 2e-2);
  EXPECT_NEAR(sc.yy / pressure, 1.0, 2e-2);
}

// ---- the in-place update of the force loop equals the law's evaluate() ---------------------------
// The force loop calls the law's in-place update() (for the linear sets: luding_evaluate written
// out); reference_contact_path calls evaluate() instead. A few thousand steps with friction,
// cohesion, damping and stress-controlled walls give the same state to the last bit.
TEST(Dynamic, InPlaceUpdateIsBitIdentical) {
  for (ContactModel model : {ContactModel::Linear, ContactModel::Hysteretic, ContactModel::Full}) {
    LudingParams p;  // Table 1: friction, cohesion, damping
    p.mu_wall = 0.3;  // wall friction too
    const int side = small_scale() ? 5 : 8;
    const double pitch = 2.05 * p.a0;
    Box box;
    box.x_max = side * pitch;
    box.y_max = side * pitch;
    for (MovingWall* w : {&box.right, &box.top}) {
      w->mode = WallMode::Stress;
      w->pressure = 100.0;
      w->damping = 20.0;
    }
    SolverState out[2];
    for (int ref = 0; ref < 2; ++ref) {
      DynamicOptions o;
      o.model = model;
      o.reference_contact_path = ref == 1;
      o.gravity_y = -9.81;
      DynamicSolver s(lattice(p, side, side, pitch, 0.3, 0.05, 21), p, box, o);
      s.run(small_scale() ? 6000 : 20000);
      out[ref] = s.state();
    }
    const auto& a = out[0].particles_of<2>();
    const auto& b = out[1].particles_of<2>();
    ASSERT_EQ(a.size(), b.size());
    std::size_t touching = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
      EXPECT_EQ(std::memcmp(&a.pos[2 * i], &b.pos[2 * i], sizeof(double)), 0);
      EXPECT_EQ(std::memcmp(&a.vel[2 * i + 1], &b.vel[2 * i + 1], sizeof(double)), 0);
      EXPECT_EQ(std::memcmp(&a.spin[i], &b.spin[i], sizeof(double)), 0);
    }
    const auto &s0 = out[0].histories_of<LudingHistory>(), &s1 = out[1].histories_of<LudingHistory>();
    ASSERT_EQ(s0.pair.size(), s1.pair.size());
    for (std::size_t k = 0; k < s0.pair.size(); ++k) {
      const auto &h0 = s0.pair[k], &h1 = s1.pair[k];
      touching += h0.fresh() ? 0 : 1;
      EXPECT_EQ(std::memcmp(&h0.xi, &h1.xi, sizeof(double)), 0);
      EXPECT_EQ(std::memcmp(&h0.delta_max, &h1.delta_max, sizeof(double)), 0);
      EXPECT_EQ(std::memcmp(&h0.delta0, &h1.delta0, sizeof(double)), 0);
      EXPECT_EQ(h0.sliding, h1.sliding);
    }
    for (std::size_t k = 0; k < s0.wall.size(); ++k)
      EXPECT_EQ(std::memcmp(&s0.wall[k].xi, &s1.wall[k].xi, sizeof(double)), 0);
    std::printf("  model %d: %zu particles, %zu contacts with a history\n", static_cast<int>(model), a.size(),
                touching);
    EXPECT_GT(touching, 0u);  // contacts were tested (1 for the linear model at the small scale, 7 at full)
  }
}
