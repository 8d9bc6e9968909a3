// Tests of the analytic affine upper-bound yield surfaces of sphere packings (docs/yield_analytic.md
// "3D"): the general evaluation against an independent Love-Weber sum over a quasi-uniform set of
// a million contact normals, against the (p, q) closed forms and the closed-form vertex; the
// stated numbers of the notes (p = 1.5 Z D sigma_y |E|, closed-die vertex 0.9 / 0.3, the isochoric
// probes); rotation covariance, normality and convexity (frictionless), homogeneity and linearity,
// the sticking limits, and input validation.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include "netdem/quasistatic/analytic_yield3.hpp"

using namespace netdem;
using Mat3 = Eigen::Matrix3d;
using Vec3 = Eigen::Vector3d;
using qs::AffineYield3Input;

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180.0;
const double kStick = 1.0 / (3.0 * std::sqrt(3.0));  // min(mu, tau_y / sigma_y / 3) for mu = inf

AffineYield3Input input(const Mat3& E, double mu_eff = 0.0, double d = 0.85, double z = 7.0) {
  AffineYield3Input in;
  in.density = d;
  in.z0 = z;
  in.sigma_y = 1.0;
  in.E = E;
  in.mu_eff = mu_eff;
  return in;
}

Mat3 hydro(double e = -0.02) { return e * Mat3::Identity(); }
Mat3 die(double e = -0.04) { return Vec3(0.0, 0.0, e).asDiagonal(); }

// A general compressive strain with principal axes off the coordinate axes.
Mat3 general_strain() {
  const Mat3 Q = Eigen::AngleAxisd(0.7, Vec3(1.0, 2.0, -0.5).normalized()).toRotationMatrix();
  return Q * Vec3(-0.01, -0.025, -0.04).asDiagonal() * Q.transpose();
}

Mat3 sym(const Mat3& m) { return 0.5 * (m + m.transpose()); }

Mat3 random_rate(std::mt19937& rng) {
  std::normal_distribution<double> g;
  Mat3 m;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) m(i, j) = g(rng);
  return sym(m);
}

// The independent reference: the Love-Weber sum over N contact normals of a Fibonacci sphere
// (quasi-uniform, each of weight 4 pi / N), every contact with the force of the model. Plain scalars
// (the test runs under the sanitizers too).
Mat3 love_weber(const AffineYield3Input& in, const Mat3& rate, int n = 1000000) {
  const double golden = kPi * (3.0 - std::sqrt(5.0));
  double s[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
  double R[3][3], E[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) R[i][j] = rate(i, j), E[i][j] = in.E(i, j);
  for (int k = 0; k < n; ++k) {
    const double z = 1.0 - (2.0 * k + 1.0) / n, r = std::sqrt(1.0 - z * z);
    const double nv[3] = {r * std::cos(golden * k), r * std::sin(golden * k), z};
    double rn[3], en = 0.0, f = 0.0;
    for (int i = 0; i < 3; ++i) {
      rn[i] = R[i][0] * nv[0] + R[i][1] * nv[1] + R[i][2] * nv[2];
      en += nv[i] * rn[i];
      f -= nv[i] * (E[i][0] * nv[0] + E[i][1] * nv[1] + E[i][2] * nv[2]);  // force / (6 pi sigma_y R^2)
    }
    if (!(en < 0.0)) continue;
    double vt[3], speed = 0.0;
    for (int i = 0; i < 3; ++i) vt[i] = rn[i] - en * nv[i], speed += vt[i] * vt[i];
    speed = std::sqrt(speed);
    const double mu = in.mu_eff > 0.0 && speed > 0.0 ? in.mu_eff / speed : 0.0;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) s[i][j] += f * (-nv[i] * nv[j] + 0.5 * mu * (vt[i] * nv[j] + nv[i] * vt[j]));
  }
  Mat3 sig;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) sig(i, j) = s[i][j];
  return (9.0 * in.density * in.z0 * in.sigma_y / (8.0 * kPi)) * (4.0 * kPi / n) * sig;
}

double rel(const Mat3& a, const Mat3& b, double scale) { return (a - b).cwiseAbs().maxCoeff() / scale; }

}  // namespace

