// Explicit DEM solver, LMM05 Eq 1, 2, 6 (see solver.hpp and docs/dynamic.md).
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
using contact::LudingFeatures;
constexpr LudingFeatures kHysteretic{true, false, false, true};
constexpr LudingFeatures kLinearFrictionless{false, false, false, false};
constexpr LudingFeatures kHystereticFrictionless{true, false, false, false};
constexpr LudingFeatures kFullFrictionless{true, true, true, false};
}  // namespace

// The force loops are flattened for speed (below). The sanitizer and fuzz builds define
// NETDEM_NO_FLATTEN: instrumented and flattened, this file took GCC 400 s to compile instead of 46 s.
#ifdef NETDEM_NO_FLATTEN
#define NETDEM_FLATTEN
#else
#define NETDEM_FLATTEN [[gnu::flatten]]
#endif

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
// The law object of a step, from the parameters of its type: the plastic law from its
// parameters, the Luding law from its parameters and the material state k1(T, t).
template <class Law>
Law make_law(const LudingParams& lp, double k1_Tt, const contact::PlasticIndentationParams& pp) {
  if constexpr (std::is_same_v<typename Law::Params, contact::PlasticIndentationParams>)
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
NETDEM_FLATTEN void DynamicSolverT<D>::compute_forces() {
  const std::size_t n = P_.size();
  const Law pair_law = make_law<Law>(params_, thermal_.k1_Tt, opt_.plastic);
  const Law wall_law = make_law<Law>(wall_params_, thermal_.k1_Tt, pl_wall_params_);
  ForceSums a;
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
  if (periodic_) {  // (the 3D stress sums per contact, through the images)
    pair_forces<Law, InPlace, true>(pair_law, a);
  } else {
    pair_forces<Law, InPlace, false>(pair_law, a);
    if constexpr (D == 3) pair_stress_3d(a);
  }
  if (walls_active()) {
    if constexpr (D == 2)
      wall_forces_2d<Law, InPlace>(wall_law, a);
    else
      wall_forces_3d<Law, InPlace>(wall_law, a);
  }
  for (int w = 0; w < kWalls; ++w) wall_force_[w] = a.wf[w];
  if constexpr (contact::kHasContactArea<Law>) area_max_ = pair_law.contact_area(a.fn_max);
  sxx_ = a.sxx;
  sxy_ = a.sxy;
  syx_ = a.syx;
  syy_ = a.syy;
  if constexpr (D == 3) std::copy(&a.s3[0][0], &a.s3[0][0] + 9, &s3_[0][0]);
  elastic_ = a.el;
}

// The particle-particle contacts of the Verlet table: forces, torques, the 2D stress sums, the
// elastic energy and the largest normal force (the sums in locals: the loop stores forces).
// Periodic: the cell h and the strain rate L as 3 x 3 (zeros beyond D), for the force loop.
template <int D>
void DynamicSolverT<D>::hoist_cell(double (&hc)[3][3], double (&Lr)[3][3]) const {
  for (int r = 0; r < D; ++r)
    for (int c = 0; c < D; ++c) {
      hc[r][c] = cell_.h(r, c);
      Lr[r][c] = D == 2 ? (r == c ? edot_[r] : edot_[2]) : L3_[r][c];
    }
}

namespace {
// The offset h n of the image n (D integers) added to the branch (dx, dy, dz).
template <int D>
inline void add_image(const int* n, const double (&hc)[3][3], double& dx, double& dy, double& dz) {
  if (!(n[0] | n[1] | (D == 3 ? n[D - 1] : 0))) return;
  const double n0 = n[0], n1 = n[1], n2 = D == 3 ? n[D - 1] : 0;
  dx += hc[0][0] * n0 + hc[0][1] * n1 + hc[0][2] * n2;
  dy += hc[1][0] * n0 + hc[1][1] * n1 + hc[1][2] * n2;
  dz += hc[2][0] * n0 + hc[2][1] * n1 + hc[2][2] * n2;
}
}  // namespace

// Periodic (issue 29): the branch to the image of j, x_j + h n - x_i, and the velocities are the
// fluctuations about the affine field, so that the relative velocity adds L times the branch.
template <int D>
template <class Law, bool InPlace, bool Periodic>
NETDEM_FLATTEN void DynamicSolverT<D>::pair_forces(const Law& pair_law, ForceSums& a) {
  using H = typename Law::History;
  const double dt = ts_.dt;
  H* const pair_hist = table<H>().pair.data();  // the law's table, taken once per evaluation
  double sxx = 0, sxy = 0, syx = 0, syy = 0, el = 0, fn_max = 0;
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
  // the cell and the strain rate (Periodic), hoisted: 3 x 3 with zeros beyond D
  double hc[3][3] = {}, Lr[3][3] = {};
  const int* const shift = pair_shift_.data();
  if constexpr (Periodic) hoist_cell(hc, Lr);
  double s3p[3][3] = {};  // Periodic, 3D: the stress sums per contact
  for (std::size_t k = 0; k < n_pairs; ++k) {
    const std::size_t i = static_cast<std::size_t>(pair_key_[k] >> 32);
    const std::size_t j = static_cast<std::size_t>(pair_key_[k] & 0xffffffffu);
    double dx = p_x[j] - p_x[i], dy = p_y[j] - p_y[i];
    const double ri = p_radius[i], rj = p_radius[j];
    double dz = 0.0;
    if constexpr (D == 3) dz = p_z[j] - p_z[i];
    if constexpr (Periodic) add_image<D>(shift + D * k, hc, dx, dy, dz);
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
      double rvx = p_vx[j] - p_vx[i], rvy = p_vy[j] - p_vy[i];
      if constexpr (Periodic) {  // the affine field's part: L (x_j + h n - x_i)
        rvx += Lr[0][0] * dx + Lr[0][1] * dy;
        rvy += Lr[1][0] * dx + Lr[1][1] * dy;
      }
      const double vn = rvx * nx + rvy * ny;
      const double vt = rvx * tx + rvy * ty - p_omega[i] * di - p_omega[j] * dj;
      contact::ContactKinematics in;
      in.overlap = s - L;
      in.v_n = -vn;
      in.v_t = vt;
      in.dslip = vt * dt;
      in.dt = dt;
      if constexpr (contact::kReadsPairProperties<Law>) {  // (the Luding law reads neither)
        in.overlap_start = in.overlap - in.v_n * dt;
        in.r_eff = ri * rj / s;
        in.m_eff = P_.mass[i] * P_.mass[j] / (P_.mass[i] + P_.mass[j]);
      }
      double f_n, f_t;
      contact::update_contact<InPlace>(pair_law, pair_hist[k], in, f_n, f_t);
      if constexpr (Law::kHistoryOutlivesSeparation) pair_live_[k] = pair_law.has_history(pair_hist[k]) ? 1 : 0;
      if constexpr (contact::kHasContactArea<Law>) fn_max = f_n > fn_max ? f_n : fn_max;
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
      if constexpr (contact::kHasElasticEnergy<Law>) el += pair_law.elastic_energy(in);
    } else {
      const double L = std::sqrt(L2), iL = 1.0 / L;
      const Eigen::Vector3d n(dx * iL, dy * iL, dz * iL);  // from i to j
      const double q = (ri * ri - rj * rj) * (0.5 * iL);
      const double di = 0.5 * L + q, dj = 0.5 * L - q;  // centre-to-contact-plane distances
      Eigen::Vector3d vrel(p_vx[j] - p_vx[i], p_vy[j] - p_vy[i], p_vz[j] - p_vz[i]);
      if constexpr (Periodic) {  // the affine field's part: L (x_j + h n - x_i)
        const double br[3] = {dx, dy, dz};
        for (int r = 0; r < 3; ++r) vrel(r) += Lr[r][0] * br[0] + Lr[r][1] * br[1] + Lr[r][2] * br[2];
      }
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
      if constexpr (contact::kReadsPairProperties<Law>) {
        in.overlap_start = in.overlap - in.v_n * dt;
        in.r_eff = ri * rj / s;
        in.m_eff = P_.mass[i] * P_.mass[j] / (P_.mass[i] + P_.mass[j]);
      }
      double f_n;
      Eigen::Vector3d f_t;
      contact::update_contact<InPlace>(pair_law, pair_hist[k], in, f_n, f_t);
      if constexpr (Law::kHistoryOutlivesSeparation) pair_live_[k] = pair_law.has_history(pair_hist[k]) ? 1 : 0;
      if constexpr (contact::kHasContactArea<Law>) fn_max = f_n > fn_max ? f_n : fn_max;
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
      if constexpr (Periodic) {  // Sigma V = sum f (x) l, l the branch to the image
        const double br[3] = {dx, dy, dz};
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c) s3p[r][c] += f(r) * br[c];
      }
      if constexpr (contact::kHasElasticEnergy<Law>) el += pair_law.elastic_energy(in);
    }
  }
  a.sxx = sxx, a.sxy = sxy, a.syx = syx, a.syy = syy, a.el = el, a.fn_max = fn_max;
  if constexpr (Periodic && D == 3) std::copy(&s3p[0][0], &s3p[0][0] + 9, &a.s3[0][0]);
}

