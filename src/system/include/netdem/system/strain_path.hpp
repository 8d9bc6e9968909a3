#pragma once
// A macroscopic strain-rate direction in Voigt order, for both dimensions (issue 26: the DEM's 2D
// and 3D compaction each parsed their own):
//   2D: (E11, E22, E12);   3D: (E11, E22, E33, E23, E13, E12).
#include <array>
#include <string>

namespace netdem::sys {

/// Number of independent components of a symmetric D x D tensor.
template <int D>
inline constexpr int kVoigt = D * (D + 1) / 2;

template <int D>
using Voigt = std::array<double, kVoigt<D>>;

/// The Voigt components' names ("11", "22", "12" / "11", "22", "33", "23", "13", "12").
template <int D>
const std::array<const char*, kVoigt<D>>& voigt_labels();

/// Row a and column b of Voigt component k.
template <int D>
inline constexpr int voigt_row(int k) {
  if constexpr (D == 2) {
    constexpr int r[3] = {0, 1, 0};
    return r[k];
  } else {
    constexpr int r[6] = {0, 1, 2, 1, 0, 0};
    return r[k];
  }
}
template <int D>
inline constexpr int voigt_col(int k) {
  if constexpr (D == 2) {
    constexpr int c[3] = {0, 1, 1};
    return c[k];
  } else {
    constexpr int c[6] = {0, 1, 2, 2, 2, 1};
    return c[k];
  }
}

template <int D>
struct StrainPathT {
  std::string name;
  Voigt<D> E{};  ///< the direction (any length)

  double trace() const;
  /// Frobenius norm sqrt(E:E) (off-diagonal components counted twice).
  double norm() const;
  /// A component off the diagonal is not zero.
  bool shear() const;
  /// "hydrostatic" (-1 on the diagonal), "closed-die" (-1 along the last axis: y in 2D, z in 3D,
  /// the deposition's gravity axis), or the finite components: 2D E11,E22,E12; 3D E11,E22,E33 or
  /// E11,E22,E33,E23,E13,E12. Throws netdem::FieldError on field "path" (one line; at most 80
  /// characters of the text quoted).
  static StrainPathT parse(const std::string& text);
};

}  // namespace netdem::sys
