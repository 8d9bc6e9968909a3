// The explicit DEM in a periodic cell (issue 29): the closed forms of periodic lattices under
// affine hydrostatic strain (no (n - 1)/n edge factor), the invariances a periodic cell must have
// (a shift of every particle wrapped into the cell, a renumbering, a mirror), and the refusals of
// the readers and solvers that cannot use a periodic packing.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cmath>
#include <numbers>
#include <numeric>
#include <random>

#include "netdem/dynamic/compaction.hpp"
#include "netdem/dynamic/solver.hpp"
#include "netdem/dynamic/state.hpp"
#include "netdem/packing/packing.hpp"
#include "netdem/packing/periodic.hpp"
#include "periodic_lattices.hpp"

using namespace netdem::dem;
namespace packing = netdem::packing;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

using netdem::test::cubic_lattice;
using netdem::test::triangular_lattice;

DynamicOptions plastic_options(double mu) {
  DynamicOptions o;
  o.model = ContactModel::PlasticIndentation;
  o.plastic.sigma_y = 2.0;
  o.plastic.mu = mu;
  o.plastic.damping_n = o.plastic.damping_t = 0.5;
  return o;
}

template <int D>
DynamicSolverT<D> periodic_solver(const packing::Packing& pk, const DynamicOptions& o) {
  return DynamicSolverT<D>(periodic_particles_from<D>(pk, 1.0), o.plastic, packing::periodic_cell<D>(pk), o);
}

// A disordered periodic packing of n x n disks: a square lattice of spacing 2.0 with jittered
// centres and radii in [0.95, 1.1] (some pairs overlap from the start, some across the faces).
packing::Packing jittered(int n, std::uint64_t seed, double a = 2.0) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  packing::Packing p;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      p.x.push_back(0.5 * a + a * i + 0.15 * U(rng));
      p.y.push_back(0.5 * a + a * j + 0.15 * U(rng));
      p.r.push_back(1.025 + 0.075 * U(rng));
    }
  p.box = {0.0, 0.0, a * n, a * n};
  for (auto* v : {&p.x, &p.y})
    for (double& x : *v) x = std::fmod(x + a * n, a * n);
  p.periodic = true;
  return p;
}

// Runs a compaction along (e11, e22, e12) for `steps` steps; returns the contact stress.
Stress2 run_path(const packing::Packing& pk, double e11, double e22, double e12, int steps, double mu) {
  DynamicOptions o = plastic_options(mu);
  DynamicSolver s = periodic_solver<2>(pk, o);
  s.set_strain_rate(e11, e22, e12);
  s.set_affine_velocities();
  s.run(static_cast<std::size_t>(steps));
  return s.contact_stress();
}

}  // namespace

