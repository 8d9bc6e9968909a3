#pragma once
// Private: the parts of the network solver (NetworkSolverT<D, L>::Impl) and which file owns what.
//
//   contact_table.cpp  ContactTableT<D>: the system layer's table (netdem/system/contact_table.hpp)
//                      with the solver's per-row data, and the neighbour rebuild
//   boundary.cpp       DofMap and the prescribed motion of an increment (boundary conditions)
//   pair_pattern.hpp   the sparsity pattern and the slots of the pairs (shared with the staggered
//                      scheme)
//   assembly.cpp       trial forces, iteration matrix (through the slots), drag and regularisation
//   newton.cpp         the Newton driver of one increment (predictor, iterations, line search, commit)
//   energy_iteration.cpp  the frictionless increment as a trust region on the contact energy
//   relaxation.cpp     the local nonlinear Gauss-Seidel sweep over the worst particles
//   measures.cpp       stresses (Eq 13, Love-Weber), Z, affine deviations, diagnostics
//   network_solver.cpp construction, the public accessors, the copyable state
//   state_io.cpp       the state file (save/restore; 2D)
//   walls.cpp          the rigid frictionless walls of BoundaryMode::Walls
//
// The dimension D is a template parameter of everything here: a node has kN = Dim<D>::kNodeDofs
// DOFs (D translations, then Dim<D>::kRotDofs rotations; DOF c of particle p at kN p + c), a pair
// element kP = 2 kN. Each .cpp file defines its members for any D and instantiates them for D = 2
// (the tools) and D = 3 (walls.cpp: D = 2 only; its callers reach it under `if constexpr`).
#include <chrono>
#include <cstdint>
#include <type_traits>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/LU>

#include "netdem/contact/element.hpp"
#include "netdem/contact/plastic_indentation.hpp"
#include "netdem/packing/periodic.hpp"
#include "netdem/quasistatic/linear_solver.hpp"
#include "netdem/quasistatic/network_solver.hpp"
#include "netdem/system/contact_table.hpp"
#include "netdem/system/particle_set.hpp"
#include "pair_pattern.hpp"

namespace netdem::qs {

namespace ct = netdem::contact;

/// The contact table of the network solver: the system layer's table (netdem/system/
/// contact_table.hpp: rows i < j sorted, every pair with a gap below the skin at the last rebuild,
/// touching or not; their committed history; the adjacency; the lifecycle, read from the law)
/// plus the solver's own per-row data, carried across rebuilds with the history: the
/// affine-deviation bookkeeping (a new row starts with E_form = the strain at its creation) and
/// the committed forces.
template <int D, class Law>
struct ContactTableT : sys::ContactTable<typename Law::History, D> {
  using Mat = Eigen::Matrix<double, D, D>;
  using Tan = typename ct::Dim<D>::Tan;
  std::vector<PairAuxT<D>> aux;
  std::vector<double> fn_c;           ///< committed normal force
  std::vector<Tan> ft_c;              ///< committed tangential force
  std::vector<std::uint8_t> slide_c;  ///< committed sliding flag

