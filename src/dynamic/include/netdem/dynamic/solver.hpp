#pragma once
// Explicit (molecular-dynamics) DEM solver for 2D disks (DynamicSolver) and 3D spheres
// (DynamicSolver3; issue 16: the same template, DynamicSolverT<D>, see "3D" below) with the sintering contact law of
// Luding, Manetsberger & Muellers, J. Mech. Phys. Solids 53 (2005) 455 (LMM05), sections 2-3:
// Newton's equations Eq 2 by velocity Verlet (kick-drift-kick), time step of Eq 6, Verlet-table
// neighbour search, a bi-axial box whose right/top walls are strain- or stress-controlled (Eq 1).
//
// Conventions (as netdem/contact/kinematics.hpp): a contact is the ordered pair (i, j), i < j;
// n from i to j, t = perp(n); overlap delta > 0 when touching; f_n > 0 repulsive is the force ON j.
// A wall contact is the pair (wall, particle): n points from the wall into the box.
// Units: SI as LMM05 Table 1; disks of height h = params.h (2D cylinders): mass rho_p pi a^2 h,
// stiffness N/m, damping kg/s, wall pressure p in N/m (force per wall length), wall mass kg.
// Stress is reported as force per length (N/m) with compression POSITIVE.
// See docs/dynamic.md.
//
// 3D (D = 3, issue 16, first part): spheres (I = 2/5 m r^2, rotation vectors), the box with six
// walls (x_min .. z_max; gravity usually along -z), the right (x_max), back (y_max) and top (z_max)
// walls moving (strain- or stress-controlled, Eq 1 with the wall's current area), the laws through
// the interface in 3D (law.hpp: the tangential history carried into the current plane every step
// by contact::step_transport), the affine field with the full symmetric 3 x 3 strain rate
// (set_strain_rate3: prescribed particles, Affine walls, the affine drag, boundary_stress), state
// files and restarts, contacts(). The 2D set_strain_rate throws std::logic_error in 3D (one line).
#include <cstddef>
#include <array>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include <type_traits>

#include "netdem/contact/luding.hpp"
#include "netdem/contact/luding_law.hpp"
#include "netdem/contact/plastic_indentation.hpp"
#include "netdem/dynamic/particles.hpp"
#include "netdem/packing/packing.hpp"
#include "netdem/packing/periodic.hpp"
#include "netdem/system/pair_rows.hpp"
#include "netdem/system/thread_team.hpp"

