// The frictionless increment of the pseudo-transient iteration as the minimisation it is: a
// trust region (Levenberg-Marquardt) on the contact energy.
//
// Without friction the contact forces derive from a potential at fixed committed histories: the
// sum over the pairs (and wall contacts) of the normal force's integral (normal_work, the law's
// potential on the branch the committed u_max selects). The undragged residual f is minus its
// gradient over the free DOFs, so an equilibrium is a stationary point and a stable one a minimum.
// Each iteration solves (M + eta W) delta = f with the symmetric iteration matrix M (W: 1 on the
// translations, r_mean^2 on the rotations), scales the step down uniformly when it would move a
// particle by more than max_step mean radii, and keeps it only when the energy fell by more than
// 1e-4 of the decrease the quadratic model predicts, rho = actual / predicted. eta follows Nielsen's
// rule (eta x max(1/3, 1 - (2 rho - 1)^3) on a kept step, x 2, 4, 8, ... on rejected ones),
// within [drag_floor, drag_ceiling] x its start value. Like the residual iteration's drag, eta
// acts on the step only: the accepted state solves f = 0, whatever eta. A rearrangement (a
// snap-through: no nearby minimum) is followed downhill in energy, which the residual's line
// search cannot judge (the residual rises on the way). docs/quasistatic.md "Frictionless: a
// trust region on the energy". With friction (opt-in, friction_energy_merit, 2D) the same trust
// region runs on an incremental potential: each tangential spring's stiffness and limit frozen at
// the iterate (freeze_tangential; docs/quasistatic.md "With friction: a trust region on an
// incremental potential").
#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "solver_impl.hpp"

