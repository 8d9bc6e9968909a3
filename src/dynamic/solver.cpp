// Explicit DEM solver, LMM05 Eq 1, 2, 6 (see solver.hpp and docs/dynamic.md).
#include "netdem/dynamic/solver.hpp"

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

namespace {
using contact::LudingFeatures;
constexpr LudingFeatures kHysteretic{true, false, false, true};
constexpr LudingFeatures kLinearFrictionless{false, false, false, false};
constexpr LudingFeatures kHystereticFrictionless{true, false, false, false};
constexpr LudingFeatures kFullFrictionless{true, true, true, false};

[[noreturn]] void fail(const std::string& msg) { throw std::invalid_argument(msg); }

}  // namespace

std::size_t Particles::add_with_mass(double px, double py, double r, double m, double pvx, double pvy,
                                     double pomega) {
  if (dim != 2) fail("Particles: a disk cannot join spheres");
  x.push_back(px);
  y.push_back(py);
  vx.push_back(pvx);
  vy.push_back(pvy);
  omega.push_back(pomega);
  theta.push_back(0.0);
  radius.push_back(r);
  mass.push_back(m);
  inertia.push_back(0.5 * m * r * r);
  fx.push_back(0.0);
  fy.push_back(0.0);
  torque.push_back(0.0);
  return x.size() - 1;
}

std::size_t Particles::add(double px, double py, double r, const LudingParams& p, double pvx, double pvy,
                           double pomega) {
  return add_with_mass(px, py, r, contact::luding_mass(p, r), pvx, pvy, pomega);
}

std::size_t Particles::add_disk(double px, double py, double r, double rho, double pvx, double pvy,
                                double pomega) {
  return add_with_mass(px, py, r, rho * std::numbers::pi * r * r, pvx, pvy, pomega);
}

std::size_t Particles::add_sphere_with_mass(double px, double py, double pz, double r, double m,
                                            const std::array<double, 3>& v, const std::array<double, 3>& w) {
  if (dim != 3 && !x.empty()) fail("Particles: a sphere cannot join disks");
  dim = 3;
  x.push_back(px);
  y.push_back(py);
  z.push_back(pz);
  vx.push_back(v[0]);
  vy.push_back(v[1]);
  vz.push_back(v[2]);
  wx.push_back(w[0]);
  wy.push_back(w[1]);
  omega.push_back(w[2]);
  theta.push_back(0.0);
  radius.push_back(r);
  mass.push_back(m);
  inertia.push_back(contact::Dim<3>::kInertia * m * r * r);
  fx.push_back(0.0);
  fy.push_back(0.0);
  fz.push_back(0.0);
  tx.push_back(0.0);
  ty.push_back(0.0);
  torque.push_back(0.0);
  return x.size() - 1;
}

std::size_t Particles::add_sphere(double px, double py, double pz, double r, double rho,
                                  const std::array<double, 3>& v) {
  return add_sphere_with_mass(px, py, pz, r, rho * (4.0 / 3.0) * std::numbers::pi * r * r * r, v);
}

Particles spheres_from(const packing::Packing& pk, double rho) {
  if (pk.dim != 3) fail("spheres_from: the packing is 2D");
  if (!(rho > 0.0) || !std::isfinite(rho)) fail("spheres_from: the density must be positive and finite");
  Particles P;
  P.dim = 3;
  for (std::size_t i = 0; i < pk.size(); ++i) P.add_sphere(pk.x[i], pk.y[i], pk.z[i], pk.r[i], rho);
  return P;
}

Particles particles_from(const packing::Packing& pk, const LudingParams& params) {
  if (pk.dim != 2) throw std::invalid_argument("dem: the packing is 3D (dim 3); the DEM is 2D only");
  Particles P;
  for (std::size_t i = 0; i < pk.size(); ++i) P.add(pk.x[i], pk.y[i], pk.r[i], params);
  return P;
}

Particles particles_from(const packing::Packing& pk, double rho) {
  if (!(rho > 0.0) || !std::isfinite(rho)) fail("particles_from: the density must be positive and finite");
  Particles P;
  for (std::size_t i = 0; i < pk.size(); ++i) P.add_disk(pk.x[i], pk.y[i], pk.r[i], rho);
  return P;
}

packing::Packing to_packing(const Particles& P, const packing::Box& box) {
  packing::Packing pk;
  pk.x = P.x;
  pk.y = P.y;
  pk.r = P.radius;
  pk.box = box;
  return pk;
}

void DynamicOptions::validate() const {
  if (!(steps_per_contact > 0.0)) fail("DynamicOptions: steps_per_contact must be > 0");
  if (!(min_steps_per_contact >= 0.0)) fail("DynamicOptions: min_steps_per_contact must be >= 0");
  if (!(dt >= 0.0)) fail("DynamicOptions: dt must be >= 0 (0 = from the rule)");
  if (!(skin >= 0.0)) fail("DynamicOptions: skin must be >= 0 (0 = 0.3 mean radius)");
  if (check_every < 0) fail("DynamicOptions: check_every must be >= 0 (0 = no instability checks)");
}

double contact_duration(double k2, double gamma0, double m12) {
  const double eta0 = gamma0 / (2.0 * m12);
  double w2 = k2 / m12 - eta0 * eta0;       // LMM05 Eq 6
  if (!(w2 > 0.0)) w2 = k2 / m12;           // over-damped: undamped omega (stricter)
  return std::numbers::pi / std::sqrt(w2);  // LMM05 Eq 6: t_c = pi / omega
}

namespace {
// The two lightest masses (m_lo <= m_lo2) of the particles.
void lightest_pair(const Particles& P, double& m_lo, double& m_lo2) {
  m_lo = m_lo2 = P.mass[0];
  if (P.size() < 2) return;
  m_lo = std::min(P.mass[0], P.mass[1]);
  m_lo2 = std::max(P.mass[0], P.mass[1]);
  for (std::size_t i = 2; i < P.size(); ++i) {
    const double m = P.mass[i];
    if (m < m_lo) {
      m_lo2 = m_lo;
      m_lo = m;
    } else if (m < m_lo2) {
      m_lo2 = m;
    }
  }
}
}  // namespace

TimeStepInfo choose_time_step(const Particles& P, const LudingParams& p, const DynamicOptions& o) {
  o.validate();
  const std::size_t n = P.size();
  if (n == 0) fail("choose_time_step: no particles");
  double mean = 0.0, m_lo = 0.0, m_lo2 = 0.0;
  for (double m : P.mass) mean += m;
  mean /= static_cast<double>(n);
  lightest_pair(P, m_lo, m_lo2);
  TimeStepInfo ts;
  // k2 is the largest stiffness of the law (cap of Eq 7); gamma_0 of Eq 5.
  ts.tc_mean = contact_duration(p.k2, p.gamma_n, 0.5 * mean);
  ts.tc_lightest = contact_duration(p.k2, p.gamma_n, m_lo * m_lo2 / (m_lo + m_lo2));
  if (o.dt > 0.0) {
    ts.dt = o.dt;
  } else {
    const double tc = o.rule == TimeStepRule::MeanPair ? ts.tc_mean : ts.tc_lightest;
    ts.dt = tc / o.steps_per_contact;  // LMM05 section 3.1.2: t_MD = pi / (50 omega)
  }
  ts.steps_per_contact_lightest = ts.tc_lightest / ts.dt;
  if (ts.steps_per_contact_lightest < o.min_steps_per_contact) {
    std::ostringstream s;
    s << "time step " << ts.dt << " s gives the lightest pair " << ts.steps_per_contact_lightest
      << " steps per contact (t_c = " << ts.tc_lightest << " s), fewer than "
      << o.min_steps_per_contact;
    fail(s.str());
  }
  return ts;
}


TimeStepInfo plastic_time_step(const Particles& P, const contact::PlasticIndentationParams& law,
                               const DynamicOptions& o, double area_max) {
  o.validate();
  law.validate();
  if (P.size() == 0) fail("plastic_time_step: no particles");
  if (!(law.first_touch > 0.0))
    fail("the explicit solver needs the plastic law's first-touch overlap > 0 (Eq 2 has an infinite stiffness "
         "at first touch)");
  double m_lo, m_lo2, mean = 0.0;
  lightest_pair(P, m_lo, m_lo2);
  for (double m : P.mass) mean += m;
  mean /= static_cast<double>(P.size());
  const double m12 = m_lo * m_lo2 / (m_lo + m_lo2);
  // the stiffest normal branch: the first-touch chord, times unload_ratio on the elastic branch
  // (3D: the loading stiffness 6 pi sigma_y R* with the largest R*, a wall contact's r_max)
  double r_max = 0.0;
  for (double r : P.radius) r_max = std::max(r_max, r);
  const double kn = (P.dim == 3 ? law.chord_stiffness_3d(r_max) : law.chord_stiffness()) *
                    (law.reversible ? 1.0 : law.unload_ratio);
  TimeStepInfo ts;
  ts.tc_mean = std::numbers::pi * std::sqrt(0.5 * mean / kn);
  ts.tc_lightest = std::numbers::pi * std::sqrt(m12 / kn);
  const double kt = law.frictional() ? law.shear_stiffness() * area_max : 0.0;
  ts.tc_tangential = kt > 0.0 ? (P.dim == 3 ? std::numbers::pi * std::sqrt(m12 * contact::kTangentialMassRatio<3> / kt)
                                            : std::numbers::pi * std::sqrt(m12 / 3.0 / kt))
                              : 0.0;
  const double tc = ts.tc_tangential > 0.0 ? std::min(ts.tc_lightest, ts.tc_tangential) : ts.tc_lightest;
  ts.dt = o.dt > 0.0 ? o.dt : tc / o.steps_per_contact;
  ts.steps_per_contact_lightest = tc / ts.dt;
  if (ts.steps_per_contact_lightest < o.min_steps_per_contact)
    fail(fmt::format("time step {:.6g} gives the stiffest contact {:.3g} steps per period (t_c = {:.6g}), fewer "
                     "than {:g}",
                     ts.dt, ts.steps_per_contact_lightest, tc, o.min_steps_per_contact));
  return ts;
}

