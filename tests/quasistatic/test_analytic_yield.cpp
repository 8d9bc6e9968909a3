// Tests of the analytic affine upper-bound yield surfaces (Redanz & Fleck 2001 Appendix A,
// docs/yield_analytic.md): closed forms against an independent adaptive quadrature of the dissipation,
// stress = gradient of the dissipation, normality and convexity, homogeneity, the vertices, the
// Appendix A closed-die formulas (typos fixed), the reference tables of the implicit-solver notes
// (section 5.5) and input validation.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <numbers>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "netdem/quasistatic/analytic_yield.hpp"

using namespace netdem;
using qs::AffineYieldInput;
using qs::YieldPoint;

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180.0;

// ---- independent numerical integration ---------------------------------------------------------

// Gauss-Legendre nodes and weights on [-1, 1] (Newton on P_n).
struct GaussLegendre {
  std::vector<double> x, w;
  explicit GaussLegendre(int n) {
    for (int i = 0; i < n; ++i) {
      double z = std::cos(kPi * (i + 0.75) / (n + 0.5)), dp = 0.0;
      for (int it = 0; it < 100; ++it) {
        double p0 = 1.0, p1 = z;
        for (int k = 2; k <= n; ++k) {
          const double p2 = ((2.0 * k - 1.0) * z * p1 - (k - 1.0) * p0) / k;
          p0 = p1;
          p1 = p2;
        }
        dp = n * (z * p1 - p0) / (z * z - 1.0);
        const double dz = p1 / dp;
        z -= dz;
        if (std::abs(dz) < 1e-16) break;
      }
      x.push_back(z);
      w.push_back(2.0 / ((1.0 - z * z) * dp * dp));
    }
  }
  double operator()(const std::function<double(double)>& f, double a, double b) const {
    double s = 0.0;
    for (std::size_t i = 0; i < x.size(); ++i) s += w[i] * f(0.5 * (a + b) + 0.5 * (b - a) * x[i]);
    return 0.5 * (b - a) * s;
  }
};

const GaussLegendre& gl20() {
  static const GaussLegendre g(20);
  return g;
}

double adaptive(const std::function<double(double)>& f, double a, double b, double tol, int depth = 0) {
  const double whole = gl20()(f, a, b), m = 0.5 * (a + b);
  const double halves = gl20()(f, a, m) + gl20()(f, m, b);
  if (std::abs(whole - halves) <= tol || depth > 40) return halves;
  return adaptive(f, a, m, tol / 2, depth + 1) + adaptive(f, m, b, tol / 2, depth + 1);
}

// Integral over [0, pi/2] split at the angle where the normal strain rate changes sign (computed here,
// not by the library): the integrands have a kink there.
double integrate_contacts(const std::function<double(double)>& f, double e1, double e2, double tol) {
  if (e1 * e2 < 0.0) {
    const double phi_star = std::atan(std::sqrt(-e1 / e2));
    return adaptive(f, 0.0, phi_star, tol) + adaptive(f, phi_star, kPi / 2, tol);
  }
  return adaptive(f, 0.0, kPi / 2, tol);
}

double prefactor(const AffineYieldInput& in) { return 12.0 / (kPi * kPi) * in.density * in.z0 * in.sigma_y; }

// F_N / (6 sigma_y R) = sqrt(-2 E(phi)) of a contact with normal angle phi.
double overlap_root(const AffineYieldInput& in, double phi) {
  const double c = std::cos(phi), s = std::sin(phi);
  return std::sqrt(std::max(0.0, -2.0 * (in.E11 * c * c + in.E22 * s * s)));
}

// The dissipation rate by quadrature: sum over contacts of F_N times the approach rate, active contacts only.
double dissipation_quadrature(const AffineYieldInput& in, double e1, double e2) {
  auto f = [&](double phi) {
    const double c = std::cos(phi), s = std::sin(phi);
    return overlap_root(in, phi) * std::max(0.0, -(e1 * c * c + e2 * s * s));
  };
  return prefactor(in) * integrate_contacts(f, e1, e2, 1e-15);
}

