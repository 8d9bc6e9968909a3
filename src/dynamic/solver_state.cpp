// Solver state between steps: restart from a SolverState, state(), the temperature schedule,
// parameter and wall changes, and contacts() (the state file: state.cpp, docs/dynamic.md).
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <fmt/format.h>

#include "netdem/dynamic/solver.hpp"
#include "state_of.hpp"

namespace netdem::dem {

namespace {
[[noreturn]] void fail(const std::string& msg) { throw std::invalid_argument(msg); }
}  // namespace


namespace {
// The particles of a state of dimension D (one line if it is of the other).
template <int D>
const ParticlesT<D>& state_particles(const SolverState& st) {
  if (st.dim() != D) fail(fmt::format("state: the particles are {}D, the solver {}D", st.dim(), D));
  return st.particles_of<D>();
}

// The options of a restart: a plastic-law state brings its law and wall friction.
DynamicOptions restart_options(const SolverState& st, DynamicOptions o) {
  if (st.plastic_law() && o.model == ContactModel::PlasticIndentation) {
    o.plastic = st.plastic;
    o.plastic_wall_mu = st.plastic_wall_mu;
  }
  return o;
}
}  // namespace

template <int D>
DynamicSolverT<D>::DynamicSolverT(const SolverState& st, const DynamicOptions& options)
    : P_(state_particles<D>(st)), params_(st.params), box_(st.box), opt_(restart_options(st, options)) {
  using S = StateOf<D>;
  if (st.periodic)
    fail("state: a state in a periodic cell cannot restart (the cell and the pairs' images are not in a state yet)");
  params_.validate();
  opt_.validate();
  const std::size_t n = P_.size();
  const std::size_t nw = static_cast<std::size_t>(kWalls);
  const bool sizes = P_.consistent() && st.radius_ref.size() == n;
  // the histories of the state's law (whichever it is): of dimension D, one per pair, 2 D per particle
  const bool hist_sizes = std::visit([&](const auto& h) {
    return h.kDim == D && h.wall.size() == nw * n && h.pair.size() == st.pair_key.size();
  }, st.histories);
  if (st.plastic_law() != (options.model == ContactModel::PlasticIndentation))
    fail(st.plastic_law() ? "state: a state of the plastic-indentation law needs ContactModel::PlasticIndentation"
                          : "state: a state of the Luding law cannot restart with ContactModel::PlasticIndentation");
  if (!sizes || !hist_sizes) fail("state: inconsistent array sizes");
  if (n == 0) fail("state: no particles");
  for (std::size_t i = 0; i < n; ++i)
    if (!(st.radius_ref[i] > 0.0 && P_.r[i] > 0.0 && P_.mass[i] > 0.0 && P_.inertia[i] > 0.0))
      fail("state: particle " + std::to_string(i) + " has a non-positive radius or mass");
  if (box_.enabled && !(box_.x_max > box_.x_min && box_.y_max > box_.y_min))
    fail("state: box must have x_max > x_min and y_max > y_min");
  if (D == 3 && box_.enabled && !(box_.z_max > box_.z_min)) fail("state: a 3D box must have z_max > z_min");
  if (!(st.dt > 0.0) || !std::isfinite(st.dt)) fail("state: time step must be positive");
  for (std::size_t k = 0; k < st.pair_key.size(); ++k) {
    const auto i = st.pair_key[k] >> 32, j = st.pair_key[k] & 0xffffffffu;
    if (!(i < j && j < n) || (k > 0 && !(st.pair_key[k - 1] < st.pair_key[k])))
      fail("state: contact table is not a sorted list of pairs i < j < N");
  }
  DynamicOptions o = opt_;
  o.dt = st.dt;
  // checks the stored dt against the stability rule
  if (plastic()) opt_.plastic.validate();
  choose_time_step_of_law(o, 0.0);
  thermal_ = st.thermal;
  time_ = st.time;
  radius_ref_ = st.radius_ref;
  radius_scale_ = P_.r[0] / radius_ref_[0];
  std::copy(S::wall_velocity(st), S::wall_velocity(st) + D, wall_v_);
  std::copy(S::wall_force(st), S::wall_force(st) + 2 * D, wall_force_);
  if constexpr (D == 2) {
    sxx_ = st.stress_sum[0];
    sxy_ = st.stress_sum[1];
    syx_ = st.stress_sum[2];
    syy_ = st.stress_sum[3];
  } else {
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) s3_[a][b] = st.stress_sum3[3 * a + b];
  }
  elastic_ = st.elastic;
  area_max_ = st.plastic_area_max;  // (0 for a law without a contact area)
  centre0_[0] = 0.5 * (box_.x_min + box_.x_max);  // the affine map starts again at the restart
  centre0_[1] = 0.5 * (box_.y_min + box_.y_max);
  if constexpr (D == 3) centre0z_ = 0.5 * (box_.z_min + box_.z_max);
  finish_setup();
  // The table is rebuilt from the current positions, carrying the stored histories; forces are
  // NOT re-evaluated (the stored ones are those of the last step).
  {  // the rows of the state, carried by the build below
    std::vector<int> pi(st.pair_key.size()), pj(st.pair_key.size());
    for (std::size_t k = 0; k < st.pair_key.size(); ++k) {
      pi[k] = static_cast<int>(st.pair_key[k] >> 32);
      pj[k] = static_cast<int>(st.pair_key[k] & 0xffffffffu);
    }
    rows_.assign(std::move(pi), std::move(pj));
  }
  visit_law([&](const auto& law) {
    using H = typename std::decay_t<decltype(law)>::History;
    if (!st.holds<H>()) fail("state: the state's histories are not of the solver's law (options.model)");
    hist_.template emplace<HistoryTable<H>>();
    table<H>().pair = st.histories_of<H>().pair;
    table<H>().wall = st.histories_of<H>().wall;
  });
  build_table();
  rebuilds_ = 0;
}

