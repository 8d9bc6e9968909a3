// The network solver and the jammed state both solvers share (netdem/system/jammed_state.hpp):
// the solver that starts from one, and the committed state as one.
#include <stdexcept>

#include "solver_impl.hpp"

namespace netdem::qs {

template <int D, class L>
NetworkSolverT<D, L>::NetworkSolverT(const sys::JammedStateT<D>& j, const Options& options)
    : NetworkSolverT((j.validate(), j.packing()), options) {  // the particles in the box, fresh rows
  static_assert(kPlastic, "the jammed state is the plastic-indentation law's");
  auto& s = *impl_;
  if (!j.wall_particle.empty() && !s.walls())
    throw std::invalid_argument("network solver: the jammed state has wall contacts; its boundary mode has no walls");
  s.ps.rot = j.particles.rot;
  s.E = j.strain;
  // the state's rows and histories, merged by a rebuild with every pair within the skin
  s.pi = j.pair_i;
  s.pj = j.pair_j;
  s.hist = j.pair_history;
  PairAuxT<D> fresh;
  fresh.E_form = s.E;
  s.aux.assign(s.pi.size(), fresh);
  s.fn_c.assign(s.pi.size(), 0.0);
  s.ft_c.assign(s.pi.size(), ct::tan_zero<typename Impl::Tan>());
  s.slide_c.assign(s.pi.size(), 0);
  s.build_neighbours();
  if (s.walls()) {
    s.whist.assign(Impl::kW * static_cast<std::size_t>(s.n), typename Impl::Law::History{});
    s.wfn_c.assign(s.whist.size(), 0.0);
    for (std::size_t k = 0; k < j.wall_particle.size(); ++k)
      s.whist[Impl::kW * static_cast<std::size_t>(j.wall_particle[k]) + static_cast<std::size_t>(j.wall_side[k])] =
          j.wall_history[k];
  }
  // the committed forces: the law on these histories at these positions (a zero increment)
  s.begin_increment(Mat::Zero());
  s.evaluate_forces();
  IncrementReport rep;
  s.commit(Mat::Zero(), rep);
  s.du_prev.clear();  // no predictor: the next increment starts from the affine motion
  s.tim = SolverTimings{};
  s.lin_base = SolverTimings{};
}

namespace {

/// The committed state as a jammed state, histories as committed.
template <int D, class L>
sys::JammedStateT<D> raw_jammed(const typename NetworkSolverT<D, L>::Impl& s) {
  for (int r = 0; r < D; ++r)
    for (int c = 0; c < D; ++c)
      if (r != c && s.Fbox(r, c) != 0.0)
        throw std::invalid_argument("jammed state: the box is sheared (the state holds an axis-aligned box)");
  sys::JammedStateT<D> j;
  j.particles = s.ps;
  j.box = s.box0;
  double* lo[3] = {&j.box.x_min, &j.box.y_min, &j.box.z_min};
  double* hi[3] = {&j.box.x_max, &j.box.y_max, &j.box.z_max};
  for (int a = 0; a < D; ++a) {  // as the walls' faces: F_aa x0 (walls.cpp)
    *lo[a] = s.Fbox(a, a) * *lo[a];
    *hi[a] = s.Fbox(a, a) * *hi[a];
  }
  j.walls = s.walls();
  j.strain = s.E;
  j.seed = s.seed;
  j.law = s.opt.law;
  j.law.damping_n = j.law.damping_t = 0.0;
  j.wall_mu = s.wall_law.params().mu;
  for (std::size_t k = 0; k < s.pi.size(); ++k)
    if (s.law.has_history(s.hist[k])) {
      j.pair_i.push_back(s.pi[k]);
      j.pair_j.push_back(s.pj[k]);
      j.pair_history.push_back(s.hist[k]);
    }
  for (std::size_t w = 0; w < s.whist.size(); ++w)
    if (s.wall_law.has_history(s.whist[w])) {
      j.wall_particle.push_back(static_cast<int>(w / (2 * D)));
      j.wall_side.push_back(static_cast<int>(w % (2 * D)));
      j.wall_history.push_back(s.whist[w]);
    }
  return j;
}

}  // namespace

/// At rest: the histories as the law leaves them after one more evaluation without an increment
/// (a contact that slid in the last increment holds now: its sliding flag is 0), as the DEM's
/// jammed_state() (the same state read by either solver is then a fixed point of it).
template <int D, class L>
sys::JammedStateT<D> NetworkSolverT<D, L>::jammed_state() const {
  static_assert(kPlastic, "the jammed state is the plastic-indentation law's");
  if (impl_->periodic()) throw std::invalid_argument("jammed state: a periodic cell is not a jammed state's box (not yet)");
  const NetworkSolverT rest(raw_jammed<D, L>(*impl_), impl_->opt);
  return raw_jammed<D, L>(*rest.impl_);
}

// the plastic law (2D, 3D): netdem_quasistatic; the linear law: NETDEM_QS_MORE (CMakeLists.txt)
#ifndef NETDEM_QS_MORE
template NetworkSolverT<2>::NetworkSolverT(const sys::JammedStateT<2>&, const SolverOptions&);
template sys::JammedStateT<2> NetworkSolverT<2>::jammed_state() const;
template NetworkSolverT<3>::NetworkSolverT(const sys::JammedStateT<3>&, const SolverOptions&);
template sys::JammedStateT<3> NetworkSolverT<3>::jammed_state() const;
#endif

}  // namespace netdem::qs
