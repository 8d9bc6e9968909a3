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
    const double g[3] = {opt_.gravity_x, opt_.gravity_y, opt_.gravity_z};
    for (std::size_t i = 0; i < n; ++i)
      for (int c = 0; c < D; ++c) P_.force[D * i + c] = P_.mass[i] * g[c];
    std::fill(P_.torque.begin(), P_.torque.end(), 0.0);
  }
  forces_initialised_ = false;
  if (periodic_)  // (3D: the rows across the faces add their f (x) h n to a.s3)
    pair_forces<Law, InPlace, true>(pair_law, a);
  else
    pair_forces<Law, InPlace, false>(pair_law, a);
  if constexpr (D == 3) pair_stress_3d(a);
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
      Lr[r][c] = velocity_gradient(r, c);
    }
}

namespace {
// Whether the image n (D integers) is not the cell itself.
template <int D>
inline bool is_image(const int* n) {
  return (n[0] | n[1] | (D == 3 ? n[D - 1] : 0)) != 0;
}
// The offset o = h n of the image n (D integers), o[2] = 0 in 2D.
template <int D>
inline void image_offset(const int* n, const double (&hc)[3][3], double (&o)[3]) {
  const double n0 = n[0], n1 = n[1], n2 = D == 3 ? n[D - 1] : 0;
  for (int r = 0; r < 3; ++r) o[r] = hc[r][0] * n0 + hc[r][1] * n1 + hc[r][2] * n2;
}
// b += h n for a row across a face (image n): the branch to j's image; nothing inside the cell.
template <int D>
inline void add_image(const int* n, const double (&hc)[3][3], double& b0, double& b1, double& b2) {
  if (!is_image<D>(n)) [[likely]]
    return;
  double o[3];
  image_offset<D>(n, hc, o);
  b0 += o[0], b1 += o[1], b2 += o[2];
}
// v += L h n for a row across a face (image n): the affine velocity of the image's offset.
template <int D>
inline void add_image_velocity(const int* n, const double (&hc)[3][3], const double (&L)[3][3], double& v0,
                               double& v1, double& v2) {
  if (!is_image<D>(n)) [[likely]]
    return;
  double o[3];
  image_offset<D>(n, hc, o);
  v0 += L[0][0] * o[0] + L[0][1] * o[1] + L[0][2] * o[2];
  v1 += L[1][0] * o[0] + L[1][1] * o[1] + L[1][2] * o[2];
  v2 += L[2][0] * o[0] + L[2][1] * o[1] + L[2][2] * o[2];
}
// s += f (x) h n for a row across a face (image n): its part of the periodic stress sum.
template <int D>
inline void add_image_stress(const int* n, const double (&hc)[3][3], const double (&f)[3], double (&s)[3][3]) {
  if (!is_image<D>(n)) [[likely]]
    return;
  double o[3];
  image_offset<D>(n, hc, o);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) s[r][c] += f[r] * o[c];
}
// The pair loops' handling of a row that does not touch: whether the law sees row k (touching, or a
// history that outlives separation: pass 1a's count), and pass 2's test, which resets the history
// of a separated row where the law clears it (docs/luding.md) and returns true when the row is
// skipped (apart, and no history to keep).
template <class Law>
inline bool law_sees(bool touch, std::uint8_t live) {
  if constexpr (Law::kHistoryOutlivesSeparation)
    return touch || live;
  else
    return touch;
}
template <class Law, class H>
inline bool skip_row(bool touch, std::uint8_t& live, H& hist) {
  if (touch) return false;
  if constexpr (!Law::kHistoryOutlivesSeparation) {
    if (live) {
      hist = H{};
      live = 0;
    }
    return true;
  } else {
    return !live;  // apart and no history: no force, nothing to keep
  }
}
}  // namespace

#include "solver_pairs_2d.hpp"  // (inside this namespace: it uses add_image and NETDEM_FLATTEN)

// Periodic 3D: the velocities plus the affine field's L x, D per particle, into vel_abs_.
template <int D>
void DynamicSolverT<D>::fill_absolute_velocities(const double (&Lr)[3][3]) {
  if constexpr (D == 3) {
    vel_abs_.resize(P_.vel.size());  // (allocates only when the particle count grows)
    const double *const p_x = P_.pos.data(), *const p_v = P_.vel.data();
    for (std::size_t i = 0, n = P_.size(); i < n; ++i) {
      const double* const x = p_x + 3 * i;
      for (int r = 0; r < 3; ++r)
        vel_abs_[3 * i + r] = p_v[3 * i + r] + (Lr[r][0] * x[0] + Lr[r][1] * x[1] + Lr[r][2] * x[2]);
    }
  }
}