// The stress by quadrature of the force moments over the active contacts (statics).
YieldPoint stress_quadrature(const AffineYieldInput& in, double e1, double e2) {
  auto moment = [&](bool cos2) {
    auto f = [&](double phi) {
      const double c = std::cos(phi), s = std::sin(phi);
      if (!(e1 * c * c + e2 * s * s < 0.0)) return 0.0;
      return overlap_root(in, phi) * (cos2 ? c * c : s * s);
    };
    return -prefactor(in) * integrate_contacts(f, e1, e2, 1e-15);
  };
  return {moment(true), moment(false)};
}

// ---- cases ----------------------------------------------------------------------------------

AffineYieldInput input(double E11, double E22) { return {0.85, 4.0, 1.0, E11, E22}; }

struct Case {
  std::string name;
  AffineYieldInput in;
};

std::vector<Case> cases() {
  return {{"hydrostatic", input(-0.02, -0.02)},          {"closed die", input(0.0, -0.04)},
          {"closed die along 1", input(-0.04, 0.0)},     {"general", input(-0.01, -0.03)},
          {"general E11 < E22", input(-0.03, -0.005)},   {"near closed die", input(-1e-9, -0.04)},
          {"near hydrostatic", input(-0.02, -0.0200001)}};
}

// The rate direction (cos theta, sin theta) as affine_yield_point forms it: components that theta cannot
// resolve (|x| < 1e-15, e.g. sin of the double nearest to pi) are exactly 0.
std::pair<double, double> rate(double theta) {
  auto snap = [](double x) { return std::abs(x) < 1e-15 ? 0.0 : x; };
  return {snap(std::cos(theta)), snap(std::sin(theta))};
}

double dist(YieldPoint a, YieldPoint b) { return std::hypot(a.S11 - b.S11, a.S22 - b.S22); }

// distance of a direction angle (degrees) from the nearest axis direction
double off_axis_deg(double deg) { return std::abs(std::remainder(deg, 90.0)); }

}  // namespace

TEST(AnalyticYield, CarlsonIntegralsMatchReferenceValues) {
  using qs::detail::carlson_rd;
  using qs::detail::carlson_rf;
  // Carlson (1995) test values, and the degenerate cases R_F(x,x,x) = x^-1/2, R_D(x,x,x) = x^-3/2.
  EXPECT_NEAR(carlson_rf(1, 2, 0), 1.3110287771460598, 1e-15);
  EXPECT_NEAR(carlson_rf(2, 3, 4), 0.5840828416771517, 1e-15);
  EXPECT_NEAR(carlson_rd(0, 2, 1), 1.7972103521033884, 2e-15);
  EXPECT_NEAR(carlson_rd(2, 3, 4), 0.16510527294261054, 1e-16);
  EXPECT_NEAR(carlson_rf(0.3, 0.7, 1.0), 1.2650802817015436, 1e-15);
  EXPECT_NEAR(carlson_rd(0.3, 0.7, 1.0), 1.5238095222414108, 2e-15);
  for (double x : {1e-3, 0.5, 7.0}) {
    EXPECT_NEAR(carlson_rf(x, x, x), 1 / std::sqrt(x), 1e-15 / std::sqrt(x));
    EXPECT_NEAR(carlson_rd(x, x, x), std::pow(x, -1.5), 1e-15 * std::pow(x, -1.5));
  }
  // Legendre forms: F(phi, k) = s R_F(c^2, 1 - k^2 s^2, 1), E = F - (k^2/3) s^3 R_D(c^2, 1 - k^2 s^2, 1),
  // against libstdc++ (whose ellint_2 is only good to ~1e-13 near k = 1) ...
  auto legendre_e = [&](double k, double phi) {
    const double s = std::sin(phi), c = std::cos(phi), d = 1 - k * k * s * s;
    return s * carlson_rf(c * c, d, 1) - k * k / 3 * s * s * s * carlson_rd(c * c, d, 1);
  };
  for (double k : {0.1, 0.6, 0.99})
    for (double phi : {0.2, 0.9, 1.5}) {
      const double s = std::sin(phi), c = std::cos(phi), d = 1 - k * k * s * s;
      EXPECT_NEAR(s * carlson_rf(c * c, d, 1), std::ellint_1(k, phi), 1e-14);
      EXPECT_NEAR(legendre_e(k, phi), std::ellint_2(k, phi), 2e-13);
    }
  // ... and against 30-digit values (mpmath.ellipe(phi, m = k^2))
  EXPECT_NEAR(legendre_e(0.99, 0.2), 0.198695968603930225706, 1e-16);
  EXPECT_NEAR(legendre_e(0.99, 0.9), 0.786008754914291518599, 3e-16);
  EXPECT_NEAR(legendre_e(0.99, 1.5), 1.018092263096806697738, 5e-16);
}

