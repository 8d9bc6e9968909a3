#pragma once
// The sintering protocol of Luding, Manetsberger & Muellers (2005) section 4.1 as library
// functions (demsolve prepare / sinter only parse, call these and write): the starting sample
// (random fill, the three-particle controls, or a packing file such as netsolve's), the
// stress-controlled walls of the preparation, the contact counts, and the stepping through the
// phases of a SinterProtocol with the friction switch at t_heat. Output is the caller's, through
// PhaseObserver. See docs/sintering.md.
//
// Units of a packing file (packing CSV, netdem/packing/io.hpp): netsolve writes lengths in units
// of its reference radius R, the DEM works in metres. Every length (x, y, r, box) is multiplied
// by `length_unit` [m per file unit]; length_unit = 0 (the default) maps the file's mean radius
// onto Luding's a0 (LudingParams::a0, Table 1: 1 mm), i.e. length_unit = a0 / mean(r).
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "netdem/dynamic/schedule.hpp"
#include "netdem/dynamic/solver.hpp"
#include "netdem/packing/packing.hpp"

namespace netdem::dem {

/// The starting sample of prepare / sinter (without a state file).
struct SampleSpec {
  int n = 300;
  double initial_density = 0.35;  ///< solid fraction of the random fill
  std::uint64_t seed = 1;
  std::string arrangement = "random";  ///< random | triangle | line (three-particle control)
  std::string packing_file;            ///< non-empty: the disks of this packing CSV, at rest
  double length_unit = 0.0;            ///< [m per file unit]; 0: a0 / mean file radius
};

/// Random fill (packing::random_fill): n radii uniform in a0 [1 - w0, 1 + w0] (radii at
/// T_radius_ref), then the positions in a square box of solid fraction initial_density, then the
/// velocities uniform in [-0.01, 0.01] m/s, all from std::mt19937_64(seed) in this order; or the
/// three-particle arrangements (n = 3, radius a0). Sets `box`'s geometry (walls fixed).
Particles place_sample(const SampleSpec& spec, const LudingParams& lp, Box& box);
/// 3D (issue 16): spheres of density rho_p (Table 1's rho_p read per volume: m = rho_p 4/3 pi a^3,
/// I = 2/5 m a^2), radii uniform in a0 [1 - w0, 1 + w0], placed by packing::random_fill_3d in a cube
/// whose centre region (L - 2 a0 (1 + w0))^3 holds the expected solid volume at kInitialDensity3
/// (random sequential addition of spheres jams near 0.38, so 2D's 0.35 is out of reach), then the
/// velocities uniform in [-0.01, 0.01] m/s per component from std::mt19937_64(seed + 1). The
/// three-particle arrangements are 2D only.
Particles3 place_sample3(const SampleSpec& spec, const LudingParams& lp, Box& box);
inline constexpr double kInitialDensity3 = 0.25;

/// The metres per file unit of the rule in the file comment (length_unit, or a0 / mean radius).
double packing_length_unit(const packing::Packing& p, const LudingParams& lp, double length_unit);

/// The disks of `p` at rest in SI units (see the file comment); `box` gets p's box scaled, its top
/// wall raised to the highest disk top if a disk sticks out through the (open) lid.
/// Throws std::invalid_argument with one line if p is invalid (packing::validate), length_unit is
/// negative or not finite, a disk reaches through a side wall or the floor (the DEM would start
/// with a wall overlap), or a radius in metres is not
/// within [a0 / 100, 100 a0] (Luding's length scales, delta_fluid = 0.2 a0, are set by a0; a
/// file in other units than assumed lands here).
Particles particles_from_packing(const packing::Packing& p, const LudingParams& lp, double length_unit, Box& box);

/// The sample of `spec`: the packing file if one is given (read_packing_csv, then
/// particles_from_packing; `length_unit`, if not null, gets the metres per file unit used), else
/// place_sample (`length_unit` untouched).
Particles make_sample(const SampleSpec& spec, const LudingParams& lp, Box& box, double* length_unit = nullptr);
/// 3D: a 3D packing file's spheres at rest (density rho_p per volume; lengths as above, the lid
/// raised to the highest sphere top), else place_sample3.
Particles3 make_sample3(const SampleSpec& spec, const LudingParams& lp, Box& box, double* length_unit = nullptr);

/// LMM05 Eq 1: right and top walls stress-controlled at pressure p [N/m], with the wall mass and
/// damping of the parameters (Table 1). dim 3: the right, back and top walls, p in N/m^2.
void set_stress_walls(Box& box, double pressure, const LudingParams& lp, int dim = 2);

struct ContactCounts {
  std::size_t pairs = 0, walls = 0;  ///< touching particle pairs and particle-wall contacts
  /// C = (2 pairs + walls) / n, with or without the wall contacts.
  double coordination(std::size_t n) const {
    return (2.0 * static_cast<double>(pairs) + static_cast<double>(walls)) / static_cast<double>(n);
  }
  double coordination_without_walls(std::size_t n) const {
    return 2.0 * static_cast<double>(pairs) / static_cast<double>(n);
  }
};
/// The contacts (overlap > 0) at the current state; `buffer` is the workspace of touching_pairs.
template <int D>
ContactCounts count_contacts(const DynamicSolverT<D>& s, std::vector<std::pair<std::uint32_t, std::uint32_t>>& buffer);

/// Average stress of each particle, p_i = (1 / (2 pi a_i^2)) sum_c f_n d_i over its contacts in
/// `contacts` (DynamicSolver::contacts; normal forces, compression positive, N/m like the wall
/// pressure; LMM05 Fig 20's colouring), and its number of contacts z_i. Spheres (D = 3): the
/// mean of the trace, p_i = (1 / (4 pi a_i^3)) sum_c f_n d_i [N/m^2].
template <int D>
void particle_stress(const ParticlesT<D>& P, const std::vector<ContactInfo>& contacts, std::vector<double>& p,
                     std::vector<double>& z);

/// What the caller records while run_phases() steps.
template <int D>
class PhaseObserverT {
 public:
  virtual ~PhaseObserverT() = default;
  /// At the start, every `sample_every` steps and after the last step (if not just sampled);
  /// `phase` is the phase of the last step (at the start: of the current time), `steps` the
  /// steps done so far in this run.
  virtual void sample(const DynamicSolverT<D>& s, std::size_t phase, std::int64_t steps) = 0;
  /// After the step that ends phase `phase` (after its sample, if any).
  virtual void phase_end(const DynamicSolverT<D>& s, std::size_t phase) = 0;
};
using PhaseObserver = PhaseObserverT<2>;

/// Friction of the protocol (LMM05 section 4.1): particles at mu_prepare (the paper: 0,
/// frictionless) and walls at mu_wall_prepare before t_heat (the phases with friction = false), mu
/// and frictionless walls after.
struct PhaseFriction {
  double mu = 0.5;
  double mu_wall_prepare = 0.0;
  double mu_prepare = 0.0;
};

struct PhaseRun {
  std::int64_t steps = 0;         ///< steps done
  std::int64_t sample_every = 1;  ///< steps between samples
};

/// The steps run_phases() does from the solver's current time to the end of the last phase.
template <int D>
std::int64_t steps_to_end(const DynamicSolverT<D>& s, const std::vector<SinterPhase>& phases);

/// Steps `s` from its current time to the end of the last phase: per step the friction of the
/// phase (set_params on a change, from the parameters `s` has at the call), the temperature ramp
/// with the phase's t0 (advance_temperature), one step. The last step may end a fraction of dt
/// past the protocol; it still belongs to the last phase of non-zero length. Samples about
/// `samples` times (every max(1, total / samples) steps).
template <int D>
PhaseRun run_phases(DynamicSolverT<D>& s, const std::vector<SinterPhase>& phases, const PhaseFriction& friction,
                    std::int64_t samples, PhaseObserverT<D>& observer);

}  // namespace netdem::dem