template <int D>
SolverState DynamicSolverT<D>::state() const {
  using S = StateOf<D>;
  SolverState st;
  st.particles = P_;  // (the alternative of dimension D)
  st.radius_ref = radius_ref_;
  st.box = box_;
  std::copy(wall_v_, wall_v_ + D, S::wall_velocity(st));
  std::copy(wall_force_, wall_force_ + 2 * D, S::wall_force(st));
  if constexpr (D == 2) {
    st.stress_sum[0] = sxx_;
    st.stress_sum[1] = sxy_;
    st.stress_sum[2] = syx_;
    st.stress_sum[3] = syy_;
  } else {
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) st.stress_sum3[3 * a + b] = s3_[a][b];
  }
  st.elastic = elastic_;
  st.time = time_;
  st.dt = ts_.dt;
  st.periodic = periodic_;
  st.thermal = thermal_;
  st.params = params_;
  if (plastic()) {
    st.plastic = opt_.plastic;
    st.plastic_wall_mu = opt_.plastic_wall_mu;
    st.plastic_area_max = area_max_;
  }
  // only the pairs with a live history (law.has_history); the others are rebuilt from positions
  visit_law([&](const auto& law) {
    using H = typename std::decay_t<decltype(law)>::History;
    const HistoryTable<H>& t = *table_if<H>();
    LawHistories<H>& h = st.histories.template emplace<LawHistories<H>>();
    for (std::size_t k = 0; k < rows_.pairs(); ++k)
      if (law.has_history(t.pair[k])) {
        st.pair_key.push_back(sys::PairRows<D>::key(rows_.pi[k], rows_.pj[k]));
        h.pair.push_back(t.pair[k]);
      }
    h.wall = t.wall;
  });
  return st;
}

template <int D>
void DynamicSolverT<D>::refresh_forces() {
  for (const auto* v : {&P_.vel, &P_.spin})
    for (double x : *v)
      if (x != 0.0) throw std::logic_error("refresh_forces: a particle moves (the forces of a state at rest only)");
  for (int a = 0; a < D; ++a)
    if (wall_v_[a] != 0.0) throw std::logic_error("refresh_forces: a wall moves (the forces of a state at rest only)");
  compute_forces_dispatch();
}