TEST(AnalyticYield, QuadratureIsAccurate) {
  // the reference integrator on the hydrostatic vertex: int_0^{pi/2} cos^2 = pi/4
  const double v = integrate_contacts([](double p) { return std::cos(p) * std::cos(p); }, -1, -1, 1e-15);
  EXPECT_NEAR(v, kPi / 4, 1e-15);
}

TEST(AnalyticYield, ClosedFormMatchesQuadratureOfDissipation) {
  for (const Case& c : cases()) {
    const AffineYieldInput& in = c.in;
    SCOPED_TRACE(c.name);
    const YieldPoint lp = qs::affine_loading_point(in);
    const double scale = std::hypot(lp.S11, lp.S22);  // stress scale, and dissipation scale for |rate| = 1
    for (int i = 0; i < 720; ++i) {
      const double th = i * 0.5 * kDeg;
      const auto [e1, e2] = rate(th);
      const double w = qs::affine_dissipation(in, e1, e2), wq = dissipation_quadrature(in, e1, e2);
      EXPECT_NEAR(w, wq, 1e-8 * std::max(wq, 1e-3 * scale)) << "theta = " << i * 0.5;
      const YieldPoint s = qs::affine_yield_point(in, th), sq = stress_quadrature(in, e1, e2);
      EXPECT_NEAR(s.S11, sq.S11, 1e-8 * scale) << "theta = " << i * 0.5;
      EXPECT_NEAR(s.S22, sq.S22, 1e-8 * scale) << "theta = " << i * 0.5;
    }
  }
}

TEST(AnalyticYield, StressIsNumericalGradientOfDissipation) {
  const double h = 1e-5;
  for (const Case& c : cases()) {
    const AffineYieldInput& in = c.in;
    SCOPED_TRACE(c.name);
    const YieldPoint lp = qs::affine_loading_point(in);
    const double scale = std::hypot(lp.S11, lp.S22);
    for (int i = 0; i < 360; ++i) {
      if (off_axis_deg(i + 0.5) < 2.0) continue;  // the gradient's derivative blows up at the axes
      const double th = (i + 0.5) * kDeg, e1 = std::cos(th), e2 = std::sin(th);
      auto W = [&](double a, double b) { return dissipation_quadrature(in, a, b); };
      const double g1 = (W(e1 + h, e2) - W(e1 - h, e2)) / (2 * h);
      const double g2 = (W(e1, e2 + h) - W(e1, e2 - h)) / (2 * h);
      const YieldPoint s = qs::affine_yield_point(in, th);
      EXPECT_NEAR(s.S11, g1, 1e-6 * scale) << "theta = " << i + 0.5;
      EXPECT_NEAR(s.S22, g2, 1e-6 * scale) << "theta = " << i + 0.5;
    }
  }
}

TEST(AnalyticYield, StrainRateIsNormalToTheSurface) {
  const double h = 1e-5;
  for (const Case& c : cases()) {
    const AffineYieldInput& in = c.in;
    SCOPED_TRACE(c.name);
    int checked = 0;
    for (int i = 0; i < 720; ++i) {
      const double deg = i * 0.5;
      const bool smooth = (deg > 90 && deg < 180) || deg > 270;  // the two branches between the vertices
      if (!smooth || off_axis_deg(deg) < 1.0) continue;
      const double th = deg * kDeg;
      const YieldPoint a = qs::affine_yield_point(in, th - h), b = qs::affine_yield_point(in, th + h);
      const double t1 = b.S11 - a.S11, t2 = b.S22 - a.S22, tn = std::hypot(t1, t2);
      ASSERT_GT(tn, 0.0);
      EXPECT_LT(std::abs(t1 * std::cos(th) + t2 * std::sin(th)) / tn, 1e-6) << "theta = " << deg;
      ++checked;
    }
    EXPECT_GT(checked, 300);
  }
}

