#pragma once
// The sintering material of `netsolve sinter-pair` and `netsolve sinter`: --material cu|ti|FILE
// with --set KEY=VALUE overrides (appended assignments; docs/sintering_pair.md "Material file format").
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

}  // namespace netdem::app::netsolve