template <int D>
DynamicSolverT<D>::DynamicSolverT(Particles particles, const LudingParams& params, const Box& box,
                                  const DynamicOptions& options)
    : P_(std::move(particles)), params_(params), box_(box), opt_(options) {
  params_.validate();
  opt_.validate();
  const std::size_t n = P_.size();
  if (n >= (std::size_t{1} << 32)) fail("DynamicSolver: too many particles");
  if (P_.dim != D) fail(fmt::format("DynamicSolver: the particles are {}D, the solver {}D", P_.dim, D));
  if constexpr (D == 3) {
    if (box_.enabled && !(box_.z_max > box_.z_min)) fail("DynamicSolver: a 3D box must have z_max > z_min");
    if (!(P_.z.size() == n && P_.vz.size() == n && P_.fz.size() == n && P_.wx.size() == n && P_.wy.size() == n &&
          P_.tx.size() == n && P_.ty.size() == n))
      fail("DynamicSolver: inconsistent 3D particle arrays");
  }
  if (box_.enabled && !(box_.x_max > box_.x_min && box_.y_max > box_.y_min))
    fail("DynamicSolver: box must have x_max > x_min and y_max > y_min");
  for (std::size_t i = 0; i < n; ++i)
    if (!(P_.radius[i] > 0.0) || !(P_.mass[i] > 0.0) || !(P_.inertia[i] > 0.0))
      fail("DynamicSolver: particle " + std::to_string(i) + " has a non-positive radius or mass");
  for (const MovingWall* w : {&box_.right, &box_.top, &box_.back})
    if (w->mode == WallMode::Stress && !(w->mass > 0.0 && w->damping >= 0.0))
      fail("DynamicSolver: a stress-controlled wall needs mass > 0 and damping >= 0");
  ts_ = plastic() ? plastic_time_step(P_, opt_.plastic, opt_, 0.0) : choose_time_step(P_, params_, opt_);
  thermal_ = contact::luding_thermal_start(params_, opt_.temperature);
  // The given radii are a(T_radius_ref) (Eq 9); the full law starts at a(T).
  radius_ref_ = P_.radius;
  if (opt_.model == ContactModel::Full) {
    radius_scale_ = contact::luding_radius(params_, 1.0, thermal_.T);
    for (std::size_t i = 0; i < n; ++i) {
      P_.radius[i] = radius_ref_[i] * radius_scale_;
      P_.inertia[i] = contact::Dim<D>::kInertia * P_.mass[i] * P_.radius[i] * P_.radius[i];
    }
  }
  for (int a = 0; a < D; ++a) {
    const MovingWall& w = moving_wall(a);
    wall_v_[a] = w.mode == WallMode::Strain ? w.velocity : 0.0;
  }
  centre0_[0] = 0.5 * (box_.x_min + box_.x_max);
  centre0_[1] = 0.5 * (box_.y_min + box_.y_max);
  if constexpr (D == 3) centre0z_ = 0.5 * (box_.z_min + box_.z_max);
  if (plastic())
    pl_wall_hist_.assign(kWalls * n, PlasticHist{});
  else
    wall_hist_.assign(kWalls * n, LudingHist{});
  finish_setup();
  build_table();
  compute_forces_dispatch();
}