TEST(AnalyticYield, SurfaceIsConvexWithStressAsSupportPoint) {
  // Sigma(theta_i) : n_j <= W(n_j) for all pairs (upper bound / maximum work), equality for i = j.
  for (const Case& c : cases()) {
    const AffineYieldInput& in = c.in;
    SCOPED_TRACE(c.name);
    const double scale = qs::affine_stress_scale(in);
    std::vector<YieldPoint> pts;
    for (int i = 0; i < 360; ++i) pts.push_back(qs::affine_yield_point(in, i * kDeg));
    for (int j = 0; j < 360; ++j) {
      const auto [e1, e2] = rate(j * kDeg);
      const double w = qs::affine_dissipation(in, e1, e2);
      EXPECT_NEAR(pts[j].S11 * e1 + pts[j].S22 * e2, w, 1e-14 * scale);
      for (const auto& p : pts) EXPECT_LE(p.S11 * e1 + p.S22 * e2, w + 1e-13 * scale);
    }
  }
}

TEST(AnalyticYield, DissipationIsHomogeneousOfDegreeOne) {
  for (const Case& c : cases()) {
    const AffineYieldInput& in = c.in;
    SCOPED_TRACE(c.name);
    for (double deg : {10.0, 100.0, 135.0, 200.0, 300.0, 350.0}) {
      const double e1 = std::cos(deg * kDeg), e2 = std::sin(deg * kDeg);
      const double w = qs::affine_dissipation(in, e1, e2);
      const YieldPoint s = qs::affine_yield_stress(in, e1, e2);
      for (double lambda : {1e-6, 0.3, 7.0, 1e5}) {
        EXPECT_NEAR(qs::affine_dissipation(in, lambda * e1, lambda * e2), lambda * w, 1e-14 * lambda * (w + 1));
        const YieldPoint sl = qs::affine_yield_stress(in, lambda * e1, lambda * e2);
        EXPECT_NEAR(sl.S11, s.S11, 1e-14);
        EXPECT_NEAR(sl.S22, s.S22, 1e-14);
      }
      EXPECT_GE(w, 0.0);
    }
    // Sigma is linear in D, Z0, sigma_y and scales with sqrt of the accumulated strain
    AffineYieldInput in2 = in;
    in2.density *= 0.5;
    in2.z0 *= 1.5;
    in2.sigma_y *= 3.0;
    in2.E11 *= 4.0;
    in2.E22 *= 4.0;
    const YieldPoint a = qs::affine_yield_point(in, 2.0), b = qs::affine_yield_point(in2, 2.0);
    EXPECT_NEAR(b.S11, a.S11 * 0.5 * 1.5 * 3.0 * 2.0, 1e-13);
    EXPECT_NEAR(b.S22, a.S22 * 0.5 * 1.5 * 3.0 * 2.0, 1e-13);
  }
}