namespace netdem::dem {

using contact::LudingHistory;
using contact::LudingParams;

/// The spheres of a 3D packing at rest, density rho (add_sphere()).
/// The readers below are for walled (or open) packings: a periodic packing (Packing::periodic) is
/// refused with one line (std::invalid_argument); periodic_particles_from() reads it.
Particles3 spheres_from(const packing::Packing& p, double rho);
/// The particles of a 2D packing (x, y, r; SI units, m) at rest: add() of each disk in order.
Particles particles_from(const packing::Packing& p, const LudingParams& params);
/// The particles of a 2D packing at rest as disks of areal density rho (add_disk(); any units).
Particles particles_from(const packing::Packing& p, double rho);
/// The particles of a walled or open packing of dimension D at rest, of density rho:
/// particles_from (disks) or spheres_from (spheres).
template <int D>
ParticlesT<D> particles_at_rest(const packing::Packing& p, double rho) {
  if constexpr (D == 2) return particles_from(p, rho);
  else return spheres_from(p, rho);
}
/// The particles of a periodic packing (issue 29) of dimension D at rest, disks or spheres of
/// density rho (add_disk(), add_sphere()): for the solver constructors that take a periodic cell
/// (packing::periodic_cell()). Refuses a packing that is not periodic or of another dimension (one line).
template <int D>
ParticlesT<D> periodic_particles_from(const packing::Packing& p, double rho);
/// The geometric description of the particles (centres, radii) in `box`; seed 0, no comments.
template <int D>
packing::Packing to_packing(const ParticlesT<D>& P, const packing::Box& box);

/// Contact-law instantiation, chosen once per run (no virtual call per contact).
enum class ContactModel : std::uint8_t {
  Linear,      ///< luding_evaluate<kLudingLinear>: k2 delta + gamma0 delta', Cundall-Strack spring
  Hysteretic,  ///< {hysteresis}: Eq 4 and Eq 7 without cohesion or temperature
  Full,        ///< kLudingFull: Eq 4-24 with k1(T, t) from the solver's thermal state
  /// The plastic-indentation law of Redanz & Fleck 2001 (contact::PlasticIndentationLaw), set by
  /// the constructor that takes its parameters (DynamicOptions::plastic); any consistent units
  /// (netdem's: sigma_y, R, t* = R sqrt(rho/sigma_y)). The Luding parameters are not used.
  PlasticIndentation
};

/// The DEM's laws, one entry each: the template of the law's contact history (Law::History of
/// dimension D, law.hpp). The solver's history tables (DynamicSolverT::HistoryTables) and the
/// histories of a SolverState are made from this one list: a new law is one entry here.
template <template <int> class... H>
struct HistoryList {
  /// std::variant<Wrap<H<D>>...>: one alternative per law, of dimension D
  template <template <class> class Wrap, int D>
  using OfDim = std::variant<Wrap<H<D>>...>;
  /// the same for both dimensions: the 2D alternatives, then the 3D ones
  template <template <class> class Wrap>
  using Of2And3 = std::variant<Wrap<H<2>>..., Wrap<H<3>>...>;
  /// f(std::type_identity<H<D>>{}) for each law, in the list's order
  template <int D, class F>
  static void for_each(F&& f) {
    (f(std::type_identity<H<D>>{}), ...);
  }
};
using DemLaws = HistoryList<contact::LudingHistoryT, contact::PlasticIndentationHistoryT>;

/// The dimension D of a history type H<D>.
template <class H>
struct HistoryDim;
template <template <int> class H, int D>
struct HistoryDim<H<D>> {
  static constexpr int value = D;
};

/// The committed contact histories of one law in a SolverState (H: the law's history type, of the
/// state's dimension).
template <class H>
struct LawHistories {
  using History = H;
  static constexpr int kDim = HistoryDim<H>::value;
  std::vector<H> pair;  ///< one per SolverState::pair_key
  std::vector<H> wall;  ///< 2 D per particle: x_min, x_max, y_min, y_max (, z_min, z_max)
};

/// Fixed; Strain: a prescribed velocity; Stress: Eq 1; Affine: the wall follows the macroscopic
/// strain rate of set_strain_rate() about the fixed lower-left corner (x_max' = E11' (x_max -
/// x_min), exactly exponential over a step).
enum class WallMode : std::uint8_t { Fixed, Strain, Stress, Affine };

/// The right (moves along x) or top (moves along y) wall.
struct MovingWall {
  WallMode mode = WallMode::Fixed;
  double velocity = 0.0;  ///< Strain: prescribed velocity [m/s] along +x (right) / +y (top)
  double pressure = 0.0;  ///< Stress: external pressure p [N/m] (Eq 1)
  double mass = 0.01;     ///< Stress: m_w [kg] (Eq 1; Table 1)
  double damping = 0.2;   ///< Stress: gamma_w [kg/s] (Eq 1; Table 1)
};

/// Bi-axial box (LMM05 Fig 1): the geometry is the toolkit's one box, packing::Box (x_min, y_min,
/// x_max, y_max, as in the packings and the network solver), with the control of its walls: left
/// (x_min) and bottom (y_min) walls fixed, right and top walls moving.
struct Box : packing::Box {
  bool enabled = true;  ///< false: no walls, unbounded free system
  /// false: the box is the measurement domain only (density, stress volume, its walls move as
  /// set), without wall contacts; the centres may leave it (a prescribed boundary layer confines)
  bool contact_walls = true;
  MovingWall right, top;  ///< x_max; y_max (2D) or z_max (3D)
  MovingWall back;        ///< 3D only: y_max
  Box() : packing::Box{0.0, 0.0, 1.0, 1.0} {}
  /// Fixed walls at the sides of `b`.
  explicit Box(const packing::Box& b) : packing::Box(b) {}
};

enum class TimeStepRule : std::uint8_t {
  MeanPair,     ///< LMM05 Eq 6: t_MD = pi/(steps_per_contact omega), omega for the mean pair
  LightestPair  ///< stricter: the same with omega of the two lightest particles
};

struct DynamicOptions {
  ContactModel model = ContactModel::Full;
  TimeStepRule rule = TimeStepRule::MeanPair;
  double steps_per_contact = 50.0;      ///< Eq 6: t_MD = t_c / 50
  double min_steps_per_contact = 10.0;  ///< refuse dt giving the lightest pair fewer steps
  double dt = 0.0;                      ///< > 0: this time step (still checked); 0: from the rule
  double skin = 0.0;                    ///< Verlet skin [m]; 0: 0.3 x mean radius
  double gravity_x = 0.0, gravity_y = 0.0;  ///< [m/s^2]
  double gravity_z = 0.0;                   ///< [m/s^2], 3D only
  double temperature = 80.0;  ///< [deg C] initial T of the thermal state (ContactModel::Full)
  /// Steps between the instability checks of step() (DynamicSolver::check_health; 0: never).
  std::int64_t check_every = 500;
  /// Test and diagnosis: the force loop calls the law's evaluate() instead of its in-place
  /// update() (law.hpp update_contact); the results are the same to the last bit.
  bool reference_contact_path = false;
  /// Drag on the motion relative to the affine field of set_strain_rate(): force -affine_drag m (v -
  /// E' (x - x_0)), torque -affine_drag I omega, on the particles that are not prescribed [1/time];
  /// 0: none.
  double affine_drag = 0.0;
  /// ContactModel::PlasticIndentation: the law (the constructor's PlasticIndentationParams;
  /// first_touch > 0: the explicit solver needs the bounded first-touch stiffness) and the
  /// friction of the walls (flat, R* = r_i).
  contact::PlasticIndentationParams plastic;
  double plastic_wall_mu = 0.0;
  /// Periodic cells: re-map the cell to its reduced (least tilted) equivalent at the table builds
  /// (Lees-Edwards; DynamicSolverT::cell_remaps()). false: the cell keeps its vectors (tests).
  bool cell_remap = true;
  /// Threads for the pair loop and the integration (sys::ThreadTeam). The results are the same to the last
  /// bit for any number: the rows' forces are summed per particle in row order, as one thread does.
  int threads = 1;
  /// Throws std::invalid_argument with one line for an invalid value.
  void validate() const;
};

struct TimeStepInfo {
  double dt = 0.0;                          ///< chosen time step [s]
  /// the tangential period of the lightest pair (tangential_period) with the law's tangential
  /// bound (0: none)
  double tc_tangential = 0.0;
  double tc_mean = 0.0;                     ///< Eq 6 contact duration of the mean pair [s]
  double tc_lightest = 0.0;                 ///< Eq 6 contact duration of the lightest pair [s]
  /// the lightest pair's shorter period (normal or tangential) / dt
  double steps_per_contact_lightest = 0.0;
};
/// Eq 6 contact duration pi/omega, omega = sqrt(k2/m12 - eta0^2), eta0 = gamma0/(2 m12);
/// for an over-damped pair the undamped omega is used (shorter, stricter).
double contact_duration(double k2, double gamma0, double m12);
/// The tangential half period pi sqrt(m_t / k_t) of a pair of effective mass m_eff, m_t its
/// tangential effective mass with the rotations (dim.hpp): m_eff / 3 for disks (dim 2), 2/7 m_eff
/// for spheres (dim 3).
double tangential_period(double m_eff, double k_t, int dim);
/// The time step from a law's a-priori stiffness bound (law.hpp kHasExplicitBound), for any law:
/// the normal period of the bound's k_n (damped by its gamma_n as Eq 6: contact_duration; pi
/// sqrt(m/k_n) without a dashpot) and the tangential period (tangential_period) of k_t + k_t_area
/// area_max, both for the pair of the rule (the mean pair only where the law allows it,
/// `mean_pair`: kMeanPairTimeStep; else the lightest pair); dt = the shorter / steps_per_contact,
/// or options.dt. The lightest pair's periods are checked (TimeStepInfo::tc_lightest, tc_tangential). Throws std::invalid_argument if the lightest pair gets fewer
/// than options.min_steps_per_contact steps per period, or if the bound is not finite.
template <int D>
TimeStepInfo choose_time_step(const ParticlesT<D>& P, const contact::StiffnessBound& bound, bool mean_pair,
                              const DynamicOptions& o, double area_max = 0.0);
/// The same with the law's bound for the largest particle radius (a wall contact's R* = r_i).
template <int D, class Law>
TimeStepInfo choose_time_step(const ParticlesT<D>& P, const Law& law, const DynamicOptions& o, double area_max = 0.0) {
  static_assert(contact::kHasExplicitBound<Law>, "an explicit time step needs the law's stiffness_bound(r_eff)");
  double r_max = 0.0;
  for (double r : P.r) r_max = r > r_max ? r : r_max;
  return choose_time_step(P, law.stiffness_bound(r_max), contact::kMeanPairTimeStep<Law>, o, area_max);
}

struct Stress2 {
  double xx = 0.0, xy = 0.0, yx = 0.0, yy = 0.0;  ///< [N/m], compression positive
};
/// 3D stress [N/m^2], compression positive; s[a][b] = (1/V) sum f_a l_b.
struct Stress3 {
  double s[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
};

struct Energies {
  double kinetic = 0.0;  ///< sum m v^2 / 2 + I omega^2 / 2 of the particles [J]
  double elastic = 0.0;  ///< sum k2 delta^2 / 2 over contacts (exact for ContactModel::Linear)
  double gravity = 0.0;  ///< -sum m g.x
  double wall_kinetic = 0.0;
  double total() const { return kinetic + elastic + gravity + wall_kinetic; }
};

/// Everything a restart needs, as plain data (see state.hpp for the file format). The forces and
/// the wall forces of the last evaluation are part of it: velocity Verlet's closing half kick used
/// them, and re-evaluating them would commit the last slip increment twice.
struct SolverState {
  /// The particles of the state's dimension (the default: none, 2D); r = current a_i(T); force,
  /// torque = the last forces.
  std::variant<Particles, Particles3> particles;
  std::vector<double> radius_ref;   ///< radii at params.T_radius_ref (Eq 9), constant
  Box box;
  double wall_velocity[2] = {0, 0};  ///< right, top [m/s]
  double wall_force[4] = {0, 0, 0, 0};  ///< left, right, bottom, top (last evaluation) [N]
  double stress_sum[4] = {0, 0, 0, 0};  ///< sum f (x) l: xx, xy, yx, yy (last evaluation) [N m]
  double elastic = 0.0;
  double time = 0.0;
  double dt = 0.0;
  contact::LudingThermalState thermal;
  LudingParams params;
  std::vector<std::uint64_t> pair_key;      ///< (i << 32 | j), i < j, sorted
  /// The histories of the state's law and dimension: one alternative per law of DemLaws and
  /// dimension (the default: the Luding law's in 2D, empty).
  DemLaws::Of2And3<LawHistories> histories;
  // 3D (dim() == 3) instead of the 2D arrays above: the moving walls right (x_max), back
  // (y_max), top (z_max); the six walls x_min, x_max, y_min, y_max, z_min, z_max; sum f (x) l row-major.
  double wall_velocity3[3] = {0, 0, 0};
  double wall_force3[6] = {0, 0, 0, 0, 0, 0};
  double stress_sum3[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
  /// ContactModel::PlasticIndentation: the law and the wall friction of the solver that wrote the
  /// state (DynamicOptions::plastic, plastic_wall_mu); a restart continues with them.
  contact::PlasticIndentationParams plastic;
  double plastic_wall_mu = 0.0;
  /// The plastic law: the largest contact width A_c of the last force evaluation (the tangential
  /// bound of the next step's time step, law.hpp StiffnessBound::k_t_area).
  double plastic_area_max = 0.0;
  /// The state of a solver in a periodic cell (issue 29): kept in memory (DynamicSolverT::last_good());
  /// the state file and the restart refuse it (the cell and the pairs' images are not in the format).
  bool periodic = false;
  int dim() const { return particles.index() == 0 ? 2 : 3; }
  /// The particles of dimension D (std::bad_variant_access if the state is of the other one).
  template <int D>
  ParticlesT<D>& particles_of() {
    return std::get<ParticlesT<D>>(particles);
  }
  template <int D>
  const ParticlesT<D>& particles_of() const {
    return std::get<ParticlesT<D>>(particles);
  }
  /// The number of particles (either dimension).
  std::size_t particle_count() const {
    return std::visit([](const auto& p) { return p.size(); }, particles);
  }
  /// The histories hold law history H (its law and dimension).
  template <class H>
  bool holds() const {
    return std::holds_alternative<LawHistories<H>>(histories);
  }
  /// The histories of law history H (std::bad_variant_access if the state holds another's).
  template <class H>
  LawHistories<H>& histories_of() {
    return std::get<LawHistories<H>>(histories);
  }
  template <class H>
  const LawHistories<H>& histories_of() const {
    return std::get<LawHistories<H>>(histories);
  }
  /// The dimension of the histories (dim() for a consistent state).
  int histories_dim() const {
    return std::visit([](const auto& h) { return std::decay_t<decltype(h)>::kDim; }, histories);
  }
  /// A state of the plastic-indentation law.
  bool plastic_law() const {
    return holds<contact::PlasticIndentationHistoryT<2>>() || holds<contact::PlasticIndentationHistoryT<3>>();
  }
};

/// One touching contact at the current state, for output (distributions, snapshots).
struct ContactInfo {
  std::uint32_t i = 0, j = 0;  ///< particles i < j; for a wall contact i = particle, j = wall
  int wall = -1;               ///< -1 particle pair; 0 left, 1 right, 2 bottom, 3 top (3D: 0 .. 5 = x_min .. z_max)
  double overlap = 0.0;        ///< delta [m]
  double d_i = 0.0, d_j = 0.0;  ///< centre-to-contact distances [m] (d_j = 0 for a wall)
  double nx = 0.0, ny = 0.0;   ///< unit normal from i to j (from the wall into the box)
  double nz = 0.0;             ///< 3D: its z component
  double f_n = 0.0;            ///< normal force on j [N], > 0 repulsive (spring + damping)
  double f_spring = 0.0;       ///< its spring part: the law at zero relative velocity (no dashpot) [N]
  double f_t = 0.0;            ///< tangential force on j along t = perp(n) [N] (3D: its magnitude)
  double ftx = 0.0, fty = 0.0, ftz = 0.0;  ///< 3D: the tangential force on j [N]
  double f_min = 0.0;          ///< Eq 15 [N] (<= 0)
  double mu = 0.0;             ///< Eq 24
  bool sliding = false;        ///< the committed step slid
};

/// A breached instability check (docs/dynamic.md "Instability detection"): the quantity, the step
/// at which the check saw it and a one-line message that names the likely cause.
class InstabilityError : public std::runtime_error {
 public:
  InstabilityError(const std::string& message, std::string quantity, std::int64_t step, double time)
      : std::runtime_error(message), quantity_(std::move(quantity)), step_(step), time_(time) {}
  const std::string& quantity() const { return quantity_; }
  std::int64_t step() const { return step_; }  ///< time / dt rounded (the plastic law: steps taken)
  double time() const { return time_; }

