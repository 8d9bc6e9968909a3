// The explicit time step from the law's a-priori stiffness bound (law.hpp kHasExplicitBound,
// dem::choose_time_step): the closed form for a known pair, the a-priori bound against every
// per-contact bound the law can show, and the steps per contact of the lightest pair for each law.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <type_traits>
#include <utility>
#include <vector>

#include "netdem/contact/luding_law.hpp"
#include "netdem/contact/plastic_indentation.hpp"
#include "netdem/dynamic/solver.hpp"

using namespace netdem::dem;
namespace ct = netdem::contact;

namespace {

// Two equal particles (disks of unit depth or spheres) of radius r and density rho.
template <int D>
ParticlesT<D> pair_of(double r, double rho) {
  ParticlesT<D> P;
  if constexpr (D == 2) {
    P.add_disk(0.0, 0.0, r, rho);
    P.add_disk(3.0 * r, 0.0, r, rho);
  } else {
    P.add_sphere(0.0, 0.0, 0.0, r, rho);
    P.add_sphere(3.0 * r, 0.0, 0.0, r, rho);
  }
  return P;
}

// A polydisperse set (radii 0.5 .. 1.5) of disks or spheres.
template <int D>
ParticlesT<D> mixed() {
  ParticlesT<D> P;
  for (int i = 0; i < 12; ++i) {
    const double r = 0.5 + 0.09 * i;
    if constexpr (D == 2)
      P.add_disk(4.0 * i, 0.0, r, 1.0);
    else
      P.add_sphere(4.0 * i, 0.0, 0.0, r, 1.0);
  }
  return P;
}

template <int D>
double lightest_m12(const ParticlesT<D>& P) {
  std::vector<double> m = P.mass;
  std::sort(m.begin(), m.end());
  return m[0] * m[1] / (m[0] + m[1]);
}

template <int D>
ct::PlasticIndentationParams plastic_law() {
  ct::PlasticIndentationParams p;
  p.mu = 0.5;
  p.first_touch = 1e-4;
  return p;
}

}  // namespace

// The closed form pi sqrt(m*/k) / steps_per_contact for two equal disks (spheres), the bound k of
// each law: Luding k2 (undamped), the plastic law's first-touch chord times unload_ratio (2D) and
// 6 pi sigma_y R unload_ratio (3D, the wall contact's R* = r).
TEST(TimeStep, ClosedFormOfAKnownPair) {
  DynamicOptions o;
  o.steps_per_contact = 50.0;
  auto check = [&](auto dimension) {
    constexpr int dim = decltype(dimension)::value;
    const ParticlesT<dim> P = pair_of<dim>(1.0, 2.0);
    const double m12 = 0.5 * P.mass[0];
    ct::LudingParams lp;
    lp.gamma_n = 0.0;
    const TimeStepInfo tl = choose_time_step(P, ct::LudingLaw<ct::kLudingFull, dim>(lp, 0.0), o);
    EXPECT_DOUBLE_EQ(tl.dt, std::numbers::pi * std::sqrt(m12 / lp.k2) / 50.0) << dim;
    // alpha = 0.2: the tangential spring alpha k2 on m*/3 (2/7 m*) is slower than the normal one
    EXPECT_GT(tl.tc_tangential, tl.tc_lightest) << dim;
    const ct::PlasticIndentationParams pp = plastic_law<2>();
    const double kn = (dim == 2 ? 6.0 * pp.sigma_y / std::sqrt(pp.first_touch) : 6.0 * std::numbers::pi * pp.sigma_y * 1.0) *
                      pp.unload_ratio;
    const TimeStepInfo tp = choose_time_step(P, ct::PlasticIndentationLawT<dim>(pp), o);
    EXPECT_NEAR(tp.dt, std::numbers::pi * std::sqrt(m12 / kn) / 50.0, 1e-14 * tp.dt) << dim;
    EXPECT_EQ(tp.tc_tangential, 0.0) << dim;  // no contact area yet
    // a contact width A: the tangential spring k_t sigma_y A on the tangential mass m*/3 (2/7 m*)
    const double A = 0.3, kt = pp.k_t * pp.sigma_y * A, mt = dim == 2 ? m12 / 3.0 : m12 * 2.0 / 7.0;
    const TimeStepInfo ta = choose_time_step(P, ct::PlasticIndentationLawT<dim>(pp), o, A);
    EXPECT_NEAR(ta.tc_tangential, std::numbers::pi * std::sqrt(mt / kt), 1e-14 * ta.tc_tangential) << dim;
    EXPECT_NEAR(ta.dt, std::min(tp.tc_lightest, ta.tc_tangential) / 50.0, 1e-14 * ta.dt) << dim;
  };
  check(std::integral_constant<int, 2>{});
  check(std::integral_constant<int, 3>{});
}

