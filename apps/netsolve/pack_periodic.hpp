#pragma once
// netsolve pack --periodic: a periodic packing by the explicit DEM in a periodic cell (a random
// gas compressed until it jams, held at a small pressure until at rest; netdem/dynamic/
// periodic_packing.hpp; docs/packing.md "Periodic packings").
#include <cstdint>
#include <filesystem>
#include <string>

#include "netdem/dynamic/periodic_packing.hpp"

namespace netdem::app::netsolve {

struct PeriodicPackArgs {
  bool periodic = false;          ///< --periodic
  dem::PeriodicPackOptions pack;  ///< n, radii, seed, --pack-friction, --jam-pressure
  bool quiet = false;
};

/// Above this the default overlap check fails the run ("unconverged", exit 3): the largest pair
/// overlap of the packing at rest, in units of the mean radius (docs/packing.md).
inline constexpr double kMaxPeriodicOverlap = 1e-2;

/// Runs the route and writes the run folder `out` (packing.csv with '# periodic', particles.vtp,
/// cell.vtp, summary.json, command.txt); returns the exit code (0 ok, 3 unconverged).
int run_pack_periodic(const PeriodicPackArgs& a, int dim, bool overwrite, const std::string& command,
                      const std::filesystem::path& out);

}  // namespace netdem::app::netsolve
