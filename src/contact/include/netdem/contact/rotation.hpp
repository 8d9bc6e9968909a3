#pragma once
// Rotation vectors, shared by the bond element (bond.hpp) and the 3D pair kinematics and element
// (kinematics.hpp, element.hpp): the cross-product matrix, the Euler-Rodrigues coefficients (the
// equation numbers are those of Ivannikov et al., the bond's paper), the rotation of a rotation
// vector and the left Jacobian of SO(3). Templated on the scalar T (double, or an AutoDiffScalar
// for the bond's finite-rotation tangent).
#include <Eigen/Core>

namespace netdem::contact {

/// skew(v) w = v x w. T: double, or an AutoDiffScalar (the finite-rotation form's tangent).
template <class T>
Eigen::Matrix<T, 3, 3> skew(const Eigen::Matrix<T, 3, 1>& v) {
  Eigen::Matrix<T, 3, 3> S;
  S << T(0.0), -v.z(), v.y(),  //
      v.z(), T(0.0), -v.x(),   //
      -v.y(), v.x(), T(0.0);
  return S;
}

/// h1 = sin t / t, h2 = (1 - cos t) / t^2 = (sin(t/2) / (t/2))^2 / 2 (Eq 24), h3 = (t - sin t) / t^3,
/// t = sqrt(s), s = |theta|^2; written in s, with their series for s < 1e-4 (error < 1e-21), so
/// that they and their derivatives are smooth at theta = 0.
template <class T>
void rodrigues_coefficients(const T& s, T& h1, T& h2, T& h3) {
  using std::cos;
  using std::sin;
  using std::sqrt;
  if (s < 1e-4) {
    h1 = 1.0 - s / 6.0 + s * s / 120.0 - s * s * s / 5040.0;
    h2 = 0.5 - s / 24.0 + s * s / 720.0 - s * s * s / 40320.0;
    h3 = 1.0 / 6.0 - s / 120.0 + s * s / 5040.0 - s * s * s / 362880.0;
  } else {
    const T t = sqrt(s), st = sin(t);
    h1 = st / t;
    h2 = (1.0 - cos(t)) / s;
    h3 = (t - st) / (s * t);
  }
}

/// I + a Theta + b Theta^2, Theta = skew(theta), with (a, b) = (h1, h2) (which = 0) or (h2, h3).
template <class T>
Eigen::Matrix<T, 3, 3> rodrigues_series(const Eigen::Matrix<T, 3, 1>& theta, int which) {
  T h1, h2, h3;
  rodrigues_coefficients(theta.squaredNorm(), h1, h2, h3);
  const Eigen::Matrix<T, 3, 3> Th = skew<T>(theta);
  return Eigen::Matrix<T, 3, 3>::Identity() + (which == 0 ? h1 : h2) * Th + (which == 0 ? h2 : h3) * (Th * Th);
}

/// Q of Eq 23: I + h1 Theta + h2 Theta^2 (Euler-Rodrigues).
template <class T>
Eigen::Matrix<T, 3, 3> rotation_rodrigues(const Eigen::Matrix<T, 3, 1>& theta) {
  return rodrigues_series<T>(theta, 0);
}

/// The left Jacobian of SO(3): d(Q(theta) l) = (J_l(theta) d theta) x (Q l), J_l = I + h2 Theta +
/// h3 Theta^2.
template <class T>
Eigen::Matrix<T, 3, 3> left_jacobian(const Eigen::Matrix<T, 3, 1>& theta) {
  return rodrigues_series<T>(theta, 1);
}

}  // namespace netdem::contact