TEST(AnalyticYield, VerticesAtLoadingPointAndOrigin) {
  for (const Case& c : cases()) {
    const AffineYieldInput& in = c.in;
    SCOPED_TRACE(c.name);
    const YieldPoint lp = qs::affine_loading_point(in);
    const double scale = std::hypot(lp.S11, lp.S22);
    // the whole negative quadrant of rate directions maps to the loading point, the positive one to 0
    for (double deg = 180.0; deg <= 270.0; deg += 2.5) {
      const YieldPoint p = qs::affine_yield_point(in, deg * kDeg);
      EXPECT_EQ(p.S11, lp.S11);
      EXPECT_EQ(p.S22, lp.S22);
    }
    for (double theta : {kPi, 1.5 * kPi, -0.5 * kPi, 3 * kPi})
      EXPECT_EQ(dist(qs::affine_yield_point(in, theta), lp), 0.0);
    for (double deg = 0.0; deg <= 90.0; deg += 2.5) EXPECT_EQ(dist(qs::affine_yield_point(in, deg * kDeg), {}), 0.0);
    // the smooth branches run continuously into both vertices
    // (like sqrt(eps): the switch angle moves by ~sqrt(eps) from the axis)
    for (double eps : {1e-4, 1e-8, 1e-12}) {
      const double tol = 2 * std::sqrt(eps) * scale;
      EXPECT_LT(dist(qs::affine_yield_point(in, kPi - eps), lp), tol);
      EXPECT_LT(dist(qs::affine_yield_point(in, 1.5 * kPi + eps), lp), tol);
      EXPECT_LT(dist(qs::affine_yield_point(in, 0.5 * kPi + eps), {}), tol);
      EXPECT_LT(dist(qs::affine_yield_point(in, 2 * kPi - eps), {}), tol);
    }
  }
}

TEST(AnalyticYield, HydrostaticLoadingPointIsAffineCompactionStress) {
  // precompaction D0 = 0.814 -> D = 0.85 along E11 = E22: Sigma = -(3/pi) D Z0 sigma_y sqrt(-2E)
  const AffineYieldInput in = qs::affine_yield_input(0.814, 0.85, 4.0, 2.0, -1.0, -1.0);
  const double E = -std::log(0.85 / 0.814) / 2;
  EXPECT_NEAR(in.E11, E, 1e-16);
  EXPECT_NEAR(in.E22, E, 1e-16);
  EXPECT_NEAR(0.814 * std::exp(-(in.E11 + in.E22)), 0.85, 1e-15);
  const double expected = -(3 / kPi) * 0.85 * 4.0 * 2.0 * std::sqrt(-2 * E);
  const YieldPoint lp = qs::affine_loading_point(in);
  EXPECT_NEAR(lp.S11, expected, 1e-14);
  EXPECT_NEAR(lp.S22, expected, 1e-14);
  EXPECT_NEAR(qs::affine_stress_scale(in), 0.85 * 4.0 * 2.0 * std::sqrt(-2 * E), 1e-14);
}

TEST(AnalyticYield, ClosedDieMatchesAppendixAWithTyposFixed) {
  const AffineYieldInput in = qs::affine_yield_input(0.814, 0.85, 4.0, 1.0, 0.0, -1.0);
  EXPECT_EQ(in.E11, 0.0);
  EXPECT_NEAR(in.E22, -std::log(0.85 / 0.814), 1e-16);
  const double s = in.density * in.z0 * in.sigma_y * std::sqrt(-2 * in.E22);
  const YieldPoint lp = qs::affine_loading_point(in);
  EXPECT_NEAR(lp.S11, -4 / (kPi * kPi) * s, 1e-14);  // A7
  EXPECT_NEAR(lp.S22, -8 / (kPi * kPi) * s, 1e-14);  // A8
  for (int i = 1; i < 90; ++i) {
    // A9-A10: E11dot > 0 > E22dot; A11-A12: E11dot < 0 < E22dot; theta_c = atan(sqrt(-E11dot/E22dot))
    for (double th : {(270.0 + i) * kDeg, (90.0 + i) * kDeg}) {
      const double e1 = std::cos(th), e2 = std::sin(th), c = std::cos(std::atan(std::sqrt(-e1 / e2)));
      const double c3 = c * c * c, k = 12 / (kPi * kPi) * s;
      const YieldPoint p = qs::affine_yield_point(in, th);
      if (e1 > 0) {
        EXPECT_NEAR(p.S11, -k / 3 * c3, 1e-13);
        EXPECT_NEAR(p.S22, -k * (c - c3 / 3), 1e-13);
      } else {
        EXPECT_NEAR(p.S11, -k / 3 * (1 - c3), 1e-13);
        EXPECT_NEAR(p.S22, -k * (2.0 / 3 - c + c3 / 3), 1e-13);
      }
      EXPECT_NEAR(qs::affine_switch_angle(e1, e2), std::atan(std::sqrt(-e1 / e2)), 1e-15);
    }
  }
}