// A periodic triangular lattice under hydrostatic strain, then held at rest: every contact of the
// infinite lattice has L = 2 R e^E and F = 3 sigma_y sqrt(8 u R*) (Eq 2, R* = R/2; u above the
// first-touch overlap) and Sigma_11 = Sigma_22 = (3/2) N F L / V (compression positive), with no
// edge factor. Each disk is a centre of symmetry, so the free disks follow the affine motion; at
// rest the dashpots carry nothing, so the DEM's contact stress is the closed form to rounding.
// While the strain runs, the dashpot adds gamma_n |E'| L to each normal force: checked as well.
TEST(PeriodicDem, TriangularLatticeMatchesInfiniteLattice) {
  const int nc = 6, nr = 6;
  const packing::Packing pk = triangular_lattice(nc, nr);
  for (double mu : {0.0, kInf}) {
    DynamicOptions o = plastic_options(mu);
    DynamicSolver s = periodic_solver<2>(pk, o);
    const double rate = -2e-2;
    s.set_strain_rate(rate, rate, 0.0);
    s.set_affine_velocities();
    const double E_end = -0.5 * std::log(1.03);  // D = 1.03 D0
    while (s.time() * -rate < -E_end) s.step();
    const double E = rate * s.time(), R = 1.0, L = 2 * R * std::exp(E), u = 2 * R - L;
    const double F = 3 * o.plastic.sigma_y * std::sqrt(8 * u * R / 2);
    const double V = pk.box.area() * std::exp(2 * E), N = nc * nr;
    // while straining: the spring and the dashpot gamma_n v_n, v_n = |E'| L, gamma_n = 2 damping_n sqrt(k_c m*)
    const double m_eff = 0.5 * std::numbers::pi, gamma = 2 * 0.5 * std::sqrt(o.plastic.chord_stiffness() * m_eff);
    const double moving = 1.5 * N * (F + gamma * -rate * L) * L / V;
    EXPECT_NEAR(s.contact_stress().xx, moving, 1e-6 * moving) << "mu " << mu;
    s.set_strain_rate(0.0, 0.0, 0.0);
    s.run(20);
    const double expect = 1.5 * N * F * L / V;
    const Stress2 sc = s.contact_stress();
    EXPECT_NEAR(sc.xx, expect, 1e-10 * expect) << "mu " << mu;
    EXPECT_NEAR(sc.yy, expect, 1e-10 * expect) << "mu " << mu;
    EXPECT_NEAR(sc.xy, 0.0, 1e-10 * expect) << "mu " << mu;
    EXPECT_NEAR(s.density(), pk.density() * std::exp(-2 * E), 1e-12);
    std::vector<std::pair<std::uint32_t, std::uint32_t>> touching;
    s.touching_pairs(touching);
    EXPECT_EQ(touching.size(), 3u * nc * nr) << "every disk keeps its six contacts";
    const Stress2 k = s.kinetic_stress();
    EXPECT_LT(std::fabs(k.xx) + std::fabs(k.yy), 1e-20 * expect) << "the fluctuations stay zero";
  }
}

template <int D>
class RowsOf : public CompactionObserverT<D> {
 public:
  void row(const CompactionRowT<D>& r) override { rows.push_back(r); }
  std::vector<CompactionRowT<D>> rows;
};

