#pragma once
// Private: the checks that 2D and 3D ballistic deposition options share (ballistic.cpp,
// ballistic3d.cpp).
#include <cmath>
#include <stdexcept>
#include <string>

#include <fmt/core.h>

#include "netdem/packing/packing.hpp"

namespace netdem::packing::detail {

/// Throws std::invalid_argument "<what>: ..." unless width, height, radius, r_min and r_max are
/// finite, radius > 0, r_min > 0 and r_min <= r_max.
inline void check_deposition_sizes(const char* what, double width, double height, double radius, double r_min,
                                   double r_max) {
  auto fail = [&](const std::string& msg) { throw std::invalid_argument(std::string(what) + ": " + msg); };
  const double v[5] = {width, height, radius, r_min, r_max};
  static constexpr const char* kName[5] = {"width", "height", "radius", "r_min", "r_max"};
  for (int i = 0; i < 5; ++i)
    if (!std::isfinite(v[i])) fail(fmt::format("{} must be finite, got {}", kName[i], v[i]));
  if (!(radius > 0)) fail(fmt::format("reference radius must be > 0, got {}", radius));
  if (!(r_min > 0)) fail(fmt::format("r_min must be > 0, got {}", r_min));
  if (r_min > r_max) fail(fmt::format("r_min = {} exceeds r_max = {}", r_min, r_max));
  // the packing's own limit, before depositing: a 3D deposition with r_min = 1e-300 never ended (the 2D one
  // refused the packing after depositing it; campaign of issue 27)
  if (!(r_max <= kMaxRadiusRatio * r_min))
    fail(fmt::format("r_max / r_min = {:g} / {:g} = {:.6g} exceeds {:g}", r_max, r_min, r_max / r_min, kMaxRadiusRatio));
}

}  // namespace netdem::packing::detail
