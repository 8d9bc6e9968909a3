// The 3D pair kinematics of kinematics.hpp that are out of line: each is a few dozen fixed-size
// matrix operations per contact and call, so the call costs nothing measurable, while as inline
// functions in the header every file that includes a contact law parsed and checked them (about
// 2.6 s of GCC's front end per file; docs/performance.md "Issue 33: the first command's build").
#include <cmath>

#include <Eigen/Geometry>

#include "netdem/contact/kinematics.hpp"

namespace netdem::contact {

PairVecT<3> normal_gradient(const PairGeometry3& g) {
  PairVecT<3> b = PairVecT<3>::Zero();
  b.segment<3>(0) = g.n;
  b.segment<3>(6) = -g.n;
  return b;
}

Eigen::Matrix<double, 3, 12> slip_gradient(const PairGeometry3& g) {
  const Eigen::Matrix3d P = Eigen::Matrix3d::Identity() - g.n * g.n.transpose();
  const Eigen::Matrix3d N = skew<double>(g.n);
  Eigen::Matrix<double, 3, 12> B;
  B << -P, g.d_i * N, P, g.d_j * N;
  return B;
}

Eigen::Matrix3d rotation_of(const Eigen::Vector3d& w) {
  const double a = w.norm();
  if (!(a > 0.0)) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(a, w / a).toRotationMatrix();
}

PairIncrement3 pair_increment(const PairGeometry3& g0, const PairGeometry3& g1,
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
    out.transport.set_R(Eigen::AngleAxisd(psi, e).toRotationMatrix() * Q);
  } else {
    out.transport.set_R(Q);
  }
  return out;
}

IncrementJacobian3 increment_jacobian(const PairGeometry3& g0, const PairGeometry3& g1,
                                      const Eigen::Vector3d& dth_i, const Eigen::Vector3d& dth_j) {
  using M312 = Eigen::Matrix<double, 3, 12>;
  using R12 = Eigen::Matrix<double, 1, 12>;
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  const Eigen::Vector3d& n = g1.n;
  const Eigen::Matrix3d P = I - n * n.transpose();
  IncrementJacobian3 J;
  J.dn.setZero();
  J.dn.block<3, 3>(0, 0) = -P / g1.L;
  J.dn.block<3, 3>(0, 6) = P / g1.L;
  R12 dL = R12::Zero();  // d L1 / d q
  dL.segment<3>(0) = -n.transpose();
  dL.segment<3>(6) = n.transpose();
  // the mean rotation W = (d_i dth_i + d_j dth_j) / Lm with mid-increment d and Lm; dd/dL1 = 1 - d/L1
  const double Lm = 0.5 * (g0.L + g1.L);
  const double di = 0.5 * (g0.d_i + g1.d_i), dj = 0.5 * (g0.d_j + g1.d_j);
  const double ai = 1.0 - g1.d_i / g1.L, aj = 1.0 - g1.d_j / g1.L;
  const Eigen::Vector3d W = (di * dth_i + dj * dth_j) / Lm;
  M312 dW = ((0.5 * (ai * dth_i + aj * dth_j) - 0.5 * W) / Lm) * dL;
  dW.block<3, 3>(0, 3) += (di / Lm) * I;
  dW.block<3, 3>(0, 9) += (dj / Lm) * I;
  const M312 dqW = left_jacobian<double>(W) * dW;
  const Eigen::Vector3d m = rotation_of(W) * g0.n;
  const M312 dm = -skew<double>(m) * dqW;
  // the rest of the normal's motion: the rotation psi from m to n1
  const double C = m.dot(n);
  const double s = m.cross(n).norm();
  const double psi = std::atan2(s, C);
  const double g = s > 0.0 ? psi / s : 1.0;
  const Eigen::Vector3d Pm = P * m;
  const R12 dC = m.transpose() * J.dn + n.transpose() * dm;
  const M312 dPm = P * dm - C * J.dn - n * (m.transpose() * J.dn);
  J.dslip = (-0.5 * g) * Pm * dL + (Lm * slip_angle_factor(psi, s)) * Pm * dC - (Lm * g) * dPm;
  const R12 twist = m.transpose() * dqW + (n.cross(m)).transpose() * (dm + J.dn) / (1.0 + C);
  J.spin = n * twist + skew<double>(n) * J.dn;
  return J;
}

Kinematics<3> increment_kinematics(const PairGeometry3& g0, const PairGeometry3& g1,
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
