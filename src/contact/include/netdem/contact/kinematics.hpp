#pragma once
// Pair kinematics shared by all contact laws: 2D disks, and 3D spheres (at the end of the file; the
// larger 3D functions are defined in kinematics.cpp).
//
// Conventions (used everywhere in netdem):
//  * a contact is the ordered pair (i, j), i < j in the solver's tables;
//  * n is the unit normal from the centre of i to the centre of j, t = perp(n) (n rotated +90 deg);
//  * overlap u_N = r_i + r_j - |x_j - x_i| is POSITIVE when the disks interpenetrate (compression
//    positive; this is the paper's u_N of Redanz & Fleck 2001 Eq 1-2);
//  * d_i, d_j are the distances from the centres to the contact plane (the common chord of the
//    two circles), d_i + d_j = L; for equal radii d = L/2;
//  * the contact force is reported as the force ON j: f_j = F_N n + F_T t, with F_N >= 0 repulsive;
//    f_i = -f_j. The moments are M_i = M_j = -d F_T (Redanz & Fleck Eq 9 with our F_T);
//  * the slip xi is the tangential displacement of j's contact point relative to i's, along t:
//    dxi = (dx_j - dx_i).t - d_i dtheta_i - d_j dtheta_j   (Redanz & Fleck Eq 5 up to the sign of
//    u_T: their u_T is the slip of 1 relative to 2, i.e. -xi). A rigid rotation gives dxi = 0.
//  * pair DOF order for 6-vectors and 6x6 matrices: (x_i, y_i, theta_i, x_j, y_j, theta_j); in 3D
//    for 12-vectors and 12x12 matrices: (u_i (3), rotation vector of i (3), u_j (3), rotation of j).
#include <cmath>
#include <type_traits>

#include <Eigen/Geometry>

#include "netdem/contact/dim.hpp"
#include "netdem/contact/law.hpp"
#include "netdem/contact/rotation.hpp"

