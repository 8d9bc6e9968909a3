// Explicit DEM solver: macroscopic strain rate, prescribed particles, affine walls, drag (solver.hpp).
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
  W_[0][1] = W_[1][0] = 0.0;  // a symmetric L (set_velocity_gradient sets the spin after this)
  spun_ = false;
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
    for (auto& row : W_) row[0] = row[1] = row[2] = 0.0;  // a symmetric L (set_velocity_gradient: the spin after)
    spun_ = false;
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
  if (periodic_) {  // the velocities are the fluctuations about the affine field, the spins its spin
    std::fill(P_.vel.begin(), P_.vel.end(), 0.0);
    for (std::size_t i = 0; i < P_.spin.size(); ++i) P_.spin[i] = affine_spin(static_cast<int>(i % ParticlesT<D>::kRot));
    return;
  }
  if constexpr (D == 3) {
    for (std::size_t i = 0; i < P_.size(); ++i) {
      affine_velocity3(i, &P_.vel[D * i]);
      P_.spin[D * i] = P_.spin[D * i + 1] = P_.spin[D * i + 2] = 0.0;  // (kRot = D)
    }
    return;
  }
  const double e12 = edot_[2];
  for (std::size_t i = 0; i < P_.size(); ++i) {
    const double dx = P_.pos[D * i] - box_.x_min, dy = P_.pos[D * i + 1] - box_.y_min;
    double* const v = &P_.vel[D * i];
    v[0] = edot_[0] * dx;
    v[1] = edot_[1] * dy;
    if (e12 != 0.0) {
      v[0] += e12 * dy;
      v[1] += e12 * dx;
    }
    P_.spin[i] = 0.0;
  }
}

template <int D>
void DynamicSolverT<D>::shift_affine_velocities(const Eigen::Matrix<double, D, D>& dL) {
  if (periodic_) return;  // the velocities are the fluctuations about the affine field
  for (std::size_t i = 0; i < P_.size(); ++i) {
    if (!is_prescribed_.empty() && is_prescribed_[i]) continue;  // imposed at the next step
    const double lo[3] = {box_.x_min, box_.y_min, box_.z_min};
    Eigen::Matrix<double, D, 1> d;
    for (int a = 0; a < D; ++a) d(a) = P_.pos[D * i + a] - lo[a];
    const Eigen::Matrix<double, D, 1> dv = dL * d;
    for (int a = 0; a < D; ++a) P_.vel[D * i + a] += dv(a);
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
    HistoryTable<PlasticHist>& t = table<PlasticHist>();
    for (std::size_t k = 0; k < rows_.pairs(); ++k) {
      const auto i = static_cast<std::size_t>(rows_.pi[k]), j = static_cast<std::size_t>(rows_.pj[k]);
      double d[3];
      branch(k, i, j, d);
      double L2 = d[0] * d[0] + d[1] * d[1];
      if constexpr (D == 3) L2 += d[2] * d[2];
      t.pair[k] = L::start_unloading_branch(t.pair[k], P_.r[i] + P_.r[j] - std::sqrt(L2));
    }
    if (walls_active())
      for (std::size_t i = 0; i < P_.size(); ++i) {
        const double lo[3] = {box_.x_min, box_.y_min, box_.z_min}, hi[3] = {box_.x_max, box_.y_max, box_.z_max};
        double dw[2 * D];
        for (int a = 0; a < D; ++a) {
          dw[2 * a] = P_.pos[D * i + a] - lo[a];
          dw[2 * a + 1] = hi[a] - P_.pos[D * i + a];
        }
        for (std::size_t w = 0; w < kWalls; ++w)
          t.wall[kWalls * i + w] = L::start_unloading_branch(t.wall[kWalls * i + w], P_.r[i] - dw[w]);
      }
  }
  opt_.plastic = law;
  pl_wall_params_ = law;
  pl_wall_params_.mu = opt_.plastic_wall_mu;
  choose_friction();
  const double dt_fixed = opt_.dt;
  choose_time_step_of_law(opt_, area_max_);
  if (!(dt_fixed > 0.0)) update_time_step();
}

template <int D>
void DynamicSolverT<D>::set_rotations(bool free) {
  rotations_ = free;
  if (!free) std::fill(P_.spin.begin(), P_.spin.end(), 0.0);
  inv_mass_.clear();  // refilled by the next step
}

