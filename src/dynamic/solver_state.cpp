// Solver state between steps: restart, temperature schedule, parameter and wall changes, and the
// state file (see state.hpp and docs/dynamic.md).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

#include <fmt/format.h>

#include "netdem/packing/io.hpp"

#include "netdem/dynamic/solver.hpp"
#include "netdem/dynamic/state.hpp"
#include "netdem/packing/cell_grid.hpp"

namespace netdem::dem {

namespace {
[[noreturn]] void fail(const std::string& msg) { throw std::invalid_argument(msg); }
}  // namespace

std::string quote_input(const std::string& s) { return packing::quote_input(s, 80); }

namespace {
// The SolverState fields of dimension D (the 2D ones, or the 3D ones of a sphere state).
template <int D>
struct StateOf;
template <>
struct StateOf<2> {
  static auto& pair(SolverState& s) { return s.pair_history; }
  static auto& wall(SolverState& s) { return s.wall_history; }
  static auto& pl_pair(SolverState& s) { return s.plastic_pair_history; }
  static auto& pl_wall(SolverState& s) { return s.plastic_wall_history; }
  static const auto& pair(const SolverState& s) { return s.pair_history; }
  static const auto& wall(const SolverState& s) { return s.wall_history; }
  static const auto& pl_pair(const SolverState& s) { return s.plastic_pair_history; }
  static const auto& pl_wall(const SolverState& s) { return s.plastic_wall_history; }
  static double* wall_velocity(SolverState& s) { return s.wall_velocity; }
  static const double* wall_velocity(const SolverState& s) { return s.wall_velocity; }
  static double* wall_force(SolverState& s) { return s.wall_force; }
  static const double* wall_force(const SolverState& s) { return s.wall_force; }
};
template <>
struct StateOf<3> {
  static auto& pair(SolverState& s) { return s.pair_history3; }
  static auto& wall(SolverState& s) { return s.wall_history3; }
  static auto& pl_pair(SolverState& s) { return s.plastic_pair_history3; }
  static auto& pl_wall(SolverState& s) { return s.plastic_wall_history3; }
  static const auto& pair(const SolverState& s) { return s.pair_history3; }
  static const auto& wall(const SolverState& s) { return s.wall_history3; }
  static const auto& pl_pair(const SolverState& s) { return s.plastic_pair_history3; }
  static const auto& pl_wall(const SolverState& s) { return s.plastic_wall_history3; }
  static double* wall_velocity(SolverState& s) { return s.wall_velocity3; }
  static const double* wall_velocity(const SolverState& s) { return s.wall_velocity3; }
  static double* wall_force(SolverState& s) { return s.wall_force3; }
  static const double* wall_force(const SolverState& s) { return s.wall_force3; }
};
}  // namespace

template <int D>
DynamicSolverT<D>::DynamicSolverT(const SolverState& st, const DynamicOptions& options)
    : P_(st.particles), params_(st.params), box_(st.box), opt_(options) {
  using S = StateOf<D>;
  params_.validate();
  opt_.validate();
  const std::size_t n = P_.size();
  if (P_.dim != D) fail(fmt::format("state: the particles are {}D, the solver {}D", P_.dim, D));
  auto same = [n](std::size_t m) { return m == n; };
  const auto& wh = S::wall(st);
  const auto& pwh = S::pl_wall(st);
  const std::size_t nw = static_cast<std::size_t>(kWalls);
  bool sizes = same(P_.y.size()) && same(P_.vx.size()) && same(P_.vy.size()) && same(P_.omega.size()) &&
               same(P_.theta.size()) && same(P_.radius.size()) && same(P_.mass.size()) &&
               same(P_.inertia.size()) && same(P_.fx.size()) && same(P_.fy.size()) && same(P_.torque.size()) &&
               same(st.radius_ref.size());
  if constexpr (D == 3)
    sizes = sizes && same(P_.z.size()) && same(P_.vz.size()) && same(P_.fz.size()) && same(P_.wx.size()) &&
            same(P_.wy.size()) && same(P_.tx.size()) && same(P_.ty.size());
  const bool luding_h = wh.size() == nw * n && st.pair_key.size() == S::pair(st).size();
  const bool plastic_h = options.model == ContactModel::PlasticIndentation && pwh.size() == nw * n &&
                         S::pl_pair(st).size() == st.pair_key.size() && wh.empty() && S::pair(st).empty();
  if (!sizes || !(luding_h || plastic_h)) fail("state: inconsistent array sizes");
  if (n == 0) fail("state: no particles");
  for (std::size_t i = 0; i < n; ++i)
    if (!(st.radius_ref[i] > 0.0 && P_.radius[i] > 0.0 && P_.mass[i] > 0.0 && P_.inertia[i] > 0.0))
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
  ts_ = plastic() ? plastic_time_step(P_, opt_.plastic, o, 0.0) : choose_time_step(P_, params_, o);
  thermal_ = st.thermal;
  time_ = st.time;
  radius_ref_ = st.radius_ref;
  radius_scale_ = P_.radius[0] / radius_ref_[0];
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
  wall_hist_ = wh;
  pl_wall_hist_ = pwh;
  centre0_[0] = 0.5 * (box_.x_min + box_.x_max);  // the affine map starts again at the restart
  centre0_[1] = 0.5 * (box_.y_min + box_.y_max);
  if constexpr (D == 3) centre0z_ = 0.5 * (box_.z_min + box_.z_max);
  finish_setup();
  // The table is rebuilt from the current positions, carrying the stored histories; forces are
  // NOT re-evaluated (the stored ones are those of the last step).
  pair_key_ = st.pair_key;
  pair_hist_ = S::pair(st);
  pl_pair_hist_ = S::pl_pair(st);
  build_table();
  rebuilds_ = 0;
}

template <int D>
SolverState DynamicSolverT<D>::state() const {
  using S = StateOf<D>;
  SolverState st;
  st.particles = P_;
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
  st.thermal = thermal_;
  st.params = params_;
  // only the pairs with a live history (touching); the others are rebuilt from positions
  for (std::size_t k = 0; k < pair_key_.size(); ++k) {
    if (plastic()) {
      const PlasticHist& h = pl_pair_hist_[k];
      if (h.u_max != 0.0 || !contact::tan_is_zero(h.f_t) || h.sliding != 0) {
        st.pair_key.push_back(pair_key_[k]);
        S::pl_pair(st).push_back(h);
      }
      continue;
    }
    const LudingHist& h = pair_hist_[k];
    if (!h.fresh()) {
      st.pair_key.push_back(pair_key_[k]);
      S::pair(st).push_back(h);
    }
  }
  S::wall(st) = wall_hist_;
  S::pl_wall(st) = pl_wall_hist_;
  return st;
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
      P_.radius[i] = radius_ref_[i] * radius_scale_;
      P_.inertia[i] = contact::Dim<D>::kInertia * P_.mass[i] * P_.radius[i] * P_.radius[i];
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
  opt_.gravity_x = gx;
  opt_.gravity_y = gy;
}

template <int D>
void DynamicSolverT<D>::set_gravity(double gx, double gy, double gz) {
  if (D == 2 && gz != 0.0) fail("set_gravity: a 2D solver has no z");
  if (!std::isfinite(gz)) fail("set_gravity: gravity must be finite");
  set_gravity(gx, gy);
  opt_.gravity_z = gz;
}

template <int D>
std::size_t DynamicSolverT<D>::wall_contacts() const {
  if (!walls_active()) return 0;
  std::size_t c = 0;
  for (std::size_t i = 0; i < P_.size(); ++i) {
    const double r = P_.radius[i];
    c += (P_.x[i] - box_.x_min < r) + (box_.x_max - P_.x[i] < r) + (P_.y[i] - box_.y_min < r) +
         (box_.y_max - P_.y[i] < r);
    if constexpr (D == 3) c += (P_.z[i] - box_.z_min < r) + (box_.z_max - P_.z[i] < r);
  }
  return c;
}

// ---- state file --------------------------------------------------------------------------------
namespace {

struct ParamField {
  const char* name;
  double LudingParams::*d;
  bool LudingParams::*b;
};
// Every LudingParams field, by name (state files; the apps' --param NAME=VALUE).
const ParamField kFields[] = {
    {"k2", &LudingParams::k2, nullptr},
    {"k1_ratio", &LudingParams::k1_ratio, nullptr},
    {"kc_ratio", &LudingParams::kc_ratio, nullptr},
    {"alpha", &LudingParams::alpha, nullptr},
    {"gamma_n", &LudingParams::gamma_n, nullptr},
    {"gamma_t", &LudingParams::gamma_t, nullptr},
    {"mu", &LudingParams::mu, nullptr},
    {"mu_wall", &LudingParams::mu_wall, nullptr},
    {"T_melt", &LudingParams::T_melt, nullptr},
    {"T_var", &LudingParams::T_var, nullptr},
    {"da_T", &LudingParams::da_T, nullptr},
    {"delta_fluid_rel", &LudingParams::delta_fluid_rel, nullptr},
    {"t0", &LudingParams::t0, nullptr},
    {"t0_sinter", &LudingParams::t0_sinter, nullptr},
    {"a0", &LudingParams::a0, nullptr},
    {"w0", &LudingParams::w0, nullptr},
    {"h", &LudingParams::h, nullptr},
    {"rho_p", &LudingParams::rho_p, nullptr},
    {"m_wall", &LudingParams::m_wall, nullptr},
    {"gamma_wall", &LudingParams::gamma_wall, nullptr},
    {"T_radius_ref", &LudingParams::T_radius_ref, nullptr},
    {"stiffness_growth", nullptr, &LudingParams::stiffness_growth},
    {"sliding_breaks_cohesion", nullptr, &LudingParams::sliding_breaks_cohesion},
    // optional in a state file (added after v2; missing lines keep the default)
    {"cooling_stiffness_update", nullptr, &LudingParams::cooling_stiffness_update},
    {"wall_sintering", nullptr, &LudingParams::wall_sintering},
};
// The first kRequiredParams fields must be in every state file, the rest may be left out.
constexpr std::size_t kRequiredParams = 23;

std::string g17(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.17g", v);
  return b;
}

const char* mode_name(WallMode m) {
  return m == WallMode::Fixed ? "fixed" : m == WallMode::Strain ? "strain" : "stress";
}

void put_tan(std::ostringstream& o, double v) { o << g17(v); }
void put_tan(std::ostringstream& o, const Eigen::Vector3d& v) { o << g17(v.x()) << ' ' << g17(v.y()) << ' ' << g17(v.z()); }

template <int D>
void put_history(std::ostringstream& o, const contact::LudingHistoryT<D>& h) {
  o << g17(h.delta_max) << ' ' << g17(h.delta0) << ' ' << g17(h.k2_line) << ' ' << g17(h.k1_seen) << ' ';
  put_tan(o, h.xi);
  o << ' ' << int(h.fluid) << ' ' << int(h.sliding);
}

}  // namespace

std::vector<std::string> luding_param_names() {
  std::vector<std::string> v;
  for (const auto& f : kFields) v.emplace_back(f.name);
  return v;
}

void set_luding_param(LudingParams& p, const std::string& name, double value) {
  for (const auto& f : kFields)
    if (name == f.name) {
      if (!std::isfinite(value)) fail("parameter " + name + " must be a finite number");
      if (f.d) p.*f.d = value;
      else p.*f.b = value != 0.0;
      return;
    }
  fail("unknown contact parameter '" + quote_input(name) + "'");
}

double get_luding_param(const LudingParams& p, const std::string& name) {
  for (const auto& f : kFields)
    if (name == f.name) return f.d ? p.*f.d : (p.*f.b ? 1.0 : 0.0);
  fail("unknown contact parameter '" + name + "'");
}

namespace {
// The body of a state file after its first line, for D = 2 (v2 as it always was) or D = 3 (the
// line "dim 3" first, then z, the back wall, six walls, the 3 x 3 stress sum and the spin vector).
template <int D>
void format_state_body(std::ostringstream& o, const SolverState& st) {
  using S = StateOf<D>;
  const Particles& P = st.particles;
  if constexpr (D == 3) o << "dim 3\n";
  o << "time " << g17(st.time) << "\ndt " << g17(st.dt) << "\n";
  if constexpr (D == 2)
    o << "box " << int(st.box.enabled) << ' ' << g17(st.box.x_min) << ' ' << g17(st.box.y_min) << ' '
      << g17(st.box.x_max) << ' ' << g17(st.box.y_max) << "\n";
  else
    o << "box " << int(st.box.enabled) << ' ' << g17(st.box.x_min) << ' ' << g17(st.box.y_min) << ' '
      << g17(st.box.z_min) << ' ' << g17(st.box.x_max) << ' ' << g17(st.box.y_max) << ' ' << g17(st.box.z_max)
      << "\n";
  const MovingWall* w[3] = {&st.box.right, D == 3 ? &st.box.back : &st.box.top, &st.box.top};
  const char* wn[3] = {"wall_right", D == 3 ? "wall_back" : "wall_top", "wall_top"};
  for (int k = 0; k < D; ++k)
    o << wn[k] << ' ' << mode_name(w[k]->mode) << ' ' << g17(w[k]->velocity) << ' '
      << g17(w[k]->pressure) << ' ' << g17(w[k]->mass) << ' ' << g17(w[k]->damping) << ' '
      << g17(S::wall_velocity(st)[k]) << "\n";
  o << "wall_force";
  for (int k = 0; k < 2 * D; ++k) o << ' ' << g17(S::wall_force(st)[k]);
  o << "\nstress_sum";
  for (int k = 0; k < D * D; ++k) o << ' ' << g17(D == 2 ? st.stress_sum[k] : st.stress_sum3[k]);
  o << ' ' << g17(st.elastic) << "\n";
  o << "thermal " << g17(st.thermal.T) << ' ' << g17(st.thermal.k1_Tt) << "\n";
  for (const auto& f : kFields) o << "param " << f.name << ' ' << g17(get_luding_param(st.params, f.name)) << "\n";
  o << "particles " << P.size() << "\n";
  if constexpr (D == 2) {
    o << "id,x,y,vx,vy,omega,theta,radius,radius_ref,mass,inertia,fx,fy,torque\n";
    for (std::size_t i = 0; i < P.size(); ++i)
      o << i << ',' << g17(P.x[i]) << ',' << g17(P.y[i]) << ',' << g17(P.vx[i]) << ',' << g17(P.vy[i])
        << ',' << g17(P.omega[i]) << ',' << g17(P.theta[i]) << ',' << g17(P.radius[i]) << ','
        << g17(st.radius_ref[i]) << ',' << g17(P.mass[i]) << ',' << g17(P.inertia[i]) << ','
        << g17(P.fx[i]) << ',' << g17(P.fy[i]) << ',' << g17(P.torque[i]) << "\n";
  } else {
    o << "id,x,y,z,vx,vy,vz,wx,wy,wz,radius,radius_ref,mass,inertia,fx,fy,fz,tx,ty,tz\n";
    for (std::size_t i = 0; i < P.size(); ++i)
      o << i << ',' << g17(P.x[i]) << ',' << g17(P.y[i]) << ',' << g17(P.z[i]) << ',' << g17(P.vx[i]) << ','
        << g17(P.vy[i]) << ',' << g17(P.vz[i]) << ',' << g17(P.wx[i]) << ',' << g17(P.wy[i]) << ','
        << g17(P.omega[i]) << ',' << g17(P.radius[i]) << ',' << g17(st.radius_ref[i]) << ','
        << g17(P.mass[i]) << ',' << g17(P.inertia[i]) << ',' << g17(P.fx[i]) << ',' << g17(P.fy[i]) << ','
        << g17(P.fz[i]) << ',' << g17(P.tx[i]) << ',' << g17(P.ty[i]) << ',' << g17(P.torque[i]) << "\n";
  }
  o << "pairs " << st.pair_key.size() << "\n";
  o << (D == 2 ? "# i j delta_max delta0 k2_line k1_seen xi fluid sliding\n"
               : "# i j delta_max delta0 k2_line k1_seen xi_x xi_y xi_z fluid sliding\n");
  for (std::size_t k = 0; k < st.pair_key.size(); ++k) {
    o << (st.pair_key[k] >> 32) << ' ' << (st.pair_key[k] & 0xffffffffu) << ' ';
    put_history<D>(o, S::pair(st)[k]);
    o << "\n";
  }
  const auto& wh = S::wall(st);
  std::size_t nw = 0;
  for (const auto& h : wh) nw += !h.fresh();
  o << "wall_contacts " << nw << "\n";
  o << (D == 2 ? "# particle wall(0 left, 1 right, 2 bottom, 3 top) delta_max delta0 k2_line k1_seen xi fluid sliding\n"
               : "# particle wall(0 x_min, 1 x_max, 2 y_min, 3 y_max, 4 z_min, 5 z_max) delta_max delta0 k2_line "
                 "k1_seen xi_x xi_y xi_z fluid sliding\n");
  constexpr std::size_t W = 2 * D;
  for (std::size_t k = 0; k < wh.size(); ++k) {
    const auto& h = wh[k];
    if (h.fresh()) continue;
    o << k / W << ' ' << k % W << ' ';
    put_history<D>(o, h);
    o << "\n";
  }
  o << "end\n";
}
}  // namespace

std::string format_state(const SolverState& st) {
  if (!st.plastic_wall_history.empty() || !st.plastic_wall_history3.empty())
    throw std::invalid_argument("state files hold the Luding models only (not the plastic-indentation law)");
  std::ostringstream o;
  o << "# demsolve state v2 (docs/dynamic.md); lengths m, masses kg, times s, forces N\n";
  if (st.dim() == 3)
    format_state_body<3>(o, st);
  else
    format_state_body<2>(o, st);
  return o.str();
}

namespace {

class Reader {
 public:
  Reader(std::istream& in, std::string name) : in_(in), name_(std::move(name)) {}
  /// Next line that is not empty and not a comment.
  std::string line() {
    if (!pending_.empty()) {
      std::string s = std::move(pending_);
      pending_.clear();
      ++no_;
      return s;
    }
    std::string s;
    while (std::getline(in_, s)) {
      ++no_;
      if (!s.empty() && s.back() == '\r') s.pop_back();
      if (!s.empty() && s[0] != '#') return s;
    }
    error("unexpected end of file");
  }
  /// A line "key v1 v2 ..." with the given key; returns the rest as a stream.
  std::istringstream keyed(const std::string& key) {
    std::istringstream ls(line());
    std::string k;
    ls >> k;
    if (k != key) error("expected '" + key + "', found '" + quote_input(k) + "'");
    return ls;
  }
  template <class T>
  T num(std::istringstream& ls, const char* what) {
    T v{};
    if (!(ls >> v)) error(std::string("cannot read ") + what);
    return v;
  }
  [[noreturn]] void error(const std::string& msg) const { error_at(no_, msg); }
  [[noreturn]] void error_at(std::size_t line, const std::string& msg) const {
    throw std::invalid_argument(quote_input(name_) + ":" + std::to_string(line) + ": " + msg);
  }
  std::size_t line_no() const { return no_; }
  /// Gives the last line back: the next line() returns it again.
  void unread(std::string s) {
    pending_ = std::move(s);
    --no_;
  }
  void count_line() { ++no_; }  ///< a line read by the caller (the first)
  /// A finite real number (strtod: also reads nan and inf, which are refused by name).
  double real(std::istringstream& ls, const char* what) {
    std::string tok;
    if (!(ls >> tok)) error(std::string("missing ") + what);
    char* end = nullptr;
    const double v = std::strtod(tok.c_str(), &end);
    if (end == tok.c_str() || *end != '\0') error(std::string("cannot read ") + what + " '" + quote_input(tok) + "'");
    if (!std::isfinite(v)) error(std::string(what) + " is not a finite number ('" + quote_input(tok) + "')");
    return v;
  }

