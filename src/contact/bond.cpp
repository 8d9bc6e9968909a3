// The bond element's functions of bond.hpp, out of line: fixed-size 6 x 12 and 12 x 12 products
// once per bond and step, where a call costs nothing measurable; as inline functions in the header
// (with Eigen's AutoDiff) every file that includes the staggered scheme parsed them.
#include <cmath>
#include <numbers>
#include <stdexcept>

#include <Eigen/Geometry>
#include <unsupported/Eigen/AutoDiff>

#include "netdem/contact/bond.hpp"
#include "netdem/contact/rotation.hpp"

namespace netdem::contact {

BondElement make_bond(const Eigen::Vector3d& xA, const Eigen::Vector3d& xB, double lA, double lB, double RA,
                      double RB) {
  const Eigen::Vector3d d = xB - xA;
  const double L = d.norm();
  if (!(L > 0.0) || !std::isfinite(L)) throw std::invalid_argument("make_bond: the centres coincide or are not finite");
  if (!(lA > 0.0 && lB > 0.0 && std::isfinite(lA + lB)))
    throw std::invalid_argument("make_bond: the centre-to-grain-boundary distances must be > 0 and finite");
  if (!(RA > 0.0 && RB > 0.0 && std::isfinite(RA + RB)))
    throw std::invalid_argument("make_bond: the radii must be > 0 and finite");
  BondElement b;
  b.e3 = d / L;
  // e1: the coordinate axis least aligned with e3, made orthogonal to it; e2 = e3 x e1
  Eigen::Vector3d a = Eigen::Vector3d::UnitX();
  const Eigen::Vector3d ab = b.e3.cwiseAbs();
  if (ab.y() <= ab.x() && ab.y() <= ab.z())
    a = Eigen::Vector3d::UnitY();
  else if (ab.z() <= ab.x() && ab.z() <= ab.y())
    a = Eigen::Vector3d::UnitZ();
  b.e1 = (a - b.e3 * b.e3.dot(a)).normalized();
  b.e2 = b.e3.cross(b.e1);
  if (!(std::fabs(lA + lB - L) <= 1e-9 * L))
    throw std::invalid_argument("make_bond: y40 + y70 must be the centre distance (the shrinkage correction, Eqs 41-44)");
  b.lA0 = lA;
  b.lB0 = L - lA;
  b.Rm = 0.5 * (RA + RB);
  return b;
}

BondH bond_H(const BondElement& b) {
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  const Eigen::Matrix3d LA = skew<double>(b.lA0 * b.e3), LB = skew<double>(-b.lB0 * b.e3);  // L_A0, L_B0 (Eq 25)
  BondH H = BondH::Zero();
  H.block<3, 3>(0, 0) = I;
  H.block<3, 3>(0, 3) = -LA;
  H.block<3, 3>(0, 6) = -I;
  H.block<3, 3>(0, 9) = LB;
  H.block<3, 3>(3, 3) = I;
  H.block<3, 3>(3, 9) = -I;
  return H;
}

BondMat6 bond_K_link(const BondElement& b, const BondMaterial& m) {
  const double pi = std::numbers::pi;
  const double A = pi * b.Rm * b.Rm, Ib = 0.25 * pi * b.Rm * b.Rm * b.Rm * b.Rm, J = 2.0 * Ib;  // Eq 36
  const double L0 = b.L0(), G = m.G();
  Eigen::Matrix3d R;
  R.col(0) = b.e1;
  R.col(1) = b.e2;
  R.col(2) = b.e3;
  const Eigen::Vector3d kF(G * A / L0, G * A / L0, m.E * A / L0), kM(m.E * Ib / L0, m.E * Ib / L0, G * J / L0);
  BondMat6 K = BondMat6::Zero();
  K.block<3, 3>(0, 0) = R * kF.asDiagonal() * R.transpose();
  K.block<3, 3>(3, 3) = R * kM.asDiagonal() * R.transpose();
  return K;
}

BondMat12 bond_stiffness(const BondElement& b, const BondMaterial& m) {
  const BondH H = bond_H(b);
  return H.transpose() * bond_K_link(b, m) * H;
}

BondVec6 bond_deformation(const BondElement& b, const BondVec12& y) { return bond_H(b) * y; }

BondVec12 bond_forces(const BondElement& b, const BondMaterial& m, const BondVec12& y) {
  const BondH H = bond_H(b);
  return H.transpose() * (bond_K_link(b, m) * (H * y));
}

double bond_energy_finite(const BondElement& b, const BondMaterial& m, const BondVec12& y) {
  const BondVec6 yl = bond_deformation_finite<double>(b, y);
  return 0.5 * yl.dot(bond_K_link(b, m) * yl);
}

namespace {

/// P of bond_forces_finite() for T = double or an AutoDiffScalar (bond.hpp).
template <class T>
Eigen::Matrix<T, 12, 1> bond_forces_finite_t(const BondElement& b, const BondMat6& K, const Eigen::Matrix<T, 12, 1>& y) {
  using V = Eigen::Matrix<T, 3, 1>;
  using M3 = Eigen::Matrix<T, 3, 3>;
  const V a = (b.lA0 * b.e3).template cast<T>(), c = (-b.lB0 * b.e3).template cast<T>();
  const V tA = y.template segment<3>(3), tB = y.template segment<3>(9);
  const M3 QA = rotation_rodrigues<T>(tA), QB = rotation_rodrigues<T>(tB);
  const V eps = y.template segment<3>(0) - y.template segment<3>(6) + (QA * a - a) - (QB * c - c);
  const V gam = tA - tB;
  const M3 KF = K.block<3, 3>(0, 0).template cast<T>(), KM = K.block<3, 3>(3, 3).template cast<T>();
  const V f = KF * eps, mm = KM * gam;
  const M3 JA = -skew<T>(QA * a) * left_jacobian<T>(tA), JB = -skew<T>(QB * c) * left_jacobian<T>(tB);
  Eigen::Matrix<T, 12, 1> P;
  P.template segment<3>(0) = f;
  P.template segment<3>(3) = JA.transpose() * f + mm;
  P.template segment<3>(6) = -f;
  P.template segment<3>(9) = -(JB.transpose() * f) - mm;
  return P;
}

}  // namespace

BondVec12 bond_forces_finite(const BondElement& b, const BondMaterial& m, const BondVec12& y) {
  return bond_forces_finite_t<double>(b, bond_K_link(b, m), y);
}

BondMat12 bond_tangent_finite(const BondElement& b, const BondMaterial& m, const BondVec12& y) {
  using AD = Eigen::AutoDiffScalar<BondVec12>;
  Eigen::Matrix<AD, 12, 1> ya;
  for (int i = 0; i < 12; ++i) ya(i) = AD(y(i), 12, i);
  const Eigen::Matrix<AD, 12, 1> P = bond_forces_finite_t<AD>(b, bond_K_link(b, m), ya);
  BondMat12 Kt;
  for (int i = 0; i < 12; ++i) Kt.row(i) = P(i).derivatives().transpose();
  return Kt;
}

}  // namespace netdem::contact
