#pragma once
// The green-body packing route of Ivannikov et al. (section 3.2, after Nosewicz et al. and Yade),
// with the 3D explicit DEM (DynamicSolver3, public API only; issue 16 item 4, issue 17 item 5):
//   1. cloud    a random non-overlapping cloud of spheres (packing::random_fill_3d) in a tall box;
//   2. settle   gravity along -z (x3) until the sample is at rest;
//   3. lid      the z_max wall is moved down onto the uppermost particle (max z + r), not into it;
//   4. compress the lid (z_max) and the side planes x_max, y_max move inward at constant
//               velocities, all three reaching the box of the target density at the same time:
//               the box of the intended aspect (height / width) if every wall then moves inward,
//               else the settled box scaled by s = (settled density / target)^(1/3) (equal strains);
//   5. rest     the walls stop at the target box, the friction of the final state is restored,
//               and the sample comes to rest; the result is the packing at rest.
// Units: SI (metres, kilograms, seconds). The contact law is the linear spring-dashpot with a
// Cundall-Strack tangential spring (ContactModel::Linear), the walls are frictionless planes unless
// mu_wall > 0. The numbers are dimensionless where they can be: the stiffness number
// kappa = k r / (m g) (one particle's weight on a spring overlaps it by r / kappa), the wall
// speed in units of sqrt(g r), the rest criterion as kinetic energy per particle over m g r, the
// phase-time caps in units of sqrt(r / g), with r and m of the mean sphere. A scaled gravity
// (gravity != 9.81) rescales time only: at a fixed kappa the stiffness k grows with g, the time
// step shrinks as 1/sqrt(g) and every phase takes the same number of steps (docs/packing.md).
// The target is reached by the walls' kinematics (strain control); what tells whether it was
// honest is the overlap of the spheres at rest: above max_mean_overlap (mean overlap / r of the
// touching pairs) the result is refused as "unreachable".
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "netdem/packing/laminar.hpp"
#include "netdem/packing/packing.hpp"
#include "netdem/packing/random_fill.hpp"