template <int D>
void DynamicSolverT<D>::finish_setup() {
  const std::size_t n = P_.size();
  wall_params_ = params_.wall_params();
  pl_wall_params_ = opt_.plastic;
  pl_wall_params_.mu = opt_.plastic_wall_mu;
  if (plastic() && n > 0) {
    double m_lo = 0.0, m_lo2 = 0.0;
    lightest_pair(P_, m_lo, m_lo2);
    pl_m12_ = m_lo * m_lo2 / (m_lo + m_lo2);
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

// ---- the history stores: one per law family; the model's is used, the other stays empty --------
namespace {
template <int D>
inline bool is_fresh(const contact::LudingHistoryT<D>& h) { return h.fresh(); }
template <int D>
inline bool is_fresh(const contact::PlasticIndentationHistoryT<D>& h) {
  return h.u_max == 0.0 && contact::tan_is_zero(h.f_t) && h.sliding == 0;
}
}  // namespace
template <int D>
template <class H>
std::vector<H>& DynamicSolverT<D>::pair_histories() {
  if constexpr (std::is_same_v<H, LudingHist>) {
    return pair_hist_;
  } else {
    return pl_pair_hist_;
  }
}
template <int D>
template <class H>
std::vector<H>& DynamicSolverT<D>::new_histories() {
  if constexpr (std::is_same_v<H, LudingHist>) {
    return new_hist_;
  } else {
    return pl_new_hist_;
  }
}
template <int D>
template <class H>
std::vector<H>& DynamicSolverT<D>::wall_histories() {
  if constexpr (std::is_same_v<H, LudingHist>) {
    return wall_hist_;
  } else {
    return pl_wall_hist_;
  }
}

// The committed histories of the pairs that stay in the table (pair_key_ and new_key_ sorted).
template <int D>
template <class H>
void DynamicSolverT<D>::carry_histories(std::size_t n_new) {
  std::vector<H>& old_h = pair_histories<H>();
  std::vector<H>& new_h = new_histories<H>();
  new_h.assign(n_new, H{});
  std::size_t a = 0;
  for (std::size_t b = 0; b < n_new; ++b) {
    while (a < pair_key_.size() && pair_key_[a] < new_key_[b]) ++a;
    if (a < pair_key_.size() && pair_key_[a] == new_key_[b]) {
      new_h[b] = old_h[a];
      pair_live_[b] = is_fresh(new_h[b]) ? 0 : 1;
    }
  }
  old_h.swap(new_h);
}

// ---- neighbour search: cell list + Verlet table ------------------------------------------------
namespace {
// Two particles each moving d and each growing by g (Eq 9) close a gap by 2 d + 2 g: the table
// (range r_i + r_j + skin at the build) stays complete while d < skin / 2 - g. Returns that limit
// on d (<= 0: rebuild now).
double displacement_limit(double skin, double radius_ref_max, double scale, double scale_build) {
  const double grow = radius_ref_max * std::max(0.0, scale - scale_build);
  return 0.5 * skin - grow;
}
}  // namespace

template <int D>
bool DynamicSolverT<D>::needs_rebuild() const {
  const double lim =
      displacement_limit(skin_, radius_ref_max_, radius_scale_, radius_scale_build_);
  if (!(lim > 0.0) || walls_moved()) return true;
  const double lim2 = lim * lim;
  for (std::size_t i = 0; i < P_.size(); ++i) {
    const double dx = P_.x[i] - x_build_[i], dy = P_.y[i] - y_build_[i];
    double d2 = dx * dx + dy * dy;
    if constexpr (D == 3) {
      const double dz = P_.z[i] - z_build_[i];
      d2 += dz * dz;
    }
    if (d2 > lim2) return true;
  }
  return false;
}

// Wall candidates: particles within a_i + skin of a wall. Any other particle's wall histories
// are cleared here (it does not touch a wall, so the next evaluation would clear them anyway).
template <int D>
void DynamicSolverT<D>::build_wall_list() {
  const std::size_t n = P_.size();
  wall_list_.clear();
  wall_list_valid_ = walls_active();
  if (!walls_active()) return;
  box_build_[0] = box_.x_min;
  box_build_[1] = box_.x_max;
  box_build_[2] = box_.y_min;
  box_build_[3] = box_.y_max;
  if constexpr (D == 3) {
    box_build_[4] = box_.z_min;
    box_build_[5] = box_.z_max;
  }
  constexpr std::uint8_t kAll = (1u << kWalls) - 1u;
  if (wall_touch_.size() != n) wall_touch_.assign(n, kAll);
  for (std::size_t i = 0; i < n; ++i) {
    const double xi = P_.x[i], yi = P_.y[i], reach = P_.radius[i] + skin_;
    bool near = xi - box_.x_min < reach || box_.x_max - xi < reach ||
                yi - box_.y_min < reach || box_.y_max - yi < reach;
    if constexpr (D == 3) near = near || P_.z[i] - box_.z_min < reach || box_.z_max - P_.z[i] < reach;
    if (near) {
      wall_list_.push_back(static_cast<std::uint32_t>(i));
      wall_touch_[i] = kAll;  // the next evaluation visits its wall histories
    } else if (wall_touch_[i] != 0) {
      if (plastic())
        for (std::size_t w = 0; w < kWalls; ++w) pl_wall_hist_[kWalls * i + w] = PlasticHist{};
      else
        for (std::size_t w = 0; w < kWalls; ++w) wall_hist_[kWalls * i + w] = LudingHist{};
      wall_touch_[i] = 0;
    }
  }
}

template <int D>
bool DynamicSolverT<D>::walls_moved() const {
  if (!walls_active()) return false;
  const double lim = 0.5 * skin_;
  bool stay = std::fabs(box_.x_min - box_build_[0]) < lim && std::fabs(box_.x_max - box_build_[1]) < lim &&
              std::fabs(box_.y_min - box_build_[2]) < lim && std::fabs(box_.y_max - box_build_[3]) < lim;
  if constexpr (D == 3)
    stay = stay && std::fabs(box_.z_min - box_build_[4]) < lim && std::fabs(box_.z_max - box_build_[5]) < lim;
  return !stay;
}

template <int D>
void DynamicSolverT<D>::build_table() {
  const std::size_t n = P_.size();
  ++rebuilds_;
  radius_scale_build_ = radius_scale_;
  x_build_ = P_.x;
  y_build_ = P_.y;
  if constexpr (D == 3) z_build_ = P_.z;
  build_wall_list();
  new_key_.clear();
  if (n >= 2) {
    double rmax = 0.0;
    for (std::size_t i = 0; i < n; ++i) rmax = std::max(rmax, P_.radius[i]);
    // cell side >= largest interaction range 2 rmax + skin (3 x 3 cells per query); <= ~4 n cells
    if constexpr (D == 2) {
      grid_.rebuild(P_.x, P_.y, 2.0 * rmax + skin_);
      for (std::size_t i = 0; i < n; ++i) {
        const double xi = P_.x[i], yi = P_.y[i], ri = P_.radius[i];
        grid_.for_each_near(xi, yi, ri + rmax + skin_, [&](std::uint32_t j) {
          if (j <= i) return;
          const double dx = P_.x[j] - xi, dy = P_.y[j] - yi;
          const double range = ri + P_.radius[j] + skin_;
          if (dx * dx + dy * dy < range * range) new_key_.push_back((static_cast<std::uint64_t>(i) << 32) | j);
        });
      }
    } else {  // 3 x 3 x 3 cells per query
      grid_.rebuild(P_.x, P_.y, P_.z, 2.0 * rmax + skin_);
      for (std::size_t i = 0; i < n; ++i) {
        const double xi = P_.x[i], yi = P_.y[i], zi = P_.z[i], ri = P_.radius[i];
        grid_.for_each_near(xi, yi, zi, ri + rmax + skin_, [&](std::uint32_t j) {
          if (j <= i) return;
          const double dx = P_.x[j] - xi, dy = P_.y[j] - yi, dz = P_.z[j] - zi;
          const double range = ri + P_.radius[j] + skin_;
          if (dx * dx + dy * dy + dz * dz < range * range)
            new_key_.push_back((static_cast<std::uint64_t>(i) << 32) | j);
        });
      }
    }
    std::sort(new_key_.begin(), new_key_.end());
  }
  // carry the committed histories of the pairs that stay in the table (both lists sorted)
  pair_live_.assign(new_key_.size(), 0);
  if (plastic())
    carry_histories<PlasticHist>(new_key_.size());
  else
    carry_histories<LudingHist>(new_key_.size());
  pair_key_.swap(new_key_);
}

template <int D>
void DynamicSolverT<D>::touching_pairs(
    std::vector<std::pair<std::uint32_t, std::uint32_t>>& out) const {
  out.clear();
  for (std::uint64_t key : pair_key_) {
    const std::uint32_t i = static_cast<std::uint32_t>(key >> 32);
    const std::uint32_t j = static_cast<std::uint32_t>(key & 0xffffffffu);
    const double dx = P_.x[j] - P_.x[i], dy = P_.y[j] - P_.y[i];
    const double s = P_.radius[i] + P_.radius[j];
    double L2 = dx * dx + dy * dy;
    if constexpr (D == 3) L2 += (P_.z[j] - P_.z[i]) * (P_.z[j] - P_.z[i]);
    if (L2 < s * s) out.emplace_back(i, j);
  }
}

template <int D>
auto DynamicSolverT<D>::history(std::uint32_t i, std::uint32_t j) const -> const LudingHist* {
  const std::uint64_t key = (static_cast<std::uint64_t>(i) << 32) | j;
  auto it = std::lower_bound(pair_key_.begin(), pair_key_.end(), key);
  if (plastic() || it == pair_key_.end() || *it != key) return nullptr;
  return &pair_hist_[static_cast<std::size_t>(it - pair_key_.begin())];
}

template <int D>
auto DynamicSolverT<D>::plastic_history(std::uint32_t i, std::uint32_t j) const -> const PlasticHist* {
  const std::uint64_t key = (static_cast<std::uint64_t>(i) << 32) | j;
  auto it = std::lower_bound(pair_key_.begin(), pair_key_.end(), key);
  if (!plastic() || it == pair_key_.end() || *it != key) return nullptr;
  return &pl_pair_hist_[static_cast<std::size_t>(it - pair_key_.begin())];
}

// ---- forces ------------------------------------------------------------------------------------
template <int D>
template <LudingFeatures F>
void DynamicSolverT<D>::compute_forces_with() {
  if (opt_.reference_contact_path)
    compute_forces<contact::LudingLaw<F, D>, false>();
  else
    compute_forces<contact::LudingLaw<F, D>, true>();
}

template <int D>
void DynamicSolverT<D>::compute_forces_dispatch() {
  // once per step: the contact loop below is straight-line code for one law and feature set
  switch (opt_.model) {
    case ContactModel::Linear:
      if (friction_)
        compute_forces_with<contact::kLudingLinear>();
      else
        compute_forces_with<kLinearFrictionless>();
      break;
    case ContactModel::Hysteretic:
      if (friction_)
        compute_forces_with<kHysteretic>();
      else
        compute_forces_with<kHystereticFrictionless>();
      break;
    case ContactModel::Full:
      if (friction_)
        compute_forces_with<contact::kLudingFull>();
      else
        compute_forces_with<kFullFrictionless>();
      break;
    case ContactModel::PlasticIndentation:
      compute_forces<contact::PlasticIndentationLawT<D>, true>();
      break;
  }
}

namespace {
template <class Law>
constexpr bool kPlasticLaw = std::is_same_v<Law, contact::PlasticIndentationLawT<Law::kDim>>;
// The law object of a step: the plastic law from its parameters, the Luding law from its
// parameters and the material state k1(T, t).
template <class Law>
Law make_law(const LudingParams& lp, double k1_Tt, const contact::PlasticIndentationParams& pp) {
  if constexpr (kPlasticLaw<Law>)
    return Law(pp);
  else
    return Law(lp, k1_Tt);
}
}  // namespace

// The force loop of one contact law (law.hpp), chosen at compile time; InPlace = false evaluates
// the law instead of its in-place update (the same results to the last bit, tested). A law whose
// history outlives separation (plastic flattening) is evaluated for a separated pair that has a
// history; otherwise a separated pair's history is reset without calling the law.
// flatten: the law is inlined into the loop (with four call sites of luding_evaluate<F> in this
// translation unit, pair and wall loops times in-place and reference path, GCC stopped inlining
// it, which halved the speed of the full law: docs/performance.md "Issue 12").
template <int D>
template <class Law, bool InPlace>
[[gnu::flatten]] void DynamicSolverT<D>::compute_forces() {
  using H = typename Law::History;
  const std::size_t n = P_.size();
  const double dt = ts_.dt;
  const Law pair_law = make_law<Law>(params_, thermal_.k1_Tt, opt_.plastic);
  const Law wall_law = make_law<Law>(wall_params_, thermal_.k1_Tt, pl_wall_params_);
  std::vector<H>& pair_hist = pair_histories<H>();
  std::vector<H>& wall_hist = wall_histories<H>();
  double sxx = 0, sxy = 0, syx = 0, syy = 0, el = 0, fn_max = 0;
  double s3[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
  if (!forces_initialised_) {  // (step() does this in its first pass over the particles)
    for (std::size_t i = 0; i < n; ++i) {
      P_.fx[i] = P_.mass[i] * opt_.gravity_x;
      P_.fy[i] = P_.mass[i] * opt_.gravity_y;
      P_.torque[i] = 0.0;
      if constexpr (D == 3) {
        P_.fz[i] = P_.mass[i] * opt_.gravity_z;
        P_.tx[i] = P_.ty[i] = 0.0;
      }
    }
  }
  forces_initialised_ = false;
  // particle-particle contacts from the Verlet table
  const std::size_t n_pairs = pair_key_.size();
  if (pair_live_.size() != n_pairs) pair_live_.assign(n_pairs, 1);
  // the particle arrays, hoisted (the loop stores forces: the vectors' data pointers are not reloaded)
  const double* const p_x = P_.x.data();
  const double* const p_y = P_.y.data();
  const double* const p_z = P_.z.data();
  const double* const p_vx = P_.vx.data();
  const double* const p_vy = P_.vy.data();
  const double* const p_vz = P_.vz.data();
  const double* const p_wx = P_.wx.data();
  const double* const p_wy = P_.wy.data();
  const double* const p_omega = P_.omega.data();
  const double* const p_radius = P_.radius.data();
  double* const p_fx = P_.fx.data();
  double* const p_fy = P_.fy.data();
  double* const p_fz = P_.fz.data();
  double* const p_tx = P_.tx.data();
  double* const p_ty = P_.ty.data();
  double* const p_torque = P_.torque.data();
  for (std::size_t k = 0; k < n_pairs; ++k) {
    const std::size_t i = static_cast<std::size_t>(pair_key_[k] >> 32);
    const std::size_t j = static_cast<std::size_t>(pair_key_[k] & 0xffffffffu);
    const double dx = p_x[j] - p_x[i], dy = p_y[j] - p_y[i];
    const double ri = p_radius[i], rj = p_radius[j];
    double dz = 0.0;
    if constexpr (D == 3) dz = p_z[j] - p_z[i];
    const double L2 = D == 2 ? dx * dx + dy * dy : dx * dx + dy * dy + dz * dz, s = ri + rj;
    if (!(L2 < s * s)) {
      if constexpr (!Law::kHistoryOutlivesSeparation) {  // the law clears the history (docs/luding.md)
        if (pair_live_[k]) {
          pair_hist[k] = H{};
          pair_live_[k] = 0;
        }
        continue;
      } else if (!pair_live_[k]) {
        continue;  // apart and no history: no force, nothing to keep
      }
    }
    pair_live_[k] = 1;
    if constexpr (D == 2) {
      const double L = std::sqrt(L2), iL = 1.0 / L;
      const double nx = dx * iL, ny = dy * iL, tx = -ny, ty = nx;  // n from i to j, t = perp(n)
      const double q = (ri * ri - rj * rj) * (0.5 * iL);
      const double di = 0.5 * L + q, dj = 0.5 * L - q;  // centre-to-chord distances (kinematics.hpp)
      // velocity of j's contact point relative to i's: v_j - w_j d_j t - (v_i + w_i d_i t)
      const double rvx = p_vx[j] - p_vx[i], rvy = p_vy[j] - p_vy[i];
      const double vn = rvx * nx + rvy * ny;
      const double vt = rvx * tx + rvy * ty - p_omega[i] * di - p_omega[j] * dj;
      contact::ContactKinematics in;
      in.overlap = s - L;
      in.v_n = -vn;
      in.v_t = vt;
      in.dslip = vt * dt;
      in.dt = dt;
      if constexpr (kPlasticLaw<Law>) {  // (the Luding law reads neither)
        in.overlap_start = in.overlap - in.v_n * dt;
        in.r_eff = ri * rj / s;
        in.m_eff = P_.mass[i] * P_.mass[j] / (P_.mass[i] + P_.mass[j]);
      }
      double f_n, f_t;
      contact::update_contact<InPlace>(pair_law, pair_hist[k], in, f_n, f_t);
      if constexpr (Law::kHistoryOutlivesSeparation) pair_live_[k] = pair_law.has_history(pair_hist[k]) ? 1 : 0;
      if constexpr (kPlasticLaw<Law>) fn_max = f_n > fn_max ? f_n : fn_max;
      const double fx = f_n * nx + f_t * tx, fy = f_n * ny + f_t * ty;  // force on j
      p_fx[j] += fx;
      p_fy[j] += fy;
      p_fx[i] -= fx;
      p_fy[i] -= fy;
      p_torque[i] -= di * f_t;  // M_i = M_j = -d F_T (kinematics.hpp)
      p_torque[j] -= dj * f_t;
      sxx += fx * dx;  // Sigma = (1/V) sum f (x) l, l = x_j - x_i
      sxy += fx * dy;
      syx += fy * dx;
      syy += fy * dy;
      if constexpr (!kPlasticLaw<Law>) el += 0.5 * params_.k2 * in.overlap * in.overlap;
    } else {
      const double L = std::sqrt(L2), iL = 1.0 / L;
      const Eigen::Vector3d n(dx * iL, dy * iL, dz * iL);  // from i to j
      const double q = (ri * ri - rj * rj) * (0.5 * iL);
      const double di = 0.5 * L + q, dj = 0.5 * L - q;  // centre-to-contact-plane distances
      const Eigen::Vector3d vrel(p_vx[j] - p_vx[i], p_vy[j] - p_vy[i], p_vz[j] - p_vz[i]);
      const Eigen::Vector3d wi(p_wx[i], p_wy[i], p_omega[i]), wj(p_wx[j], p_wy[j], p_omega[j]);
      const Eigen::Vector3d W = di * wi + dj * wj;  // L x the pair's rotation rate (kinematics.hpp)
      // velocity of j's contact point relative to i's: v_j - v_i - (d_i w_i + d_j w_j) x n
      const double vn = vrel.dot(n);
      const Eigen::Vector3d vc = vrel - W.cross(n);
      const Eigen::Vector3d vt = vc - n * vc.dot(n);
      contact::Kinematics<3> in;
      in.overlap = s - L;
      in.v_n = -vn;
      in.v_t = vt;
      in.dslip = vt * dt;
      in.dt = dt;
      in.transport = contact::step_transport(n, (n.cross(vrel) + W.dot(n) * n) * (iL * dt));
      if constexpr (kPlasticLaw<Law>) {
        in.overlap_start = in.overlap - in.v_n * dt;
        in.r_eff = ri * rj / s;
        in.m_eff = P_.mass[i] * P_.mass[j] / (P_.mass[i] + P_.mass[j]);
      }
      double f_n;
      Eigen::Vector3d f_t;
      contact::update_contact<InPlace>(pair_law, pair_hist[k], in, f_n, f_t);
      if constexpr (Law::kHistoryOutlivesSeparation) pair_live_[k] = pair_law.has_history(pair_hist[k]) ? 1 : 0;
      if constexpr (kPlasticLaw<Law>) fn_max = f_n > fn_max ? f_n : fn_max;
      const Eigen::Vector3d f = f_n * n + f_t;  // on j
      p_fx[j] += f.x();
      p_fy[j] += f.y();
      p_fz[j] += f.z();
      p_fx[i] -= f.x();
      p_fy[i] -= f.y();
      p_fz[i] -= f.z();
      const Eigen::Vector3d m = n.cross(f_t);  // M_i = -d_i n x f_t, M_j = -d_j n x f_t
      p_tx[i] -= di * m.x();
      p_ty[i] -= di * m.y();
      p_torque[i] -= di * m.z();
      p_tx[j] -= dj * m.x();
      p_ty[j] -= dj * m.y();
      p_torque[j] -= dj * m.z();
      if constexpr (!kPlasticLaw<Law>) el += 0.5 * params_.k2 * in.overlap * in.overlap;
    }
  }
  if constexpr (D == 3) {
    // The pairs' part of Sigma V = sum_pairs f (x) (x_j - x_i) (f on j) is sum_i F_i (x) x_i, with
    // F_i the sum of the pair forces on i: one pass over the particles instead of one sum per
    // contact. F_i is the accumulator less the m g it started from (the same product), and x_i is
    // taken from the first particle (exactly translation invariant, and no cancellation of large
    // coordinates).
    const double* const p_mass = P_.mass.data();
    const double gx = opt_.gravity_x, gy = opt_.gravity_y, gz = opt_.gravity_z;
    const double x0 = n > 0 ? p_x[0] : 0.0, y0 = n > 0 ? p_y[0] : 0.0, z0 = n > 0 ? p_z[0] : 0.0;
    double s00 = 0, s01 = 0, s02 = 0, s10 = 0, s11 = 0, s12 = 0, s20 = 0, s21 = 0, s22 = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const double Fx = p_fx[i] - p_mass[i] * gx, Fy = p_fy[i] - p_mass[i] * gy, Fz = p_fz[i] - p_mass[i] * gz;
      const double X = p_x[i] - x0, Y = p_y[i] - y0, Z = p_z[i] - z0;
      s00 += Fx * X, s01 += Fx * Y, s02 += Fx * Z;
      s10 += Fy * X, s11 += Fy * Y, s12 += Fy * Z;
      s20 += Fz * X, s21 += Fz * Y, s22 += Fz * Z;
    }
    s3[0][0] = s00, s3[0][1] = s01, s3[0][2] = s02;
    s3[1][0] = s10, s3[1][1] = s11, s3[1][2] = s12;
    s3[2][0] = s20, s3[2][1] = s21, s3[2][2] = s22;
  }
  // walls: the pair (wall, particle), n from the wall into the box
  double wf[2 * D] = {};
  if (walls_active() && D == 2) {
    const double wnx[4] = {1, -1, 0, 0}, wny[4] = {0, 0, 1, -1};
    const double wvx[4] = {0, wall_v_[0], 0, 0}, wvy[4] = {0, 0, 0, wall_v_[1]};
    if (wall_touch_.size() != n) wall_touch_.assign(n, 0xF);
    if constexpr (D == 2) {
    // the candidates of the last build suffice unless a wall moved by skin/2 since (then all)
    const bool use_list = wall_list_valid_ && !walls_moved();
    const std::size_t n_visit = use_list ? wall_list_.size() : n;
    for (std::size_t c = 0; c < n_visit; ++c) {
      const std::size_t i = use_list ? wall_list_[c] : c;
      // distances to the four walls (= wn . (x - wall), exactly); skip the particle when it
      // overlaps no wall and touched none at the last evaluation (histories already fresh)
      const double xi = P_.x[i], yi = P_.y[i], ai = P_.radius[i];
      const double d4[4] = {xi - box_.x_min, box_.x_max - xi, yi - box_.y_min, box_.y_max - yi};
      const unsigned touch = (ai - d4[0] > 0.0 ? 1u : 0u) | (ai - d4[1] > 0.0 ? 2u : 0u) |
                             (ai - d4[2] > 0.0 ? 4u : 0u) | (ai - d4[3] > 0.0 ? 8u : 0u);
      const unsigned todo = touch | wall_touch_[i];
      wall_touch_[i] = static_cast<std::uint8_t>(touch);
      if (todo == 0) continue;
      for (int w = 0; w < 4; ++w) {
        if (!((todo >> w) & 1u)) continue;
        H& h = wall_hist[4 * i + static_cast<std::size_t>(w)];
        const double dist = d4[w];
        const double delta = ai - dist;
        if (!(delta > 0.0)) {
          if constexpr (!Law::kHistoryOutlivesSeparation) {
            h = H{};
            continue;
          } else if (!wall_law.has_history(h)) {
            continue;
          }
        }
        const double nx = wnx[w], ny = wny[w], tx = -ny, ty = nx;
        const double rvx = P_.vx[i] - wvx[w], rvy = P_.vy[i] - wvy[w];
        const double vn = rvx * nx + rvy * ny;
        const double vt = rvx * tx + rvy * ty - P_.omega[i] * dist;
        contact::ContactKinematics in;
        in.overlap = delta;
        in.v_n = -vn;
        in.v_t = vt;
        in.dslip = vt * dt;
        in.dt = dt;
        if constexpr (kPlasticLaw<Law>) {
          in.overlap_start = delta - in.v_n * dt;
          in.r_eff = ai;
          in.m_eff = P_.mass[i];
        }
        double f_n, f_t;
        contact::update_contact<InPlace>(wall_law, h, in, f_n, f_t);
        if constexpr (kPlasticLaw<Law>) fn_max = f_n > fn_max ? f_n : fn_max;
        const double fx = f_n * nx + f_t * tx, fy = f_n * ny + f_t * ty;  // on particle
        P_.fx[i] += fx;
        P_.fy[i] += fy;
        P_.torque[i] -= dist * f_t;
        wf[w] -= w < 2 ? fx : fy;  // force of the contacts on the wall along x (y)
        const double lx = dist * nx, ly = dist * ny;  // contact point -> particle centre
        sxx += fx * lx;
        sxy += fx * ly;
        syx += fy * lx;
        syy += fy * ly;
        if constexpr (!kPlasticLaw<Law>) el += 0.5 * wall_params_.k2 * delta * delta;
      }
    }
    }
  }
  if constexpr (D == 3) {
    if (walls_active()) {
      // wall w: axis a = w / 2; w even: the minimum (normal +e_a), odd: the maximum (normal -e_a,
      // moving at wall_v_[a])
      constexpr std::uint8_t kAll = (1u << kWalls) - 1u;
      if (wall_touch_.size() != n) wall_touch_.assign(n, kAll);
      const bool use_list = wall_list_valid_ && !walls_moved();
      const std::size_t n_visit = use_list ? wall_list_.size() : n;
      const double lo[3] = {box_.x_min, box_.y_min, box_.z_min}, hi[3] = {box_.x_max, box_.y_max, box_.z_max};
      for (std::size_t c = 0; c < n_visit; ++c) {
        const std::size_t i = use_list ? wall_list_[c] : c;
        const double pos[3] = {P_.x[i], P_.y[i], P_.z[i]}, ai = P_.radius[i];
        double d6[6];
        unsigned touch = 0;
        for (int w = 0; w < 6; ++w) {
          d6[w] = (w & 1) ? hi[w / 2] - pos[w / 2] : pos[w / 2] - lo[w / 2];
          touch |= ai - d6[w] > 0.0 ? (1u << w) : 0u;
        }
        const unsigned todo = touch | wall_touch_[i];
        wall_touch_[i] = static_cast<std::uint8_t>(touch);
        if (todo == 0) continue;
        const Eigen::Vector3d wi(P_.wx[i], P_.wy[i], P_.omega[i]);
        for (int w = 0; w < 6; ++w) {
          if (!((todo >> w) & 1u)) continue;
          H& h = wall_hist[kWalls * i + static_cast<std::size_t>(w)];
          const double dist = d6[w];
          const double delta = ai - dist;
          if (!(delta > 0.0)) {
            if constexpr (!Law::kHistoryOutlivesSeparation) {
              h = H{};
              continue;
            } else if (!wall_law.has_history(h)) {
              continue;
            }
          }
          const int ax = w / 2;
          Eigen::Vector3d nw = Eigen::Vector3d::Zero();
          nw(ax) = (w & 1) ? -1.0 : 1.0;
          Eigen::Vector3d vrel(P_.vx[i], P_.vy[i], P_.vz[i]);
          if (w & 1) vrel(ax) -= wall_v_[ax];
          const double vn = vrel.dot(nw);
          const Eigen::Vector3d vc = vrel - dist * wi.cross(nw);  // the particle's contact point
          const Eigen::Vector3d vt = vc - nw * vc.dot(nw);
          contact::Kinematics<3> in;
          in.overlap = delta;
          in.v_n = -vn;
          in.v_t = vt;
          in.dslip = vt * dt;
          in.dt = dt;
          in.transport = contact::step_transport(nw, wi.dot(nw) * dt * nw);  // the twist; n is fixed
          if constexpr (kPlasticLaw<Law>) {
            in.overlap_start = delta - in.v_n * dt;
            in.r_eff = ai;
            in.m_eff = P_.mass[i];
          }
          double f_n;
          Eigen::Vector3d f_t;
          contact::update_contact<InPlace>(wall_law, h, in, f_n, f_t);
          if constexpr (kPlasticLaw<Law>) fn_max = f_n > fn_max ? f_n : fn_max;
          const Eigen::Vector3d f = f_n * nw + f_t;  // on the particle
          P_.fx[i] += f.x();
          P_.fy[i] += f.y();
          P_.fz[i] += f.z();
          const Eigen::Vector3d m = nw.cross(f_t);  // -dist n x f_t
          P_.tx[i] -= dist * m.x();
          P_.ty[i] -= dist * m.y();
          P_.torque[i] -= dist * m.z();
          wf[w] -= f(ax);  // the force of the contacts on the wall along its axis
          const Eigen::Vector3d l = dist * nw;  // contact point -> particle centre
          for (int r = 0; r < 3; ++r)
            for (int cc = 0; cc < 3; ++cc) s3[r][cc] += f(r) * l(cc);
          if constexpr (!kPlasticLaw<Law>) el += 0.5 * wall_params_.k2 * delta * delta;
        }
      }
    }
  }
  for (int w = 0; w < kWalls; ++w) wall_force_[w] = wf[w];
  if constexpr (kPlasticLaw<Law>) area_max_ = fn_max / (3.0 * opt_.plastic.sigma_y);
  sxx_ = sxx;
  sxy_ = sxy;
  syx_ = syx;
  syy_ = syy;
  if constexpr (D == 3) std::copy(&s3[0][0], &s3[0][0] + 9, &s3_[0][0]);
  elastic_ = el;
}

// ---- integration: velocity Verlet, LMM05 Eq 2 and Eq 1 ------------------------------------------
namespace {
// Half kick v += h f / m, omega += h tau / I (with the inverses), on distinct arrays (restrict:
// the loops vectorise without alias checks).
// Track (the steps of an instability check only): also returns max vx^2 + vy^2 after the kick
// (NaN if a velocity is NaN), so that the check needs no pass of its own over the velocities.
template <bool Track>
double kick_pass(std::size_t n, double h, double* __restrict vx, double* __restrict vy,
                 double* __restrict om, const double* __restrict fx, const double* __restrict fy,
                 const double* __restrict tq, const double* __restrict im,
                 const double* __restrict iI) {
  double vmax2 = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    vx[i] += h * fx[i] * im[i];
    vy[i] += h * fy[i] * im[i];
    om[i] += h * tq[i] * iI[i];
    if constexpr (Track) {
      const double v2 = vx[i] * vx[i] + vy[i] * vy[i];
      vmax2 = v2 <= vmax2 ? vmax2 : v2;  // a NaN replaces the maximum and stays
    }
  }
  return vmax2;
}
// First half kick and drift in one pass; also the table check (displacement since the build
// beyond sqrt(lim2): returns 1) and the reset of the force accumulators to m g for the coming
// force evaluation.
template <bool Gravity>
int kick_drift_pass_impl(std::size_t n, double h, double dt, double lim2, double* __restrict vx,
                         double* __restrict vy, double* __restrict om, double* __restrict x,
                         double* __restrict y, double* __restrict th, double* __restrict fx,
                         double* __restrict fy, double* __restrict tq,
                         const double* __restrict im, const double* __restrict iI,
                         const double* __restrict xb, const double* __restrict yb,
                         const double* __restrict m, double gx, double gy) {
  int moved = 0;
  for (std::size_t i = 0; i < n; ++i) {
    vx[i] += h * fx[i] * im[i];
    vy[i] += h * fy[i] * im[i];
    om[i] += h * tq[i] * iI[i];
    x[i] += dt * vx[i];  // drift
    y[i] += dt * vy[i];
    th[i] += dt * om[i];
    const double ddx = x[i] - xb[i], ddy = y[i] - yb[i];
    moved |= ddx * ddx + ddy * ddy > lim2 ? 1 : 0;
    fx[i] = Gravity ? m[i] * gx : 0.0;
    fy[i] = Gravity ? m[i] * gy : 0.0;
    tq[i] = 0.0;
  }
  return moved;
}
template <bool Gravity>
int kick_drift_pass(std::size_t n, double h, double dt, double lim2, Particles& P,
                    const double* im, const double* iI, const double* xb, const double* yb,
                    double gx, double gy) {
  return kick_drift_pass_impl<Gravity>(n, h, dt, lim2, P.vx.data(), P.vy.data(), P.omega.data(),
                                       P.x.data(), P.y.data(), P.theta.data(), P.fx.data(),
                                       P.fy.data(), P.torque.data(), im, iI, xb, yb,
                                       P.mass.data(), gx, gy);
}
// 3D: the same passes over (x, y, z), the spin vector (wx, wy, omega) and the torque (tx, ty,
// torque); spheres have an isotropic inertia, so the spin kick is h tau / I per component.
template <bool Track>
double kick_pass3(std::size_t n, double h, Particles& P, const double* __restrict im, const double* __restrict iI) {
  double* __restrict vx = P.vx.data();
  double* __restrict vy = P.vy.data();
  double* __restrict vz = P.vz.data();
  double* __restrict wx = P.wx.data();
  double* __restrict wy = P.wy.data();
  double* __restrict wz = P.omega.data();
  const double* __restrict fx = P.fx.data();
  const double* __restrict fy = P.fy.data();
  const double* __restrict fz = P.fz.data();
  const double* __restrict tx = P.tx.data();
  const double* __restrict ty = P.ty.data();
  const double* __restrict tz = P.torque.data();
  double vmax2 = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    vx[i] += h * fx[i] * im[i];
    vy[i] += h * fy[i] * im[i];
    vz[i] += h * fz[i] * im[i];
    wx[i] += h * tx[i] * iI[i];
    wy[i] += h * ty[i] * iI[i];
    wz[i] += h * tz[i] * iI[i];
    if constexpr (Track) {
      const double v2 = vx[i] * vx[i] + vy[i] * vy[i] + vz[i] * vz[i];
      vmax2 = v2 <= vmax2 ? vmax2 : v2;
    }
  }
  return vmax2;
}
int kick_drift_pass3(std::size_t n, double h, double dt, double lim2, Particles& P, const double* __restrict im,
                     const double* __restrict iI, const double* __restrict xb, const double* __restrict yb,
                     const double* __restrict zb, double gx, double gy, double gz) {
  kick_pass3<false>(n, h, P, im, iI);
  int moved = 0;
  double* __restrict x = P.x.data();
  double* __restrict y = P.y.data();
  double* __restrict z = P.z.data();
  const double* __restrict vx = P.vx.data();
  const double* __restrict vy = P.vy.data();
  const double* __restrict vz = P.vz.data();
  const double* __restrict m = P.mass.data();
  for (std::size_t i = 0; i < n; ++i) {
    x[i] += dt * vx[i];  // drift
    y[i] += dt * vy[i];
    z[i] += dt * vz[i];
    const double ddx = x[i] - xb[i], ddy = y[i] - yb[i], ddz = z[i] - zb[i];
    moved |= ddx * ddx + ddy * ddy + ddz * ddz > lim2 ? 1 : 0;
    P.fx[i] = m[i] * gx;
    P.fy[i] = m[i] * gy;
    P.fz[i] = m[i] * gz;
    P.tx[i] = P.ty[i] = P.torque[i] = 0.0;
  }
  return moved;
}
}  // namespace

