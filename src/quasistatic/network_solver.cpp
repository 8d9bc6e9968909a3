// NetworkSolver: construction from a packing or from a state, the copyable state, and the public
// accessors. The parts are listed in solver_impl.hpp.
#include "netdem/quasistatic/network_solver.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <numbers>
#include <stdexcept>
#include <string>

#include <fmt/format.h>

#include "netdem/packing/packing.hpp"
#include "solver_impl.hpp"

namespace netdem::qs {

void NetworkSolver::Impl::init_linear_solver() {
  LinearSolverOptions lo;
  lo.gmres_tolerance = opt.linear_tolerance;
  lin = LinearSolver(lo);
  r_mean = std::accumulate(ps.r.begin(), ps.r.end(), 0.0) / n;
  r_max = *std::max_element(ps.r.begin(), ps.r.end());
  DofMap::build(opt.mode, opt.rotations && opt.law.frictional(), periph);
  std::vector<int> particle_of_dof(static_cast<std::size_t>(nfree));
  for (int q = 0; q < 3 * n; ++q)
    if (dof[q] >= 0) particle_of_dof[dof[q]] = q / 3;
  lin.set_row_blocks(std::move(particle_of_dof));
  du.assign(3 * n, 0.0);
  f.assign(3 * n, 0.0);
}

void NetworkSolver::Impl::set_options(const SolverOptions& o) {
  opt = o;
  law = Law(o.law);
  contact::PlasticIndentationParams frictionless = o.law;
  frictionless.mu = 0.0;
  wall_law = Law(frictionless);
}

NetworkSolver::NetworkSolver(const packing::Packing& pk, const SolverOptions& options) : impl_(std::make_unique<Impl>()) {
  options.validate();
  if (pk.dim != 2) throw std::invalid_argument("network solver: the packing is 3D (dim 3); the network solver is 2D only");
  packing::validate(pk);
  auto& s = *impl_;
  s.set_options(options);
  s.n = static_cast<int>(pk.size());
  s.ps = sys::ParticleSet<2>::from_packing(pk);
  s.periph = packing::peripheral_layer(pk);
  s.solid_area = pk.solid_area();
  s.box_area0 = pk.box.area();
  s.box0 = pk.box;
  s.seed = pk.seed;
  s.D0 = s.solid_area / s.box_area0;
  s.init_linear_solver();
  s.f_c.assign(3 * s.n, 0.0);
  s.build_neighbours();
}

NetworkSolver::NetworkSolver(const NetworkState& st, const SolverOptions& options) : impl_(std::make_unique<Impl>()) {
  options.validate();
  st.validate();
  auto& s = *impl_;
  s.set_options(options);
  s.n = static_cast<int>(st.x.size());
  s.ps.pos.resize(2 * st.x.size());
  for (int p = 0; p < s.n; ++p) {
    s.ps.pos[2 * p] = st.x[p];
    s.ps.pos[2 * p + 1] = st.y[p];
  }
  s.ps.rot = st.theta;
  s.ps.r = st.r;
  s.periph = st.peripheral;
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
  s.hist = st.history;
  s.aux = st.aux;
  s.fn_c = st.f_n;
  s.ft_c = st.f_t;
  s.slide_c = st.sliding;
  s.pos_build.resize(2 * st.x.size());
  for (int p = 0; p < s.n; ++p) {
    s.pos_build[2 * p] = st.x_build[p];
    s.pos_build[2 * p + 1] = st.y_build[p];
  }
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

NetworkSolver::NetworkSolver(const NetworkSolver& other) : NetworkSolver(other.state(), other.options()) {}

NetworkSolver::~NetworkSolver() = default;

NetworkState NetworkSolver::state() const {
  const auto& s = *impl_;
  NetworkState st;
  st.x = s.ps.axis(0);
  st.y = s.ps.axis(1);
  st.theta = s.ps.rot;
  st.r = s.ps.r;
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
  st.x_build.resize(s.ps.size());
  st.y_build.resize(s.ps.size());
  for (std::size_t p = 0; p < s.ps.size(); ++p) {
    st.x_build[p] = s.pos_build[2 * p];
    st.y_build[p] = s.pos_build[2 * p + 1];
  }
  st.box_deformation_build = s.F_build;
  st.f_contact = s.f_c;
  st.du_prev = s.du_prev;
  st.dE_prev = s.dE_prev;
  st.timings = s.tim;
  return st;
}

void NetworkState::validate() const {
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
    const double box_area = (box0.x_max - box0.x_min) * (box0.y_max - box0.y_min);
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
  if (!strain.allFinite() || !dE_prev.allFinite()) bad("non-finite strain");
}

const SolverOptions& NetworkSolver::options() const { return impl_->opt; }
const SolverTimings& NetworkSolver::timings() const { return impl_->tim; }
std::size_t NetworkSolver::size() const { return static_cast<std::size_t>(impl_->n); }
std::vector<double> NetworkSolver::x() const { return impl_->ps.axis(0); }
std::vector<double> NetworkSolver::y() const { return impl_->ps.axis(1); }
const std::vector<double>& NetworkSolver::theta() const { return impl_->ps.rot; }
const std::vector<double>& NetworkSolver::radius() const { return impl_->ps.r; }
const sys::ParticleSet<2>& NetworkSolver::particles() const { return impl_->ps; }
const std::vector<std::uint8_t>& NetworkSolver::peripheral() const { return impl_->periph; }
Eigen::Matrix2d NetworkSolver::box_deformation() const { return impl_->Fbox; }
double NetworkSolver::solid_area() const { return impl_->solid_area; }
double NetworkSolver::initial_density() const { return impl_->D0; }
const packing::Box& NetworkSolver::initial_box() const { return impl_->box0; }
std::uint64_t NetworkSolver::seed() const { return impl_->seed; }
int NetworkSolver::free_dofs() const { return impl_->nfree; }

}  // namespace netdem::qs
