// Explicit DEM solver: particles, time step rule, construction (see solver.hpp, docs/dynamic.md).
#include "netdem/dynamic/solver.hpp"
#include "solver_detail.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <type_traits>

#include <Eigen/Eigenvalues>
#include <fmt/format.h>

#include "netdem/contact/luding_law.hpp"

namespace netdem::dem {

using detail::displacement_limit;
using detail::fail;

namespace {
// The walled readers refuse a periodic packing (issue 29): its centres near a face touch the
// particles at the opposite face, which a box would not see.
void refuse_periodic(const packing::Packing& pk) {
  if (pk.periodic)
    fail("the packing is periodic (its '# periodic' line): a box with walls would cut the contacts across its faces; "
         "run it in a periodic cell");
}
}  // namespace

template <int D>
ParticlesT<D> periodic_particles_from(const packing::Packing& pk, double rho) {
  if (!pk.periodic) fail("periodic_particles_from: the packing is not periodic (no '# periodic' line)");
  if (pk.dim != D) fail(fmt::format("periodic_particles_from: the packing is {}D, the particles {}D", pk.dim, D));
  if (!(rho > 0.0) || !std::isfinite(rho)) fail("periodic_particles_from: the density must be positive and finite");
  ParticlesT<D> P;
  for (std::size_t i = 0; i < pk.size(); ++i) {
    if constexpr (D == 3)
      P.add_sphere(pk.x[i], pk.y[i], pk.z[i], pk.r[i], rho);
    else
      P.add_disk(pk.x[i], pk.y[i], pk.r[i], rho);
  }
  return P;
}
template Particles periodic_particles_from<2>(const packing::Packing&, double);
template Particles3 periodic_particles_from<3>(const packing::Packing&, double);

Particles3 spheres_from(const packing::Packing& pk, double rho) {
  refuse_periodic(pk);
  if (pk.dim != 3) fail("spheres_from: the packing is 2D");
  if (!(rho > 0.0) || !std::isfinite(rho)) fail("spheres_from: the density must be positive and finite");
  Particles3 P;
  for (std::size_t i = 0; i < pk.size(); ++i) P.add_sphere(pk.x[i], pk.y[i], pk.z[i], pk.r[i], rho);
  return P;
}

Particles particles_from(const packing::Packing& pk, const LudingParams& params) {
  refuse_periodic(pk);
  if (pk.dim != 2) throw std::invalid_argument("dem: the packing is 3D (dim 3); the DEM is 2D only");
  Particles P;
  for (std::size_t i = 0; i < pk.size(); ++i) P.add(pk.x[i], pk.y[i], pk.r[i], params);
  return P;
}

Particles particles_from(const packing::Packing& pk, double rho) {
  refuse_periodic(pk);
  if (!(rho > 0.0) || !std::isfinite(rho)) fail("particles_from: the density must be positive and finite");
  Particles P;
  for (std::size_t i = 0; i < pk.size(); ++i) P.add_disk(pk.x[i], pk.y[i], pk.r[i], rho);
  return P;
}

template <int D>
packing::Packing to_packing(const ParticlesT<D>& P, const packing::Box& box) {
  packing::Packing pk;
  pk.dim = D;
  pk.x = P.axis(0);
  pk.y = P.axis(1);
  if constexpr (D == 3) pk.z = P.axis(2);
  pk.r = P.r;
  pk.box = box;
  return pk;
}
template packing::Packing to_packing(const Particles&, const packing::Box&);
template packing::Packing to_packing(const Particles3&, const packing::Box&);

void DynamicOptions::validate() const {
  if (!(steps_per_contact > 0.0)) fail("DynamicOptions: steps_per_contact must be > 0");
  if (!(min_steps_per_contact >= 0.0)) fail("DynamicOptions: min_steps_per_contact must be >= 0");
  if (!(dt >= 0.0)) fail("DynamicOptions: dt must be >= 0 (0 = from the rule)");
  if (!(skin >= 0.0)) fail("DynamicOptions: skin must be >= 0 (0 = 0.3 mean radius)");
  if (check_every < 0) fail("DynamicOptions: check_every must be >= 0 (0 = no instability checks)");
  if (threads < 1 || threads > 256) fail("DynamicOptions: threads must be in [1, 256]");
}

double contact_duration(double k2, double gamma0, double m12) {
  const double eta0 = gamma0 / (2.0 * m12);
  double w2 = k2 / m12 - eta0 * eta0;       // LMM05 Eq 6
  if (!(w2 > 0.0)) w2 = k2 / m12;           // over-damped: undamped omega (stricter)
  return std::numbers::pi / std::sqrt(w2);  // LMM05 Eq 6: t_c = pi / omega
}

namespace {
// The two lightest masses (m_lo <= m_lo2) of the particles.
void lightest_pair(const std::vector<double>& mass, double& m_lo, double& m_lo2) {
  m_lo = m_lo2 = mass[0];
  if (mass.size() < 2) return;
  m_lo = std::min(mass[0], mass[1]);
  m_lo2 = std::max(mass[0], mass[1]);
  for (std::size_t i = 2; i < mass.size(); ++i) {
    const double m = mass[i];
    if (m < m_lo) {
      m_lo2 = m_lo;
      m_lo = m;
    } else if (m < m_lo2) {
      m_lo2 = m;
    }
  }
}
}  // namespace

namespace {
// The half period pi / omega of a spring k on the mass m: with a dashpot gamma, Eq 6
// (contact_duration); without, pi sqrt(m / k).
double period(double k, double gamma, double m) {
  return gamma > 0.0 ? contact_duration(k, gamma, m) : std::numbers::pi * std::sqrt(m / k);
}
}  // namespace

double tangential_period(double m_eff, double k_t, int dim) {
  // the tangential effective mass with the rotations (dim.hpp): m*/3 for disks, 2/7 m* for spheres
  return dim == 3 ? std::numbers::pi * std::sqrt(m_eff * contact::kTangentialMassRatio<3> / k_t)
                  : std::numbers::pi * std::sqrt(m_eff / 3.0 / k_t);
}

template <int D>
TimeStepInfo choose_time_step(const ParticlesT<D>& P, const contact::StiffnessBound& b, bool mean_pair,
                              const DynamicOptions& o, double area_max) {
  o.validate();
  const std::size_t n = P.size();
  if (n == 0) fail("choose_time_step: no particles");
  if (!(b.k_n > 0.0) || !std::isfinite(b.k_n))
    fail(fmt::format("the contact law's largest normal stiffness {:g} is not a positive finite bound for an explicit "
                     "time step (the plastic law: a first-touch overlap > 0)",
                     b.k_n));
  double mean = 0.0, m_lo = 0.0, m_lo2 = 0.0;
  for (double m : P.mass) mean += m;
  mean /= static_cast<double>(n);
  lightest_pair(P.mass, m_lo, m_lo2);
  const double m12 = m_lo * m_lo2 / (m_lo + m_lo2);
  TimeStepInfo ts;
  ts.tc_mean = period(b.k_n, b.gamma_n, 0.5 * mean);
  ts.tc_lightest = period(b.k_n, b.gamma_n, m12);
  // the pair of the rule: its normal and tangential periods set dt; the lightest pair's are checked
  const bool use_mean = mean_pair && o.rule == TimeStepRule::MeanPair;
  const double tc_rule = use_mean ? ts.tc_mean : ts.tc_lightest;
  const double kt = b.k_t + b.k_t_area * area_max;
  const double tc_t_rule = kt > 0.0 ? tangential_period(use_mean ? 0.5 * mean : m12, kt, D) : 0.0;
  if (kt > 0.0) ts.tc_tangential = tangential_period(m12, kt, D);
  const double tc = tc_t_rule > 0.0 ? std::min(tc_rule, tc_t_rule) : tc_rule;
  const double tc_check = ts.tc_tangential > 0.0 ? std::min(ts.tc_lightest, ts.tc_tangential) : ts.tc_lightest;
  ts.dt = o.dt > 0.0 ? o.dt : tc / o.steps_per_contact;  // LMM05 section 3.1.2: t_MD = pi / (50 omega)
  ts.steps_per_contact_lightest = tc_check / ts.dt;
  if (ts.steps_per_contact_lightest < o.min_steps_per_contact)
    fail(fmt::format("time step {:.6g} gives the lightest pair {:.3g} steps per contact (its shorter period t_c = "
                     "{:.6g}), fewer than {:g}",
                     ts.dt, ts.steps_per_contact_lightest, tc_check, o.min_steps_per_contact));
  return ts;
}
template TimeStepInfo choose_time_step(const Particles&, const contact::StiffnessBound&, bool, const DynamicOptions&,
                                       double);
template TimeStepInfo choose_time_step(const Particles3&, const contact::StiffnessBound&, bool, const DynamicOptions&,
                                       double);

template <int D>
void DynamicSolverT<D>::choose_time_step_of_law(const DynamicOptions& o, double area) {
  double r_max = 0.0;
  for (double r : P_.r) r_max = std::max(r_max, r);
  visit_law([&](const auto& law) {
    bound_ = law.stiffness_bound(r_max);
    mean_pair_ = contact::kMeanPairTimeStep<std::decay_t<decltype(law)>>;
  });
  ts_ = choose_time_step(P_, bound_, mean_pair_, o, area);
}

namespace {
// The options of a Luding run (its model one of the Luding feature sets) and of a plastic one.
const DynamicOptions& luding_options(const DynamicOptions& o) {
  if (o.model == ContactModel::PlasticIndentation)
    fail("DynamicSolver: the plastic-indentation law takes its own parameters (PlasticIndentationParams), not the "
         "Luding law's");
  return o;
}
DynamicOptions plastic_options(DynamicOptions o, const contact::PlasticIndentationParams& law) {
  o.model = ContactModel::PlasticIndentation;
  o.plastic = law;
  return o;
}
}  // namespace

template <int D>
DynamicSolverT<D>::DynamicSolverT(ParticlesT<D> particles, const LudingParams& params, const Box& box,
                                  const DynamicOptions& options)
    : DynamicSolverT(std::move(particles), params, box, luding_options(options), Setup{}) {}

template <int D>
DynamicSolverT<D>::DynamicSolverT(ParticlesT<D> particles, const contact::PlasticIndentationParams& law, const Box& box,
                                  const DynamicOptions& options)
    : DynamicSolverT(std::move(particles), LudingParams{}, box, plastic_options(options, law), Setup{}) {}

namespace {
// The box of a periodic run: the measurement domain only (no contact walls), fixed walls (the cell
// moves with the strain rate).
template <int D>
Box periodic_box(const packing::PeriodicCellT<D>& cell) {
  for (int a = 0; a < D; ++a)
    for (int b = 0; b < D; ++b)
      if (!std::isfinite(cell.h(a, b))) fail("DynamicSolver: the periodic cell's vectors must be finite");
  if (!(cell.h.determinant() > 0.0))
    fail("DynamicSolver: the periodic cell's vectors must span a positive area (volume), det h > 0");
  Box b;
  b.contact_walls = false;
  b.x_min = b.x_max = cell.origin(0);
  b.y_min = b.y_max = cell.origin(1);
  if constexpr (D == 3) b.z_min = b.z_max = cell.origin(2);
  return b;  // (its extents: set_box_to_cell())
}
}  // namespace

template <int D>
DynamicSolverT<D>::DynamicSolverT(ParticlesT<D> particles, const LudingParams& params,
                                  const packing::PeriodicCellT<D>& cell, const DynamicOptions& options)
    : DynamicSolverT(std::move(particles), params, periodic_box(cell), luding_options(options), Setup{&cell}) {}

template <int D>
DynamicSolverT<D>::DynamicSolverT(ParticlesT<D> particles, const contact::PlasticIndentationParams& law,
                                  const packing::PeriodicCellT<D>& cell, const DynamicOptions& options)
    : DynamicSolverT(std::move(particles), LudingParams{}, periodic_box(cell), plastic_options(options, law),
                     Setup{&cell}) {}

template <int D>
DynamicSolverT<D>::DynamicSolverT(ParticlesT<D> particles, const LudingParams& params, const Box& box,
                                  const DynamicOptions& options, Setup setup)
    : P_(std::move(particles)), params_(params), box_(box), opt_(options) {
  params_.validate();
  opt_.validate();
  // (-0 + 0 = +0: no force accumulator starts at -0, so a thread adding a skipped row's +0 share
  // leaves it as one thread does; solver_threads.hpp)
  opt_.gravity_x += 0.0, opt_.gravity_y += 0.0, opt_.gravity_z += 0.0;
  if (setup.cell) {
    periodic_ = true;
    cell_ = *setup.cell;
    set_box_to_cell();
  }
  const std::size_t n = P_.size();
  if (n >= (std::size_t{1} << 32)) fail("DynamicSolver: too many particles");
  if (!P_.consistent()) fail("DynamicSolver: inconsistent particle arrays");
  if constexpr (D == 3) {
    if (box_.enabled && !(box_.z_max > box_.z_min)) fail("DynamicSolver: a 3D box must have z_max > z_min");
  }
  if (box_.enabled && !(box_.x_max > box_.x_min && box_.y_max > box_.y_min))
    fail("DynamicSolver: box must have x_max > x_min and y_max > y_min");
  for (std::size_t i = 0; i < n; ++i)
    if (!(P_.r[i] > 0.0) || !(P_.mass[i] > 0.0) || !(P_.inertia[i] > 0.0))
      fail("DynamicSolver: particle " + std::to_string(i) + " has a non-positive radius or mass");
  for (const MovingWall* w : {&box_.right, &box_.top, &box_.back})
    if (w->mode == WallMode::Stress && !(w->mass > 0.0 && w->damping >= 0.0))
      fail("DynamicSolver: a stress-controlled wall needs mass > 0 and damping >= 0");
  thermal_ = contact::luding_thermal_start(params_, opt_.temperature);
  if (plastic()) opt_.plastic.validate();
  choose_time_step_of_law(opt_, 0.0);
  // The given radii are a(T_radius_ref) (Eq 9); the full law starts at a(T).
  radius_ref_ = P_.r;
  if (opt_.model == ContactModel::Full) {
    radius_scale_ = contact::luding_radius(params_, 1.0, thermal_.T);
    for (std::size_t i = 0; i < n; ++i) {
      P_.r[i] = radius_ref_[i] * radius_scale_;
      P_.inertia[i] = contact::Dim<D>::kInertia * P_.mass[i] * P_.r[i] * P_.r[i];
    }
  }
  for (int a = 0; a < D; ++a) {
    const MovingWall& w = moving_wall(a);
    wall_v_[a] = w.mode == WallMode::Strain ? w.velocity : 0.0;
  }
  centre0_[0] = 0.5 * (box_.x_min + box_.x_max);
  centre0_[1] = 0.5 * (box_.y_min + box_.y_max);
  if constexpr (D == 3) centre0z_ = 0.5 * (box_.z_min + box_.z_max);
  make_tables(n);
  finish_setup();
  if (periodic_) {
    for (double x : P_.pos)
      if (!std::isfinite(x)) fail("DynamicSolver: a particle position is not finite");
    double rmax = 0.0;
    for (double r : P_.r) rmax = std::max(rmax, r);
    if (n >= 2 && !(cell_.min_width() >= 2.0 * (2.0 * rmax + skin_)))
      fail(fmt::format("DynamicSolver: the periodic cell is {:.4g} wide across an axis, less than twice the largest "
                       "interaction range 2 r_max + skin = {:.4g} (a pair would meet through two images)",
                       cell_.min_width(), 2.0 * rmax + skin_));
  }
  build_table();
  compute_forces_dispatch();
}

template <int D>
void DynamicSolverT<D>::finish_setup() {
  const std::size_t n = P_.size();
  wall_params_ = params_.wall_params();
  pl_wall_params_ = opt_.plastic;
  pl_wall_params_.mu = opt_.plastic_wall_mu;
  if (n > 0) {
    double m_lo = 0.0, m_lo2 = 0.0, mean = 0.0;
    lightest_pair(P_.mass, m_lo, m_lo2);
    m12_ = m_lo * m_lo2 / (m_lo + m_lo2);
    for (double m : P_.mass) mean += m;
    mean /= static_cast<double>(n);
    m_rule_ = mean_pair_ && opt_.rule == TimeStepRule::MeanPair ? 0.5 * mean : m12_;
  }
  choose_friction();
  double rmean = 0.0;
  radius_ref_max_ = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    rmean += radius_ref_[i];
    radius_ref_max_ = std::max(radius_ref_max_, radius_ref_[i]);
  }
  rmean /= static_cast<double>(std::max<std::size_t>(n, 1));
  skin_ = opt_.skin > 0.0 ? opt_.skin : 0.3 * rmean;
  radius_scale_build_ = radius_scale_;
}