template <int D>
void DynamicSolverT<D>::advance_temperature(double T_new, double dt, double t0) {
  if (opt_.model != ContactModel::Full)
    fail("advance_temperature: a temperature needs ContactModel::Full");
  if (!std::isfinite(T_new) || !(dt >= 0.0) || !(t0 > 0.0))
    fail("advance_temperature: T must be finite, dt >= 0 and t0 > 0");
  const double k1T = contact::luding_k1_of_T(params_, T_new);
  if (T_new == thermal_.T && thermal_.k1_Tt == k1T) return;  // nothing moves
  const bool t_changed = T_new != thermal_.T;
  thermal_ = contact::luding_advance_thermal(params_, thermal_, T_new, dt, t0);
  if (t_changed) {  // Eq 9 with constant mass
    radius_scale_ = contact::luding_radius(params_, 1.0, T_new);
    for (std::size_t i = 0; i < P_.size(); ++i) {
      P_.r[i] = radius_ref_[i] * radius_scale_;
      P_.inertia[i] = contact::Dim<D>::kInertia * P_.mass[i] * P_.r[i] * P_.r[i];
    }
  }
}

template <int D>
void DynamicSolverT<D>::set_params(const LudingParams& params) {
  params.validate();
  params_ = params;
  wall_params_ = params_.wall_params();
  choose_friction();
}

template <int D>
void DynamicSolverT<D>::set_walls(const MovingWall& right, const MovingWall& back, const MovingWall& top) {
  if constexpr (D == 2) {
    (void)right;
    (void)back;
    (void)top;
    fail("set_walls: a 2D box has two moving walls (right, top)");
  } else {
    for (const MovingWall* w : {&right, &back, &top}) {
      if (w->mode == WallMode::Stress && !(w->mass > 0.0 && w->damping >= 0.0))
        fail("set_walls: a stress-controlled wall needs mass > 0 and damping >= 0");
    }
    box_.right = right;
    box_.back = back;
    box_.top = top;
    for (int a = 0; a < 3; ++a) {
      const MovingWall& w = moving_wall(a);
      if (w.mode == WallMode::Strain) wall_v_[a] = w.velocity;
      if (w.mode == WallMode::Fixed) wall_v_[a] = 0.0;
    }
  }
}

template <int D>
void DynamicSolverT<D>::set_walls(const MovingWall& right, const MovingWall& top) {
  if constexpr (D == 3) {
    set_walls(right, box_.back, top);
    return;
  }
  for (const MovingWall* w : {&right, &top})
    if (w->mode == WallMode::Stress && !(w->mass > 0.0 && w->damping >= 0.0))
      fail("set_walls: a stress-controlled wall needs mass > 0 and damping >= 0");
  box_.right = right;
  box_.top = top;
  if (right.mode == WallMode::Strain) wall_v_[0] = right.velocity;
  if (right.mode == WallMode::Fixed) wall_v_[0] = 0.0;
  if (top.mode == WallMode::Strain) wall_v_[1] = top.velocity;
  if (top.mode == WallMode::Fixed) wall_v_[1] = 0.0;
}

template <int D>
void DynamicSolverT<D>::set_gravity(double gx, double gy) {
  if (!std::isfinite(gx) || !std::isfinite(gy)) fail("set_gravity: gravity must be finite");
  opt_.gravity_x = gx + 0.0;  // (+0, never -0: the constructor's note)
  opt_.gravity_y = gy + 0.0;
}

template <int D>
void DynamicSolverT<D>::set_gravity(double gx, double gy, double gz) {
  if (D == 2 && gz != 0.0) fail("set_gravity: a 2D solver has no z");
  if (!std::isfinite(gz)) fail("set_gravity: gravity must be finite");
  set_gravity(gx, gy);
  opt_.gravity_z = gz + 0.0;
}

template <int D>
std::size_t DynamicSolverT<D>::wall_contacts() const {
  if (!walls_active()) return 0;
  std::size_t c = 0;
  const double lo[3] = {box_.x_min, box_.y_min, box_.z_min}, hi[3] = {box_.x_max, box_.y_max, box_.z_max};
  for (std::size_t i = 0; i < P_.size(); ++i) {
    const double r = P_.r[i];
    for (int a = 0; a < D; ++a) c += (P_.pos[D * i + a] - lo[a] < r) + (hi[a] - P_.pos[D * i + a] < r);
  }
  return c;
}