  /// New rows (gap < skin) merged with the committed history and the per-row data above.
  void rebuild(const Law& law, const sys::ParticleSet<D>& ps, double skin, double r_max, const Mat& E,
               const Mat& Fbox, const packing::PeriodicCellT<D>* cell = nullptr);
};

/// The boundary conditions as a DOF map: dof[kN p + c] = free index or -1 (prescribed).
/// Die mode: the peripheral layer's translations are prescribed; affine mode: every centre's.
/// Walls: nothing is prescribed.
/// Peripheral rotations are always held (section 2.4); interior rotations are free when the law
/// has friction and rotations are allowed.
/// Periodic: every DOF is free but the translations of particle `pinned` (the rigid translation).
struct DofMap {
  std::vector<int> dof;
  int nfree = 0;
  void build(int dim, int rot_dofs, BoundaryMode mode, bool rotations_free, const std::vector<std::uint8_t>& periph,
             int pinned = -1, bool affine_centres = false);
};

/// BoundaryMode::Walls: the contacts of every particle with the 2D walls (slot 2D p + w; wall w at
/// the minimum (w even) or maximum (w odd) of axis w / 2: in 2D 0 left, 1 right, 2 bottom, 3 top),
/// the plastic-indentation law with R* = r_p and mu = 0.
template <int D, class Law>
struct WallTableT {
  std::vector<typename Law::History> whist;  ///< committed history
  std::vector<double> wfn_c;                 ///< committed normal force
  std::vector<typename Law::Response> wtrial;  ///< trial state of the current du
  std::vector<double> wwork;   ///< the normal force's potential per slot (energy mode only)
  std::vector<double> wf, wk;  ///< trial force on p along its wall axis (signed), iteration stiffness
  Eigen::Matrix<double, D, D> Fbox_trial = Eigen::Matrix<double, D, D>::Identity();  ///< the box at the end of the increment
};

template <int D, class L>
struct NetworkSolverT<D, L>::Impl : ContactTableT<D, L>, DofMap, WallTableT<D, L> {
  using Law = L;
  static_assert(ct::ContactLaw<Law> && ct::kHasReferenceScales<Law>,
                "the network solver's law: law.hpp's interface and its reference scales");
  using Element = ct::PairElementT<Law>;
  using Response = typename Law::Response;
  using Geometry = ct::PairGeometryT<D>;
  using Vec = typename ct::Dim<D>::Vec;
  using Tan = typename ct::Dim<D>::Tan;
  using PairVec = ct::PairVecT<D>;
  using PairMat = ct::PairMatT<D>;
  /// d slip / d q of a pair: b_t (6) in 2D, B_t (3 x 12) in 3D (kinematics.hpp slip_gradient).
  using SlipGradient = std::conditional_t<D == 2, PairVec, Eigen::Matrix<double, 3, 12>>;
  using Mat = Eigen::Matrix<double, D, D>;
  using Table = ContactTableT<D, L>;
  static constexpr int kN = ct::Dim<D>::kNodeDofs;  ///< DOFs per node
  static constexpr int kP = 2 * kN;                 ///< DOFs per pair element
  static constexpr int kR = ct::Dim<D>::kRotDofs;
  static constexpr int kW = 2 * D;  ///< walls per particle (BoundaryMode::Walls): 2a min, 2a + 1 max of axis a
  using Table::adj_pair;
  using Table::adj_start;
  using Table::aux;
  using Table::F_build;
  using Table::fn_c;
  using Table::ft_c;
  using Table::hist;
  using Table::pi;
  using Table::pj;
  using Table::pos_build;
  using Table::slide_c;
  using WallTableT<D, L>::whist;
  using WallTableT<D, L>::wfn_c;
  using WallTableT<D, L>::wtrial;
  using WallTableT<D, L>::wf;
  using WallTableT<D, L>::wk;
  using WallTableT<D, L>::wwork;
  using WallTableT<D, L>::Fbox_trial;

  Options opt;
  Law law;       ///< the law of opt.law (set_options keeps both together)
  Law wall_law;  ///< the same law without friction (the walls are frictionless)
  typename Law::Params wall_params;  ///< wall_law's parameters (a law may hold them by reference)
  int n = 0;
  sys::ParticleSet<D> ps;  ///< centres, rotations, radii (committed state)
  std::vector<std::uint8_t> periph;
  double solid_area = 0, D0 = 0, r_mean = 0, r_max = 0, box_area0 = 0;  ///< 3D: volumes
  packing::Box box0;
  std::uint64_t seed = 0;
  Mat Fbox = Mat::Identity();
  Mat E = Mat::Zero();
  // BoundaryMode::Periodic (issue 29): the initial cell (the current one is Fbox h0), its vectors
  // as the packing gave them (empty: the box's edges), the particle whose translation is held
  // (it removes the rigid translation, the periodic network's null space; -1 in other modes)
  packing::PeriodicCellT<D> cell0;
  std::vector<double> cell_vectors;
  int pinned = -1;
  std::vector<double> f_c;  ///< kN n contact forces on the particles (committed state)
  std::vector<double> du_prev;  ///< the last committed increment's displacements (predictor)
  Mat dE_prev = Mat::Zero();

  // sparse pattern (free DOFs only, full storage)
  SpMat K, M;
  PairPattern pattern;  // K's structure, the pairs' slots and the diagonal entries (pair_pattern.hpp)
  bool pattern_changed = true;
  // the kept factor (IterationOptions::factor_reuse): whether the factor is of the current M,
  // fresh tangents solved with it since it was made, GMRES iterations of the last such solve
  bool factor_current = false;
  int factor_reuses = 0, kept_iterations = 0;