// ContactModel::PlasticIndentation: the tangential bound k_t sigma_y A_c grows with the contact
// width; the step follows it (with 10 % margin for the growth within a step).
template <int D>
void DynamicSolverT<D>::update_plastic_time_step() {
  const contact::PlasticIndentationParams& law = opt_.plastic;
  const double kt = law.frictional() ? law.shear_stiffness() * 1.1 * area_max_ : 0.0;
  if (kt <= 0.0) return;
  const double m12 = pl_m12_;
  if constexpr (D == 2) {
    ts_.tc_tangential = std::numbers::pi * std::sqrt(m12 / 3.0 / kt);
  } else {  // the sphere's tangential mass m* 2/7 (dim.hpp)
    ts_.tc_tangential = std::numbers::pi * std::sqrt(m12 * contact::kTangentialMassRatio<3> / kt);
  }
  const double tc = std::min(ts_.tc_lightest, ts_.tc_tangential);
  if (opt_.dt > 0.0) {
    ts_.steps_per_contact_lightest = tc / ts_.dt;
    if (ts_.steps_per_contact_lightest < opt_.min_steps_per_contact)
      breach("time step",
             fmt::format("the fixed time step {:.4g} gives the stiffest tangential spring {:.3g} steps per period, "
                         "fewer than {:g}",
                         ts_.dt, ts_.steps_per_contact_lightest, opt_.min_steps_per_contact),
             "the contacts grew stiffer than the fixed time step allows (--dt; let the rule choose it)");
    return;
  }
  ts_.dt = tc / opt_.steps_per_contact;
  ts_.steps_per_contact_lightest = opt_.steps_per_contact;
}