 private:
  std::string quantity_;
  std::int64_t step_;
  double time_;
};

/// The limits of the instability checks (docs/dynamic.md "Instability detection").
struct HealthLimits {
  /// overlap < 0.5 x the smaller radius of the contact (a wall contact: the particle's), >= 0.5 r_min
  static constexpr double kMaxOverlap = 0.5;
  static constexpr double kMaxDensity = 1.25;  ///< nu <= 1.25 (nu counts overlapping areas twice)
  static constexpr double kMaxTravel = 0.1;    ///< max|v| dt < 0.1 r_min
  static constexpr std::int64_t kLastGoodEvery = 1000;  ///< steps between refreshes of last_good()
};

template <int D>
class DynamicSolverT {
 public:
  static constexpr int kDim = D;
  static constexpr int kWalls = 2 * D;  ///< axis a: wall 2a at the minimum, 2a + 1 at the maximum
  using LudingHist = contact::LudingHistoryT<D>;
  using PlasticHist = contact::PlasticIndentationHistoryT<D>;
  using Stress = std::conditional_t<D == 2, Stress2, Stress3>;

  /// Restart: continues exactly (bit for bit) where the solver that produced `state` stopped.
  /// The state's params and dt (the plastic law: also its law and wall friction) are used; options
  /// give the model and the checks.
  DynamicSolverT(const SolverState& state, const DynamicOptions& options);
  /// The complete state at the current time (for state files and restarts).
  SolverState state() const;
  const DynamicOptions& options() const { return opt_; }
  /// Evaluates the forces again at the current positions on the committed histories (a state at
  /// rest whose forces are not those of a last step: a jammed state, jammed.hpp). With zero
  /// velocities no slip is committed; throws std::logic_error if a particle or wall moves.
  void refresh_forces();

