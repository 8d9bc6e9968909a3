#include "netdem/quasistatic/analytic_yield.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <utility>

#include <boost/math/special_functions/ellint_rd.hpp>
#include <boost/math/special_functions/ellint_rf.hpp>
#include <fmt/format.h>

namespace netdem::qs {

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kHalfPi = std::numbers::pi / 2;

// (12 / pi^2) D Z0 sigma_y: the prefactor of the dissipation (Appendix A, Eq A4).
double prefactor(const AffineYieldInput& in) { return 12.0 / (kPi * kPi) * in.density * in.z0 * in.sigma_y; }

// Integrals from 0 to phi of sqrt(c^2 + r s^2) {c^2, s^2} (c = cos, s = sin), 0 < r <= 1, in terms of
// F = int 1/w, G = int s^2/w (w^2 = 1 - m s^2 = c^2 + r s^2, m = 1 - r), using
//   int w s^2 = (F + (1 - 2m) G - s c w) / 3,   int w c^2 = (2F - (1 + m) G + s c w) / 3
// (from d(s c w)/dphi = (1 - 2(1 + m) s^2 + 3m s^4) / w), F = s R_F(c^2, w^2, 1),
// G = (s^3 / 3) R_D(c^2, w^2, 1) (DLMF section 19.25). Both stay finite and free of 1/m cancellation
// for m -> 0 (hydrostatic); r > 0 keeps R_F finite at phi = pi/2.
std::array<double, 2> elliptic_primitive(double phi, double r) {
  const double s = std::sin(phi), c = std::cos(phi);
  const double c2 = c * c, w2 = c2 + r * s * s, m = 1.0 - r;
  const double F = s * detail::carlson_rf(c2, w2, 1.0);
  const double G = s * s * s / 3.0 * detail::carlson_rd(c2, w2, 1.0);
  const double scw = s * c * std::sqrt(w2);
  return {(2.0 * F - (1.0 + m) * G + scw) / 3.0, (F + (1.0 - 2.0 * m) * G - scw) / 3.0};
}

// Snaps strain-rate components that a direction angle theta cannot resolve (|x| of a few ulps of 2 pi)
// to zero, so that theta = pi, 3 pi / 2, ... give the vertex exactly.
double snap(double x) { return std::abs(x) < 1e-15 ? 0.0 : x; }

void check_rate(double E11dot, double E22dot) {
  if (!std::isfinite(E11dot) || !std::isfinite(E22dot))
    throw std::invalid_argument(fmt::format("strain rate ({}, {}) is not finite", E11dot, E22dot));
}

}  // namespace

void AffineYieldInput::validate() const {
  detail::validate_aggregate(density, z0, sigma_y);
  if (!(E11 <= 0.0 && E22 <= 0.0 && std::isfinite(E11) && std::isfinite(E22)))
    throw std::invalid_argument(fmt::format(
        "accumulated precompaction strain (E11, E22) = ({}, {}) must be finite and <= 0 (compressive)", E11, E22));
}

AffineYieldInput affine_yield_input(double d0, double d, double z0, double sigma_y, double dir11, double dir22) {
  if (!(d0 > 0.0 && std::isfinite(d0)))
    throw std::invalid_argument(fmt::format("initial relative density d0 must be positive, got {}", d0));
  if (!(d >= d0 && std::isfinite(d)))
    throw std::invalid_argument(fmt::format("relative density {} is below the initial density {}", d, d0));
  if (!(std::isfinite(dir11) && std::isfinite(dir22) && dir11 <= 0.0 && dir22 <= 0.0 && dir11 + dir22 < 0.0))
    throw std::invalid_argument(
        fmt::format("precompaction direction ({}, {}) must have components <= 0 and a negative sum", dir11, dir22));
  const double lambda = std::log(d / d0) / -(dir11 + dir22);
  AffineYieldInput in{d, z0, sigma_y, lambda * dir11, lambda * dir22};
  in.validate();
  return in;
}

double affine_switch_angle(double E11dot, double E22dot) {
  if (!(E11dot * E22dot < 0.0)) return std::numeric_limits<double>::quiet_NaN();
  return std::atan2(std::sqrt(std::abs(E11dot)), std::sqrt(std::abs(E22dot)));
}

YieldPoint affine_yield_stress(const AffineYieldInput& in, double E11dot, double E22dot) {
  in.validate();
  check_rate(E11dot, E22dot);
  if (E11dot == 0.0 && E22dot == 0.0) throw std::invalid_argument("strain rate (0, 0) has no direction");
  if (E11dot >= 0.0 && E22dot >= 0.0) return {0.0, 0.0};  // no contact is compressed
  double phi0 = 0.0, phi1 = kHalfPi;                      // both rates <= 0: all contacts active
  if (E11dot < 0.0 && E22dot > 0.0) phi1 = affine_switch_angle(E11dot, E22dot);
  if (E11dot > 0.0 && E22dot < 0.0) phi0 = affine_switch_angle(E11dot, E22dot);
  const auto mom = detail::overlap_moments(-2.0 * in.E11, -2.0 * in.E22, phi0, phi1);
  const double k = prefactor(in);
  return {-k * mom[0], -k * mom[1]};
}

YieldPoint affine_yield_point(const AffineYieldInput& in, double theta) {
  if (!std::isfinite(theta))
    throw std::invalid_argument(fmt::format("direction angle theta = {} is not finite", theta));
  return affine_yield_stress(in, snap(std::cos(theta)), snap(std::sin(theta)));
}

