// Explicit DEM solver, LMM05 Eq 1, 2, 6 (see solver.hpp and docs/dynamic.md).
#include "netdem/dynamic/solver.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>

namespace netdem::dem {

namespace {
using contact::LudingFeatures;
using contact::LudingInput;
using contact::LudingResult;
constexpr LudingFeatures kHysteretic{true, false, false, true};
constexpr LudingFeatures kLinearFrictionless{false, false, false, false};
constexpr LudingFeatures kHystereticFrictionless{true, false, false, false};
constexpr LudingFeatures kFullFrictionless{true, true, true, false};

[[noreturn]] void fail(const std::string& msg) { throw std::invalid_argument(msg); }
}  // namespace

std::size_t Particles::add(double px, double py, double r, const LudingParams& p, double pvx,
                           double pvy, double pomega) {
  const double m = contact::luding_mass(p, r);
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

void DynamicOptions::validate() const {
  if (!(steps_per_contact > 0.0)) fail("DynamicOptions: steps_per_contact must be > 0");
  if (!(min_steps_per_contact >= 0.0)) fail("DynamicOptions: min_steps_per_contact must be >= 0");
  if (!(dt >= 0.0)) fail("DynamicOptions: dt must be >= 0 (0 = from the rule)");
  if (!(skin >= 0.0)) fail("DynamicOptions: skin must be >= 0 (0 = 0.3 mean radius)");
}

double contact_duration(double k2, double gamma0, double m12) {
  const double eta0 = gamma0 / (2.0 * m12);
  double w2 = k2 / m12 - eta0 * eta0;       // LMM05 Eq 6
  if (!(w2 > 0.0)) w2 = k2 / m12;           // over-damped: undamped omega (stricter)
  return std::numbers::pi / std::sqrt(w2);  // LMM05 Eq 6: t_c = pi / omega
}

TimeStepInfo choose_time_step(const Particles& P, const LudingParams& p, const DynamicOptions& o) {
  o.validate();
  const std::size_t n = P.size();
  if (n == 0) fail("choose_time_step: no particles");
  double mean = 0.0, m_lo = P.mass[0], m_lo2 = P.mass[0];
  for (double m : P.mass) mean += m;
  mean /= static_cast<double>(n);
  if (n >= 2) {
    m_lo = std::min(P.mass[0], P.mass[1]);
    m_lo2 = std::max(P.mass[0], P.mass[1]);
    for (std::size_t i = 2; i < n; ++i) {
      const double m = P.mass[i];
      if (m < m_lo) {
        m_lo2 = m_lo;
        m_lo = m;
      } else if (m < m_lo2) {
        m_lo2 = m;
      }
    }
  }
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

DynamicSolver::DynamicSolver(Particles particles, const LudingParams& params, const Box& box,
                             const DynamicOptions& options)
    : P_(std::move(particles)), params_(params), box_(box), opt_(options) {
  params_.validate();
  opt_.validate();
  const std::size_t n = P_.size();
  if (n >= (std::size_t{1} << 32)) fail("DynamicSolver: too many particles");
  if (box_.enabled && !(box_.x_max > box_.x_min && box_.y_max > box_.y_min))
    fail("DynamicSolver: box must have x_max > x_min and y_max > y_min");
  for (std::size_t i = 0; i < n; ++i)
    if (!(P_.radius[i] > 0.0) || !(P_.mass[i] > 0.0) || !(P_.inertia[i] > 0.0))
      fail("DynamicSolver: particle " + std::to_string(i) + " has a non-positive radius or mass");
  for (const MovingWall* w : {&box_.right, &box_.top})
    if (w->mode == WallMode::Stress && !(w->mass > 0.0 && w->damping >= 0.0))
      fail("DynamicSolver: a stress-controlled wall needs mass > 0 and damping >= 0");
  ts_ = choose_time_step(P_, params_, opt_);
  thermal_ = contact::luding_thermal_start(params_, opt_.temperature);
  // The given radii are a(T_radius_ref) (Eq 9); the full law starts at a(T).
  radius_ref_ = P_.radius;
  if (opt_.model == ContactModel::Full) {
    radius_scale_ = contact::luding_radius(params_, 1.0, thermal_.T);
    for (std::size_t i = 0; i < n; ++i) {
      P_.radius[i] = radius_ref_[i] * radius_scale_;
      P_.inertia[i] = 0.5 * P_.mass[i] * P_.radius[i] * P_.radius[i];
    }
  }
  wall_v_[0] = box_.right.mode == WallMode::Strain ? box_.right.velocity : 0.0;
  wall_v_[1] = box_.top.mode == WallMode::Strain ? box_.top.velocity : 0.0;
  wall_hist_.assign(4 * n, LudingHistory{});
  finish_setup();
  build_table();
  compute_forces_dispatch();
}

void DynamicSolver::finish_setup() {
  const std::size_t n = P_.size();
  wall_params_ = params_.wall_params();
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

void DynamicSolver::choose_friction() {
  friction_ = params_.mu > 0.0 || (box_.enabled && params_.mu_wall > 0.0);
}

// ---- neighbour search: cell list + Verlet table ------------------------------------------------
bool DynamicSolver::needs_rebuild() const {
  // Two particles each moving d and each growing by g (Eq 9) close a gap by 2 d + 2 g: the table
  // (range r_i + r_j + skin at the build) stays complete while d < skin / 2 - g.
  const double grow = radius_ref_max_ * std::max(0.0, radius_scale_ - radius_scale_build_);
  const double lim = 0.5 * skin_ - grow;
  if (!(lim > 0.0)) return true;
  const double lim2 = lim * lim;
  for (std::size_t i = 0; i < P_.size(); ++i) {
    const double dx = P_.x[i] - x_build_[i], dy = P_.y[i] - y_build_[i];
    if (dx * dx + dy * dy > lim2) return true;
  }
  return false;
}

void DynamicSolver::build_table() {
  const std::size_t n = P_.size();
  ++rebuilds_;
  radius_scale_build_ = radius_scale_;
  x_build_ = P_.x;
  y_build_ = P_.y;
  new_key_.clear();
  if (n >= 2) {
    double xlo = P_.x[0], xhi = xlo, ylo = P_.y[0], yhi = ylo, rmax = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      xlo = std::min(xlo, P_.x[i]);
      xhi = std::max(xhi, P_.x[i]);
      ylo = std::min(ylo, P_.y[i]);
      yhi = std::max(yhi, P_.y[i]);
      rmax = std::max(rmax, P_.radius[i]);
    }
    // cell side >= largest interaction range 2 rmax + skin; at most ~4 n cells
    double c = 2.0 * rmax + skin_;
    const double cmin =
        std::sqrt((xhi - xlo + c) * (yhi - ylo + c) / (4.0 * static_cast<double>(n)));
    c = std::max(c, cmin);
    const std::size_t nx = static_cast<std::size_t>((xhi - xlo) / c) + 1;
    const std::size_t ny = static_cast<std::size_t>((yhi - ylo) / c) + 1;
    auto cell_of = [&](std::size_t i, std::size_t& cx, std::size_t& cy) {
      cx = std::min(nx - 1, static_cast<std::size_t>((P_.x[i] - xlo) / c));
      cy = std::min(ny - 1, static_cast<std::size_t>((P_.y[i] - ylo) / c));
    };
    cell_start_.assign(nx * ny + 1, 0);
    cell_items_.resize(n);
    for (std::size_t i = 0; i < n; ++i) {  // counting sort of particles by cell
      std::size_t cx, cy;
      cell_of(i, cx, cy);
      ++cell_start_[cy * nx + cx + 1];
    }
    for (std::size_t k = 0; k < nx * ny; ++k) cell_start_[k + 1] += cell_start_[k];
    cell_cursor_.assign(cell_start_.begin(), cell_start_.end() - 1);
    std::vector<std::uint32_t>& cursor = cell_cursor_;
    for (std::size_t i = 0; i < n; ++i) {
      std::size_t cx, cy;
      cell_of(i, cx, cy);
      cell_items_[cursor[cy * nx + cx]++] = static_cast<std::uint32_t>(i);
    }
    for (std::size_t i = 0; i < n; ++i) {
      std::size_t cx, cy;
      cell_of(i, cx, cy);
      for (std::size_t gy = (cy > 0 ? cy - 1 : 0); gy <= std::min(ny - 1, cy + 1); ++gy)
        for (std::size_t gx = (cx > 0 ? cx - 1 : 0); gx <= std::min(nx - 1, cx + 1); ++gx)
          for (std::uint32_t k = cell_start_[gy * nx + gx]; k < cell_start_[gy * nx + gx + 1];
               ++k) {
            const std::uint32_t j = cell_items_[k];
            if (j <= i) continue;
            const double dx = P_.x[j] - P_.x[i], dy = P_.y[j] - P_.y[i];
            const double range = P_.radius[i] + P_.radius[j] + skin_;
            if (dx * dx + dy * dy < range * range)
              new_key_.push_back((static_cast<std::uint64_t>(i) << 32) | j);
          }
    }
    std::sort(new_key_.begin(), new_key_.end());
  }
  // carry the committed histories of the pairs that stay in the table (both lists sorted)
  new_hist_.assign(new_key_.size(), LudingHistory{});
  std::size_t a = 0;
  for (std::size_t b = 0; b < new_key_.size(); ++b) {
    while (a < pair_key_.size() && pair_key_[a] < new_key_[b]) ++a;
    if (a < pair_key_.size() && pair_key_[a] == new_key_[b]) new_hist_[b] = pair_hist_[a];
  }
  pair_key_.swap(new_key_);
  pair_hist_.swap(new_hist_);
}

void DynamicSolver::touching_pairs(
    std::vector<std::pair<std::uint32_t, std::uint32_t>>& out) const {
  out.clear();
  for (std::uint64_t key : pair_key_) {
    const std::uint32_t i = static_cast<std::uint32_t>(key >> 32);
    const std::uint32_t j = static_cast<std::uint32_t>(key & 0xffffffffu);
    const double dx = P_.x[j] - P_.x[i], dy = P_.y[j] - P_.y[i];
    const double s = P_.radius[i] + P_.radius[j];
    if (dx * dx + dy * dy < s * s) out.emplace_back(i, j);
  }
}

const LudingHistory* DynamicSolver::history(std::uint32_t i, std::uint32_t j) const {
  const std::uint64_t key = (static_cast<std::uint64_t>(i) << 32) | j;
  auto it = std::lower_bound(pair_key_.begin(), pair_key_.end(), key);
  if (it == pair_key_.end() || *it != key) return nullptr;
  return &pair_hist_[static_cast<std::size_t>(it - pair_key_.begin())];
}

// ---- forces ------------------------------------------------------------------------------------
void DynamicSolver::compute_forces_dispatch() {
  // once per step: the contact loop below is straight-line code for one feature set
  switch (opt_.model) {
    case ContactModel::Linear:
      if (friction_)
        compute_forces<contact::kLudingLinear>();
      else
        compute_forces<kLinearFrictionless>();
      break;
    case ContactModel::Hysteretic:
      if (friction_)
        compute_forces<kHysteretic>();
      else
        compute_forces<kHystereticFrictionless>();
      break;
    case ContactModel::Full:
      if (friction_)
        compute_forces<contact::kLudingFull>();
      else
        compute_forces<kFullFrictionless>();
      break;
  }
}

template <LudingFeatures F>
void DynamicSolver::compute_forces() {
  const std::size_t n = P_.size();
  const double dt = ts_.dt;
  const double k1Tt = thermal_.k1_Tt;
  double sxx = 0, sxy = 0, syx = 0, syy = 0, el = 0;
  for (std::size_t i = 0; i < n; ++i) {
    P_.fx[i] = P_.mass[i] * opt_.gravity_x;
    P_.fy[i] = P_.mass[i] * opt_.gravity_y;
    P_.torque[i] = 0.0;
  }
  // particle-particle contacts from the Verlet table
  for (std::size_t k = 0; k < pair_key_.size(); ++k) {
    const std::size_t i = static_cast<std::size_t>(pair_key_[k] >> 32);
    const std::size_t j = static_cast<std::size_t>(pair_key_[k] & 0xffffffffu);
    const double dx = P_.x[j] - P_.x[i], dy = P_.y[j] - P_.y[i];
    const double ri = P_.radius[i], rj = P_.radius[j];
    const double L2 = dx * dx + dy * dy, s = ri + rj;
    if (!(L2 < s * s)) {  // separated: the law clears the history (docs/luding.md)
      pair_hist_[k] = LudingHistory{};
      continue;
    }
    const double L = std::sqrt(L2);
    const double nx = dx / L, ny = dy / L, tx = -ny, ty = nx;  // n from i to j, t = perp(n)
    const double q = (ri * ri - rj * rj) / (2.0 * L);
    const double di = 0.5 * L + q, dj = 0.5 * L - q;  // centre-to-chord distances (kinematics.hpp)
    // velocity of j's contact point relative to i's: v_j - w_j d_j t - (v_i + w_i d_i t)
    const double rvx = P_.vx[j] - P_.vx[i], rvy = P_.vy[j] - P_.vy[i];
    const double vn = rvx * nx + rvy * ny;
    const double vt = rvx * tx + rvy * ty - P_.omega[i] * di - P_.omega[j] * dj;
    LudingInput in;
    in.delta = s - L;
    in.delta_dot = -vn;
    in.xi_dot = vt;
    in.dxi = vt * dt;
    in.k1_Tt = k1Tt;
    const LudingResult r = contact::luding_evaluate<F>(params_, pair_hist_[k], in);
    pair_hist_[k] = r.history;
    const double fx = r.f_n * nx + r.f_t * tx, fy = r.f_n * ny + r.f_t * ty;  // force on j
    P_.fx[j] += fx;
    P_.fy[j] += fy;
    P_.fx[i] -= fx;
    P_.fy[i] -= fy;
    P_.torque[i] -= di * r.f_t;  // M_i = M_j = -d F_T (kinematics.hpp)
    P_.torque[j] -= dj * r.f_t;
    sxx += fx * dx;  // Sigma = (1/V) sum f (x) l, l = x_j - x_i
    sxy += fx * dy;
    syx += fy * dx;
    syy += fy * dy;
    el += 0.5 * params_.k2 * in.delta * in.delta;
  }
  // walls: the pair (wall, particle), n from the wall into the box
  double wf[4] = {0, 0, 0, 0};
  if (box_.enabled) {
    const double wall_pos[4] = {box_.x_min, box_.x_max, box_.y_min, box_.y_max};
    const double wnx[4] = {1, -1, 0, 0}, wny[4] = {0, 0, 1, -1};
    const double wvx[4] = {0, wall_v_[0], 0, 0}, wvy[4] = {0, 0, 0, wall_v_[1]};
    for (std::size_t i = 0; i < n; ++i) {
      for (int w = 0; w < 4; ++w) {
        LudingHistory& h = wall_hist_[4 * i + static_cast<std::size_t>(w)];
        const double dist =
            w < 2 ? wnx[w] * (P_.x[i] - wall_pos[w]) : wny[w] * (P_.y[i] - wall_pos[w]);
        const double delta = P_.radius[i] - dist;
        if (!(delta > 0.0)) {
          h = LudingHistory{};
          continue;
        }
        const double nx = wnx[w], ny = wny[w], tx = -ny, ty = nx;
        const double rvx = P_.vx[i] - wvx[w], rvy = P_.vy[i] - wvy[w];
        const double vn = rvx * nx + rvy * ny;
        const double vt = rvx * tx + rvy * ty - P_.omega[i] * dist;
        LudingInput in;
        in.delta = delta;
        in.delta_dot = -vn;
        in.xi_dot = vt;
        in.dxi = vt * dt;
        in.k1_Tt = k1Tt;
        const LudingResult r = contact::luding_evaluate<F>(wall_params_, h, in);
        h = r.history;
        const double fx = r.f_n * nx + r.f_t * tx, fy = r.f_n * ny + r.f_t * ty;  // on particle
        P_.fx[i] += fx;
        P_.fy[i] += fy;
        P_.torque[i] -= dist * r.f_t;
        wf[w] -= w < 2 ? fx : fy;  // force of the contacts on the wall along x (y)
        const double lx = dist * nx, ly = dist * ny;  // contact point -> particle centre
        sxx += fx * lx;
        sxy += fx * ly;
        syx += fy * lx;
        syy += fy * ly;
        el += 0.5 * wall_params_.k2 * delta * delta;
      }
    }
  }
  for (int w = 0; w < 4; ++w) wall_force_[w] = wf[w];
  sxx_ = sxx;
  sxy_ = sxy;
  syx_ = syx;
  syy_ = syy;
  elastic_ = el;
}

// ---- integration: velocity Verlet, LMM05 Eq 2 and Eq 1 ------------------------------------------
void DynamicSolver::step() {
  const std::size_t n = P_.size();
  const double dt = ts_.dt, h = 0.5 * dt;
  // Eq 1 total wall forces at the current state: F_w - p z - gamma_w x'
  auto wall_accel = [&](int which) {
    const MovingWall& w = which == 0 ? box_.right : box_.top;
    if (w.mode != WallMode::Stress) return 0.0;
    const double z = which == 0 ? box_.y_max - box_.y_min : box_.x_max - box_.x_min;
    const double Fw = which == 0 ? wall_force_[1] : wall_force_[3];
    return (Fw - w.pressure * z - w.damping * wall_v_[which]) / w.mass;  // LMM05 Eq 1
  };
  // half-step kick of particles and moving walls; the damping term of Eq 1 is taken at the
  // half-step wall velocity (explicit)
  auto kick = [&] {
    for (std::size_t i = 0; i < n; ++i) {
      P_.vx[i] += h * P_.fx[i] / P_.mass[i];
      P_.vy[i] += h * P_.fy[i] / P_.mass[i];
      P_.omega[i] += h * P_.torque[i] / P_.inertia[i];
    }
    if (box_.enabled) {
      const double a0 = wall_accel(0), a1 = wall_accel(1);
      wall_v_[0] += h * a0;
      wall_v_[1] += h * a1;
    }
  };
  kick();
  for (std::size_t i = 0; i < n; ++i) {  // drift
    P_.x[i] += dt * P_.vx[i];
    P_.y[i] += dt * P_.vy[i];
    P_.theta[i] += dt * P_.omega[i];
  }
  if (box_.enabled) {
    box_.x_max += dt * wall_v_[0];
    box_.y_max += dt * wall_v_[1];
  }
  time_ += dt;
  if (needs_rebuild()) build_table();
  compute_forces_dispatch();  // forces use the half-step velocities for the damping terms
  kick();
}

void DynamicSolver::run(std::size_t n_steps) {
  for (std::size_t s = 0; s < n_steps; ++s) step();
}

// ---- observables --------------------------------------------------------------------------------
Stress2 DynamicSolver::wall_stress() const {
  Stress2 s;
  if (!box_.enabled) return s;
  s.xx = wall_force_[1] / (box_.y_max - box_.y_min);
  s.yy = wall_force_[3] / (box_.x_max - box_.x_min);
  return s;
}

Stress2 DynamicSolver::contact_stress() const {
  Stress2 s;
  if (!box_.enabled) return s;
  const double V = (box_.x_max - box_.x_min) * (box_.y_max - box_.y_min);
  s.xx = sxx_ / V;
  s.xy = sxy_ / V;
  s.yx = syx_ / V;
  s.yy = syy_ / V;
  return s;
}

double DynamicSolver::density() const {
  if (!box_.enabled) return 0.0;
  double a = 0.0;
  for (double r : P_.radius) a += std::numbers::pi * r * r;
  return a / ((box_.x_max - box_.x_min) * (box_.y_max - box_.y_min));
}

Energies DynamicSolver::energies() const {
  Energies e;
  for (std::size_t i = 0; i < P_.size(); ++i) {
    e.kinetic += 0.5 * P_.mass[i] * (P_.vx[i] * P_.vx[i] + P_.vy[i] * P_.vy[i]) +
                 0.5 * P_.inertia[i] * P_.omega[i] * P_.omega[i];
    e.gravity -= P_.mass[i] * (opt_.gravity_x * P_.x[i] + opt_.gravity_y * P_.y[i]);
  }
  e.elastic = elastic_;
  if (box_.enabled) {
    if (box_.right.mode == WallMode::Stress)
      e.wall_kinetic += 0.5 * box_.right.mass * wall_v_[0] * wall_v_[0];
    if (box_.top.mode == WallMode::Stress)
      e.wall_kinetic += 0.5 * box_.top.mass * wall_v_[1] * wall_v_[1];
  }
  return e;
}

}  // namespace netdem::dem
