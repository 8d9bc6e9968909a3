#pragma once
// Options of the quasi-static network solver (network_solver.hpp) and its three presets.
//
// `SolverOptions{}` is the plain base: full Newton, a drag per increment, tolerance 1e-3. The
// commands never use it directly: they start from a preset, whose values are stated once here
// and explained in docs/quasistatic.md ("Presets"):
//   compact()             `netsolve compact` (and its tests): strain-rate drag, chord steps
//   yield_precompaction() the precompaction of `netsolve yield`: exactly compact()
//   yield_probe()         unloading and probing of `netsolve yield`: the base options on the
//                         section 3.4 elastic unloading branch
// Options that were measured and not kept (energy line search, adaptive sub-stepping, viscosity
// continuation, kink freezing, pair relaxation, the geometric stiffness) are gone from the code;
// their findings and the commit in which the code last existed are in docs/quasistatic.md.
#include <limits>
#include <type_traits>

#include "netdem/contact/plastic_indentation.hpp"

namespace netdem::qs {

/// Die: the peripheral layer is prescribed (section 2.4), the interior is free. Affine: every
/// centre follows the macroscopic strain, only the interior rotations are free.
/// Die: the peripheral layer is prescribed (section 2.4); Affine: every centre; Walls: nothing is
/// prescribed, four rigid frictionless walls at the faces of the box move with it (E12 = 0).
/// Periodic (issue 29): a periodic packing whose cell follows the strain; contacts across the
/// cell's faces meet the images, every particle is free but one whose translation is held (the
/// rigid translation); the stress is the contact stress (Eq 13 has no reactions to sum).
enum class BoundaryMode { Die, Affine, Walls, Periodic };

/// The nonlinear iteration of an increment.
///  PseudoTransient: pseudo-transient continuation (Kelley & Keyes 1998). Each Newton step solves
///    (K + eta I) delta = f(u_k) with the undragged residual f; the drag eta (u - u_k) acts on the
///    step from the current iterate only, so it vanishes at convergence and the accepted state
///    solves f(u) = 0 whatever eta. eta follows switched evolution relaxation: it is multiplied
///    by the ratio of successive residuals (falls towards Newton while the residual falls, rises
///    and damps the path through a snap-through). The increment is accepted when the undragged
///    residual meets RMS <= residual_tol and max <= max_residual_factor x residual_tol.
///  LegacyDrag: the drag eta (u - u_affine) of the whole increment stays in the equations (the
///    solver before issue 28; its answers contain the drag). Kept to reproduce earlier results.
enum class Iteration { PseudoTransient, LegacyDrag };

/// The commands' default iteration for the boundary modes a run uses (measured, docs/quasistatic.md
/// "Which iteration by default"): the pseudo-transient iteration, whose answer is an equilibrium of
/// the undragged equations, wherever the boundary can hold the packing without a drag (affine,
/// walls, periodic); the legacy drag when a phase runs in the paper's die (a prescribed peripheral
/// layer), which has no undragged equilibrium of a sticking packing past D ~ 0.824: the disks are
/// extruded between the prescribed ones.
Iteration default_iteration(BoundaryMode compaction, BoundaryMode probing);

/// What the network solver's iteration takes, whatever its contact law.
struct IterationOptions {
  BoundaryMode mode = BoundaryMode::Die;
  /// BoundaryMode::Periodic only: every centre follows the affine field of the cell (affine
  /// probing of a periodic state, netsolve yield --compact-bc periodic --probe-bc affine); the
  /// rotations stay unknowns. A solver restored from a periodic state with it keeps the histories.
  bool affine_centres = false;
  bool rotations = true;  ///< false: forbid every particle rotation
  double skin = 0.2;               ///< neighbour-list skin, in units of the mean radius
  int max_newton = 10;             ///< Newton iterations per increment (then the residual is carried)
  double residual_tol = 1e-3;      ///< converged when RMS(residual) <= tol * mean normal contact force ...
  double max_residual_tol = std::numeric_limits<double>::infinity();  ///< ... and max|residual| <= this
  double max_step = 0.02;          ///< cap on a Newton step's translation of one particle (mean radii) ...
  double max_rotation_step = 0.01; ///< ... and rotation (rad), per particle
  double regularisation = 1e-9;    ///< diagonal shift, relative to the mean translational diagonal
  double slide_stiffness_fraction = 0.05;  ///< tangential stiffness kept by sliding contacts in the iteration matrix
  /// Viscous drag on the non-affine motion of the free DOFs, relative to the mean contact
  /// stiffness (pseudo-time regularisation; 0 = purely quasi-static Newton).
  double viscosity = 0.01;
  /// The legacy drag is still the default of the library and of the commands: the pseudo-transient
  /// iteration does not yet converge everywhere (docs/quasistatic.md "Equilibrium without drag").
  Iteration iteration = Iteration::LegacyDrag;
  /// Multiplies every regularisation the iteration keeps (the drag's start value); the answer of
  /// a converged pseudo-transient increment must not depend on it (--regularisation-scale).
  double regularisation_scale = 1.0;
  /// PseudoTransient: accepted when max|residual| <= this x residual_tol (and RMS <= residual_tol).
  double max_residual_factor = 10.0;
  /// PseudoTransient: the drag stays within [eta_0 x drag_floor, eta_0 x drag_ceiling].
  double drag_floor = 1e-2, drag_ceiling = 1e4;
  /// PseudoTransient with a frictionless law (mu = 0, whose increment is the minimisation of the
  /// contact energy at fixed histories): true takes Levenberg-Marquardt steps (K + eta I) delta = f
  /// on the energy, each kept only when the energy fell, with eta from the ratio of the actual to
  /// the predicted decrease (a trust region; docs/quasistatic.md "Frictionless: a trust region on
  /// the energy"). false: the residual line search, as with friction. Chosen by measurement on
  /// frictionless periodic packings (with 200 iterations and the first-touch force floor: 101
  /// against 66 of 120 increments accepted; the residual iteration with 200 lost its network).
  bool energy_merit = true;
  /// With energy_merit and a frictional law (2D): the trust region on an incremental potential,
  /// the contact energy with each tangential spring's stiffness k_t sigma_y A_c and limit mu_eff
  /// F_N frozen at the iterate (contact::tangential_work), refrozen at every kept step. Its
  /// gradient at the iterate is the undragged residual, so the trust region judges each step by
  /// the law's forces there; the accepted state meets the law's residual. false (the default):
  /// the residual line search with friction.
  bool friction_energy_merit = false;
  /// PseudoTransient: an increment that is not accepted within max_newton iterations is undone
  /// and done again as two halves, down to 2^-max_cuts of it (0: never cut).
  int max_cuts = 4;
  /// 0: the drag coefficient is viscosity x mean stiffness in every increment (so the drag per
  /// unit strain grows as the increments shrink). > 0: a strain-rate viscosity, the drag
  /// coefficient of an increment dE is viscosity x mean stiffness x viscosity_strain / |dE|
  /// (Frobenius norm), so that refining the increments converges to one regularised problem.
  double viscosity_strain = 0.0;
  /// GMRES tolerance relative to the Newton residual (inexact Newton: the outer iteration is
  /// far from quadratic convergence, so solving the linear system to 1e-10 is wasted work).
  double linear_tolerance = 1e-2;
  /// A contact whose stick/slip status flipped this many times within an increment keeps its
  /// elastic-predictor (stick) tangential stiffness in the iteration matrix (open/closed flips:
  /// always after two, with the last closed normal stiffness).
  int freeze_after = 2;
  /// Chord (modified Newton) steps: after each fresh tangent and factorisation, up to this many
  /// iterations reuse them (residual re-evaluated, no assembly, no factorisation; 0: off).
  int chord_steps = 0;
  /// Kept factor (issue 30; the staggered scheme's rule): up to this many fresh tangents in a row
  /// are solved by GMRES preconditioned with the last factorisation instead of a new one; a new
  /// factorisation follows a pattern change, a GMRES that does not converge, or one that needed
  /// more than kKeptFactorMaxIterations iterations (0: every fresh tangent is factorised). The
  /// tangent solved is the current one, so the converged state is the same; only the path and the
  /// cost change.
  int factor_reuse = 0;
  static constexpr int kKeptFactorMaxIterations = 30;
  /// The linear solver's preconditioner (docs/performance.md "Issue 30, part 5"). Full: the CHOLMOD
  /// factor of the whole iteration matrix. Translations: the factor of the translations' block
  /// only, and the inverse of each particle's rotation block (LinearSolver::set_split); every
  /// solve is then GMRES on the whole matrix, so the answer is judged on the same residual. Auto:
  /// Translations in 3D, Full in 2D (resolved_preconditioner).
  enum class Preconditioner { Auto, Full, Translations } preconditioner = Preconditioner::Auto;
  /// Nonlinear Gauss-Seidel smoothing after each Newton step: local_sweeps sweeps over the
  /// particles whose residual exceeds local_threshold x the RMS residual, each a damped Newton
  /// iteration (local_iterations at most) on the particle's own DOFs with its neighbours held
  /// (0: off).
  int local_sweeps = 1;
  int local_iterations = 10;
  double local_threshold = 3.0;
  /// Residual line search: step lengths tried (1, 1/2, 1/4, ...); the first that lowers the RMS
  /// residual is taken, else the best of them.
  int backtracks = 5;
  /// Threads for the force evaluations without tangent (line search, local-sweep restarts;
  /// OpenMP, results bit-identical for any number). Assembly and linear algebra stay on one core.
  int threads = 1;
  bool verbose = false;  ///< print every Newton iteration on stderr

