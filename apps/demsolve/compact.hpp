#pragma once
// demsolve compact: the explicit DEM with the plastic-indentation law of Redanz & Fleck 2001 on
// netsolve's compaction scene, in netsolve's units and files (docs/dynamic.md "demsolve compact").
#include <filesystem>
#include <string>

#include "netdem/dynamic/solver.hpp"
#include "setup.hpp"

namespace netdem::app::dem {

struct DemCompactArgs {
  netdem::app::netsolve::PackArgs pack;  ///< netsolve's deposition options and defaults
  std::string packing_file;
  std::string state_file;   ///< a jammed state to start from (netdem/system/jammed_state.hpp)
  bool save_state = false;  ///< write the final jammed state, jammed.json
  std::string path = "hydrostatic";
  std::string boundary = "layer";  ///< layer | walls
  std::string friction = netdem::app::netsolve::LawArgs{}.friction;
  std::string normal_unloading = netdem::app::netsolve::LawArgs{}.normal_unloading;
  std::vector<double> snapshots = {0.82, 0.84, 0.85};  ///< densities, a set: sorted before use
  bool affine = false, no_rotation = false, quiet = false, overwrite = false;
  bool simple_shear = false;  ///< --boundary periodic: the path's shear rates as simple shear
  double to_density = 0.85;
  double to_strain = 0.0;  ///< > 0: run --path to the equivalent strain |E| = to_strain instead
  /// > 0: a hydrostatic precompaction to this density first (history.csv column `leg`)
  double precompact_density = 0.0;
  int precompact_increments = 20;
  double first_touch = netdem::app::netsolve::LawArgs{}.first_touch;
  double k_t = netdem::app::netsolve::LawArgs{}.k_t;
  /// I = gamma' d sqrt(rho / P_ref), d = 2R, P_ref = sigma_y (docs/dynamic.md "demsolve compact")
  double inertial_number = kDefaultInertialNumber;
  double damping = 0.5;  ///< damping_n = damping_t, fractions of critical damping of the chord stiffness
  double drag = 0.0;     ///< DynamicOptions::affine_drag [1/t*]
  double steps_per_contact = netdem::dem::DynamicOptions{}.steps_per_contact;
  int threads = 1;  ///< DynamicOptions::threads
  int increments = 100;
  double max_steps = 1e10;
  static constexpr double kDefaultInertialNumber = 1.5e-4;  // docs/dynamic.md "demsolve compact": the fit
};

/// demsolve yield: netsolve yield's options where they apply (docs/dynamic.md "demsolve yield").
struct DemYieldArgs {
  netdem::app::netsolve::PackArgs pack;
  std::string packing_file;
  std::string precompact = "hydrostatic", compact_bc = "die", probe_bc;
  double to_density = 0.85;
  int increments = 100;
  std::string friction = DemCompactArgs{}.friction, normal_unloading = DemCompactArgs{}.normal_unloading;
  double first_touch = DemCompactArgs{}.first_touch, k_t = DemCompactArgs{}.k_t;
  int directions = 24;
  std::vector<int> probe_list;  ///< empty: every direction
  int jobs = 1;
  double offset = 1e-3, max_strain = 4e-3, window = 0.1, unload_tol = 1e-3, growth = 1.2;
  int fine = 20;
  double inertial_number = DemCompactArgs::kDefaultInertialNumber;
  double probe_inertial_number = 0.0;  ///< 0: the precompaction's
  double relax_drag = 30.0;  ///< drag of the holds after each unloading/probe increment [1/t*]
  double settle_tol = 1e-3;  ///< a hold ends when the unbalanced force < this x the mean contact force ...
  double settle_time = 50.0; ///< ... or after this time [t*] (the sample counts as unsettled)
  double damping = 0.5, steps_per_contact = netdem::dem::DynamicOptions{}.steps_per_contact, max_steps = 1e11;
  bool no_rotation = false, quiet = false, overwrite = false, allow_unconverged = false;
};

int run_dem_yield(const std::string& command, const DemYieldArgs& a, const std::filesystem::path& out);

int run_dem_compact(const std::string& command, const DemCompactArgs& a, const std::filesystem::path& out);

/// The checks of the law's and the integrator's numeric options (UsageError naming the option);
/// the protocol's own (inertial number, increments, target) are the library's
/// (netdem::dem::CompactionOptions).
void check_compact_numbers(const DemCompactArgs& a);

}  // namespace netdem::app::dem
