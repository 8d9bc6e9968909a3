// The law-agnostic conformance suite of the contact-law interface (law.hpp): every law of the
// toolkit, in each of its configurations and in both dimensions (2D disks, 3D spheres), passes the
// same tests.
//  * Tangent: the consistent tangent equals central finite differences of evaluate() in every
//    regime the law has (each regime must be visited by the load path, or the test fails).
//  * Coulomb: |f_t| never exceeds the law's friction limit.
//  * First touch: the force is continuous at first touch (f -> 0 as the overlap -> 0+).
//  * Dissipation: the work done on the contact over closed load paths (from first touch to
//    separation) is >= 0.
//  * Objectivity: a rigid rotation plus translation of a loaded pair changes no force magnitude and
//    gives no slip (3D: about any axis, the tangential force turning with the pair).
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
#include "netdem/contact/kinematics.hpp"
#include "netdem/contact/law.hpp"
#include "netdem/contact/luding_law.hpp"
#include "netdem/contact/plastic_indentation.hpp"

using namespace netdem::contact;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// ---- the laws under test: one fixture per configuration and dimension --------------------------
// Each fixture gives the law, its length scale (typical overlap), R*, the friction limit of a
// response, and the regimes (branch code, sliding) its load path must visit. Every fixture exists
// for D = 2 (disks) and D = 3 (spheres): the same law template, instantiated twice (dim.hpp).
using Regime = std::pair<int, bool>;

template <class L>
struct FixtureBase {
  using Law = L;
  static constexpr int D = L::kDim;
  using History = typename L::History;
  using Response = ContactResponse<History, D>;
  using Kin = Kinematics<D>;
  using Tan = typename Dim<D>::Tan;
};
inline std::string dim_name(const char* name, int D) { return std::string(name) + (D == 3 ? " [3D]" : " [2D]"); }

template <int Dm>
struct PlasticElastic : FixtureBase<PlasticIndentationLawT<Dm>> {  // yield: section 3.4 unloading, mu = inf
  using B = FixtureBase<PlasticIndentationLawT<Dm>>;
  static std::string name() { return dim_name("plastic, elastic unloading, mu = inf", Dm); }
  static typename B::Law make() {
    PlasticIndentationParams p;
    p.reversible = false;
    p.unload_ratio = 10.0;  // a softer unloading line keeps the elastic branch wide on the path
    return typename B::Law(p);
  }
  static double scale() { return 1e-2; }
  static double r_eff() { return 0.5; }
  static double v_scale() { return 0.0; }  // rate-independent
  static double limit(const typename B::Law& l, const typename B::History&, const typename B::Kin&,
                      const typename B::Response& r) {
    return l.params().mu_eff() * r.f_n;
  }
  static std::set<Regime> regimes() {
    return {{0, false}, {int(NormalBranch::Plastic), false}, {int(NormalBranch::Plastic), true},
            {int(NormalBranch::Elastic), false}, {int(NormalBranch::Elastic), true}};
  }
};
template <int Dm>
struct PlasticReversibleCoulomb : FixtureBase<PlasticIndentationLawT<Dm>> {  // compaction law, mu = 0.1
  using B = FixtureBase<PlasticIndentationLawT<Dm>>;
  static std::string name() { return dim_name("plastic, reversible, mu = 0.1", Dm); }
  static typename B::Law make() {
    PlasticIndentationParams p;
    p.reversible = true;
    p.mu = 0.1;
    return typename B::Law(p);
  }
  static double scale() { return 1e-2; }
  static double r_eff() { return 0.45; }
  static double v_scale() { return 0.0; }
  static double limit(const typename B::Law& l, const typename B::History&, const typename B::Kin&,
                      const typename B::Response& r) {
    return l.params().mu_eff() * r.f_n;
  }
  static std::set<Regime> regimes() {
    return {{0, false}, {int(NormalBranch::Plastic), false}, {int(NormalBranch::Plastic), true}};
  }
};
template <int Dm>
struct PlasticFrictionless : FixtureBase<PlasticIndentationLawT<Dm>> {
  using B = FixtureBase<PlasticIndentationLawT<Dm>>;
  static std::string name() { return dim_name("plastic, elastic unloading, mu = 0", Dm); }
  static typename B::Law make() {
    PlasticIndentationParams p;
    p.reversible = false;
    p.mu = 0.0;
    p.unload_ratio = 10.0;
    return typename B::Law(p);
  }
  static double scale() { return 1e-2; }
  static double r_eff() { return 0.5; }
  static double v_scale() { return 0.0; }
  static double limit(const typename B::Law&, const typename B::History&, const typename B::Kin&,
                      const typename B::Response&) {
    return 0.0;
  }
  static std::set<Regime> regimes() {
    return {{0, false}, {int(NormalBranch::Plastic), false}, {int(NormalBranch::Elastic), false}};
  }
};