TEST(AnalyticYield3, VertexIsTheStatedClosedForm) {
  // Isotropic affine bound (notes: p = 1.5 Z D sigma_y |E|; closed die sigma_zz = 0.9, sigma_rr = 0.3
  // in units of Z D sigma_y |E33|), and (3 D Z sigma_y / 10)(tr E I + 2E) for any E: every compressive
  // rate gives it, by the general quadrature.
  const auto h = input(hydro(-0.02)), d = input(die(-0.04));
  const double sh = 0.85 * 7.0 * 0.02, sd = 0.85 * 7.0 * 0.04;
  EXPECT_NEAR(qs::affine_vertex3(h)(0, 0) / sh, -1.5, 1e-14);
  EXPECT_NEAR(qs::affine_vertex3(h)(2, 2) / sh, -1.5, 1e-14);
  EXPECT_NEAR(qs::affine_vertex3(d)(2, 2) / sd, -0.9, 1e-14);
  EXPECT_NEAR(qs::affine_vertex3(d)(0, 0) / sd, -0.3, 1e-14);
  EXPECT_NEAR(qs::affine_vertex3(d)(1, 1) / sd, -0.3, 1e-14);
  std::mt19937 rng(5);
  for (const Mat3& E : {hydro(), die(), general_strain()}) {
    auto in = input(E);
    const Mat3 v = qs::affine_vertex3(in);
    const double scale = v.norm();
    for (int k = 0; k < 20; ++k) {
      Mat3 r = random_rate(rng);
      const Eigen::SelfAdjointEigenSolver<Mat3> eig(r);
      r = -(eig.eigenvectors() * eig.eigenvalues().cwiseAbs().asDiagonal() * eig.eigenvectors().transpose());
      EXPECT_LT(rel(qs::affine_yield3_stress(in, r), v, scale), 1e-14);
    }
    // the quadrature of the same integral over the whole sphere: sticking with a purely normal rate
    // (the precompaction direction of a hydrostatic strain has no tangential velocity)
    in.mu_eff = kStick;
    if (E == hydro()) {
      EXPECT_LT(rel(qs::affine_yield3_stress(in, -Mat3::Identity()), v, scale), 1e-13);
    }
    EXPECT_LT(rel(love_weber(in, -Mat3::Identity() - 1e-3 * E), qs::affine_yield3_stress(in, -Mat3::Identity() - 1e-3 * E), scale), 2e-4);
  }
}

TEST(AnalyticYield3, IsochoricProbesAfterHydrostaticPrecompaction) {
  // Notes: (p, |q|) = (0.634, 0.866) for isochoric compression and (0.866, 0.866) for extension, in
  // units of Z D sigma_y |E|; exactly ((3 - sqrt 3)/2, sqrt 3 / 2) and (sqrt 3 / 2, sqrt 3 / 2) (the
  // switch cosine is 1/sqrt 3 for both).
  const auto in = input(hydro(-0.02));
  const double s = 0.85 * 7.0 * 0.02, r3 = std::sqrt(3.0);
  const auto comp = qs::affine_yield3_pq(in, -90 * kDeg), ext = qs::affine_yield3_pq(in, 90 * kDeg);
  EXPECT_NEAR(comp.p / s, (3.0 - r3) / 2.0, 1e-13);
  EXPECT_NEAR(comp.q / s, -r3 / 2.0, 1e-13);
  EXPECT_NEAR(ext.p / s, r3 / 2.0, 1e-13);
  EXPECT_NEAR(ext.q / s, r3 / 2.0, 1e-13);
  EXPECT_NEAR(std::round(comp.p / s * 1000) / 1000, 0.634, 1e-12);
  EXPECT_NEAR(std::round(ext.p / s * 1000) / 1000, 0.866, 1e-12);
  // the hydrostatic point and the vertex cone psi in [-90 deg + atan.., ...]: psi = 0 is the vertex
  EXPECT_NEAR(qs::affine_yield3_pq(in, 0.0).p / s, 1.5, 1e-13);
  EXPECT_NEAR(qs::affine_yield3_pq(in, 0.0).q / s, 0.0, 1e-13);
  // pure extension (psi = 180 deg) loads nothing
  EXPECT_EQ(qs::affine_yield3_pq(in, kPi).p, 0.0);
}

