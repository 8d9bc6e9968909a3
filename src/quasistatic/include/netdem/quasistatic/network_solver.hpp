#pragma once
// Quasi-static implicit network solver (Redanz & Fleck, Acta Mater. 49 (2001) 4325, sections 2.3-2.4).
//
// Each particle is a node with Dim<D>::kNodeDofs DOFs ((u1, u2, theta) for disks, (u1, u2, u3) and
// a rotation vector for spheres); each contact an element of the contact law from src/contact
// (6x6 or 12x12, contact/element.hpp). The dimension and the law are the template parameters of
// NetworkSolverT<D, Law> (NetworkSolver = NetworkSolverT<2>, the plastic-indentation law, used by
// the tools; NetworkSolver3 = NetworkSolverT<3>; NetworkSolverLinear(3): the linear spring).
// The state file and the measures of StateMeasures (strain, Figs 7-8 deviations) are 2D only for
// now; stress() gives the Eq 13 and contact stresses in both. Every load increment prescribes Delta u = (exp(Delta E) - I) x (Eqs 14-15, current
// coordinates) on the prescribed particles (the peripheral layer in die mode, every centre in
// affine mode; peripheral rotations are always held), then finds the free DOFs by Newton
// iterations on the equilibrium equations (Eq 10-12). The trial state is always recomputed from
// the committed contact history plus the whole increment (return mapping) and committed only when
// the increment ends. Legacy drag (the default): if Newton does not reach the tolerance within
// max_newton iterations the increment is accepted anyway and its residual is carried into the next
// increment (forward Euler with equilibrium correction); the residual norm is reported per
// increment. Pseudo-transient iteration (Iteration::PseudoTransient, solver_options.hpp): the drag
// acts on each Newton step only, the increment is accepted on the undragged residual, and an
// unaccepted increment is cut in halves (max_cuts) before it is reported unconverged. With chord_steps > 0
// an assembled tangent and its factorisation serve several iterations (modified Newton).
//
// Linear algebra: the global tangent K is assembled into a fixed sparsity pattern built from the
// neighbour list (pairs with gap < skin, non-touching ones stored as explicit zeros), analysed by
// CHOLMOD only when that list is rebuilt and refactorised otherwise. Frictionless runs are
// symmetric (direct solve). With friction the consistent tangent of sliding contacts is
// non-symmetric (dF_T = mu_eff k_N du_N): it is solved by GMRES preconditioned with the CHOLMOD
// factor of the symmetric slip-status tangent M (sliding contacts keep only a small fraction of
// their tangential stiffness in M), see docs/quasistatic.md.
//
// Singular modes (rattlers, rotations of particles without tangential stiffness, rolling modes of
// particles with a single contact) are removed by a tiny diagonal regularisation of the matrix
// only (it changes the Newton path, never the equilibrium being solved), and Newton steps are
// limited in size. A genuinely indefinite tangent (localisation) is reported as an error.
//
// The committed state (NetworkState) can be taken, copied, saved to a file and restored: a solver
// restored from a state continues bit-identically to the solver it was taken from.
//
// Where the parts live: src/quasistatic/solver_impl.hpp.
#include <array>
#include <cstdint>
#include <istream>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include <Eigen/Core>

#include "netdem/contact/dim.hpp"
#include "netdem/contact/luding_law.hpp"
#include "netdem/contact/plastic_indentation.hpp"
#include "netdem/packing/packing.hpp"
#include "netdem/packing/periodic.hpp"
#include "netdem/quasistatic/solver_options.hpp"
#include "netdem/system/jammed_state.hpp"
#include "netdem/system/particle_set.hpp"

