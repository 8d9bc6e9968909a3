// The law-agnostic conformance suite of the contact-law interface (law.hpp): every law of the
// toolkit, in each of its configurations, passes the same tests.
//  * Tangent: the consistent tangent equals central finite differences of evaluate() in every
//    regime the law has (each regime must be visited by the load path, or the test fails).
//  * Coulomb: |f_t| never exceeds the law's friction limit.
//  * First touch: the force is continuous at first touch (f -> 0 as the overlap -> 0+).
//  * Dissipation: the work done on the contact over closed load paths (from first touch to
//    separation) is >= 0.
//  * Objectivity: a rigid rotation plus translation of a loaded pair changes no force magnitude and
//    gives no slip.
//  * In place: a law's in-place update() equals evaluate() to the last bit.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "netdem/contact/element.hpp"
#include "netdem/contact/law.hpp"
#include "netdem/contact/luding_law.hpp"
#include "netdem/contact/plastic_indentation.hpp"

using namespace netdem::contact;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// ---- the laws under test: one fixture per configuration ---------------------------------------
// Each fixture gives the law, its length scale (typical overlap), R*, the friction limit of a
// response, and the regimes (branch code, sliding) its load path must visit.
using Regime = std::pair<int, bool>;

template <class L>
struct FixtureBase {
  using Law = L;
  using History = typename L::History;
  using Response = ContactResponse<History>;
};

struct PlasticElastic : FixtureBase<PlasticIndentationLaw> {  // yield: section 3.4 unloading, mu = inf
  static constexpr const char* kName = "plastic, elastic unloading, mu = inf";
  static Law make() {
    PlasticIndentationParams p;
    p.reversible = false;
    p.unload_ratio = 10.0;  // a softer unloading line keeps the elastic branch wide on the path
    return Law(p);
  }
  static double scale() { return 1e-2; }
  static double r_eff() { return 0.5; }
  static double v_scale() { return 0.0; }  // rate-independent
  static double limit(const Law& l, const History&, const ContactKinematics&, const Response& r) {
    return l.params().mu_eff() * r.f_n;
  }
  static std::set<Regime> regimes() {
    return {{0, false}, {int(NormalBranch::Plastic), false}, {int(NormalBranch::Plastic), true},
            {int(NormalBranch::Elastic), false}, {int(NormalBranch::Elastic), true}};
  }
};
struct PlasticReversibleCoulomb : FixtureBase<PlasticIndentationLaw> {  // compaction law, mu = 0.1
  static constexpr const char* kName = "plastic, reversible, mu = 0.1";
  static Law make() {
    PlasticIndentationParams p;
    p.reversible = true;
    p.mu = 0.1;
    return Law(p);
  }
  static double scale() { return 1e-2; }
  static double r_eff() { return 0.45; }
  static double v_scale() { return 0.0; }
  static double limit(const Law& l, const History&, const ContactKinematics&, const Response& r) {
    return l.params().mu_eff() * r.f_n;
  }
  static std::set<Regime> regimes() {
    return {{0, false}, {int(NormalBranch::Plastic), false}, {int(NormalBranch::Plastic), true}};
  }
};
struct PlasticFrictionless : FixtureBase<PlasticIndentationLaw> {
  static constexpr const char* kName = "plastic, elastic unloading, mu = 0";
  static Law make() {
    PlasticIndentationParams p;
    p.reversible = false;
    p.mu = 0.0;
    p.unload_ratio = 10.0;
    return Law(p);
  }
  static double scale() { return 1e-2; }
  static double r_eff() { return 0.5; }
  static double v_scale() { return 0.0; }
  static double limit(const Law&, const History&, const ContactKinematics&, const Response&) { return 0.0; }
  static std::set<Regime> regimes() {
    return {{0, false}, {int(NormalBranch::Plastic), false}, {int(NormalBranch::Elastic), false}};
  }
};