 private:
  std::istream& in_;
  std::string name_;
  std::size_t no_ = 0;
  std::string pending_;
};

WallMode parse_mode(Reader& r, const std::string& s) {
  if (s == "fixed") return WallMode::Fixed;
  if (s == "strain") return WallMode::Strain;
  if (s == "stress") return WallMode::Stress;
  r.error("unknown wall mode '" + quote_input(s) + "'");
}

template <int D>
contact::LudingHistoryT<D> get_history(Reader& r, std::istringstream& ls) {
  contact::LudingHistoryT<D> h;
  h.delta_max = r.real(ls, "delta_max");
  h.delta0 = r.real(ls, "delta0");
  h.k2_line = r.real(ls, "k2_line");
  h.k1_seen = r.real(ls, "k1_seen");
  if constexpr (D == 2) {
    h.xi = r.real(ls, "xi");
  } else {
    h.xi.x() = r.real(ls, "xi_x");
    h.xi.y() = r.real(ls, "xi_y");
    h.xi.z() = r.real(ls, "xi_z");
  }
  h.fluid = static_cast<std::uint8_t>(r.num<int>(ls, "fluid") != 0);
  h.sliding = static_cast<std::uint8_t>(r.num<int>(ls, "sliding") != 0);
  return h;
}

// The body of a state file after its first line (and, in 3D, after "dim 3"): format_state_body.
template <int D>
void parse_state_body(Reader& r, SolverState& st) {
  using S = StateOf<D>;
  auto one = [&](const char* key) {
    auto ls = r.keyed(key);
    return r.real(ls, key);
  };
  st.time = one("time");
  if (!(st.time >= 0.0 && st.time <= StateLimits::kMaxTime)) r.error(fmt::format("time must be in [0, {:g}] s", StateLimits::kMaxTime));
  st.dt = one("dt");
  if (!(st.dt > 0.0 && st.dt <= StateLimits::kMaxDt)) r.error(fmt::format("dt must be in (0, {:g}] s", StateLimits::kMaxDt));
  std::size_t box_line = 0, wall_line[3] = {0, 0, 0}, thermal_line = 0;
  {
    auto ls = r.keyed("box");
    box_line = r.line_no();
    st.box.enabled = r.num<int>(ls, "box enabled") != 0;
    st.box.x_min = r.real(ls, "x_min");
    st.box.y_min = r.real(ls, "y_min");
    if constexpr (D == 3) st.box.z_min = r.real(ls, "z_min");
    st.box.x_max = r.real(ls, "x_max");
    st.box.y_max = r.real(ls, "y_max");
    if constexpr (D == 3) st.box.z_max = r.real(ls, "z_max");
  }
  MovingWall* w[3] = {&st.box.right, D == 3 ? &st.box.back : &st.box.top, &st.box.top};
  const char* wn[3] = {"wall_right", D == 3 ? "wall_back" : "wall_top", "wall_top"};
  for (int k = 0; k < D; ++k) {
    auto ls = r.keyed(wn[k]);
    wall_line[k] = r.line_no();
    w[k]->mode = parse_mode(r, r.num<std::string>(ls, "wall mode"));
    w[k]->velocity = r.real(ls, "wall velocity");
    w[k]->pressure = r.real(ls, "wall pressure");
    w[k]->mass = r.real(ls, "wall mass");
    w[k]->damping = r.real(ls, "wall damping");
    S::wall_velocity(st)[k] = r.real(ls, "wall velocity");
    if (w[k]->mode == WallMode::Stress && !(w[k]->mass > 0.0 && w[k]->damping >= 0.0 && w[k]->pressure >= 0.0))
      r.error("a stress-controlled wall needs mass > 0, damping >= 0 and pressure >= 0");
  }
  {
    auto ls = r.keyed("wall_force");
    for (int k = 0; k < 2 * D; ++k) S::wall_force(st)[k] = r.real(ls, "wall force");
  }
  {
    auto ls = r.keyed("stress_sum");
    for (int k = 0; k < D * D; ++k) (D == 2 ? st.stress_sum[k] : st.stress_sum3[k]) = r.real(ls, "stress");
    st.elastic = r.real(ls, "elastic energy");
  }
  {
    auto ls = r.keyed("thermal");
    thermal_line = r.line_no();
    st.thermal.T = r.real(ls, "T");
    st.thermal.k1_Tt = r.real(ls, "k1_Tt");
  }
  for (std::size_t k = 0; k < std::size(kFields); ++k) {
    if (k >= kRequiredParams) {  // optional lines: stop at the first line that is not a param
      std::string s = r.line();
      std::istringstream ks(s);
      std::string key;
      ks >> key;
      r.unread(s);
      if (key != "param") break;
    }
    auto ls = r.keyed("param");
    const auto key = r.num<std::string>(ls, "parameter name");
    const double v = r.real(ls, "parameter value");
    try {
      set_luding_param(st.params, key, v);
    } catch (const std::invalid_argument& e) {
      r.error(e.what());
    }
  }
  try {
    st.params.validate();
  } catch (const std::invalid_argument& e) {
    r.error(e.what());
  }
  const LudingParams& lp = st.params;
  // what needs the parameters: the box, the walls' loading ratio, the temperature
  if (st.box.enabled) {
    const double L = StateLimits::kMaxBox * lp.a0;
    const double b[6] = {st.box.x_min, st.box.y_min, st.box.x_max, st.box.y_max, st.box.z_min, st.box.z_max};
    for (int k = 0; k < 2 * D; ++k)
      if (!(std::fabs(b[k]) <= L)) r.error_at(box_line, fmt::format("box coordinates must be within +-{:g} a0 = {:g} m", StateLimits::kMaxBox, L));
    if (!(st.box.x_max > st.box.x_min && st.box.y_max > st.box.y_min))
      r.error_at(box_line, "box must have x_max > x_min and y_max > y_min");
    if (D == 3 && !(st.box.z_max > st.box.z_min)) r.error_at(box_line, "box must have z_max > z_min");
  }
  // 2D: 2p/k2 (p in N/m); 3D: 4 p a0/k2 (p in N/m^2, the force on a particle's (2 a0)^2 of wall)
  for (int k = 0; k < D; ++k) {
    const double ratio = D == 2 ? 2.0 * w[k]->pressure / lp.k2 : 4.0 * w[k]->pressure * lp.a0 / lp.k2;
    if (w[k]->mode == WallMode::Stress && !(ratio <= StateLimits::kMaxLoading))
      r.error_at(wall_line[k], fmt::format("loading ratio {} = {:.3g} is above {} (Luding section 4)",
                                           D == 2 ? "2p/k2" : "4 p a0/k2", ratio, StateLimits::kMaxLoading));
  }
  if (!(st.thermal.T > StateLimits::kAbsoluteZero))
    r.error_at(thermal_line, fmt::format("T = {:g} deg C is not above absolute zero", st.thermal.T));
  if (!(std::fabs(lp.da_T * (st.thermal.T - lp.T_radius_ref)) <= StateLimits::kMaxThermalStrain))
    r.error_at(thermal_line, fmt::format("|da_T (T - T_radius_ref)| = {:.3g} is above {}",
                                         std::fabs(lp.da_T * (st.thermal.T - lp.T_radius_ref)), StateLimits::kMaxThermalStrain));
  if (!(st.thermal.k1_Tt >= 0.0 && st.thermal.k1_Tt <= lp.k1() * (1.0 + 1e-9)))
    r.error_at(thermal_line, "k1_Tt must be in [0, k1]");
  std::size_t n = 0;
  {
    auto ls = r.keyed("particles");
    n = r.num<std::size_t>(ls, "particle count");
    if (n == 0 || n > StateLimits::kMaxParticles) r.error(fmt::format("particle count must be in [1, {}]", StateLimits::kMaxParticles));
  }
  if (r.line().rfind(D == 2 ? "id,x,y," : "id,x,y,z,", 0) != 0) r.error("expected the particle header line");
  Particles& P = st.particles;
  P.dim = D;
  std::vector<std::size_t> pline;
  const double rlo = lp.a0 / StateLimits::kRadiusRange, rhi = lp.a0 * StateLimits::kRadiusRange;
  constexpr double kI = contact::Dim<D>::kInertia;
  for (std::size_t i = 0; i < n; ++i) {
    std::string s = r.line();
    pline.push_back(r.line_no());
    std::replace(s.begin(), s.end(), ',', ' ');
    std::istringstream ls(s);
    const auto id = r.num<std::size_t>(ls, "particle id");
    if (id != i) r.error("particle ids must be 0..N-1 in order");
    // 2D: x y vx vy omega theta | radius radius_ref mass inertia | fx fy torque
    // 3D: x y z vx vy vz wx wy wz | radius radius_ref mass inertia | fx fy fz tx ty tz
    constexpr int kKin = D == 2 ? 6 : 9;
    double v[19];
    for (int k = 0; k < (D == 2 ? 13 : 19); ++k) v[k] = r.real(ls, "particle value");
    const double a = v[kKin], a_ref = v[kKin + 1], m = v[kKin + 2], I = v[kKin + 3];
    if (!(a > 0.0 && a_ref > 0.0 && m > 0.0 && I > 0.0))
      r.error("particle " + std::to_string(i) + ": radius, mass and inertia must be positive");
    if (!(a >= rlo && a <= rhi && a_ref >= rlo && a_ref <= rhi))
      r.error(fmt::format("particle {}: radius and radius_ref must be within [a0 / 100, 100 a0] = [{:g}, {:g}] m", i, rlo, rhi));
    const double m_ref = D == 2 ? contact::luding_mass(lp, a_ref) : lp.rho_p * 4.0 / 3.0 * std::numbers::pi * a_ref * a_ref * a_ref;
    if (!(m >= 1e-3 * m_ref && m <= 1e3 * m_ref && I >= 1e-3 * kI * m * a * a && I <= 1e3 * kI * m * a * a))
      r.error(fmt::format("particle {}: mass and inertia must be within a factor 1000 of {}", i,
                          D == 2 ? "rho_p pi a^2 h and m a^2 / 2" : "rho_p 4/3 pi a^3 and 2/5 m a^2"));
    st.radius_ref.push_back(a_ref);
    P.radius.push_back(a);
    P.mass.push_back(m);
    P.inertia.push_back(I);
    P.x.push_back(v[0]);
    P.y.push_back(v[1]);
    if constexpr (D == 2) {
      P.vx.push_back(v[2]);
      P.vy.push_back(v[3]);
      P.omega.push_back(v[4]);
      P.theta.push_back(v[5]);
      P.fx.push_back(v[10]);
      P.fy.push_back(v[11]);
      P.torque.push_back(v[12]);
    } else {
      P.z.push_back(v[2]);
      P.vx.push_back(v[3]);
      P.vy.push_back(v[4]);
      P.vz.push_back(v[5]);
      P.wx.push_back(v[6]);
      P.wy.push_back(v[7]);
      P.omega.push_back(v[8]);
      P.theta.push_back(0.0);
      P.fx.push_back(v[13]);
      P.fy.push_back(v[14]);
      P.fz.push_back(v[15]);
      P.tx.push_back(v[16]);
      P.ty.push_back(v[17]);
      P.torque.push_back(v[18]);
    }
  }
  // geometry and speeds, with the line of the particle (docs/dynamic.md "State file limits")
  double rmin = P.radius[0];
  for (double a : P.radius) rmin = std::min(rmin, a);
  const double travel = StateLimits::kMaxTravel * rmin, dt = st.dt;
  auto zc = [&](std::size_t i) { return D == 3 ? P.z[i] : 0.0; };
  for (std::size_t i = 0; i < n; ++i) {
    const bool inside = P.x[i] >= st.box.x_min && P.x[i] <= st.box.x_max && P.y[i] >= st.box.y_min &&
                        P.y[i] <= st.box.y_max && (D == 2 || (zc(i) >= st.box.z_min && zc(i) <= st.box.z_max));
    if (st.box.enabled && !inside) {
      if constexpr (D == 2)
        r.error_at(pline[i], fmt::format("particle {}: the centre ({:g}, {:g}) is outside the box", i, P.x[i], P.y[i]));
      else
        r.error_at(pline[i], fmt::format("particle {}: the centre ({:g}, {:g}, {:g}) is outside the box", i, P.x[i],
                                         P.y[i], P.z[i]));
    }
    if (!st.box.enabled && !(std::fabs(P.x[i]) <= StateLimits::kMaxBox * lp.a0 && std::fabs(P.y[i]) <= StateLimits::kMaxBox * lp.a0 &&
                             std::fabs(zc(i)) <= StateLimits::kMaxBox * lp.a0))
      r.error_at(pline[i], fmt::format("particle {}: the centre must be within +-{:g} a0", i, StateLimits::kMaxBox));
    double v = 0.0, f = 0.0;
    if constexpr (D == 2) {
      v = std::hypot(P.vx[i], P.vy[i]) + std::fabs(P.omega[i]) * P.radius[i];
      f = std::hypot(P.fx[i], P.fy[i]);
    } else {
      v = std::sqrt(P.vx[i] * P.vx[i] + P.vy[i] * P.vy[i] + P.vz[i] * P.vz[i]) +
          std::sqrt(P.wx[i] * P.wx[i] + P.wy[i] * P.wy[i] + P.omega[i] * P.omega[i]) * P.radius[i];
      f = std::sqrt(P.fx[i] * P.fx[i] + P.fy[i] * P.fy[i] + P.fz[i] * P.fz[i]);
    }
    if (!(v * dt < travel))
      r.error_at(pline[i], fmt::format("particle {}: speed {:.3g} m/s moves it {:.3g} m per step, not below 0.1 r_min = {:.3g} m",
                                       i, v, v * dt, travel));
    const double dv = 0.5 * dt * f / P.mass[i];
    if (!(dv * dt < travel))
      r.error_at(pline[i], fmt::format("particle {}: force {:.3g} N would move it {:.3g} m in the next step, not below 0.1 r_min",
                                       i, f, dv * dt));
  }
  for (int k = 0; k < D; ++k)
    if (!(std::fabs(S::wall_velocity(st)[k]) * dt < travel && std::fabs(w[k]->velocity) * dt < travel))
      r.error_at(wall_line[k], fmt::format("the wall moves {:.3g} m per step, not below 0.1 r_min = {:.3g} m",
                                           std::max(std::fabs(S::wall_velocity(st)[k]), std::fabs(w[k]->velocity)) * dt, travel));
  {  // pairs closer than the larger radius, on the shared cell grid
    double rmax = 0.0;
    for (double a : P.radius) rmax = std::max(rmax, a);
    auto check = [&](std::size_t i, std::uint32_t j) {
      if (j <= i) return;
      const double dx = P.x[j] - P.x[i], dy = P.y[j] - P.y[i], dz = zc(j) - zc(i);
      const double lim = std::max(P.radius[i], P.radius[j]);
      if (dx * dx + dy * dy + dz * dz < lim * lim)
        r.error_at(pline[j], fmt::format("particles {} (line {}) and {}: centre distance {:.3g} m is below the larger "
                                         "radius {:.3g} m (a duplicate?)",
                                         i, pline[i], j, std::sqrt(dx * dx + dy * dy + dz * dz), lim));
    };
    if constexpr (D == 2) {
      const packing::CellGrid grid(P.x, P.y, rmax);
      for (std::size_t i = 0; i < n; ++i) grid.for_each_near(P.x[i], P.y[i], rmax, [&](std::uint32_t j) { check(i, j); });
    } else {
      const packing::CellGrid3 grid(P.x, P.y, P.z, rmax);
      for (std::size_t i = 0; i < n; ++i)
        grid.for_each_near(P.x[i], P.y[i], P.z[i], rmax, [&](std::uint32_t j) { check(i, j); });
    }
  }
  std::size_t m = 0;
  {
    auto ls = r.keyed("pairs");
    m = r.num<std::size_t>(ls, "pair count");
  }
  for (std::size_t k = 0; k < m; ++k) {
    std::istringstream ls(r.line());
    const auto i = r.num<std::uint64_t>(ls, "pair i"), j = r.num<std::uint64_t>(ls, "pair j");
    if (!(i < j && j < n)) r.error("pair indices must satisfy i < j < N");
    st.pair_key.push_back((i << 32) | j);
    S::pair(st).push_back(get_history<D>(r, ls));
    if (k > 0 && !(st.pair_key[k - 1] < st.pair_key[k])) r.error("pairs must be sorted by (i, j)");
  }
  constexpr std::size_t W = 2 * D;
  S::wall(st).assign(W * n, contact::LudingHistoryT<D>{});
  {
    auto ls = r.keyed("wall_contacts");
    m = r.num<std::size_t>(ls, "wall contact count");
  }
  for (std::size_t k = 0; k < m; ++k) {
    std::istringstream ls(r.line());
    const auto i = r.num<std::size_t>(ls, "particle"), wall = r.num<std::size_t>(ls, "wall");
    if (!(i < n && wall < W)) r.error(D == 2 ? "wall contact needs particle < N and wall in 0..3" : "wall contact needs particle < N and wall in 0..5");
    S::wall(st)[W * i + wall] = get_history<D>(r, ls);
  }
  if (r.line() != "end") r.error("expected 'end' (truncated file?)");
}

}  // namespace

SolverState parse_state(std::istream& in, const std::string& name) {
  Reader r(in, name);
  SolverState st;
  {
    std::string first;
    if (!std::getline(in, first)) r.error_at(1, "empty file");
    r.count_line();
    if (first.rfind("# demsolve state v2", 0) != 0)
      r.error_at(1, "not a demsolve state file v2 (first line '" + quote_input(first.substr(0, 40)) + "')");
  }
  // "dim 3": a sphere state; no dim line: 2D (every file before issue 16)
  const std::string s = r.line();
  std::istringstream ks(s);
  std::string key;
  ks >> key;
  if (key == "dim") {
    const auto d = r.num<int>(ks, "dim");
    if (d != 3) r.error("dim must be 3 (a 2D state file has no dim line)");
    parse_state_body<3>(r, st);
  } else {
    r.unread(s);
    parse_state_body<2>(r, st);
  }
  return st;
}

SolverState read_state(std::istream& in) { return parse_state(in, "state"); }

SolverState read_state_file(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw std::invalid_argument("state file '" + quote_input(path) + "' is a folder");
  std::ifstream in(path);
  if (!in) throw std::invalid_argument("cannot open state file '" + quote_input(path) + "'");
  return parse_state(in, path);
}

}  // namespace netdem::dem

