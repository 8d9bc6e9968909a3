// ContactTable: the system layer's contact table with the network solver's per-row data, and the
// neighbour rebuild (solver_impl.hpp states the rules).
#include <chrono>

#include "solver_impl.hpp"

namespace netdem::qs {

void ContactTable::rebuild(const Law& law, const sys::ParticleSet<2>& ps, double skin, double r_max,
                           const Eigen::Matrix2d& E, const Eigen::Matrix2d& Fbox) {
  sys::ContactTable<Law::History, 2>::rebuild(law, ps, skin, r_max, Fbox);
  PairAux fresh;
  fresh.E_form = E;
  carry(aux, fresh);
  carry(fn_c, 0.0);
  carry(ft_c, 0.0);
  carry(slide_c, std::uint8_t{0});
}

void NetworkSolver::Impl::build_neighbours() {
  const auto t0 = std::chrono::steady_clock::now();
  ContactTable::rebuild(law, ps, opt.skin * r_mean, r_max, E, Fbox);
  apart.assign(pi.size(), 0);  // new pair indices: nothing is known to be zero
  build_pattern();
  tim.neighbours += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace netdem::qs
