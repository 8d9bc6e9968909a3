// ContactTableT: the system layer's contact table with the network solver's per-row data, and the
// neighbour rebuild (solver_impl.hpp states the rules).
#include <chrono>

#include "solver_impl.hpp"

namespace netdem::qs {

template <int D, class L>
void ContactTableT<D, L>::rebuild(const L& law, const sys::ParticleSet<D>& ps, double skin, double r_max,
                               const Mat& E, const Mat& Fbox, const packing::PeriodicCellT<D>* cell) {
  sys::ContactTable<typename L::History, D>::rebuild(law, ps, skin, r_max, Fbox, cell);
  PairAuxT<D> fresh;
  fresh.E_form = E;
  this->carry(aux, fresh);
  this->carry(fn_c, 0.0);
  this->carry(ft_c, ct::tan_zero<Tan>());
  this->carry(slide_c, std::uint8_t{0});
}

template <int D, class L>
void NetworkSolverT<D, L>::Impl::build_neighbours() {
  const auto t0 = std::chrono::steady_clock::now();
  if (periodic()) {
    const packing::PeriodicCellT<D> cell = cell0.deformed(Fbox);
    Table::rebuild(law, ps, opt.skin * r_mean, r_max, E, Fbox, &cell);
  } else {
    Table::rebuild(law, ps, opt.skin * r_mean, r_max, E, Fbox);
  }
  apart.assign(pi.size(), 0);  // new pair indices: nothing is known to be zero
  build_pattern();
  tim.neighbours += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// the plastic law (2D, 3D): netdem_quasistatic; the linear law: NETDEM_QS_MORE (CMakeLists.txt)
#ifndef NETDEM_QS_MORE
template struct ContactTableT<2, ct::PlasticIndentationLawT<2>>;
template struct NetworkSolverT<2>::Impl;
template struct ContactTableT<3, ct::PlasticIndentationLawT<3>>;
template struct NetworkSolverT<3>::Impl;
#else
template struct ContactTableT<2, LinearLawT<2>>;
template struct ContactTableT<3, LinearLawT<3>>;
template struct NetworkSolverT<2, LinearLawT<2>>::Impl;
template struct NetworkSolverT<3, LinearLawT<3>>::Impl;
#endif

}  // namespace netdem::qs
