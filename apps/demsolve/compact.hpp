#pragma once
// demsolve compact: the explicit DEM with the plastic-indentation law of Redanz & Fleck 2001 on
// netsolve's compaction scene, in netsolve's units and files (docs/dynamic.md "demsolve compact").
#include <filesystem>
#include <string>

#include "../netsolve/setup.hpp"

namespace netdem::app::dem {

struct DemCompactArgs {
  netdem::app::netsolve::PackArgs pack;  ///< netsolve's deposition options and defaults
  std::string packing_file;
  std::string path = "hydrostatic";
  std::string boundary = "layer";  ///< layer | walls
  std::string friction = "inf";
  std::string normal_unloading = "reversible";
  std::string snapshots = "0.82,0.84,0.85";
  bool affine = false, no_rotation = false, quiet = false, overwrite = false;
  double to_density = 0.85;
  double first_touch = 1e-5;
  double k_t = 1e3;
  /// I = gamma' d sqrt(rho / P_ref), d = 2R, P_ref = sigma_y (docs/dynamic.md "demsolve compact")
  double inertial_number = kDefaultInertialNumber;
  double damping = 0.5;  ///< damping_n = damping_t, fractions of critical damping of the chord stiffness
  double drag = 0.0;     ///< DynamicOptions::affine_drag [1/t*]
  double steps_per_contact = 50.0;
  int increments = 100;
  double max_steps = 1e10;
  static constexpr double kDefaultInertialNumber = 1.5e-4;  // docs/dynamic.md "demsolve compact": the fit
};

int run_dem_compact(const std::string& command, const DemCompactArgs& a, const std::filesystem::path& out);

}  // namespace netdem::app::dem