template <int D>
void DynamicSolverT<D>::step() {
  const std::size_t n = P_.size();
  if (plastic()) update_plastic_time_step();
  impose_affine_motion(ts_.dt);
  const bool checking = opt_.check_every > 0;
  if (checking && !last_good_) last_good_ = std::make_shared<const SolverState>(state());
  const bool check = checking && ++since_check_ >= opt_.check_every;
  ++since_good_;
  double vmax2 = 0.0;
  const double dt = ts_.dt, h = 0.5 * dt;
  // Eq 1 total wall forces at the current state: F_w - p z - gamma_w x'
  auto wall_accel = [&](int which) {
    if constexpr (D == 2) {
      const MovingWall& w = which == 0 ? box_.right : box_.top;
      if (w.mode != WallMode::Stress) return 0.0;
      const double z = which == 0 ? box_.y_max - box_.y_min : box_.x_max - box_.x_min;
      const double Fw = which == 0 ? wall_force_[1] : wall_force_[3];
      return (Fw - w.pressure * z - w.damping * wall_v_[which]) / w.mass;  // LMM05 Eq 1
    } else {  // Eq 1 with the wall's current area
      const MovingWall& w = moving_wall(which);
      if (w.mode != WallMode::Stress) return 0.0;
      const double e[3] = {box_.x_max - box_.x_min, box_.y_max - box_.y_min, box_.z_max - box_.z_min};
      const double A = e[(which + 1) % 3] * e[(which + 2) % 3];
      return (wall_force_[2 * which + 1] - w.pressure * A - w.damping * wall_v_[which]) / w.mass;
    }
  };
  if (inv_mass_.size() != n || inv_scale_ != radius_scale_) {  // no division in the kicks
    inv_mass_.resize(n);
    inv_inertia_.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      inv_mass_[i] = 1.0 / P_.mass[i];
      inv_inertia_[i] = 1.0 / P_.inertia[i];
    }
    for (std::uint32_t p : prescribed_) {  // the kicks leave them
      inv_mass_[p] = 0.0;
      if (spin_held_[p]) inv_inertia_[p] = 0.0;
    }
    if (!rotations_) std::fill(inv_inertia_.begin(), inv_inertia_.end(), 0.0);
    inv_scale_ = radius_scale_;
  }
  // half-step kick of particles and moving walls; the damping term of Eq 1 is taken at the
  // half-step wall velocity (explicit)
  // (the first kick, the drift, the table check and the reset of the force accumulators to m g
  // share one pass over the particles)
  const double lim = displacement_limit(skin_, radius_ref_max_, radius_scale_, radius_scale_build_);
  const double lim2 = lim * lim;
  bool far = !(lim > 0.0);
  auto kick = [&](bool drift) {
    if constexpr (D == 3) {
      if (drift) {
        far = far || kick_drift_pass3(n, h, dt, lim2, P_, inv_mass_.data(), inv_inertia_.data(), x_build_.data(),
                                      y_build_.data(), z_build_.data(), opt_.gravity_x, opt_.gravity_y,
                                      opt_.gravity_z) != 0;
        forces_initialised_ = true;
      } else if (check) {
        vmax2 = kick_pass3<true>(n, h, P_, inv_mass_.data(), inv_inertia_.data());
      } else {
        kick_pass3<false>(n, h, P_, inv_mass_.data(), inv_inertia_.data());
      }
      if (box_.enabled)
        for (int a = 0; a < 3; ++a) wall_v_[a] += h * wall_accel(a);
      return;
    }
    if (drift) {
      const bool gravity = opt_.gravity_x != 0.0 || opt_.gravity_y != 0.0;
      const int moved =
          gravity ? kick_drift_pass<true>(n, h, dt, lim2, P_, inv_mass_.data(), inv_inertia_.data(),
                                          x_build_.data(), y_build_.data(), opt_.gravity_x,
                                          opt_.gravity_y)
                  : kick_drift_pass<false>(n, h, dt, lim2, P_, inv_mass_.data(),
                                           inv_inertia_.data(), x_build_.data(), y_build_.data(),
                                           0.0, 0.0);
      far = far || moved != 0;
      forces_initialised_ = true;
    } else if (check) {
      vmax2 = kick_pass<true>(n, h, P_.vx.data(), P_.vy.data(), P_.omega.data(), P_.fx.data(),
                              P_.fy.data(), P_.torque.data(), inv_mass_.data(), inv_inertia_.data());
    } else {
      kick_pass<false>(n, h, P_.vx.data(), P_.vy.data(), P_.omega.data(), P_.fx.data(),
                       P_.fy.data(), P_.torque.data(), inv_mass_.data(), inv_inertia_.data());
    }
    if (box_.enabled) {
      const double a0 = wall_accel(0), a1 = wall_accel(1);
      wall_v_[0] += h * a0;
      wall_v_[1] += h * a1;
    }
  };
  kick(true);
  if (box_.enabled) {
    box_.x_max += dt * wall_v_[0];
    box_.y_max += dt * wall_v_[1];
    if constexpr (D == 3) box_.z_max += dt * wall_v_[2];
  }
  time_ += dt;
  if (far || walls_moved()) build_table();
  compute_forces_dispatch();  // forces use the half-step velocities for the damping terms
  if (opt_.affine_drag > 0.0) apply_affine_drag();
  kick(false);
  if (check) {
    since_check_ = 0;
    check_health_with(vmax2);
    if (since_good_ >= HealthLimits::kLastGoodEvery) {
      last_good_ = std::make_shared<const SolverState>(state());
      since_good_ = 0;
    }
  }
}