  /// The Luding law (options.model: Linear, Hysteretic or Full) with its parameters. Validates,
  /// chooses the time step, builds the neighbour table, computes the first forces.
  DynamicSolverT(ParticlesT<D> particles, const LudingParams& params, const Box& box,
                 const DynamicOptions& options);
  /// The plastic-indentation law with its parameters `law` (options.model and options.plastic are
  /// set from it; the walls' friction is options.plastic_wall_mu). As above.
  DynamicSolverT(ParticlesT<D> particles, const contact::PlasticIndentationParams& law, const Box& box,
                 const DynamicOptions& options);
  /// The same two laws in a periodic cell (issue 29; docs/dynamic.md "Periodic cell"): no walls;
  /// the cell follows the strain rate of set_strain_rate() (h <- exp(L dt) h about cell.origin), the
  /// positions are advected with it and the velocities are the fluctuations about the affine field
  /// (the particles' vx, vy, vz); a pair interacts through the image n of j found at the table
  /// build (branch x_j + h n - x_i; positions unwrapped, so a pair keeps its image and its history
  /// when a particle crosses the boundary). box() is the cell's bounding box. The cell must stay
  /// at least 2 (2 r_max + skin) wide across every axis (else InstabilityError at a table build).
  DynamicSolverT(ParticlesT<D> particles, const LudingParams& params, const packing::PeriodicCellT<D>& cell,
                 const DynamicOptions& options);
  DynamicSolverT(ParticlesT<D> particles, const contact::PlasticIndentationParams& law,
                 const packing::PeriodicCellT<D>& cell, const DynamicOptions& options);
  /// A periodic cell (the constructors above).
  bool periodic() const { return periodic_; }
  /// Periodic cells only (issue 29): a general velocity gradient L (row a, column b: d v_a / d x_b),
  /// not necessarily symmetric: simple shear [[0, g], [0, 0]], a rigid spin. The cell follows
  /// h <- exp(L dt) h; the symmetric part is the strain rate (strain_rate_*), W = (L - L^T) / 2 the
  /// spin, the affine angular velocity of the particles (set_affine_velocities(), the affine drag
  /// on the spins). set_strain_rate() and set_strain_rate3() set a symmetric L (W = 0).
  void set_velocity_gradient(const Eigen::Matrix<double, D, D>& L);
  /// The Lees-Edwards re-mappings of the cell so far (docs/dynamic.md "Periodic cell"): at a table
  /// build a cell vector b is replaced by b - k a (k the nearest integer to b.a / a.a) when its
  /// projection on another vector a exceeds half of a's length, until no vector does.
  std::size_t cell_remaps() const { return cell_remaps_; }
  /// The periodic cell now (periodic() only; its h the initial one deformed by the strain so far).
  const packing::PeriodicCellT<D>& cell() const { return cell_; }
  /// The periodic packing of the current state: every centre wrapped into the cell, the radii, the
  /// '# periodic' flag and the cell ('# cell' when it is not a rectangle), seed 0 (periodic() only).
  packing::Packing periodic_packing() const;
  /// The kinetic part of the stress, (1/V) sum m u (x) u over the fluctuation velocities u
  /// (compression positive, as contact_stress(); periodic(): the velocities are the fluctuations,
  /// else the velocities themselves), reported apart from the contact stress.
  Stress kinetic_stress() const;