  void validate() const;  ///< throws std::invalid_argument (one line)
};

/// The network solver's options for a contact law with parameters LawParams (the law of
/// NetworkSolverT<D, Law>: LawParams = Law::Params). LawParams gives validate() and frictional().
template <class LawParams>
struct SolverOptionsT : IterationOptions {
  LawParams law;

  void validate() const {  ///< throws std::invalid_argument (one line)
    law.validate();
    IterationOptions::validate();
  }
  /// Whether an increment runs the trust region on the energy: the pseudo-transient iteration with
  /// energy_merit and a frictionless law.
  bool uses_energy_merit() const {
    return iteration == Iteration::PseudoTransient && energy_merit && (!law.frictional() || friction_energy_merit);
  }
  /// The preconditioner a network of dimension dim uses: Translations (Auto: in 3D) only where
  /// the rotations are unknowns (a frictional law with rotations) and the iteration is not the
  /// energy trust region (which reads the inertia of the full factor); otherwise Full.
  Preconditioner resolved_preconditioner(int dim) const {
    const bool split_ok = rotations && law.frictional() && !uses_energy_merit();
    const bool want = preconditioner == Preconditioner::Translations ||
                      (preconditioner == Preconditioner::Auto && dim == 3);
    return split_ok && want ? Preconditioner::Translations : Preconditioner::Full;
  }
  /// The merit the pseudo-transient iteration uses: "energy", "energy-friction" or "residual".
  const char* merit_name() const {
    return uses_energy_merit() ? (law.frictional() ? "energy-friction" : "energy") : "residual";
  }

  // ---- the presets of the tools (the plastic-indentation law of Redanz & Fleck; they compile for
  // it only) ----
  static constexpr bool kPlastic = std::is_same_v<LawParams, contact::PlasticIndentationParams>;
  /// `netsolve compact`: sticking, reversible Eq 2, drag per unit strain (viscosity 0.01 at
  /// |dE| = 3.57e-4, the increment of the 100-increment default run), tolerance 3e-3, three
  /// chord steps, GMRES to 0.3 of the Newton residual, line search 1, 1/2, 1/4.
  static SolverOptionsT compact();
  /// `netsolve yield` precompaction: the same as compact().
  static SolverOptionsT yield_precompaction();
  /// `netsolve yield` unloading and probes: SolverOptions{} (per-increment drag 0.01, tolerance
  /// 1e-3, full Newton, GMRES 1e-2, five backtracks) with sticking friction on the section 3.4
  /// elastic unloading branch (law.reversible = false).
  static SolverOptionsT yield_probe();
};

/// The options of the tools' network solver: the plastic-indentation law.
using SolverOptions = SolverOptionsT<contact::PlasticIndentationParams>;
extern template struct SolverOptionsT<contact::PlasticIndentationParams>;

}  // namespace netdem::qs