template <int D>
void DynamicSolverT<D>::pair_stress_3d(ForceSums& a) const {
  const std::size_t n = P_.size();
  const double* const p_x = P_.x.data();
  const double* const p_y = P_.y.data();
  const double* const p_z = P_.z.data();
  const double* const p_fx = P_.fx.data();
  const double* const p_fy = P_.fy.data();
  const double* const p_fz = P_.fz.data();
  double (&s3)[3][3] = a.s3;
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

// The particle-wall contacts, 2D: the pair (wall, particle), n from the wall into the box.
template <int D>
template <class Law, bool InPlace>
NETDEM_FLATTEN void DynamicSolverT<D>::wall_forces_2d(const Law& wall_law, ForceSums& a) {
  using H = typename Law::History;
  const std::size_t n = P_.size();
  const double dt = ts_.dt;
  H* const wall_hist = table<H>().wall.data();
  double& sxx = a.sxx; double& sxy = a.sxy; double& syx = a.syx; double& syy = a.syy;
  double& el = a.el; double& fn_max = a.fn_max;
  double* const wf = a.wf;
  // walls: the pair (wall, particle), n from the wall into the box
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
        if constexpr (contact::kReadsPairProperties<Law>) {
          in.overlap_start = delta - in.v_n * dt;
          in.r_eff = ai;
          in.m_eff = P_.mass[i];
        }
        double f_n, f_t;
        contact::update_contact<InPlace>(wall_law, h, in, f_n, f_t);
        if constexpr (contact::kHasContactArea<Law>) fn_max = f_n > fn_max ? f_n : fn_max;
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
        if constexpr (contact::kHasElasticEnergy<Law>) el += wall_law.elastic_energy(in);
      }
    }
    }
  }
}

