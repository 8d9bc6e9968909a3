#pragma once
// The demsolve state file (v2): a complete, exact restart point of DynamicSolver (text, every
// double printed with 17 significant digits, so reading it back gives the same bits). Format in
// docs/dynamic.md. Also the by-name access to every LudingParams field used by state files and by
// the apps' --param NAME=VALUE.
#include <istream>
#include <string>
#include <vector>

#include "netdem/dynamic/solver.hpp"

namespace netdem::dem {

/// The text of a state file.
std::string format_state(const SolverState& state);
/// Parses a state file; throws std::invalid_argument "name:line: problem" on bad input.
SolverState parse_state(std::istream& in, const std::string& name);
/// Opens and parses `path`; a missing file is a one-line std::invalid_argument.
SolverState read_state_file(const std::string& path);

/// Names of all LudingParams fields (Table 1 and the switches).
std::vector<std::string> luding_param_names();
/// Sets a field by name (booleans: value != 0); throws std::invalid_argument for an unknown name
/// or a non-finite value (the range is checked by LudingParams::validate()).
void set_luding_param(LudingParams& p, const std::string& name, double value);
double get_luding_param(const LudingParams& p, const std::string& name);

}  // namespace netdem::dem
