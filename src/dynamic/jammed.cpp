// The DEM and the jammed state (jammed.hpp).
#include "netdem/dynamic/jammed.hpp"

#include <stdexcept>

namespace netdem::dem {

namespace {

/// The jammed state of a solver's state as it stands (histories as committed).
template <int D>
sys::JammedStateT<D> raw_jammed(const SolverState& st, const Eigen::Matrix<double, D, D>& strain, std::uint64_t seed) {
  using H = contact::PlasticIndentationHistoryT<D>;
  if (!st.holds<H>()) throw std::invalid_argument("jammed state: the DEM run is not of the plastic-indentation law");
  sys::JammedStateT<D> j;
  j.particles = st.particles_of<D>();  // the centres, rotations (3D: zero) and radii
  j.box = st.box;
  j.walls = st.box.enabled && st.box.contact_walls;
  j.strain = strain;
  j.seed = seed;
  j.law = st.plastic;
  j.law.damping_n = j.law.damping_t = 0.0;  // the dashpots are the solver's, not the state's
  j.wall_mu = st.plastic_wall_mu;
  const contact::PlasticIndentationLawT<D> law(st.plastic);
  const auto& ph = st.histories_of<H>().pair;
  for (std::size_t k = 0; k < st.pair_key.size(); ++k) {  // (state(): the live histories only)
    j.pair_i.push_back(static_cast<int>(st.pair_key[k] >> 32));
    j.pair_j.push_back(static_cast<int>(st.pair_key[k] & 0xffffffffu));
    j.pair_history.push_back(ph[k]);
  }
  const auto& wh = st.histories_of<H>().wall;
  constexpr std::size_t W = 2 * D;
  if (j.walls)
    for (std::size_t s = 0; s < wh.size(); ++s)
      if (law.has_history(wh[s])) {
        j.wall_particle.push_back(static_cast<int>(s / W));
        j.wall_side.push_back(static_cast<int>(s % W));
        j.wall_history.push_back(wh[s]);
      }
  return j;
}

DynamicOptions undamped(DynamicOptions o) {
  o.plastic.damping_n = o.plastic.damping_t = 0.0;
  return o;
}

/// The forces at rest, twice: a spring held at the Coulomb limit is s limit after the first
/// evaluation; in 3D the norm of s limit can round above the limit, so that the first evaluation
/// flags it sliding and the second (which keeps the spring to the bit) not. After two the
/// histories are a fixed point (2D: after one).
template <int D>
void settle(DynamicSolverT<D>& s) {
  s.refresh_forces();
  if constexpr (D == 3) s.refresh_forces();
}

}  // namespace

template <int D>
DynamicSolverT<D> solver_from_jammed(const sys::JammedStateT<D>& j, double rho, const Box& control, DynamicOptions o) {
  using H = contact::PlasticIndentationHistoryT<D>;
  j.validate();
  const packing::Packing pk = j.packing();
  ParticlesT<D> P = particles_at_rest<D>(pk, rho);
  if constexpr (D == 2) P.rot = j.particles.rot;
  Box box = control;
  static_cast<packing::Box&>(box) = j.box;
  box.contact_walls = j.walls;
  o.model = ContactModel::PlasticIndentation;
  o.plastic.sigma_y = j.law.sigma_y;  // the state's law, the run's dashpots
  o.plastic.mu = j.law.mu;
  o.plastic.k_t = j.law.k_t;
  o.plastic.unload_ratio = j.law.unload_ratio;
  o.plastic.reversible = j.law.reversible;
  o.plastic.first_touch = j.law.first_touch;
  o.plastic_wall_mu = j.wall_mu;
  // a fresh solver gives the time step and the law's set-up; its state takes the jammed histories
  SolverState st = DynamicSolverT<D>(std::move(P), o.plastic, box, o).state();
  st.plastic.damping_n = st.plastic.damping_t = 0.0;
  st.pair_key.clear();
  auto& ph = st.histories_of<H>().pair;
  ph.clear();
  for (std::size_t k = 0; k < j.pair_i.size(); ++k) {
    st.pair_key.push_back((std::uint64_t(j.pair_i[k]) << 32) | std::uint64_t(j.pair_j[k]));
    ph.push_back(j.pair_history[k]);
  }
  auto& wh = st.histories_of<H>().wall;
  wh.assign(wh.size(), {});
  for (std::size_t k = 0; k < j.wall_particle.size(); ++k)
    wh[static_cast<std::size_t>(2 * D * j.wall_particle[k] + j.wall_side[k])] = j.wall_history[k];
  // the forces at rest without the dashpots (they are zero at rest; the undamped law is the
  // network solver's arithmetic), then the run's solver from that state with its dashpots
  DynamicSolverT<D> rest(st, undamped(o));
  settle(rest);
  SolverState settled = rest.state();
  settled.plastic = o.plastic;
  return DynamicSolverT<D>(settled, o);
}

template <int D>
sys::JammedStateT<D> jammed_state(const DynamicSolverT<D>& s, const Eigen::Matrix<double, D, D>& strain,
                                  std::uint64_t seed) {
  SolverState st = s.state();
  // at rest: the same positions, zero velocities, the forces evaluated again (no slip increment)
  ParticlesT<D>& P = st.particles_of<D>();
  for (auto* v : {&P.vel, &P.spin}) std::fill(v->begin(), v->end(), 0.0);
  std::fill(std::begin(st.wall_velocity), std::end(st.wall_velocity), 0.0);
  std::fill(std::begin(st.wall_velocity3), std::end(st.wall_velocity3), 0.0);
  st.plastic.damping_n = st.plastic.damping_t = 0.0;
  DynamicSolverT<D> rest(st, undamped(s.options()));
  settle(rest);
  return raw_jammed<D>(rest.state(), strain, seed);
}

template DynamicSolverT<2> solver_from_jammed<2>(const sys::JammedStateT<2>&, double, const Box&, DynamicOptions);
template DynamicSolverT<3> solver_from_jammed<3>(const sys::JammedStateT<3>&, double, const Box&, DynamicOptions);
template sys::JammedStateT<2> jammed_state<2>(const DynamicSolverT<2>&, const Eigen::Matrix2d&, std::uint64_t);
template sys::JammedStateT<3> jammed_state<3>(const DynamicSolverT<3>&, const Eigen::Matrix3d&, std::uint64_t);

}  // namespace netdem::dem
