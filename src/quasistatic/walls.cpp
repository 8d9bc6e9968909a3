// BoundaryMode::Walls: 2D rigid, frictionless walls at the faces of the box, moving with it (the
// face of wall w, at the minimum (w even) or maximum (w odd) of axis a = w / 2, is F_aa x_face0;
// the path is diagonal). Each particle has a slot per wall; the contact is the plastic-indentation
// law of the pairs with R* = r_p (a flat) and mu = 0, so the force is normal to the wall and the
// element touches one translational DOF: the stiffness goes on the diagonal of K and M. No
// particle is prescribed; the stress of the walls (their reactions) takes the place of Eq 13
// (measures.cpp).
#include "solver_impl.hpp"

namespace netdem::qs {

namespace {
// the face coordinate of wall w for the box deformation F (diagonal)
template <int D>
double face(const Eigen::Matrix<double, D, D>& F, const packing::Box& b, int w) {
  const int a = w / 2;
  const double lo[3] = {b.x_min, b.y_min, b.z_min}, hi[3] = {b.x_max, b.y_max, b.z_max};
  return F(a, a) * (w % 2 == 0 ? lo[a] : hi[a]);
}
// distance of a centre with coordinate x along the wall's axis from wall w, positive inside the box
double distance(int w, double x, double f) { return w % 2 == 0 ? x - f : f - x; }
}  // namespace

template <int D, class L>
typename NetworkSolverT<D, L>::Impl::WallEval NetworkSolverT<D, L>::Impl::wall_eval(int p, int w) const {
  WallEval e;
  const std::size_t s = kW * static_cast<std::size_t>(p) + static_cast<std::size_t>(w);
  const int a = w / 2;
  const double d1 = distance(w, ps.pos[D * p + a] + du[kN * p + a], face<D>(Fbox_trial, box0, w));
  if (ps.r[p] - d1 <= 0.0 && !wall_law.has_history(whist[s])) return e;
  ct::Kinematics<D> k;
  k.overlap = ps.r[p] - d1;
  k.overlap_start = ps.r[p] - distance(w, ps.pos[D * p + a], face<D>(Fbox, box0, w));
  k.r_eff = ps.r[p];
  ct::Tangent<D> t;
  e.r = wall_law.evaluate(whist[s], k, &t);
  if constexpr (ct::kHasPotential<Law>)
    if (energy_mode()) e.work = wall_law.normal_work(whist[s], k.r_eff, k.overlap);
  if (!e.r.loaded) return e;
  const double sign = w % 2 == 0 ? 1.0 : -1.0;  // the inward normal along the wall's axis
  e.force = sign * e.r.f_n;
  e.k = t.dfn_dun + wall_law.iteration_stiffness(whist[s], k, e.r).k_n_add;
  return e;
}

template <int D, class L>
void NetworkSolverT<D, L>::Impl::wall_particle(int p, double sign) {
  for (int w = 0; w < kW; ++w) {
    const std::size_t s = kW * static_cast<std::size_t>(p) + static_cast<std::size_t>(w);
    const int axis = w / 2;
    if (sign < 0.0) {  // remove the current contribution
      f[kN * p + axis] -= wf[s];
      continue;
    }
    const WallEval e = wall_eval(p, w);
    wtrial[s] = e.r;
    wf[s] = e.force;
    wk[s] = e.k;
    wwork[s] = e.work;
    f[kN * p + axis] += e.force;
  }
}

template <int D, class L>
void NetworkSolverT<D, L>::Impl::wall_forces() {
  if (!walls()) return;
  const std::size_t slots = kW * static_cast<std::size_t>(n);
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
    for (int w = 0; w < kW; ++w) {
      const std::size_t s = kW * static_cast<std::size_t>(p) + static_cast<std::size_t>(w);
      if (!(wk[s] > 0.0)) continue;
      const int d = dof[kN * p + w / 2];
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
    for (int c = 0; c < kW; ++c) {
      const std::size_t s = kW * static_cast<std::size_t>(p) + static_cast<std::size_t>(c);
      if (!wtrial[s].loaded && wfn_c[s] <= 0.0) continue;
      const int a = c / 2;
      const double u0 = ps.r[p] - distance(c, ps.pos[D * p + a], face<D>(Fbox, box0, c));
      const double u1 = ps.r[p] - distance(c, ps.pos[D * p + a] + du[kN * p + a], face<D>(Fbox_trial, box0, c));
      w += 0.5 * (wfn_c[s] + wtrial[s].f_n) * (std::max(u1, 0.0) - std::max(u0, 0.0));
    }
  return w;
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