  /// One velocity-Verlet step (Eq 2, Eq 1). Every options.check_every steps it runs
  /// check_health() (the closing kick of that step also takes max|v|); throws InstabilityError
  /// on a breach, leaving the state of that step.
  void step();
  /// One step that does not pass the time t (> time()): of min(dt(), t - time()); dt() stays the
  /// rule's. A protocol that must end at t exactly (a strain to reach) takes its last step with it;
  /// the last good state is not refreshed by a shortened step (a state's dt is its time step).
  void step_to(double t);
  /// The instability checks on the current state: finite, box extents positive, centres inside
  /// the box, every overlap < 0.5 min(a_i, a_j) (>= 0.5 r_min), nu <= 1.25, max|v| dt < 0.1 r_min. Throws
  /// InstabilityError (one line: quantity, step, likely cause). O(N + pairs).
  void check_health() const;
  /// The last state that passed check_health() in step(), refreshed at most every
  /// HealthLimits::kLastGoodEvery steps and held in memory (the state at the first step before
  /// any check); nullptr before the first step.
  const SolverState* last_good() const { return last_good_.get(); }
  void run(std::size_t n_steps);  ///< n_steps steps

  const ParticlesT<D>& particles() const { return P_; }
  const Box& box() const { return box_; }
  const TimeStepInfo& time_step() const { return ts_; }
  double dt() const { return ts_.dt; }
  double time() const { return time_; }
  std::size_t rebuilds() const { return rebuilds_; }  ///< neighbour-table builds so far
  std::size_t table_size() const { return rows_.pairs(); }
  /// Heap bytes held (vector capacities): the per-particle arrays (wall histories included), the
  /// per-row arrays (pair histories, a table build's scratch histories, the threads' slots)
  /// and the neighbour search's scratch. A kept last_good() state is not counted.
  struct MemoryUse { std::size_t particles = 0, rows = 0, search = 0; };
  MemoryUse memory_use() const;
  /// Threads the last force evaluation's pair loop ran on (1 below its thresholds; DynamicOptions::threads).
  int threads_used() const { return threads_used_; }
  /// Material thermal state (ContactModel::Full); the temperature schedule is the caller's.
  const contact::LudingThermalState& thermal() const { return thermal_; }
  /// Moves the material to temperature T_new over the time dt with relaxation time t0
  /// (k1(T, t) by Eq 11-12 and the freezing rule, luding_advance_thermal) and rescales the radii
  /// by Eq 9 (constant mass, I = m a^2 / 2). Call it between steps, once per step of a schedule;
  /// a constant T with a converged k1(T, t) costs nothing.
  void advance_temperature(double T_new, double dt, double t0);
  /// Changes the contact parameters between steps (e.g. friction on at t_heat); the time step is
  /// kept. The feature set of the force loop (friction or not) is chosen again.
  void set_params(const LudingParams& params);
  const LudingParams& params() const { return params_; }
  /// ContactModel::PlasticIndentation: changes the law between steps and chooses the time step
  /// again (its normal bound depends on the unloading branch). Switching the section 3.4 elastic
  /// branch on (reversible -> elastic, as netsolve's set_reversible_normal) starts every contact's
  /// branch at its current overlap (PlasticIndentationLaw::start_unloading_branch: no force jump).
  void set_plastic_law(const contact::PlasticIndentationParams& law);
  const contact::PlasticIndentationParams& plastic_law() const { return opt_.plastic; }
  /// Changes the control of the right and top walls (mode, velocity, pressure) between steps; a
  /// strain-controlled wall takes its velocity at once, a stress-controlled one keeps its own.
  void set_walls(const MovingWall& right, const MovingWall& top);
  /// 3D: the right (x_max), back (y_max) and top (z_max) walls.
  void set_walls(const MovingWall& right, const MovingWall& back, const MovingWall& top);
  /// Velocities of the right and top walls [m/s].
  double wall_velocity_right() const { return wall_v_[0]; }
  double wall_velocity_top() const { return wall_v_[D - 1]; }
  /// Velocity of the moving wall of axis a (its maximum) [m/s].
  double wall_velocity(int axis) const { return wall_v_[axis]; }
  /// Sets the gravity vector [m/s^2] between steps.
  void set_gravity(double gx, double gy);
  void set_gravity(double gx, double gy, double gz);
  /// The macroscopic strain rate E' = diag(e11, e22) (no shear) about the box's lower-left corner
  /// x_0: prescribed particles follow it, Affine walls follow it, the affine drag acts relative to
  /// it. Over a step of length dt the affine motion is exactly x_0 + exp(E' dt)(x - x_0).
  ///
  /// With e12 != 0 (a symmetric shear rate, netsolve's E12; only without contact walls) the affine
  /// map is x_0 + exp(L dt)(x - x_0), L = [[e11, e12], [e12, e22]]; the box then stays the
  /// axis-aligned rectangle of the diagonal rates (its area, and so density() and the stresses' V,
  /// is exactly the deformed domain's, det exp(L t) = exp(tr L t)), and box_deformation() holds the
  /// accumulated map, whose parallelogram is the deformed domain.
  void set_strain_rate(double e11, double e22, double e12 = 0.0);
  /// 3D: the symmetric strain rate L = E' (e11, e22, e33 on the diagonal; e23, e13, e12 the shear
  /// rates, 0 by default) about the box's lower corner x_0 = (x_min, y_min, z_min): prescribed
  /// particles, Affine walls and the affine drag follow it, over a step exactly x_0 + exp(L dt)(x -
  /// x_0) (exp(L dt) - I = V diag(expm1(lambda dt)) V^T from the eigen-decomposition of L, no
  /// cancellation for small rates; diagonal L: expm1 of each rate, as before the shear rates came).
  /// Shear rates only without contact walls (std::invalid_argument: the walls stay axis-aligned).
  /// The box stays the axis-aligned box of the diagonal rates: its volume, and so density() and the
  /// stresses' V, is exactly the deformed domain's (det exp(L t) = exp(tr L t)); affine_map3()
  /// holds the accumulated map, whose parallelepiped is the deformed domain.
  void set_strain_rate3(double e11, double e22, double e33, double e23 = 0.0, double e13 = 0.0, double e12 = 0.0);
  /// 3D: the accumulated stretch of the box, exp(L_aa t) along each axis (the diagonal of
  /// affine_map3() when no shear rate was ever set).
  const std::array<double, 3>& box_deformation3() const { return F3_; }
  /// 3D: the accumulated affine map F (row-major, 9 entries) since construction: x_0 + F (X - x_0).
  const std::array<double, 9>& affine_map3() const { return F3m_; }
  /// 3D: the component (a, b) of the strain rate L (symmetric; a, b in 0..2).
  double strain_rate3(int a, int b) const { return L3_[a][b]; }
  double strain_rate_11() const { return edot_[0]; }
  double strain_rate_22() const { return edot_[1]; }
  double strain_rate_12() const { return edot_[2]; }
  /// The accumulated affine map F (row-major f11, f12, f21, f22) since construction: x_0 + F (X - x_0).
  const std::array<double, 4>& box_deformation() const { return F_; }
  /// Adds dL (x - x_0) to the velocity of every particle that is not prescribed (x_0 the box's
  /// lower corner; dL symmetric): after a change dL of the strain rate between steps the motion
  /// relative to the new affine field is the motion relative to the old one. Nothing in a periodic
  /// cell, whose velocities are the fluctuations already.
  void shift_affine_velocities(const Eigen::Matrix<double, D, D>& dL);
  /// Changes DynamicOptions::affine_drag between steps (e.g. a drag that relaxes a held state).
  void set_affine_drag(double drag);
  double affine_drag() const { return opt_.affine_drag; }
  /// The RMS over the free degrees of freedom of the contact force on each particle that is not
  /// prescribed (the force of the last evaluation without the affine drag) and of the torque / radius
  /// of every free spin (prescribed centres with free spins included): the equilibrium residual of a
  /// held state (netsolve's Newton residual in the same units).
  double unbalanced_force_rms() const;
  /// Sets every particle's velocity to the affine field E' (x - x_0) and its spin to 0.
  void set_affine_velocities();
  /// The particles whose centres follow the affine motion exactly (their rotations are held): the
  /// kinematic boundary layer of a compaction (netsolve's die mode) or every particle (affine mode).
  /// With hold_spins = false only the centres are prescribed and their spins stay free (netsolve's
  /// affine mode: every centre affine, the rotations unknowns). In a periodic cell the cell carries
  /// the affine motion and the velocities are the fluctuations: a prescribed particle's is held at
  /// zero from this call on (its centre follows the cell exactly; affine probing of a periodic
  /// state), a held spin at the cell's spin, and a free spin's affine drag acts relative to it.
  void set_prescribed(const std::vector<std::uint32_t>& particles, bool hold_spins = true);
  /// Holds the spins of these prescribed particles as well (after set_prescribed(..., false)): e.g.
  /// netsolve's and Redanz & Fleck's affine mode, every centre prescribed and the peripheral layer's
  /// rotations prevented (section 2.4: "In both cases, the rotation of particles in the peripheral
  /// layer is prevented").
  void hold_spins(const std::vector<std::uint32_t>& particles);
  const std::vector<std::uint32_t>& prescribed() const { return prescribed_; }
  /// false: every spin is held at zero (netsolve's --no-rotation); true (default): free, except the
  /// spins set_prescribed holds.
  void set_rotations(bool free);
  /// The stress from the contact forces on the prescribed particles (their reactions, Redanz & Fleck
  /// Eq 13), about the box centre: Sigma = (1/V) sum_p f_p (x) (x_p - x_c), compression positive.
  Stress boundary_stress() const;
  /// Number of particle-wall contacts (overlap > 0) at the current positions.
  std::size_t wall_contacts() const;
  /// All touching contacts (pairs, then walls) with their forces: the law evaluated on the
  /// committed histories with a zero slip increment (the tangential spring force of the last step)
  /// and the current normal approach rate.
  void contacts(std::vector<ContactInfo>& out) const;

