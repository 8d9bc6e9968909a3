// NetworkSolverT<D, L>: construction from a packing or from a state, the copyable state, and the public
// accessors. The parts are listed in solver_impl.hpp.
#include "netdem/quasistatic/network_solver.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <numbers>
#include <stdexcept>
#include <string>

#include <fmt/format.h>

#include "netdem/packing/packing.hpp"
#include "solver_impl.hpp"

namespace netdem::qs {

template <int D, class L>
void NetworkSolverT<D, L>::Impl::init_linear_solver() {
  LinearSolverOptions lo;
  lo.gmres_tolerance = opt.linear_tolerance;
  // 3D: nested dissection (METIS on the particles' graph) at every size. CHOLMOD's default keeps
  // AMD when its fill looks acceptable, and on sphere networks AMD's factor takes 2.4x (2000
  // spheres) to 3.4x (10^4) the flops of nested dissection's (docs/performance.md "Issue 30, part 3").
  if constexpr (D == 3) lo.ordering = LinearSolverOptions::Ordering::Nesdis;
  lin = LinearSolver(lo);
  r_mean = std::accumulate(ps.r.begin(), ps.r.end(), 0.0) / n;
  r_max = *std::max_element(ps.r.begin(), ps.r.end());
  DofMap::build(D, kR, opt.mode, opt.rotations && opt.law.frictional(), periph, pinned,
                opt.mode == BoundaryMode::Periodic && opt.affine_centres);
  std::vector<int> particle_of_dof(static_cast<std::size_t>(nfree));
  for (int q = 0; q < kN * n; ++q)
    if (dof[q] >= 0) particle_of_dof[dof[q]] = q / kN;
  if (opt.resolved_preconditioner(D) == IterationOptions::Preconditioner::Translations) {
    std::vector<int> group(static_cast<std::size_t>(nfree), -1);  // translations factored
    for (int q = 0; q < kN * n; ++q)
      if (dof[q] >= 0 && is_rotation(q % kN)) group[dof[q]] = q / kN;  // a particle's rotations
    lin.set_split(std::move(group));
  }
  lin.set_row_blocks(std::move(particle_of_dof));
  du.assign(kN * n, 0.0);
  f.assign(kN * n, 0.0);
}

template <int D, class L>
void NetworkSolverT<D, L>::Impl::set_options(const Options& o) {
  if (o.uses_energy_merit() && !ct::kHasPotential<Law>)
    throw std::invalid_argument("network solver: the energy merit needs a contact law with a potential; this law has "
                                "none (use the residual merit)");
  opt = o;
  law = Law(opt.law);
  wall_params = opt.law;
  wall_params.mu = 0.0;
  wall_law = Law(wall_params);
}

namespace {

/// The outer layer of a 3D packing (the die mode's prescribed particles): the spheres whose
/// surface comes within one mean radius of a face of the spheres' bounding box.
/// (maybe_unused: the NETDEM_QS_MORE build of this file instantiates only the linear law)
[[maybe_unused]] std::vector<std::uint8_t> peripheral_layer_3d(const packing::Packing& pk) {
  const std::size_t n = pk.size();
  const std::vector<double>* axes[3] = {&pk.x, &pk.y, &pk.z};
  double lo[3], hi[3], r_mean = 0.0;
  for (int a = 0; a < 3; ++a) {
    lo[a] = std::numeric_limits<double>::infinity();
    hi[a] = -lo[a];
  }
  for (std::size_t p = 0; p < n; ++p) {
    r_mean += pk.r[p] / static_cast<double>(n);
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], (*axes[a])[p] - pk.r[p]);
      hi[a] = std::max(hi[a], (*axes[a])[p] + pk.r[p]);
    }
  }
  std::vector<std::uint8_t> per(n, 0);
  for (std::size_t p = 0; p < n; ++p)
    for (int a = 0; a < 3; ++a)
      if ((*axes[a])[p] - pk.r[p] - lo[a] < r_mean || hi[a] - (*axes[a])[p] - pk.r[p] < r_mean) per[p] = 1;
  return per;
}

}  // namespace

