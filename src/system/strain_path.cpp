#include "netdem/system/strain_path.hpp"

#include <cmath>
#include <sstream>
#include <vector>

#include <fmt/format.h>

#include "netdem/field_error.hpp"
#include "netdem/packing/io.hpp"

namespace netdem::sys {

template <>
const std::array<const char*, 3>& voigt_labels<2>() {
  static const std::array<const char*, 3> l = {"11", "22", "12"};
  return l;
}
template <>
const std::array<const char*, 6>& voigt_labels<3>() {
  static const std::array<const char*, 6> l = {"11", "22", "33", "23", "13", "12"};
  return l;
}

template <int D>
double StrainPathT<D>::trace() const {
  double t = 0.0;
  for (int a = 0; a < D; ++a) t += E[static_cast<std::size_t>(a)];
  return t;
}

template <int D>
double StrainPathT<D>::norm() const {
  double s = 0.0;
  for (int k = 0; k < kVoigt<D>; ++k) {
    const double e = E[static_cast<std::size_t>(k)];
    s += (k < D ? 1.0 : 2.0) * e * e;
  }
  return std::sqrt(s);
}

template <int D>
bool StrainPathT<D>::shear() const {
  for (int k = D; k < kVoigt<D>; ++k)
    if (E[static_cast<std::size_t>(k)] != 0.0) return true;
  return false;
}

template <int D>
StrainPathT<D> StrainPathT<D>::parse(const std::string& text) {
  StrainPathT p;
  p.name = text;
  if (text == "hydrostatic") {
    for (int a = 0; a < D; ++a) p.E[static_cast<std::size_t>(a)] = -1.0;
    return p;
  }
  if (text == "closed-die") {
    p.E[D - 1] = -1.0;
    return p;
  }
  std::vector<double> v;
  std::istringstream in(text);
  std::string item;
  bool ok = !text.empty() && text.back() != ',';
  while (ok && std::getline(in, item, ',')) {
    std::istringstream one(item);
    double x = 0.0;
    ok = static_cast<bool>(one >> x) && (one >> std::ws).eof() && std::isfinite(x);
    v.push_back(x);
  }
  // 2D: three components; 3D: the diagonal or all six
  ok = ok && (D == 2 ? v.size() == 3 : (v.size() == 3 || v.size() == 6));
  if (!ok) {
    const char* expected = D == 2 ? "three finite numbers E11,E22,E12"
                                  : "3 or 6 finite numbers E11,E22,E33[,E23,E13,E12]";
    throw FieldError("path", fmt::format("the strain path '{}' is not 'hydrostatic', 'closed-die' or {}",
                                         packing::quote_input(text, 80), expected));
  }
  for (std::size_t k = 0; k < v.size(); ++k) p.E[k] = v[k];
  if (!(p.norm() > 0.0))
    throw FieldError("path", fmt::format("the strain path {} has no direction", packing::quote_input(text, 80)));
  return p;
}

template struct StrainPathT<2>;
template struct StrainPathT<3>;

}  // namespace netdem::sys