namespace {
void set_tangential(ContactInfo& c, double f_t) { c.f_t = f_t; }
void set_tangential(ContactInfo& c, const Eigen::Vector3d& f_t) {
  c.ftx = f_t.x();
  c.fty = f_t.y();
  c.ftz = f_t.z();
  c.f_t = f_t.norm();
}

// The touching contacts (pairs of the table, then the walls) at the current positions, with the
// law evaluated on the committed histories with a zero slip increment and the current normal
// rate. eval(history, kinematics, wall, info) fills the forces of `info` and returns whether the
// contact is reported.
// Periodic (issue 29): `frame` holds the branch offsets h n of the rows (D per row) and the strain
// rate L (3 x 3, row-major): the velocities are the fluctuations, the relative one adds L l.
struct PeriodicFrame {
  std::vector<double> offset;
  double L[9] = {};
};
template <int D, class H, class Eval>
void contacts_of(const ParticlesT<D>& P, const Box& box, const sys::PairRows<D>& rows,
                 const std::vector<H>& hist, const std::vector<H>& whist, std::vector<ContactInfo>& out, Eval&& eval,
                 const PeriodicFrame* frame = nullptr) {
  out.clear();
  auto xc = [&](std::size_t i) { return P.pos[D * i]; };
  auto yc = [&](std::size_t i) { return P.pos[D * i + 1]; };
  auto zc = [&](std::size_t i) {
    if constexpr (D == 3) return P.pos[D * i + 2];
    else return 0.0;
  };
  auto vxc = [&](std::size_t i) { return P.vel[D * i]; };
  auto vyc = [&](std::size_t i) { return P.vel[D * i + 1]; };
  auto vzc = [&](std::size_t i) {
    if constexpr (D == 3) return P.vel[D * i + 2];
    else return 0.0;
  };
  for (std::size_t k = 0; k < rows.pairs(); ++k) {
    const auto i = static_cast<std::uint32_t>(rows.pi[k]);
    const auto j = static_cast<std::uint32_t>(rows.pj[k]);
    double dx = xc(j) - xc(i), dy = yc(j) - yc(i), dz = zc(j) - zc(i);
    double avx = 0.0, avy = 0.0, avz = 0.0;  // periodic: L l
    if (frame) {
      const double* o = &frame->offset[static_cast<std::size_t>(D) * k];
      dx += o[0], dy += o[1];
      if constexpr (D == 3) dz += o[2];
      const double* L = frame->L;
      avx = L[0] * dx + L[1] * dy + L[2] * dz;
      avy = L[3] * dx + L[4] * dy + L[5] * dz;
      avz = L[6] * dx + L[7] * dy + L[8] * dz;
    }
    const double ri = P.r[i], rj = P.r[j], s = ri + rj;
    const double L2 = D == 2 ? dx * dx + dy * dy : dx * dx + dy * dy + dz * dz;
    if (!(L2 < s * s)) continue;
    const double L = std::sqrt(L2), nx = dx / L, ny = dy / L, nz = dz / L;
    const double q = (ri * ri - rj * rj) / (2.0 * L);
    contact::Kinematics<D> in;
    in.overlap = in.overlap_start = s - L;
    if (frame) {
      in.v_n = -((vxc(j) - vxc(i) + avx) * nx + (vyc(j) - vyc(i) + avy) * ny);
      if constexpr (D == 3) in.v_n -= (vzc(j) - vzc(i) + avz) * nz;
    } else if constexpr (D == 2) {
      in.v_n = -((vxc(j) - vxc(i)) * nx + (vyc(j) - vyc(i)) * ny);
    } else {
      in.v_n = -((vxc(j) - vxc(i)) * nx + (vyc(j) - vyc(i)) * ny + (vzc(j) - vzc(i)) * nz);
    }
    in.r_eff = ri * rj / s;
    in.m_eff = P.mass[i] * P.mass[j] / (P.mass[i] + P.mass[j]);
    ContactInfo c;
    c.i = i;
    c.j = j;
    c.overlap = in.overlap;
    c.d_i = 0.5 * L + q;
    c.d_j = 0.5 * L - q;
    c.nx = nx;
    c.ny = ny;
    if constexpr (D == 3) {
      c.nz = nz;
      in.transport.n = Eigen::Vector3d(nx, ny, nz);  // the committed spring lies in this plane already
    }
    if (!eval(hist[k], in, false, c)) continue;
    c.sliding = hist[k].sliding != 0;
    out.push_back(c);
  }
  if (!(box.enabled && box.contact_walls)) return;
  constexpr int W = 2 * D;
  const double pos[6] = {box.x_min, box.x_max, box.y_min, box.y_max, box.z_min, box.z_max};
  for (std::size_t i = 0; i < P.size(); ++i)
    for (int w = 0; w < W; ++w) {
      const int axis = w / 2;
      const double sign = (w % 2 == 0) ? 1.0 : -1.0;  // the normal from the wall into the box
      const double xa = P.pos[D * i + static_cast<std::size_t>(axis)];
      const double va = P.vel[D * i + static_cast<std::size_t>(axis)];
      const double dist = sign * (xa - pos[w]);
      const double delta = P.r[i] - dist;
      if (!(delta > 0.0)) continue;
      contact::Kinematics<D> in;
      in.overlap = in.overlap_start = delta;
      in.v_n = -(va * sign);
      in.r_eff = P.r[i];
      in.m_eff = P.mass[i];
      const H& h = whist[static_cast<std::size_t>(W) * i + static_cast<std::size_t>(w)];
      ContactInfo c;
      c.i = static_cast<std::uint32_t>(i);
      c.j = static_cast<std::uint32_t>(w);
      c.wall = w;
      c.overlap = delta;
      c.d_i = dist;
      c.nx = axis == 0 ? sign : 0.0;
      c.ny = axis == 1 ? sign : 0.0;
      if constexpr (D == 3) {
        c.nz = axis == 2 ? sign : 0.0;
        in.transport.n = Eigen::Vector3d(c.nx, c.ny, c.nz);
      }
      if (!eval(h, in, true, c)) continue;
      c.sliding = h.sliding != 0;
      out.push_back(c);
    }
}

template <contact::LudingFeatures F, int D>
void luding_contacts(const ParticlesT<D>& P, const Box& box, const LudingParams& pp, const LudingParams& pw, double k1Tt,
                     const sys::PairRows<D>& rows, const std::vector<contact::LudingHistoryT<D>>& hist,
                     const std::vector<contact::LudingHistoryT<D>>& whist, std::vector<ContactInfo>& out,
                     const PeriodicFrame* frame) {
  contacts_of<D>(P, box, rows, hist, whist, out,
                 [&](const contact::LudingHistoryT<D>& h, const contact::Kinematics<D>& k, bool wall, ContactInfo& c) {
                   contact::LudingInputT<D> in;
                   in.delta = k.overlap;
                   in.delta_dot = k.v_n;
                   in.k1_Tt = k1Tt;
                   const auto r = contact::luding_evaluate<F>(wall ? pw : pp, h, in);
                   c.f_n = r.f_n;
                   in.delta_dot = 0.0;
                   c.f_spring = contact::luding_evaluate<F>(wall ? pw : pp, h, in).f_n;
                   set_tangential(c, r.f_t);
                   c.f_min = r.f_min;
                   c.mu = r.mu;
                   return true;
                 }, frame);
}
constexpr contact::LudingFeatures kHystereticOut{true, false, false, true};

// The plastic-indentation law: the contacts on their loaded branch.
template <int D>
void plastic_contacts(const ParticlesT<D>& P, const Box& box, const contact::PlasticIndentationParams& pp,
                      const contact::PlasticIndentationParams& pw, const sys::PairRows<D>& rows,
                      const std::vector<contact::PlasticIndentationHistoryT<D>>& hist,
                      const std::vector<contact::PlasticIndentationHistoryT<D>>& whist, std::vector<ContactInfo>& out,
                      const PeriodicFrame* frame) {
  const contact::PlasticIndentationLawT<D> lp(pp), lw(pw);
  contacts_of<D>(P, box, rows, hist, whist, out,
                 [&](const contact::PlasticIndentationHistoryT<D>& h, const contact::Kinematics<D>& k, bool wall,
                     ContactInfo& c) {
                   const auto& law = wall ? lw : lp;
                   const auto r = law.evaluate(h, k, nullptr);
                   c.f_n = r.f_n;
                   auto k0 = k;  // no relative velocity: the spring force without the dashpot
                   k0.v_n = 0.0;
                   k0.v_t = contact::tan_zero<typename contact::Dim<D>::Tan>();
                   c.f_spring = law.evaluate(h, k0, nullptr).f_n;
                   set_tangential(c, r.f_t);
                   c.mu = (wall ? pw : pp).mu_eff();
                   return r.loaded;
                 }, frame);
}
}  // namespace