namespace netdem::qs {

/// Thrown by NetworkSolver::increment when the Newton iteration produces non-finite contact forces
/// (a diverged iteration; the increment is not committed). Apps report it as an unstable run.
struct DivergedError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// What one increment did.
struct IncrementReport {
  int newton_iterations = 0;
  bool converged = false;
  double residual = 0.0;        ///< out-of-balance contact force on the free DOFs / mean normal contact force
  double residual_rms = 0.0;    ///< root mean square of the same over the free DOFs
  double newton_residual = 0.0; ///< RMS Newton residual (contact force - viscous drag) / mean contact force
  int linear_iterations = 0;    ///< GMRES iterations summed over the Newton iterations
  bool reanalysed = false;
  int new_contacts = 0, lost_contacts = 0, sliding = 0;
  /// Sub-increments the increment was cut into (1: not cut) after an unaccepted attempt.
  int substeps = 1;
  /// Sub-increments committed without being accepted (at the finest cut, max_cuts; an uncut
  /// increment that is not accepted counts 1). A cut increment is accepted when its last
  /// sub-increment is: its end state is an equilibrium by the criterion, and the unaccepted
  /// sub-increments before it are the damped path through an instability (instability is set;
  /// their drag work is in drag_work). docs/quasistatic.md "Cut increments".
  int unconverged_substeps = 0;
  /// Instability event (pseudo-transient iteration): the undragged residual rose between two
  /// fresh iterations, so the pseudo-time step had to damp the path (drag above its start value).
  bool instability = false;
  /// Energy merit: accepted as unjammed, i.e. with a mean contact force below the force of a contact
  /// at the law's first-touch overlap (R* = r_mean/2), against which the residual was then measured:
  /// no load-bearing network (docs/quasistatic.md "Frictionless: a trust region on the energy").
  bool unjammed = false;
  /// Work of the regularising drag along the iteration path (its dissipation) and the work of
  /// the contact forces over the increment (trapezoidal in the start and end forces): the path's
  /// dissipated energy is reported as drag_work / contact_work.
  double drag_work = 0.0, contact_work = 0.0;
};

/// The energy the iteration path dissipated in the drag, as a fraction of the work of the contact
/// forces over the increment (0 when the contacts did no work).
inline double drag_work_fraction(const IncrementReport& r) {
  return r.contact_work > 0.0 ? r.drag_work / r.contact_work : 0.0;
}

/// Macroscopic and microscopic measures of the committed state.
struct StateMeasures {
  double E11 = 0, E22 = 0, E12 = 0;  ///< accumulated strain E = integral of Edot
  double density = 0;                ///< D = solid area / current box area
  /// Symmetric part of Eq 13 (tension positive), lever arms from the centre of the current box:
  /// origin-free although the reactions need not sum to zero (docs/quasistatic.md)
  double S11 = 0, S22 = 0, S12 = 0;
  double S_asym = 0;                 ///< (S12 - S21)/2
  double S11_contacts = 0, S22_contacts = 0, S12_contacts = 0;  ///< Love-Weber average over contacts
  /// |sum of the reactions| / sum of |reaction| over the prescribed particles (0 without forces):
  /// the net force the drag and the residual hold on the free particles
  double net_force_ratio = 0;
  /// |S - S_contacts| / |S_contacts| (symmetric parts, Frobenius norms): how far from equilibrium
  double eq13_vs_contacts = 0;
  double Z = 0;                      ///< 2 x load-bearing contacts / N
  int contacts = 0, sliding = 0;
  /// Rattlers: particles left out when every particle with fewer than D + 1 load-bearing contacts
  /// (walls included) is removed, recursively (sys::prune_rattlers); Z_backbone = 2 x contacts
  /// among the others / their number.
  int rattlers = 0;
  double Z_backbone = 0;
  double mean_normal_force = 0;
  /// The fabric <n (x) n> over the load-bearing contacts (trace 1; 0 without any), issue 30
  double fabric11 = 0, fabric22 = 0, fabric12 = 0;
  // Fig 7 / Fig 8 affine-deviation measures (section 3.3)
  double dev_normal_mean_ratio = 0;  ///< < |u_N - u_N^A| / u_N^A >
  double dev_normal_ratio_of_means = 0;  ///< < |u_N - u_N^A| > / < u_N^A >
  double dev_tangential_centres = 0;     ///< < |u_T - u_T^A| > / < u_N^A >, u_T from the centres only
  double dev_tangential_rotations = 0;   ///< same with the rotations of Eq 5
  double affine_tangential = 0;          ///< < |u_T^A| > / < u_N^A >
};

struct SolverTimings {
  double assemble = 0, analyse = 0, factorise = 0, solve = 0, neighbours = 0, total = 0;
  long analyses = 0, factorisations = 0, solves = 0, increments = 0, newton_iterations = 0;
};

/// Read-only view of one contact of the committed state (for output).
struct ContactView {
  int i, j;
  double f_n, f_t, overlap;
  bool sliding;
  double l[3] = {0, 0, 0};  ///< the branch vector from i to j (to j's image in a periodic cell)
};

/// The Eq 13 and Love-Weber stresses of the committed state in dimension D (tension positive):
/// the symmetric parts, and what tells how far from equilibrium they are.
template <int D>
struct StressMeasuresT {
  using Mat = Eigen::Matrix<double, D, D>;
  Mat strain = Mat::Zero();      ///< accumulated E
  double density = 0;            ///< solid measure / current box measure
  Mat eq13 = Mat::Zero();        ///< symmetric part of Eq 13 (reactions of the prescribed particles)
  Mat contacts = Mat::Zero();    ///< symmetric part of the Love-Weber average over the contacts
  double eq13_vs_contacts = 0;   ///< |eq13 - contacts| / |contacts| (Frobenius)
  double net_force_ratio = 0;    ///< |sum of the reactions| / sum of |reaction|
  int contact_count = 0, sliding = 0;
  double Z = 0;                  ///< 2 x load-bearing contacts / N (before any load: touching pairs)
  double mean_normal_force = 0;
  /// <n (x) n> over the load-bearing contacts (trace 1; zero without any): the fabric
  Mat fabric = Mat::Zero();
  /// Rattlers (sys::prune_rattlers, fewer than D + 1 load-bearing contacts, recursively) and the
  /// backbone's 2 x contacts / particles, as StateMeasures.
  int rattlers = 0;
  double Z_backbone = 0;
};

/// Affine-deviation bookkeeping of one contact (section 3.3, Figs 7-8). In 3D only E_form is kept
/// (the Figs 7-8 measures are 2D).
template <int D>
struct PairAuxT {
  Eigen::Matrix<double, D, D> E_form = Eigen::Matrix<double, D, D>::Zero();  ///< accumulated strain when the contact formed
  double slip = 0.0;    ///< accumulated slip with rotations (Eq 5)
  double centre = 0.0;  ///< accumulated tangential displacement of the centres (L dphi)
};
using PairAux = PairAuxT<2>;

/// Everything a solver in dimension D needs to continue a run (the 3D layout; the 2D one below
/// keeps the fields of the 2D state file): the particles, the contact table with its committed
/// history, the committed forces and the predictor of the next increment. Plain data.
template <int D, class History = contact::PlasticIndentationHistoryT<D>>
struct NetworkStateT {
  using Mat = Eigen::Matrix<double, D, D>;
  using Tan = typename contact::Dim<D>::Tan;
  sys::ParticleSet<D> particles;
  std::vector<std::uint8_t> peripheral;
  double solid_area = 0, initial_density = 0, box_area0 = 0;  ///< 3D: volumes
  packing::Box box0;
  std::uint64_t seed = 0;
  Mat box_deformation = Mat::Identity();
  Mat strain = Mat::Zero();
  std::vector<int> pair_i, pair_j;
  std::vector<History> history;
  std::vector<PairAuxT<D>> aux;
  std::vector<double> f_n;
  std::vector<Tan> f_t;
  std::vector<std::uint8_t> sliding;
  std::vector<double> pos_build;  ///< D per particle: the centres at the last neighbour rebuild
  Mat box_deformation_build = Mat::Identity();
  std::vector<double> f_contact;  ///< kNodeDofs per particle
  std::vector<double> du_prev;
  Mat dE_prev = Mat::Zero();
  SolverTimings timings;
  std::vector<History> wall_history;  ///< BoundaryMode::Walls: 2D per particle (walls.cpp's slots); else empty
  std::vector<double> wall_f_n;
  /// BoundaryMode::Periodic (issue 29): the packing's cell vectors (packing::Packing::cell; empty:
  /// the box's edges), each row's image of j (empty in other modes), the particle whose
  /// translation is held (3D: no state file yet).
  bool periodic = false;
  std::vector<double> cell;
  std::vector<std::array<int, D>> shift;
  int pinned = -1;