namespace netdem::dem {

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
template <int D, class H, class Eval>
void contacts_of(const Particles& P, const Box& box, const std::vector<std::uint64_t>& keys,
                 const std::vector<H>& hist, const std::vector<H>& whist, std::vector<ContactInfo>& out, Eval&& eval) {
  out.clear();
  auto zc = [&](std::size_t i) { return D == 3 ? P.z[i] : 0.0; };
  auto vzc = [&](std::size_t i) { return D == 3 ? P.vz[i] : 0.0; };
  for (std::size_t k = 0; k < keys.size(); ++k) {
    const auto i = static_cast<std::uint32_t>(keys[k] >> 32);
    const auto j = static_cast<std::uint32_t>(keys[k] & 0xffffffffu);
    const double dx = P.x[j] - P.x[i], dy = P.y[j] - P.y[i], dz = zc(j) - zc(i);
    const double ri = P.radius[i], rj = P.radius[j], s = ri + rj;
    const double L2 = D == 2 ? dx * dx + dy * dy : dx * dx + dy * dy + dz * dz;
    if (!(L2 < s * s)) continue;
    const double L = std::sqrt(L2), nx = dx / L, ny = dy / L, nz = dz / L;
    const double q = (ri * ri - rj * rj) / (2.0 * L);
    contact::Kinematics<D> in;
    in.overlap = in.overlap_start = s - L;
    if constexpr (D == 2)
      in.v_n = -((P.vx[j] - P.vx[i]) * nx + (P.vy[j] - P.vy[i]) * ny);
    else
      in.v_n = -((P.vx[j] - P.vx[i]) * nx + (P.vy[j] - P.vy[i]) * ny + (vzc(j) - vzc(i)) * nz);
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
      const double xa = axis == 0 ? P.x[i] : axis == 1 ? P.y[i] : zc(i);
      const double va = axis == 0 ? P.vx[i] : axis == 1 ? P.vy[i] : vzc(i);
      const double dist = sign * (xa - pos[w]);
      const double delta = P.radius[i] - dist;
      if (!(delta > 0.0)) continue;
      contact::Kinematics<D> in;
      in.overlap = in.overlap_start = delta;
      in.v_n = -(va * sign);
      in.r_eff = P.radius[i];
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
void luding_contacts(const Particles& P, const Box& box, const LudingParams& pp, const LudingParams& pw, double k1Tt,
                     const std::vector<std::uint64_t>& keys, const std::vector<contact::LudingHistoryT<D>>& hist,
                     const std::vector<contact::LudingHistoryT<D>>& whist, std::vector<ContactInfo>& out) {
  contacts_of<D>(P, box, keys, hist, whist, out,
                 [&](const contact::LudingHistoryT<D>& h, const contact::Kinematics<D>& k, bool wall, ContactInfo& c) {
                   contact::LudingInputT<D> in;
                   in.delta = k.overlap;
                   in.delta_dot = k.v_n;
                   in.k1_Tt = k1Tt;
                   const auto r = contact::luding_evaluate<F>(wall ? pw : pp, h, in);
                   c.f_n = r.f_n;
                   set_tangential(c, r.f_t);
                   c.f_min = r.f_min;
                   c.mu = r.mu;
                   return true;
                 });
}
constexpr contact::LudingFeatures kHystereticOut{true, false, false, true};

// The plastic-indentation law: the contacts on their loaded branch.
template <int D>
void plastic_contacts(const Particles& P, const Box& box, const contact::PlasticIndentationParams& pp,
                      const contact::PlasticIndentationParams& pw, const std::vector<std::uint64_t>& keys,
                      const std::vector<contact::PlasticIndentationHistoryT<D>>& hist,
                      const std::vector<contact::PlasticIndentationHistoryT<D>>& whist, std::vector<ContactInfo>& out) {
  const contact::PlasticIndentationLawT<D> lp(pp), lw(pw);
  contacts_of<D>(P, box, keys, hist, whist, out,
                 [&](const contact::PlasticIndentationHistoryT<D>& h, const contact::Kinematics<D>& k, bool wall,
                     ContactInfo& c) {
                   const auto r = (wall ? lw : lp).evaluate(h, k, nullptr);
                   c.f_n = r.f_n;
                   set_tangential(c, r.f_t);
                   c.mu = (wall ? pw : pp).mu_eff();
                   return r.loaded;
                 });
}
}  // namespace

template <int D>
void DynamicSolverT<D>::contacts(std::vector<ContactInfo>& out) const {
  switch (opt_.model) {
    case ContactModel::Linear:
      luding_contacts<contact::kLudingLinear, D>(P_, box_, params_, wall_params_, thermal_.k1_Tt, pair_key_,
                                                 pair_hist_, wall_hist_, out);
      break;
    case ContactModel::Hysteretic:
      luding_contacts<kHystereticOut, D>(P_, box_, params_, wall_params_, thermal_.k1_Tt, pair_key_, pair_hist_,
                                         wall_hist_, out);
      break;
    case ContactModel::Full:
      luding_contacts<contact::kLudingFull, D>(P_, box_, params_, wall_params_, thermal_.k1_Tt, pair_key_,
                                               pair_hist_, wall_hist_, out);
      break;
    case ContactModel::PlasticIndentation:
      plastic_contacts<D>(P_, box_, opt_.plastic, pl_wall_params_, pair_key_, pl_pair_hist_, pl_wall_hist_, out);
      break;
  }
}

// the members defined here, for both dimensions (the class: solver.cpp)
template DynamicSolverT<2>::DynamicSolverT(const SolverState&, const DynamicOptions&);
template SolverState DynamicSolverT<2>::state() const;
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
template void DynamicSolverT<3>::advance_temperature(double, double, double);
template void DynamicSolverT<3>::set_params(const LudingParams&);
template void DynamicSolverT<3>::set_walls(const MovingWall&, const MovingWall&);
template void DynamicSolverT<3>::set_walls(const MovingWall&, const MovingWall&, const MovingWall&);
template void DynamicSolverT<3>::set_gravity(double, double);
template void DynamicSolverT<3>::set_gravity(double, double, double);
template std::size_t DynamicSolverT<3>::wall_contacts() const;
template void DynamicSolverT<3>::contacts(std::vector<ContactInfo>&) const;

}  // namespace netdem::dem