// Issue 29's cross-check path through the protocol's legs (compaction_legs, run_compaction): a
// hydrostatic precompaction to D1 = 1.05 D0, then pure shear (1, -1, 0) to |E| = 0.02, at
// gamma' = I / 2 = 0.02 along both. Each leg ends at its target exactly (step_to): the density D1
// and |E| of the shear leg to rounding, and the cell is exp(E) h0 with the reported E. Held at rest
// at the end, the lattice (it follows the affine motion: every disk a centre of symmetry, the
// torques cancel in pairs) has the closed form's stress of netsolve's test
// (PeriodicNetwork.PrecompactionThenPureShearMatchesLattice; tests/periodic_lattices.hpp) to 1e-10:
// the bonds along x unload (Eq 2 retraced by the reversible law, opened by the elastic line), and
// with sticking the slanted bonds slide at the shear cap against their slip. No tangential dashpot
// here: at this rate gamma_t v_t is 1.9 x the cap of a slanted bond, and the sliding rule (spring +
// dashpot on the limit, LMM05 Eq 21) leaves the spring at cap - gamma_t v_t, past the cap the
// other way; held at rest, those bonds then slide back against the shear (S11 - S22 0.13 instead
// of 1.24 with damping_t = 0.5: a rate artefact, docs/dynamic.md "Periodic cell").
TEST(PeriodicDem, PrecompactionThenPureShearMatchesLattice) {
  const int nc = 6, nr = 6;
  const packing::Packing pk = triangular_lattice(nc, nr);
  const double D0 = pk.density(), D1 = D0 * 1.05, S = 0.02, R = 1.0;
  const auto path = netdem::sys::StrainPathT<2>::parse("1,-1,0");
  for (bool reversible : {true, false}) {
    for (double mu : {0.0, kInf}) {
      DynamicOptions o = plastic_options(mu);
      o.plastic.reversible = reversible;
      o.plastic.damping_t = 0.0;
      DynamicSolver s = periodic_solver<2>(pk, o);
      CompactionOptions co;
      co.precompact_density = D1;
      co.precompact_increments = 4;
      co.target_strain = S;
      co.increments = 4;
      co.inertial_number = 4e-2;
      co.validate(path, D0);
      const auto legs = compaction_legs(path, co, D0);
      ASSERT_EQ(legs.size(), 2u);
      set_strain_rate(s, legs[0].rate.rate);
      s.set_affine_velocities();
      RowsOf<2> obs;
      const auto sum = run_compaction(s, legs, co, obs);
      const std::string what = "reversible " + std::to_string(reversible) + ", mu " + std::to_string(mu);
      ASSERT_TRUE(sum.ok()) << what << ": " << sum.reason;
      ASSERT_EQ(obs.rows.size(), 9u);
      for (std::size_t k = 0; k < obs.rows.size(); ++k) EXPECT_EQ(obs.rows[k].leg, k <= 4 ? 0 : 1) << k;
      const auto& pre = obs.rows[4];
      EXPECT_NEAR(pre.density, D1, 1e-12 * D1) << "the precompaction ends at D1";
      const auto& end = obs.rows.back();
      const double d11 = end.E[0] - pre.E[0], d22 = end.E[1] - pre.E[1], d12 = end.E[2] - pre.E[2];
      EXPECT_NEAR(std::sqrt(d11 * d11 + d22 * d22 + 2 * d12 * d12), S, 1e-12) << "|E| of the shear leg";
      EXPECT_NEAR(d11, S / std::sqrt(2.0), 1e-12);
      EXPECT_NEAR(end.density, D1, 1e-12 * D1);
      const Eigen::Matrix2d h = s.cell().h, h0 = packing::periodic_cell<2>(pk).h;
      EXPECT_NEAR(h(0, 0), h0(0, 0) * std::exp(end.E[0]), 1e-12 * h0(0, 0)) << "the cell is exp(E) h0";
      EXPECT_NEAR(h(1, 1), h0(1, 1) * std::exp(end.E[1]), 1e-12 * h0(1, 1));
      EXPECT_EQ(h(0, 1), 0.0);
      s.set_strain_rate(0.0, 0.0, 0.0);
      s.run(20);
      const double sy = o.plastic.sigma_y, uh = 2 * R - 2 * R * std::exp(pre.E[0]);
      auto eq2 = [&](double u) { return 3 * sy * std::sqrt(8 * u * R / 2); };
      auto tangent = [&](double u) { return 3 * sy * std::sqrt(2 * (R / 2) / u); };
      auto normal = [&](int k, double u) {
        if (reversible || k != 0) return eq2(u);
        return std::max(0.0, eq2(uh) - o.plastic.unload_ratio * tangent(uh) * (uh - u));
      };
      auto tangential = [&](int k, double Fn) { return mu == 0.0 ? 0.0 : netdem::test::sheared_lattice_cap(k, Fn); };
      const auto cf = netdem::test::triangular_lattice_stress(nc, nr, R, end.E[0], end.E[1], normal, tangential);
      const double scale = cf.xx + cf.yy;
      const Stress2 sc = s.contact_stress();
      EXPECT_NEAR(sc.xx, cf.xx, 1e-10 * scale) << what;
      EXPECT_NEAR(sc.yy, cf.yy, 1e-10 * scale) << what;
      EXPECT_NEAR(sc.xy, 0.0, 1e-10 * scale) << what;
      EXPECT_NEAR(sc.yx, 0.0, 1e-10 * scale) << what;
      EXPECT_GT(sc.yy - sc.xx, 0.1 * scale) << what << ": S11 - S22 > 0 (netsolve's sign)";
    }
  }
}

// The same for a periodic simple cubic lattice of spheres: F = 6 pi sigma_y R* u (R* = R/2),
// Sigma_ii = (3 pi / 4) sigma_y (u / R) e^{-2E} (compression positive), no (n - 1)/n factor.
TEST(PeriodicDem, CubicLatticeMatchesInfiniteLattice) {
  const int n = 4;
  const packing::Packing pk = cubic_lattice(n);
  DynamicOptions o = plastic_options(0.0);
  DynamicSolver3 s = periodic_solver<3>(pk, o);
  const double rate = -5e-3;
  s.set_strain_rate3(rate, rate, rate);
  s.set_affine_velocities();
  while (s.time() * -rate < 0.01) s.step();
  const double E = rate * s.time(), R = 1.0, u = 2 * R * (1 - std::exp(E));
  s.set_strain_rate3(0.0, 0.0, 0.0);
  s.run(20);
  const double expect = 0.75 * std::numbers::pi * o.plastic.sigma_y * (u / R) * std::exp(-2 * E);
  const Stress3 sc = s.contact_stress();
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(sc.s[a][a], expect, 1e-10 * expect) << "axis " << a;
  EXPECT_NEAR(sc.s[0][1], 0.0, 1e-10 * expect);
  std::vector<std::pair<std::uint32_t, std::uint32_t>> touching;
  s.touching_pairs(touching);
  EXPECT_EQ(touching.size(), 3u * n * n * n);
}