  /// Pairs (i < j) of the table that currently overlap, sorted.
  void touching_pairs(std::vector<std::pair<std::uint32_t, std::uint32_t>>& out) const;
  /// Committed contact history of pair (i < j); nullptr if the pair is not in the table.
  const LudingHist* history(std::uint32_t i, std::uint32_t j) const;
  /// The same for ContactModel::PlasticIndentation.
  const PlasticHist* plastic_history(std::uint32_t i, std::uint32_t j) const;

  double wall_force_right() const { return wall_force_[1]; }  ///< contacts on right wall, +x [N]
  double wall_force_top() const { return wall_force_[2 * D - 1]; }  ///< contacts on top wall, +y (3D: +z) [N]
  /// The force of the contacts on wall w (0 .. 2D - 1) along its axis [N].
  double wall_force(int w) const { return wall_force_[w]; }
  /// Wall stresses F_right / height and F_top / width [N/m] (3D: the three moving walls' forces
  /// over their areas on the diagonal [N/m^2]).
  Stress wall_stress() const;
  /// Contact-network stress Sigma = (1/V) sum_c f_c (x) l_c at the last force evaluation: pairs
  /// with l = x_j - x_i and f on j, wall contacts with l = particle centre - contact point.
  Stress contact_stress() const;
  /// Density nu = sum pi a_i^2 / box area (3D: sum 4/3 pi a_i^3 / box volume).
  double density() const;
  Energies energies() const;