template <int D, class L>
NetworkSolverT<D, L>::NetworkSolverT(const packing::Packing& pk, const Options& options)
    : impl_(std::make_unique<Impl>()) {
  options.validate();
  if (pk.dim != D)
    throw std::invalid_argument(fmt::format("network solver: the packing has dimension {}, the solver {}", pk.dim, D));
  packing::validate(pk);
  const bool periodic = options.mode == BoundaryMode::Periodic;
  if (pk.periodic != periodic)
    throw std::invalid_argument(periodic ? "network solver: the periodic boundary mode needs a periodic packing"
                                         : "network solver: the packing is periodic; only the periodic boundary mode "
                                           "can use it");
  auto& s = *impl_;
  s.set_options(options);
  s.n = static_cast<int>(pk.size());
  s.ps = sys::ParticleSet<D>::from_packing(pk);
  if (periodic) {  // no peripheral layer; the best-connected particle holds the rigid translation
    s.periph.assign(pk.size(), 0);
    s.cell0 = packing::periodic_cell<D>(pk);
    s.cell_vectors = pk.cell;
    std::vector<int> touching(pk.size(), 0);
    for (const auto& [i, j] : packing::touching_pairs(pk)) ++touching[i], ++touching[j];
    s.pinned = static_cast<int>(std::max_element(touching.begin(), touching.end()) - touching.begin());
  } else if constexpr (D == 2) {
    s.periph = packing::peripheral_layer(pk);
  } else {
    s.periph = peripheral_layer_3d(pk);
  }
  s.solid_area = pk.solid_measure();
  s.box_area0 = periodic ? s.cell0.measure() : pk.box_measure();
  s.box0 = pk.box;
  s.seed = pk.seed;
  s.D0 = s.solid_area / s.box_area0;
  s.init_linear_solver();
  s.f_c.assign(Impl::kN * s.n, 0.0);
  s.build_neighbours();
}

template <int D, class L>
NetworkSolverT<D, L>::NetworkSolverT(const State& st, const Options& options) : impl_(std::make_unique<Impl>()) {
  options.validate();
  st.validate();
  auto& s = *impl_;
  s.set_options(options);
  if constexpr (kFileLayout) {  // the 2D state keeps the layout of the 2D state file
    s.n = static_cast<int>(st.x.size());
    s.ps.pos.resize(2 * st.x.size());
    s.pos_build.resize(2 * st.x.size());
    for (int p = 0; p < s.n; ++p) {
      s.ps.pos[2 * p] = st.x[p];
      s.ps.pos[2 * p + 1] = st.y[p];
      s.pos_build[2 * p] = st.x_build[p];
      s.pos_build[2 * p + 1] = st.y_build[p];
    }
    s.ps.rot = st.theta;
    s.ps.r = st.r;
  } else {
    s.n = static_cast<int>(st.particles.size());
    s.ps = st.particles;
    s.pos_build = st.pos_build;
  }
  s.periph = st.peripheral;
  if (st.periodic != (options.mode == BoundaryMode::Periodic))
    throw std::invalid_argument(st.periodic ? "network solver: the state is of a periodic cell; only the periodic "
                                              "boundary mode can continue it"
                                            : "network solver: the periodic boundary mode needs a periodic state");
  if (st.periodic) {
    packing::Packing cell_of;  // the cell from the state's box and vectors
    cell_of.dim = D;
    cell_of.box = st.box0;
    cell_of.periodic = true;
    cell_of.cell = st.cell;
    s.cell0 = packing::periodic_cell<D>(cell_of);
    s.cell_vectors = st.cell;
    s.pinned = st.pinned;
  }
  s.solid_area = st.solid_area;
  s.box_area0 = st.box_area0;
  s.box0 = st.box0;
  s.seed = st.seed;
  s.D0 = st.initial_density;
  s.Fbox = st.box_deformation;
  s.E = st.strain;
  s.init_linear_solver();
  s.pi = st.pair_i;
  s.pj = st.pair_j;
  if (st.periodic)
    s.shift = st.shift;
  else
    s.shift.assign(st.pair_i.size(), {});
  s.hist = st.history;
  s.aux = st.aux;
  s.fn_c = st.f_n;
  s.ft_c = st.f_t;
  s.slide_c = st.sliding;
  s.F_build = st.box_deformation_build;
  s.build_adjacency(s.n);
  s.apart.assign(s.pi.size(), 0);
  s.build_pattern();
  s.f_c = st.f_contact;
  s.du_prev = st.du_prev;
  s.dE_prev = st.dE_prev;
  s.tim = st.timings;
  s.lin_base = st.timings;
  s.whist = st.wall_history;
  s.wfn_c = st.wall_f_n;
}

template <int D, class L>
NetworkSolverT<D, L>::NetworkSolverT(const NetworkSolverT& other) : NetworkSolverT(other.state(), other.options()) {}

template <int D, class L>
NetworkSolverT<D, L>::~NetworkSolverT() = default;