  // trial buffers of the current increment
  std::vector<double> du, f;
  std::vector<double> pw;  // per pair: the contact's potential in the trial state (energy mode only)
  // per pair, energy mode with friction (2D): the tangential spring's stiffness and limit frozen
  // at the iterate (tangential_work), set by assemble() and kept while the step is judged
  std::vector<double> t_kt, t_limit;
  std::vector<double> mdiag;  // energy mode: M's assembled diagonal (free DOFs), before the shift
  std::vector<double> pf;  // kP per pair: the pair's force on (i, j) in the trial state (summed into f)
  std::vector<std::uint8_t> apart;      // per pair: never touched, apart, trial state and pf already zero
  std::vector<std::uint8_t> refreshed;  // per pair, scratch of refresh_particles
  std::vector<double> relax_rp;         // scratch of relax_worst (it runs every Newton iteration)
  std::vector<std::uint8_t> relax_done;
  std::vector<int> relax_moved;
  std::vector<std::pair<double, int>> relax_bad;
  std::vector<Geometry> g0;
  std::vector<Response> trial;
  std::vector<Tan> trial_slip;
  std::vector<std::uint8_t> last_sliding, flips;  // per pair, within the current increment
  std::vector<std::uint8_t> last_open, open_flips;
  std::vector<double> last_kn;
  std::vector<std::uint8_t> diag_branch;  // verbose diagnostics: branch + 4*sliding at the last iteration
  std::vector<double> du_aff;  // affine motion of the increment (drag reference)
  std::vector<double> du_ref;  // the drag's reference: du_aff (legacy drag) or the iterate of the
                               // current iteration (pseudo-transient: the drag acts on the step)
  double eta = -1.0;           // viscous drag coefficient of the current factor
  double eta0 = 0.0;           // its start value in the increment
  double res_fresh = -1.0;     // pseudo-transient: the residual at the last fresh iteration
  double last_alpha = 1.0;     // the step length the last line search took
  int rises = 0;               // fresh iterations in a row whose residual rose
  double kl_ref = 1.0;         // mean translational diagonal (local regularisation)
  std::vector<double> du_start;  // du at the start of a line search
  std::vector<double> du_before;  // legacy drag: du at the start of a Newton step (its drag work)
  VecX rhs, sol;

  LinearSolver lin;
  SolverTimings tim;
  SolverTimings lin_base;  ///< linear-solver counters of the solver(s) this one was restored from

  /// Centre of p in the committed state and at the end of the trial increment du.
  Vec at(int p) const {
    if constexpr (D == 2) {
      return Vec(ps.pos[2 * p], ps.pos[2 * p + 1]);
    } else {
      return Vec(ps.pos[3 * p], ps.pos[3 * p + 1], ps.pos[3 * p + 2]);
    }
  }
  Vec moved(int p) const {
    if constexpr (D == 2) {
      return Vec(ps.pos[2 * p] + du[3 * p], ps.pos[2 * p + 1] + du[3 * p + 1]);
    } else {
      return Vec(ps.pos[3 * p] + du[6 * p], ps.pos[3 * p + 1] + du[6 * p + 1], ps.pos[3 * p + 2] + du[6 * p + 2]);
    }
  }
  bool periodic() const { return opt.mode == BoundaryMode::Periodic; }
  /// The offset of row k's image of j under the box deformation F (zero outside periodic cells).
  Vec image(std::size_t k, const Mat& F) const {
    const auto& sh = this->shift[k];
    Vec nv;
    for (int a = 0; a < D; ++a) nv[a] = sh[static_cast<std::size_t>(a)];
    return F * (cell0.h * nv);
  }
  /// Row k's particle j as i meets it (its periodic image) in the committed state and at the end
  /// of the trial increment (the trial cell Fbox_trial h0).
  Vec at_j(std::size_t k) const { return periodic() ? Vec(at(pj[k]) + image(k, Fbox)) : at(pj[k]); }
  Vec moved_j(std::size_t k) const {
    return periodic() ? Vec(moved(pj[k]) + image(k, this->Fbox_trial)) : moved(pj[k]);
  }
  /// The rotation increment of p in du (2D: the angle; 3D: the rotation vector).
  typename ct::Dim<D>::Rot rotation(int p) const {
    if constexpr (D == 2) {
      return du[3 * p + 2];
    } else {
      return Vec(du[6 * p + 3], du[6 * p + 4], du[6 * p + 5]);
    }
  }
  /// Whether DOF c of a node is a rotation.
  static bool is_rotation(int c) { return c >= D; }

