#pragma once
// The bond element of the staggered sintering scheme of Ivannikov et al. (section 2.4, Eqs 18-40;
// issue 17): the Potyondy-Cundall link between two bonded spheres A and B, each a node with 6 DOF
// (3 displacements, a rotation vector), for one step of the quasi-static scheme: the small-increment
// form of Eq 25 (linear, Eq 40), and the finite-rotation form of Eq 20 with Euler-Rodrigues (Eqs
// 23-24) and its consistent tangent (bond_forces_finite, bond_tangent_finite; see there).
//
// Element frame: e3 from the centre of A to the centre of B, e1, e2 completing a right-handed
// orthonormal triad. l_A0 = y40 e3 and l_B0 = -y70 e3 run from the centres to the grain-boundary
// centre (Eq 21), with y40 + y70 = L0 = the centre distance at the start of the step (the link of
// a pair whose shrinkage was corrected, Eqs 41-44).
//
// Nodal vector y = (u_A, theta_A, u_B, theta_B) (Eq 28); the link deformation y_link = (eps, gamma)
// = H y (Eqs 25-29): eps = u_A - u_B - L_A0 theta_A + L_B0 theta_B, gamma = theta_A - theta_B, with
// L = skew(l). The link is a zero-length spring on rigid arms, P_link = K_link y_link (Eq 32),
// K_link = diag(K_F, K_M), K_F = diag(GA, GA, EA)/L0, K_M = diag(EI, EI, GJ)/L0 in the element
// frame (Eqs 33-34), A = pi R_m^2, I = pi R_m^4/4, J = pi R_m^4/2 (Eq 36), G = E/(2(1 + nu)) (Eq
// 35). Its shear stiffness is GA/L0, not the 12 EI/L^3 of an Euler-Bernoulli beam.
//
// Nodal forces P = H^T K_link H y (Eq 40), the internal force vector of a finite element: the
// forces and moments the nodes must receive to hold the deformation y (the element pushes back
// with -P), and K_e = H^T K_link H its symmetric positive semi-definite stiffness. Eq 40 is used,
// not Eq 37: Eq 37b/d as printed give M_A + M_B = -d e3 x F_link, which together with the couple of
// F_A = -F_B = F_link, (x_A - x_B) x F_link = -d e3 x F_link, leaves a net moment; H^T gives
// M_A = M_link + l_A0 x F_link, M_B = -M_link - l_B0 x F_link, so M_A + M_B = +d e3 x F_link, and
// the element is in moment balance (tests/contact/test_bond.cpp).
#include <cmath>
#include <numbers>
#include <stdexcept>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "netdem/contact/rotation.hpp"