template <int D>
void DynamicSolverT<D>::contacts(std::vector<ContactInfo>& out) const {
  // (the output's own choice of law: the Luding law reports f_min and mu of its response)
  PeriodicFrame frame_storage;
  const PeriodicFrame* frame = nullptr;
  if (periodic_) {  // the rows' branch offsets h n and the strain rate
    frame_storage.offset.resize(static_cast<std::size_t>(D) * rows_.pairs());
    for (std::size_t k = 0; k < rows_.pairs(); ++k)
      for (int a = 0; a < D; ++a) {
        double o = 0.0;
        for (int b = 0; b < D; ++b) o += cell_.h(a, b) * rows_.shift[k][static_cast<std::size_t>(b)];
        frame_storage.offset[static_cast<std::size_t>(D) * k + a] = o;
      }
    for (int a = 0; a < D; ++a)
      for (int b = 0; b < D; ++b)
        frame_storage.L[3 * a + b] = velocity_gradient(a, b);
    frame = &frame_storage;
  }
  if (const HistoryTable<PlasticHist>* t = table_if<PlasticHist>()) {
    plastic_contacts<D>(P_, box_, opt_.plastic, pl_wall_params_, rows_, t->pair, t->wall, out, frame);
    return;
  }
  const HistoryTable<LudingHist>& t = *table_if<LudingHist>();
  switch (opt_.model) {
    case ContactModel::Linear:
      luding_contacts<contact::kLudingLinear, D>(P_, box_, params_, wall_params_, thermal_.k1_Tt, rows_, t.pair,
                                                 t.wall, out, frame);
      break;
    case ContactModel::Hysteretic:
      luding_contacts<kHystereticOut, D>(P_, box_, params_, wall_params_, thermal_.k1_Tt, rows_, t.pair, t.wall,
                                         out, frame);
      break;
    default:
      luding_contacts<contact::kLudingFull, D>(P_, box_, params_, wall_params_, thermal_.k1_Tt, rows_, t.pair,
                                               t.wall, out, frame);
      break;
  }
}

