#pragma once
// The sintering material of `netsolve sinter-pair` and `netsolve sinter`: --material cu|ti|FILE
// with --set KEY=VALUE overrides (appended assignments; docs/sintering_pair.md "Material file format"),
// and the work a temperature profile adds (check_profile_work).
#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "netdem/contact/sintering_pair.hpp"
#include "netdem/packing/io.hpp"
#include "output.hpp"

namespace netdem::app::netsolve {

/// The material named by `material` (a built-in set or a file) with the `set` overrides; `source`
/// receives where it came from. Throws UsageError or std::invalid_argument (one line).
inline contact::sinter::SinterMaterial load_sinter_material(const std::string& material,
                                                            const std::vector<std::string>& set, std::string& source) {
  namespace sp = contact::sinter;
  std::string text;
  if (material == "cu" || material == "ti") {
    text = sp::builtin_sinter_material_text(material);
    source = "built-in " + material + " (src/contact/materials/" + material + ".txt)";
  } else {
    if (!std::filesystem::is_regular_file(material))
      throw UsageError(fmt::format("--material '{}' is not cu, ti or a readable file", packing::quote_input(material)));
    sp::read_sinter_material(material);  // reports file errors with the file's line numbers
    std::ostringstream o;
    o << std::ifstream(material).rdbuf();
    text = o.str();
    source = material;
  }
  // the k-th --set lands on line base + 2 + 2k of the text: an error there names the --set
  const auto base_lines = static_cast<long>(std::count(text.begin(), text.end(), '\n'));
  for (const auto& kv : set) {
    if (kv.find('=') == std::string::npos)
      throw UsageError(fmt::format("--set '{}' is not KEY=VALUE", packing::quote_input(kv)));
    text += "\n" + kv + "\n";
  }
  const std::string origin = set.empty() ? source : source + " with --set";
  try {
    return sp::parse_sinter_material(text, origin);
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what(), head = origin + ":";
    if (set.empty() || what.rfind(head, 0) != 0) throw;
    const auto colon = what.find(':', head.size());
    const long line = std::atol(what.c_str() + head.size());
    const long k = (line - base_lines - 2) / 2;
    if (colon == std::string::npos || line < base_lines + 2 || (line - base_lines) % 2 != 0 ||
        k >= static_cast<long>(set.size()))
      throw;
    throw UsageError(fmt::format("--set '{}':{}", packing::quote_input(set[static_cast<std::size_t>(k)]), what.substr(colon + 1)));
  }
}

/// The most breakpoints a temperature profile may place within a run unless --allow-long: each one
/// ends a global step of `netsolve sinter` (and an integration segment and a row of pair.csv in
/// `sinter-pair`), whatever --dt-max, so that a profile of 1e5 rows is 1e5 steps (13 s on a
/// 27-sphere lattice, minutes on a green body; docs/staggered.md "Run status and exit").
inline constexpr long kMaxProfileBreakpoints = 10000;

/// The breakpoints of T strictly inside (t_start, t_end), a jump's two rows counted once.
inline long profile_breakpoints_within(const contact::sinter::TemperatureProfile& T, double t_start, double t_end) {
  long n = 0;
  double prev = t_start;
  for (double b : T.times())
    if (b > prev && b < t_end) {
      ++n;
      prev = b;
    }
  return n;
}

/// Refuses (UsageError, exit 2) a profile with more than kMaxProfileBreakpoints breakpoints within
/// the run unless allow_long; `source` names where the profile came from ("--profile 'FILE'").
inline void check_profile_work(const contact::sinter::TemperatureProfile& T, double t_start, double t_end, bool allow_long,
                               const std::string& source) {
  const long n = profile_breakpoints_within(T, t_start, t_end);
  if (allow_long || n <= kMaxProfileBreakpoints) return;
  throw UsageError(fmt::format("{}: {} breakpoints of the temperature profile within the run ({:g} to {:g} s), more than {}; "
                               "each ends a step: pass --allow-long to run it",
                               source, n, t_start, t_end, kMaxProfileBreakpoints));
}

}  // namespace netdem::app::netsolve
