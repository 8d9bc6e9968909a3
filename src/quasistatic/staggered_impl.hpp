#pragma once
// The staggered scheme's private parts (netdem/quasistatic/staggered.hpp; docs/staggered.md): the
// state behind Staggered (Staggered::Impl) and the helpers its files share. Private to
// netdem_quasistatic. Which file owns what:
//   staggered.cpp            options, set-up, one step (Fig 6), the public accessors, save/load
//   staggered_contacts.cpp   contact creation and detection, the move and the shrinkage correction
//   staggered_integrate.cpp  the two-particle models over a step: RK4 with step doubling,
//                            strategies 1 and 2 (section 3.3), advance_free
//   staggered_network.cpp    constraints and held clusters, the pattern (pair_pattern.hpp, shared
//                            with the network solver), the assembly and the solve of the bond network
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "netdem/packing/cell_grid.hpp"
#include "netdem/quasistatic/linear_solver.hpp"
#include "netdem/quasistatic/staggered.hpp"
#include "pair_pattern.hpp"

namespace netdem::qs::staggered {

// ---- helpers shared by the scheme's files

using Clock = std::chrono::steady_clock;
inline double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

using cs::kHA;
using cs::kHB;
using cs::kRA;
using cs::kRB;
using cs::kX;
using cs::State;

// Spheres touch when their centre distance is below (1 + 1e-12) (r_a + r_b): a lattice of touching
// spheres is in contact whatever the rounding of its coordinates.
constexpr double kTouch = 1.0 + 1e-12;

[[noreturn]] inline void bad(const std::string& what) { throw std::invalid_argument(what); }

// Arrhenius values for the few temperatures of one step (the stage times of RK4).
struct DiffCache {
  const cs::SinterMaterial* m = nullptr;
  std::array<cs::Diffusivities, 4> d{};
  int next = 0;
  const cs::Diffusivities& at(double T) {
    for (const auto& e : d)
      if (e.T == T) return e;
    cs::Diffusivities& e = d[next];
    next = (next + 1) % 4;
    e = cs::diffusivities(*m, T);
    return e;
  }
};

struct RhsCtx {
  const cs::SinterMaterial* m;
  DiffCache* cache;
  cs::TemperatureProfile::Segment seg;
  long* evals;
  bool operator()(double t, const State& q, State& dq) const {
    ++*evals;
    return cs::pair_rhs(q, cache->at(seg(t)), 0.0, *m, cs::PathSwitches{}, dq);
  }
};

inline bool finite_state(const State& q) {
  for (double v : q)
    if (!std::isfinite(v)) return false;
  return true;
}

// ---- the state behind Staggered

struct Staggered::Impl {
  StaggeredOptions opt;
  cs::SinterMaterial mat;
  cs::TemperatureProfile prof = cs::TemperatureProfile::constant(1000.0);
  contact::BondMaterial bmat;
  double x_max = 0.0;
  Particles p, p0;
  std::vector<Contact> c;
  std::vector<std::vector<int>> adj;  // particle -> contact indices
  packing::CellGrid3 grid;                        // detect(): the cell grid,
  std::array<std::vector<double>, 3> grid_xyz;    // the centres it sorts
  std::vector<std::pair<int, int>> found;         // and the new pairs (all reused)
  std::vector<std::uint8_t> fixed_user, fixed_plane, fixed;  // 6N flags
  double t = 0.0, dt = 0.0;
  long nsteps = 0;
  Timers timers;
  long rhs_evals = 0;
  DiffCache cache;
  // scaling of the linear system (powers of two: exact): K^ = c S K S, S = 1 (u), 1/ell (theta)
  double cscale = 1.0, ell = 1.0;
  // the network system
  bool pattern_dirty = true, need_factor = true;
  int last_iterations = 0;  // GMRES iterations of the solves since the last factorisation
  std::vector<int> dof;    // 6N -> free index or -1
  int nfree = 0;
  SpMat K;
  PairPattern pattern;     // K's structure and the contacts' slots (pair_pattern.hpp, the network solver's)
  std::vector<contact::BondElement> ref;  // the elements of the last factorisation (its contacts)
  std::vector<std::uint8_t> ref_fixed;    // and its constraints
  std::vector<std::vector<int>> floating;  // clusters held at their first particle
  // work arrays of step()
  std::vector<State> qnew;
  std::vector<int> active;
  std::vector<int> domain_fail;  // strategy 1: the contacts whose trial step left the domain
  std::vector<std::uint8_t> freeze;
  std::vector<contact::BondElement> el;
  std::vector<Eigen::Vector3d> u;
  std::unique_ptr<LinearSolver> solver;
  std::string origin_record = "null";  // JSON: the run that made the sample (set_origin_record)

  // set-up (staggered.cpp)
  void setup_material();
  void setup_particles();
  int N() const { return static_cast<int>(p.size()); }
  Eigen::Vector3d centre(int i) const { return p.position(static_cast<std::size_t>(i)); }

  // contacts (staggered_contacts.cpp)
  void add_contact(int a, int b, double d);
  bool bonded(int a, int b) const;
  int detect();
  void move_and_correct(StepRecord& rec, const VecX& uhat, double t_new);

  // the network (staggered_network.cpp)
  void init_solver();
  void update_constraints();
  Eigen::MatrixXd rigid_null_space(const std::vector<int>& m) const;
  void remove_rigid_motions(std::vector<Eigen::Vector3d>& u) const;
  void build_pattern();
  void build_pattern_for(std::size_t nc, const std::vector<std::uint8_t>& fx);
  double dof_scale(int l) const { return (l % 6) < 3 ? 1.0 : 1.0 / ell; }
  void assemble(const std::vector<contact::BondElement>& e);
  contact::BondElement element(const Contact& k) const {
    return contact::make_bond(centre(k.a), centre(k.b), k.pair.q[kHA], k.pair.q[kHB], p.r[k.a], p.r[k.b]);
  }
  VecX solve_network(StepRecord& rec);

  // one step (staggered.cpp) and its integration of the contacts (staggered_integrate.cpp)
  StepRecord step(double t_end);
  double integrate_contacts(StepRecord& rec, double t_end, double seg_end);
  bool strategy1_attempt(StepRecord& rec, const RhsCtx& f, double h);
  void strategy2_step(StepRecord& rec, const RhsCtx& f, double h);
};

}  // namespace netdem::qs::staggered