// the members defined here, for both dimensions (the class: solver.cpp)
template DynamicSolverT<2>::DynamicSolverT(const SolverState&, const DynamicOptions&);
template SolverState DynamicSolverT<2>::state() const;
template void DynamicSolverT<2>::refresh_forces();
template void DynamicSolverT<2>::advance_temperature(double, double, double);
template void DynamicSolverT<2>::set_params(const LudingParams&);
template void DynamicSolverT<2>::set_walls(const MovingWall&, const MovingWall&);
template void DynamicSolverT<2>::set_walls(const MovingWall&, const MovingWall&, const MovingWall&);
template void DynamicSolverT<2>::set_gravity(double, double);
template void DynamicSolverT<2>::set_gravity(double, double, double);
template std::size_t DynamicSolverT<2>::wall_contacts() const;
template void DynamicSolverT<2>::contacts(std::vector<ContactInfo>&) const;
template DynamicSolverT<3>::DynamicSolverT(const SolverState&, const DynamicOptions&);
template SolverState DynamicSolverT<3>::state() const;
template void DynamicSolverT<3>::refresh_forces();
template void DynamicSolverT<3>::advance_temperature(double, double, double);
template void DynamicSolverT<3>::set_params(const LudingParams&);
template void DynamicSolverT<3>::set_walls(const MovingWall&, const MovingWall&);
template void DynamicSolverT<3>::set_walls(const MovingWall&, const MovingWall&, const MovingWall&);
template void DynamicSolverT<3>::set_gravity(double, double);
template void DynamicSolverT<3>::set_gravity(double, double, double);
template std::size_t DynamicSolverT<3>::wall_contacts() const;
template void DynamicSolverT<3>::contacts(std::vector<ContactInfo>&) const;

}  // namespace netdem::dem