TEST(AnalyticYield, HydrostaticSurfaceIsSineArch) {
  // |tau| = (3/pi^2) sin(pi^2 |Sigma_m| / 3) in units of D Z0 sigma_y sqrt(-2E) (notes 5.2)
  const AffineYieldInput in = input(-0.02, -0.02);
  const double u = qs::affine_stress_scale(in);
  for (int i = 1; i < 90; ++i)
    for (double deg : {90.0 + i, 270.0 + i}) {
      const YieldPoint p = qs::affine_yield_point(in, deg * kDeg);
      const double sm = (p.S11 + p.S22) / 2 / u, tau = (p.S22 - p.S11) / 2 / u;
      EXPECT_NEAR(std::abs(tau), 3 / (kPi * kPi) * std::sin(kPi * kPi * std::abs(sm) / 3), 1e-14);
    }
}

TEST(AnalyticYield, ReproducesNotesTables) {
  // implicit-solver notes section 5.5, stresses / (D Z0 sigma_y sqrt(-2E)); to the printed 4 digits,
  // active contact angles to the printed 0.1 degree
  struct Row {
    double deg, phi_lo, phi_hi, s11, s22, sm, tau;
  };
  const std::vector<Row> hydro = {
      {95, 0, 16.5, -0.3402, -0.0095, -0.1748, +0.1653},  {100, 0, 22.8, -0.4587, -0.0247, -0.2417, +0.2170},
      {110, 0, 31.1, -0.5989, -0.0611, -0.3300, +0.2689}, {120, 0, 37.2, -0.6879, -0.1022, -0.3950, +0.2928},
      {135, 0, 45.0, -0.7814, -0.1735, -0.4775, +0.3040}, {150, 0, 52.8, -0.8528, -0.2671, -0.5599, +0.2928},
      {160, 0, 58.9, -0.8938, -0.3560, -0.6249, +0.2689}, {170, 0, 67.2, -0.9303, -0.4962, -0.7132, +0.2170},
      {175, 0, 73.5, -0.9454, -0.6147, -0.7801, +0.1653}, {200, 0, 90, -0.9549, -0.9549, -0.9549, 0},
      {315, 45, 90, -0.1735, -0.7814, -0.4775, -0.3040},  {30, 0, 0, 0, 0, 0, 0}};
  const std::vector<Row> die = {
      {95, 0, 16.5, -0.0479, -0.0020, -0.0250, +0.0229},   {100, 0, 22.8, -0.0876, -0.0072, -0.0474, +0.0402},
      {110, 0, 31.1, -0.1509, -0.0239, -0.0874, +0.0635},  {120, 0, 37.2, -0.2007, -0.0471, -0.1239, +0.0768},
      {135, 0, 45.0, -0.2620, -0.0941, -0.1781, +0.0839},  {150, 0, 52.8, -0.3155, -0.1647, -0.2401, +0.0754},
      {160, 0, 58.9, -0.3494, -0.2384, -0.2939, +0.0555},  {170, 0, 67.2, -0.3818, -0.3634, -0.3726, +0.0092},
      {175, 0, 73.5, -0.3960, -0.4750, -0.4355, -0.0395},  {225, 0, 90, -0.4053, -0.8106, -0.6079, -0.2026},
      {275, 16.5, 90, -0.3574, -0.8085, -0.5830, -0.2256}, {280, 22.8, 90, -0.3177, -0.8034, -0.5605, -0.2429},
      {290, 31.1, 90, -0.2544, -0.7866, -0.5205, -0.2661}, {300, 37.2, 90, -0.2046, -0.7635, -0.4840, -0.2795},
      {315, 45.0, 90, -0.1433, -0.7164, -0.4299, -0.2866}, {330, 52.8, 90, -0.0897, -0.6458, -0.3678, -0.2780},
      {340, 58.9, 90, -0.0559, -0.5722, -0.3140, -0.2582}, {350, 67.2, 90, -0.0235, -0.4472, -0.2354, -0.2118},
      {355, 73.5, 90, -0.0092, -0.3356, -0.1724, -0.1632}, {60, 0, 0, 0, 0, 0, 0}};
  const double tol = 0.5e-4 + 1e-12;
  for (const auto& [label, in, rows] :
       {std::tuple{"hydrostatic", input(-0.03, -0.03), hydro}, std::tuple{"closed die", input(0.0, -0.03), die}}) {
    const double u = qs::affine_stress_scale(in);
    for (const Row& r : rows) {
      SCOPED_TRACE(std::string(label) + " theta = " + std::to_string(r.deg));
      const double th = r.deg * kDeg, e1 = std::cos(th), e2 = std::sin(th);
      const YieldPoint p = qs::affine_yield_point(in, th);
      const double s11 = p.S11 / u, s22 = p.S22 / u;
      EXPECT_NEAR(s11, r.s11, tol);
      EXPECT_NEAR(s22, r.s22, tol);
      EXPECT_NEAR((s11 + s22) / 2, r.sm, tol);
      EXPECT_NEAR((s22 - s11) / 2, r.tau, tol);
      if (e1 * e2 < 0) {  // active [0, phi*) for E11dot < 0 < E22dot, (phi*, 90] otherwise
        const double phi = qs::affine_switch_angle(e1, e2) / kDeg;
        EXPECT_NEAR(phi, e1 < 0 ? r.phi_hi : r.phi_lo, 0.05 + 1e-9);
        EXPECT_EQ(e1 < 0 ? r.phi_lo : r.phi_hi, e1 < 0 ? 0.0 : 90.0);
      }
    }
  }
}

