#pragma once
// Pair kinematics shared by all contact laws (2D disks).
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

#include "netdem/contact/dim.hpp"

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

}  // namespace netdem::contact