struct PlasticDamped : FixtureBase<PlasticIndentationLaw> {  // the explicit solver's law: dashpots
  static constexpr const char* kName = "plastic, elastic unloading, mu = 0.3, dashpots";
  static Law make() {
    PlasticIndentationParams p;
    p.reversible = false;
    p.mu = 0.3;
    p.unload_ratio = 10.0;
    p.damping_n = 0.5;
    p.damping_t = 0.5;
    return Law(p);
  }
  static double scale() { return 1e-2; }
  static double r_eff() { return 0.5; }
  static double v_scale() { return 0.3; }  // dashpot forces comparable to the spring forces
  static double limit(const Law& l, const History& h, const ContactKinematics& k, const Response& r) {
    // min(mu F_N, A_c tau_y) with A_c from the spring force (the undamped law)
    const double fs = netdem::contact::evaluate(l.params(), h, k.r_eff, k.overlap, k.dslip).f_n;
    return std::fmin(l.params().mu * r.f_n, fs / (3.0 * std::sqrt(3.0)));
  }
  static std::set<Regime> regimes() {
    return {{0, false}, {int(NormalBranch::Plastic), false}, {int(NormalBranch::Plastic), true},
            {int(NormalBranch::Elastic), false}, {int(NormalBranch::Elastic), true}};
  }
};

// The Luding law holds its parameters by reference: each fixture keeps them in a static.
template <LudingFeatures F>
struct LudingFixture : FixtureBase<LudingLaw<F>> {
  using Base = FixtureBase<LudingLaw<F>>;
  using typename Base::History;
  using typename Base::Response;
  static double scale() { return 4e-5; }  // m (a0 = 1 mm)
  static double r_eff() { return 5e-4; }
  static double v_scale() { return 1e-3; }  // m/s: the dashpots act
  // LMM05 Eq 14: f_C = mu (f_n - f_min), on the damped normal force before footnote 5
  static double limit(const LudingLaw<F>& l, const History& h, const ContactKinematics& k,
                      const Response& r) {
    const LudingResult lr = luding_evaluate<F>(l.params(), h, l.input(k));
    return F.friction ? lr.mu * std::fmax(std::fmax(r.f_n, lr.f_n) - lr.f_min, 0.0) : 0.0;
  }
};
struct LudingTable1 : LudingFixture<kLudingFull> {  // Table 1 at 80 deg C, delta_fluid lowered
  static constexpr const char* kName = "Luding, Table 1 (hysteresis, Eq 7, cohesion, k1(T), friction)";
  static const LudingParams& params() {
    static const LudingParams p = [] {
      LudingParams q;
      q.delta_fluid_rel = 0.05;  // 50 um: the path reaches the fluid limit
      return q;
    }();
    return p;
  }
  static Law make() { return Law(params(), 0.8 * params().k1()); }
  static std::set<Regime> regimes() {
    return {{0, false},
            {int(LudingBranch::Loading), false}, {int(LudingBranch::Loading), true},
            {int(LudingBranch::Line), false},    {int(LudingBranch::Line), true},
            {int(LudingBranch::Cohesive), false}, {int(LudingBranch::Cohesive), true},
            {int(LudingBranch::Fluid), false}};
  }
};
constexpr LudingFeatures kHystereticOnly{true, false, false, true};
struct LudingHysteretic : LudingFixture<kHystereticOnly> {
  static constexpr const char* kName = "Luding, hysteresis without cohesion or temperature";
  static const LudingParams& params() {
    static const LudingParams p;
    return p;
  }
  static Law make() { return Law(params(), 0.0); }
  static std::set<Regime> regimes() {
    return {{0, false}, {int(LudingBranch::Loading), false}, {int(LudingBranch::Loading), true},
            {int(LudingBranch::Line), false}, {int(LudingBranch::Line), true}};
  }
};
struct LudingLinear : LudingFixture<kLudingLinear> {
  static constexpr const char* kName = "Luding, linear spring-dashpot";
  static const LudingParams& params() {
    static const LudingParams p = [] {
      LudingParams q;
      q.k1_ratio = 1.0;
      q.kc_ratio = 0.0;
      return q;
    }();
    return p;
  }
  static Law make() { return Law(params(), 0.0); }
  static std::set<Regime> regimes() {
    return {{0, false}, {int(LudingBranch::Line), false}, {int(LudingBranch::Line), true}};
  }
};