// ---- macroscopic strain rate: prescribed particles, affine walls, drag -----------------------------
template <int D>
void DynamicSolverT<D>::set_strain_rate(double e11, double e22, double e12) {
  if constexpr (D == 3) throw std::logic_error("set_strain_rate is 2D only (issue 16, 3D first part)");
  if (!std::isfinite(e11) || !std::isfinite(e22) || !std::isfinite(e12)) fail("set_strain_rate: the strain rate must be finite");
  if (!box_.enabled) fail("set_strain_rate: the affine field needs a box (its lower-left corner is x_0)");
  if (e12 != 0.0 && walls_active())
    fail("set_strain_rate: a shear rate (e12 != 0) needs a box without contact walls (the walls stay axis-aligned)");
  edot_[0] = e11;
  edot_[1] = e22;
  edot_[2] = e12;
  sheared_ = sheared_ || e12 != 0.0;
}

template <int D>
void DynamicSolverT<D>::set_strain_rate3(double e11, double e22, double e33, double e23, double e13, double e12) {
  if constexpr (D == 2) {
    (void)e11, (void)e22, (void)e33, (void)e23, (void)e13, (void)e12;
    fail("set_strain_rate3: a 2D solver takes set_strain_rate(e11, e22, e12)");
  } else {
    for (double v : {e11, e22, e33, e23, e13, e12})
      if (!std::isfinite(v)) fail("set_strain_rate3: the strain rate must be finite");
    if (!box_.enabled) fail("set_strain_rate3: the affine field needs a box (its lower corner is x_0)");
    const bool shear = e23 != 0.0 || e13 != 0.0 || e12 != 0.0;
    if (shear && walls_active())
      fail("set_strain_rate3: a shear rate (e23, e13 or e12 != 0) needs a box without contact walls (the walls stay "
           "axis-aligned)");
    edot3_[0] = e11;
    edot3_[1] = e22;
    edot3_[2] = e33;
    const double L[3][3] = {{e11, e12, e13}, {e12, e22, e23}, {e13, e23, e33}};
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) L3_[a][b] = L[a][b];
    shear3_ = shear;
    sheared3_ = sheared3_ || shear;
    if (shear) {  // exp(L dt) - I = V diag(expm1(lambda dt)) V^T in impose_affine_motion
      Eigen::Matrix3d M;
      M << e11, e12, e13, e12, e22, e23, e13, e23, e33;
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(M);
      for (int a = 0; a < 3; ++a) {
        eig_l3_[a] = es.eigenvalues()(a);
        for (int b = 0; b < 3; ++b) eig_v3_[3 * a + b] = es.eigenvectors()(a, b);
      }
    }
  }
}

template <int D>
void DynamicSolverT<D>::set_affine_velocities() {
  if constexpr (D == 3) {
    for (std::size_t i = 0; i < P_.size(); ++i) {
      const double d[3] = {P_.x[i] - box_.x_min, P_.y[i] - box_.y_min, P_.z[i] - box_.z_min};
      P_.vx[i] = edot3_[0] * d[0];
      P_.vy[i] = edot3_[1] * d[1];
      P_.vz[i] = edot3_[2] * d[2];
      if (shear3_) {
        P_.vx[i] += L3_[0][1] * d[1] + L3_[0][2] * d[2];
        P_.vy[i] += L3_[1][0] * d[0] + L3_[1][2] * d[2];
        P_.vz[i] += L3_[2][0] * d[0] + L3_[2][1] * d[1];
      }
      P_.wx[i] = P_.wy[i] = P_.omega[i] = 0.0;
    }
    return;
  }
  const double e12 = edot_[2];
  for (std::size_t i = 0; i < P_.size(); ++i) {
    const double dx = P_.x[i] - box_.x_min, dy = P_.y[i] - box_.y_min;
    P_.vx[i] = edot_[0] * dx;
    P_.vy[i] = edot_[1] * dy;
    if (e12 != 0.0) {
      P_.vx[i] += e12 * dy;
      P_.vy[i] += e12 * dx;
    }
    P_.omega[i] = 0.0;
  }
}

template <int D>
void DynamicSolverT<D>::set_plastic_law(const contact::PlasticIndentationParams& law) {
  if (!plastic()) fail("set_plastic_law: the solver runs the Luding law, not the plastic-indentation law");
  law.validate();
  if (!(law.first_touch > 0.0))
    fail("set_plastic_law: the explicit solver needs the plastic law's first-touch overlap > 0");
  if (opt_.plastic.reversible && !law.reversible) {
    using L = contact::PlasticIndentationLawT<D>;
    for (std::size_t k = 0; k < pair_key_.size(); ++k) {
      const auto i = static_cast<std::size_t>(pair_key_[k] >> 32), j = static_cast<std::size_t>(pair_key_[k] & 0xffffffffu);
      double L2 = (P_.x[j] - P_.x[i]) * (P_.x[j] - P_.x[i]) + (P_.y[j] - P_.y[i]) * (P_.y[j] - P_.y[i]);
      if constexpr (D == 3) L2 += (P_.z[j] - P_.z[i]) * (P_.z[j] - P_.z[i]);
      pl_pair_hist_[k] = L::start_unloading_branch(pl_pair_hist_[k], P_.radius[i] + P_.radius[j] - std::sqrt(L2));
    }
    if (walls_active())
      for (std::size_t i = 0; i < P_.size(); ++i) {
        double dw[2 * D] = {P_.x[i] - box_.x_min, box_.x_max - P_.x[i], P_.y[i] - box_.y_min, box_.y_max - P_.y[i]};
        if constexpr (D == 3) {
          dw[4] = P_.z[i] - box_.z_min;
          dw[5] = box_.z_max - P_.z[i];
        }
        for (std::size_t w = 0; w < kWalls; ++w)
          pl_wall_hist_[kWalls * i + w] = L::start_unloading_branch(pl_wall_hist_[kWalls * i + w], P_.radius[i] - dw[w]);
      }
  }
  opt_.plastic = law;
  pl_wall_params_ = law;
  pl_wall_params_.mu = opt_.plastic_wall_mu;
  choose_friction();
  const double dt_fixed = opt_.dt;
  ts_ = plastic_time_step(P_, opt_.plastic, opt_, area_max_);
  if (!(dt_fixed > 0.0)) update_plastic_time_step();
}

template <int D>
void DynamicSolverT<D>::set_rotations(bool free) {
  rotations_ = free;
  if (!free) std::fill(P_.omega.begin(), P_.omega.end(), 0.0);
  if constexpr (D == 3) {
    if (!free) {
      std::fill(P_.wx.begin(), P_.wx.end(), 0.0);
      std::fill(P_.wy.begin(), P_.wy.end(), 0.0);
    }
  }
  inv_mass_.clear();  // refilled by the next step
}

template <int D>
void DynamicSolverT<D>::hold_spins(const std::vector<std::uint32_t>& particles) {
  for (std::uint32_t p : particles) {
    if (p >= P_.size() || is_prescribed_.empty() || !is_prescribed_[p])
      fail("hold_spins: particle " + std::to_string(p) + " is not prescribed (call set_prescribed first)");
    spin_held_[p] = 1;
    P_.omega[p] = 0.0;
    if constexpr (D == 3) P_.wx[p] = P_.wy[p] = 0.0;
  }
  inv_mass_.clear();  // the kicks' inverse inertias are refilled
}

template <int D>
void DynamicSolverT<D>::set_prescribed(const std::vector<std::uint32_t>& particles, bool hold_spins) {
  is_prescribed_.assign(P_.size(), 0);
  spin_held_.assign(P_.size(), 0);
  for (std::uint32_t p : particles) {
    if (p >= P_.size()) fail("set_prescribed: particle " + std::to_string(p) + " does not exist");
    is_prescribed_[p] = 1;
    spin_held_[p] = hold_spins ? 1 : 0;
  }
  prescribed_.clear();
  for (std::uint32_t p = 0; p < P_.size(); ++p)
    if (is_prescribed_[p]) prescribed_.push_back(p);
  inv_mass_.clear();  // the kicks' inverse masses are refilled (zero for the prescribed)
}

// Over the coming step of length dt: the prescribed particles and the Affine walls get the
// velocity (exp(E' dt) - 1)/dt (x - x_0), with which the drift moves them exactly along the
// exponential affine motion; prescribed spins are zero.
namespace {
/// exp(L t) - I of the symmetric L = [[a, c], [c, b]] (row-major), without cancellation for small t:
/// exp(L t) = e^(m t) (cosh(d t) I + sinh(d t)/d (L - m I)), m = (a + b)/2, d = sqrt(((a - b)/2)^2 + c^2),
/// and e^(m t) cosh(d t) - 1 = expm1(m t) cosh(d t) + 2 sinh^2(d t / 2).
std::array<double, 4> expm1_sym2(double a, double b, double c, double t) {
  const double m = 0.5 * (a + b), h = 0.5 * (a - b), d = std::sqrt(h * h + c * c);
  const double em = std::exp(m * t), ch = std::cosh(d * t), s2 = std::sinh(0.5 * d * t);
  const double sh = d * t > 1e-8 ? std::sinh(d * t) / d : t * (1.0 + d * d * t * t / 6.0);
  const double diag = std::expm1(m * t) * ch + 2.0 * s2 * s2;
  return {diag + em * sh * h, em * sh * c, em * sh * c, diag - em * sh * h};
}
}  // namespace