// Invariance over 1000 steps of a disordered packing on a sheared compaction path (contacts form,
// slide and cross the faces): every centre shifted by an arbitrary vector and wrapped into the
// cell, and a renumbering, give the same contact stress to 1e-9 of its scale; a mirror x -> W - x
// with E12 -> -E12 flips the sign of S12 only.
TEST(PeriodicDem, ShiftRenumberAndMirrorInvariance) {
  const int side = 8;
  const packing::Packing pk = jittered(side, 11);
  const double W = pk.box.width();
  packing::Packing sh = pk;
  for (std::size_t i = 0; i < sh.size(); ++i) {
    sh.x[i] = std::fmod(pk.x[i] + 5.3, W);
    sh.y[i] = std::fmod(pk.y[i] + W - 3.1, W);
  }
  std::vector<std::size_t> order(pk.size());
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), std::mt19937_64(5));
  packing::Packing perm = sh;
  for (std::size_t i = 0; i < order.size(); ++i) {
    perm.x[i] = sh.x[order[i]];
    perm.y[i] = sh.y[order[i]];
    perm.r[i] = sh.r[order[i]];
  }
  packing::Packing mir = pk;
  for (auto& x : mir.x) x = std::fmod(W - x, W);
  for (double mu : {0.3, kInf}) {
    const double e11 = -0.02, e22 = -0.012, e12 = 0.006;
    const int steps = 1000;
    const Stress2 a = run_path(pk, e11, e22, e12, steps, mu);
    const Stress2 b = run_path(sh, e11, e22, e12, steps, mu);
    const Stress2 c = run_path(perm, e11, e22, e12, steps, mu);
    const Stress2 m = run_path(mir, e11, e22, -e12, steps, mu);
    const double scale = std::max(std::fabs(a.xx), std::fabs(a.yy));
    ASSERT_GT(scale, 0.0);
    ASSERT_GT(std::fabs(a.xy), 1e-3 * scale) << "the sheared path loads S12";
    for (const Stress2* r : {&b, &c}) {
      EXPECT_NEAR(r->xx, a.xx, 1e-9 * scale) << "mu " << mu;
      EXPECT_NEAR(r->yy, a.yy, 1e-9 * scale) << "mu " << mu;
      EXPECT_NEAR(r->xy, a.xy, 1e-9 * scale) << "mu " << mu;
    }
    EXPECT_NEAR(m.xx, a.xx, 1e-9 * scale) << "mu " << mu;
    EXPECT_NEAR(m.yy, a.yy, 1e-9 * scale) << "mu " << mu;
    EXPECT_NEAR(m.xy, -a.xy, 1e-9 * scale) << "mu " << mu;
    EXPECT_NEAR(m.yx, -a.yx, 1e-9 * scale) << "mu " << mu;
    double worst = 0.0;
    for (const Stress2* r : {&b, &c})
      worst = std::max({worst, std::fabs(r->xx - a.xx), std::fabs(r->yy - a.yy), std::fabs(r->xy - a.xy)});
    worst = std::max({worst, std::fabs(m.xx - a.xx), std::fabs(m.yy - a.yy), std::fabs(m.xy + a.xy)});
    std::printf("  mu %g: S = (%.6g, %.6g, %.6g), largest difference / scale %.3g\n", mu, a.xx, a.yy, a.xy,
                worst / scale);
  }
}