template <int D>
void DynamicSolverT<D>::hold_spins(const std::vector<std::uint32_t>& particles) {
  for (std::uint32_t p : particles) {
    if (p >= P_.size() || is_prescribed_.empty() || !is_prescribed_[p])
      fail("hold_spins: particle " + std::to_string(p) + " is not prescribed (call set_prescribed first)");
    spin_held_[p] = 1;
    for (int c = 0; c < ParticlesT<D>::kRot; ++c) P_.spin[ParticlesT<D>::kRot * p + c] = 0.0;
  }
  inv_mass_.clear();  // the kicks' inverse inertias are refilled
  if (periodic_) hold_prescribed_fluctuations();  // a held spin is the cell's
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
  if (periodic_) hold_prescribed_fluctuations();  // at once, not at the next step
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
  if (spun_) {  // a general velocity gradient (periodic cells only)
    impose_general_motion(dt);
    return;
  }
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
      if (periodic_) advect_periodic(Eigen::Matrix3d(Eigen::Vector3d(md[0], md[1], md[2]).asDiagonal()));
      const double lo[3] = {box_.x_min, box_.y_min, box_.z_min};
      for (std::uint32_t p : prescribed_) {
        for (int a = 0; a < 3; ++a) P_.vel[D * p + a] = g[a] * (P_.pos[D * p + a] - lo[a]);
        if (spin_held_[p]) P_.spin[D * p] = P_.spin[D * p + 1] = P_.spin[D * p + 2] = 0.0;
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
      if (periodic_) {
        Eigen::Matrix3d Gm;
        for (int a = 0; a < 3; ++a)
          for (int b = 0; b < 3; ++b) Gm(a, b) = G[a][b];
        advect_periodic(Gm);
      }
      const auto F = F3m_;  // F <- (I + G) F
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) {
          double v = F[static_cast<std::size_t>(3 * a + b)];
          for (int k = 0; k < 3; ++k) v += G[a][k] * F[static_cast<std::size_t>(3 * k + b)];
          F3m_[static_cast<std::size_t>(3 * a + b)] = v;
        }
      const double inv = 1.0 / dt;
      const double lo[3] = {box_.x_min, box_.y_min, box_.z_min};
      for (std::uint32_t p : prescribed_) {
        double d[3];
        for (int a = 0; a < 3; ++a) d[a] = P_.pos[D * p + a] - lo[a];
        for (int a = 0; a < 3; ++a) P_.vel[D * p + a] = (G[a][0] * d[0] + G[a][1] * d[1] + G[a][2] * d[2]) * inv;
        if (spin_held_[p]) P_.spin[D * p] = P_.spin[D * p + 1] = P_.spin[D * p + 2] = 0.0;
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
    if constexpr (D == 2) {
      if (periodic_) advect_periodic((Eigen::Matrix2d() << M[0], M[1], M[2], M[3]).finished());
    }
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
      const double dx = P_.pos[D * p] - box_.x_min, dy = P_.pos[D * p + 1] - box_.y_min;
      P_.vel[D * p] = g11 * dx + g12 * dy;
      P_.vel[D * p + 1] = g12 * dx + g22 * dy;
      if (spin_held_[p]) P_.spin[p] = 0.0;
    }
  } else {
    for (std::uint32_t p : prescribed_) {
      P_.vel[D * p] = gx * (P_.pos[D * p] - box_.x_min);
      P_.vel[D * p + 1] = gy * (P_.pos[D * p + 1] - box_.y_min);
      if (spin_held_[p]) P_.spin[p] = 0.0;
    }
  }
  if (box_.right.mode == WallMode::Affine) wall_v_[0] = gx * (box_.x_max - box_.x_min);
  if (box_.top.mode == WallMode::Affine) wall_v_[1] = gy * (box_.y_max - box_.y_min);
}

// A periodic cell carries the affine motion (advect_periodic) and the velocities are the
// fluctuations about it: a prescribed particle has none, and a held spin is the cell's (zero
// without a velocity gradient's spin).
template <int D>
void DynamicSolverT<D>::hold_prescribed_fluctuations() {
  constexpr int R = ParticlesT<D>::kRot;
  for (std::uint32_t p : prescribed_) {
    std::fill_n(&P_.vel[D * static_cast<std::size_t>(p)], D, 0.0);
    if (spin_held_[p])
      for (int k = 0; k < R; ++k) P_.spin[R * static_cast<std::size_t>(p) + static_cast<std::size_t>(k)] = affine_spin(k);
  }
}