// The fields of a history as numbers (for bitwise comparison without padding bytes).
std::array<double, 3> fields(const PlasticIndentationHistory& h) { return {h.u_max, h.f_t, double(h.sliding)}; }
std::array<double, 7> fields(const LudingHistory& h) {
  return {h.delta_max, h.delta0, h.k2_line, h.k1_seen, h.xi, double(h.fluid), double(h.sliding)};
}

// ---- a load path: a random walk in (overlap, slip) that loads, unloads, reloads and separates ----
template <class Fx>
std::vector<ContactKinematics> load_path(unsigned seed, int n) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double s = Fx::scale(), dt = 1e-4;
  std::vector<ContactKinematics> path;
  // phases of 97 steps, each towards a random target overlap in [-0.5, 3.5] s (load, unload,
  // reload, separate), with noise
  double overlap = -0.1 * s, target = 0.0;
  for (int i = 0; i < n; ++i) {
    if (i % 97 == 0) target = s * (-0.5 + 4.0 * (0.5 + 0.5 * u(rng)));
    ContactKinematics k;
    k.overlap_start = overlap;
    overlap += 0.05 * (target - overlap) + 0.02 * s * u(rng);
    k.overlap = overlap;
    // slip: bursts of one sign (gross slip) and small oscillations (stick)
    k.dslip = (i % 53 < 20 ? 0.3 : 0.01) * s * u(rng);
    k.r_eff = Fx::r_eff();
    k.m_eff = 1.0;
    k.dt = Fx::v_scale() > 0.0 ? dt : 0.0;
    k.v_n = Fx::v_scale() * u(rng);
    k.v_t = Fx::v_scale() * u(rng);
    path.push_back(k);
  }
  return path;
}

template <class Fx>
class LawConformance : public ::testing::Test {};

using Fixtures = ::testing::Types<PlasticElastic, PlasticReversibleCoulomb, PlasticFrictionless, PlasticDamped,
                                  LudingTable1, LudingHysteretic, LudingLinear>;
TYPED_TEST_SUITE(LawConformance, Fixtures);

// The consistent tangent against central differences in the end overlap and the slip increment
// (rates held), at every state of the path whose branch and slip status are the same on both
// sides of the difference; every regime of the fixture is visited.
TYPED_TEST(LawConformance, TangentMatchesFiniteDifferencesInEveryRegime) {
  using Fx = TypeParam;
  const auto law = Fx::make();
  std::set<Regime> seen;
  int checked = 0;
  for (unsigned seed : {1u, 2u, 3u}) {
    typename Fx::History h{};
    for (const ContactKinematics& k : load_path<Fx>(seed, 3000)) {
      ContactTangent t;
      const auto r = law.evaluate(h, k, &t);
      const Regime rg{r.branch, r.sliding};
      if (r.loaded) {
        const double hu = 1e-6 * std::fmin(Fx::scale(), std::fabs(k.overlap));
        const double hs = 1e-6 * Fx::scale();
        auto at = [&](double du, double ds) {
          ContactKinematics q = k;
          q.overlap += du;
          q.dslip += ds;
          return law.evaluate(h, q, nullptr);
        };
        const auto up = at(hu, 0), um = at(-hu, 0), sp = at(0, hs), sm = at(0, -hs);
        auto same = [&](const auto& a) { return a.branch == r.branch && a.sliding == r.sliding; };
        if (same(up) && same(um) && same(sp) && same(sm)) {
          const double fd[4] = {(up.f_n - um.f_n) / (2 * hu), (sp.f_n - sm.f_n) / (2 * hs),
                                (up.f_t - um.f_t) / (2 * hu), (sp.f_t - sm.f_t) / (2 * hs)};
          const double an[4] = {t.dfn_dun, t.dfn_dslip, t.dft_dun, t.dft_dslip};
          double ref = (std::fabs(r.f_n) + std::fabs(r.f_t)) / Fx::scale();
          for (int c = 0; c < 4; ++c) ref = std::fmax(ref, std::fabs(fd[c]));
          for (int c = 0; c < 4; ++c)
            ASSERT_NEAR(an[c], fd[c], 1e-4 * ref)
                << Fx::kName << ": derivative " << c << " branch " << int(r.branch) << " sliding "
                << r.sliding << " overlap " << k.overlap;
          ++checked;
          seen.insert(rg);
        }
      } else {
        EXPECT_EQ(r.f_n, 0.0);
        EXPECT_EQ(r.f_t, 0.0);
        seen.insert(rg);
      }
      h = r.history;
    }
  }
  for (const Regime& want : Fx::regimes())
    EXPECT_TRUE(seen.count(want)) << Fx::kName << ": regime (branch " << want.first << ", sliding "
                                  << want.second << ") not visited";
  std::printf("  %s: %d states checked, %zu regimes\n", Fx::kName, checked, seen.size());
  EXPECT_GT(checked, 1000);
}