template <int D, class L>
typename NetworkSolverT<D, L>::State NetworkSolverT<D, L>::state() const {
  const auto& s = *impl_;
  State st;
  if constexpr (kFileLayout) {
    st.x = s.ps.axis(0);
    st.y = s.ps.axis(1);
    st.theta = s.ps.rot;
    st.r = s.ps.r;
    st.x_build.resize(s.ps.size());
    st.y_build.resize(s.ps.size());
    for (std::size_t p = 0; p < s.ps.size(); ++p) {
      st.x_build[p] = s.pos_build[2 * p];
      st.y_build[p] = s.pos_build[2 * p + 1];
    }
  } else {
    st.particles = s.ps;
    st.pos_build = s.pos_build;
  }
  st.peripheral = s.periph;
  st.solid_area = s.solid_area;
  st.initial_density = s.D0;
  st.box_area0 = s.box_area0;
  st.box0 = s.box0;
  st.seed = s.seed;
  st.box_deformation = s.Fbox;
  st.strain = s.E;
  st.pair_i = s.pi;
  st.pair_j = s.pj;
  st.history = s.hist;
  st.aux = s.aux;
  st.wall_history = s.whist;
  st.wall_f_n = s.wfn_c;
  st.f_n = s.fn_c;
  st.f_t = s.ft_c;
  st.sliding = s.slide_c;
  st.box_deformation_build = s.F_build;
  st.periodic = s.periodic();
  if (st.periodic) {
    st.cell = s.cell_vectors;
    st.shift = s.shift;
    st.pinned = s.pinned;
  }
  st.f_contact = s.f_c;
  st.du_prev = s.du_prev;
  st.dE_prev = s.dE_prev;
  st.timings = s.tim;
  return st;
}

/// The 3D state: sizes, order and finiteness (the 2D state below checks the 2D file's fields).
namespace {
/// No entry of a state's box deformation may exceed this in magnitude: compaction shrinks the box
/// and a probe stretches it by e^|E| <= e; a 1e300 or 2^64 entry (robustness campaign, issue 27)
/// passed the density check and reached the analytic yield surface as null.
constexpr double kMaxBoxStretch = 1e3;

/// The periodic fields of a state: shifts per row only in a periodic cell, a held particle, cell
/// numbers D x D or none (the cell's measure is checked by the caller's box-area check).
template <class State, typename Bad>
void check_periodic(const State& st, std::size_t n, std::size_t np, const Bad& bad) {
  if (!st.periodic) {
    if (!st.shift.empty() || !st.cell.empty() || st.pinned != -1) bad("periodic-cell fields in a state without a periodic cell");
    return;
  }
  if (st.shift.size() != np) bad(fmt::format("{} periodic images for {} pairs", st.shift.size(), np));
  if (st.pinned < 0 || static_cast<std::size_t>(st.pinned) >= n) bad(fmt::format("held particle {} is not in [0, {})", st.pinned, n));
  const std::size_t d = st.shift.empty() ? 0 : st.shift.front().size();
  if (!st.cell.empty() && st.cell.size() != d * d && d != 0) bad(fmt::format("{} cell numbers", st.cell.size()));
  for (double v : st.cell)
    if (!std::isfinite(v)) bad("a non-finite cell vector");
  for (const auto& sh : st.shift)
    for (int v : sh)
      if (v < -1000000 || v > 1000000) bad(fmt::format("a periodic image {} cells away", v));
}

template <int D, typename Bad>
void check_box_stretch(const Eigen::Matrix<double, D, D>& F, const Bad& bad) {
  if (!(F.cwiseAbs().maxCoeff() <= kMaxBoxStretch))
    bad(fmt::format("box deformation entry {} is beyond {:g} in magnitude", F.cwiseAbs().maxCoeff(), kMaxBoxStretch));
}
}  // namespace

