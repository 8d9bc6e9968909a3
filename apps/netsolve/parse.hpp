#pragma once
// Value parsing shared by the netsolve subcommands (main.cpp, yield.cpp).
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <fmt/format.h>

namespace netdem::app::netsolve {

/// The whole of `s` as a double, or false.
inline bool parse_double(const std::string& s, double& v) {
  std::size_t used = 0;
  try {
    v = std::stod(s, &used);
  } catch (...) {
    return false;
  }
  return used == s.size();
}

/// The whole of `s` as an integer, or false.
inline bool parse_int(const std::string& s, long& v) {
  std::size_t used = 0;
  try {
    v = std::stol(s, &used);
  } catch (...) {
    return false;
  }
  return used == s.size();
}

/// --friction: a number >= 0, or inf / infinity / sticking (mu = infinity).
inline double parse_friction(const std::string& s) {
  if (s == "inf" || s == "infinity" || s == "sticking") return std::numeric_limits<double>::infinity();
  double v = 0;
  if (!parse_double(s, v) || std::isnan(v) || v < 0)
    throw std::invalid_argument(fmt::format("--friction '{}' is not a non-negative number or 'inf'", s));
  return v;
}

}  // namespace netdem::app::netsolve