namespace netdem::qs {

namespace {
using Clock = std::chrono::steady_clock;
}  // namespace

/// The contact energy of the trial state: the pairs' normal_work (pw, filled with the forces),
/// then the wall contacts' (fixed order: reproducible to the bit).
template <int D, class L>
double NetworkSolverT<D, L>::Impl::energy() const {
  double w = 0.0;
  for (double x : pw) w += x;
  if (walls())
    for (double x : wwork) w += x;
  return w;
}

/// Pair k's tangential spring stiffness and limit frozen at the normal force f_n of the iterate.
template <int D, class L>
void NetworkSolverT<D, L>::Impl::freeze_tangential(std::size_t k, double f_n) {
  if constexpr (ct::kHasPotential<Law>) {
    const auto [kt, limit] = law.tangential_frozen(f_n);
    t_kt[k] = kt;
    t_limit[k] = limit;
  } else {
    (void)k, (void)f_n;
  }
}

/// After a rebuild within a step (friction): the frozen stiffness and limit of the new rows, from
/// the normal forces at the iterate (du_ref); returns the energy there (the trial state is left to
/// the caller's evaluation).
template <int D, class L>
double NetworkSolverT<D, L>::Impl::refreeze_at_iterate() {
  std::swap(du, du_ref);
  t_kt.assign(pi.size(), 0.0);
  t_limit.assign(pi.size(), 0.0);
  evaluate_forces();
  for (std::size_t k = 0; k < pi.size(); ++k)
    if (!apart[k]) freeze_tangential(k, trial[k].f_n);
  evaluate_forces();
  const double e = energy();
  std::swap(du, du_ref);
  return e;
}

/// Keeps the assembled diagonal of M (with the tiny regularisation) so that shifts can be changed
/// without assembling again.
template <int D, class L>
void NetworkSolverT<D, L>::Impl::keep_diagonal() {
  const double eps = opt.regularisation * mean_diagonal();
  mdiag.assign(static_cast<std::size_t>(nfree), 0.0);
  for (int p = 0; p < n; ++p)
    for (int a = 0; a < kN; ++a)
      if (const int d = dof[kN * p + a]; d >= 0)
        mdiag[static_cast<std::size_t>(d)] =
            M.valuePtr()[pattern.diag(d)] + eps * (is_rotation(a) ? r_mean * r_mean : 1.0);
}

/// M's diagonal = the kept one + shift W.
template <int D, class L>
void NetworkSolverT<D, L>::Impl::shift_matrix(double shift) {
  for (int p = 0; p < n; ++p)
    for (int a = 0; a < kN; ++a)
      if (const int d = dof[kN * p + a]; d >= 0)
        M.valuePtr()[pattern.diag(d)] =
            mdiag[static_cast<std::size_t>(d)] + shift * (is_rotation(a) ? r_mean * r_mean : 1.0);
}

/// The uniform factor (<= 1) that keeps every particle's translation in sol within max_step mean
/// radii (and its rotation within max_rotation_step).
template <int D, class L>
double NetworkSolverT<D, L>::Impl::step_scale() const {
  double s = 1.0;
  for (int p = 0; p < n; ++p) {
    double t2 = 0.0, r2 = 0.0;
    for (int a = 0; a < kN; ++a)
      if (const int d = dof[kN * p + a]; d >= 0) (is_rotation(a) ? r2 : t2) += sol(d) * sol(d);
    const double t = std::sqrt(t2), r = std::sqrt(r2);
    if (t > opt.max_step * r_mean) s = std::min(s, opt.max_step * r_mean / t);
    if (r > opt.max_rotation_step) s = std::min(s, opt.max_rotation_step / r);
  }
  return s;
}

/// du += a sol on the free DOFs.
template <int D, class L>
void NetworkSolverT<D, L>::Impl::add_step(double a) {
  for (int p = 0; p < n; ++p)
    for (int c = 0; c < kN; ++c)
      if (const int d = dof[kN * p + c]; d >= 0) du[kN * p + c] += a * sol(d);
}

/// Whether the trial state (x + du, the trial box) has moved so far from the positions of the last
/// neighbour rebuild that a pair outside the table could touch (the table's own rule).
template <int D, class L>
bool NetworkSolverT<D, L>::Impl::trial_needs_rebuild() {
  ps_trial.pos = ps.pos;
  if (ps_trial.r.size() != ps.r.size()) ps_trial.r = ps.r;  // the radii do not change
  for (int p = 0; p < n; ++p)
    for (int a = 0; a < D; ++a) ps_trial.pos[D * p + a] += du[kN * p + a];
  return this->needs_rebuild(ps_trial, Fbox_trial, opt.skin * r_mean, r_max);
}

/// A rebuild within the increment: the rows found at the trial positions and box (their committed
/// history and data carried, new rows fresh), then the per-pair data of the increment for them.
/// A frictionless rearrangement can carry a particle farther than the skin in one increment.
template <int D, class L>
void NetworkSolverT<D, L>::Impl::rebuild_at_trial() {
  std::swap(ps.pos, ps_trial.pos);  // ps_trial holds x + du (trial_needs_rebuild)
  const Mat F = Fbox;
  Fbox = Fbox_trial;
  build_neighbours();
  Fbox = F;
  std::swap(ps.pos, ps_trial.pos);
  begin_pairs();
}

template <int D, class L>
IncrementReport NetworkSolverT<D, L>::Impl::attempt_energy(const Mat& dE) {
  const auto t_start = Clock::now();
  IncrementReport rep;
  start_attempt(dE, rep);  // the affine predictor (prescribe)
  if (trial_needs_rebuild()) {  // the predictor went past the skin
    rebuild_at_trial();
    rep.reanalysed = true;
  }
  bool nonsym = false;
  bool assembled = false;  // M and its kept diagonal belong to the current du
  double energy_now = 0.0;  // the energy at the iterate
  // the forces and the energy at du, with the table rebuilt first where du has gone farther than
  // the table's skin allows (a rebuild keeps every touching pair: the energy of a state does not
  // change with it; the matrix must be assembled again on the new pattern)
  auto evaluate_here = [&] {
    if (trial_needs_rebuild()) {
      rebuild_at_trial();
      rep.reanalysed = true;
      assembled = false;
      if (friction_energy()) energy_now = refreeze_at_iterate();
    }
    evaluate_forces();
  };
  double fbar = 1.0, shift = 0.0, growth = 2.0;
  // the force of a contact at the law's first-touch overlap (mean radii): below it a packing has
  // no load-bearing network the law resolves, and the residual is measured against it instead of
  // a mean contact force that tends to zero (an unjammed state's equilibrium is force-free)
  const double r_star = 0.5 * r_mean;
  const double f_touch = law.first_touch_force(r_star);
  for (int it = 0;; ++it) {
    if (!assembled) {
      const auto ta = Clock::now();
      assemble(nonsym);
      tim.assemble += seconds_since(ta);
      if (eta < 0.0) {
        start_drag(dE);
        shift = eta;
      }
      keep_diagonal();
      energy_now = energy();
      assembled = true;
    }
    du_ref = du;  // the step's drag is zero at the iterate: the residual is the undragged one
    fbar = mean_normal_force();
    if (fbar <= 0.0) fbar = law.reference_force(r_mean) * 1e-6;
    const bool below_touch = fbar < f_touch;
    fbar = std::max(fbar, f_touch);
    double res_max = 0.0;
    const double res = nfree > 0 ? residual(fbar, true, &res_max) : 0.0;
    rep.newton_residual = res;
    if (!std::isfinite(res)) throw DivergedError("increment: non-finite contact forces (diverged Newton iteration)");
    if (opt.verbose) print_iteration(it, res, res_max, fbar);
    if (accepted(res, res_max) || nfree == 0) {
      rep.converged = true;
      rep.unjammed = below_touch;
      break;
    }
    if (it >= opt.max_newton) break;
    ++rep.newton_iterations;
    eta = shift;
    shift_matrix(shift);
    LinearStatus st = lin.factorise(M, pattern_changed);
    pattern_changed = false;
    if (!st.ok && st.minor >= 0 && shift < eta0 * opt.drag_ceiling) {  // indefinite: a larger shift
      shift = std::min(shift * growth, eta0 * opt.drag_ceiling);
      growth *= 2.0;
      rep.instability = true;
      continue;
    }
    if (!st.ok) throw std::runtime_error("increment: " + st.message);
    st = lin.solve(rhs, sol);
    if (!st.ok) throw std::runtime_error("increment: " + st.message);
    rep.linear_iterations += st.iterations;
    // the quadratic model's decrease along a = step_scale() x delta:
    // a f.delta - a^2/2 delta.M0.delta, with delta.M0.delta = f.delta - shift delta.W.delta
    double fd = 0.0, dwd = 0.0;
    for (int p = 0; p < n; ++p)
      for (int c = 0; c < kN; ++c)
        if (const int d = dof[kN * p + c]; d >= 0) {
          fd += rhs(d) * sol(d);
          dwd += sol(d) * sol(d) * (is_rotation(c) ? r_mean * r_mean : 1.0);
        }
    const double a = step_scale();
    const double predicted = a * fd - 0.5 * a * a * (fd - shift * dwd);
    add_step(a);
    evaluate_here();
    double energy_trial = energy();
    double rho = predicted > 0.0 ? (energy_now - energy_trial) / predicted : -1.0;
    // a decrease at the round-off of the energy cannot be judged by it: the step is judged by the
    // residual there (kept as a good model step when the residual fell)
    auto residual_fell = [&](double factor) {  // the undragged residual at du below factor x the iterate's
      const double fb = std::max(mean_normal_force(), 1e-300);
      eta = 0.0;
      const bool fell = residual(fb, false) < factor * res * fbar / fb;
      eta = shift;
      return fell;
    };
    if (!(predicted > 1e-12 * std::fabs(energy_now))) {
      rho = residual_fell(1.0) ? 1.0 : -1.0;
    } else if (friction_energy() && rho <= 1e-4 && residual_fell(0.5)) {
      // with friction the frozen potential's gradient is the law's force at the iterate only: its
      // change over a step is the law's work to first order in the step (the slip's lever arms and
      // the normal's turn move with it), which near an equilibrium is the size of the decrease
      // itself; there a step that halves the residual is kept (a Newton step in its quadratic range)
      rho = 1.0;
    }
    // the model was too stiff along delta (the energy fell more than predicted, about twice as much
    // where the energy is nearly linear: a soft mode the iteration matrix stiffens): go on along
    // delta while the energy keeps falling, doubling the step up to 8 times its first length
    double a_total = a;
    if (rho > 1.2) {
      for (int ext = 0; ext < 3; ++ext) {
        add_step(a_total);
        evaluate_here();
        const double e2 = energy();
        if (!(e2 < energy_trial)) {
          add_step(-a_total);
          evaluate_here();
          break;
        }
        energy_trial = e2;
        a_total *= 2.0;
      }
    }
    if (opt.verbose)
      std::fprintf(stderr, "    energy step %.4f (x%g): rho %.3f, energy %.9e -> %.9e, shift %.3e (x start %.3g)\n", a, a_total / a, rho, energy_now, energy_trial, shift,
                   shift / std::max(eta0, 1e-300));
    if (rho > 1e-4) {  // kept: the energy fell
      rep.drag_work += shift * a_total * a_total * dwd;
      shift *= std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * rho - 1.0, 3));
      growth = 2.0;
      assembled = false;
    } else {  // rejected: back to the iterate, a shorter step (a larger shift)
      add_step(-a);
      evaluate_here();
      shift *= growth;
      growth *= 2.0;
    }
    shift = std::clamp(shift, eta0 * opt.drag_floor, eta0 * opt.drag_ceiling);
    if (shift > eta0) rep.instability = true;
  }
  finish_attempt(dE, fbar, t_start, rep);
  return rep;
}

// the plastic law (2D, 3D): netdem_quasistatic; the linear law: NETDEM_QS_MORE (CMakeLists.txt)
#ifndef NETDEM_QS_MORE
template struct NetworkSolverT<2>::Impl;
template struct NetworkSolverT<3>::Impl;
#else
template struct NetworkSolverT<2, LinearLawT<2>>::Impl;
template struct NetworkSolverT<3, LinearLawT<3>>::Impl;
#endif

}  // namespace netdem::qs