YieldPoint affine_loading_point(const AffineYieldInput& in) { return affine_yield_stress(in, -1.0, -1.0); }

double affine_dissipation(const AffineYieldInput& in, double E11dot, double E22dot) {
  in.validate();
  check_rate(E11dot, E22dot);
  if (E11dot == 0.0 && E22dot == 0.0) return 0.0;
  const YieldPoint s = affine_yield_stress(in, E11dot, E22dot);
  return std::max(0.0, s.S11 * E11dot + s.S22 * E22dot);  // Euler: W = Sigma : Edot (degree 1)
}

double affine_stress_scale(const AffineYieldInput& in) {
  in.validate();
  return in.density * in.z0 * in.sigma_y * std::sqrt(-2.0 * std::min(in.E11, in.E22));
}

namespace detail {

void validate_aggregate(double density, double z0, double sigma_y) {
  if (!(density > 0.0 && density <= 1.0))
    throw std::invalid_argument(fmt::format("relative density must be in (0, 1], got {}", density));
  if (!(z0 > 0.0 && std::isfinite(z0)))
    throw std::invalid_argument(fmt::format("coordination number z0 must be positive and finite, got {}", z0));
  if (!(sigma_y > 0.0 && std::isfinite(sigma_y)))
    throw std::invalid_argument(fmt::format("yield strength sigma_y must be positive and finite, got {}", sigma_y));
}

// Carlson's symmetric integrals from Boost.Math (duplication algorithm, relative error ~1e-15); the
// argument checks are ours, so that a bad argument is one std::invalid_argument naming the values.
double carlson_rf(double x, double y, double z) {
  if (!(x >= 0.0 && y >= 0.0 && z >= 0.0) || (x == 0.0) + (y == 0.0) + (z == 0.0) > 1 || !std::isfinite(x + y + z))
    throw std::invalid_argument(
        fmt::format("carlson_rf({}, {}, {}): arguments must be finite, >= 0, at most one zero", x, y, z));
  return boost::math::ellint_rf(x, y, z);
}

double carlson_rd(double x, double y, double z) {
  if (!(x >= 0.0 && y >= 0.0 && z > 0.0) || (x == 0.0 && y == 0.0) || !std::isfinite(x + y + z))
    throw std::invalid_argument(
        fmt::format("carlson_rd({}, {}, {}): need finite x, y >= 0 not both zero, z > 0", x, y, z));
  return boost::math::ellint_rd(x, y, z);
}

std::array<double, 2> overlap_moments(double a, double b, double phi0, double phi1, bool force_elliptic) {
  if (!(a >= 0.0 && b >= 0.0 && std::isfinite(a) && std::isfinite(b)))
    throw std::invalid_argument(fmt::format("overlap_moments: a = {}, b = {} must be finite and >= 0", a, b));
  if (!(0.0 <= phi0 && phi0 <= phi1 && phi1 <= kHalfPi))
    throw std::invalid_argument(
        fmt::format("overlap_moments: need 0 <= phi0 <= phi1 <= pi/2, got [{}, {}]", phi0, phi1));
  if (a == 0.0 && b == 0.0) return {0.0, 0.0};
  if (b == 0.0) {  // sqrt(a) cos: mirror of the a == 0 case (phi -> pi/2 - phi swaps cos and sin)
    const auto m = overlap_moments(0.0, a, kHalfPi - phi1, kHalfPi - phi0);
    return {m[1], m[0]};
  }
  if (a == 0.0) {  // closed die (E11 = 0): sqrt(b) sin phi
    // int s c^2 = (c0^3 - c1^3)/3, int s^3 = (c0 - c1) - (c0^3 - c1^3)/3, with c0 - c1 and
    // 3 - c0^2 - c0 c1 - c1^2 = 3 (s0^2 + s1^2)/2 + (c0 - c1)^2/2 written without cancellation.
    const double c0 = std::cos(phi0), c1 = std::cos(phi1), s0 = std::sin(phi0), s1 = std::sin(phi1);
    const double dc = 2.0 * std::sin((phi0 + phi1) / 2.0) * std::sin((phi1 - phi0) / 2.0);  // c0 - c1
    const double sb = std::sqrt(b);
    return {sb * dc * (c0 * c0 + c0 * c1 + c1 * c1) / 3.0, sb * dc * (1.5 * (s0 * s0 + s1 * s1) + 0.5 * dc * dc) / 3.0};
  }
  if (a == b && !force_elliptic) {  // hydrostatic: sqrt(a) {phi/2 + sin 2phi/4, phi/2 - sin 2phi/4}
    const double sa = std::sqrt(a), dphi = phi1 - phi0;
    const double ds2 = (std::sin(2.0 * phi1) - std::sin(2.0 * phi0)) / 4.0;
    return {sa * (dphi / 2.0 + ds2), sa * (dphi / 2.0 - ds2)};
  }
  if (a < b) {  // keep r = b/a <= 1 (m in [0, 1)) by measuring the angle from the 2-axis
    const auto m = overlap_moments(b, a, kHalfPi - phi1, kHalfPi - phi0, force_elliptic);
    return {m[1], m[0]};
  }
  const double r = b / a, sa = std::sqrt(a);
  const auto p1 = elliptic_primitive(phi1, r), p0 = elliptic_primitive(phi0, r);
  return {sa * (p1[0] - p0[0]), sa * (p1[1] - p0[1])};
}

}  // namespace detail

}  // namespace netdem::qs