  /// Throws std::invalid_argument (one line) if sizes or values are inconsistent.
  void validate() const;
};

/// The 2D state of the plastic-indentation law: the fields of the 2D state file (save_state,
/// load_state).
/// Everything a solver needs to continue a run: the particles, the contact table with its
/// committed history, the committed forces and the predictor of the next increment. Plain data:
/// copy it, save it (save_state), restore it (NetworkSolver(state, options)).
template <>
struct NetworkStateT<2, contact::PlasticIndentationHistory> {
  std::vector<double> x, y, theta, r;
  std::vector<std::uint8_t> peripheral;
  double solid_area = 0, initial_density = 0, box_area0 = 0;
  packing::Box box0;       ///< the packing's box (box_deformation maps it to the current one)
  std::uint64_t seed = 0;  ///< the packing's seed (0 if unknown)
  Eigen::Matrix2d box_deformation = Eigen::Matrix2d::Identity();  ///< initial box -> current box
  Eigen::Matrix2d strain = Eigen::Matrix2d::Zero();               ///< accumulated E
  // contact table (pairs i < j sorted) and its committed history
  std::vector<int> pair_i, pair_j;
  std::vector<contact::PlasticIndentationHistory> history;
  std::vector<PairAux> aux;
  std::vector<double> f_n, f_t;
  std::vector<std::uint8_t> sliding;
  std::vector<double> x_build, y_build;  ///< positions at the last neighbour rebuild
  Eigen::Matrix2d box_deformation_build = Eigen::Matrix2d::Identity();
  std::vector<double> f_contact;  ///< 3 per particle: committed contact forces (Eq 13 reactions)
  std::vector<double> du_prev;    ///< 3 per particle: the last increment (predictor); empty at start
  Eigen::Matrix2d dE_prev = Eigen::Matrix2d::Zero();
  SolverTimings timings;
  /// BoundaryMode::Walls: 4 per particle (left, right, bottom, top), the committed wall-contact
  /// history and normal force; empty otherwise. (The state file does not hold them yet.)
  std::vector<contact::PlasticIndentationHistory> wall_history;
  std::vector<double> wall_f_n;
  /// BoundaryMode::Periodic (issue 29): the packing's cell vectors (packing::Packing::cell; empty:
  /// the box's edges), each row's image of j (empty in other modes), the particle whose
  /// translation is held (the 2D state file's optional "periodic" member).
  bool periodic = false;
  std::vector<double> cell;
  std::vector<std::array<int, 2>> shift;
  int pinned = -1;