TEST(AnalyticYield, HydrostaticPrecompactionIsSymmetric) {
  // swapping the rate components swaps the stress components (S11 <-> S22)
  const AffineYieldInput in = input(-0.02, -0.02);
  for (int i = 0; i < 360; ++i) {
    const double th = (i + 0.25) * kDeg;
    const YieldPoint a = qs::affine_yield_point(in, th), b = qs::affine_yield_point(in, kPi / 2 - th);
    EXPECT_NEAR(a.S11, b.S22, 1e-15);
    EXPECT_NEAR(a.S22, b.S11, 1e-15);
  }
  // and in general: swapping E11 <-> E22 together with the rates swaps the stresses
  const AffineYieldInput g = input(-0.01, -0.03), gs = input(-0.03, -0.01);
  for (int i = 0; i < 360; ++i) {
    const double th = (i + 0.25) * kDeg;
    const YieldPoint a = qs::affine_yield_point(g, th), b = qs::affine_yield_point(gs, kPi / 2 - th);
    EXPECT_NEAR(a.S11, b.S22, 1e-15);
    EXPECT_NEAR(a.S22, b.S11, 1e-15);
  }
}

TEST(AnalyticYield, GeneralFormulaReducesToHydrostaticAndClosedDie) {
  using qs::detail::overlap_moments;
  const double h = kPi / 2;
  for (auto [p0, p1] : {std::pair{0.0, h}, std::pair{0.0, 0.3}, std::pair{0.7, h}, std::pair{0.2, 1.1}}) {
    // elliptic form at a == b against the elementary hydrostatic form
    const auto el = overlap_moments(0.04, 0.04, p0, p1, true), hy = overlap_moments(0.04, 0.04, p0, p1);
    EXPECT_NEAR(el[0], hy[0], 1e-15);
    EXPECT_NEAR(el[1], hy[1], 1e-15);
    // continuity in a at the closed-die limit (difference bounded by sqrt(a) (phi1 - phi0)) ...
    for (double a : {1e-10, 1e-14, 1e-20}) {
      const auto g = overlap_moments(a, 0.08, p0, p1), cd = overlap_moments(0.0, 0.08, p0, p1);
      EXPECT_NEAR(g[0], cd[0], std::sqrt(a) * (p1 - p0) + 1e-15);
      EXPECT_NEAR(g[1], cd[1], std::sqrt(a) * (p1 - p0) + 1e-15);
      const auto g2 = overlap_moments(0.08, a, p0, p1), cd2 = overlap_moments(0.08, 0.0, p0, p1);
      EXPECT_NEAR(g2[0], cd2[0], std::sqrt(a) * (p1 - p0) + 1e-15);
      EXPECT_NEAR(g2[1], cd2[1], std::sqrt(a) * (p1 - p0) + 1e-15);
    }
    // ... and at the hydrostatic limit
    const auto n = overlap_moments(0.04, 0.04 * (1 + 1e-12), p0, p1);
    EXPECT_NEAR(n[0], hy[0], 1e-13);
    EXPECT_NEAR(n[1], hy[1], 1e-13);
  }
}

