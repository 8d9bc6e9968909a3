#pragma once
// The one place where the spatial dimension of netdem's models is fixed (issue 16).
//
// `Dim<D>` (D = 2: disks of unit depth; D = 3: spheres) gives the vector type, the rotation
// representation, the degrees of freedom per node and the type of a tangential quantity:
//  * 2D: a node has (u1, u2, theta); a rotation increment is an angle about e3; a tangential
//    quantity (slip, tangential force, spring) is a scalar, its component along t = perp(n);
//  * 3D: a node has (u1, u2, u3) and a rotation vector (increments); a tangential quantity is a
//    3-vector in global axes lying in the contact's tangent plane (normal to n).
// Laws are written once against `Dim<D>::Tan` with the helpers below; the same expression gives
// the 2D scalar code (bit for bit the code before the dimension became a parameter) and the 3D
// vector code.
//
// The names without a dimension (kDim, Vec, PairVec, ...) are the 2D ones: the solvers are 2D
// only and use them until they are templates too.
#include <cmath>
#include <type_traits>

#include <Eigen/Core>

namespace netdem::contact {

template <int D>
struct Dim;

template <>
struct Dim<2> {
  static constexpr int kDim = 2;
  static constexpr int kRotDofs = 1;
  static constexpr int kNodeDofs = kDim + kRotDofs;  // (u1, u2, theta)
  static constexpr int kPairDofs = 2 * kNodeDofs;    // a contact element: (node i, node j)
  using Vec = Eigen::Vector2d;
  using Rot = double;   ///< rotation increment: angle about e3
  using Tan = double;   ///< tangential quantity: component along t = perp(n)
  using TanMat = double;  ///< derivative of a tangential quantity by a tangential quantity
  /// I = kInertia m r^2 (disk)
  static constexpr double kInertia = 0.5;
};

template <>
struct Dim<3> {
  static constexpr int kDim = 3;
  static constexpr int kRotDofs = 3;
  static constexpr int kNodeDofs = kDim + kRotDofs;  // (u1, u2, u3, rotation vector)
  static constexpr int kPairDofs = 2 * kNodeDofs;    // a contact element: (node i, node j)
  using Vec = Eigen::Vector3d;
  using Rot = Eigen::Vector3d;  ///< rotation increment: rotation vector
  using Tan = Eigen::Vector3d;  ///< tangential quantity: global axes, in the tangent plane
  using TanMat = Eigen::Matrix3d;
  /// I = kInertia m r^2 (sphere)
  static constexpr double kInertia = 0.4;
};

/// m_t / m for the tangential motion of a contact point of a free particle, rotation included:
/// 1 / (1 + 1 / kInertia): 1/3 for a disk, 2/7 for a sphere.
template <int D>
inline constexpr double kTangentialMassRatio = 1.0 / (1.0 + 1.0 / Dim<D>::kInertia);

/// The generalized vector and matrix of a contact element over the DOFs of its two nodes:
/// 6 = (u_i, theta_i, u_j, theta_j) in 2D, 12 = (u_i (3), rotation vector of i (3), u_j, rotation
/// of j) in 3D (element.hpp).
template <int D>
using PairVecT = Eigen::Matrix<double, Dim<D>::kPairDofs, 1>;
template <int D>
using PairMatT = Eigen::Matrix<double, Dim<D>::kPairDofs, Dim<D>::kPairDofs>;

// ---- tangential quantities: the same expression in both dimensions -------------------------
template <class T>
inline T tan_zero() {
  if constexpr (std::is_same_v<T, double>) {
    return 0.0;
  } else if constexpr (std::is_same_v<T, Eigen::Vector3d>) {
    return T(0.0, 0.0, 0.0);  // (from scalars: Zero() is a chain of calls where it is not inlined, law.hpp Transport)
  } else {
    return T::Zero();
  }
}
inline double tan_norm(double v) { return std::fabs(v); }
inline double tan_norm(const Eigen::Vector3d& v) { return v.norm(); }
inline bool tan_is_zero(double v) { return v == 0.0; }
inline bool tan_is_zero(const Eigen::Vector3d& v) { return v.x() == 0.0 && v.y() == 0.0 && v.z() == 0.0; }
inline double tan_dot(double a, double b) { return a * b; }
inline double tan_dot(const Eigen::Vector3d& a, const Eigen::Vector3d& b) { return a.dot(b); }
/// The unit direction of v != 0: +-1 in 2D (exactly), v / |v| in 3D.
inline double tan_direction(double v) { return v > 0.0 ? 1.0 : -1.0; }
inline Eigen::Vector3d tan_direction(const Eigen::Vector3d& v) { return v / v.norm(); }
/// The identity of TanMat, scaled.
template <int D>
inline typename Dim<D>::TanMat tan_identity(double s) {
  if constexpr (D == 2) {
    return s;
  } else {
    return s * Eigen::Matrix3d::Identity();
  }
}

// ---- the 2D names (solvers) --------------------------------------------------------------------
inline constexpr int kDim = Dim<2>::kDim;
inline constexpr int kRotDofs = Dim<2>::kRotDofs;
inline constexpr int kNodeDofs = Dim<2>::kNodeDofs;  // (u1, u2, theta) per node
inline constexpr int kPairDofs = 2 * kNodeDofs;      // 6 for a 2D contact element

using Vec = Dim<2>::Vec;
using PairVec = PairVecT<2>;
using PairMat = PairMatT<2>;

/// In-plane perpendicular: rotates v by +90 degrees (t = J n).
inline Vec perp(const Vec& v) { return Vec(-v.y(), v.x()); }
/// 2D cross product a x b (z component).
inline double cross(const Vec& a, const Vec& b) { return a.x() * b.y() - a.y() * b.x(); }

}  // namespace netdem::contact
