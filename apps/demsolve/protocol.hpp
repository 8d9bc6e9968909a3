#pragma once
// demsolve's commands: the parsed options, the calls into netdem/dynamic/protocol.hpp (the
// sintering protocol of LMM05 section 4.1) and material_tests.hpp (section 4.4), and the output:
// time series, snapshots, contact distributions and a restartable state after every phase, all
// under one output folder.
#include <cstdint>
#include <filesystem>
#include <functional>
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
  double mu_prepare = 0.0;       ///< particle friction during preparation (the paper: 0); mu after t_heat
  double steps_per_contact = netdem::dem::DynamicOptions{}.steps_per_contact;  ///< Eq 6 rule, mean pair
  std::int64_t samples = 3000;  ///< timeseries.csv rows over the run (equal steps apart)
  int threads = 1;              ///< DynamicOptions::threads (the same results for any number)
  bool quiet = false;
  std::string state_file;  ///< start from this state (its time decides the phase)
  std::vector<std::string> param_overrides;  ///< NAME=VALUE for LudingParams
  bool sample_given = false;   ///< --n, --seed or --arrangement on the command line (refused with --state)
  bool packing_given = false;  ///< --packing on the command line (refused if empty)
  double max_steps = 1e9;      ///< --max-steps
  bool allow_long = false;     ///< --allow-long: run past kMaxParticleSteps
  bool overwrite = false;      ///< --overwrite
  int dim = 2;                 ///< --dim: 2 disks, 3 spheres (a state file gives its own)
  bool dim_given = false;
};

/// `m` with control characters as spaces (one line on stderr).
std::string one_line(const std::string& m);

/// Runs `body` (a command) and maps its exceptions to one line on stderr and the exit code:
/// UsageError, or any std::invalid_argument before the run folder was opened: 2; out of memory
/// and every other error: 1. (A detected instability is handled inside the command: exit 3.)
int guarded(const std::function<int()>& body);

/// Work above which a run is refused unless --allow-long: particles x time steps (about 1-3 h of
/// one core at the measured 1e7-2e7 particle-steps per second; docs/dynamic.md "Limits").
inline constexpr double kMaxParticleSteps = 5e10;

/// Door checks shared by every command, on the solver before it runs (docs/dynamic.md "Limits"):
/// the step count `steps` (a double, so that an absurd count is not an overflow) against
/// max_steps, the work (particles x steps) against kMaxParticleSteps unless allow_long, the
/// normal and wall damping and the wall mass against the time step. Throws UsageError with the
/// estimate.
template <int D>
void check_run_limits(const netdem::dem::DynamicSolverT<D>& s, double steps, double max_steps, bool allow_long);
/// The memory estimate of a run of n particles against MemAvailable (/proc/meminfo); throws
/// UsageError with the estimate. Call it before building the solver.
void check_memory(std::size_t n);
/// 2p/k2 (Luding section 4): UsageError above 0.1, a warning line on stderr above 0.02 (returned,
/// "" if none). `what` names the option. dim 3: p in N/m^2 and the ratio 4 p a0 / k2 (the force on
/// a sphere's (2 a0)^2 of wall over k2 a0).
std::string check_loading(double pressure, const netdem::dem::LudingParams& p, const std::string& what, int dim = 2);
/// T above absolute zero and |da_T (T - T_radius_ref)| <= 0.05; UsageError naming `what`.
void check_temperature(double T, const netdem::dem::LudingParams& p, const std::string& what);

/// A run stopped by an instability check: writes state_last_good.txt (the solver's last checked
/// state) and summary.json (`summary` + "status": "unstable", the reason, step and quantity),
/// closes the run folder, prints the one-line error; returns 3.
template <int D>
int report_unstable(const netdem::dem::InstabilityError& e, const netdem::dem::DynamicSolverT<D>& s,
                    const std::filesystem::path& out, nlohmann::json summary);

/// Applies NAME=VALUE overrides; throws std::invalid_argument naming the bad item.
void apply_overrides(netdem::dem::LudingParams& p, const std::vector<std::string>& items);

/// particles_<label>.vtp (radius, velocity, omega, particle_pressure = average particle stress
/// p_i = sum_c f_n d_i / (2 pi a_i^2) [N/m], contacts, and `extra`), contacts_<label>.vtp (f_n,
/// f_t, attractive, sliding per contact line) and contacts_<label>.csv (distributions).
/// 3D: the same with z, velocity and spin vectors, p_i in N/m^2 and |f_t|. In series.dir(), listed in
/// `series` at the time `t`.
template <int D>
void write_snapshot(const netdem::dem::DynamicSolverT<D>& s, SnapshotSeries& series, const std::string& label, double t,
                    std::vector<netdem::dem::ContactInfo>& buffer, const std::vector<Field>& extra = {});
/// The series of those snapshots, snapshots.pvd: ParaView's time is the time t of the run's time
/// series (timeseries.csv, compress.csv); parts particles and contacts.
SnapshotSeries protocol_snapshot_series(const std::filesystem::path& out);

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
  int threads = 1;
  bool quiet = false;
  std::vector<std::string> param_overrides;
  double max_steps = 1e9;
  bool allow_long = false;
  bool overwrite = false;
};
int run_compress(const std::string& command, const CompressArgs& a, const std::filesystem::path& out);

/// demsolve vibrate: LMM05 Figs 21-22, the sample on a flat bottom vibrated vertically in gravity.
struct VibrateArgs {
  std::string state_file;
  double frequency = 100.0;  ///< [Hz]
  double amplitude = 2.0e-4;  ///< [m]
  double time = 0.1;          ///< [s]
  double gravity = 9.81;      ///< [m/s^2]
  int threads = 1;
  bool quiet = false;
  std::vector<std::string> param_overrides;
  double max_steps = 1e9;
  bool allow_long = false;
  bool overwrite = false;
};
int run_vibrate(const std::string& command, const VibrateArgs& a, const std::filesystem::path& out);

/// dim 3: spheres (netdem::dem::place_sample3 / make_sample3, a 3D state file), the right, back and top
/// walls stress-controlled at p [N/m^2].
int run_protocol(const std::string& command, const netdem::dem::SampleSpec& sample, const RunArgs& args,
                 const netdem::dem::SinterProtocol& protocol, bool prepare_only,
                 const std::filesystem::path& out);

}  // namespace netdem::app::dem