#include "solver_pairs_3d.hpp"  // (inside this namespace, as solver_pairs_2d.hpp)
#include "solver_threads.hpp"  // (inside this namespace: the pair loop on threads)

template <int D>
void DynamicSolverT<D>::pair_stress_3d(ForceSums& a) const {
  // The pairs' part of Sigma V = sum_pairs f (x) (x_j - x_i) (f on j) is sum_i F_i (x) x_i, with
  // F_i the sum of the pair forces on i: one pass over the particles instead of one sum per
  // contact, per group of kSumGroup particles (pair_forces: on the threads each its own groups),
  // the groups then added in order.
  double s[9] = {};
  for (std::size_t g = 0; g < sum_groups(); ++g)
    for (int c = 0; c < 9; ++c) s[c] += pst_sums_[9 * g + static_cast<std::size_t>(c)];
  for (int c = 0; c < 9; ++c) (&a.s3[0][0])[c] += s[c];
}

// Groups [g0, g1) of sum_i F_i (x) x_i into pst_sums_ (9 per group). F_i is the accumulator less
// the m g it started from (the same product), and x_i is taken from the first particle (exactly
// translation invariant, and no cancellation of large coordinates).
template <int D>
void DynamicSolverT<D>::particle_stress_groups(std::size_t g0, std::size_t g1) {
  const std::size_t n = P_.size();
  const double* const p_x = P_.pos.data();
  const double* const p_f = P_.force.data();
  const double* const p_mass = P_.mass.data();
  const double gx = opt_.gravity_x, gy = opt_.gravity_y, gz = opt_.gravity_z;
  const double x0 = n > 0 ? p_x[0] : 0.0, y0 = n > 0 ? p_x[1] : 0.0, z0 = n > 0 ? p_x[D - 1] : 0.0;
  for (std::size_t g = g0; g < g1; ++g) {
    double s00 = 0, s01 = 0, s02 = 0, s10 = 0, s11 = 0, s12 = 0, s20 = 0, s21 = 0, s22 = 0;
    for (std::size_t i = g * kSumGroup; i < std::min(n, (g + 1) * kSumGroup); ++i) {
      const double* const f = p_f + D * i;
      const double* const x = p_x + D * i;
      const double Fx = f[0] - p_mass[i] * gx, Fy = f[1] - p_mass[i] * gy, Fz = f[D - 1] - p_mass[i] * gz;
      const double X = x[0] - x0, Y = x[1] - y0, Z = x[D - 1] - z0;
      s00 += Fx * X, s01 += Fx * Y, s02 += Fx * Z;
      s10 += Fy * X, s11 += Fy * Y, s12 += Fy * Z;
      s20 += Fz * X, s21 += Fz * Y, s22 += Fz * Z;
    }
    double* const q = pst_sums_.data() + 9 * g;
    q[0] = s00, q[1] = s01, q[2] = s02, q[3] = s10, q[4] = s11, q[5] = s12, q[6] = s20, q[7] = s21, q[8] = s22;
  }
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
      const double xi = P_.pos[D * i], yi = P_.pos[D * i + 1], ai = P_.r[i];
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
        const double rvx = P_.vel[D * i] - wvx[w], rvy = P_.vel[D * i + 1] - wvy[w];
        const double vn = rvx * nx + rvy * ny;
        const double vt = rvx * tx + rvy * ty - P_.spin[i] * dist;
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
        P_.force[D * i] += fx;
        P_.force[D * i + 1] += fy;
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
        const double* const pos = &P_.pos[D * i];
        const double ai = P_.r[i];
        double d6[6];
        unsigned touch = 0;
        for (int w = 0; w < 6; ++w) {
          d6[w] = (w & 1) ? hi[w / 2] - pos[w / 2] : pos[w / 2] - lo[w / 2];
          touch |= ai - d6[w] > 0.0 ? (1u << w) : 0u;
        }
        const unsigned todo = touch | wall_touch_[i];
        wall_touch_[i] = static_cast<std::uint8_t>(touch);
        if (todo == 0) continue;
        const Eigen::Vector3d wi(P_.spin[D * i], P_.spin[D * i + 1], P_.spin[D * i + 2]);  // (kRot = D)
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
          Eigen::Vector3d vrel(P_.vel[D * i], P_.vel[D * i + 1], P_.vel[D * i + 2]);
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
          P_.force[D * i] += f.x();
          P_.force[D * i + 1] += f.y();
          P_.force[D * i + 2] += f.z();
          const Eigen::Vector3d m = nw.cross(f_t);  // -dist n x f_t
          P_.torque[D * i] -= dist * m.x();
          P_.torque[D * i + 1] -= dist * m.y();
          P_.torque[D * i + 2] -= dist * m.z();
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
// The passes run over flat arrays: the translational ones over D n entries (velocities, forces,
// positions and the inverse masses, D per particle), the rotational ones over kRot n, so that
// every stream advances at the same stride and the loops vectorise without shuffles; the arrays
// are restrict parameters (GCC keeps restrict for a function's parameters, not for local
// pointers).
// Half kick v += h f / m, w += h tau / I (spheres have an isotropic inertia, so the spin kick is
// h tau / I per component). Track (the steps of an instability check only): also returns max
// |v|^2 after the kick (NaN if a velocity is NaN), so that the check needs no pass of its own
// over the velocities.
// max(m, x), except that a NaN x replaces the maximum and stays (associative: blocks may combine).
inline double nan_keeping_max(double m, double x) { return x > m || x != x ? x : m; }
template <int D, bool Track>
double kick_pass_impl(std::size_t n, double h, double* __restrict v, double* __restrict w,
                      const double* __restrict f, const double* __restrict t, const double* __restrict im,
                      const double* __restrict iI) {
  constexpr std::size_t R = ParticlesT<D>::kRot;
  for (std::size_t k = 0; k < D * n; ++k) v[k] += h * f[k] * im[k];
  for (std::size_t k = 0; k < R * n; ++k) w[k] += h * t[k] * iI[k];
  double vmax2 = 0.0;
  if constexpr (Track) {
    for (std::size_t i = 0; i < n; ++i) {
      const double* const u = v + D * i;
      double v2 = u[0] * u[0] + u[1] * u[1];
      if constexpr (D == 3) v2 += u[2] * u[2];
      vmax2 = nan_keeping_max(vmax2, v2);
    }
  }
  return vmax2;
}
// The kicks' inverse masses: D per particle (im) and kRot per particle (iI).
// Particles [i0, i1).
template <int D, bool Track>
double kick_pass(std::size_t i0, std::size_t i1, double h, ParticlesT<D>& P, const double* im, const double* iI) {
  constexpr std::size_t R = ParticlesT<D>::kRot;
  return kick_pass_impl<D, Track>(i1 - i0, h, P.vel.data() + D * i0, P.spin.data() + R * i0, P.force.data() + D * i0,
                                  P.torque.data() + R * i0, im + D * i0, iI + R * i0);
}
// First half kick and drift (2D: the angle too); also the table check (displacement since the
// build xb beyond sqrt(lim2): returns 1) and the reset of the force accumulators to m g for the
// coming force evaluation.
template <int D, bool Gravity>
int kick_drift_pass_impl(std::size_t n, double h, double dt, double lim2, double* __restrict x, double* __restrict th,
                         double* __restrict v, double* __restrict w, double* __restrict f, double* __restrict t,
                         const double* __restrict m, const double* __restrict im, const double* __restrict iI,
                         const double* __restrict xb, const double (&g)[3]) {
  constexpr std::size_t R = ParticlesT<D>::kRot;
  for (std::size_t k = 0; k < D * n; ++k) {
    v[k] += h * f[k] * im[k];
    x[k] += dt * v[k];  // drift
  }
  for (std::size_t k = 0; k < R * n; ++k) {
    w[k] += h * t[k] * iI[k];
    if constexpr (D == 2) th[k] += dt * w[k];  // (3D: the orientation is not tracked)
    t[k] = 0.0;
  }
  int moved = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double* const xi = x + D * i;
    const double* const bi = xb + D * i;
    const double ddx = xi[0] - bi[0], ddy = xi[1] - bi[1];
    double d2 = ddx * ddx + ddy * ddy;
    if constexpr (D == 3) {
      const double ddz = xi[2] - bi[2];
      d2 += ddz * ddz;
    }
    moved |= d2 > lim2 ? 1 : 0;
    for (int c = 0; c < D; ++c) f[D * i + c] = Gravity ? m[i] * g[c] : 0.0;
  }
  return moved;
}
template <int D, bool Gravity>
int kick_drift_pass(std::size_t i0, std::size_t i1, double h, double dt, double lim2, ParticlesT<D>& P,
                    const double* im, const double* iI, const double* xb, const double (&g)[3]) {
  constexpr std::size_t R = ParticlesT<D>::kRot;
  return kick_drift_pass_impl<D, Gravity>(i1 - i0, h, dt, lim2, P.pos.data() + D * i0, P.rot.data() + R * i0,
                                          P.vel.data() + D * i0, P.spin.data() + R * i0, P.force.data() + D * i0,
                                          P.torque.data() + R * i0, P.mass.data() + i0, im + D * i0, iI + R * i0,
                                          xb + D * i0, g);
}
// f(i0, i1, t) on the particles [0, n) split into blocks, one per thread of the team (one block
// below kMinThreadedParticles particles or with one thread); returns the number of blocks.
constexpr std::size_t kMinThreadedParticles = 2048;
template <class F>
int on_blocks(sys::TeamHandle& team, int threads, std::size_t n, F&& f) {
  if (threads <= 1 || n < kMinThreadedParticles) {
    f(std::size_t{0}, n, 0);
    return 1;
  }
  auto block = [&](int t, int nt) {
    const auto ts = static_cast<std::size_t>(t), nts = static_cast<std::size_t>(nt);
    f(n * ts / nts, n * (ts + 1) / nts, t);
  };
  sys::ThreadTeam& members = team.get(threads);
  members.run(block);
  return members.size();
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
  if (periodic_ && !prescribed_.empty()) hold_prescribed_fluctuations();
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
  constexpr std::size_t R = ParticlesT<D>::kRot;
  if (inv_mass_.size() != D * n || inv_scale_ != radius_scale_) {  // no division in the kicks
    inv_mass_.resize(D * n);  // (D per particle, kRot per particle: the kicks' flat loops)
    inv_inertia_.resize(R * n);
    for (std::size_t i = 0; i < n; ++i) {
      std::fill_n(&inv_mass_[D * i], D, 1.0 / P_.mass[i]);
      std::fill_n(&inv_inertia_[R * i], R, 1.0 / P_.inertia[i]);
    }
    for (std::uint32_t p : prescribed_) {  // the kicks leave them
      std::fill_n(&inv_mass_[D * p], D, 0.0);
      if (spin_held_[p]) std::fill_n(&inv_inertia_[R * p], R, 0.0);
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
  const double *const im = inv_mass_.data(), *const iI = inv_inertia_.data();
  double part[256];  // per block: moved, or max |v|^2 (the blocks' maxima combined in block order)
  auto kick = [&](bool drift) {
    if (drift) {
      const double g[3] = {opt_.gravity_x, opt_.gravity_y, opt_.gravity_z};
      const bool gravity = g[0] != 0.0 || g[1] != 0.0 || (D == 3 && g[2] != 0.0);
      const int used = on_blocks(team_, opt_.threads, n, [&](std::size_t i0, std::size_t i1, int t) {
        part[t] = gravity ? kick_drift_pass<D, true>(i0, i1, h, dt, lim2, P_, im, iI, pos_build_.data(), g)
                          : kick_drift_pass<D, false>(i0, i1, h, dt, lim2, P_, im, iI, pos_build_.data(), g);
      });
      for (int t = 0; t < used; ++t) far = far || part[t] != 0.0;
      forces_initialised_ = true;
    } else if (check) {
      const int used = on_blocks(team_, opt_.threads, n, [&](std::size_t i0, std::size_t i1, int t) {
        part[t] = kick_pass<D, true>(i0, i1, h, P_, im, iI);
      });
      for (int t = 0; t < used; ++t) vmax2 = nan_keeping_max(vmax2, part[t]);  // (the blocks in order: as one)
    } else {
      on_blocks(team_, opt_.threads, n, [&](std::size_t i0, std::size_t i1, int) { kick_pass<D, false>(i0, i1, h, P_, im, iI); });
    }
    if (box_.enabled) {
      double acc[D];  // (all from the walls' state before the kick)
      for (int a = 0; a < D; ++a) acc[a] = wall_accel(a);
      for (int a = 0; a < D; ++a) wall_v_[a] += h * acc[a];
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
