#pragma once
// Value parsing shared by the netsolve subcommands (main.cpp, yield.cpp).
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "netdem/packing/io.hpp"

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

/// A comma-separated list of finite numbers (empty items skipped), sorted ascending; throws
/// std::invalid_argument naming `what` and the bad item.
inline std::vector<double> parse_number_list(const std::string& s, const char* what) {
  std::vector<double> out;
  std::stringstream in(s);
  std::string item;
  while (std::getline(in, item, ',')) {
    if (item.empty()) continue;
    double v = 0;
    if (!parse_double(item, v) || !std::isfinite(v))
      throw std::invalid_argument(fmt::format("{}: '{}' is not a number", what, packing::quote_input(item)));
    out.push_back(v);
  }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace netdem::app::netsolve