 private:
  template <contact::LudingFeatures F>
  void compute_forces_with();
  double box_measure() const;  ///< area (2D) or volume (3D) of the box
  const MovingWall& moving_wall(int axis) const {
    return axis == 0 ? box_.right : (axis == D - 1 ? box_.top : box_.back);
  }
  template <class L, bool InPlace>
  void compute_forces();
  /// The sums of a force evaluation (stress about the contacts, elastic energy, largest normal
  /// force, the walls' forces), filled by the loops below.
  struct ForceSums {
    double sxx = 0, sxy = 0, syx = 0, syy = 0, el = 0, fn_max = 0;
    double s3[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
    double wf[6] = {0, 0, 0, 0, 0, 0};
  };
  template <class L, bool InPlace, bool Periodic>
  void pair_forces(const L& pair_law, ForceSums& a);  ///< on opt_.threads threads (solver_threads.hpp)
  /// Rows [k0, k1); Threaded: a boundary particle's shares to its slots (solver_pairs_{2,3}d.hpp)
  template <class L, bool InPlace, bool Periodic, bool Threaded>
  void pair_forces_3d(const L& pair_law, ForceSums& a, std::size_t k0, std::size_t k1);
  template <class L, bool InPlace, bool Periodic, bool Threaded>
  void pair_forces_2d(const L& pair_law, ForceSums& a, std::size_t k0, std::size_t k1);
  template <bool Periodic>
  void add_group_sums(ForceSums& a) const;  ///< (solver_threads.hpp)
  void pair_stress_3d(ForceSums& a) const;  ///< adds sum_i F_i (x) x_i to a.s3 (pst_sums_'s groups)
  void particle_stress_groups(std::size_t g0, std::size_t g1);  ///< (filled by pair_forces)
  std::size_t sum_groups() const { return (P_.size() + kSumGroup - 1) / kSumGroup; }
  void fill_absolute_velocities(const double (&Lr)[3][3]);
  template <class L, bool InPlace>
  void wall_forces_2d(const L& wall_law, ForceSums& a);
  template <class L, bool InPlace>
  void wall_forces_3d(const L& wall_law, ForceSums& a);
  /// The contact histories of one law: one per row of the Verlet table (rows_), the scratch of a
  /// table build, kWalls per particle for the walls (x_min, x_max, y_min, ...).
  template <class H>
  struct HistoryTable {
    std::vector<H> pair, next, wall;  ///< (next: the scratch of a table build)
  };
  /// One history table per law, chosen at construction (the law's history type); a force
  /// evaluation takes its table once (std::get), not per contact. One alternative per law of DemLaws.
  using HistoryTables = DemLaws::OfDim<HistoryTable, D>;
  template <class H>
  HistoryTable<H>& table() { return *std::get_if<HistoryTable<H>>(&hist_); }  ///< (the law's: by construction)
  template <class H>
  const HistoryTable<H>* table_if() const { return std::get_if<HistoryTable<H>>(&hist_); }
  /// f(law) with the solver's law object (the Luding law with the full feature set: every feature
  /// set has the same history, lifecycle and bound): the table's lifecycle (has_history), the time
  /// step's bound, the table of a new solver. The one choice of law besides the force loop's
  /// dispatch (compute_forces_dispatch) and the output of contacts().
  template <class F>
  decltype(auto) visit_law(F&& f) const {
    if (plastic()) return f(contact::PlasticIndentationLawT<D>(opt_.plastic));
    return f(contact::LudingLaw<contact::kLudingFull, D>(params_, thermal_.k1_Tt));
  }
  /// the constructors' common part: the law is in options.model; cell: a periodic cell or none
  struct Setup {
    const packing::PeriodicCellT<D>* cell = nullptr;
  };
  DynamicSolverT(ParticlesT<D> particles, const LudingParams& params, const Box& box, const DynamicOptions& options,
                 Setup);
  /// A new table of the law's history type, with fresh wall histories for n particles.
  void make_tables(std::size_t n);
  template <class Law>
  void carry_histories(const Law& law);
  bool plastic() const { return opt_.model == ContactModel::PlasticIndentation; }
  /// A law whose tangential bound grows with the contact area: the time step follows the largest
  /// area of the last force evaluation (StiffnessBound::k_t_area, with 10 % margin).
  void update_time_step();
  /// The step after the time step's update (step, step_to); `full`: a step of the rule's length.
  void advance(bool full);
  /// bound_, mean_pair_ and ts_ from the law's a-priori bound (choose_time_step) with options o.
  void choose_time_step_of_law(const DynamicOptions& o, double area);
  void compute_forces_dispatch();
  void choose_friction();
  void finish_setup();
  void build_table();
  void build_wall_list();
  bool walls_moved() const;
  bool needs_rebuild() const;
  [[noreturn]] void breach(const std::string& quantity, const std::string& what, const std::string& cause) const;
  void check_health_with(double vmax2) const;

