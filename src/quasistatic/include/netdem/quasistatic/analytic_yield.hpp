#pragma once
// Analytic upper-bound yield surfaces for affine motion of frictionless, cohesionless, rigid-plastic
// cylinders in 2D (Redanz & Fleck 2001, Appendix A, with its typos fixed; derivation and formulas in
// docs/yield_analytic.md, tests in tests/quasistatic/test_analytic_yield.cpp).
//
// Model: equal radii, Z0 contacts per particle with normals uniformly distributed in angle, Z0 constant,
// affine motion. A contact with normal n = (cos phi, sin phi) has the overlap u_N = -2R E(phi) with
// E(phi) = E11 cos^2 phi + E22 sin^2 phi (accumulated precompaction strain, principal axes 1, 2) and
// carries F_N = 3 sigma_y sqrt(8 u_N R/2) = 6 sigma_y R sqrt(-2E(phi)) (Eq 2). The plastic dissipation
// rate per unit volume (area) is
//   W(Edot) = (12 sigma_y D Z0 / pi^2) int_0^{pi/2} sqrt(-2E(phi)) max(-Edot(phi), 0) dphi,
// Edot(phi) = E11dot cos^2 phi + E22dot sin^2 phi: only contacts still being compressed dissipate.
// W is convex and positively homogeneous of degree 1 in Edot; the stress on the yield surface is its
// gradient Sigma = dW/dEdot (tension positive), with the strain rate as outward normal.
//
// Vertices: every rate with E11dot <= 0 and E22dot <= 0 (not both zero) gives the loading point (all
// contacts active); every rate with both components >= 0 gives the origin (no contact active).
#include <array>

#include "netdem/system/yield_curve.hpp"

namespace netdem::qs {

using sys::YieldPoint;  // the stress point type of every yield surface

/// State of the precompacted aggregate.
struct AffineYieldInput {
  double density = 0.0;  ///< relative density D at the end of precompaction, > 0
  double z0 = 0.0;       ///< coordination number Z0 (contacts per particle), > 0
  double sigma_y = 1.0;  ///< yield strength of the solid, > 0
  double E11 = 0.0;      ///< accumulated precompaction strain (logarithmic, from D0), <= 0
  double E22 = 0.0;      ///< accumulated precompaction strain, <= 0
  /// Throws std::invalid_argument with a one-line message if a value is out of range or not finite.
  void validate() const;
};

/// Input for a proportional precompaction from relative density d0 to d along the strain-rate direction
/// (dir11, dir22), dir11 + dir22 < 0: E = lambda (dir11, dir22) with E11 + E22 = -ln(d/d0), as in the
/// network solver (D = D0 exp(-(E11 + E22))). Hydrostatic: (-1, -1); closed die: (0, -1).
/// Throws std::invalid_argument (one line) for d0 <= 0, d < d0, a non-compacting direction or a
/// direction that gives a positive strain component.
AffineYieldInput affine_yield_input(double d0, double d, double z0, double sigma_y, double dir11, double dir22);

/// Stress on the yield surface for the strain rate (E11dot, E22dot) (only its direction matters):
/// the gradient of affine_dissipation. Throws std::invalid_argument for a zero or non-finite rate.
YieldPoint affine_yield_stress(const AffineYieldInput& in, double E11dot, double E22dot);

/// Stress on the surface whose outward normal is the strain-rate direction (cos theta, sin theta) in the
/// (E11dot, E22dot) plane (theta in radians, any value). theta in [pi, 3pi/2]: the loading point
/// (vertex); theta in [0, pi/2]: the origin.
YieldPoint affine_yield_point(const AffineYieldInput& in, double theta);

/// The loading point (vertex of the surface): all contacts active.
YieldPoint affine_loading_point(const AffineYieldInput& in);

/// Plastic dissipation rate per unit volume W(Edot) >= 0 for the strain rate (E11dot, E22dot);
/// equals S11 E11dot + S22 E22dot of affine_yield_stress (Euler's theorem), 0 for a zero rate.
double affine_dissipation(const AffineYieldInput& in, double E11dot, double E22dot);

/// Stress scale D Z0 sigma_y sqrt(-2 min(E11, E22)) used for the normalised tables:
/// D Z0 sigma_y sqrt(-2E) for hydrostatic precompaction E11 = E22 = E, D Z0 sigma_y sqrt(-2 E22) for
/// closed die. Hydrostatic loading point: -(3/pi) times this scale.
double affine_stress_scale(const AffineYieldInput& in);

/// Contact angle phi* in [0, pi/2] at which the normal strain rate Edot(phi) changes sign,
/// tan^2 phi* = -E11dot / E22dot (the "loading angle" theta_c of Appendix A, Eqs A9-A12);
/// meaningful only when E11dot E22dot < 0, returns NaN otherwise.
double affine_switch_angle(double E11dot, double E22dot);

namespace detail {

/// The checks of the aggregate every analytic surface shares (2D and 3D): density in (0, 1], z0 and
/// sigma_y positive and finite; std::invalid_argument with one line otherwise.
void validate_aggregate(double density, double z0, double sigma_y);

/// Carlson's symmetric elliptic integrals R_F(x, y, z) and R_D(x, y, z) (Boost.Math's
/// ellint_rf/ellint_rd; relative error ~1e-15). x, y, z >= 0, at most one of them zero (z > 0 for
/// R_D); a bad argument throws std::invalid_argument.
double carlson_rf(double x, double y, double z);
double carlson_rd(double x, double y, double z);

/// The two moments of the contact force over the contact angles [phi0, phi1] within [0, pi/2]:
///   {int sqrt(a cos^2 + b sin^2) cos^2 dphi, int sqrt(a cos^2 + b sin^2) sin^2 dphi},
/// a = -2 E11 >= 0, b = -2 E22 >= 0. Elementary closed forms for a == b (hydrostatic) and a == 0 or
/// b == 0 (closed die), elliptic (Carlson) forms otherwise; force_elliptic uses the latter whenever
/// a > 0 and b > 0 (to test that it reduces to the elementary forms).
std::array<double, 2> overlap_moments(double a, double b, double phi0, double phi1, bool force_elliptic = false);

}  // namespace detail

}  // namespace netdem::qs