  /// Throws std::invalid_argument (one line) if sizes, order or values are inconsistent.
  void validate() const;
};
using NetworkState = NetworkStateT<2>;

/// Writes the state exactly in the state archive (JSON, kind "network"; docs/quasistatic.md
/// "State file"), atomically (temporary file + rename). Throws std::runtime_error naming the file
/// on failure.
void save_state(const NetworkState& state, const std::string& path);
/// Reads and validates a state file written by save_state; throws std::invalid_argument (one line,
/// "FILE: /json/pointer: problem") on a missing, truncated, old-format or inconsistent file.
NetworkState load_state(const std::string& path);
/// The same reader on a stream and on the text (load_state(path) is a thin wrapper); `source`
/// names the input in the messages.
NetworkState load_state(std::istream& in, const std::string& source);
NetworkState load_state_text(std::string_view text, const std::string& source);

/// The 3D state of the plastic-indentation law (the generic layout) and its state file (kind
/// "network3d"; docs/quasistatic.md "State file"): the same contract as the 2D functions above.
using NetworkState3 = NetworkStateT<3>;
void save_state(const NetworkState3& state, const std::string& path);
NetworkState3 load_state3(const std::string& path);
NetworkState3 load_state3_text(std::string_view text, const std::string& source);

/// The network solver in dimension D with the contact law Law (law.hpp's interface, chosen at
/// compile time). The tools use the plastic-indentation law of Redanz & Fleck, the default.
template <int D, class Law = contact::PlasticIndentationLawT<D>>
class NetworkSolverT {
 public:
  static constexpr int kDim = D;
  using Mat = Eigen::Matrix<double, D, D>;
  using LawType = Law;
  using Options = SolverOptionsT<typename Law::Params>;
  using State = NetworkStateT<D, typename Law::History>;
  /// The plastic-indentation law: the jammed state both solvers share, the section 3.4 unloading
  /// branch (set_reversible_normal) and the 2D state file are this law's (the members compile for
  /// it only: a static_assert, not a constraint, because clang 14 cannot match an out-of-line
  /// definition's constraint on a class member).
  static constexpr bool kPlastic = std::is_same_v<Law, contact::PlasticIndentationLawT<D>>;
  /// The state has the 2D state file's layout (NetworkState: the plastic law in 2D); any other
  /// law and dimension, the generic layout of NetworkStateT.
  static constexpr bool kFileLayout = std::is_same_v<State, NetworkStateT<2>>;