template <int Dm>
struct PlasticDamped : FixtureBase<PlasticIndentationLawT<Dm>> {  // the explicit solver's law: dashpots
  using B = FixtureBase<PlasticIndentationLawT<Dm>>;
  static std::string name() { return dim_name("plastic, elastic unloading, mu = 0.3, dashpots", Dm); }
  static typename B::Law make() {
    PlasticIndentationParams p;
    p.reversible = false;
    p.mu = 0.3;
    p.unload_ratio = 10.0;
    p.damping_n = 0.5;
    p.damping_t = 0.5;
    return typename B::Law(p);
  }
  static double scale() { return 1e-2; }
  static double r_eff() { return 0.5; }
  static double v_scale() { return Dm == 3 ? 0.03 : 0.3; }  // dashpot forces comparable to the spring forces
  static double limit(const typename B::Law& l, const typename B::History& h, const typename B::Kin& k,
                      const typename B::Response& r) {
    // min(mu F_N, A_c tau_y) with A_c from the spring force (the undamped law)
    typename B::History buf;
    const double fs =
        netdem::contact::evaluate<Dm>(l.params(), B::Law::transported(h, k, buf), k.r_eff, k.overlap, k.dslip).f_n;
    return std::fmin(l.params().mu * r.f_n, fs / (3.0 * std::sqrt(3.0)));
  }
  static std::set<Regime> regimes() {
    return {{0, false}, {int(NormalBranch::Plastic), false}, {int(NormalBranch::Plastic), true},
            {int(NormalBranch::Elastic), false}, {int(NormalBranch::Elastic), true}};
  }
};

// The Luding law holds its parameters by reference: each fixture keeps them in a static.
template <LudingFeatures F, int Dm>
struct LudingFixture : FixtureBase<LudingLaw<F, Dm>> {
  using B = FixtureBase<LudingLaw<F, Dm>>;
  static double scale() { return 4e-5; }  // m (a0 = 1 mm)
  static double r_eff() { return 5e-4; }
  static double v_scale() { return 1e-3; }  // m/s: the dashpots act
  // LMM05 Eq 14: f_C = mu (f_n - f_min), on the damped normal force before footnote 5
  static double limit(const typename B::Law& l, const typename B::History& h, const typename B::Kin& k,
                      const typename B::Response& r) {
    typename B::History buf;
    const auto lr = luding_evaluate<F>(l.params(), B::Law::transported(h, k, buf), l.input(k));
    return F.friction ? lr.mu * std::fmax(std::fmax(r.f_n, lr.f_n) - lr.f_min, 0.0) : 0.0;
  }
};
template <int Dm>
struct LudingTable1 : LudingFixture<kLudingFull, Dm> {  // Table 1 at 80 deg C, delta_fluid lowered
  using B = LudingFixture<kLudingFull, Dm>;
  static std::string name() { return dim_name("Luding, Table 1 (hysteresis, Eq 7, cohesion, k1(T), friction)", Dm); }
  static const LudingParams& params() {
    static const LudingParams p = [] {
      LudingParams q;
      q.delta_fluid_rel = 0.05;  // 50 um: the path reaches the fluid limit
      return q;
    }();
    return p;
  }
  static typename B::Law make() { return typename B::Law(params(), 0.8 * params().k1()); }
  static std::set<Regime> regimes() {
    return {{0, false},
            {int(LudingBranch::Loading), false}, {int(LudingBranch::Loading), true},
            {int(LudingBranch::Line), false},    {int(LudingBranch::Line), true},
            {int(LudingBranch::Cohesive), false}, {int(LudingBranch::Cohesive), true},
            {int(LudingBranch::Fluid), false}};
  }
};
constexpr LudingFeatures kHystereticOnly{true, false, false, true};
template <int Dm>
struct LudingHysteretic : LudingFixture<kHystereticOnly, Dm> {
  using B = LudingFixture<kHystereticOnly, Dm>;
  static std::string name() { return dim_name("Luding, hysteresis without cohesion or temperature", Dm); }
  static const LudingParams& params() {
    static const LudingParams p;
    return p;
  }
  static typename B::Law make() { return typename B::Law(params(), 0.0); }
  static std::set<Regime> regimes() {
    return {{0, false}, {int(LudingBranch::Loading), false}, {int(LudingBranch::Loading), true},
            {int(LudingBranch::Line), false}, {int(LudingBranch::Line), true}};
  }
};
template <int Dm>
struct LudingLinear : LudingFixture<kLudingLinear, Dm> {
  using B = LudingFixture<kLudingLinear, Dm>;
  static std::string name() { return dim_name("Luding, linear spring-dashpot", Dm); }
  static const LudingParams& params() {
    static const LudingParams p = [] {
      LudingParams q;
      q.k1_ratio = 1.0;
      q.kc_ratio = 0.0;
      return q;
    }();
    return p;
  }
  static typename B::Law make() { return typename B::Law(params(), 0.0); }
  static std::set<Regime> regimes() {
    return {{0, false}, {int(LudingBranch::Line), false}, {int(LudingBranch::Line), true}};
  }
};