// The rigid translation does not drift: the pair forces conserve the momentum and the table
// builds remove what rounding leaves, with particles that move across the faces.
TEST(PeriodicDem, NoDrift) {
  const packing::Packing pk = jittered(8, 3, 3.0);  // loose: the disks fly and collide
  DynamicOptions o = plastic_options(0.3);
  Particles P = periodic_particles_from<2>(pk, 1.0);
  std::mt19937_64 rng(9);
  std::normal_distribution<double> G(0.0, 0.5);
  for (std::size_t i = 0; i < P.size(); ++i) P.vel[2 * i] = G(rng), P.vel[2 * i + 1] = G(rng);
  DynamicSolver s(std::move(P), o.plastic, packing::periodic_cell<2>(pk), o);
  s.set_strain_rate(-0.02, -0.02, 0.0);
  s.run(60000);
  const Particles& Q = s.particles();
  double p[2] = {0, 0}, m = 0, vrms = 0;
  int outside = 0;
  for (std::size_t i = 0; i < Q.size(); ++i) {
    p[0] += Q.mass[i] * Q.vel[2 * i];
    p[1] += Q.mass[i] * Q.vel[2 * i + 1];
    m += Q.mass[i];
    vrms += Q.vel[2 * i] * Q.vel[2 * i] + Q.vel[2 * i + 1] * Q.vel[2 * i + 1];
    const auto f = s.cell().fractional(Q.position(i));
    outside += f.minCoeff() < 0.0 || f.maxCoeff() >= 1.0;
  }
  vrms = std::sqrt(vrms / static_cast<double>(Q.size()));
  std::printf("  t = %g, dt = %g, rebuilds %zu, vrms %g, x0 %g\n", s.time(), s.dt(), s.rebuilds(), vrms, Q.pos[0]);
  EXPECT_GT(outside, 0) << "some centres crossed a face (the positions stay unwrapped)";
  EXPECT_GT(vrms, 1e-3);
  EXPECT_LT(std::hypot(p[0], p[1]) / m, 1e-13 * vrms) << "the mean fluctuation velocity";
  EXPECT_GT(s.rebuilds(), 1u);
  // the periodic packing of the state is valid and periodic, every centre wrapped into the cell
  const packing::Packing out = s.periodic_packing();
  EXPECT_TRUE(out.periodic);
  EXPECT_NO_THROW(packing::validate(out));
  EXPECT_NEAR(out.density(), s.density(), 1e-12);
}

// Prescribed particles in a periodic cell (demsolve yield --compact-bc periodic --probe-bc affine):
// the cell carries the affine motion and a prescribed particle has no fluctuation. After a free
// phase (the disks moving), set_prescribed stops every fluctuation at once, and from then on every
// centre follows x_i - x_0 -> exp(L t) (x_i - x_0) to rounding while the contact forces act; free
// spins turn under the tangential forces, held ones stay at zero. Without the prescription the
// same run leaves the affine field.
TEST(PeriodicDem, PrescribedCentresFollowTheCell) {
  const packing::Packing pk = jittered(6, 5);
  const double e11 = 0.4, e22 = -0.6, e12 = 0.3;
  for (const int mode : {0, 1, 2}) {  // prescribed with free spins, with held spins, free
    const bool prescribed = mode < 2, held = mode == 1;
    DynamicSolver s = periodic_solver<2>(pk, plastic_options(0.3));
    s.set_strain_rate(e11, e22, e12);
    s.set_affine_velocities();
    s.run(1000);  // the free phase: fluctuation velocities and spins
    double v0 = 0.0;
    for (double v : s.particles().vel) v0 = std::max(v0, std::fabs(v));
    ASSERT_GT(v0, 1e-6);
    if (prescribed) {
      std::vector<std::uint32_t> all(pk.size());
      for (std::size_t p = 0; p < all.size(); ++p) all[p] = static_cast<std::uint32_t>(p);
      s.set_prescribed(all, held);
      double v = 0.0, w = 0.0;
      for (double x : s.particles().vel) v = std::max(v, std::fabs(x));
      for (double x : s.particles().spin) w = std::max(w, std::fabs(x));
      EXPECT_EQ(v, 0.0) << "stopped at once";
      if (held) {
        EXPECT_EQ(w, 0.0);
      }
    }
    const Particles start = s.particles();
    const double t0 = s.time();
    s.run(3000);
    Eigen::Matrix2d A;
    A << e11, e12, e12, e22;
    A *= s.time() - t0;
    Eigen::Matrix2d G = Eigen::Matrix2d::Identity(), term = Eigen::Matrix2d::Identity();
    for (int k = 1; k <= 12; ++k) G += (term = term * A / k);  // exp(L t)
    const Particles& Q = s.particles();
    double worst = 0.0, spin = 0.0, vel = 0.0;
    for (std::size_t i = 1; i < Q.size(); ++i) {
      const Eigen::Vector2d expect = G * (start.position(i) - start.position(0));
      worst = std::max(worst, (Q.position(i) - Q.position(0) - expect).norm());
      spin = std::max(spin, std::fabs(Q.spin[i]));
      vel = std::max(vel, std::hypot(Q.vel[2 * i], Q.vel[2 * i + 1]));
    }
    std::printf("  mode %d: |L t| = %.3g, worst %.3e, max spin %.3e, max fluctuation velocity %.3e\n", mode, A.norm(),
                worst, spin, vel);
    ASSERT_GT(A.norm(), 1e-3);
    if (prescribed) {
      EXPECT_LT(worst, 1e-12) << "every centre follows the cell";
      EXPECT_EQ(vel, 0.0);
      if (held) {
        EXPECT_EQ(spin, 0.0) << "held spins";
      } else {
        EXPECT_GT(spin, 0.0) << "the spins are free";
      }
    } else {
      EXPECT_GT(worst, 1e-6) << "free disks leave the affine field";
    }
  }
}