  /// Throws std::invalid_argument on invalid options or packing (a packing of another dimension).
  NetworkSolverT(const packing::Packing& packing, const Options& options);
  /// Continues from a state (bit-identical to the solver it was taken from when `options` are
  /// that solver's). The boundary mode may differ; throws std::invalid_argument on a bad state.
  NetworkSolverT(const State& state, const Options& options);
  /// Starts from a jammed state (netdem/system/jammed_state.hpp, the state both solvers share):
  /// its particles in its box (the run's initial box, box deformation I), its strain, its
  /// histories (jammed.cpp); the committed forces are the law's on these histories at these
  /// positions (no Newton iteration: the state is taken as it is). options.law is the run's (the
  /// caller checks it against the state's: sys::law_difference). Throws std::invalid_argument on a
  /// bad state or wall contacts without the walls mode.
  NetworkSolverT(const sys::JammedStateT<D>& state, const Options& options);
  /// The committed state as a jammed state: the rows and wall contacts with a history. Throws
  /// std::invalid_argument for a sheared box (the jammed state's box is axis-aligned).
  sys::JammedStateT<D> jammed_state() const;
  ~NetworkSolverT();
  NetworkSolverT(const NetworkSolverT& other);  ///< = NetworkSolverT(other.state(), other.options())
  NetworkSolverT& operator=(const NetworkSolverT&) = delete;

  /// One load increment with the macroscopic strain increment dE (symmetric D x D).
  /// Throws std::runtime_error with a one-line message on a singular/indefinite system or NaN.
  IncrementReport increment(const Mat& dE);

  /// Switches the normal law between reversible Eq 2 (compaction as in sections 2-3.3 of the
  /// paper) and the section 3.4 elastic unloading branch (yield-surface probing). Switching the
  /// branch on starts every touching contact at its current overlap (u_max := overlap), so no force
  /// jumps; pairs apart start fresh. Takes effect from the next increment.
  void set_reversible_normal(bool reversible);

  State state() const;
  const Options& options() const;
  StateMeasures measures() const
    requires(D == 2);
  /// The Eq 13 and contact stresses (both dimensions; in the walls mode Eq 13 sums the walls'
  /// reactions and the contact stress includes the wall contacts, as measures()).
  StressMeasuresT<D> stress() const;
  const SolverTimings& timings() const;

  // committed state
  std::size_t size() const;
  std::vector<double> x() const  ///< the centres' x (a copy of particles().axis(0))
    requires(D == 2);
  std::vector<double> y() const
    requires(D == 2);
  const std::vector<double>& theta() const
    requires(D == 2);
  const sys::ParticleSet<D>& particles() const;  ///< centres, rotations, radii
  const std::vector<double>& radius() const;
  const std::vector<std::uint8_t>& peripheral() const;
  std::vector<ContactView> contacts() const;  ///< load-bearing contacts only (3D: f_t = |f_t|)
  Mat box_deformation() const;                ///< maps the initial box to the current one
  /// The current periodic cell (BoundaryMode::Periodic), else none.
  std::optional<packing::PeriodicCellT<D>> periodic_cell() const;
  double solid_area() const;                  ///< 3D: the solid volume
  double initial_density() const;
  const packing::Box& initial_box() const;  ///< the packing's box
  std::uint64_t seed() const;               ///< the packing's seed
  int free_dofs() const;

  struct Impl;

 private:
  IncrementReport advance(const Mat& dE, int depth);
  std::unique_ptr<Impl> impl_;
};

using NetworkSolver = NetworkSolverT<2>;
using NetworkSolver3 = NetworkSolverT<3>;
extern template class NetworkSolverT<2>;
extern template class NetworkSolverT<3>;

/// The linear spring of Luding et al. (the Luding law's linear feature set: f_n = k2 u, the
/// tangential spring alpha k2 capped at mu f_n), the law of demsolve's linear model: the network
/// core on a second law (tests/quasistatic/test_network_law.cpp).
template <int D>
using LinearLawT = contact::LudingLaw<contact::kLudingLinear, D>;
using NetworkSolverLinear = NetworkSolverT<2, LinearLawT<2>>;
using NetworkSolverLinear3 = NetworkSolverT<3, LinearLawT<3>>;
extern template class NetworkSolverT<2, LinearLawT<2>>;
extern template class NetworkSolverT<3, LinearLawT<3>>;

}  // namespace netdem::qs