template <int D>
void DynamicSolverT<D>::impose_affine_motion(double dt) {
  if constexpr (D == 3) {  // x_0 + exp(L dt)(x - x_0) exactly (set_strain_rate3)
    double g[3], md[3];
    for (int a = 0; a < 3; ++a) {
      const double m = std::expm1(edot3_[a] * dt);
      F3_[static_cast<std::size_t>(a)] *= 1.0 + m;
      g[a] = m / dt;
      md[a] = m;
    }
    if (!shear3_) {  // diagonal: expm1 of each rate
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) F3m_[static_cast<std::size_t>(3 * a + b)] *= 1.0 + md[a];
      for (std::uint32_t p : prescribed_) {
        P_.vx[p] = g[0] * (P_.x[p] - box_.x_min);
        P_.vy[p] = g[1] * (P_.y[p] - box_.y_min);
        P_.vz[p] = g[2] * (P_.z[p] - box_.z_min);
        if (spin_held_[p]) P_.wx[p] = P_.wy[p] = P_.omega[p] = 0.0;
      }
    } else {  // G = exp(L dt) - I = V diag(expm1(lambda dt)) V^T
      double G[3][3] = {}, m[3];
      for (int k = 0; k < 3; ++k) m[k] = std::expm1(eig_l3_[k] * dt);
      for (int a = 0; a < 3; ++a)
        for (int b = a; b < 3; ++b) {
          double v = 0.0;
          for (int k = 0; k < 3; ++k) v += eig_v3_[3 * a + k] * m[k] * eig_v3_[3 * b + k];
          G[a][b] = G[b][a] = v;
        }
      const auto F = F3m_;  // F <- (I + G) F
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) {
          double v = F[static_cast<std::size_t>(3 * a + b)];
          for (int k = 0; k < 3; ++k) v += G[a][k] * F[static_cast<std::size_t>(3 * k + b)];
          F3m_[static_cast<std::size_t>(3 * a + b)] = v;
        }
      const double inv = 1.0 / dt;
      for (std::uint32_t p : prescribed_) {
        const double d[3] = {P_.x[p] - box_.x_min, P_.y[p] - box_.y_min, P_.z[p] - box_.z_min};
        P_.vx[p] = (G[0][0] * d[0] + G[0][1] * d[1] + G[0][2] * d[2]) * inv;
        P_.vy[p] = (G[1][0] * d[0] + G[1][1] * d[1] + G[1][2] * d[2]) * inv;
        P_.vz[p] = (G[2][0] * d[0] + G[2][1] * d[1] + G[2][2] * d[2]) * inv;
        if (spin_held_[p]) P_.wx[p] = P_.wy[p] = P_.omega[p] = 0.0;
      }
    }
    // the box: the axis-aligned box of the diagonal rates
    const double L[3] = {box_.x_max - box_.x_min, box_.y_max - box_.y_min, box_.z_max - box_.z_min};
    for (int a = 0; a < 3; ++a)
      if (moving_wall(a).mode == WallMode::Affine) wall_v_[a] = g[a] * L[a];
    return;
  }
  {  // the accumulated map
    auto M = edot_[2] != 0.0 ? expm1_sym2(edot_[0], edot_[1], edot_[2], dt)
                             : std::array<double, 4>{std::expm1(edot_[0] * dt), 0.0, 0.0, std::expm1(edot_[1] * dt)};
    M[0] += 1.0;
    M[3] += 1.0;
    const auto F = F_;
    F_ = {M[0] * F[0] + M[1] * F[2], M[0] * F[1] + M[1] * F[3], M[2] * F[0] + M[3] * F[2], M[2] * F[1] + M[3] * F[3]};
  }
  if (prescribed_.empty() && box_.right.mode != WallMode::Affine && box_.top.mode != WallMode::Affine) return;
  const double gx = std::expm1(edot_[0] * dt) / dt, gy = std::expm1(edot_[1] * dt) / dt;
  if (edot_[2] != 0.0) {  // x_0 + exp(L dt)(x - x_0) over the step: v = (exp(L dt) - I)(x - x_0) / dt
    const auto G = expm1_sym2(edot_[0], edot_[1], edot_[2], dt);
    const double g11 = G[0] / dt, g22 = G[3] / dt, g12 = G[1] / dt;
    for (std::uint32_t p : prescribed_) {
      const double dx = P_.x[p] - box_.x_min, dy = P_.y[p] - box_.y_min;
      P_.vx[p] = g11 * dx + g12 * dy;
      P_.vy[p] = g12 * dx + g22 * dy;
      if (spin_held_[p]) P_.omega[p] = 0.0;
    }
  } else {
    for (std::uint32_t p : prescribed_) {
      P_.vx[p] = gx * (P_.x[p] - box_.x_min);
      P_.vy[p] = gy * (P_.y[p] - box_.y_min);
      if (spin_held_[p]) P_.omega[p] = 0.0;
    }
  }
  if (box_.right.mode == WallMode::Affine) wall_v_[0] = gx * (box_.x_max - box_.x_min);
  if (box_.top.mode == WallMode::Affine) wall_v_[1] = gy * (box_.y_max - box_.y_min);
}

// 3D: the affine velocity L (x_i - x_0) of particle i (diagonal L: the products of before the shear rates)
template <int D>
void DynamicSolverT<D>::affine_velocity3(std::size_t i, double* a) const {
  if constexpr (D == 3) {
    const double d[3] = {P_.x[i] - box_.x_min, P_.y[i] - box_.y_min, P_.z[i] - box_.z_min};
    a[0] = edot3_[0] * d[0];
    a[1] = edot3_[1] * d[1];
    a[2] = edot3_[2] * d[2];
    if (shear3_) {
      a[0] += L3_[0][1] * d[1] + L3_[0][2] * d[2];
      a[1] += L3_[1][0] * d[0] + L3_[1][2] * d[2];
      a[2] += L3_[2][0] * d[0] + L3_[2][1] * d[1];
    }
  } else {
    (void)i, (void)a;
  }
}

template <int D>
void DynamicSolverT<D>::set_affine_drag(double drag) {
  if (!(std::isfinite(drag) && drag >= 0.0)) fail(fmt::format("set_affine_drag: the drag must be finite and >= 0, got {}", drag));
  opt_.affine_drag = drag;
}

template <int D>
double DynamicSolverT<D>::unbalanced_force_rms() const {
  if constexpr (D == 3) {
    const double c = opt_.affine_drag;
    double sum = 0.0;
    std::size_t n = 0;
    for (std::size_t i = 0; i < P_.size(); ++i) {
      const bool pres = !is_prescribed_.empty() && is_prescribed_[i];
      if (rotations_ && !(pres && spin_held_[i])) {
        const double r = P_.radius[i], I = P_.inertia[i];
        const double mx = (P_.tx[i] + c * I * P_.wx[i]) / r, my = (P_.ty[i] + c * I * P_.wy[i]) / r,
                     mz = (P_.torque[i] + c * I * P_.omega[i]) / r;
        sum += mx * mx + my * my + mz * mz;
        ++n;
      }
      if (pres) continue;
      const double m = P_.mass[i];
      double a[3];
      affine_velocity3(i, a);
      const double fx = P_.fx[i] + c * m * (P_.vx[i] - a[0]);
      const double fy = P_.fy[i] + c * m * (P_.vy[i] - a[1]);
      const double fz = P_.fz[i] + c * m * (P_.vz[i] - a[2]);
      sum += fx * fx + fy * fy + fz * fz;
      if (!rotations_) ++n;
    }
    return n > 0 ? std::sqrt(sum / static_cast<double>(n)) : 0.0;
  }
  const double c = opt_.affine_drag;
  double sum = 0.0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < P_.size(); ++i) {
    if (!is_prescribed_.empty() && is_prescribed_[i]) {
      if (!spin_held_[i] && rotations_) {  // a prescribed centre with a free spin: its torque
        const double m = (P_.torque[i] + c * P_.inertia[i] * P_.omega[i]) / P_.radius[i];
        sum += m * m;
        ++n;
      }
      continue;
    }
    const double dx = P_.x[i] - box_.x_min, dy = P_.y[i] - box_.y_min;
    const double ax = edot_[0] * dx + edot_[2] * dy, ay = edot_[1] * dy + edot_[2] * dx;
    const double fx = P_.fx[i] + c * P_.mass[i] * (P_.vx[i] - ax), fy = P_.fy[i] + c * P_.mass[i] * (P_.vy[i] - ay);
    const double m = rotations_ ? (P_.torque[i] + c * P_.inertia[i] * P_.omega[i]) / P_.radius[i] : 0.0;
    sum += fx * fx + fy * fy + m * m;
    ++n;
  }
  return n > 0 ? std::sqrt(sum / static_cast<double>(n)) : 0.0;
}

template <int D>
void DynamicSolverT<D>::apply_affine_drag() {
  if constexpr (D == 3) {
    const double c = opt_.affine_drag;
    for (std::size_t i = 0; i < P_.size(); ++i) {
      const bool pres = !is_prescribed_.empty() && is_prescribed_[i];
      if (!(pres && spin_held_[i])) {
        P_.tx[i] -= c * P_.inertia[i] * P_.wx[i];
        P_.ty[i] -= c * P_.inertia[i] * P_.wy[i];
        P_.torque[i] -= c * P_.inertia[i] * P_.omega[i];
      }
      if (pres) continue;
      double a[3];
      affine_velocity3(i, a);
      P_.fx[i] -= c * P_.mass[i] * (P_.vx[i] - a[0]);
      P_.fy[i] -= c * P_.mass[i] * (P_.vy[i] - a[1]);
      P_.fz[i] -= c * P_.mass[i] * (P_.vz[i] - a[2]);
    }
    return;
  }
  const double c = opt_.affine_drag;
  for (std::size_t i = 0; i < P_.size(); ++i) {
    if (!is_prescribed_.empty() && is_prescribed_[i]) {
      if (!spin_held_[i]) P_.torque[i] -= c * P_.inertia[i] * P_.omega[i];  // a free spin
      continue;
    }
    const double dx = P_.x[i] - box_.x_min, dy = P_.y[i] - box_.y_min;
    double ax = edot_[0] * dx, ay = edot_[1] * dy;
    if (edot_[2] != 0.0) {
      ax += edot_[2] * dy;
      ay += edot_[2] * dx;
    }
    P_.fx[i] -= c * P_.mass[i] * (P_.vx[i] - ax);
    P_.fy[i] -= c * P_.mass[i] * (P_.vy[i] - ay);
    P_.torque[i] -= c * P_.inertia[i] * P_.omega[i];
  }
}

template <int D>
auto DynamicSolverT<D>::boundary_stress() const -> Stress {
  if constexpr (D == 3) {  // about the box centre (diagonal L: the box is the deformed domain)
    Stress s;
    if (!box_.enabled) return s;
    double c[3] = {0.5 * (box_.x_min + box_.x_max), 0.5 * (box_.y_min + box_.y_max), 0.5 * (box_.z_min + box_.z_max)};
    if (sheared3_) {  // the centre of the deformed parallelepiped x_0 + F (c_0 - x_0)
      const double x0[3] = {box_.x_min, box_.y_min, box_.z_min};
      const double X[3] = {centre0_[0] - x0[0], centre0_[1] - x0[1], centre0z_ - x0[2]};
      for (int a = 0; a < 3; ++a) {
        c[a] = x0[a];
        for (int b = 0; b < 3; ++b) c[a] += F3m_[static_cast<std::size_t>(3 * a + b)] * X[b];
      }
    }
    for (std::uint32_t p : prescribed_) {
      const double f[3] = {P_.fx[p], P_.fy[p], P_.fz[p]};
      const double l[3] = {P_.x[p] - c[0], P_.y[p] - c[1], P_.z[p] - c[2]};
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) s.s[a][b] += f[a] * l[b];
    }
    const double V = box_measure();
    for (auto& row : s.s)
      for (double& v : row) v /= V;
    return s;
  } else {
  Stress s;
  if (!box_.enabled) return s;
  double xc = 0.5 * (box_.x_min + box_.x_max), yc = 0.5 * (box_.y_min + box_.y_max);
  if (sheared_) {  // the centre of the deformed parallelogram x_0 + F (c_0 - x_0)
    const double X = centre0_[0] - box_.x_min, Y = centre0_[1] - box_.y_min;
    xc = box_.x_min + F_[0] * X + F_[1] * Y;
    yc = box_.y_min + F_[2] * X + F_[3] * Y;
  }
  for (std::uint32_t p : prescribed_) {
    const double lx = P_.x[p] - xc, ly = P_.y[p] - yc;
    s.xx += P_.fx[p] * lx;
    s.xy += P_.fx[p] * ly;
    s.yx += P_.fy[p] * lx;
    s.yy += P_.fy[p] * ly;
  }
  // f_p = the contact forces on p, balanced by the boundary's -f_p: sum_p f_p (x) (x_p - x_c) is
  // the contact stress sum when every particle is prescribed (compression positive)
  const double V = (box_.x_max - box_.x_min) * (box_.y_max - box_.y_min);
  s.xx /= V;
  s.xy /= V;
  s.yx /= V;
  s.yy /= V;
  return s;
  }
}

