#pragma once
// Quasi-static implicit network solver (Redanz & Fleck, Acta Mater. 49 (2001) 4325, sections 2.3-2.4).
//
// Each particle is a node with (u1, u2, theta); each contact a plastic-indentation element from
// src/contact. Every load increment prescribes Delta u = (exp(Delta E) - I) x (Eqs 14-15, current
// coordinates) on the prescribed particles (the peripheral layer in die mode, every centre in
// affine mode; peripheral rotations are always held), then finds the free DOFs by Newton
// iterations on the equilibrium equations (Eq 10-12). The trial state is always recomputed from
// the committed contact history plus the whole increment (return mapping) and committed only when
// the increment is accepted. If Newton does not reach the tolerance within max_newton iterations
// the increment is accepted anyway and its residual is carried into the next increment
// (forward Euler with equilibrium correction); the residual norm is reported per increment.
// With chord_steps > 0 an assembled tangent and its factorisation serve several iterations
// (modified Newton; `netsolve compact` uses 3).
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
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "netdem/contact/plastic_indentation.hpp"

namespace netdem::packing {
struct Packing;
}

namespace netdem::qs {

enum class BoundaryMode { Die, Affine };

/// Globalisation of the Newton step.
enum class LineSearch {
  Residual,  ///< backtracking (halving) on the RMS residual (the original scheme)
  Energy     ///< Crisfield: zero of the slope step . r(u + a step), i.e. the minimum of the incremental potential
};

struct SolverOptions {
  BoundaryMode mode = BoundaryMode::Die;
  bool rotations = true;  ///< false: forbid every particle rotation
  contact::PlasticIndentationParams law;
  double skin = 0.2;               ///< neighbour-list skin, in units of the mean radius
  int max_newton = 10;             ///< Newton iterations per increment (then the residual is carried)
  double residual_tol = 1e-3;      ///< converged when RMS(residual) <= tol * mean normal contact force ...
  double max_residual_tol = std::numeric_limits<double>::infinity();  ///< ... and max|residual| <= this
  double max_step = 0.02;          ///< cap on a Newton step's translation of one particle (mean radii) ...
  double max_rotation_step = 0.01; ///< ... and rotation (rad), per particle
  double regularisation = 1e-9;    ///< diagonal shift, relative to the mean translational diagonal
  double slide_stiffness_fraction = 0.05;  ///< tangential stiffness kept by sliding contacts in the iteration matrix
  bool geometric_stiffness = false;        ///< add the geometric stiffness to the tangent
  /// Viscous drag on the non-affine motion of the free DOFs, relative to the mean contact
  /// stiffness (pseudo-time regularisation; 0 = purely quasi-static Newton).
  double viscosity = 0.01;
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
  /// A plastic contact that switched between loading and elastic unloading this many times within
  /// an increment gets the unloading stiffness in the iteration matrix (0: off).
  int kink_freeze_after = 0;
  /// Nonlinear Gauss-Seidel smoothing after each Newton step: local_sweeps sweeps over the
  /// particles whose residual exceeds local_threshold x the RMS residual, each a damped Newton
  /// iteration (local_iterations at most) on the particle's own DOFs with its neighbours held
  /// (0: off).
  int local_sweeps = 1;
  int local_iterations = 10;
  double local_threshold = 3.0;
  bool local_pairs = false;  ///< relax a particle together with its worst loaded contact partner
  /// Viscosity continuation: the first Newton iteration of an increment uses
  /// max(viscosity, viscosity_start), each further one viscosity_decay times the previous value
  /// down to `viscosity`; only the target viscosity counts as converged (0: off).
  double viscosity_start = 0.0;
  double viscosity_decay = 0.5;
  /// Adaptive sub-stepping: an increment that does not converge is redone from the committed
  /// state as two halves, recursively up to max_cuts levels (0: off).
  int max_cuts = 0;
  LineSearch line_search = LineSearch::Residual;
  int line_search_max = 6;         ///< energy line search: residual evaluations per line search
  /// Residual line search: step lengths tried (1, 1/2, 1/4, ...); the first that lowers the RMS
  /// residual is taken, else the best of them.
  int backtracks = 5;
  double line_search_tol = 0.5;    ///< energy line search: accept |slope| <= tol * initial slope
  /// Threads for the force evaluations without tangent (line search, local-sweep restarts;
  /// OpenMP, results bit-identical for any number). Assembly and linear algebra stay on one core.
  int threads = 1;
  bool verbose = false;  ///< print every Newton iteration on stderr
  void validate() const;  ///< throws std::invalid_argument (one line)
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
  int cuts = 0;      ///< failed attempts that were split in two (adaptive sub-stepping)
  int substeps = 1;  ///< committed sub-increments
};

/// Macroscopic and microscopic measures of the committed state.
struct StateMeasures {
  double E11 = 0, E22 = 0, E12 = 0;  ///< accumulated strain E = integral of Edot
  double density = 0;                ///< D = solid area / current box area
  double S11 = 0, S22 = 0, S12 = 0;  ///< symmetric part of Eq 13 (tension positive)
  double S_asym = 0;                 ///< (S12 - S21)/2
  double S11_contacts = 0, S22_contacts = 0, S12_contacts = 0;  ///< Love-Weber average over contacts
  double Z = 0;                      ///< 2 x load-bearing contacts / N
  int contacts = 0, sliding = 0;
  double mean_normal_force = 0;
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
};

class NetworkSolver {
 public:
  /// Throws std::invalid_argument on invalid options or packing.
  NetworkSolver(const packing::Packing& packing, const SolverOptions& options);
  ~NetworkSolver();
  NetworkSolver(const NetworkSolver&) = delete;
  NetworkSolver& operator=(const NetworkSolver&) = delete;

  /// One load increment with the macroscopic strain increment dE (symmetric 2x2).
  /// Throws std::runtime_error with a one-line message on a singular/indefinite system or NaN.
  IncrementReport increment(const Eigen::Matrix2d& dE);

  /// Switches the normal law between reversible Eq 2 (compaction as in sections 2-3.3 of the
  /// paper) and the section 3.4 elastic unloading branch (yield-surface probing). Switching the
  /// branch on starts every touching contact at its current overlap (u_max := overlap), so no force
  /// jumps; pairs apart start fresh. Takes effect from the next increment.
  void set_reversible_normal(bool reversible);

  StateMeasures measures() const;
  const SolverTimings& timings() const;

  // committed state
  std::size_t size() const;
  const std::vector<double>& x() const;
  const std::vector<double>& y() const;
  const std::vector<double>& theta() const;
  const std::vector<double>& radius() const;
  const std::vector<std::uint8_t>& peripheral() const;
  std::vector<ContactView> contacts() const;  ///< load-bearing contacts only
  Eigen::Matrix2d box_deformation() const;     ///< maps the initial box to the current one
  double solid_area() const;
  double initial_density() const;
  int free_dofs() const;

 private:
  IncrementReport substep(const Eigen::Matrix2d& dE, int depth);
  IncrementReport attempt(const Eigen::Matrix2d& dE, bool accept_unconverged);
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace netdem::qs