template <int D, class H>
void NetworkStateT<D, H>::validate() const {
  auto bad = [](const std::string& m) { throw std::invalid_argument("network state: " + m); };
  constexpr std::size_t kN = contact::Dim<D>::kNodeDofs;
  const std::size_t n = particles.size(), np = pair_i.size();
  if (n == 0) bad("no particles");
  if (particles.pos.size() != D * n || particles.rot.size() != contact::Dim<D>::kRotDofs * n ||
      peripheral.size() != n || pos_build.size() != D * n || f_contact.size() != kN * n ||
      (!du_prev.empty() && du_prev.size() != kN * n))
    bad(fmt::format("per-particle arrays do not all have {} entries", n));
  if (pair_j.size() != np || history.size() != np || aux.size() != np || f_n.size() != np || f_t.size() != np ||
      sliding.size() != np)
    bad(fmt::format("per-pair arrays do not all have {} entries", np));
  if ((!wall_history.empty() && wall_history.size() != 2 * D * n) || wall_f_n.size() != wall_history.size())
    bad(fmt::format("the wall-contact arrays must be empty or have {} x {} entries", 2 * D, n));
  check_periodic(*this, n, np, bad);
  for (std::size_t k = 0; k < np; ++k) {
    const int i = pair_i[k], j = pair_j[k];
    if (i < 0 || j <= i || static_cast<std::size_t>(j) >= n) bad(fmt::format("pair {} ({}, {}) is not i < j < N", k, i, j));
    if (k > 0 && !(std::make_pair(pair_i[k - 1], pair_j[k - 1]) < std::make_pair(i, j)))
      bad(fmt::format("pairs are not sorted at pair {}", k));
  }
  for (const auto* v : {&particles.pos, &particles.rot, &particles.r, &pos_build, &f_contact, &du_prev, &f_n})
    for (const double d : *v)
      if (!std::isfinite(d)) bad("a non-finite value");
  if (!(solid_area > 0 && box_area0 > 0 && initial_density > 0)) bad("solid and box measures must be positive");
  if (!box_deformation.allFinite() || !(box_deformation.determinant() > 0.0) || !strain.allFinite())
    bad("box deformation must be finite with a positive determinant");
  check_box_stretch(box_deformation, bad);
}

#ifndef NETDEM_QS_MORE  // (a specialisation: compiled once, with the 2D solver)
void NetworkStateT<2>::validate() const {
  auto bad = [](const std::string& m) { throw std::invalid_argument("network state: " + m); };
  const std::size_t n = x.size(), np = pair_i.size();
  if (n == 0) bad("no particles");
  if (y.size() != n || theta.size() != n || r.size() != n || peripheral.size() != n || x_build.size() != n ||
      y_build.size() != n || f_contact.size() != 3 * n || (!du_prev.empty() && du_prev.size() != 3 * n))
    bad(fmt::format("per-particle arrays do not all have {} entries", n));
  if (pair_j.size() != np || history.size() != np || aux.size() != np || f_n.size() != np || f_t.size() != np ||
      sliding.size() != np)
    bad(fmt::format("per-pair arrays do not all have {} entries", np));
  if ((!wall_history.empty() && wall_history.size() != 4 * n) || wall_f_n.size() != wall_history.size())
    bad(fmt::format("the wall-contact arrays must be empty or have 4 x {} entries", n));
  check_periodic(*this, n, np, bad);
  for (std::size_t p = 0; p < n; ++p) {
    if (!(std::isfinite(x[p]) && std::isfinite(y[p]) && std::isfinite(theta[p]) && std::isfinite(x_build[p]) &&
          std::isfinite(y_build[p])))
      bad(fmt::format("particle {} has a non-finite coordinate", p));
    if (!(std::isfinite(r[p]) && r[p] > 0.0)) bad(fmt::format("particle {} has radius {}", p, r[p]));
    if (peripheral[p] > 1) bad(fmt::format("particle {} has peripheral flag {}", p, peripheral[p]));
  }
  for (std::size_t k = 0; k < np; ++k) {
    const int i = pair_i[k], j = pair_j[k];
    if (i < 0 || j <= i || static_cast<std::size_t>(j) >= n) bad(fmt::format("pair {} ({}, {}) is not i < j < N", k, i, j));
    if (k > 0 && !(std::make_pair(pair_i[k - 1], pair_j[k - 1]) < std::make_pair(i, j)))
      bad(fmt::format("pairs are not sorted at pair {}", k));
    if (!(std::isfinite(history[k].u_max) && history[k].u_max >= 0.0 && std::isfinite(history[k].f_t) &&
          history[k].sliding <= 1 && std::isfinite(f_n[k]) && f_n[k] >= 0.0 && std::isfinite(f_t[k]) && sliding[k] <= 1 &&
          aux[k].E_form.allFinite() && std::isfinite(aux[k].slip) && std::isfinite(aux[k].centre)))
      bad(fmt::format("pair {} ({}, {}) has an invalid history", k, i, j));
  }
  for (const double v : f_contact)
    if (!std::isfinite(v)) bad("non-finite committed contact force");
  for (const double v : du_prev)
    if (!std::isfinite(v)) bad("non-finite predictor");
  if (!(std::isfinite(solid_area) && solid_area > 0 && std::isfinite(box_area0) && box_area0 > 0 &&
        std::isfinite(initial_density) && initial_density > 0))
    bad("solid area, box area and initial density must be positive");
  {  // the recorded sums agree with the particles and the box they were made from
    auto near = [](double a, double b) { return std::fabs(a - b) <= 1e-9 * std::fabs(b); };
    double area = 0.0;
    for (const double rp : r) area += std::numbers::pi * rp * rp;
    if (!near(solid_area, area))
      bad(fmt::format("the solid area {} is not the particles' sum pi r^2 = {}", solid_area, area));
    const double box_area = periodic && cell.size() == 4 ? std::fabs(cell[0] * cell[3] - cell[1] * cell[2])
                                                          : (box0.x_max - box0.x_min) * (box0.y_max - box0.y_min);
    if (!near(box_area0, box_area)) bad(fmt::format("the initial box area {} is not the initial box's {}", box_area0, box_area));
    if (!near(initial_density, solid_area / box_area0))
      bad(fmt::format("the initial density {} is not solid area / box area = {}", initial_density, solid_area / box_area0));
    const double density = solid_area / (box_area0 * box_deformation.determinant());
    if (!(density > 0.0 && density <= 1.0))
      bad(fmt::format("the density after the box deformation is {}, outside (0, 1]", density));
  }
  if (!(std::isfinite(box0.x_min) && std::isfinite(box0.y_min) && std::isfinite(box0.x_max) && std::isfinite(box0.y_max) &&
        box0.x_max > box0.x_min && box0.y_max > box0.y_min))
    bad("the initial box must be finite with positive size");
  if (!box_deformation.allFinite() || !(box_deformation.determinant() > 0.0) || !box_deformation_build.allFinite() ||
      !(box_deformation_build.determinant() > 0.0))
    bad("box deformation must be finite with a positive determinant");
  check_box_stretch(box_deformation, bad);
  check_box_stretch(box_deformation_build, bad);
  if (!strain.allFinite() || !dE_prev.allFinite()) bad("non-finite strain");
}
#endif