// ---- instability checks (docs/dynamic.md "Instability detection") -------------------------------
namespace {
const char* const kCauseStep =
    "the time step is too large for the stiffness, the damping or the masses (--steps-per-contact, k2, "
    "gamma_n, rho_p, m_wall, gamma_wall)";
const char* const kCauseWall =
    "a stress-controlled wall is unstable or driven too hard (m_wall, gamma_wall, --pressure, --strain-rate)";
const char* const kCauseLoad =
    "the load is too high for the stiffness (2p/k2, k1_ratio, k2, --strain-rate) or the time step too large "
    "(--steps-per-contact)";
}  // namespace

template <int D>
void DynamicSolverT<D>::breach(const std::string& quantity, const std::string& what, const std::string& cause) const {
  const std::int64_t step = ts_.dt > 0.0 ? static_cast<std::int64_t>(std::llround(time_ / ts_.dt)) : 0;
  throw InstabilityError(fmt::format("unstable at step {} (t = {:.6g} s): {}; likely cause: {}", step, time_, what,
                                     cause),
                         quantity, step, time_);
}

template <int D>
void DynamicSolverT<D>::check_health() const { check_health_with(-1.0); }

template <int D>
void DynamicSolverT<D>::check_health_with(double vmax2) const {
  const std::size_t n = P_.size();
  const bool track = vmax2 < 0.0;  // (NaN: not negative, the pass below reports it)
  if (track) vmax2 = 0.0;
  double rmin = std::numeric_limits<double>::infinity(), area = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const double v[7] = {P_.x[i], P_.y[i], P_.vx[i], P_.vy[i], P_.omega[i], P_.fx[i], P_.fy[i]};
    bool fin = std::isfinite(P_.radius[i]) && std::isfinite(P_.torque[i]);
    for (double q : v) fin = fin && std::isfinite(q);
    if constexpr (D == 3) {
      const double v3[7] = {P_.z[i], P_.vz[i], P_.wx[i], P_.wy[i], P_.fz[i], P_.tx[i], P_.ty[i]};
      for (double q : v3) fin = fin && std::isfinite(q);
    }
    if (!fin)
      breach("finite", fmt::format("particle {} has a non-finite position, velocity or force", i), kCauseStep);
    rmin = std::min(rmin, P_.radius[i]);
    if constexpr (D == 2) {
      area += P_.radius[i] * P_.radius[i];
      if (track) vmax2 = std::max(vmax2, P_.vx[i] * P_.vx[i] + P_.vy[i] * P_.vy[i]);
    } else {
      area += P_.radius[i] * P_.radius[i] * P_.radius[i];
      if (track) vmax2 = std::max(vmax2, P_.vx[i] * P_.vx[i] + P_.vy[i] * P_.vy[i] + P_.vz[i] * P_.vz[i]);
    }
  }
  if (!(std::isfinite(vmax2))) breach("finite", "a particle velocity is not finite", kCauseStep);
  bool wall_finite = true;
  for (int a = 0; a < D; ++a) wall_finite = wall_finite && std::isfinite(wall_v_[a]) && std::isfinite(wall_force_[2 * a + 1]);
  if (!wall_finite) breach("finite", "a wall velocity or force is not finite", kCauseWall);
  const double dt = ts_.dt, travel = HealthLimits::kMaxTravel * rmin;
  if (!(std::sqrt(vmax2) * dt < travel))
    breach("velocity", fmt::format("max|v| dt = {:.3g} m is not below 0.1 r_min = {:.3g} m", std::sqrt(vmax2) * dt, travel),
           kCauseStep);
  if (box_.enabled) {
    const double b[6] = {box_.x_min, box_.x_max, box_.y_min, box_.y_max, box_.z_min, box_.z_max};
    for (double q : b)
      if (!std::isfinite(q)) breach("finite", "the box is not finite", kCauseWall);
    if (!(box_.x_max > box_.x_min && box_.y_max > box_.y_min))
      breach("box", fmt::format("the box extents {:.3g} x {:.3g} m are not positive", box_.x_max - box_.x_min,
                                box_.y_max - box_.y_min),
             kCauseWall);
    if constexpr (D == 3) {
      if (!(box_.z_max > box_.z_min))
        breach("box", fmt::format("the box extent {:.3g} m along z is not positive", box_.z_max - box_.z_min), kCauseWall);
    }
    double wv = std::max(std::fabs(wall_v_[0]), std::fabs(wall_v_[1]));
    if constexpr (D == 3) wv = std::max(wv, std::fabs(wall_v_[2]));
    if (!(wv * dt < travel))
      breach("velocity", fmt::format("a wall moves {:.3g} m per step, not below 0.1 r_min = {:.3g} m", wv * dt, travel),
             kCauseWall);
    for (std::size_t i = 0; i < n && box_.contact_walls; ++i) {
      bool inside = P_.x[i] >= box_.x_min && P_.x[i] <= box_.x_max && P_.y[i] >= box_.y_min && P_.y[i] <= box_.y_max;
      if constexpr (D == 3) inside = inside && P_.z[i] >= box_.z_min && P_.z[i] <= box_.z_max;
      if (!inside)
        breach("centre", fmt::format("the centre of particle {} ({:.6g}, {:.6g}) m is outside the box", i, P_.x[i], P_.y[i]),
               kCauseLoad);
    }
  }
  // overlaps: the pairs of the table (complete for the touching pairs) and the walls, each against
  // half the smaller radius of its contact (>= 0.5 r_min; docs/dynamic.md)
  for (std::uint64_t key : pair_key_) {
    const auto i = static_cast<std::size_t>(key >> 32), j = static_cast<std::size_t>(key & 0xffffffffu);
    const double dx = P_.x[j] - P_.x[i], dy = P_.y[j] - P_.y[i], s = P_.radius[i] + P_.radius[j];
    double L2 = dx * dx + dy * dy;
    if constexpr (D == 3) L2 += (P_.z[j] - P_.z[i]) * (P_.z[j] - P_.z[i]);
    if (!(L2 < s * s)) continue;
    const double d = s - std::sqrt(L2), lim = HealthLimits::kMaxOverlap * std::min(P_.radius[i], P_.radius[j]);
    if (!(d < lim))
      breach("overlap", fmt::format("the overlap {:.3g} m of particles {} and {} is not below half the smaller radius, "
                                    "{:.3g} m", d, i, j, lim),
             kCauseLoad);
  }
  if (walls_active()) {
    for (std::size_t i = 0; i < n; ++i) {
      const double r = P_.radius[i];
      double d = std::max(std::max(r - (P_.x[i] - box_.x_min), r - (box_.x_max - P_.x[i])),
                          std::max(r - (P_.y[i] - box_.y_min), r - (box_.y_max - P_.y[i])));
      if constexpr (D == 3) d = std::max(d, std::max(r - (P_.z[i] - box_.z_min), r - (box_.z_max - P_.z[i])));
      if (!(d < HealthLimits::kMaxOverlap * r))
        breach("overlap", fmt::format("particle {} overlaps a wall by {:.3g} m, not below half its radius, {:.3g} m", i, d,
                                      HealthLimits::kMaxOverlap * r),
               kCauseLoad);
    }
    const double nu = D == 2 ? std::numbers::pi * area / ((box_.x_max - box_.x_min) * (box_.y_max - box_.y_min))
                             : (4.0 / 3.0) * std::numbers::pi * area / box_measure();
    if (!(nu <= HealthLimits::kMaxDensity))
      breach("density", fmt::format("nu = {:.4g} is above 1.25", nu),
             "overlaps beyond the model's range: the pressure is too high for the stiffness (2p/k2, k1_ratio) or a "
             "wall is unstable (m_wall, gamma_wall)");
  }
}

template <int D>
void DynamicSolverT<D>::run(std::size_t n_steps) {
  for (std::size_t s = 0; s < n_steps; ++s) step();
}

// ---- observables --------------------------------------------------------------------------------
template <int D>
double DynamicSolverT<D>::box_measure() const {
  const double a = (box_.x_max - box_.x_min) * (box_.y_max - box_.y_min);
  if constexpr (D == 2) {
    return a;
  } else {
    return a * (box_.z_max - box_.z_min);
  }
}

template <int D>
auto DynamicSolverT<D>::wall_stress() const -> Stress {
  Stress s;
  if (!box_.enabled) return s;
  if constexpr (D == 2) {
    s.xx = wall_force_[1] / (box_.y_max - box_.y_min);
    s.yy = wall_force_[3] / (box_.x_max - box_.x_min);
  } else {
    const double e[3] = {box_.x_max - box_.x_min, box_.y_max - box_.y_min, box_.z_max - box_.z_min};
    for (int a = 0; a < 3; ++a) s.s[a][a] = wall_force_[2 * a + 1] / (e[(a + 1) % 3] * e[(a + 2) % 3]);
  }
  return s;
}

template <int D>
auto DynamicSolverT<D>::contact_stress() const -> Stress {
  Stress s;
  if (!box_.enabled) return s;
  const double V = box_measure();
  if constexpr (D == 2) {
    s.xx = sxx_ / V;
    s.xy = sxy_ / V;
    s.yx = syx_ / V;
    s.yy = syy_ / V;
  } else {
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) s.s[a][b] = s3_[a][b] / V;
  }
  return s;
}

template <int D>
double DynamicSolverT<D>::density() const {
  if (!box_.enabled) return 0.0;
  double a = 0.0;
  if constexpr (D == 2) {
    for (double r : P_.radius) a += std::numbers::pi * r * r;
    return a / ((box_.x_max - box_.x_min) * (box_.y_max - box_.y_min));
  } else {
    for (double r : P_.radius) a += (4.0 / 3.0) * std::numbers::pi * r * r * r;
    return a / box_measure();
  }
}

template <int D>
Energies DynamicSolverT<D>::energies() const {
  Energies e;
  for (std::size_t i = 0; i < P_.size(); ++i) {
    if constexpr (D == 2) {
      e.kinetic += 0.5 * P_.mass[i] * (P_.vx[i] * P_.vx[i] + P_.vy[i] * P_.vy[i]) +
                   0.5 * P_.inertia[i] * P_.omega[i] * P_.omega[i];
      e.gravity -= P_.mass[i] * (opt_.gravity_x * P_.x[i] + opt_.gravity_y * P_.y[i]);
    } else {
      e.kinetic += 0.5 * P_.mass[i] * (P_.vx[i] * P_.vx[i] + P_.vy[i] * P_.vy[i] + P_.vz[i] * P_.vz[i]) +
                   0.5 * P_.inertia[i] * (P_.wx[i] * P_.wx[i] + P_.wy[i] * P_.wy[i] + P_.omega[i] * P_.omega[i]);
      e.gravity -= P_.mass[i] * (opt_.gravity_x * P_.x[i] + opt_.gravity_y * P_.y[i] + opt_.gravity_z * P_.z[i]);
    }
  }
  e.elastic = elastic_;
  if (box_.enabled) {
    if (box_.right.mode == WallMode::Stress)
      e.wall_kinetic += 0.5 * box_.right.mass * wall_v_[0] * wall_v_[0];
    if (box_.top.mode == WallMode::Stress)
      e.wall_kinetic += 0.5 * box_.top.mass * wall_v_[D - 1] * wall_v_[D - 1];
    if constexpr (D == 3) {
      if (box_.back.mode == WallMode::Stress) e.wall_kinetic += 0.5 * box_.back.mass * wall_v_[1] * wall_v_[1];
    }
  }
  return e;
}

template class DynamicSolverT<2>;
template class DynamicSolverT<3>;

}  // namespace netdem::dem
