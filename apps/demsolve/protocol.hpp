#pragma once
// demsolve's commands: the parsed options, the calls into netdem/dynamic/protocol.hpp (the
// sintering protocol of LMM05 section 4.1) and material_tests.hpp (section 4.4), and the output:
// time series, snapshots, contact distributions and a restartable state after every phase, all
// under one output folder.
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "netdem/dynamic/protocol.hpp"
#include "netdem/dynamic/schedule.hpp"
#include "netdem/dynamic/solver.hpp"
#include "output.hpp"

namespace netdem::app::dem {

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

/// Applies NAME=VALUE overrides; throws std::invalid_argument naming the bad item.
void apply_overrides(netdem::dem::LudingParams& p, const std::vector<std::string>& items);

/// particles_<label>.vtp (radius, velocity, omega, particle_pressure = average particle stress
/// p_i = sum_c f_n d_i / (2 pi a_i^2) [N/m], contacts, and `extra`), contacts_<label>.vtp (f_n,
/// f_t, attractive, sliding per contact line) and contacts_<label>.csv (distributions).
void write_snapshot(const netdem::dem::DynamicSolver& s, const std::filesystem::path& out, const std::string& label,
                    std::vector<netdem::dem::ContactInfo>& buffer, const std::vector<Field>& extra = {});

/// Loads a state file with NAME=VALUE overrides applied to its contact parameters.
netdem::dem::SolverState load_state(const std::string& file, const std::vector<std::string>& overrides);

/// Everything for `demsolve prepare` / `demsolve sinter`: builds or loads the sample and runs.
/// demsolve compress: the bi-axial test of LMM05 section 4.4.1 on a state.
struct CompressArgs {
  std::string state_file;
  double strain_rate = 1.0;  ///< d eps_zz / dt [1/s], top wall velocity -rate z0
  double max_strain = 0.1;
  double ramp_time = 0.005;  ///< the top wall's speed rises smoothly, (1 - cos)/2, over this time [s]
  double pressure = 0.0;     ///< sigma_xx held by the right wall; 0: the state's
  bool quiet = false;
  std::vector<std::string> param_overrides;
};
int run_compress(const std::string& command, const CompressArgs& a, const std::filesystem::path& out);

/// demsolve vibrate: LMM05 Figs 21-22, the sample on a flat bottom vibrated vertically in gravity.
struct VibrateArgs {
  std::string state_file;
  double frequency = 100.0;  ///< [Hz]
  double amplitude = 2.0e-4;  ///< [m]
  double time = 0.1;          ///< [s]
  double gravity = 9.81;      ///< [m/s^2]
  bool quiet = false;
  std::vector<std::string> param_overrides;
};
int run_vibrate(const std::string& command, const VibrateArgs& a, const std::filesystem::path& out);

int run_protocol(const std::string& command, const netdem::dem::SampleSpec& sample, const RunArgs& args,
                 const netdem::dem::SinterProtocol& protocol, bool prepare_only,
                 const std::filesystem::path& out);

}  // namespace netdem::app::dem