  // construction (network_solver.cpp)
  void set_options(const Options& o);
  void init_linear_solver();
  // contact_table.cpp
  void build_neighbours();
  // boundary.cpp
  void prescribe(const Mat& dE);
  void loaded_particle(std::vector<std::uint8_t>& loaded) const;
  std::vector<std::uint8_t> predictor_loaded;  // scratch of prescribe
  // assembly.cpp
  void build_pattern();
  void assemble(bool& any_nonsymmetric);
  double iteration_stiffness(std::size_t k, const PairVec& bn, const SlipGradient& bt, Element& e, double& k_t);
  void scatter(std::size_t k, const Element& e, const PairVec& bn, const SlipGradient& bt, double kn_sym, double k_t);
  void set_apart(std::size_t k);
  /// The potential of pair k at overlap u and slip increment dslip: the normal force's (its
  /// committed history, R* of its radii) plus, with friction, the tangential spring's at the
  /// stiffness and limit frozen at the iterate (t_kt, t_limit).
  double pair_work(std::size_t k, double u, const Tan& dslip) const {
    if constexpr (ct::kHasPotential<Law>) {
      const double ri = ps.r[pi[k]], rj = ps.r[pj[k]];
      const double w = law.normal_work(hist[k], ri * rj / (ri + rj), u);
      if (!friction_energy() || k >= t_kt.size()) return w;  // (no frozen values before the first step)
      return w + law.tangential_work(hist[k], t_kt[k], t_limit[k], dslip);
    } else {  // (set_options refuses the energy merit for a law without a potential)
      (void)k, (void)u, (void)dslip;
      return 0.0;
    }
  }
  /// Energy mode with a frictional law (2D): the merit adds the tangential springs' potential.
  bool friction_energy() const { return D == 2 && opt.law.frictional() && energy_mode(); }
  void freeze_tangential(std::size_t k, double f_n);
  double refreeze_at_iterate();
  void pair_forces(std::size_t k, Element& e);
  void evaluate_forces();
  void open_contact_stiffness(std::size_t k, const Geometry& g1);
  void refresh_particles(const std::vector<int>& group);
  double mean_diagonal() const;
  void regularise();
  // newton.cpp
  IncrementReport attempt(const Mat& dE);
  void start_attempt(const Mat& dE, IncrementReport& rep);
  void finish_attempt(const Mat& dE, double fbar, std::chrono::steady_clock::time_point t_start, IncrementReport& rep);
  void begin_increment(const Mat& dE);
  void begin_pairs();
  void start_drag(const Mat& dE);
  bool pseudo_transient() const { return opt.iteration == Iteration::PseudoTransient; }
  bool accepted(double rms, double max) const;
  /// Pseudo-transient with energy_merit (frictionless, or friction_energy_merit in 2D): the trust
  /// region on the energy.
  bool energy_mode() const { return opt.uses_energy_merit() && (D == 2 || !opt.law.frictional()); }
  // energy_iteration.cpp
  IncrementReport attempt_energy(const Mat& dE);
  double energy() const;
  void keep_diagonal();
  void shift_matrix(double shift);
  double step_scale() const;
  void add_step(double a);
  bool trial_needs_rebuild();
  void rebuild_at_trial();
  sys::ParticleSet<D> ps_trial;  // scratch of trial_needs_rebuild
  void adapt_drag(double res, IncrementReport& rep);
  double drag_work(const std::vector<double>& before) const;
  double contact_work() const;
  bool linear_step(bool fresh, bool nonsym, IncrementReport& rep);
  bool line_search(double newton_res);
  bool local_sweeps(bool f_current);
  void commit(const Mat& dE, IncrementReport& rep);
  double mean_normal_force() const;
  double residual(double fbar, bool fill_rhs, double* max_norm = nullptr);
  void clip_step();
  // walls.cpp
  bool walls() const { return opt.mode == BoundaryMode::Walls; }
  struct WallEval {
    Response r;
    double force = 0.0, k = 0.0;  ///< on p along the wall's axis (signed), iteration stiffness
    double work = 0.0;            ///< the normal force's potential (energy mode only)
  };
  WallEval wall_eval(int p, int w) const;  ///< at x + du against the trial box
  void wall_particle(int p, double sign);  ///< evaluates p's walls and adds sign x forces to f
  void wall_forces();                      ///< every wall contact: trial state, forces into f
  void wall_stiffness();                   ///< the wall contacts' stiffness into K and M
  void commit_walls();
  double wall_work() const;  ///< the wall contacts' share of contact_work()
  // relaxation.cpp
  void local_eval(const int* group, int m, Eigen::VectorXd& res, Eigen::MatrixXd& Kl) const;
  void relax_set(const int* group, int m, double fbar);
  int relax_worst(double fbar, double rms);
  // measures.cpp
  double unbalance(double fbar, double* rms = nullptr) const;
  void print_iteration(int it, double newton_res, double newton_max, double fbar);
  void print_worst(double fbar) const;
};

/// Seconds since t0 (the solver's timers).
inline double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// exp(A) for a small symmetric D x D matrix (series; |A| << 1 per increment).
template <int D>
Eigen::Matrix<double, D, D> small_expm(const Eigen::Matrix<double, D, D>& A) {
  using Mat = Eigen::Matrix<double, D, D>;
  Mat term = Mat::Identity(), sum = Mat::Identity();
  for (int k = 1; k <= 8; ++k) {
    term = term * A / static_cast<double>(k);
    sum += term;
  }
  return sum;
}

}  // namespace netdem::qs