template <int D, class L>
const typename NetworkSolverT<D, L>::Options& NetworkSolverT<D, L>::options() const {
  return impl_->opt;
}
template <int D, class L>
const SolverTimings& NetworkSolverT<D, L>::timings() const {
  return impl_->tim;
}
template <int D, class L>
std::size_t NetworkSolverT<D, L>::size() const {
  return static_cast<std::size_t>(impl_->n);
}
template <int D, class L>
std::vector<double> NetworkSolverT<D, L>::x() const
  requires(D == 2)
{
  return impl_->ps.axis(0);
}
template <int D, class L>
std::vector<double> NetworkSolverT<D, L>::y() const
  requires(D == 2)
{
  return impl_->ps.axis(1);
}
template <int D, class L>
const std::vector<double>& NetworkSolverT<D, L>::theta() const
  requires(D == 2)
{
  return impl_->ps.rot;
}
template <int D, class L>
const std::vector<double>& NetworkSolverT<D, L>::radius() const {
  return impl_->ps.r;
}
template <int D, class L>
const sys::ParticleSet<D>& NetworkSolverT<D, L>::particles() const {
  return impl_->ps;
}
template <int D, class L>
const std::vector<std::uint8_t>& NetworkSolverT<D, L>::peripheral() const {
  return impl_->periph;
}
template <int D, class L>
typename NetworkSolverT<D, L>::Mat NetworkSolverT<D, L>::box_deformation() const {
  return impl_->Fbox;
}
template <int D, class L>
double NetworkSolverT<D, L>::solid_area() const {
  return impl_->solid_area;
}
template <int D, class L>
double NetworkSolverT<D, L>::initial_density() const {
  return impl_->D0;
}
template <int D, class L>
const packing::Box& NetworkSolverT<D, L>::initial_box() const {
  return impl_->box0;
}
template <int D, class L>
std::uint64_t NetworkSolverT<D, L>::seed() const {
  return impl_->seed;
}
template <int D, class L>
int NetworkSolverT<D, L>::free_dofs() const {
  return impl_->nfree;
}

// the plastic law (2D, 3D): netdem_quasistatic; the linear law: NETDEM_QS_MORE (CMakeLists.txt)
#ifndef NETDEM_QS_MORE
template class NetworkSolverT<2>;
template struct NetworkStateT<3>;
template class NetworkSolverT<3>;
#else
template struct NetworkStateT<2, LinearLawT<2>::History>;
template struct NetworkStateT<3, LinearLawT<3>::History>;
template class NetworkSolverT<2, LinearLawT<2>>;
template class NetworkSolverT<3, LinearLawT<3>>;
#endif

}  // namespace netdem::qs
