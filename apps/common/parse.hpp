#pragma once
// Value parsing shared by the netsolve and demsolve subcommands: numbers, --friction, comma lists.
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include <CLI/CLI.hpp>
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

/// A comma-list option bound by CLI11 (`--snapshots 0.82,0.84,0.85`, `--probes 0,3,5`): one
/// argument, which CLI11 splits at ',' (empty items skipped) and converts item by item (CLI11's
/// number syntax); a bad item is refused while parsing, one line naming the option and the item
/// ("--snapshots: '0.8x' is not a number", exit 2). Three rules that CLI11 2.1 does not have are
/// added in the option's callback: an empty argument (`--snapshots ""`) is the empty list (CLI11
/// reads it as one 0), numbers are finite (CLI11 reads inf and nan), and the option is given once
/// (a second --snapshots is refused, not appended). The list keeps the order given: the command
/// decides what order means (--snapshots and --probes are sets and sorted, --checkpoints must
/// increase: the library refuses another order).
template <class T>
CLI::Option* add_list_option(CLI::App& app, const std::string& name, std::vector<T>& v, const std::string& help) {
  static_assert(std::is_arithmetic_v<T>);
  auto seen = std::make_shared<bool>(false);
  CLI::callback_t convert = [&v, name, seen](const CLI::results_t& res) {
    if (*seen) throw CLI::ArgumentMismatch(name + ": given more than once (give one comma list)");
    *seen = true;
    std::vector<T> out;
    if (!(res.size() == 1 && res[0].empty()))
      for (const auto& item : res) {
        T x{};
        if (!CLI::detail::lexical_cast(item, x) || !std::isfinite(static_cast<double>(x)))
          throw CLI::ValidationError(name, fmt::format("'{}' is not {}", packing::quote_input(item),
                                                       std::is_integral_v<T> ? "a whole number" : "a number"));
        out.push_back(x);
      }
    v = std::move(out);
    return true;
  };
  std::string def;
  for (const T& x : v) def += (def.empty() ? "" : ",") + fmt::format("{}", x);
  return app.add_option(name, convert, help)
      ->delimiter(',')
      ->expected(1, CLI::detail::expected_max_vector_size)
      ->allow_extra_args(false)
      ->trigger_on_parse()
      ->type_name("LIST")
      ->default_str(def);
}

/// The check of a file option: an empty value is refused with one line ("--state: is empty: give
/// a jammed state file") instead of being read as "not given".
inline CLI::Validator non_empty_file(const std::string& what) {
  return CLI::Validator([what](std::string& v) { return v.empty() ? "is empty: give " + what : std::string(); }, "FILE");
}

}  // namespace netdem::app::netsolve