// ---- tangential quantities as lists of numbers (2D: one, 3D: three) ---------------------------
std::vector<double> comps(double v) { return {v}; }
std::vector<double> comps(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

// The fields of a history as numbers (for bitwise comparison without padding bytes).
template <int Dm>
std::vector<double> fields(const PlasticIndentationHistoryT<Dm>& h) {
  std::vector<double> f{h.u_max, double(h.sliding)};
  for (double c : comps(h.f_t)) f.push_back(c);
  return f;
}
template <int Dm>
std::vector<double> fields(const LudingHistoryT<Dm>& h) {
  std::vector<double> f{h.delta_max, h.delta0, h.k2_line, h.k1_seen, double(h.fluid), double(h.sliding)};
  for (double c : comps(h.xi)) f.push_back(c);
  return f;
}

// The in-plane unit directions of a step: 2D the scalar 1 (along t); 3D two orthonormal vectors
// normal to the step's normal.
template <int Dm>
std::vector<typename Dim<Dm>::Tan> plane_axes(const Kinematics<Dm>& k) {
  if constexpr (Dm == 2) {
    (void)k;
    return {1.0};
  } else {
    const Eigen::Vector3d n = k.transport.n;
    const Eigen::Vector3d a = (std::fabs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY());
    const Eigen::Vector3d t1 = (a - n * n.dot(a)).normalized();
    return {t1, n.cross(t1)};
  }
}
template <int Dm>
typename Dim<Dm>::Tan mat_apply(const typename Dim<Dm>::TanMat& m, const typename Dim<Dm>::Tan& v) {
  return m * v;
}

// ---- a load path: a random walk in (overlap, slip) that loads, unloads, reloads and separates ----
// 3D: the normal turns by a small random rotation every step (the Transport of the step), and the
// slip is a vector in the current plane whose direction wanders (bursts of gross slip in one
// direction and small oscillations); the same random draws as 2D for the overlaps.
template <class Fx>
std::vector<typename Fx::Kin> load_path(unsigned seed, int n) {
  constexpr int Dm = Fx::D;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double s = Fx::scale(), dt = 1e-4;
  std::vector<typename Fx::Kin> path;
  // phases of 97 steps, each towards a random target overlap in [-0.5, 3.5] s (load, unload,
  // reload, separate), with noise
  double overlap = -0.1 * s, target = 0.0;
  Eigen::Vector3d normal = Eigen::Vector3d(0.3, -0.5, 0.8).normalized();
  double phi = 0.0;  // direction of the slip in the plane (3D)
  for (int i = 0; i < n; ++i) {
    if (i % 97 == 0) target = s * (-0.5 + 4.0 * (0.5 + 0.5 * u(rng)));
    typename Fx::Kin k;
    k.overlap_start = overlap;
    overlap += 0.05 * (target - overlap) + 0.02 * s * u(rng);
    k.overlap = overlap;
    // slip: bursts of one sign (gross slip) and small oscillations (stick)
    const double ds = (i % 53 < 20 ? 0.3 : 0.01) * s * u(rng);
    const double vn = Fx::v_scale() * u(rng), vt = Fx::v_scale() * u(rng);
    if constexpr (Dm == 2) {
      k.dslip = ds;
      k.v_t = vt;
    } else {
      const double w2 = 0.01 * u(rng), w1 = 0.01 * u(rng), w0 = 0.01 * u(rng);  // GCC's order of the former
      const Eigen::Vector3d w(w0, w1, w2);  // constructor arguments (unspecified in C++)
      normal = (rotation_of(w) * normal).normalized();
      if (i % 2 == 0) {  // a quasi-static increment's finite rotation
        k.transport.set_R(rotation_of(w));
        k.transport.n = normal;
      } else {  // an explicit step's small rotation (the DEM's transport, law.hpp transport_small)
        k.transport = step_transport(normal, w);
      }
      phi += 0.3 * u(rng);
      const auto ax = plane_axes<3>(k);
      const Eigen::Vector3d dir = std::cos(phi) * ax[0] + std::sin(phi) * ax[1];
      k.dslip = ds * dir;
      k.v_t = vt * (std::cos(phi + 1.0) * ax[0] + std::sin(phi + 1.0) * ax[1]);
    }
    k.r_eff = Fx::r_eff();
    k.m_eff = 1.0;
    k.dt = Fx::v_scale() > 0.0 ? dt : 0.0;
    k.v_n = vn;
    path.push_back(k);
  }
  return path;
}

template <class Fx>
class LawConformance : public ::testing::Test {};

using Fixtures = ::testing::Types<PlasticElastic<2>, PlasticReversibleCoulomb<2>, PlasticFrictionless<2>,
                                  PlasticDamped<2>, LudingTable1<2>, LudingHysteretic<2>, LudingLinear<2>,
                                  PlasticElastic<3>, PlasticReversibleCoulomb<3>, PlasticFrictionless<3>,
                                  PlasticDamped<3>, LudingTable1<3>, LudingHysteretic<3>, LudingLinear<3>>;
TYPED_TEST_SUITE(LawConformance, Fixtures);

// The consistent tangent against central differences in the end overlap and the slip increment
// (rates held; 3D: along two axes of the tangent plane), at every state of the path whose branch
// and slip status are the same on both sides of the difference; every regime of the fixture is
// visited.
TYPED_TEST(LawConformance, TangentMatchesFiniteDifferencesInEveryRegime) {
  using Fx = TypeParam;
  constexpr int Dm = Fx::D;
  const auto law = Fx::make();
  std::set<Regime> seen;
  int checked = 0;
  for (unsigned seed : {1u, 2u, 3u}) {
    typename Fx::History h{};
    for (const typename Fx::Kin& k : load_path<Fx>(seed, 3000)) {
      Tangent<Dm> t;
      const auto r = law.evaluate(h, k, &t);
      const Regime rg{r.branch, r.sliding};
      if (r.loaded) {
        const double hu = 1e-6 * std::fmin(Fx::scale(), std::fabs(k.overlap));
        const double hs = 1e-6 * Fx::scale();
        auto at = [&](double du, const typename Fx::Tan& ds) {
          typename Fx::Kin q = k;
          q.overlap += du;
          q.dslip = q.dslip + ds;
          return law.evaluate(h, q, nullptr);
        };
        const auto zero = tan_zero<typename Fx::Tan>();
        const auto up = at(hu, zero), um = at(-hu, zero);
        auto same = [&](const auto& a) { return a.branch == r.branch && a.sliding == r.sliding; };
        bool ok = same(up) && same(um);
        // 3D gross slip: the force's direction f_t / |f_t| turns with the trial force, with a
        // curvature ~ 1/|trial|: central differences resolve it only where the step moves the
        // trial force by much less than the force (|f_t| <= |trial|, so this is conservative)
        if constexpr (Dm == 3) {
          if (r.sliding && tan_norm(r.f_t) < 1e3 * hs * law.stiffness_bound(h, k).k_t) ok = false;
        }
        // (finite difference, analytic) pairs
        std::vector<std::pair<double, double>> cmp;
        cmp.emplace_back((up.f_n - um.f_n) / (2 * hu), t.dfn_dun);
        {
          const auto fd = comps(typename Fx::Tan((up.f_t - um.f_t) / (2 * hu)));
          const auto an = comps(t.dft_dun);
          for (std::size_t c = 0; c < fd.size(); ++c) cmp.emplace_back(fd[c], an[c]);
        }
        for (const auto& e : plane_axes<Dm>(k)) {
          const auto sp = at(0, hs * e), sm = at(0, -hs * e);
          ok = ok && same(sp) && same(sm);
          cmp.emplace_back((sp.f_n - sm.f_n) / (2 * hs), tan_dot(t.dfn_dslip, e));
          const auto fd = comps(typename Fx::Tan((sp.f_t - sm.f_t) / (2 * hs)));
          const auto an = comps(mat_apply<Dm>(t.dft_dslip, e));
          for (std::size_t c = 0; c < fd.size(); ++c) cmp.emplace_back(fd[c], an[c]);
        }
        if (ok) {
          double ref = (std::fabs(r.f_n) + tan_norm(r.f_t)) / Fx::scale();
          for (const auto& [fd, an] : cmp) ref = std::fmax(ref, std::fabs(fd));
          for (std::size_t c = 0; c < cmp.size(); ++c)
            ASSERT_NEAR(cmp[c].second, cmp[c].first, 1e-4 * ref)
                << Fx::name() << ": derivative " << c << " branch " << int(r.branch) << " sliding "
                << r.sliding << " overlap " << k.overlap;
          ++checked;
          seen.insert(rg);
        }
      } else {
        EXPECT_EQ(r.f_n, 0.0);
        EXPECT_EQ(tan_norm(r.f_t), 0.0);
        seen.insert(rg);
      }
      h = r.history;
    }
  }
  for (const Regime& want : Fx::regimes())
    EXPECT_TRUE(seen.count(want)) << Fx::name() << ": regime (branch " << want.first << ", sliding "
                                  << want.second << ") not visited";
  std::printf("  %s: %d states checked, %zu regimes\n", Fx::name().c_str(), checked, seen.size());
  EXPECT_GT(checked, 1000);
}

// |f_t| <= the friction limit at every state of the path; 3D: f_t lies in the tangent plane.
TYPED_TEST(LawConformance, CoulombConeNeverExceeded) {
  using Fx = TypeParam;
  const auto law = Fx::make();
  int on_limit = 0;
  for (unsigned seed : {4u, 5u}) {
    typename Fx::History h{};
    for (const typename Fx::Kin& k : load_path<Fx>(seed, 4000)) {
      const auto r = law.evaluate(h, k, nullptr);
      const double lim = Fx::limit(law, h, k, r);
      ASSERT_LE(tan_norm(r.f_t), lim * (1.0 + 1e-12) + 1e-300) << Fx::name();
      if constexpr (Fx::D == 3) {
        ASSERT_LE(std::fabs(r.f_t.dot(k.transport.n)), 1e-12 * (r.f_t.norm() + 1e-300)) << Fx::name();
      }
      on_limit += r.sliding;
      h = r.history;
    }
  }
  if (law.params().mu > 0.0) { EXPECT_GT(on_limit, 10) << Fx::name(); }  // the limit was reached
}

// From a fresh history, the force at overlap eps -> 0+ goes to 0 (no jump at first touch), with
// the rates zero (a dashpot's force at touch is the rate's, not the law's).
TYPED_TEST(LawConformance, ForceContinuousAtFirstTouch) {
  using Fx = TypeParam;
  const auto law = Fx::make();
  typename Fx::Kin k;
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
    EXPECT_LT(std::fabs(r.f_n), prev) << Fx::name() << " eps " << e;
    prev = std::fabs(r.f_n);
  }
  EXPECT_LT(prev, 1e-5 * f_ref) << Fx::name();  // f(1e-12 u) / f(u) <= sqrt(1e-12) for Eq 2
  k.overlap = -1e-12 * Fx::scale();
  const auto open = law.evaluate({}, k, nullptr);
  EXPECT_FALSE(open.loaded);
  EXPECT_EQ(open.f_n, 0.0);
}