// A Luding tangential spring stiffer than the normal one on the tangential mass (alpha = 0.5 > 1/3
// for disks): the tangential period sets the step, so that it, too, gets steps_per_contact steps.
TEST(TimeStep, StiffTangentialSpringSetsTheStep) {
  const Particles P = pair_of<2>(1.0, 1.0);
  const double m12 = 0.5 * P.mass[0];
  ct::LudingParams lp;
  lp.gamma_n = 0.0;
  lp.alpha = 0.5;
  DynamicOptions o;
  const TimeStepInfo ts = choose_time_step(P, ct::LudingLaw<ct::kLudingFull, 2>(lp, 0.0), o);
  EXPECT_LT(ts.tc_tangential, ts.tc_lightest);
  EXPECT_NEAR(ts.dt, std::numbers::pi * std::sqrt(m12 / 3.0 / (lp.alpha * lp.k2)) / o.steps_per_contact, 1e-14 * ts.dt);
  EXPECT_NEAR(ts.steps_per_contact_lightest, o.steps_per_contact, 1e-9);
}

// The a-priori bound covers every per-contact bound of the law (stiffness_bound(h, k) over
// overlaps and flattening histories of contacts of R* up to r_max), so that the chosen step gives
// the lightest pair at least steps_per_contact steps per period of its stiffest contact.
template <int D>
void check_plastic_bound_covers_contacts() {
  const ct::PlasticIndentationParams pp = plastic_law<D>();
  const ct::PlasticIndentationLawT<D> law(pp);
  const ParticlesT<D> P = mixed<D>();
  const double r_max = *std::max_element(P.r.begin(), P.r.end());
  const ct::StiffnessBound b = law.stiffness_bound(r_max);
  double kn_seen = 0.0;
  for (double r_eff : {0.25, 0.5 * r_max, r_max}) {
    const double uc = pp.first_touch * 2.0 * r_eff;
    for (double u_max : {0.0, 0.3 * uc, 0.99 * uc, uc, 3.0 * uc, 0.01 * r_eff})
      for (double u : {0.1 * uc, 0.5 * uc, 0.999 * uc, 2.0 * uc, u_max, 0.02 * r_eff}) {
        ct::PlasticIndentationHistoryT<D> h;
        h.u_max = u_max;
        ct::Kinematics<D> k;
        k.overlap = u;
        k.r_eff = r_eff;
        const ct::StiffnessBound c = law.stiffness_bound(h, k);
        kn_seen = std::max(kn_seen, c.k_n);
        EXPECT_LE(c.k_n, b.k_n * (1.0 + 1e-12)) << "D " << D << " R* " << r_eff << " u_max " << u_max << " u " << u;
        // the tangential spring at this contact's force: k_t sigma_y A_c(f)
        double f, kk;
        ct::NormalBranch br;
        ct::normal_force<D>(pp, r_eff, u_max, u, f, kk, br);
        EXPECT_LE(c.k_t, b.k_t_area * law.contact_area(f) * (1.0 + 1e-12));
      }
  }
  EXPECT_GT(kn_seen, 0.5 * b.k_n) << D;  // the bound is not far above the stiffest contact
  DynamicOptions o;
  const TimeStepInfo ts = choose_time_step(P, law, o, law.contact_area(1.0));
  const double m12 = lightest_m12(P);
  const double t_n = std::numbers::pi * std::sqrt(m12 / kn_seen);
  EXPECT_GE(t_n / ts.dt, o.steps_per_contact * (1.0 - 1e-12)) << D;
  EXPECT_GE(ts.steps_per_contact_lightest, o.steps_per_contact * (1.0 - 1e-12)) << D;
  EXPECT_GE(ts.steps_per_contact_lightest, o.min_steps_per_contact) << D;
}

TEST(TimeStep, PlasticBoundCoversEveryContact2D) { check_plastic_bound_covers_contacts<2>(); }
TEST(TimeStep, PlasticBoundCoversEveryContact3D) { check_plastic_bound_covers_contacts<3>(); }

// The Luding law: the mean-pair rule (Eq 6) gives the lightest pair fewer than 50 steps but at
// least min_steps_per_contact; the lightest-pair rule 50. A fixed dt below the minimum is refused.
TEST(TimeStep, LudingLightestPairSteps) {
  auto check = [&](auto dimension) {
    constexpr int dim = decltype(dimension)::value;
    const ParticlesT<dim> P = mixed<dim>();
    ct::LudingParams lp;
    lp.gamma_n = 0.0;
    DynamicOptions o;
    auto choose = [&](const DynamicOptions& oo) {
      return choose_time_step(P, ct::LudingLaw<ct::kLudingFull, dim>(lp, 0.0), oo);
    };
    const TimeStepInfo mean = choose(o);
    const double t_light = std::numbers::pi * std::sqrt(lightest_m12(P) / lp.k2);
    EXPECT_NEAR(mean.steps_per_contact_lightest, t_light / mean.dt, 1e-9);
    EXPECT_LT(mean.steps_per_contact_lightest, o.steps_per_contact);
    EXPECT_GE(mean.steps_per_contact_lightest, o.min_steps_per_contact);
    o.rule = TimeStepRule::LightestPair;
    EXPECT_NEAR(choose(o).dt, t_light / o.steps_per_contact, 1e-14 * t_light);
    o.dt = t_light / 9.0;
    EXPECT_THROW((void)choose(o), std::invalid_argument);
  };
  check(std::integral_constant<int, 2>{});
  check(std::integral_constant<int, 3>{});
}