  ParticlesT<D> P_;
  LudingParams params_, wall_params_;
  Box box_;
  DynamicOptions opt_;
  TimeStepInfo ts_;
  contact::LudingThermalState thermal_;
  double time_ = 0.0, skin_ = 0.0;
  std::int64_t steps_taken_ = 0;  ///< steps since construction or restore (the plastic law's dt varies)
  std::size_t rebuilds_ = 0;
  bool friction_ = true;             ///< any friction (particles or walls): F.friction instantiation
  std::vector<double> radius_ref_;   ///< radii at T_radius_ref (Eq 9)
  double radius_scale_ = 1.0, radius_scale_build_ = 1.0, radius_ref_max_ = 0.0;
  // Verlet table: the system layer's rows (pairs i < j sorted by (i, j), the periodic image of j
  // per row, the neighbour search); the histories per row are hist_'s, carried by rows_.carry().
  sys::PairRows<D> rows_;
  // periodic cell (issue 29): the cell now, the map since the last table build (the table's
  // affine stretch)
  bool periodic_ = false;
  packing::PeriodicCellT<D> cell_;
  Eigen::Matrix<double, D, D> F_build_ = Eigen::Matrix<double, D, D>::Identity();
  double range_max_ = 0.0;  ///< 2 r_max + skin at the last build
  double W_[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};  ///< the spin of set_velocity_gradient (zeros beyond D)
  bool spun_ = false;                                     ///< W_ != 0
  std::size_t cell_remaps_ = 0;
  void reduce_cell();                   ///< the Lees-Edwards re-mapping (cell_remaps())
  void impose_general_motion(double dt);  ///< periodic with a spin: x <- x + (exp(L dt) - I)(x - origin)
  /// Component k of the particles' affine angular velocity: W as a rotation rate (2D: W_21; 3D: the
  /// axial vector (W_32, W_13, W_21)); zero without a spin.
  double affine_spin(int k) const {
    if constexpr (D == 2) return W_[1][0];
    return k == 0 ? W_[2][1] : k == 1 ? W_[0][2] : W_[1][0];
  }
  /// Component (a, b) of the velocity gradient: the strain rate plus the spin.
  double velocity_gradient(int a, int b) const {
    return (D == 2 ? (a == b ? edot_[a] : edot_[2]) : L3_[a][b]) + W_[a][b];
  }
  void build_table_periodic();
  void advect_periodic(const Eigen::Matrix<double, D, D>& G);  ///< x <- x + G (x - origin), h <- (I + G) h
  void remove_mean_velocity();
  void set_box_to_cell();  ///< box_ = the cell's bounding box
  void hoist_cell(double (&hc)[3][3], double (&Lr)[3][3]) const;  ///< h and L as 3 x 3 (the force loop)
  /// The branch x_j (+ h n) - x_i of table row k (D components).
  void branch(std::size_t k, std::size_t i, std::size_t j, double* d) const {
    for (int a = 0; a < D; ++a) d[a] = P_.pos[D * j + a] - P_.pos[D * i + a];
    if (periodic_) {
      const int* n = rows_.shift[k].data();
      for (int a = 0; a < D; ++a)
        for (int b = 0; b < D; ++b) d[a] += cell_.h(a, b) * n[b];
    }
  }
  HistoryTables hist_;  ///< the law's histories of the pairs (one per row of rows_) and of the walls
  // ContactModel::PlasticIndentation: the walls' law
  contact::PlasticIndentationParams pl_wall_params_;
  double area_max_ = 0.0;  ///< largest contact width of the last force evaluation (kHasContactArea)
  double m12_ = 0.0;       ///< effective mass of the two lightest particles
  double m_rule_ = 0.0;    ///< effective mass of the time step rule's pair (choose_time_step)
  contact::StiffnessBound bound_;  ///< the law's a-priori stiffness bound (the time step)
  bool mean_pair_ = false;         ///< the law's time step may take the mean pair (kMeanPairTimeStep)
  // macroscopic strain rate, prescribed particles
  double edot_[3] = {0.0, 0.0, 0.0};  ///< e11, e22, e12
  std::array<double, 4> F_ = {1.0, 0.0, 0.0, 1.0};
  double edot3_[3] = {0.0, 0.0, 0.0};  ///< 3D: e11, e22, e33
  std::array<double, 3> F3_ = {1.0, 1.0, 1.0};
  // 3D shear rates (set_strain_rate3): the full L, its eigen-decomposition (V row-major, lambda),
  // the accumulated map; sheared3_: a shear rate was ever set (boundary_stress about x_0 + F (c_0 - x_0))
  double L3_[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
  bool shear3_ = false;  ///< the current L has a shear rate
  double eig_v3_[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, eig_l3_[3] = {0, 0, 0};
  std::array<double, 9> F3m_ = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  bool sheared3_ = false;
  double centre0z_ = 0.0;  ///< 3D: the z of the box centre at construction (x, y: centre0_)
  bool sheared_ = false;  ///< e12 was ever non-zero (boundary_stress takes the parallelogram's centre)
  double centre0_[2] = {0.0, 0.0};  ///< the box centre at construction
  std::vector<std::uint32_t> prescribed_;
  std::vector<std::uint8_t> is_prescribed_;
  std::vector<std::uint8_t> spin_held_;  ///< per particle: a prescribed centre whose spin is held
  bool rotations_ = true;
  bool walls_active() const { return box_.enabled && box_.contact_walls; }
  void impose_affine_motion(double dt);
  /// periodic: the prescribed particles' velocities zero, their held spins the cell's spin
  void hold_prescribed_fluctuations();
  void apply_affine_drag();
  void affine_velocity3(std::size_t i, double* a) const;  ///< 3D: L (x_i - x_0)
  /// pair_live_[k] == 0: the pair history k is fresh, so a separated pair needs no history access
  /// (set at a table build; refilled with 1 if its size differs from the table's).
  std::vector<std::uint8_t> pair_live_;
  /// The pair loop's stress and energy sums per group of kSumGroup particles (kGroupSums each: 2D
  /// sxx, sxy, syx, syy, energy; 3D energy, the periodic f (x) h n), added in group order
  /// (solver_threads.hpp). Threads: the boundary particles' slots (built after each table build:
  /// rows_csr_ok_) and their shares.
  static constexpr std::size_t kSumGroup = 1024, kGroupSums = 10;
  std::vector<double> grp_sums_, slot_buf_, pst_sums_;  ///< (pst_sums_: pair_stress_3d's groups)
  std::vector<int> row_start_, row_slot_;
  /// The threads' blocks: particles [blk_p_[t], blk_p_[t + 1]) and their rows [blk_k_[t], blk_k_[t + 1]);
  /// the boundary particles (a row of another block reaches them) of block t: bnd_list_[bnd_off_[t] ..
  /// bnd_off_[t + 1]), with their slots from row_start_ (for blk_threads_ threads)
  std::vector<std::size_t> blk_p_, blk_k_;
  std::vector<int> bnd_list_, bnd_off_;
  int blk_threads_ = 0;
  bool rows_csr_ok_ = false;
  int threads_used_ = 1;
  sys::TeamHandle team_;  ///< the threads (made at the first threaded step; a copy of the solver has none)
  std::vector<double> vel_abs_;  ///< periodic 3D force loop: v_i + L x_i (D per particle), per evaluation
  std::vector<double> pos_build_;  ///< D per particle: the centres at the last table build
  /// Bit w of wall_touch_[i]: the wall history kWalls i + w may be non-fresh (touching at the last force
  /// evaluation). A table build sets all four bits of the wall candidates and resets the wall
  /// histories of the other particles. Particles with no bit and no overlap are skipped by the
  /// wall loop (their histories are already fresh).
  std::vector<std::uint8_t> wall_touch_;
  /// Particles within a_i + skin of a wall at the last table build (ascending); with the walls
  /// within skin/2 of box_build_ (else a rebuild) no other particle can touch a wall.
  std::vector<std::uint32_t> wall_list_;
  double box_build_[2 * D] = {};  ///< x_min, x_max, y_min, y_max (, z_min, z_max) at the build
  bool wall_list_valid_ = false;
  /// 1/m (D per particle) and 1/I (kRot per particle) for the kicks, refilled by step() when the
  /// particle count or radius_scale_ (the only thing that changes the inertia, Eq 9) differs from
  /// the values they were computed for.
  std::vector<double> inv_mass_, inv_inertia_;
  double inv_scale_ = -1.0;
  /// step() set the force accumulators to m g in its first pass (compute_forces skips its own)
  bool forces_initialised_ = false;
  double wall_force_[2 * D] = {};
  double wall_v_[D] = {};  ///< velocities of the moving walls: right, top (3D: right, back, top)
  double sxx_ = 0, sxy_ = 0, syx_ = 0, syy_ = 0, elastic_ = 0;
  double s3_[3][3] = {};  ///< 3D: sum f (x) l
  // instability checks
  std::int64_t since_check_ = 0, since_good_ = 0;
  std::shared_ptr<const SolverState> last_good_;
};

using DynamicSolver = DynamicSolverT<2>;
using DynamicSolver3 = DynamicSolverT<3>;
extern template class DynamicSolverT<2>;
extern template class DynamicSolverT<3>;

}  // namespace netdem::dem