// Closed load paths from first touch to separation, at zero rates: the work done on the contact,
// W = integral of f_n du_N - f_t . dslip (trapezoidal, fine steps), is >= 0 (no energy created).
// 3D: the slip path is a polygon in the tangent plane (two independent components).
TYPED_TEST(LawConformance, DissipationNonNegativeOverClosedPaths) {
  using Fx = TypeParam;
  constexpr int Dm = Fx::D;
  using Tan = typename Fx::Tan;
  const auto law = Fx::make();
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double s = Fx::scale();
  double w_min = kInf, w_max = -kInf;
  for (int path = 0; path < 40; ++path) {
    // corners of a polygon in (overlap, slip): touch, load with slip, unload, reload, separate
    const double umax = s * (0.5 + 4.0 * u(rng)), smax = s * (2.0 * u(rng) - 1.0);
    const double smax2 = Dm == 3 ? s * (2.0 * u(rng) - 1.0) : 0.0;  // (2D: the same draws as before)
    auto slip = [&](double a, double b) {
      if constexpr (Dm == 2) {
        (void)b;
        return Tan(a);
      } else {
        return Tan(a, b, 0.0);  // the plane normal to n = e3
      }
    };
    const double corners[6][3] = {{-0.01 * s, 0.0, 0.0},      {umax, smax, 0.0},
                                  {0.5 * umax, -smax, smax2},  {0.9 * umax, 0.5 * smax, -smax2},
                                  {0.3 * umax, 0.0, 0.5 * smax2}, {-0.1 * s, 0.0, 0.0}};
    typename Fx::History h{};
    double w = 0.0, f_n0 = 0.0, un = corners[0][0];
    Tan f_t0 = tan_zero<Tan>();
    for (int c = 0; c + 1 < 6; ++c) {
      const int m = 4000;
      for (int q = 1; q <= m; ++q) {
        const double a = static_cast<double>(q) / m;
        typename Fx::Kin k;
        if constexpr (Dm == 3) k.transport.n = Eigen::Vector3d::UnitZ();
        k.r_eff = Fx::r_eff();
        k.overlap_start = un;
        k.overlap = corners[c][0] + a * (corners[c + 1][0] - corners[c][0]);
        k.dslip = slip((corners[c + 1][1] - corners[c][1]) / m, (corners[c + 1][2] - corners[c][2]) / m);
        const auto r = law.evaluate(h, k, nullptr);
        w += 0.5 * (r.f_n + f_n0) * (k.overlap - un) - 0.5 * tan_dot(Tan(r.f_t + f_t0), k.dslip);
        f_n0 = r.f_n;
        f_t0 = r.f_t;
        un = k.overlap;
        h = r.history;
      }
    }
    EXPECT_EQ(f_n0, 0.0);  // separated: no stored energy left
    const double f_scale = law.evaluate({}, [&] {
      typename Fx::Kin k;
      k.r_eff = Fx::r_eff();
      k.overlap = umax;
      return k;
    }(), nullptr).f_n;
    const double w_rel = w / (f_scale * umax);
    w_min = std::fmin(w_min, w_rel);
    w_max = std::fmax(w_max, w_rel);
    EXPECT_GE(w_rel, -1e-3) << Fx::name() << " path " << path;  // trapezoidal error O(1/m^2)
  }
  std::printf("  %s: W / (F(u_max) u_max) in [%.3e, %.3e]\n", Fx::name().c_str(), w_min, w_max);
}