// 3D: the affine velocity L (x_i - x_0) of particle i (diagonal L: the products of before the shear rates)
template <int D>
void DynamicSolverT<D>::affine_velocity3(std::size_t i, double* a) const {
  if constexpr (D == 3) {
    if (periodic_) {  // the velocities are the fluctuations
      a[0] = a[1] = a[2] = 0.0;
      return;
    }
    const double* const x = &P_.pos[D * i];
    const double d[3] = {x[0] - box_.x_min, x[1] - box_.y_min, x[D - 1] - box_.z_min};
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
        const double r = P_.r[i], I = P_.inertia[i];
        const double* const t = &P_.torque[D * i];  // (kRot = D)
        const double* const w = &P_.spin[D * i];
        const double mx = (t[0] + c * I * (w[0] - affine_spin(0))) / r, my = (t[1] + c * I * (w[1] - affine_spin(1))) / r,
                     mz = (t[2] + c * I * (w[2] - affine_spin(2))) / r;
        sum += mx * mx + my * my + mz * mz;
        ++n;
      }
      if (pres) continue;
      const double m = P_.mass[i];
      double a[3];
      affine_velocity3(i, a);
      const double* const f = &P_.force[D * i];
      const double* const v = &P_.vel[D * i];
      const double fx = f[0] + c * m * (v[0] - a[0]);
      const double fy = f[1] + c * m * (v[1] - a[1]);
      const double fz = f[2] + c * m * (v[2] - a[2]);
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
        const double m = (P_.torque[i] + c * P_.inertia[i] * (P_.spin[i] - affine_spin(0))) / P_.r[i];
        sum += m * m;
        ++n;
      }
      continue;
    }
    const double* const x = &P_.pos[D * i];
    const double* const f = &P_.force[D * i];
    const double* const v = &P_.vel[D * i];
    const double dx = x[0] - box_.x_min, dy = x[1] - box_.y_min;
    double ax = edot_[0] * dx + edot_[2] * dy, ay = edot_[1] * dy + edot_[2] * dx;
    if (periodic_) ax = ay = 0.0;  // the velocities are the fluctuations
    const double fx = f[0] + c * P_.mass[i] * (v[0] - ax), fy = f[1] + c * P_.mass[i] * (v[1] - ay);
    const double m = rotations_ ? (P_.torque[i] + c * P_.inertia[i] * (P_.spin[i] - affine_spin(0))) / P_.r[i] : 0.0;
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
        for (int k = 0; k < 3; ++k) P_.torque[D * i + k] -= c * P_.inertia[i] * (P_.spin[D * i + k] - affine_spin(k));  // (kRot = D)
      }
      if (pres) continue;
      double a[3];
      affine_velocity3(i, a);
      for (int k = 0; k < 3; ++k) P_.force[D * i + k] -= c * P_.mass[i] * (P_.vel[D * i + k] - a[k]);
    }
    return;
  }
  const double c = opt_.affine_drag;
  for (std::size_t i = 0; i < P_.size(); ++i) {
    if (!is_prescribed_.empty() && is_prescribed_[i]) {
      if (!spin_held_[i]) P_.torque[i] -= c * P_.inertia[i] * (P_.spin[i] - affine_spin(0));  // a free spin
      continue;
    }
    const double dx = P_.pos[D * i] - box_.x_min, dy = P_.pos[D * i + 1] - box_.y_min;
    double ax = edot_[0] * dx, ay = edot_[1] * dy;
    if (edot_[2] != 0.0) {
      ax += edot_[2] * dy;
      ay += edot_[2] * dx;
    }
    if (periodic_) ax = ay = 0.0;  // the velocities are the fluctuations
    P_.force[D * i] -= c * P_.mass[i] * (P_.vel[D * i] - ax);
    P_.force[D * i + 1] -= c * P_.mass[i] * (P_.vel[D * i + 1] - ay);
    P_.torque[i] -= c * P_.inertia[i] * (P_.spin[i] - affine_spin(0));
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
      const double* const f = &P_.force[D * p];
      double l[3];
      for (int a = 0; a < 3; ++a) l[a] = P_.pos[D * p + a] - c[a];
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
    const double lx = P_.pos[D * p] - xc, ly = P_.pos[D * p + 1] - yc;
    const double fx = P_.force[D * p], fy = P_.force[D * p + 1];
    s.xx += fx * lx;
    s.xy += fx * ly;
    s.yx += fy * lx;
    s.yy += fy * ly;
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

// The periodic cell over a step (issue 29): the affine part of the motion, x <- x + G (x - origin)
// with G = exp(L dt) - I, for the particles and their positions at the last table build (so that the
// table's check sees the fluctuations only), and the cell h <- (I + G) h. box() follows the
// cell's bounding box.
template <int D>
void DynamicSolverT<D>::advect_periodic(const Eigen::Matrix<double, D, D>& G) {
  // G and the origin as plain numbers: no Eigen accessor is called per particle (a sanitizer build
  // with clang called them out of line, into the copies of its -O0 translation units)
  double o[D], Gm[D][D];
  for (int a = 0; a < D; ++a) {
    o[a] = cell_.origin(a);
    for (int b = 0; b < D; ++b) Gm[a][b] = G(a, b);
  }
  auto move = [&](std::vector<double>& pos) {  // D per particle
    for (std::size_t i = 0; i < pos.size() / D; ++i) {
      double* const x = &pos[D * i];
      double d[D];
      for (int a = 0; a < D; ++a) d[a] = x[a] - o[a];
      double g[3] = {0.0, 0.0, 0.0};
      for (int a = 0; a < D; ++a)
        for (int b = 0; b < D; ++b) g[a] += Gm[a][b] * d[b];
      for (int a = 0; a < D; ++a) x[a] += g[a];
    }
  };
  move(P_.pos);
  move(pos_build_);
  cell_.h += G * cell_.h;
  F_build_ += G * F_build_;
  set_box_to_cell();
}

template <int D>
void DynamicSolverT<D>::set_box_to_cell() {
  Eigen::Matrix<double, D, 1> lo = cell_.origin, hi = cell_.origin;
  for (int corner = 1; corner < (1 << D); ++corner) {
    Eigen::Matrix<double, D, 1> p = cell_.origin;
    for (int a = 0; a < D; ++a)
      if ((corner >> a) & 1) p += cell_.h.col(a);
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  box_.x_min = lo(0), box_.x_max = hi(0), box_.y_min = lo(1), box_.y_max = hi(1);
  if constexpr (D == 3) box_.z_min = lo(2), box_.z_max = hi(2);
}

template void DynamicSolverT<2>::advect_periodic(const Eigen::Matrix2d& G);
template void DynamicSolverT<3>::advect_periodic(const Eigen::Matrix3d& G);
template void DynamicSolverT<2>::set_box_to_cell();
template void DynamicSolverT<3>::set_box_to_cell();

template void DynamicSolverT<2>::set_strain_rate(double e11, double e22, double e12);
template void DynamicSolverT<2>::set_strain_rate3(double e11, double e22, double e33, double e23, double e13, double e12);
template void DynamicSolverT<2>::set_affine_velocities();
template void DynamicSolverT<2>::shift_affine_velocities(const Eigen::Matrix2d&);
template void DynamicSolverT<2>::set_plastic_law(const contact::PlasticIndentationParams& law);
template void DynamicSolverT<2>::set_rotations(bool free);
template void DynamicSolverT<2>::hold_spins(const std::vector<std::uint32_t>& particles);
template void DynamicSolverT<2>::set_prescribed(const std::vector<std::uint32_t>& particles, bool hold_spins);
template void DynamicSolverT<2>::hold_prescribed_fluctuations();
template void DynamicSolverT<2>::impose_affine_motion(double dt);
template void DynamicSolverT<2>::affine_velocity3(std::size_t i, double* a) const;
template void DynamicSolverT<2>::set_affine_drag(double drag);
template double DynamicSolverT<2>::unbalanced_force_rms() const;
template void DynamicSolverT<2>::apply_affine_drag();
template auto DynamicSolverT<2>::boundary_stress() const -> Stress;

template void DynamicSolverT<3>::set_strain_rate(double e11, double e22, double e12);
template void DynamicSolverT<3>::set_strain_rate3(double e11, double e22, double e33, double e23, double e13, double e12);
template void DynamicSolverT<3>::set_affine_velocities();
template void DynamicSolverT<3>::shift_affine_velocities(const Eigen::Matrix3d&);
template void DynamicSolverT<3>::set_plastic_law(const contact::PlasticIndentationParams& law);
template void DynamicSolverT<3>::set_rotations(bool free);
template void DynamicSolverT<3>::hold_spins(const std::vector<std::uint32_t>& particles);
template void DynamicSolverT<3>::set_prescribed(const std::vector<std::uint32_t>& particles, bool hold_spins);
template void DynamicSolverT<3>::hold_prescribed_fluctuations();
template void DynamicSolverT<3>::impose_affine_motion(double dt);
template void DynamicSolverT<3>::affine_velocity3(std::size_t i, double* a) const;
template void DynamicSolverT<3>::set_affine_drag(double drag);
template double DynamicSolverT<3>::unbalanced_force_rms() const;
template void DynamicSolverT<3>::apply_affine_drag();
template auto DynamicSolverT<3>::boundary_stress() const -> Stress;

}  // namespace netdem::dem
