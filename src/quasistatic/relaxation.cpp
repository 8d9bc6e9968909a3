// The local nonlinear Gauss-Seidel sweep of the network solver: after each global Newton step
// the particles with the largest residual are relaxed one at a time (damped Newton on their own
// DOFs, neighbours held), largest first.
#include <algorithm>
#include <cmath>
#include <functional>

#include <Eigen/LU>

#include "solver_impl.hpp"

namespace netdem::qs {

/// Residual (contact force - drag) and tangent of a set of m particles (1 or 2) alone, with all
/// other particles held at their current trial positions: kN entries per particle.
template <int D, class L>
void NetworkSolverT<D, L>::Impl::local_eval(const int* group, int m, Eigen::VectorXd& res, Eigen::MatrixXd& Kl) const {
  res.setZero(kN * m);
  Kl.setZero(kN * m, kN * m);
  const ct::TangentOptions topt;
  Element e;
  auto slot = [&](int p) {
    for (int t = 0; t < m; ++t)
      if (group[t] == p) return t;
    return -1;
  };
  for (int sp = 0; sp < m; ++sp)
    for (int q = adj_start[group[sp]]; q < adj_start[group[sp] + 1]; ++q) {
      const int k = adj_pair[q], i = pi[k], j = pj[k];
      const int si = slot(i), sj = slot(j);
      if ((si >= 0 && si < sp) || (sj >= 0 && sj < sp)) continue;  // pair inside the set: once
      const Geometry g1 = ct::pair_geometry(moved(i), moved_j(k), ps.r[i], ps.r[j]);
      if (g1.overlap <= 0.0 && !law.has_history(hist[k])) continue;
      ct::pair_element(law, hist[k], g0[k], g1, rotation(i), rotation(j), e, &topt);
      const int sl[2] = {si, sj};
      for (int A = 0; A < 2; ++A)
        if (sl[A] >= 0) res.template segment<kN>(kN * sl[A]) += e.force.template segment<kN>(kN * A);
      if (!e.law.loaded) continue;
      if (e.law.sliding && opt.slide_stiffness_fraction > 0.0) {
        const SlipGradient bt = ct::slip_gradient(g1);
        const double k_t = law.iteration_stiffness(hist[k], e.kin, e.law).k_t;
        if constexpr (D == 2) {
          e.stiffness.noalias() += opt.slide_stiffness_fraction * k_t * bt * bt.transpose();
        } else {
          e.stiffness.noalias() += opt.slide_stiffness_fraction * k_t * bt.transpose() * bt;
        }
      }
      for (int A = 0; A < 2; ++A)
        for (int B = 0; B < 2; ++B)
          if (sl[A] >= 0 && sl[B] >= 0)
            Kl.template block<kN, kN>(kN * sl[A], kN * sl[B]) += e.stiffness.template block<kN, kN>(kN * A, kN * B);
    }
  if (walls())
    for (int t = 0; t < m; ++t)
      for (int w = 0; w < kW; ++w) {
        const WallEval we = wall_eval(group[t], w);
        const int a = w / 2;
        res(kN * t + a) += we.force;
        Kl(kN * t + a, kN * t + a) += we.k;
      }
  const double eta_t = std::max(eta, 0.0);
  for (int t = 0; t < m; ++t)
    for (int a = 0; a < kN; ++a) {
      const int p = group[t];
      const double ea = is_rotation(a) ? eta_t * r_mean * r_mean : eta_t;
      res(kN * t + a) -= ea * (du[kN * p + a] - du_ref[kN * p + a]);
      Kl(kN * t + a, kN * t + a) += ea + 1e-9 * kl_ref * (is_rotation(a) ? r_mean * r_mean : 1.0);
    }
}

/// Nonlinear Gauss-Seidel on a set of particles: damped Newton on their own free DOFs.
template <int D, class L>
void NetworkSolverT<D, L>::Impl::relax_set(const int* group, int m, double fbar) {
  int idx[kP], nf = 0;  // local index kN t + a of the free DOFs (m <= 2)
  for (int t = 0; t < m; ++t)
    for (int a = 0; a < kN; ++a)
      if (dof[kN * group[t] + a] >= 0) idx[nf++] = kN * t + a;
  if (nf == 0) return;
  auto norm = [&](const Eigen::VectorXd& v) {
    double s2 = 0.0;
    for (int c = 0; c < nf; ++c) s2 += std::pow(v(idx[c]) / (is_rotation(idx[c] % kN) ? r_mean : 1.0), 2);
    return std::sqrt(s2);
  };
  auto at = [&](int c) -> double& { return du[kN * group[idx[c] / kN] + idx[c] % kN]; };
  Eigen::VectorXd res, res2;
  Eigen::MatrixXd Kl, Kl2;
  local_eval(group, m, res, Kl);
  double rn = norm(res);
  for (int it = 0; it < opt.local_iterations && rn > 0.1 * opt.residual_tol * fbar; ++it) {
    Eigen::MatrixXd A(nf, nf);
    Eigen::VectorXd b(nf);
    for (int c = 0; c < nf; ++c) {
      b(c) = res(idx[c]);
      for (int d = 0; d < nf; ++d) A(c, d) = Kl(idx[c], idx[d]);
    }
    Eigen::VectorXd step = A.partialPivLu().solve(b);
    if (!step.allFinite()) return;
    // same per-particle limits as the global step
    double scale = 1.0;
    for (int c = 0; c < nf; ++c) {
      const double lim = is_rotation(idx[c] % kN) ? opt.max_rotation_step : opt.max_step * r_mean;
      if (std::fabs(step(c)) > lim) scale = std::min(scale, lim / std::fabs(step(c)));
    }
    step *= scale;
    double old[kP];
    for (int c = 0; c < nf; ++c) old[c] = at(c);
    bool accepted = false;
    for (double alpha = 1.0; alpha > 0.01; alpha *= 0.5) {
      for (int c = 0; c < nf; ++c) at(c) = old[c] + alpha * step(c);
      local_eval(group, m, res2, Kl2);
      const double rn2 = norm(res2);
      if (rn2 < rn) {
        rn = rn2;
        res = res2;
        Kl = Kl2;
        accepted = true;
        break;
      }
    }
    if (!accepted) {
      for (int c = 0; c < nf; ++c) at(c) = old[c];
      return;
    }
  }
}

/// One Gauss-Seidel sweep over the particles whose residual exceeds local_threshold x the RMS
/// residual (and the tolerance), largest first. Needs f from the current trial state; leaves f
/// and the trial state current (the pairs of the moved particles are refreshed).
template <int D, class L>
int NetworkSolverT<D, L>::Impl::relax_worst(double fbar, double rms) {
  const double eta_t = std::max(eta, 0.0), eta_r = eta_t * r_mean * r_mean;
  const double thr = std::max(opt.local_threshold * rms, opt.residual_tol) * fbar;
  auto& bad = relax_bad;
  auto& rp = relax_rp;
  bad.clear();
  rp.resize(n);
  for (int p = 0; p < n; ++p) {
    double s2 = 0.0;
    for (int a = 0; a < kN; ++a)
      if (dof[kN * p + a] >= 0) {
        const double rv = f[kN * p + a] - (is_rotation(a) ? eta_r : eta_t) * (du[kN * p + a] - du_ref[kN * p + a]);
        s2 += std::pow(rv / (is_rotation(a) ? r_mean : 1.0), 2);
      }
    rp[p] = std::sqrt(s2);
    if (rp[p] > thr) bad.emplace_back(rp[p], p);
  }
  std::sort(bad.begin(), bad.end(), std::greater<>());
  auto& done = relax_done;
  auto& moved = relax_moved;
  done.assign(n, 0);
  moved.clear();
  for (const auto& b : bad) {
    const int p = b.second;
    if (done[p]) continue;
    relax_set(&p, 1, fbar);
    done[p] = 1;
    moved.push_back(p);
  }
  refreshed.resize(pi.size(), 0);
  refresh_particles(moved);  // f and the trial state follow the relaxed du
  return static_cast<int>(bad.size());
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
