// Explicit DEM solver: instability checks and observables (solver.hpp, docs/dynamic.md).
#include "netdem/dynamic/solver.hpp"
#include "solver_detail.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <type_traits>
#include <variant>

#include <Eigen/Eigenvalues>
#include <fmt/format.h>

#include "netdem/contact/luding_law.hpp"

namespace netdem::dem {

using detail::displacement_limit;
using detail::fail;

// ---- instability checks (docs/dynamic.md "Instability detection") -------------------------------
namespace {
const char* const kCauseStep =
    "the time step is too large for the stiffness, the damping or the masses (steps per contact, k2, "
    "gamma_n, rho_p, m_wall, gamma_wall)";
const char* const kCauseWall =
    "a stress-controlled wall is unstable or driven too hard (m_wall, gamma_wall, the wall pressure p, the strain rate)";
const char* const kCauseLoad =
    "the load is too high for the stiffness (2p/k2, k1_ratio, k2, the strain rate) or the time step too large "
    "(steps per contact)";
// the same causes in the terms of the plastic-indentation law (Redanz & Fleck; demsolve compact, yield)
const char* const kCauseStepPlastic =
    "the time step is too large for the stiffness, the damping or the masses (steps per contact, the first-touch "
    "chord stiffness 6 sigma_y / sqrt(first_touch), the damping fractions, the density)";
const char* const kCauseWallPlastic = "a wall is driven too hard (the strain rate or the inertial number)";
const char* const kCauseLoadPlastic =
    "the load is too high for the stiffness (sigma_y, first_touch, the strain rate or the inertial number) or the "
    "time step too large (steps per contact)";

// the cause in the terms of the law the run uses
const char* cause_for(bool plastic, const std::string& cause) {
  if (!plastic) return cause.c_str();
  if (cause == kCauseStep) return kCauseStepPlastic;
  if (cause == kCauseWall) return kCauseWallPlastic;
  if (cause == kCauseLoad) return kCauseLoadPlastic;
  return cause.c_str();
}
}  // namespace

template <int D>
void DynamicSolverT<D>::breach(const std::string& quantity, const std::string& what, const std::string& cause) const {
  // fixed dt: the step since t = 0 (restarts included); the plastic law's dt varies, so its steps are counted
  const std::int64_t step =
      plastic() ? steps_taken_ : ts_.dt > 0.0 ? static_cast<std::int64_t>(std::llround(time_ / ts_.dt)) : 0;
  throw InstabilityError(fmt::format("unstable at step {} (t = {:.6g} s): {}; likely cause: {}", step, time_, what,
                                     cause_for(plastic(), cause)),
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
  constexpr std::size_t R = ParticlesT<D>::kRot;
  for (std::size_t i = 0; i < n; ++i) {
    bool fin = std::isfinite(P_.r[i]);
    for (std::size_t c = 0; c < D; ++c)
      fin = fin && std::isfinite(P_.pos[D * i + c]) && std::isfinite(P_.vel[D * i + c]) &&
            std::isfinite(P_.force[D * i + c]);
    for (std::size_t c = 0; c < R; ++c) fin = fin && std::isfinite(P_.spin[R * i + c]) && std::isfinite(P_.torque[R * i + c]);
    if (!fin)
      breach("finite", fmt::format("particle {} has a non-finite position, velocity or force", i), kCauseStep);
    rmin = std::min(rmin, P_.r[i]);
    const double* const v = &P_.vel[D * i];
    if constexpr (D == 2) {
      area += P_.r[i] * P_.r[i];
      if (track) vmax2 = std::max(vmax2, v[0] * v[0] + v[1] * v[1]);
    } else {
      area += P_.r[i] * P_.r[i] * P_.r[i];
      if (track) vmax2 = std::max(vmax2, v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
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
    const double lo[3] = {box_.x_min, box_.y_min, box_.z_min}, hi[3] = {box_.x_max, box_.y_max, box_.z_max};
    for (std::size_t i = 0; i < n && box_.contact_walls; ++i) {
      const double* const x = &P_.pos[D * i];
      bool inside = true;
      for (int a = 0; a < D; ++a) inside = inside && x[a] >= lo[a] && x[a] <= hi[a];
      if (!inside)
        breach("centre", fmt::format("the centre of particle {} ({:.6g}, {:.6g}) m is outside the box", i, x[0], x[1]),
               kCauseLoad);
    }
  }
  // overlaps: the pairs of the table (complete for the touching pairs) and the walls, each against
  // half the smaller radius of its contact (>= 0.5 r_min; docs/dynamic.md)
  for (std::size_t k = 0; k < rows_.pairs(); ++k) {
    const auto i = static_cast<std::size_t>(rows_.pi[k]), j = static_cast<std::size_t>(rows_.pj[k]);
    double dd[3];
    branch(k, i, j, dd);
    const double s = P_.r[i] + P_.r[j];
    double L2 = dd[0] * dd[0] + dd[1] * dd[1];
    if constexpr (D == 3) L2 += dd[2] * dd[2];
    if (!(L2 < s * s)) continue;
    const double d = s - std::sqrt(L2), lim = HealthLimits::kMaxOverlap * std::min(P_.r[i], P_.r[j]);
    if (!(d < lim))
      breach("overlap", fmt::format("the overlap {:.3g} m of particles {} and {} is not below half the smaller radius, "
                                    "{:.3g} m", d, i, j, lim),
             kCauseLoad);
  }
  if (walls_active()) {
    for (std::size_t i = 0; i < n; ++i) {
      const double r = P_.r[i];
      const double* const x = &P_.pos[D * i];
      double d = std::max(std::max(r - (x[0] - box_.x_min), r - (box_.x_max - x[0])),
                          std::max(r - (x[1] - box_.y_min), r - (box_.y_max - x[1])));
      if constexpr (D == 3) d = std::max(d, std::max(r - (x[2] - box_.z_min), r - (box_.z_max - x[2])));
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
  if (periodic_) return cell_.measure();
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
    for (double r : P_.r) a += std::numbers::pi * r * r;
    if (periodic_) return a / cell_.measure();
    return a / ((box_.x_max - box_.x_min) * (box_.y_max - box_.y_min));
  } else {
    for (double r : P_.r) a += (4.0 / 3.0) * std::numbers::pi * r * r * r;
    return a / box_measure();
  }
}

template <int D>
auto DynamicSolverT<D>::kinetic_stress() const -> Stress {
  Stress s;
  if (!box_.enabled) return s;
  double k[3][3] = {};
  for (std::size_t i = 0; i < P_.size(); ++i) {
    const double* const u = &P_.vel[D * i];
    const double m = P_.mass[i];
    for (int a = 0; a < D; ++a)
      for (int b = 0; b < D; ++b) k[a][b] += m * u[a] * u[b];
  }
  const double V = box_measure();
  if constexpr (D == 2) {
    s.xx = k[0][0] / V, s.xy = k[0][1] / V, s.yx = k[1][0] / V, s.yy = k[1][1] / V;
  } else {
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) s.s[a][b] = k[a][b] / V;
  }
  return s;
}

template <int D>
packing::Packing DynamicSolverT<D>::periodic_packing() const {
  if (!periodic_) fail("periodic_packing: the solver has no periodic cell");
  packing::Packing pk;
  pk.dim = D;
  pk.periodic = true;
  pk.r = P_.r;
  for (std::size_t i = 0; i < P_.size(); ++i) {
    Eigen::Matrix<double, D, 1> x = P_.position(i);
    // wrapped into [0, 1) (the rounding of origin + h s can land on the upper face: s = 1 - ulp)
    Eigen::Matrix<double, D, 1> f = cell_.fractional(x);
    for (int a = 0; a < D; ++a) {
      f(a) -= std::floor(f(a));
      if (!(f(a) < 1.0)) f(a) = 0.0;
    }
    x = cell_.origin + cell_.h * f;
    pk.x.push_back(x(0));
    pk.y.push_back(x(1));
    if constexpr (D == 3) pk.z.push_back(x(2));
  }
  pk.box.x_min = box_.x_min, pk.box.x_max = box_.x_max, pk.box.y_min = box_.y_min, pk.box.y_max = box_.y_max;
  if constexpr (D == 3) pk.box.z_min = box_.z_min, pk.box.z_max = box_.z_max;
  bool rectangle = true;
  for (int a = 0; a < D; ++a)
    for (int b = 0; b < D; ++b) rectangle = rectangle && (a == b || cell_.h(a, b) == 0.0);
  if (!rectangle)
    for (int a = 0; a < D; ++a)
      for (int b = 0; b < D; ++b) pk.cell.push_back(cell_.h(b, a));  // vector a at [D a, D a + D)
  return pk;
}

template <int D>
Energies DynamicSolverT<D>::energies() const {
  Energies e;
  for (std::size_t i = 0; i < P_.size(); ++i) {
    const double* const x = &P_.pos[D * i];
    const double* const v = &P_.vel[D * i];
    if constexpr (D == 2) {
      const double w = P_.spin[i];
      e.kinetic += 0.5 * P_.mass[i] * (v[0] * v[0] + v[1] * v[1]) + 0.5 * P_.inertia[i] * w * w;
      e.gravity -= P_.mass[i] * (opt_.gravity_x * x[0] + opt_.gravity_y * x[1]);
    } else {
      const double* const w = &P_.spin[3 * i];
      e.kinetic += 0.5 * P_.mass[i] * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) +
                   0.5 * P_.inertia[i] * (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
      e.gravity -= P_.mass[i] * (opt_.gravity_x * x[0] + opt_.gravity_y * x[1] + opt_.gravity_z * x[2]);
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

template <int D>
auto DynamicSolverT<D>::memory_use() const -> MemoryUse {
  const auto cap = [](const auto& v) { return v.capacity() * sizeof(typename std::decay_t<decltype(v)>::value_type); };
  MemoryUse m;
  m.particles = cap(P_.pos) + cap(P_.rot) + cap(P_.r) + cap(P_.vel) + cap(P_.spin) + cap(P_.mass) +
                cap(P_.inertia) + cap(P_.force) + cap(P_.torque) + cap(radius_ref_) + cap(prescribed_) +
                cap(is_prescribed_) + cap(spin_held_) + cap(vel_abs_) + cap(pos_build_) + cap(wall_touch_) +
                cap(wall_list_) + cap(inv_mass_) + cap(inv_inertia_) + cap(blk_p_) + cap(bnd_list_) + cap(bnd_off_) + cap(grp_sums_);
  m.rows = rows_.row_bytes() + cap(pair_live_) + cap(slot_buf_) + cap(row_start_) + cap(row_slot_) + cap(blk_k_);
  std::visit(
      [&](const auto& t) {
        m.rows += cap(t.pair) + cap(t.next);
        m.particles += cap(t.wall);
      },
      hist_);
  m.search = rows_.scratch_bytes();
  return m;
}

template void DynamicSolverT<2>::breach(const std::string& quantity, const std::string& what, const std::string& cause) const;
template void DynamicSolverT<2>::check_health() const;
template void DynamicSolverT<2>::check_health_with(double vmax2) const;
template void DynamicSolverT<2>::run(std::size_t n_steps);
template double DynamicSolverT<2>::box_measure() const;
template auto DynamicSolverT<2>::wall_stress() const -> Stress;
template auto DynamicSolverT<2>::contact_stress() const -> Stress;
template double DynamicSolverT<2>::density() const;
template Energies DynamicSolverT<2>::energies() const;
template auto DynamicSolverT<2>::kinetic_stress() const -> Stress;
template packing::Packing DynamicSolverT<2>::periodic_packing() const;
template auto DynamicSolverT<2>::memory_use() const -> MemoryUse;

template void DynamicSolverT<3>::breach(const std::string& quantity, const std::string& what, const std::string& cause) const;
template void DynamicSolverT<3>::check_health() const;
template void DynamicSolverT<3>::check_health_with(double vmax2) const;
template void DynamicSolverT<3>::run(std::size_t n_steps);
template double DynamicSolverT<3>::box_measure() const;
template auto DynamicSolverT<3>::wall_stress() const -> Stress;
template auto DynamicSolverT<3>::contact_stress() const -> Stress;
template double DynamicSolverT<3>::density() const;
template Energies DynamicSolverT<3>::energies() const;
template auto DynamicSolverT<3>::kinetic_stress() const -> Stress;
template packing::Packing DynamicSolverT<3>::periodic_packing() const;
template auto DynamicSolverT<3>::memory_use() const -> MemoryUse;

}  // namespace netdem::dem