// The particle-wall contacts, 3D: six walls.
template <int D>
template <class Law, bool InPlace>
NETDEM_FLATTEN void DynamicSolverT<D>::wall_forces_3d(const Law& wall_law, ForceSums& a) {
  using H = typename Law::History;
  const std::size_t n = P_.size();
  const double dt = ts_.dt;
  H* const wall_hist = table<H>().wall.data();
  double& el = a.el; double& fn_max = a.fn_max;
  double* const wf = a.wf;
  double (&s3)[3][3] = a.s3;
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
          if constexpr (contact::kReadsPairProperties<Law>) {
            in.overlap_start = delta - in.v_n * dt;
            in.r_eff = ai;
            in.m_eff = P_.mass[i];
          }
          double f_n;
          Eigen::Vector3d f_t;
          contact::update_contact<InPlace>(wall_law, h, in, f_n, f_t);
          if constexpr (contact::kHasContactArea<Law>) fn_max = f_n > fn_max ? f_n : fn_max;
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
          if constexpr (contact::kHasElasticEnergy<Law>) el += wall_law.elastic_energy(in);
        }
      }
    }
  }
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

// A law whose tangential spring grows with its contact area (StiffnessBound::k_t_area, the plastic
// law's k_t sigma_y A_c): the step follows the largest area of the last force evaluation (with 10 %
// margin for the growth within a step). A smaller area keeps the step.
template <int D>
void DynamicSolverT<D>::update_time_step() {
  const double kt = bound_.k_t + bound_.k_t_area * 1.1 * area_max_;
  if (kt <= 0.0) return;
  ts_.tc_tangential = tangential_period(m12_, kt, D);
  const bool use_mean = mean_pair_ && opt_.rule == TimeStepRule::MeanPair;
  const double tc_rule = use_mean ? ts_.tc_mean : ts_.tc_lightest;
  const double tc = std::min(tc_rule, use_mean ? tangential_period(m_rule_, kt, D) : ts_.tc_tangential);
  const double tc_check = std::min(ts_.tc_lightest, ts_.tc_tangential);
  if (opt_.dt > 0.0) {
    ts_.steps_per_contact_lightest = tc_check / ts_.dt;
    if (ts_.steps_per_contact_lightest < opt_.min_steps_per_contact)
      breach("time step",
             fmt::format("the fixed time step {:.4g} gives the stiffest tangential spring {:.3g} steps per period, "
                         "fewer than {:g}",
                         ts_.dt, ts_.steps_per_contact_lightest, opt_.min_steps_per_contact),
             "the contacts grew stiffer than the fixed time step allows (the fixed time step dt; let the rule choose it)");
    return;
  }
  ts_.dt = tc / opt_.steps_per_contact;
  ts_.steps_per_contact_lightest = tc_check == tc ? opt_.steps_per_contact : tc_check / ts_.dt;
}

