#pragma once
// The demsolve state file: a complete, exact restart point of DynamicSolver (2D and 3D, the Luding
// models and the plastic-indentation law) in the state archive of netdem_system (a JSON document,
// kind "dem", every double read back to the same bits). Format in docs/dynamic.md "State files".
// Also the by-name access to every LudingParams field used by the apps' --param NAME=VALUE.
#include <cstddef>
#include <istream>
#include <string>
#include <string_view>
#include <vector>

#include "netdem/dynamic/solver.hpp"

namespace netdem::dem {

/// The version of the "dem" archive that format_state writes.
inline constexpr int kDemStateVersion = 1;

/// Limits of the state-file reader (docs/dynamic.md "State file limits"); parse_state refuses a
/// value outside them with "name: /json/pointer: problem". The length scale L is a0 for the Luding
/// models and the mean radius_ref of the state for the plastic law.
struct StateLimits {
  static constexpr double kMaxTime = 1.0e6;       ///< time in [0, 1e6] s
  static constexpr double kMaxDt = 1.0;           ///< dt in (0, 1] s
  static constexpr double kMaxBox = 1.0e6;        ///< box corners and free centres within +-1e6 L
  static constexpr double kMaxLoading = 0.1;      ///< stress-wall loading ratio 2p/k2 <= 0.1 (Luding)
  static constexpr double kMinLoading = 1e-9;     ///< ... >= 1e-9, as --pressure (stresses over p overflow)
  static constexpr double kAbsoluteZero = -273.15;  ///< T > -273.15 deg C
  static constexpr double kMaxThermalStrain = 0.05;  ///< |da_T (T - T_radius_ref)| <= 0.05
  static constexpr std::size_t kMaxParticles = 10000000;  ///< 1 .. 1e7 particles
  static constexpr double kRadiusRange = 100.0;   ///< radii within [L / 100, 100 L]
  static constexpr double kMaxTravel = 0.1;       ///< |v| dt, |w| a dt, wall speed dt < 0.1 r_min
};

/// At most 80 printable characters of `s` (control characters as '?', "..." if cut), for messages
/// that quote an input.
std::string quote_input(const std::string& s);

/// The text of a state file (one JSON line). Throws std::invalid_argument for a NaN anywhere.
std::string format_state(const SolverState& state);
/// Parses a state file; throws std::invalid_argument "name: /pointer: problem" (one line) on bad
/// input, and for an old text state file (before issue 26) says how to convert it.
SolverState parse_state(std::string_view text, const std::string& name);
SolverState parse_state(std::istream& in, const std::string& name);
/// parse_state under the name "state" (the entry point of a fuzz target: every input either
/// parses or throws std::invalid_argument).
SolverState read_state(std::istream& in);
/// Opens and parses `path`; a missing file or a folder is a one-line std::invalid_argument.
SolverState read_state_file(const std::string& path);

/// Names of all LudingParams fields (Table 1 and the switches).
std::vector<std::string> luding_param_names();
/// Sets a field by name (booleans: value != 0); throws std::invalid_argument for an unknown name
/// or a non-finite value (the range is checked by LudingParams::validate()).
void set_luding_param(LudingParams& p, const std::string& name, double value);
double get_luding_param(const LudingParams& p, const std::string& name);

}  // namespace netdem::dem