TEST(AnalyticYield, BadInputThrowsOneLineMessage) {
  auto expect_throw = [](const std::function<void()>& f, const std::string& what) {
    try {
      f();
      ADD_FAILURE() << "no exception: " << what;
    } catch (const std::invalid_argument& e) {
      const std::string msg = e.what();
      EXPECT_FALSE(msg.empty()) << what;
      EXPECT_EQ(msg.find('\n'), std::string::npos) << what;
    }
  };
  const AffineYieldInput good = input(-0.01, -0.02);
  auto with = [&](auto mutate) {
    AffineYieldInput in = good;
    mutate(in);
    return in;
  };
  const std::vector<std::pair<std::string, AffineYieldInput>> bad = {
      {"negative density", with([](auto& in) { in.density = -0.5; })},
      {"zero density", with([](auto& in) { in.density = 0.0; })},
      {"density above 1", with([](auto& in) { in.density = 1.2; })},
      {"NaN density", with([](auto& in) { in.density = std::nan(""); })},
      {"zero z0", with([](auto& in) { in.z0 = 0.0; })},
      {"negative z0", with([](auto& in) { in.z0 = -3.0; })},
      {"zero sigma_y", with([](auto& in) { in.sigma_y = 0.0; })},
      {"positive E11", with([](auto& in) { in.E11 = 0.01; })},
      {"positive E22", with([](auto& in) { in.E22 = 1e-9; })},
      {"infinite E22", with([](auto& in) { in.E22 = -INFINITY; })},
  };
  for (const auto& item : bad) {
    const std::string& what = item.first;
    const AffineYieldInput& in = item.second;
    expect_throw([&] { in.validate(); }, what);
    expect_throw([&] { qs::affine_yield_point(in, 2.0); }, what);
    expect_throw([&] { qs::affine_dissipation(in, -1.0, 0.5); }, what);
    expect_throw([&] { qs::affine_loading_point(in); }, what);
  }
  expect_throw([&] { qs::affine_yield_stress(good, 0.0, 0.0); }, "zero rate");
  expect_throw([&] { qs::affine_yield_stress(good, NAN, 1.0); }, "NaN rate");
  expect_throw([&] { qs::affine_yield_point(good, INFINITY); }, "infinite theta");
  expect_throw([&] { qs::affine_yield_input(0.0, 0.85, 4, 1, -1, -1); }, "d0 = 0");
  expect_throw([&] { qs::affine_yield_input(0.9, 0.85, 4, 1, -1, -1); }, "d < d0");
  expect_throw([&] { qs::affine_yield_input(0.8, 0.85, 4, 1, 0.5, -1); }, "tensile direction");
  expect_throw([&] { qs::affine_yield_input(0.8, 0.85, 4, 1, 0, 0); }, "zero direction");
  expect_throw([&] { qs::affine_yield_input(0.8, 0.85, -4, 1, -1, -1); }, "negative z0");
  EXPECT_EQ(qs::affine_dissipation(good, 0.0, 0.0), 0.0);
  EXPECT_NO_THROW(good.validate());
  // no accumulated strain: the surface collapses to the origin
  const YieldPoint z = qs::affine_loading_point(qs::affine_yield_input(0.8, 0.8, 4, 1, -1, -1));
  EXPECT_EQ(z.S11, 0.0);
  EXPECT_EQ(z.S22, 0.0);
}