// |f_t| <= the friction limit at every state of the path.
TYPED_TEST(LawConformance, CoulombConeNeverExceeded) {
  using Fx = TypeParam;
  const auto law = Fx::make();
  int on_limit = 0;
  for (unsigned seed : {4u, 5u}) {
    typename Fx::History h{};
    for (const ContactKinematics& k : load_path<Fx>(seed, 4000)) {
      const auto r = law.evaluate(h, k, nullptr);
      const double lim = Fx::limit(law, h, k, r);
      ASSERT_LE(std::fabs(r.f_t), lim * (1.0 + 1e-12) + 1e-300) << Fx::kName;
      on_limit += r.sliding;
      h = r.history;
    }
  }
  if (law.params().mu > 0.0) { EXPECT_GT(on_limit, 10) << Fx::kName; }  // the limit was reached
}

// From a fresh history, the force at overlap eps -> 0+ goes to 0 (no jump at first touch), with
// the rates zero (a dashpot's force at touch is the rate's, not the law's).
TYPED_TEST(LawConformance, ForceContinuousAtFirstTouch) {
  using Fx = TypeParam;
  const auto law = Fx::make();
  ContactKinematics k;
  k.r_eff = Fx::r_eff();
  k.overlap = Fx::scale();
  const double f_ref = law.evaluate({}, k, nullptr).f_n;
  ASSERT_GT(f_ref, 0.0);
  double prev = f_ref;
  for (double e : {1e-2, 1e-4, 1e-6, 1e-8, 1e-10, 1e-12}) {
    k.overlap = e * Fx::scale();
    k.overlap_start = 0.0;
    const auto r = law.evaluate({}, k, nullptr);
    EXPECT_TRUE(r.loaded);
    EXPECT_LT(std::fabs(r.f_n), prev) << Fx::kName << " eps " << e;
    prev = std::fabs(r.f_n);
  }
  EXPECT_LT(prev, 1e-5 * f_ref) << Fx::kName;  // f(1e-12 u) / f(u) <= sqrt(1e-12) for Eq 2
  k.overlap = -1e-12 * Fx::scale();
  const auto open = law.evaluate({}, k, nullptr);
  EXPECT_FALSE(open.loaded);
  EXPECT_EQ(open.f_n, 0.0);
}