// A loaded pair with a tangential force moved rigidly (2D: rotation by up to 2.5 rad about an
// arbitrary point and a translation; 3D: rotations about arbitrary axes, with a twist about n):
// no slip, the same force magnitudes, the force vector rotated with the pair; and the same for
// every intermediate angle.
template <class Fx>
void objective_2d() {
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
  if (law.params().mu > 0.0) { ASSERT_NE(e0.law.f_t, 0.0) << Fx::name(); }
  const Vec pivot(-3.0 * ri, 5.0 * ri), shift(7.0 * ri, -2.0 * ri);
  for (double ang : {1e-3, 0.1, 0.7, 2.5, -1.2}) {
    const Eigen::Rotation2Dd R(ang);
    const Vec xi1 = pivot + R * (xi0 - pivot) + shift;
    const Vec xj1 = pivot + R * (g.n * g.L + xi0 - pivot) + shift;
    const PairGeometry g1 = pair_geometry(xi1, xj1, ri, rj);
    PairElement<typename Fx::Law> e;
    pair_element(law, h, g, g1, ang, ang, e);
    EXPECT_NEAR(e.dslip, 0.0, 1e-12 * s) << Fx::name() << " angle " << ang;
    EXPECT_NEAR(e.law.f_n, e0.law.f_n, 1e-9 * std::fabs(e0.law.f_n)) << Fx::name();
    EXPECT_NEAR(e.law.f_t, e0.law.f_t, 1e-9 * std::fabs(e0.law.f_n)) << Fx::name();
    EXPECT_EQ(e.law.sliding, e0.law.sliding);
    // the force on j rotates with the pair
    const Vec f0(e0.force(3), e0.force(4)), f1(e.force(3), e.force(4));
    EXPECT_LT((R * f0 - f1).norm(), 1e-9 * f0.norm()) << Fx::name();
  }
}
template <class Fx>
void objective_3d() {
  using V3 = Eigen::Vector3d;
  const auto law = Fx::make();
  const double s = Fx::scale();
  const double ri = 2.0 * Fx::r_eff(), rj = 2.0 * Fx::r_eff();
  const V3 xi0(0.3 * ri, -0.2 * ri, 0.1 * ri);
  const V3 n0 = V3(0.4, -0.7, 0.59).normalized();
  const V3 xj0 = xi0 + n0 * (ri + rj - 2.0 * s);
  // load: from touch to 2 s with a slip along a tangent (so that f_t != 0), no rotation
  typename Fx::History h{};
  const V3 t1 = n0.unitOrthogonal();
  const V3 xj1 = xj0 + t1 * (0.005 * s) + n0.cross(t1) * (0.003 * s);
  const PairGeometry3 gt = pair_geometry(xi0, V3(xi0 + n0 * (ri + rj)), ri, rj);
  const PairGeometry3 g = pair_geometry(xi0, xj1, ri, rj);
  h = law.evaluate(h, increment_kinematics(gt, g, V3::Zero(), V3::Zero()), nullptr).history;
  const auto r0 = law.evaluate(h, increment_kinematics(g, g, V3::Zero(), V3::Zero()), nullptr);
  ASSERT_TRUE(r0.loaded);
  if (law.params().mu > 0.0) { ASSERT_GT(r0.f_t.norm(), 0.0) << Fx::name(); }
  const V3 pivot(-3.0 * ri, 5.0 * ri, 2.0 * ri), shift(7.0 * ri, -2.0 * ri, 3.0 * ri);
  const V3 axes[] = {V3(0, 0, 1), g.n, V3(1, 2, -0.5).normalized(), g.n.unitOrthogonal()};
  for (const V3& axis : axes) {
    for (double ang : {1e-3, 0.1, 0.7, 2.5, -1.2}) {
      const Eigen::Matrix3d R = Eigen::AngleAxisd(ang, axis).toRotationMatrix();
      const V3 xi1 = pivot + R * (xi0 - pivot) + shift;
      const V3 xj2 = pivot + R * (xj1 - pivot) + shift;
      const PairGeometry3 g1 = pair_geometry(xi1, xj2, ri, rj);
      const auto k = increment_kinematics(g, g1, V3(ang * axis), V3(ang * axis));
      const auto r = law.evaluate(h, k, nullptr);
      EXPECT_LT(k.dslip.norm(), 1e-12 * s) << Fx::name() << " angle " << ang;
      EXPECT_NEAR(r.f_n, r0.f_n, 1e-9 * std::fabs(r0.f_n)) << Fx::name();
      EXPECT_NEAR(r.f_t.norm(), r0.f_t.norm(), 1e-9 * std::fabs(r0.f_n)) << Fx::name();
      EXPECT_EQ(r.sliding, r0.sliding);
      // the tangential force rotates with the pair (twist about n included)
      EXPECT_LT((R * r0.f_t - r.f_t).norm(), 1e-9 * std::fabs(r0.f_n)) << Fx::name() << " angle " << ang;
    }
  }
}
TYPED_TEST(LawConformance, ObjectiveUnderRigidMotion) {
  if constexpr (TypeParam::D == 2) {
    objective_2d<TypeParam>();
  } else {
    objective_3d<TypeParam>();
  }
}