namespace netdem::contact {

struct PairGeometry {
  Vec n = Vec::UnitX();  ///< unit normal from i to j
  Vec t = Vec::UnitY();  ///< perp(n)
  double L = 0;          ///< centre distance
  double overlap = 0;    ///< r_i + r_j - L (> 0: touching)
  double d_i = 0, d_j = 0;  ///< centre-to-contact-plane distances (chord), d_i + d_j = L
  double a_i = 0, a_j = 0;  ///< dd_i/dL, dd_j/dL (for the geometric stiffness)
  double r_eff = 0;         ///< R* = r_i r_j / (r_i + r_j)
};

inline PairGeometry pair_geometry(const Vec& xi, const Vec& xj, double ri, double rj) {
  PairGeometry g;
  const Vec dx = xj - xi;
  g.L = dx.norm();
  g.n = dx / g.L;
  g.t = perp(g.n);
  g.overlap = ri + rj - g.L;
  const double q = (ri * ri - rj * rj) / (2.0 * g.L);
  g.d_i = 0.5 * g.L + q;
  g.d_j = 0.5 * g.L - q;
  g.a_i = 0.5 - q / g.L;
  g.a_j = 0.5 + q / g.L;
  g.r_eff = ri * rj / (ri + rj);
  return g;
}

/// b_n: du_N = b_n . dq (normal approach, compression positive).
inline PairVec normal_gradient(const PairGeometry& g) {
  PairVec b;
  b << g.n.x(), g.n.y(), 0.0, -g.n.x(), -g.n.y(), 0.0;
  return b;
}
/// b_t: dxi = b_t . dq (Eq 5, slip of j relative to i along t).
inline PairVec slip_gradient(const PairGeometry& g) {
  PairVec b;
  b << -g.t.x(), -g.t.y(), -g.d_i, g.t.x(), g.t.y(), -g.d_j;
  return b;
}

/// Finite slip increment between two configurations of the same pair (objective form of Eq 5):
/// the relative tangential motion is L*dphi, with dphi the exact rotation of the normal, and the
/// rolling part uses the mid-increment lever arms. A rigid-body rotation gives exactly zero.
inline double slip_increment(const PairGeometry& g0, const PairGeometry& g1, double dtheta_i,
                             double dtheta_j) {
  const double dphi = std::atan2(cross(g0.n, g1.n), g0.n.dot(g1.n));
  const double L = 0.5 * (g0.L + g1.L);
  const double di = 0.5 * (g0.d_i + g1.d_i);
  const double dj = 0.5 * (g0.d_j + g1.d_j);
  return L * dphi - di * dtheta_i - dj * dtheta_j;
}


// ---------------------------------------------------------------------------------------------
// 3D (spheres). The same conventions: n from i to j, overlap > 0 touching, d_i, d_j the distances
// from the centres to the plane of the intersection circle, the slip the displacement of j's
// contact point relative to i's, now a vector in the tangent plane (normal to n).

struct PairGeometry3 {
  Eigen::Vector3d n = Eigen::Vector3d::UnitX();  ///< unit normal from i to j
  double L = 0;          ///< centre distance
  double overlap = 0;    ///< r_i + r_j - L (> 0: touching)
  double d_i = 0, d_j = 0;  ///< centre-to-contact-plane distances, d_i + d_j = L
  double r_eff = 0;         ///< R* = r_i r_j / (r_i + r_j)
};

inline PairGeometry3 pair_geometry(const Eigen::Vector3d& xi, const Eigen::Vector3d& xj, double ri,
                                   double rj) {
  PairGeometry3 g;
  const Eigen::Vector3d dx = xj - xi;
  g.L = dx.norm();
  g.n = dx / g.L;
  g.overlap = ri + rj - g.L;
  const double q = (ri * ri - rj * rj) / (2.0 * g.L);
  g.d_i = 0.5 * g.L + q;
  g.d_j = 0.5 * g.L - q;
  g.r_eff = ri * rj / (ri + rj);
  return g;
}

/// The pair geometry of dimension D (a solver written once for both dimensions names it so).
template <int D>
using PairGeometryT = std::conditional_t<D == 2, PairGeometry, PairGeometry3>;

/// 3D b_n: du_N = b_n . dq over the 12 pair DOFs (u_i, rotation of i, u_j, rotation of j).
PairVecT<3> normal_gradient(const PairGeometry3& g);
/// 3D B_t (3 x 12): the instantaneous slip of j's contact point relative to i's, in the tangent
/// plane, dxi = P (du_j - du_i) + n x (d_i dth_i + d_j dth_j), P = I - n n^T: the derivative of
/// pair_increment()'s dslip at a zero increment (tests/contact/test_element3d.cpp).
Eigen::Matrix<double, 3, 12> slip_gradient(const PairGeometry3& g);

/// The rotation matrix of a rotation vector w (angle |w| about w / |w|; Euler-Rodrigues).
Eigen::Matrix3d rotation_of(const Eigen::Vector3d& w);

/// What a 3D law needs of the motion of a pair over a step: the slip increment (in the end
/// tangent plane) and the Transport of the stored tangential history (law.hpp).
struct PairIncrement3 {
  Eigen::Vector3d dslip = Eigen::Vector3d::Zero();
  Transport<3> transport;
};

/// The increment between two configurations g0 -> g1 of a pair of spheres that turned by the
/// rotation vectors dth_i, dth_j. The pair's rigid rotation is the lever-arm weighted mean
/// W = (d_i dth_i + d_j dth_j) / L (mid-increment d and L; a rigid rotation of both spheres by w
/// gives W = w): it carries n0 to Q n0, Q = exp(W). The slip is the rest of the motion of the
/// normal, the rotation from Q n0 to n1 (angle psi about e): dslip = L psi e x n1, which is
/// Redanz & Fleck Eq 5 in 3D (2D: L dphi - d_i dth_i - d_j dth_j, as slip_increment()). The history
/// is carried by the same two rotations: R = R(psi e) Q. A rigid motion gives dslip = 0 and
/// R = the rotation (up to rounding), for any angle; the twist of the pair about n turns the
/// spring with it (LAMMPS `pair granular` and MercuryDPM project the old spring onto the new plane
/// and rescale it, which is this rotation without Q's twist to first order).
PairIncrement3 pair_increment(const PairGeometry3& g0, const PairGeometry3& g1,
                              const Eigen::Vector3d& dth_i, const Eigen::Vector3d& dth_j);

/// The derivatives of an increment g0 -> g1 (pair_increment()) by the end configuration q_end =
/// (x_i, dth_i, x_j, dth_j) (12 columns; g0 held), for the consistent tangent of the 3D contact
/// element (element.hpp; derivation in docs/contact.md "The 3D contact element"):
///  * dslip: d dslip / d q_end;
///  * spin: the spatial variation dw of the Transport's rotation R, dR R^T = [dw]x; since
///    R n0 = n1, dn1 = dw x n1, and its component along n1 is the twist of the pair;
///  * dn: d n1 / d q_end = P (dx_j - dx_i) / L.
struct IncrementJacobian3 {
  Eigen::Matrix<double, 3, 12> dslip, spin, dn;
};

/// (sin psi - psi cos psi) / sin^3 psi = -d(psi / sin psi) / d(cos psi), s = sin psi (series below
/// 1e-3: 1/3 + 2 psi^2 / 15, error O(psi^4)).
inline double slip_angle_factor(double psi, double s) {
  if (psi < 1e-3) return 1.0 / 3.0 + (2.0 / 15.0) * psi * psi;
  return (s - psi * std::cos(psi)) / (s * s * s);
}

/// The Jacobians of pair_increment(g0, g1, dth_i, dth_j). With m = Q n0 (Q = exp(W), W the
/// lever-arm weighted rotation), C = m . n1, psi the angle from m to n1 and g = psi / sin psi:
///   dslip = -Lm g P m                       (= Lm psi e x n1, Lm = (L0 + L1)/2)
///   dm = dq_W x m, dq_W = J_l(W) dW         (J_l the left Jacobian of SO(3))
///   d dslip = -g P m dLm + Lm h(psi) P m dC - Lm g (P dm - C dn1 - n1 (m . dn1)),  h = -dg/dC
///   spin = n1 (m . dq_W + (n1 x m) . (dm + dn1) / (1 + C)) + n1 x dn1
/// (the twist: that of Q about n1 plus that of the minimal rotation m -> n1, from its quaternion
/// (1 + C, m x n1)). Singular only at psi = pi.
IncrementJacobian3 increment_jacobian(const PairGeometry3& g0, const PairGeometry3& g1,
                                      const Eigen::Vector3d& dth_i, const Eigen::Vector3d& dth_j);

/// The Transport of one explicit time step of a pair of spheres (or of a sphere and a wall) from
/// its rotation vector over the step, theta = (n x v_rel / L + (W . n / L) n) dt (v_rel = v_j - v_i,
/// W = d_i w_i + d_j w_j: the rates of pair_increment(); a wall: theta = (w_i . n) n dt), applied
/// to second order (law.hpp transport_small(): the length of the carried vector is kept to
/// O(theta^4) without a rescale; LAMMPS `pair granular` and MercuryDPM project the spring and
/// rescale it, which is this rotation to first order without the twist). A rigid rotation at w
/// carries the spring with the pair to O((w dt)^3) per step.
inline Transport<3> step_transport(const Eigen::Vector3d& n, const Eigen::Vector3d& theta) {
  // (copy-constructed members, not assigned: where Eigen is not inlined, as under the sanitizers,
  // an assignment is a chain of calls, and this runs per contact and step; law.hpp Transport)
  return Transport<3>{.n = n, .theta = theta, .small = true};  // (R: its default, the identity)
}

/// The quasi-static 3D kinematics of the increment g0 -> g1 (no rates, no time step).
Kinematics<3> increment_kinematics(const PairGeometry3& g0, const PairGeometry3& g1,
                                   const Eigen::Vector3d& dth_i, const Eigen::Vector3d& dth_j);

}  // namespace netdem::contact
