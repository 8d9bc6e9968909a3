#include "netdem/quasistatic/analytic_yield3.hpp"
#include "netdem/quasistatic/analytic_yield.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include <Eigen/Eigenvalues>
#include <boost/math/quadrature/gauss.hpp>
#include <fmt/format.h>

namespace netdem::qs {

namespace {

using Mat3 = Eigen::Matrix3d;
using Vec3 = Eigen::Vector3d;
constexpr double kPi = std::numbers::pi;
constexpr double kHalfPi = std::numbers::pi / 2;

// 9 D Z0 sigma_y / (8 pi): contacts per volume 3 D Z0 / (8 pi R^3), normals of density 1/(4 pi),
// force 6 pi sigma_y R^2 (-n.E.n) on the lever 2R (docs/yield_analytic.md "3D").
double prefactor(const AffineYield3Input& in) { return 9.0 * in.density * in.z0 * in.sigma_y / (8.0 * kPi); }

// Calls visit(x, w) for the nodes and weights of `panels` 30-point Gauss-Legendre panels on [a, b].
template <class F>
void gauss_nodes(double a, double b, int panels, F&& visit) {
  using Rule = boost::math::quadrature::gauss<double, 30>;
  const double h = (b - a) / panels;
  for (int k = 0; k < panels; ++k) {
    const double mid = a + (k + 0.5) * h, half = 0.5 * h;
    for (std::size_t i = 0; i < Rule::abscissa().size(); ++i) {
      const double x = Rule::abscissa()[i], w = Rule::weights()[i] * half;
      visit(mid + half * x, w);
      if (x != 0.0) visit(mid - half * x, w);
    }
  }
}

bool is_symmetric(const Mat3& m) { return (m - m.transpose()).cwiseAbs().maxCoeff() <= 1e-12 * std::max(1.0, m.cwiseAbs().maxCoeff()); }

void check_rate(const Mat3& Edot) {
  if (!Edot.allFinite()) throw std::invalid_argument("strain rate has a non-finite component");
  if (!is_symmetric(Edot)) throw std::invalid_argument("strain rate must be a symmetric tensor");
}

// The stress of the affine mechanism in the eigenframe of the rate, rate = diag(lam), E in that frame.
// The polar axis (index 2 of `lam`) is the eigenvector whose eigenvalue has the sign the other two do
// not have, so that the active set of the upper hemisphere is one interval in theta for every phi:
// theta < theta*(phi) (polar eigenvalue < 0) or theta > theta*(phi) (> 0), with
// tan^2 theta* = -lam_p / B(phi), B = lam_a cos^2 phi + lam_b sin^2 phi. theta*(phi) is analytic inside
// each quadrant of phi, so the outer rule converges fast; the inner integrand is a trigonometric
// polynomial (frictionless) or has the tangential speed's zeros at the eigen-directions (sticking).
Mat3 frame_stress(const AffineYield3Input& in, const Mat3& Ef, const Vec3& lam, bool all_active, int panels,
                  double& w_out) {
  Mat3 sig = Mat3::Zero();
  double w = 0.0;
  const double lp = lam[2];
  for (int quad = 0; quad < 4; ++quad) {
    gauss_nodes(quad * kHalfPi, (quad + 1) * kHalfPi, panels, [&](double phi, double wphi) {
      const double c = std::cos(phi), s = std::sin(phi);
      double t0 = 0.0, t1 = kHalfPi;
      if (!all_active) {
        const double B = lam[0] * c * c + lam[1] * s * s;
        if (lp < 0.0) t1 = std::atan2(std::sqrt(-lp), std::sqrt(std::max(B, 0.0)));
        else t0 = std::atan2(std::sqrt(lp), std::sqrt(std::max(-B, 0.0)));
      }
      if (!(t1 > t0)) return;
      gauss_nodes(t0, t1, panels, [&](double th, double wth) {
        const double st = std::sin(th);
        const Vec3 n(st * c, st * s, std::cos(th));
        const double weight = wphi * wth * st;
        const double e = -n.dot(Ef * n);  // overlap / 2R, >= 0
        const Vec3 rn = lam.cwiseProduct(n);
        const double en = n.dot(rn);  // normal strain rate (< 0: compressed)
        sig.noalias() -= weight * e * n * n.transpose();
        w += weight * e * (-en);
        if (in.mu_eff > 0.0) {
          const Vec3 vt = rn - en * n;  // tangential velocity / 2R
          const double speed = vt.norm();
          if (speed > 1e-12 * lam.cwiseAbs().maxCoeff()) {  // rounding has no direction
            const Vec3 t = vt / speed;
            sig.noalias() += weight * e * in.mu_eff * 0.5 * (t * n.transpose() + n * t.transpose());
            w += weight * e * in.mu_eff * speed;
          }
        }
      });
    });
  }
  const double k = 2.0 * prefactor(in);  // x2: the lower hemisphere (the integrand is even in n)
  w_out = k * w;
  return k * sig;
}

}  // namespace

void AffineYield3Input::validate() const {
  detail::validate_aggregate(density, z0, sigma_y);
  if (!(mu_eff >= 0.0 && std::isfinite(mu_eff)))
    throw std::invalid_argument(fmt::format("tangential limit mu_eff must be finite and >= 0, got {}", mu_eff));
  if (!E.allFinite() || !is_symmetric(E))
    throw std::invalid_argument("precompaction strain must be a finite symmetric tensor");
  const double top = Eigen::SelfAdjointEigenSolver<Mat3>(E, Eigen::EigenvaluesOnly).eigenvalues().maxCoeff();
  if (top > 1e-12 * std::max(1.0, E.cwiseAbs().maxCoeff()))
    throw std::invalid_argument(
        fmt::format("precompaction strain must be compressive (negative semidefinite), largest principal value {}", top));
}

AffineYield3Input affine_yield3_input(double d0, double d, double z0, double sigma_y, const Mat3& direction,
                                      double mu_eff) {
  if (!(d0 > 0.0 && std::isfinite(d0)))
    throw std::invalid_argument(fmt::format("initial relative density d0 must be positive, got {}", d0));
  if (!(d >= d0 && std::isfinite(d)))
    throw std::invalid_argument(fmt::format("relative density {} is below the initial density {}", d, d0));
  if (!direction.allFinite() || !(direction.trace() < 0.0))
    throw std::invalid_argument("precompaction direction must be finite with a negative trace (compacting)");
  AffineYield3Input in;
  in.density = d;
  in.z0 = z0;
  in.sigma_y = sigma_y;
  in.mu_eff = mu_eff;
  in.E = direction * (std::log(d / d0) / -direction.trace());
  in.validate();
  return in;
}

Mat3 affine_vertex3(const AffineYield3Input& in) {
  in.validate();
  return 0.3 * in.density * in.z0 * in.sigma_y * (in.E.trace() * Mat3::Identity() + 2.0 * in.E);
}

Mat3 affine_yield3_stress(const AffineYield3Input& in, const Mat3& Edot) {
  return detail::affine_yield3_stress(in, Edot, 2);
}

namespace detail {

Mat3 affine_yield3_stress(const AffineYield3Input& in, const Mat3& Edot, int panels) {
  double w = 0.0;
  if (panels < 1) throw std::invalid_argument(fmt::format("quadrature panels must be >= 1, got {}", panels));
  in.validate();
  check_rate(Edot);
  if (Edot.isZero(0.0)) throw std::invalid_argument("strain rate 0 has no direction");
  const Eigen::SelfAdjointEigenSolver<Mat3> eig(0.5 * (Edot + Edot.transpose()));
  Vec3 lam = eig.eigenvalues() / eig.eigenvalues().cwiseAbs().maxCoeff();  // ascending
  for (int i = 0; i < 3; ++i)
    if (std::abs(lam[i]) < 1e-14) lam[i] = 0.0;  // what rounding of the direction cannot resolve
  if (lam[0] >= 0.0) return Mat3::Zero();  // nothing is compressed
  const bool all_active = lam[2] <= 0.0;
  if (all_active && in.mu_eff == 0.0) return affine_vertex3(in);
  // polar axis: the eigenvalue of the odd sign (one negative -> index 0, two negative -> index 2);
  // all compressive: the most distinct one, so that a double eigenvalue (an axisymmetric rate) is
  // the equator, where the tangential speed then has no zero
  const int p = all_active ? (lam[1] - lam[0] > lam[2] - lam[1] ? 0 : 2) : (lam[1] < 0.0 ? 2 : 0);
  const int a = p == 2 ? 0 : 1, b = p == 2 ? 1 : 2;
  Mat3 F;
  F.col(0) = eig.eigenvectors().col(a);
  F.col(1) = eig.eigenvectors().col(b);
  F.col(2) = eig.eigenvectors().col(p);
  const Vec3 lf(lam[a], lam[b], lam[p]);
  const Mat3 sig = frame_stress(in, F.transpose() * in.E * F, lf, all_active, panels, w);
  return F * sig * F.transpose();
}

}  // namespace detail

double affine_dissipation3(const AffineYield3Input& in, const Mat3& Edot) {
  in.validate();
  check_rate(Edot);
  if (Edot.isZero(0.0)) return 0.0;
  return std::max(0.0, affine_yield3_stress(in, Edot).cwiseProduct(Edot).sum());
}

Mat3 axisymmetric_rate(double psi) {
  if (!std::isfinite(psi)) throw std::invalid_argument(fmt::format("direction angle psi = {} is not finite", psi));
  const double ev = std::cos(psi), eq = std::sin(psi);
  const double e11 = -ev / 3.0 - eq / 2.0, e33 = -ev / 3.0 + eq;
  return Vec3(e11, e11, e33).asDiagonal();
}

PQPoint pq_of(const Mat3& s) { return {-s.trace() / 3.0, s(2, 2) - 0.5 * (s(0, 0) + s(1, 1))}; }

PQPoint affine_yield3_pq(const AffineYield3Input& in, double psi) {
  in.validate();
  const Mat3& E = in.E;
  const double off = std::max({std::abs(E(0, 1)), std::abs(E(0, 2)), std::abs(E(1, 2))});
  if (std::abs(E(0, 0) - E(1, 1)) > 1e-12 * E.cwiseAbs().maxCoeff() || off > 0.0)
    throw std::invalid_argument("the (p, q) closed form needs a precompaction strain axisymmetric about z");
  const Mat3 rate = axisymmetric_rate(psi);
  double r1 = rate(0, 0), r3 = rate(2, 2);
  if (std::abs(r1) < 1e-15) r1 = 0.0;
  if (std::abs(r3) < 1e-15) r3 = 0.0;
  if (r1 >= 0.0 && r3 >= 0.0) return {0.0, 0.0};
  // the active cosines mu = |n3| of [0, 1]: n.Edot.n = r1 + (r3 - r1) mu^2 < 0
  double m0 = 0.0, m1 = 1.0;
  if (r1 < 0.0 && r3 > 0.0) m1 = std::sqrt(-r1 / (r3 - r1));
  if (r3 < 0.0 && r1 > 0.0) m0 = std::sqrt(r1 / (r1 - r3));
  // -n.E.n = a + b mu^2 with a = -E11, b = E11 - E33
  const double a = -E(0, 0), b = E(0, 0) - E(2, 2);
  auto pw = [](double x, int k) { return std::pow(x, k); };
  auto diff = [&](int k) { return pw(m1, k) - pw(m0, k); };
  const double i2 = a * diff(3) / 3.0 + b * diff(5) / 5.0;                         // int (a + b mu^2) mu^2
  const double ip = a * diff(1) + (b - a) * diff(3) / 3.0 - b * diff(5) / 5.0;     // int (a + b mu^2)(1 - mu^2)
  auto prim_t = [&](double m) {  // primitive of (a + b mu^2) mu sqrt(1 - mu^2)
    const double w = 1.0 - m * m;
    return -(a + b) * std::pow(w, 1.5) / 3.0 + b * std::pow(w, 2.5) / 5.0;
  };
  const double it = prim_t(m1) - prim_t(m0);
  const double dz = in.density * in.z0 * in.sigma_y;
  const double sgn = r3 > r1 ? 1.0 : (r3 < r1 ? -1.0 : 0.0);
  const double s33 = -4.5 * dz * i2 + 4.5 * dz * in.mu_eff * sgn * it;
  const double s11 = -2.25 * dz * ip - 2.25 * dz * in.mu_eff * sgn * it;
  return {-(2.0 * s11 + s33) / 3.0, s33 - s11};
}

}  // namespace netdem::qs
