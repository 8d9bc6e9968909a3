#pragma once
// The affine-deviation measures of Redanz & Fleck (2001) Eq 16, written once for every solver and
// both dimensions (issue 26: the network solver's measures and the DEM's compaction meter had
// three copies).
//
// A contact between particles i and j with unit normal n (from i to j) that formed when the
// macroscopic strain was E_form has, at strain E, the affine relative displacement
//   u_N^a = -n . dE . n (r_i + r_j),   u_T^a = (dE n - (n . dE . n) n) (r_i + r_j),   dE = E - E_form:
// what the contact would carry if every centre followed the mean strain. The measures compare the
// contact's actual normal approach u_N (its overlap) with u_N^a, and report |u_T^a| against u_N^a.
#include <algorithm>
#include <cmath>

#include <Eigen/Core>

#include "netdem/contact/dim.hpp"

namespace netdem::sys {

/// Eq 16 for one contact: the affine normal approach u_N^a and the affine tangential
/// displacement u_T^a (2D: its component along t = perp(n); 3D: the vector in the tangent plane).
template <int D>
struct AffineApproach {
  double normal = 0.0;
  typename contact::Dim<D>::Tan tangential{};
  /// |u_T^a|
  double tangential_norm() const { return contact::tan_norm(tangential); }
};

/// Eq 16: n the unit normal from i to j, dE the symmetric strain since the contact formed, Rsum
/// = r_i + r_j.
template <int D>
AffineApproach<D> affine_approach(const Eigen::Matrix<double, D, 1>& n, const Eigen::Matrix<double, D, D>& dE,
                                  double Rsum) {
  AffineApproach<D> a;
  if constexpr (D == 2) {
    // n.dE.n and t.dE.n (t = perp(n) = (-ny, nx)) term by term, so that an isotropic dE gives an
    // exactly zero tangential part (the d12 terms vanish on diagonal paths)
    const double nx = n.x(), ny = n.y(), d11 = dE(0, 0), d22 = dE(1, 1), d12 = dE(0, 1);
    a.normal = -(nx * nx * d11 + ny * ny * d22) * Rsum;
    a.tangential = (-ny * nx * d11 + nx * ny * d22) * Rsum;
    if (d12 != 0.0) {
      a.normal -= 2.0 * nx * ny * d12 * Rsum;
      a.tangential += (nx * nx - ny * ny) * d12 * Rsum;
    }
  } else {
    const Eigen::Matrix<double, D, 1> dn = dE * n;
    const double ndn = n.dot(dn);
    a.normal = -ndn * Rsum;
    a.tangential = (dn - ndn * n) * Rsum;
  }
  return a;
}

/// The sums of the Eq 16 measures over the loaded contacts of a state, and the ratios reported in
/// history.csv (netsolve and demsolve alike):
///  * mean_ratio:      mean over the contacts with u_N^a > 0 of |u_N - u_N^a| / u_N^a;
///  * ratio_of_means:  mean |u_N - u_N^a| over the mean u_N^a;
///  * affine_tangential: mean |u_T^a| over the mean u_N^a.
class AffineDeviation {
 public:
  explicit AffineDeviation(double r_mean) : r_mean_(r_mean) {}
  /// One loaded contact: its normal approach (overlap) u_N and its Eq 16 affine approach.
  template <int D>
  void add(double u_n, const AffineApproach<D>& a) {
    sum_absdev_ += std::fabs(u_n - a.normal);
    sum_una_ += a.normal;
    if (a.normal > 1e-12 * r_mean_) {  // contacts the mean strain closes
      sum_ratio_ += std::fabs(u_n - a.normal) / a.normal;
      ++n_ratio_;
    }
    sum_ta_ += a.tangential_norm();
  }
  /// The mean u_N^a over `contacts` contacts (at least one).
  double mean_affine_normal(int contacts) const { return sum_una_ / std::max(contacts, 1); }
  double mean_ratio() const { return n_ratio_ > 0 ? sum_ratio_ / n_ratio_ : 0.0; }
  double ratio_of_means(int contacts) const { return of_mean_affine_normal(sum_absdev_, contacts); }
  double affine_tangential(int contacts) const { return of_mean_affine_normal(sum_ta_, contacts); }
  /// (sum / n) / mean u_N^a with n = max(contacts, 1); 0 where the mean u_N^a is not positive.
  double of_mean_affine_normal(double sum, int contacts) const {
    const int nl = std::max(contacts, 1);
    const double una_mean = sum_una_ / nl;
    return una_mean > 0 ? (sum / nl) / una_mean : 0.0;
  }

 private:
  double r_mean_;
  double sum_ratio_ = 0.0, sum_absdev_ = 0.0, sum_una_ = 0.0, sum_ta_ = 0.0;
  int n_ratio_ = 0;
};

}  // namespace netdem::sys
