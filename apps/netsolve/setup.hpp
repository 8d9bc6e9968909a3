#pragma once
// Packing set-up shared by the netsolve subcommands (main.cpp: pack, compact; yield.cpp: yield).
#include <cstdint>
#include <stdexcept>
#include <string>

#include <fmt/format.h>

#include "netdem/packing/ballistic.hpp"
#include "netdem/packing/io.hpp"
#include "netdem/packing/packing.hpp"

namespace netdem::app::netsolve {

/// Options of a new ballistic deposition.
struct PackArgs {
  double width = 80.0, r_min = 0.9, r_max = 1.1;
  bool mono = false;
  std::string lid = "centre";
  std::uint64_t seed = 1;
};

/// The ballistic deposition of `a`; throws std::invalid_argument for an unknown --lid.
inline packing::Packing make_packing(const PackArgs& a) {
  packing::DepositionOptions o;
  o.width = a.width;
  o.r_min = a.mono ? 1.0 : a.r_min;
  o.r_max = a.mono ? 1.0 : a.r_max;
  o.seed = a.seed;
  if (a.lid == "centre") {
    o.lid = packing::Lid::Centre;
  } else if (a.lid == "inside") {
    o.lid = packing::Lid::Inside;
  } else {
    throw std::invalid_argument(fmt::format("--lid '{}' is not 'centre' or 'inside'", a.lid));
  }
  return packing::ballistic_deposition(o);
}

/// The packing file if one is given, else a new deposition; `source` describes which.
inline packing::Packing input_packing(const std::string& packing_file, const PackArgs& a, std::string& source) {
  if (!packing_file.empty()) {
    source = packing_file;
    return packing::read_packing_csv(packing_file);
  }
  source = fmt::format("ballistic deposition, W = {} R, r = R[{}, {}], seed {}", a.width, a.mono ? 1.0 : a.r_min,
                       a.mono ? 1.0 : a.r_max, a.seed);
  return make_packing(a);
}

}  // namespace netdem::app::netsolve
