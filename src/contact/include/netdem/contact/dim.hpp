#pragma once
// The one place where the spatial dimension of netdem's 2D models is fixed.
// 2D disks of unit depth: each particle has kDim translational and kRotDofs rotational
// degrees of freedom. A 3D port changes this header (kDim = 3, kRotDofs = 3, Vec = Vector3d)
// and the pair kinematics in kinematics.hpp; the laws are written in a contact frame.
#include <Eigen/Core>

namespace netdem::contact {

inline constexpr int kDim = 2;
inline constexpr int kRotDofs = 1;
inline constexpr int kNodeDofs = kDim + kRotDofs;   // (u1, u2, theta) per node
inline constexpr int kPairDofs = 2 * kNodeDofs;     // 6 for a 2D contact element

using Vec = Eigen::Matrix<double, kDim, 1>;
using PairVec = Eigen::Matrix<double, kPairDofs, 1>;
using PairMat = Eigen::Matrix<double, kPairDofs, kPairDofs>;

/// In-plane perpendicular: rotates v by +90 degrees (t = J n).
inline Vec perp(const Vec& v) { return Vec(-v.y(), v.x()); }
/// 2D cross product a x b (z component).
inline double cross(const Vec& a, const Vec& b) { return a.x() * b.y() - a.y() * b.x(); }

}  // namespace netdem::contact