// The in-place update() of a law (where it has one) against evaluate(): the same forces and
// histories to the last bit over thousands of steps.
TYPED_TEST(LawConformance, InPlaceUpdateEqualsEvaluate) {
  using Fx = TypeParam;
  const auto law = Fx::make();
  typename Fx::History h1{}, h2{};
  int n = 0;
  for (const typename Fx::Kin& k : load_path<Fx>(9, 5000)) {
    double fn1, fn2;
    typename Fx::Tan ft1, ft2;
    update_contact<true>(law, h1, k, fn1, ft1);
    update_contact<false>(law, h2, k, fn2, ft2);
    ASSERT_EQ(std::memcmp(&fn1, &fn2, sizeof fn1), 0) << Fx::name() << " step " << n;
    const auto t1 = comps(ft1), t2 = comps(ft2);
    ASSERT_EQ(std::memcmp(t1.data(), t2.data(), sizeof(double) * t1.size()), 0) << Fx::name() << " step " << n;
    const auto a = fields(h1), b = fields(h2);
    ASSERT_EQ(std::memcmp(a.data(), b.data(), sizeof(double) * a.size()), 0) << Fx::name() << " step " << n;
    ++n;
  }
}

// The interface's answers that the solvers rely on.
TYPED_TEST(LawConformance, StiffnessBoundAndIterationStiffness) {
  using Fx = TypeParam;
  constexpr int Dm = Fx::D;
  const auto law = Fx::make();
  typename Fx::History h{};
  for (const typename Fx::Kin& k : load_path<Fx>(11, 3000)) {
    Tangent<Dm> t;
    const auto r = law.evaluate(h, k, &t);
    const StiffnessBound b = law.stiffness_bound(h, k);
    const IterationStiffness is = law.iteration_stiffness(h, k, r);
    if (r.loaded) {
      // the bound covers the tangent of the step (the first-touch singularity of Eq 2 excepted)
      if (k.overlap > 1e-3 * Fx::scale()) { EXPECT_GE(b.k_n * (1 + 1e-12), std::fabs(t.dfn_dun)) << Fx::name(); }
      for (const auto& e : plane_axes<Dm>(k)) {
        const double kt_e = -tan_dot(mat_apply<Dm>(t.dft_dslip, e), e);  // the spring along e
        if (!r.sliding) { EXPECT_GE(b.k_t * (1 + 1e-12), tan_norm(mat_apply<Dm>(t.dft_dslip, e))) << Fx::name(); }
        // a sticking spring: the iteration matrix takes the tangent's spring
        if (!r.sliding && tan_norm(r.f_t) != 0.0) { EXPECT_NEAR(is.k_t, kt_e, 1e-12 * is.k_t) << Fx::name(); }
      }
      EXPECT_GE(is.k_n_add, 0.0);
      EXPECT_GE(t.dfn_dun + is.k_n_add, 0.0) << Fx::name();  // a non-negative normal stiffness
      EXPECT_GE(is.k_t, 0.0);
    }
    h = r.history;
    if (r.loaded) { EXPECT_TRUE(law.has_history(h)) << Fx::name(); }  // a loaded contact has a history
  }
  EXPECT_FALSE(law.has_history(typename Fx::History{})) << Fx::name();
}

}  // namespace
