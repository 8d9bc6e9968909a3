// BoundaryMode::Walls: four rigid, frictionless die walls at the faces of the box, moving with it
// (x_face = F11 x_face0, y_face = F22 y_face0; E12 = 0). Each particle has a slot per wall; the
// contact is the plastic-indentation law of the pairs with R* = r_p (a flat) and mu = 0, so the
// force is normal to the wall and the element touches one translational DOF: the stiffness goes on
// the diagonal of K and M. No particle is prescribed; the stress of the walls (their reactions)
// takes the place of Eq 13 (measures.cpp).
#include "solver_impl.hpp"

namespace netdem::qs {

namespace {
// the face coordinate of wall w for the box deformation F (diagonal)
double face(const Eigen::Matrix2d& F, const packing::Box& b, int w) {
  switch (w) {
    case 0: return F(0, 0) * b.x_min;
    case 1: return F(0, 0) * b.x_max;
    case 2: return F(1, 1) * b.y_min;
    default: return F(1, 1) * b.y_max;
  }
}
// distance of the point (px, py) from wall w, positive inside the box
double distance(int w, double px, double py, double f) {
  switch (w) {
    case 0: return px - f;
    case 1: return f - px;
    case 2: return py - f;
    default: return f - py;
  }
}
}  // namespace

template <int D, class L>
typename NetworkSolverT<D, L>::Impl::WallEval NetworkSolverT<D, L>::Impl::wall_eval(int p, int w) const {
  WallEval e;
  const std::size_t s = 4 * static_cast<std::size_t>(p) + static_cast<std::size_t>(w);
  const double d1 = distance(w, ps.pos[2 * p] + du[3 * p], ps.pos[2 * p + 1] + du[3 * p + 1], face(Fbox_trial, box0, w));
  if (ps.r[p] - d1 <= 0.0 && !wall_law.has_history(whist[s])) return e;
  ct::ContactKinematics k;
  k.overlap = ps.r[p] - d1;
  k.overlap_start = ps.r[p] - distance(w, ps.pos[2 * p], ps.pos[2 * p + 1], face(Fbox, box0, w));
  k.r_eff = ps.r[p];
  ct::ContactTangent t;
  e.r = wall_law.evaluate(whist[s], k, &t);
  if constexpr (ct::kHasPotential<Law>)
    if (energy_mode()) e.work = wall_law.normal_work(whist[s], k.r_eff, k.overlap);
  if (!e.r.loaded) return e;
  const double sign = (w == 0 || w == 2) ? 1.0 : -1.0;  // the inward normal along the wall's axis
  e.force = sign * e.r.f_n;
  e.k = t.dfn_dun + wall_law.iteration_stiffness(whist[s], k, e.r).k_n_add;
  return e;
}

template <int D, class L>
void NetworkSolverT<D, L>::Impl::wall_particle(int p, double sign) {
  for (int w = 0; w < 4; ++w) {
    const std::size_t s = 4 * static_cast<std::size_t>(p) + static_cast<std::size_t>(w);
    const int axis = w < 2 ? 0 : 1;
    if (sign < 0.0) {  // remove the current contribution
      f[3 * p + axis] -= wf[s];
      continue;
    }
    const WallEval e = wall_eval(p, w);
    wtrial[s] = e.r;
    wf[s] = e.force;
    wk[s] = e.k;
    wwork[s] = e.work;
    f[3 * p + axis] += e.force;
  }
}

template <int D, class L>
void NetworkSolverT<D, L>::Impl::wall_forces() {
  if (!walls()) return;
  const std::size_t slots = 4 * static_cast<std::size_t>(n);
  if (whist.size() != slots) {
    whist.assign(slots, typename Law::History{});
    wfn_c.assign(slots, 0.0);
  }
  wtrial.resize(slots);
  wf.resize(slots);
  wk.resize(slots);
  wwork.resize(slots, 0.0);
  for (int p = 0; p < n; ++p) wall_particle(p, 1.0);
}

template <int D, class L>
void NetworkSolverT<D, L>::Impl::wall_stiffness() {
  if (!walls()) return;
  for (int p = 0; p < n; ++p)
    for (int w = 0; w < 4; ++w) {
      const std::size_t s = 4 * static_cast<std::size_t>(p) + static_cast<std::size_t>(w);
      if (!(wk[s] > 0.0)) continue;
      const int d = dof[3 * p + (w < 2 ? 0 : 1)];
      if (d < 0) continue;
      K.valuePtr()[pattern.diag(d)] += wk[s];
      M.valuePtr()[pattern.diag(d)] += wk[s];
    }
}

template <int D, class L>
void NetworkSolverT<D, L>::Impl::commit_walls() {
  if (!walls()) return;
  for (std::size_t s = 0; s < whist.size(); ++s) {
    if (wtrial[s].loaded || wall_law.has_history(whist[s])) whist[s] = wtrial[s].history;
    wfn_c[s] = wtrial[s].f_n;
  }
}

// The work of the wall contacts' normal forces over the increment, trapezoidal in the committed
// and trial forces on the overlap change while in contact (as contact_work() for the pairs).
template <int D, class L>
double NetworkSolverT<D, L>::Impl::wall_work() const {
  if (!walls() || wtrial.size() != wfn_c.size()) return 0.0;
  double w = 0.0;
  for (int p = 0; p < n; ++p)
    for (int c = 0; c < 4; ++c) {
      const std::size_t s = 4 * static_cast<std::size_t>(p) + static_cast<std::size_t>(c);
      if (!wtrial[s].loaded && wfn_c[s] <= 0.0) continue;
      const double u0 = ps.r[p] - distance(c, ps.pos[2 * p], ps.pos[2 * p + 1], face(Fbox, box0, c));
      const double u1 =
          ps.r[p] - distance(c, ps.pos[2 * p] + du[3 * p], ps.pos[2 * p + 1] + du[3 * p + 1], face(Fbox_trial, box0, c));
      w += 0.5 * (wfn_c[s] + wtrial[s].f_n) * (std::max(u1, 0.0) - std::max(u0, 0.0));
    }
  return w;
}

// the plastic law (2D, 3D): netdem_quasistatic; the linear law: NETDEM_QS_MORE (CMakeLists.txt)
// 2D only: the 3D solver refuses the walls mode (network_solver.cpp) and never calls these
#ifndef NETDEM_QS_MORE
template struct NetworkSolverT<2>::Impl;
#else
template struct NetworkSolverT<2, LinearLawT<2>>::Impl;
#endif

}  // namespace netdem::qs
