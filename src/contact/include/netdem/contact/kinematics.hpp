#pragma once
// Pair kinematics shared by all contact laws: 2D disks, and 3D spheres (at the end of the file).
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
//  * pair DOF order for 6-vectors and 6x6 matrices: (x_i, y_i, theta_i, x_j, y_j, theta_j).
#include <cmath>

#include <Eigen/Geometry>

#include "netdem/contact/dim.hpp"
#include "netdem/contact/law.hpp"

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

/// The rotation matrix of a rotation vector w (angle |w| about w / |w|; Euler-Rodrigues).
inline Eigen::Matrix3d rotation_of(const Eigen::Vector3d& w) {
  const double a = w.norm();
  if (!(a > 0.0)) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(a, w / a).toRotationMatrix();
}

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
inline PairIncrement3 pair_increment(const PairGeometry3& g0, const PairGeometry3& g1,
                                     const Eigen::Vector3d& dth_i, const Eigen::Vector3d& dth_j) {
  const double L = 0.5 * (g0.L + g1.L);
  const double di = 0.5 * (g0.d_i + g1.d_i);
  const double dj = 0.5 * (g0.d_j + g1.d_j);
  const Eigen::Matrix3d Q = rotation_of((di * dth_i + dj * dth_j) / L);
  const Eigen::Vector3d n0r = Q * g0.n;
  const Eigen::Vector3d c = n0r.cross(g1.n);
  const double sn = c.norm();
  PairIncrement3 out;
  out.transport.n = g1.n;
  if (sn > 0.0) {
    const double psi = std::atan2(sn, n0r.dot(g1.n));
    const Eigen::Vector3d e = c / sn;
    out.dslip = (L * psi) * e.cross(g1.n);
    out.transport.R = Eigen::AngleAxisd(psi, e).toRotationMatrix() * Q;
  } else {
    out.transport.R = Q;
  }
  return out;
}

/// The Transport of one explicit time step of a pair of spheres (or of a sphere and a wall) from
/// its rotation vector over the step, theta = (n x v_rel / L + (W . n / L) n) dt (v_rel = v_j - v_i,
/// W = d_i w_i + d_j w_j: the rates of pair_increment(); a wall: theta = (w_i . n) n dt), applied
/// to second order (law.hpp transport_small(): the length of the carried vector is kept to
/// O(theta^4) without a rescale; LAMMPS `pair granular` and MercuryDPM project the spring and
/// rescale it, which is this rotation to first order without the twist). A rigid rotation at w
/// carries the spring with the pair to O((w dt)^3) per step.
inline Transport<3> step_transport(const Eigen::Vector3d& n, const Eigen::Vector3d& theta) {
  Transport<3> t;
  t.n = n;
  t.theta = theta;
  t.small = true;
  return t;
}

/// The quasi-static 3D kinematics of the increment g0 -> g1 (no rates, no time step).
inline Kinematics<3> increment_kinematics(const PairGeometry3& g0, const PairGeometry3& g1,
                                          const Eigen::Vector3d& dth_i, const Eigen::Vector3d& dth_j) {
  const PairIncrement3 inc = pair_increment(g0, g1, dth_i, dth_j);
  Kinematics<3> k;
  k.overlap = g1.overlap;
  k.overlap_start = g0.overlap;
  k.dslip = inc.dslip;
  k.transport = inc.transport;
  k.r_eff = g1.r_eff;
  return k;
}

}  // namespace netdem::contact
