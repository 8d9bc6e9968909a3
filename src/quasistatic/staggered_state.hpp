#pragma once
// The staggered scheme's state as plain data, and its file in the state archive of netdem_system
// (kind "staggered"; docs/staggered.md "Restart state"). Private to netdem_quasistatic:
// Staggered::save()/load() (staggered.cpp) go through it.
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "netdem/contact/bond.hpp"
#include "netdem/quasistatic/staggered.hpp"

namespace netdem::qs::staggered {

struct StaggeredState {
  StaggeredOptions opt;
  cs::SinterMaterial mat;
  std::vector<double> profile_t, profile_T;  ///< breakpoints; both empty: constant profile_constant
  double profile_constant = 0.0;
  double t = 0.0, dt = 0.0;
  long nsteps = 0, rhs_evals = 0;
  bool need_factor = true;
  int last_iterations = 0;
  Timers timers;
  Particles p, p0;
  std::vector<std::uint8_t> fixed_user, fixed_plane;  ///< 6 per particle
  std::vector<Contact> c;
  std::vector<std::uint8_t> ref_fixed;  ///< empty or 6 per particle: the constraints of the last factorisation
  std::vector<contact::BondElement> ref;  ///< its elements (at most one per contact)
  std::string origin_record = "null";  ///< JSON text: an object (the run that made the sample) or null
};

/// The archive text of a state (one JSON line); NaN anywhere throws std::invalid_argument.
std::string format_staggered_state(const StaggeredState& s);
/// Reads format_staggered_state(); every field checked at the door (the options and the material
/// through their validate()): std::invalid_argument "ORIGIN: /json/pointer: problem".
StaggeredState parse_staggered_state(std::string_view text, const std::string& origin);

}  // namespace netdem::qs::staggered