template <int D>
void DynamicSolverT<D>::step() {
  if (bound_.k_t_area > 0.0) update_time_step();
  advance(true);
}

template <int D>
void DynamicSolverT<D>::step_to(double t) {
  if (!(t > time_)) fail(fmt::format("step_to: the time {} is not after the current time {}", t, time_));
  if (bound_.k_t_area > 0.0) update_time_step();
  const double left = t - time_;
  if (!(left < ts_.dt)) {
    advance(true);
    return;
  }
  const double rule = ts_.dt;  // the shortened step, then the rule's again
  ts_.dt = left;
  try {
    advance(false);
  } catch (...) {
    ts_.dt = rule;
    throw;
  }
  ts_.dt = rule;
}

template <int D>
void DynamicSolverT<D>::advance(bool full) {
  const std::size_t n = P_.size();
  impose_affine_motion(ts_.dt);
  const bool checking = opt_.check_every > 0;
  if (checking && full && !last_good_) last_good_ = std::make_shared<const SolverState>(state());
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
  double lim = displacement_limit(skin_, radius_ref_max_, radius_scale_, radius_scale_build_);
  if (periodic_) lim -= 0.5 * (F_build_ - Eigen::Matrix<double, D, D>::Identity()).norm() * range_max_;
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
  ++steps_taken_;
  if (far || walls_moved()) build_table();
  compute_forces_dispatch();  // forces use the half-step velocities for the damping terms
  if (opt_.affine_drag > 0.0) apply_affine_drag();
  kick(false);
  if (check) {
    since_check_ = 0;
    check_health_with(vmax2);
    if (full && since_good_ >= HealthLimits::kLastGoodEvery) {
      last_good_ = std::make_shared<const SolverState>(state());
      since_good_ = 0;
    }
  }
}

template class DynamicSolverT<2>;
template class DynamicSolverT<3>;

}  // namespace netdem::dem
