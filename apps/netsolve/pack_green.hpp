#pragma once
// netsolve pack --dim 3 --route green-body: the packing route of Ivannikov et al. (section 3.2)
// with the 3D explicit DEM (netdem/dynamic/green_body.hpp; docs/packing.md "The green-body
// route"). Lengths in SI metres (the sintering of issue 17 is in SI).
#include <cstdint>
#include <filesystem>
#include <string>

#include "netdem/dynamic/green_body.hpp"

namespace netdem::app::netsolve {

struct GreenArgs {
  std::string route = "ballistic";  ///< --route ballistic | green-body
  dem::GreenBodyOptions body;       ///< bound directly by the command line
  double diameter = 50e-6;          ///< --diameter: mean diameter [m] (body.mean_radius = diameter / 2)
  double lamina = 25e-6;            ///< --lamina: q_s of Eq 48 [m] (the paper's Fig 10: 0.025 mm)
  double bulk_margin = 2.0;         ///< --bulk-margin: the bulk region's distance from every wall [mean diameters]
  double bulk_spacing = 0.1;        ///< lattice spacing of the bulk density [mean radii]
  bool quiet = false;
  bool allow_long = false;          ///< --allow-long: run even above kMaxGreenParticleSteps
};

/// Work above which the route is refused unless --allow-long: spheres x the lower bound of its
/// time steps (dem::green_body_min_steps); the default 805 spheres need about 6e7 (measured 7.5e7
/// in 16 s), 5e10 is hours of one core.
inline constexpr double kMaxGreenParticleSteps = 5e10;

/// Runs the route and writes the run folder `out` (packing.csv, laminar.csv, particles.vtp,
/// summary.json, command.txt); returns the exit code (0 ok, 3 unreachable or unconverged).
/// `overwrite`: --overwrite. Throws UsageError for bad options (before anything is written).
int run_pack_green_body(const GreenArgs& a, std::uint64_t seed, bool overwrite, const std::string& command,
                        const std::filesystem::path& out);

}  // namespace netdem::app::netsolve