// Closed load paths from first touch to separation, at zero rates: the work done on the contact,
// W = integral of f_n du_N - f_t dslip (trapezoidal, fine steps), is >= 0 (no energy created).
TYPED_TEST(LawConformance, DissipationNonNegativeOverClosedPaths) {
  using Fx = TypeParam;
  const auto law = Fx::make();
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double s = Fx::scale();
  double w_min = kInf, w_max = -kInf;
  for (int path = 0; path < 40; ++path) {
    // corners of a polygon in (overlap, slip): touch, load with slip, unload, reload, separate
    const double umax = s * (0.5 + 4.0 * u(rng)), smax = s * (2.0 * u(rng) - 1.0);
    const double corners[6][2] = {{-0.01 * s, 0.0},     {umax, smax},
                                  {0.5 * umax, -smax},  {0.9 * umax, 0.5 * smax},
                                  {0.3 * umax, 0.0},    {-0.1 * s, 0.0}};
    typename Fx::History h{};
    double w = 0.0, f_n0 = 0.0, f_t0 = 0.0, un = corners[0][0];
    for (int c = 0; c + 1 < 6; ++c) {
      const int m = 4000;
      for (int q = 1; q <= m; ++q) {
        const double a = static_cast<double>(q) / m;
        ContactKinematics k;
        k.r_eff = Fx::r_eff();
        k.overlap_start = un;
        k.overlap = corners[c][0] + a * (corners[c + 1][0] - corners[c][0]);
        k.dslip = (corners[c + 1][1] - corners[c][1]) / m;
        const auto r = law.evaluate(h, k, nullptr);
        w += 0.5 * (r.f_n + f_n0) * (k.overlap - un) - 0.5 * (r.f_t + f_t0) * k.dslip;
        f_n0 = r.f_n;
        f_t0 = r.f_t;
        un = k.overlap;
        h = r.history;
      }
    }
    EXPECT_EQ(f_n0, 0.0);  // separated: no stored energy left
    const double f_scale = law.evaluate({}, [&] {
      ContactKinematics k;
      k.r_eff = Fx::r_eff();
      k.overlap = umax;
      return k;
    }(), nullptr).f_n;
    const double w_rel = w / (f_scale * umax);
    w_min = std::fmin(w_min, w_rel);
    w_max = std::fmax(w_max, w_rel);
    EXPECT_GE(w_rel, -1e-3) << Fx::kName << " path " << path;  // trapezoidal error O(1/m^2)
  }
  std::printf("  %s: W / (F(u_max) u_max) in [%.3e, %.3e]\n", Fx::kName, w_min, w_max);
}

// A loaded pair with a tangential force moved rigidly (rotation by 0.7 rad about an arbitrary
// point and a translation): no slip, the same force magnitudes, the force vector rotated with the
// pair; and the same for every intermediate angle.
TYPED_TEST(LawConformance, ObjectiveUnderRigidMotion) {
  using Fx = TypeParam;
  const auto law = Fx::make();
  const double s = Fx::scale();
  // radii with R* = r_eff: r_i = 2 r_eff, r_j = 2 r_eff
  const double ri = 2.0 * Fx::r_eff(), rj = 2.0 * Fx::r_eff();
  const Vec xi0(0.3 * ri, -0.2 * ri);
  const Vec xj0 = xi0 + Vec(std::cos(0.4), std::sin(0.4)) * (ri + rj - 2.0 * s);
  PairGeometry g = pair_geometry(xi0, xj0, ri, rj);
  // load: approach from touch to 2 s with a slip, then one more step to get f_t != 0
  typename Fx::History h{};
  {
    const PairGeometry gt = pair_geometry(xi0, xi0 + g.n * (ri + rj), ri, rj);
    PairElement<typename Fx::Law> e;
    const Vec xj1 = xj0 + g.t * (0.005 * s);
    pair_element(law, h, gt, pair_geometry(xi0, xj1, ri, rj), 0.0, 0.0, e);
    h = e.law.history;
    g = pair_geometry(xi0, xj1, ri, rj);
  }
  PairElement<typename Fx::Law> e0;
  pair_element(law, h, g, g, 0.0, 0.0, e0);
  ASSERT_TRUE(e0.law.loaded);
  if (law.params().mu > 0.0) { ASSERT_NE(e0.law.f_t, 0.0) << Fx::kName; }
  const Vec pivot(-3.0 * ri, 5.0 * ri), shift(7.0 * ri, -2.0 * ri);
  for (double ang : {1e-3, 0.1, 0.7, 2.5, -1.2}) {
    const Eigen::Rotation2Dd R(ang);
    const Vec xi1 = pivot + R * (xi0 - pivot) + shift;
    const Vec xj1 = pivot + R * (g.n * g.L + xi0 - pivot) + shift;
    const PairGeometry g1 = pair_geometry(xi1, xj1, ri, rj);
    PairElement<typename Fx::Law> e;
    pair_element(law, h, g, g1, ang, ang, e);
    EXPECT_NEAR(e.dslip, 0.0, 1e-12 * s) << Fx::kName << " angle " << ang;
    EXPECT_NEAR(e.law.f_n, e0.law.f_n, 1e-9 * std::fabs(e0.law.f_n)) << Fx::kName;
    EXPECT_NEAR(e.law.f_t, e0.law.f_t, 1e-9 * std::fabs(e0.law.f_n)) << Fx::kName;
    EXPECT_EQ(e.law.sliding, e0.law.sliding);
    // the force on j rotates with the pair
    const Vec f0(e0.force(3), e0.force(4)), f1(e.force(3), e.force(4));
    EXPECT_LT((R * f0 - f1).norm(), 1e-9 * f0.norm()) << Fx::kName;
  }
}

