#pragma once
// demsolve run driver: a sequence of temperature/friction phases (LMM05 section 4.1) on one
// DynamicSolver, with the time series, snapshots, contact distributions and a restartable state
// after every phase, all under one output folder.
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "netdem/dynamic/schedule.hpp"
#include "netdem/dynamic/solver.hpp"

namespace netdem::app::dem {

/// Sample: random disks in a square box (prepare/sinter without --state).
struct SampleArgs {
  int n = 300;
  double initial_density = 0.35;
  std::uint64_t seed = 1;
  std::string arrangement = "random";  ///< random | triangle | line (three-particle control)
};

struct RunArgs {
  double pressure = 100.0;  ///< isotropic wall pressure p [N/m] (Eq 1)
  bool pressure_given = false;  ///< with a state file: override the state's wall pressure
  double mu = 0.5;          ///< particle friction once friction is on (Table 1)
  double mu_wall_prepare = 0.0;  ///< wall friction during preparation (Table 1: 0); 0 after t_heat
  double steps_per_contact = 50.0;  ///< Eq 6 rule, mean pair
  bool quiet = false;
  std::string state_file;  ///< start from this state (its time decides the phase)
  std::vector<std::string> param_overrides;  ///< NAME=VALUE for LudingParams
};

/// Random non-overlapping disks (radii uniform in a0 [1 - w0, 1 + w0] at T_radius_ref) with random
/// velocities in a square box of the given solid fraction; or the three-particle arrangements.
netdem::dem::Particles place_sample(const SampleArgs& a, const netdem::dem::LudingParams& lp,
                                    netdem::dem::Box& box);

/// Applies NAME=VALUE overrides; throws std::invalid_argument naming the bad item.
void apply_overrides(netdem::dem::LudingParams& p, const std::vector<std::string>& items);

/// Runs the phases from the solver's current time to the end of the last phase, writing
/// timeseries.csv, per-phase state/vtp/contact files and filling `summary`. Returns 0.
int run_phases(netdem::dem::DynamicSolver& s, const std::vector<netdem::dem::SinterPhase>& phases,
               const RunArgs& a, const std::filesystem::path& out, nlohmann::json& summary);

/// Everything for `demsolve prepare` / `demsolve sinter`: builds or loads the sample and runs.
int run_protocol(const std::string& command, const SampleArgs& sample, const RunArgs& args,
                 const netdem::dem::SinterProtocol& protocol, bool prepare_only,
                 const std::filesystem::path& out);

}  // namespace netdem::app::dem
