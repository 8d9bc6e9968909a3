// The Newton driver of one increment: predictor, Newton iterations (fresh tangents and chord
// steps), the linear solve, the residual line search, the local sweep, and the commit of the
// converged (or carried) trial state.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>

#include "solver_impl.hpp"

namespace netdem::qs {

namespace {
using Clock = std::chrono::steady_clock;
}  // namespace

template <int D, class L>
IncrementReport NetworkSolverT<D, L>::increment(const Mat& dE) {
  if (!dE.allFinite()) throw std::runtime_error("increment: strain increment is not finite");
  return advance(dE, 0);
}

// An increment, cut in halves while it is not accepted (pseudo-transient iteration): the committed
// state before it is restored exactly (the state copy continues bit-identically) and the two
// halves are done in turn. The report sums the iterations of all attempts (the undone one
// included) and the drag work of the path kept; a cut increment is an instability event. It is
// accepted when its second half is (the state it ends in is an equilibrium); a sub-increment at
// the finest cut that is not accepted is committed as it is, part of the damped path, and counted
// (unconverged_substeps).
template <int D, class L>
IncrementReport NetworkSolverT<D, L>::advance(const Mat& dE, int depth) {
  auto attempt = [this](const Mat& d) {
    IncrementReport r = impl_->energy_mode() ? impl_->attempt_energy(d) : impl_->attempt(d);
    r.unconverged_substeps = r.converged ? 0 : 1;
    return r;
  };
  if (!impl_->pseudo_transient() || depth >= impl_->opt.max_cuts) return attempt(dE);
  const State saved = state();
  IncrementReport first;
  try {
    first = attempt(dE);
    if (first.converged) return first;
  } catch (const DivergedError&) {
  }
  const SolverTimings spent = impl_->tim;
  NetworkSolverT restored(saved, impl_->opt);
  std::swap(impl_, restored.impl_);
  impl_->tim = spent;
  impl_->lin_base = spent;
  IncrementReport rep = advance(dE / 2.0, depth + 1);
  const IncrementReport second = advance(dE / 2.0, depth + 1);
  rep.newton_iterations += first.newton_iterations + second.newton_iterations;
  rep.linear_iterations += first.linear_iterations + second.linear_iterations;
  rep.converged = second.converged;
  rep.unconverged_substeps += second.unconverged_substeps;
  rep.residual = second.residual;
  rep.residual_rms = second.residual_rms;
  rep.newton_residual = second.newton_residual;
  rep.reanalysed = true;
  rep.new_contacts += second.new_contacts;
  rep.lost_contacts += second.lost_contacts;
  rep.sliding = second.sliding;
  rep.substeps += second.substeps;
  rep.instability = true;
  rep.unjammed = second.unjammed;  // the state the increment ends in
  rep.drag_work += second.drag_work;
  rep.contact_work += second.contact_work;
  return rep;
}

template <int D, class L>
IncrementReport NetworkSolverT<D, L>::Impl::attempt(const Mat& dE) {
  const auto t_start = Clock::now();
  IncrementReport rep;
  start_attempt(dE, rep);
  double fbar = 1.0;
  bool f_valid = false;  // f, pf and the trial state belong to the current du
  for (int it = 0;; ++it) {
    const bool want_tangent = it < opt.max_newton;
    // chord steps: between fresh tangents, iterations reuse the last assembled K and its factor
    const bool fresh = opt.chord_steps <= 0 || it % (opt.chord_steps + 1) == 0;
    bool nonsym = opt.law.frictional();
    const auto ta = Clock::now();
    if (want_tangent && nfree > 0 && fresh) {
      assemble(nonsym);
    } else if (!f_valid) {
      evaluate_forces();
    }  // else: a chord step from a state the line search and the local sweep left current
    tim.assemble += seconds_since(ta);
    // pseudo-transient: the drag acts on the step from this iterate, so the residual below is the
    // undragged one (the legacy drag keeps du_ref = du_aff for the whole increment)
    if (pseudo_transient()) du_ref = du;
    if (eta < 0.0 && want_tangent && nfree > 0) start_drag(dE);
    fbar = mean_normal_force();
    if (fbar <= 0.0) fbar = law.reference_force(r_mean) * 1e-6;
    double newton_max = 0.0;
    const double newton_res = nfree > 0 ? residual(fbar, true, &newton_max) : 0.0;  // RMS
    rep.newton_residual = newton_res;
    if (!std::isfinite(newton_res))
      throw DivergedError("increment: non-finite contact forces (diverged Newton iteration)");
    if (opt.verbose) print_iteration(it, newton_res, newton_max, fbar);
    if (accepted(newton_res, newton_max) || nfree == 0) {
      rep.converged = true;
      break;
    }
    if (!want_tangent) break;
    if (pseudo_transient() && fresh) adapt_drag(newton_res, rep);
    if (!pseudo_transient()) du_before = du;  // pseudo-transient: the step starts at du_ref
    linear_step(fresh, nonsym, rep);
    const bool f_current = line_search(newton_res);
    f_valid = local_sweeps(f_current);  // relax_worst refreshes the pairs of the particles it moved
    rep.drag_work += drag_work(pseudo_transient() ? du_ref : du_before);
    ++rep.newton_iterations;
  }
  finish_attempt(dE, fbar, t_start, rep);
  return rep;
}

// The start of an attempt at an increment: the neighbour table rebuilt if the committed state has
// moved past its skin, the predictor and the per-pair data.
template <int D, class L>
void NetworkSolverT<D, L>::Impl::start_attempt(const Mat& dE, IncrementReport& rep) {
  if (this->needs_rebuild(ps, Fbox, opt.skin * r_mean, r_max)) {
    build_neighbours();
    rep.reanalysed = true;
  }
  begin_increment(dE);
}

// The end of an attempt: the undragged residual, the contact work, the commit and the timers.
template <int D, class L>
void NetworkSolverT<D, L>::Impl::finish_attempt(const Mat& dE, double fbar, Clock::time_point t_start,
                                             IncrementReport& rep) {
  rep.residual = nfree > 0 ? unbalance(fbar, &rep.residual_rms) : 0.0;
  if (opt.verbose && nfree > 0) print_worst(fbar);
  rep.contact_work = contact_work();
  commit(dE, rep);
  tim.newton_iterations += rep.newton_iterations;
  tim.total += seconds_since(t_start);
}

/// Whether an iterate with this residual (RMS and max over the free DOFs, relative to the mean
/// contact force) is an accepted equilibrium. Pseudo-transient: the residual is the undragged one.
template <int D, class L>
bool NetworkSolverT<D, L>::Impl::accepted(double rms, double max) const {
  if (pseudo_transient()) return rms <= opt.residual_tol && max <= opt.max_residual_factor * opt.residual_tol;
  return rms <= opt.residual_tol && max <= opt.max_residual_tol;
}

/// The pseudo-time step between fresh iterations, within [floor, ceiling] x the drag's start value:
/// - the last step was cut by the line search (the pseudo-time step was too long): the drag grows
///   by the ratio of the undragged residuals if they rose, else it stays;
/// - else, the residual fell: switched evolution relaxation, the drag follows that ratio down;
/// - else the full step was taken and the residual rose: the drag stays; when that happens twice
///   in a row, the signature of an unstable path (a buckling chain, a snap-through), it halves, so
///   that the path is followed faster (switched evolution relaxation would raise it and stall on
///   the unstable branch). A single rise is often a contact changing status.
/// A rise above the start value marks the increment as an instability event.
template <int D, class L>
void NetworkSolverT<D, L>::Impl::adapt_drag(double res, IncrementReport& rep) {
  if (res_fresh > 0.0 && res > 0.0) {
    const double ratio = res / res_fresh;
    rises = ratio > 1.0 ? rises + 1 : 0;
    double f = ratio <= 1.0 ? ratio : rises >= 2 ? 0.5 : 1.0;
    if (last_alpha < 1.0) f = std::max(ratio, 1.0);
    eta = std::clamp(eta * f, eta0 * opt.drag_floor, eta0 * opt.drag_ceiling);
  }
  if (eta > eta0) rep.instability = true;
  res_fresh = res;
}

/// Work of the drag along the step from `before` to du: eta (du - du_ref) . (du - before) over the
/// free DOFs (rotations with eta r_mean^2). Pseudo-transient: eta |step|^2, the energy the path
/// dissipated in the step.
template <int D, class L>
double NetworkSolverT<D, L>::Impl::drag_work(const std::vector<double>& before) const {
  const double eta_t = std::max(eta, 0.0), eta_r = eta_t * r_mean * r_mean;
  double w = 0.0;
  for (int q = 0; q < kN * n; ++q)
    if (dof[q] >= 0) w += (is_rotation(q % kN) ? eta_r : eta_t) * (du[q] - du_ref[q]) * (du[q] - before[q]);
  return w;
}

/// Work of the contact forces over the increment, trapezoidal in the committed and the trial
/// forces: the normal force on the overlap change while in contact (a pair that closes or opens
/// carries force from or to zero overlap), the tangential force against the slip increment (the
/// law's f_t opposes the slip: f_t = f_t0 - k dslip), and the wall contacts' normal forces. For a
/// quasi-static increment without drag it equals the boundary's work, V S:dE.
template <int D, class L>
double NetworkSolverT<D, L>::Impl::contact_work() const {
  double w = 0.0;
  for (std::size_t k = 0; k < pi.size(); ++k) {
    const auto& t = trial[k];
    if (!t.loaded && fn_c[k] <= 0.0) continue;
    const int i = pi[k], j = pj[k];
    const double u1 = ct::pair_geometry(moved(i), moved_j(k), ps.r[i], ps.r[j]).overlap;
    w += 0.5 * (fn_c[k] + t.f_n) * (std::max(u1, 0.0) - std::max(g0[k].overlap, 0.0));
    if constexpr (D == 2) {
      w -= 0.5 * (ft_c[k] + t.f_t) * trial_slip[k];
    } else {
      w -= 0.5 * (ft_c[k] + t.f_t).dot(trial_slip[k]);
    }
  }
  w += wall_work();
  return w;
}

// Per-increment set-up: the start geometry of every pair, the prescribed motion and predictor,
// the flip counters of the iteration matrix, and the drag (computed at the first assembly).
template <int D, class L>
void NetworkSolverT<D, L>::Impl::begin_increment(const Mat& dE) {
  prescribe(dE);
  begin_pairs();
  rhs.resize(nfree);
  sol.resize(nfree);
  eta = -1.0;
  res_fresh = -1.0;
  last_alpha = 1.0;
  rises = 0;
  du_ref = du_aff;
}

// The per-pair data of an increment (also after a rebuild within it): the committed geometry of
// every row and the flip counters of the iteration matrix.
template <int D, class L>
void NetworkSolverT<D, L>::Impl::begin_pairs() {
  const std::size_t np = pi.size();
  g0.resize(np);
  trial.resize(np);
  trial_slip.resize(np);
  for (std::size_t k = 0; k < np; ++k) {
    const int i = pi[k], j = pj[k];
    g0[k] = ct::pair_geometry(at(i), at_j(k), ps.r[i], ps.r[j]);
  }
  last_sliding.assign(np, 0);
  flips.assign(np, 0);
  last_open.assign(np, 0);
  open_flips.assign(np, 0);
  last_kn.assign(np, 0.0);
  if (friction_energy()) {  // (assemble() freezes them at the iterate)
    t_kt.assign(np, 0.0);
    t_limit.assign(np, 0.0);
  }
  for (std::size_t k = 0; k < np; ++k) {
    last_sliding[k] = slide_c[k];
    last_open[k] = fn_c[k] > 0.0 ? 0 : 1;
  }
}

// Viscous regularisation (pseudo-time): the free DOFs feel a drag eta (du - du_ref), so mechanisms
// and collapsing regions get a finite stiffness eta and move at a finite rate instead of making
// the tangent singular. Pseudo-transient: du_ref is the current iterate (the drag shapes the path
// only); legacy drag: du_ref is the affine motion of the increment (the drag stays in the answer). Homogeneous (affine) motion is not
// resisted; its size, max|f_contact| / mean contact force, is reported as the unbalanced force
// of the increment. With viscosity_strain > 0 the drag is per unit strain (|dE| scaled).
template <int D, class L>
void NetworkSolverT<D, L>::Impl::start_drag(const Mat& dE) {
  const double md = mean_diagonal();
  kl_ref = md;
  eta = opt.viscosity * opt.regularisation_scale * md;
  if (opt.viscosity_strain > 0.0 && dE.norm() > 0.0) eta *= opt.viscosity_strain / dE.norm();
  eta0 = eta;
}

// The Newton step into sol: a fresh factorisation of M (with drag and regularisation) on fresh
// iterations, then GMRES on K preconditioned by it (direct solve when symmetric); clipped. With
// factor_reuse, a fresh tangent may instead be solved by GMRES with the kept (older) factor.
template <int D, class L>
bool NetworkSolverT<D, L>::Impl::linear_step(bool fresh, bool nonsym, IncrementReport& rep) {
  LinearStatus st;
  bool solved = false;
  if (fresh) {
    regularise();
    const bool keep = opt.factor_reuse > 0 && !pattern_changed && factor_reuses < opt.factor_reuse &&
                      kept_iterations <= IterationOptions::kKeptFactorMaxIterations && lin.has_factor();
    if (keep) {  // GMRES on the current tangent, the kept factor as preconditioner
      st = lin.solve(nonsym ? K : M, rhs, sol);
      ++factor_reuses;
      kept_iterations = st.iterations;
      factor_current = false;
      solved = st.ok;
    }
    if (!solved) {
      st = lin.factorise(M, pattern_changed);
      pattern_changed = false;
      if (!st.ok) throw std::runtime_error("increment: " + st.message);
      factor_current = true;
      factor_reuses = kept_iterations = 0;
    }
  }
  if (!solved) st = nonsym || !factor_current ? lin.solve(nonsym ? K : M, rhs, sol) : lin.solve(rhs, sol);
  if (!st.ok) {
    // GMRES hit its cap: fall back to the symmetric slip-status tangent (defect correction)
    st = lin.solve(rhs, sol);
    if (!st.ok) throw std::runtime_error("increment: " + st.message);
  }
  rep.linear_iterations += st.iterations;
  clip_step();
  return true;
}

// Backtracking line search on the RMS residual (steps 1, 1/2, ... backtracks of them): the first
// step that lowers it, else the best step tried. Returns whether f and the trial state belong to
// the final du (false when it went back to an earlier step).
template <int D, class L>
bool NetworkSolverT<D, L>::Impl::line_search(double newton_res) {
  bool f_current = true;
  du_start = du;
  auto apply = [&](double a) {
    for (int p = 0; p < n; ++p)
      for (int c = 0; c < kN; ++c)
        if (const int d = dof[kN * p + c]; d >= 0) du[kN * p + c] = du_start[kN * p + c] + a * sol(d);
  };
  double alpha = 1.0;
  const double r_before = newton_res;
  double best_alpha = 1.0, best_r = std::numeric_limits<double>::infinity();
  for (int ls = 0; ls < opt.backtracks; ++ls, alpha *= 0.5) {
    apply(alpha);
    evaluate_forces();
    const double rr = residual(std::max(mean_normal_force(), 1e-300), false);
    if (rr < best_r) {
      best_r = rr;
      best_alpha = alpha;
    }
    if (rr < r_before) break;
  }
  if (best_alpha != alpha || best_r >= r_before) {
    alpha = best_alpha;
    apply(alpha);
    f_current = false;  // f and trial belong to the last step tried, not to best_alpha
  }
  if (opt.verbose) std::fprintf(stderr, "    line search step %.4f\n", alpha);
  last_alpha = alpha;
  return f_current;
}

// Nonlinear Gauss-Seidel on the worst particles after the global step; returns whether f and
// the trial state belong to the final du.
template <int D, class L>
bool NetworkSolverT<D, L>::Impl::local_sweeps(bool f_current) {
  for (int sweep = 0; sweep < opt.local_sweeps; ++sweep) {
    if (!f_current) {
      evaluate_forces();
      f_current = true;
    }
    const double fb = std::max(mean_normal_force(), 1e-300);
    const double rms = residual(fb, false);
    const int relaxed = relax_worst(fb, rms);
    if (opt.verbose) std::fprintf(stderr, "    local relaxation: %d particles\n", relaxed);
    if (relaxed == 0) break;
  }
  return f_current;
}

// Commits the trial state of the increment: contact histories, affine-deviation bookkeeping,
// committed forces, positions, the strain and the box.
template <int D, class L>
void NetworkSolverT<D, L>::Impl::commit(const Mat& dE, IncrementReport& rep) {
  const Mat E_old = E;
  for (std::size_t k = 0; k < pi.size(); ++k) {
    const auto& t = trial[k];
    const bool was_loaded = fn_c[k] > 0.0;
    const bool loaded = t.loaded;
    if (loaded && !law.has_history(hist[k])) {  // first touch: start the affine-deviation bookkeeping
      aux[k] = PairAuxT<D>{};
      aux[k].E_form = E_old;
    }
    if (loaded && !was_loaded) ++rep.new_contacts;
    if (!loaded && was_loaded) ++rep.lost_contacts;
    if (loaded || law.has_history(hist[k])) {
      hist[k] = t.history;
      if constexpr (D == 2) {  // the Figs 7-8 bookkeeping (2D)
        aux[k].slip += trial_slip[k];
        // tangential displacement of the centres, L dphi (only needed here: not in the evaluation)
        const int i = pi[k], j = pj[k];
        const Geometry& g = g0[k];
        const Geometry g1 = ct::pair_geometry(moved(i), moved_j(k), ps.r[i], ps.r[j]);
        aux[k].centre += std::atan2(ct::cross(g.n, g1.n), g.n.dot(g1.n)) * 0.5 * (g.L + g1.L);
      }
    }
    fn_c[k] = t.f_n;
    ft_c[k] = t.f_t;
    slide_c[k] = t.sliding ? 1 : 0;
    rep.sliding += t.sliding;
  }
  commit_walls();
  for (int p = 0; p < n; ++p) {
    for (int a = 0; a < D; ++a) ps.pos[D * p + a] += du[kN * p + a];
    for (int a = 0; a < kR; ++a) ps.rot[kR * p + a] += du[kN * p + D + a];
  }
  f_c = f;
  E += dE;
  Fbox = small_expm<D>(dE) * Fbox;
  du_prev = du;
  dE_prev = dE;
  const auto& ls = lin.stats();
  tim.analyses = lin_base.analyses + ls.analyses;
  tim.factorisations = lin_base.factorisations + ls.factorisations;
  tim.solves = lin_base.solves + ls.solves;
  tim.analyse = lin_base.analyse + ls.t_analyse;
  tim.factorise = lin_base.factorise + ls.t_factorise;
  tim.solve = lin_base.solve + ls.t_solve;
  tim.increments += 1;
}

template <int D, class L>
double NetworkSolverT<D, L>::Impl::mean_normal_force() const {
  double s = 0.0;
  int c = 0;
  for (const auto& t : trial)
    if (t.loaded) {
      s += t.f_n;
      ++c;
    }
  return c > 0 ? s / c : 0.0;
}

/// Newton residual r = f_contact - eta (du - du_ref) on the free DOFs, as RMS / fbar (max-norm
/// in max_norm). If fill_rhs, also stores r in rhs for the linear solve.
template <int D, class L>
double NetworkSolverT<D, L>::Impl::residual(double fbar, bool fill_rhs, double* max_norm) {
  const double eta_t = std::max(eta, 0.0), eta_r = eta_t * r_mean * r_mean;
  double m = 0.0, s2 = 0.0;
  for (int p = 0; p < n; ++p)
    for (int a = 0; a < kN; ++a)
      if (const int d = dof[kN * p + a]; d >= 0) {
        const double rv = f[kN * p + a] - (is_rotation(a) ? eta_r : eta_t) * (du[kN * p + a] - du_ref[kN * p + a]);
        if (fill_rhs) rhs(d) = rv;
        const double v = std::fabs(rv) / (is_rotation(a) ? r_mean : 1.0);
        m = std::max(m, v);
        s2 += v * v;
      }
  const double scale = 1.0 / std::max(fbar, 1e-300);
  if (max_norm) *max_norm = m * scale;
  return std::sqrt(s2 / std::max(nfree, 1)) * scale;
}

/// Per-particle step limits: a single soft mode must not freeze the whole network.
template <int D, class L>
void NetworkSolverT<D, L>::Impl::clip_step() {
  for (int p = 0; p < n; ++p) {
    if constexpr (D == 2) {
      const int dx = dof[3 * p], dy = dof[3 * p + 1], dr = dof[3 * p + 2];
      if (dx >= 0) {
        const double t = std::hypot(sol(dx), sol(dy)), tl = opt.max_step * r_mean;
        if (t > tl) {
          sol(dx) *= tl / t;
          sol(dy) *= tl / t;
        }
      }
      if (dr >= 0) sol(dr) = std::clamp(sol(dr), -opt.max_rotation_step, opt.max_rotation_step);
    } else {  // the translation by its length, the rotation vector by its angle
      const int* d = &dof[6 * p];
      if (d[0] >= 0) {
        const double t = std::sqrt(sol(d[0]) * sol(d[0]) + sol(d[1]) * sol(d[1]) + sol(d[2]) * sol(d[2]));
        const double tl = opt.max_step * r_mean;
        if (t > tl)
          for (int a = 0; a < 3; ++a) sol(d[a]) *= tl / t;
      }
      if (d[3] >= 0) {
        const double t = std::sqrt(sol(d[3]) * sol(d[3]) + sol(d[4]) * sol(d[4]) + sol(d[5]) * sol(d[5]));
        if (t > opt.max_rotation_step)
          for (int a = 3; a < 6; ++a) sol(d[a]) *= opt.max_rotation_step / t;
      }
    }
  }
}

// the plastic law (2D, 3D): netdem_quasistatic; the linear law: NETDEM_QS_MORE (CMakeLists.txt)
#ifndef NETDEM_QS_MORE
template class NetworkSolverT<2>;
template class NetworkSolverT<3>;
#else
template class NetworkSolverT<2, LinearLawT<2>>;
template class NetworkSolverT<3, LinearLawT<3>>;
#endif

}  // namespace netdem::qs