namespace netdem::contact {

using BondVec12 = Eigen::Matrix<double, 12, 1>;
using BondMat12 = Eigen::Matrix<double, 12, 12>;
using BondVec6 = Eigen::Matrix<double, 6, 1>;
using BondMat6 = Eigen::Matrix<double, 6, 6>;
using BondH = Eigen::Matrix<double, 6, 12>;

/// The bond's elastic constants (Eq 35).
struct BondMaterial {
  double E = 0.0;   ///< Young's modulus [Pa]
  double nu = 0.0;  ///< Poisson's ratio
  double G() const { return E / (2.0 * (1.0 + nu)); }
};

/// One bond over one step: the element frame and the lengths of Eqs 16, 21 and 34.
struct BondElement {
  Eigen::Vector3d e1 = Eigen::Vector3d::UnitX(), e2 = Eigen::Vector3d::UnitY(), e3 = Eigen::Vector3d::UnitZ();
  double lA0 = 0.0;  ///< y40: centre of A to the grain-boundary centre, along +e3 [m]
  double lB0 = 0.0;  ///< y70: centre of B to the grain-boundary centre, along -e3 [m]
  double Rm = 0.0;   ///< R_m = (R_A + R_B)/2 (Eq 16) [m]
  double L0() const { return lA0 + lB0; }  ///< Eq 14: L0 = y40 + y70
};

/// The element of the pair A-B at centres xA, xB with y40 = lA, y70 = lB (their sum must be the
/// centre distance to 1e-9, as after the shrinkage correction; lB0 is then set to the exact rest,
/// so that a rigid rotation gives no force) and the radii RA, RB. Throws std::invalid_argument for
/// coincident centres, non-positive or non-finite lengths, or y40 + y70 != |xB - xA|.
BondElement make_bond(const Eigen::Vector3d& xA, const Eigen::Vector3d& xB, double lA, double lB, double RA,
                      double RB);

/// H of Eq 29 in global coordinates: y_link = H y (Eq 27), y = (u_A, theta_A, u_B, theta_B).
BondH bond_H(const BondElement& b);

/// The axial stiffness E A / L0 of the link (Eqs 33, 36), the same expression as K_link's (3,3)
/// entry in the element frame. The sintering element's load is this times the step's shrinkage,
/// so that a free pair shortens by exactly that shrinkage (Eq 10 with the bond's own L0).
inline double bond_axial_stiffness(const BondElement& b, const BondMaterial& m) {
  const double A = std::numbers::pi * b.Rm * b.Rm;
  return m.E * A / b.L0();
}

/// K_link of Eqs 33-36 in global coordinates: blocks R diag(GA, GA, EA) R^T / L0 and
/// R diag(EI, EI, GJ) R^T / L0, R = [e1 e2 e3].
BondMat6 bond_K_link(const BondElement& b, const BondMaterial& m);

/// The element stiffness K_e = H^T K_link H (Eq 40), 12 x 12, symmetric positive semi-definite
/// with the six rigid-body motions of the step as its null space.
BondMat12 bond_stiffness(const BondElement& b, const BondMaterial& m);

/// The link deformation y_link = (eps, gamma) = H y (Eq 27).
BondVec6 bond_deformation(const BondElement& b, const BondVec12& y);

/// The nodal forces and moments P = H^T K_link H y (Eq 40): (F_A, M_A, F_B, M_B).
BondVec12 bond_forces(const BondElement& b, const BondMaterial& m, const BondVec12& y);

// ---------------------------------------------------------------------------------------------
// The finite-rotation form (Eq 20 with Eqs 22-24). The arms turn with the nodes, l_A = Q_A l_A0 and
// l_B = Q_B l_B0, so eps = u_A - u_B + (Q_A - I) l_A0 - (Q_B - I) l_B0: a rigid motion of any angle
// (theta_A = theta_B = w, u = (Q(w) - I)(x - c) + t) gives eps = 0 and gamma = 0, where Eq 25 gives
// a force of order |w|^2. The relative rotation stays gamma = theta_A - theta_B (the paper gives no
// finite form of it: this is where the small-rotation form is kept), and the link's frame and
// K_link are those of the start of the step. The nodal forces are the gradient of the link energy
// W = 1/2 y_link^T K_link y_link, P = dW/dy = B^T K_link y_link with B = d y_link / d y, which
// needs d(Q l)/d theta = -skew(Q l) J_l(theta), J_l the left Jacobian of SO(3); the tangent is the
// Hessian of W, obtained exactly by forward-mode automatic differentiation of P (Eigen's
// AutoDiffScalar). Tested against finite differences of W and of P (tests/contact/test_bond.cpp).

/// The link deformation of the finite-rotation form, (eps, gamma) (Eq 20; gamma as Eq 26).
template <class T>
Eigen::Matrix<T, 6, 1> bond_deformation_finite(const BondElement& b, const Eigen::Matrix<T, 12, 1>& y) {
  using V = Eigen::Matrix<T, 3, 1>;
  const V a = (b.lA0 * b.e3).template cast<T>(), c = (-b.lB0 * b.e3).template cast<T>();
  const V uA = y.template segment<3>(0), tA = y.template segment<3>(3), uB = y.template segment<3>(6),
          tB = y.template segment<3>(9);
  Eigen::Matrix<T, 6, 1> out;
  out.template head<3>() = uA - uB + (rotation_rodrigues<T>(tA) * a - a) - (rotation_rodrigues<T>(tB) * c - c);
  out.template tail<3>() = tA - tB;
  return out;
}

/// The link energy W = 1/2 y_link^T K_link y_link of the finite-rotation form.
double bond_energy_finite(const BondElement& b, const BondMaterial& m, const BondVec12& y);

/// The nodal forces of the finite-rotation form, P = dW/dy = B^T K_link y_link: (F_A, M_A, F_B, M_B)
/// with F_A = -F_B = K_F eps, M_A = J_A^T K_F eps + K_M gamma, M_B = -J_B^T K_F eps - K_M gamma,
/// J_A = -skew(Q_A l_A0) J_l(theta_A), J_B = -skew(Q_B l_B0) J_l(theta_B) (bond.cpp; there also in an
/// AutoDiffScalar for the tangent).
BondVec12 bond_forces_finite(const BondElement& b, const BondMaterial& m, const BondVec12& y);

/// The consistent tangent dP/dy of the finite-rotation form (the Hessian of W, symmetric): forward-
/// mode automatic differentiation of bond_forces_finite_t. At y = 0 it is K_e of Eq 40.
BondMat12 bond_tangent_finite(const BondElement& b, const BondMaterial& m, const BondVec12& y);

}  // namespace netdem::contact