namespace netdem::dem {

struct GreenBodyOptions {
  // the sample (defaults: the Cu packing of issue 17: 805 spheres, mean diameter 50 um +- 10 %)
  std::size_t n = 805;
  double mean_radius = 25e-6;      ///< [m]
  double dispersion = 0.1;         ///< radii uniform in mean_radius (1 +- dispersion)
  std::uint64_t seed = 1;
  double solid_density = 8960.0;   ///< [kg/m^3] (Cu); the masses only
  double target_density = 0.60;    ///< sum of sphere volumes / wall-box volume at the end
  double aspect = 0.8;             ///< intended final height / width (x = y), the paper's 0.4 / 0.5
  double cloud_fraction = 0.25;    ///< solid fraction of the cloud box (<= packing::kMaxCloudFraction)
  double settled_guess = 0.51;     ///< expected box density after the lid (sets the cloud's width; measured 0.511 at mu 0.3)
  // physics
  double gravity = 9.81;           ///< [m/s^2] along -z
  double stiffness_number = 1e4;   ///< kappa = k r / (m g) of the mean sphere
  double restitution = 0.3;        ///< normal restitution of a mean pair (sets gamma_n)
  double mu_settle = 0.3;          ///< particle friction while settling
  double mu_compress = 0.0;        ///< particle friction during the compression
  double mu_final = 0.3;           ///< particle friction of the final rest
  double mu_wall = 0.0;            ///< sphere-wall friction (all phases)
  double steps_per_contact = 25.0; ///< dt = t_c / steps_per_contact for a mean pair (Eq 6)
  // compression and rest
  double wall_speed = 0.02;        ///< speed of the fastest wall / sqrt(g r)
  double rest_energy = 1e-6;       ///< rest: translational kinetic energy per sphere < rest_energy m g r at 3 checks in a row
  double max_mean_overlap = 0.0025;  ///< refuse ("unreachable") a mean pair overlap / r above this at rest
  double max_phase_time = 400.0;   ///< cap of the settle and rest phases [sqrt(r / g)]
  std::int64_t check_every = 100;  ///< steps between the rest / progress checks
  /// Throws std::invalid_argument with one line naming the first bad value.
  void validate() const;
};

/// One phase of the route as run.
struct GreenBodyPhase {
  std::string name;                ///< settle, lid, compress, rest
  std::int64_t steps = 0;
  double time = 0.0;               ///< simulated time [s]
  double wall_seconds = 0.0;       ///< run time
  double density = 0.0;            ///< wall-box density at the end of the phase
  double kinetic = 0.0;            ///< translational kinetic energy per sphere / (m g r) at the end
  bool at_rest = false;            ///< the rest criterion held at the end (settle, rest)
};

/// What the progress callback sees (every check_every steps).
struct GreenBodyProgress {
  const char* phase = "";
  std::int64_t steps = 0;          ///< in this phase
  double time = 0.0;               ///< simulated time since the start [s]
  double density = 0.0;            ///< wall-box density
  double kinetic = 0.0;            ///< translational kinetic energy per sphere / (m g r)
  double fraction = -1.0;          ///< compress: fraction of the wall travel done; else -1
};

struct GreenBodyResult {
  packing::Packing packing;        ///< the final packing at rest (dim 3, box = the walls, seed)
  std::string status = "ok";       ///< ok | unreachable | unconverged
  std::string reason;              ///< why, when not ok
  // the model as run
  double stiffness = 0.0;          ///< k [N/m]
  double gamma_n = 0.0, gamma_t = 0.0;  ///< [kg/s]
  double dt = 0.0;                 ///< [s]
  double contact_time = 0.0;       ///< t_c of a mean pair [s]
  double mean_mass = 0.0;          ///< [kg]
  double time_unit = 0.0;          ///< sqrt(r / g) [s]
  // the boxes
  packing::Box cloud_box, settled_box, target_box;
  double settled_density = 0.0;    ///< sum V / box with the lid on the uppermost sphere
  double scale = 1.0;              ///< s = target box / settled box per axis
  double wall_velocity[3] = {0, 0, 0};  ///< x_max, y_max, z_max during the compression [m/s]
  double strain_rate = 0.0;        ///< |v| / L of the walls at the start of the compression [1/s]
  double inertial_number = 0.0;    ///< strain_rate d sqrt(rho_s / p_g), p_g = rho_s phi g H / 2
  double compress_max_mean_overlap = 0.0;  ///< the largest mean pair overlap / r seen while compressing
  /// the wall-box density at which the mean overlap first exceeded max_mean_overlap while
  /// compressing (0: never): about the densest state the rule admits
  double limit_density = 0.0;
  bool exact_aspect = false;       ///< the target box has the intended aspect (else: equal strains)
  double wall_stress[3] = {0, 0, 0};  ///< final stresses of the x_max, y_max, z_max walls [Pa]
  packing::OverlapStats overlaps;  ///< of the final packing
  std::vector<GreenBodyPhase> phases;
  bool ok() const { return status == "ok"; }
};

using GreenBodyObserver = std::function<void(const GreenBodyProgress&)>;

/// The options of the route's random cloud (step 1): random_fill_3d with them makes the same cloud
/// as make_green_body, so a cloud that cannot be placed can be refused before anything is written.
/// Throws std::invalid_argument for bad options (validate()).
packing::RandomFill3dOptions green_body_cloud_options(const GreenBodyOptions& options);

/// A lower bound on the route's time steps, for a work estimate before it runs: the free fall over
/// the cloud's empty height and the walls' travel at wall_speed from the expected settled box to
/// the target, over the mean pair's time step (the settle and rest phases' waits to come to rest
/// are not counted). Throws std::invalid_argument for bad options (validate()).
double green_body_min_steps(const GreenBodyOptions& options);

/// The steps per contact that the lightest pair of `cloud` (the route's cloud, green_body_cloud_options)
/// gets from the mean pair's time step, as the route's solver computes it; the solver refuses fewer
/// than 10 (DynamicOptions::min_steps_per_contact), which a wide dispersion gives.
double green_body_lightest_steps_per_contact(const GreenBodyOptions& options, const packing::Packing& cloud);

/// Runs the route. Deterministic for the options (one thread). Throws std::invalid_argument for
/// bad options (validate(), the cloud's checks), std::runtime_error when the cloud cannot be
/// placed, InstabilityError if the DEM breaks down. An unreachable target or a phase that does not
/// come to rest is not an exception: the result says so (status, reason) and holds the packing.
GreenBodyResult make_green_body(const GreenBodyOptions& options, const GreenBodyObserver& observer = {});

}  // namespace netdem::dem