// The in-place update() of a law (where it has one) against evaluate(): the same forces and
// histories to the last bit over thousands of steps.
TYPED_TEST(LawConformance, InPlaceUpdateEqualsEvaluate) {
  using Fx = TypeParam;
  const auto law = Fx::make();
  typename Fx::History h1{}, h2{};
  int n = 0;
  for (const ContactKinematics& k : load_path<Fx>(9, 5000)) {
    double fn1, ft1, fn2, ft2;
    update_contact<true>(law, h1, k, fn1, ft1);
    update_contact<false>(law, h2, k, fn2, ft2);
    ASSERT_EQ(std::memcmp(&fn1, &fn2, sizeof fn1), 0) << Fx::kName << " step " << n;
    ASSERT_EQ(std::memcmp(&ft1, &ft2, sizeof ft1), 0) << Fx::kName << " step " << n;
    const auto a = fields(h1), b = fields(h2);
    ASSERT_EQ(std::memcmp(a.data(), b.data(), sizeof(double) * a.size()), 0) << Fx::kName << " step " << n;
    ++n;
  }
}

// The interface's answers that the solvers rely on.
TYPED_TEST(LawConformance, StiffnessBoundAndIterationStiffness) {
  using Fx = TypeParam;
  const auto law = Fx::make();
  typename Fx::History h{};
  for (const ContactKinematics& k : load_path<Fx>(11, 3000)) {
    ContactTangent t;
    const auto r = law.evaluate(h, k, &t);
    const StiffnessBound b = law.stiffness_bound(h, k);
    const IterationStiffness is = law.iteration_stiffness(h, k, r);
    if (r.loaded) {
      // the bound covers the tangent of the step (the first-touch singularity of Eq 2 excepted)
      if (k.overlap > 1e-3 * Fx::scale()) { EXPECT_GE(b.k_n * (1 + 1e-12), std::fabs(t.dfn_dun)) << Fx::kName; }
      if (!r.sliding) { EXPECT_GE(b.k_t * (1 + 1e-12), std::fabs(t.dft_dslip)) << Fx::kName; }
      EXPECT_GE(is.k_n_add, 0.0);
      EXPECT_GE(t.dfn_dun + is.k_n_add, 0.0) << Fx::kName;  // a non-negative normal stiffness
      EXPECT_GE(is.k_t, 0.0);
      // a sticking spring: the iteration matrix takes the tangent's spring
      if (!r.sliding && r.f_t != 0.0) { EXPECT_NEAR(is.k_t, -t.dft_dslip, 1e-12 * is.k_t) << Fx::kName; }
    }
    h = r.history;
    if (r.loaded) { EXPECT_TRUE(law.has_history(h)) << Fx::kName; }  // a loaded contact has a history
  }
  EXPECT_FALSE(law.has_history(typename Fx::History{})) << Fx::kName;
}

}  // namespace