TEST(AnalyticYield3, GeneralQuadratureMatchesPQClosedForms) {
  // The general evaluation (eigenframe of the rate, Gauss-Legendre in both angles) against the
  // polynomial closed forms of the axisymmetric plane, frictionless and sticking, 72 directions.
  const Mat3 axi = Vec3(-0.01, -0.01, -0.035).asDiagonal();
  for (const Mat3& E : {hydro(), die(), axi}) {
    for (const double mu : {0.0, kStick, 0.5}) {
      const auto in = input(E, mu);
      const double scale = std::abs(qs::pq_of(qs::affine_vertex3(in)).p);
      for (int k = 0; k < 36; ++k) {
        const double psi = 10.0 * k * kDeg;
        const auto ref = qs::affine_yield3_pq(in, psi);
        const auto got = qs::pq_of(qs::affine_yield3_stress(in, qs::axisymmetric_rate(psi)));
        EXPECT_NEAR(got.p / scale, ref.p / scale, 1e-12) << "psi " << 10 * k << " mu " << mu;
        EXPECT_NEAR(got.q / scale, ref.q / scale, 1e-12) << "psi " << 10 * k << " mu " << mu;
      }
    }
  }
}

TEST(AnalyticYield3, GeneralQuadratureMatchesLoveWeberSum) {
  // Any E, any rate (not coaxial), frictionless and sticking, against the Fibonacci-sphere sum.
  std::mt19937 rng(11);
  for (const Mat3& E : {hydro(), die(), general_strain()}) {
    for (const double mu : {0.0, kStick}) {
      const auto in = input(E, mu);
      const double scale = qs::affine_vertex3(in).norm();
      double worst = 0.0;
      for (int k = 0; k < 2; ++k) {
        const Mat3 r = random_rate(rng);
        worst = std::max(worst, rel(qs::affine_yield3_stress(in, r), love_weber(in, r), scale));
      }
      EXPECT_LT(worst, 2e-4) << "mu " << mu;
      std::printf("Love-Weber sum, mu_eff %.3f: worst %.2e of the vertex\n", mu, worst);
    }
  }
}

TEST(AnalyticYield3, QuadratureHasConverged) {
  // Frictionless, the integrand is analytic inside each panel (exponential convergence); sticking,
  // the tangential speed vanishes at the rate's eigen-directions on the equator (a cone point at a
  // corner of the panels: algebraic convergence; 2 against 32 panels: 1.6e-10 of the vertex).
  std::mt19937 rng(13);
  for (const double mu : {0.0, kStick}) {
    const auto in = input(general_strain(), mu);
    const double scale = qs::affine_vertex3(in).norm();
    double worst = 0.0;
    for (int k = 0; k < 5; ++k) {
      const Mat3 r = random_rate(rng);
      worst = std::max(worst, rel(qs::affine_yield3_stress(in, r), qs::detail::affine_yield3_stress(in, r, 8), scale));
    }
    EXPECT_LT(worst, mu == 0.0 ? 1e-12 : 1e-8) << "mu " << mu;
    std::printf("2 against 8 panels, mu_eff %.3f: worst %.2e of the vertex\n", mu, worst);
  }
}

TEST(AnalyticYield3, RotatingInputAndRateRotatesTheStress) {
  std::mt19937 rng(3);
  const Mat3 Q = Eigen::AngleAxisd(1.1, Vec3(0.3, -1.0, 0.4).normalized()).toRotationMatrix();
  for (const double mu : {0.0, kStick}) {
    for (int k = 0; k < 10; ++k) {
      const Mat3 r = random_rate(rng);
      const auto a = input(general_strain(), mu), b = input(Q * general_strain() * Q.transpose(), mu);
      const Mat3 sa = qs::affine_yield3_stress(a, r), sb = qs::affine_yield3_stress(b, Q * r * Q.transpose());
      EXPECT_LT(rel(Q * sa * Q.transpose(), sb, qs::affine_vertex3(a).norm()), 1e-9) << "mu " << mu;
    }
  }
}

TEST(AnalyticYield3, FrictionlessStressIsGradientAndSupportPoint) {
  std::mt19937 rng(7);
  const auto in = input(general_strain());
  const double scale = qs::affine_vertex3(in).norm();
  std::vector<Mat3> rates;
  for (int k = 0; k < 20; ++k) rates.push_back(random_rate(rng));
  for (const Mat3& r : rates) {
    const Mat3 s = qs::affine_yield3_stress(in, r);
    // normality: Sigma = dW/dEdot (central differences on the six components)
    const double h = 1e-6;
    for (int i = 0; i < 3; ++i)
      for (int j = i; j < 3; ++j) {
        Mat3 d = Mat3::Zero();
        d(i, j) = d(j, i) = h;
        const double g = (qs::affine_dissipation3(in, r + d) - qs::affine_dissipation3(in, r - d)) / (2.0 * h);
        EXPECT_NEAR(g / (i == j ? 1.0 : 2.0) / scale, s(i, j) / scale, 1e-6);
      }
    // convexity: every other point lies inside the half-space of this normal
    for (const Mat3& o : rates)
      EXPECT_LE(qs::affine_yield3_stress(in, o).cwiseProduct(r).sum(), qs::affine_dissipation3(in, r) + 1e-12 * scale);
  }
}