template <int D>
void DynamicSolverT<D>::choose_friction() {
  if (plastic())
    friction_ = opt_.plastic.mu > 0.0 || (walls_active() && opt_.plastic_wall_mu > 0.0);
  else
    friction_ = params_.mu > 0.0 || (walls_active() && params_.mu_wall > 0.0);
}

template DynamicSolverT<2>::DynamicSolverT(Particles particles, const LudingParams& params, const Box& box, const DynamicOptions& options);
template DynamicSolverT<2>::DynamicSolverT(Particles particles, const contact::PlasticIndentationParams& law, const Box& box, const DynamicOptions& options);
template DynamicSolverT<2>::DynamicSolverT(Particles particles, const LudingParams& params, const Box& box, const DynamicOptions& options, Setup);
template DynamicSolverT<2>::DynamicSolverT(Particles, const LudingParams&, const packing::PeriodicCellT<2>&, const DynamicOptions&);
template DynamicSolverT<2>::DynamicSolverT(Particles, const contact::PlasticIndentationParams&, const packing::PeriodicCellT<2>&, const DynamicOptions&);
template void DynamicSolverT<2>::finish_setup();
template void DynamicSolverT<2>::choose_friction();
template void DynamicSolverT<2>::choose_time_step_of_law(const DynamicOptions& o, double area);

template DynamicSolverT<3>::DynamicSolverT(Particles3 particles, const LudingParams& params, const Box& box, const DynamicOptions& options);
template DynamicSolverT<3>::DynamicSolverT(Particles3 particles, const contact::PlasticIndentationParams& law, const Box& box, const DynamicOptions& options);
template DynamicSolverT<3>::DynamicSolverT(Particles3 particles, const LudingParams& params, const Box& box, const DynamicOptions& options, Setup);
template DynamicSolverT<3>::DynamicSolverT(Particles3, const LudingParams&, const packing::PeriodicCellT<3>&, const DynamicOptions&);
template DynamicSolverT<3>::DynamicSolverT(Particles3, const contact::PlasticIndentationParams&, const packing::PeriodicCellT<3>&, const DynamicOptions&);
template void DynamicSolverT<3>::finish_setup();
template void DynamicSolverT<3>::choose_friction();
template void DynamicSolverT<3>::choose_time_step_of_law(const DynamicOptions& o, double area);

}  // namespace netdem::dem
