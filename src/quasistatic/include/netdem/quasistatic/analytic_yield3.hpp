#pragma once
// Analytic affine upper-bound yield surfaces of sphere packings: the 3D counterpart of Redanz &
// Fleck's Appendix A (analytic_yield.hpp), the construction of Fleck (1995) for the sphere law of
// netdem (PlasticIndentationLaw3: F_N = 3 pi sigma_y a^2, a^2 = 2 R* u_N, i.e. F_N = 3 pi sigma_y R u_N
// for equal radii R, linear in the overlap). Derivation, closed forms and tests:
// docs/yield_analytic.md "3D", tests/quasistatic/test_analytic_yield3.cpp.
//
// Model: equal spheres of radius R, relative density D, Z0 contacts per particle with normals
// uniformly distributed on the sphere, Z0 constant, affine motion without particle spin, small
// strain, rigid-plastic contacts. The precompaction strain E (symmetric, negative semidefinite, any
// axes) gives the contact n the overlap u_N = -2R n.E.n and the force 6 pi sigma_y R^2 (-n.E.n). A
// probing strain rate Edot (symmetric, any axes) compresses the contacts with n.Edot.n < 0; those
// re-yield at once and keep their force, every other contact opens and carries nothing. Sticking
// contacts (mu_eff > 0) also slide at the cap mu_eff F_N against their tangential velocity
// 2R (Edot n - (n.Edot.n) n). The stress is the Love-Weber average of these forces,
//   Sigma = K int_{n.Edot.n < 0} (-n.E.n) [-n (x) n + mu_eff sym(t (x) n)] dOmega,  K = 9 D Z0 sigma_y / (8 pi),
// t the unit tangential velocity, and the dissipation rate per unit volume is
//   W(Edot) = K int_{n.Edot.n < 0} (-n.E.n) [-n.Edot.n + mu_eff |Edot n - (n.Edot.n) n|] dOmega = Sigma : Edot.
// Frictionless, W is convex and homogeneous of degree 1 and Sigma = dW/dEdot (normality), every
// compressive Edot gives the vertex Sigma = (3 D Z0 sigma_y / 10)(tr E I + 2E) and the isotropic
// hydrostatic compaction stress is p = (3/2) D Z0 sigma_y |E11|. With sticking contacts the
// tangential dissipation jumps where a contact starts to open, so W is not convex there and Sigma
// is not its gradient (no normality); Sigma : Edot = W still holds.
#include <Eigen/Core>

namespace netdem::qs {

/// State of the precompacted aggregate.
struct AffineYield3Input {
  double density = 0.0;  ///< relative density D, in (0, 1]
  double z0 = 0.0;       ///< coordination number Z0, > 0
  double sigma_y = 1.0;  ///< yield strength of the solid, > 0
  Eigen::Matrix3d E = Eigen::Matrix3d::Zero();  ///< precompaction strain: symmetric, negative semidefinite
  /// Tangential limit over the normal force: 0 frictionless; min(mu, 1/(3 sqrt 3)) for the law's
  /// Coulomb limit combined with the shear cap tau_y = sigma_y / sqrt 3 (sticking: 1/(3 sqrt 3)).
  double mu_eff = 0.0;
  /// Throws std::invalid_argument with a one-line message for a value out of range or not finite.
  void validate() const;
};

/// The precompaction strain of a proportional path from relative density d0 to d along the
/// strain-rate direction `direction` (symmetric, negative semidefinite, negative trace):
/// E = lambda direction with tr E = -ln(d / d0), as in the network solver (D = D0 exp(-tr E)).
/// Hydrostatic: -I; closed die along z: -e3 e3.
AffineYield3Input affine_yield3_input(double d0, double d, double z0, double sigma_y, const Eigen::Matrix3d& direction,
                                      double mu_eff);

/// Stress (tension positive) of the affine mechanism with strain rate Edot (only its direction
/// matters; any symmetric nonzero rate, any axes). Frictionless: the point of the yield surface with
/// outward normal Edot. Throws std::invalid_argument for a zero, non-symmetric or non-finite rate.
Eigen::Matrix3d affine_yield3_stress(const AffineYield3Input& in, const Eigen::Matrix3d& Edot);

/// Dissipation rate per unit volume W(Edot) = affine_yield3_stress : Edot >= 0 (0 for a zero rate).
double affine_dissipation3(const AffineYield3Input& in, const Eigen::Matrix3d& Edot);

/// The frictionless vertex (every compressive rate): (3 D Z0 sigma_y / 10)(tr E I + 2 E), closed form.
Eigen::Matrix3d affine_vertex3(const AffineYield3Input& in);

/// The axisymmetric (p, q) plane about z: p = -tr Sigma / 3 (compression positive),
/// q = Sigma33 - Sigma11 (signed: negative for axial compression). Its conjugate rates are
/// ev = -tr Edot and eq = (2/3)(Edot33 - Edot11), p ev + q eq = Sigma : Edot.
struct PQPoint {
  double p = 0.0, q = 0.0;
};

/// The axisymmetric strain rate whose (ev, eq) = (cos psi, sin psi): psi = 0 compacts
/// hydrostatically, psi = 90 deg is isochoric axial extension, -90 deg isochoric axial compression.
Eigen::Matrix3d axisymmetric_rate(double psi);

/// (p, q) of the point with outward normal (cos psi, sin psi) in (ev, eq), by the closed forms
/// (polynomials in the switch cosine, docs/yield_analytic.md), for E axisymmetric about z
/// (E11 = E22, no shear): hydrostatic and closed-die precompaction along z. Throws
/// std::invalid_argument for any other E.
PQPoint affine_yield3_pq(const AffineYield3Input& in, double psi);

/// (p, q) of a stress.
PQPoint pq_of(const Eigen::Matrix3d& sigma);

namespace detail {
/// affine_yield3_stress with `panels` 30-point Gauss-Legendre panels per quadrant of the azimuth and
/// per active polar interval (the public function uses 2), for the convergence tests.
Eigen::Matrix3d affine_yield3_stress(const AffineYield3Input& in, const Eigen::Matrix3d& Edot, int panels);
}  // namespace detail

}  // namespace netdem::qs