TEST(AnalyticYield3, HomogeneousInRateAndLinearInStateAndFriction) {
  std::mt19937 rng(9);
  const Mat3 r = random_rate(rng);
  const auto in = input(general_strain(), kStick);
  const Mat3 s = qs::affine_yield3_stress(in, r);
  const double scale = qs::affine_vertex3(in).norm();
  EXPECT_LT(rel(qs::affine_yield3_stress(in, 7.5 * r), s, scale), 1e-13);
  auto twice = in;
  twice.E *= 2.0;  // the sphere law is linear in the overlap
  EXPECT_LT(rel(qs::affine_yield3_stress(twice, r), 2.0 * s, scale), 1e-13);
  twice = in;
  twice.z0 *= 2.0;
  twice.density *= 0.5;
  twice.sigma_y *= 3.0;
  EXPECT_LT(rel(qs::affine_yield3_stress(twice, r), 3.0 * s, scale), 1e-13);
  auto m0 = in, m2 = in;
  m0.mu_eff = 0.0;
  m2.mu_eff = 2.0 * kStick;
  const Mat3 s0 = qs::affine_yield3_stress(m0, r), s2 = qs::affine_yield3_stress(m2, r);
  EXPECT_LT(rel(s2 - s, s - s0, scale), 1e-12);
  EXPECT_GT((s - s0).norm() / scale, 1e-3);  // the tangential part is there
  EXPECT_GE(qs::affine_dissipation3(in, r), qs::affine_dissipation3(m0, r));
}

TEST(AnalyticYield3, AffineYieldInputFollowsTheDensity) {
  const auto h = qs::affine_yield3_input(0.64, 0.7, 7.0, 1.0, -Mat3::Identity(), 0.0);
  EXPECT_NEAR(h.E.trace(), -std::log(0.7 / 0.64), 1e-15);
  EXPECT_NEAR(h.E(0, 0), h.E(2, 2), 1e-16);
  const auto d = qs::affine_yield3_input(0.64, 0.7, 7.0, 1.0, die(-1.0), kStick);
  EXPECT_NEAR(d.E(2, 2), -std::log(0.7 / 0.64), 1e-15);
  EXPECT_EQ(d.E(0, 0), 0.0);
}

TEST(AnalyticYield3, BadInputThrowsOneLineMessage) {
  auto expect_throw = [](auto&& f, const std::string& what) {
    try {
      f();
      ADD_FAILURE() << "no throw: " << what;
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  const Mat3 r = -Mat3::Identity();
  expect_throw([&] { qs::affine_yield3_stress(input(hydro(), 0.0, 1.5), r); }, "relative density");
  expect_throw([&] { qs::affine_yield3_stress(input(hydro(), 0.0, 0.8, 0.0), r); }, "coordination");
  expect_throw([&] { qs::affine_yield3_stress(input(-hydro()), r); }, "compressive");
  expect_throw([&] { qs::affine_yield3_stress(input(hydro(), -1.0), r); }, "mu_eff");
  Mat3 asym = Mat3::Zero();
  asym(0, 1) = 1.0;
  expect_throw([&] { qs::affine_yield3_stress(input(hydro()), asym); }, "symmetric");
  expect_throw([&] { qs::affine_yield3_stress(input(hydro()), Mat3::Zero()); }, "no direction");
  expect_throw([&] { qs::affine_yield3_stress(input(hydro()), Mat3::Constant(NAN)); }, "non-finite");
  expect_throw([&] { qs::affine_yield3_pq(input(general_strain()), 0.0); }, "axisymmetric");
  expect_throw([&] { qs::affine_yield3_input(0.7, 0.6, 7.0, 1.0, r, 0.0); }, "below the initial");
  expect_throw([&] { qs::axisymmetric_rate(NAN); }, "not finite");
}