// The plastic law ignores the mean-pair rule (its bound is for the lightest pair: the law has no
// kMeanPairTimeStep), and a law without a finite normal bound (first_touch = 0) is refused.
TEST(TimeStep, PlasticLawBoundsTheLightestPair) {
  const Particles P = mixed<2>();
  const ct::PlasticIndentationParams pp = plastic_law<2>();
  DynamicOptions o;
  o.rule = TimeStepRule::MeanPair;
  const TimeStepInfo a = choose_time_step(P, ct::PlasticIndentationLawT<2>(pp), o);
  o.rule = TimeStepRule::LightestPair;
  const TimeStepInfo b = choose_time_step(P, ct::PlasticIndentationLawT<2>(pp), o);
  EXPECT_EQ(a.dt, b.dt);
  EXPECT_NEAR(a.steps_per_contact_lightest, o.steps_per_contact, 1e-9);
  ct::PlasticIndentationParams sharp = pp;
  sharp.first_touch = 0.0;
  EXPECT_THROW((void)choose_time_step(P, ct::PlasticIndentationLawT<2>(sharp), o), std::invalid_argument);
}

// In a run: a frictional plastic packing compressed by its affine walls (the contacts flatten, so
// the tangential spring k_t sigma_y A_c grows and the step follows it). At every step each touching
// pair's own stiffnesses from the law's per-contact bound (stiffness_bound(h, k) at its current
// overlap and history) get at least steps_per_contact steps per period on the pair's masses, and
// the step shrinks as the contacts grow.
TEST(TimeStep, EveryContactOfARunIsResolved) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Particles P;
  const int side = 6;
  for (int j = 0; j < side; ++j)
    for (int i = 0; i < side; ++i)
    {  // the draws in a fixed order (GCC's: a call's arguments are evaluated in an unspecified order)
      const double r = 0.97 + 0.03 * u(rng), y = 1.0 + 2.0 * j + 0.02 * u(rng), x = 1.0 + 2.0 * i + 0.02 * u(rng);
      P.add_disk(x, y, r, 1.0);
    }
  Box box;
  box.x_max = box.y_max = 2.0 * side;
  box.right.mode = box.top.mode = WallMode::Affine;
  ct::PlasticIndentationParams law;
  law.mu = 0.5;
  law.first_touch = 1e-4;
  law.damping_n = law.damping_t = 0.3;
  law.reversible = true;  // the normal bound is the chord 6 sigma_y / sqrt(first_touch) = 600
  DynamicOptions o;
  DynamicSolver s(P, law, box, o);
  s.set_strain_rate(-0.04, -0.04);
  s.set_affine_velocities();
  const ct::PlasticIndentationLawT<2> pl(law);
  const double dt0 = s.dt();
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
  double worst = 1e300, kt_max = 0.0;
  for (int step = 0; step < 3000; ++step) {
    s.step();
    s.touching_pairs(pairs);
    const Particles& Q = s.particles();
    for (const auto& [i, j] : pairs) {
      const ct::PlasticIndentationHistory* h = s.plastic_history(i, j);
      ASSERT_NE(h, nullptr);
      ct::ContactKinematics k;
      const double dx = Q.coord(j, 0) - Q.coord(i, 0), dy = Q.coord(j, 1) - Q.coord(i, 1);
      k.overlap = Q.r[i] + Q.r[j] - std::sqrt(dx * dx + dy * dy);
      k.r_eff = Q.r[i] * Q.r[j] / (Q.r[i] + Q.r[j]);
      const double m = Q.mass[i] * Q.mass[j] / (Q.mass[i] + Q.mass[j]);
      const ct::StiffnessBound b = pl.stiffness_bound(*h, k);
      kt_max = std::max(kt_max, b.k_t);
      const double t_n = std::numbers::pi * std::sqrt(m / b.k_n);
      const double t_t = b.k_t > 0.0 ? std::numbers::pi * std::sqrt(m / 3.0 / b.k_t) : 1e300;
      worst = std::min(worst, std::min(t_n, t_t) / s.dt());
    }
  }
  std::printf("  dt %.4g -> %.4g, largest tangential spring %.4g, fewest steps per period of a contact %.1f\n", dt0,
              s.dt(), kt_max, worst);
  EXPECT_GT(kt_max, 0.0);
  EXPECT_LT(s.dt(), dt0);  // the tangential spring of the flattened contacts now sets the step
  EXPECT_GE(worst, o.steps_per_contact * (1.0 - 1e-9));
}