// A contact across a face keeps its history while one of its particles crosses the face: two
// pressed disks (plastic flattening u_max > 0) drift through the face x = W with a third disk
// balancing their momentum; the pair's history is found and unchanged after the crossing.
TEST(PeriodicDem, HistoryAcrossTheFaces) {
  packing::Packing pk;
  pk.periodic = true;
  pk.box = {0.0, 0.0, 12.0, 12.0};
  pk.x = {11.0, 0.9, 5.0};  // disks 0 and 1 overlap by 0.1 through the face x = 12
  pk.y = {6.0, 6.0, 2.0};
  pk.r = {1.0, 1.0, std::sqrt(2.0)};
  DynamicOptions o = plastic_options(kInf);
  o.plastic.damping_n = o.plastic.damping_t = 1.0;
  Particles P = periodic_particles_from<2>(pk, 1.0);
  P.vel = {0.5, 0.0, 0.5, 0.0, -0.5, 0.0};  // (vx, vy) of each: the third has the mass of the first two
  DynamicSolver s(std::move(P), o.plastic, packing::periodic_cell<2>(pk), o);
  s.run(5);
  ASSERT_NE(s.plastic_history(0, 1), nullptr);
  const double u_max = s.plastic_history(0, 1)->u_max;
  EXPECT_GT(u_max, 0.05);
  const std::size_t builds = s.rebuilds();
  while (s.particles().pos[0] < 12.5) s.step();
  EXPECT_GT(s.rebuilds(), builds) << "the table was built again after the crossing";
  ASSERT_NE(s.plastic_history(0, 1), nullptr);
  EXPECT_EQ(s.plastic_history(0, 1)->u_max, u_max);
  std::vector<std::pair<std::uint32_t, std::uint32_t>> touching;
  s.touching_pairs(touching);
  EXPECT_EQ(touching.size(), 1u) << "the pair still touches through the face";
}

// The readers and solvers that cannot use a periodic packing refuse it with one line.
TEST(PeriodicDem, Refusals) {
  const packing::Packing pk = triangular_lattice(6, 6);
  EXPECT_THROW(particles_from(pk, 1.0), std::invalid_argument);
  EXPECT_THROW(spheres_from(cubic_lattice(4), 1.0), std::invalid_argument);
  packing::Packing walled = pk;
  walled.periodic = false;
  EXPECT_THROW(periodic_particles_from<2>(walled, 1.0), std::invalid_argument);
  // a cell narrower than two interaction ranges
  const packing::Packing small = triangular_lattice(2, 2);
  DynamicOptions o = plastic_options(0.0);
  EXPECT_THROW(periodic_solver<2>(small, o), std::invalid_argument);
  // no state file and no restart in a periodic cell yet
  DynamicSolver s = periodic_solver<2>(pk, o);
  const SolverState st = s.state();
  EXPECT_TRUE(st.periodic);
  EXPECT_THROW(format_state(st), std::invalid_argument);
  EXPECT_THROW(DynamicSolver(st, o), std::invalid_argument);
}
