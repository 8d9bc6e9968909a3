// The demsolve state file in the state archive (state.hpp, docs/dynamic.md "State files"): the
// writer, and the reader that checks every field at the door (the ranges of StateLimits).
#include "netdem/dynamic/state.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>

#include <fmt/format.h>

#include "netdem/packing/cell_grid.hpp"
#include "netdem/packing/io.hpp"
#include "netdem/system/archive.hpp"
#include "netdem/system/law_json.hpp"
#include "state_of.hpp"

namespace netdem::dem {

using sys::Field;
using sys::Json;
using sys::real_json;

std::string quote_input(const std::string& s) { return packing::quote_input(s, 80); }

std::vector<std::string> luding_param_names() {
  std::vector<std::string> v;
  for (const auto& f : sys::luding_fields()) v.emplace_back(f.name);
  return v;
}

void set_luding_param(LudingParams& p, const std::string& name, double value) {
  for (const auto& f : sys::luding_fields())
    if (name == f.name) {
      if (!std::isfinite(value)) throw std::invalid_argument("parameter " + name + " must be a finite number");
      if (f.d) p.*f.d = value;
      else p.*f.b = value != 0.0;
      return;
    }
  throw std::invalid_argument("unknown contact parameter '" + quote_input(name) + "'");
}

double get_luding_param(const LudingParams& p, const std::string& name) {
  for (const auto& f : sys::luding_fields())
    if (name == f.name) return f.d ? p.*f.d : (p.*f.b ? 1.0 : 0.0);
  throw std::invalid_argument("unknown contact parameter '" + quote_input(name) + "'");
}

namespace {

constexpr const char* kWallModes[] = {"fixed", "strain", "stress", "affine"};

// The particle columns of dimension D: name, and the array of ParticlesT<D> (or radius_ref) with
// the column's component: entry `comp` of every `stride` (a vector quantity has D per particle).
template <int D>
struct Column {
  const char* name;
  std::vector<double> ParticlesT<D>::*member;  ///< nullptr: radius_ref
  std::size_t stride = 1, comp = 0;
};
template <int D>
std::span<const Column<D>> columns() {
  using P = ParticlesT<2>;
  static const Column<2> c2[] = {{"x", &P::pos, 2, 0},    {"y", &P::pos, 2, 1},      {"vx", &P::vel, 2, 0},
                                 {"vy", &P::vel, 2, 1},   {"omega", &P::spin},       {"theta", &P::rot},
                                 {"radius", &P::r},       {"radius_ref", nullptr},   {"mass", &P::mass},
                                 {"inertia", &P::inertia}, {"fx", &P::force, 2, 0},  {"fy", &P::force, 2, 1},
                                 {"torque", &P::torque}};
  using Q = ParticlesT<3>;
  static const Column<3> c3[] = {{"x", &Q::pos, 3, 0},     {"y", &Q::pos, 3, 1},     {"z", &Q::pos, 3, 2},
                                 {"vx", &Q::vel, 3, 0},    {"vy", &Q::vel, 3, 1},    {"vz", &Q::vel, 3, 2},
                                 {"wx", &Q::spin, 3, 0},   {"wy", &Q::spin, 3, 1},   {"wz", &Q::spin, 3, 2},
                                 {"radius", &Q::r},        {"radius_ref", nullptr},  {"mass", &Q::mass},
                                 {"inertia", &Q::inertia}, {"fx", &Q::force, 3, 0},  {"fy", &Q::force, 3, 1},
                                 {"fz", &Q::force, 3, 2},  {"tx", &Q::torque, 3, 0}, {"ty", &Q::torque, 3, 1},
                                 {"tz", &Q::torque, 3, 2}};
  if constexpr (D == 2) return c2;
  else return c3;
}
template <int D>
std::vector<double>& column(ParticlesT<D>& P, std::vector<double>& radius_ref, const Column<D>& c) {
  return c.member ? P.*c.member : radius_ref;
}
template <int D>
const std::vector<double>& column(const ParticlesT<D>& P, const std::vector<double>& radius_ref, const Column<D>& c) {
  return c.member ? P.*c.member : radius_ref;
}

Json reals(const double* v, std::size_t n, const char* what) {
  Json a = Json::array();
  for (std::size_t k = 0; k < n; ++k) a.push_back(real_json(v[k], what));
  return a;
}

template <class H>
bool live(const H& h) {
  if constexpr (requires { h.u_max; }) return h.u_max != 0.0 || !contact::tan_is_zero(h.f_t) || h.sliding != 0;
  else return !h.fresh();
}

// The wall contacts with a live history: {"particle": [...], "wall": [...], "history": [...]}.
template <int D, class H>
Json wall_contacts_json(const std::vector<H>& wh) {
  Json p = Json::array(), w = Json::array(), h = Json::array();
  constexpr std::size_t W = 2 * D;
  for (std::size_t k = 0; k < wh.size(); ++k) {
    if (!live(wh[k])) continue;
    p.push_back(k / W);
    w.push_back(k % W);
    h.push_back(wh[k]);
  }
  return Json{{"particle", p}, {"wall", w}, {"history", h}};
}

template <int D, class H>
Json pairs_json(const SolverState& st, const std::vector<H>& hist) {
  Json i = Json::array(), j = Json::array(), h = Json::array();
  for (std::size_t k = 0; k < st.pair_key.size(); ++k) {
    i.push_back(st.pair_key[k] >> 32);
    j.push_back(st.pair_key[k] & 0xffffffffu);
    h.push_back(hist[k]);
  }
  return Json{{"i", i}, {"j", j}, {"history", h}};
}

template <int D>
Json state_json(const SolverState& st) {
  using S = StateOf<D>;
  Json j = sys::make_archive("dem", kDemStateVersion);
  j["dim"] = D;
  j["time"] = real_json(st.time, "time");
  j["dt"] = real_json(st.dt, "dt");
  const Box& b = st.box;
  const double lo[3] = {b.x_min, b.y_min, b.z_min}, hi[3] = {b.x_max, b.y_max, b.z_max};
  j["box"] = Json{{"enabled", b.enabled}, {"contact_walls", b.contact_walls},
                  {"min", reals(lo, D, "box")}, {"max", reals(hi, D, "box")}};
  const MovingWall* w[3] = {&b.right, D == 3 ? &b.back : &b.top, &b.top};
  Json walls = Json::array();
  for (int k = 0; k < D; ++k)
    walls.push_back(Json{{"mode", kWallModes[static_cast<int>(w[k]->mode)]},
                         {"velocity", real_json(w[k]->velocity, "wall velocity")},
                         {"pressure", real_json(w[k]->pressure, "wall pressure")},
                         {"mass", real_json(w[k]->mass, "wall mass")},
                         {"damping", real_json(w[k]->damping, "wall damping")},
                         {"current_velocity", real_json(S::wall_velocity(st)[k], "wall velocity")}});
  j["moving_walls"] = walls;
  j["wall_force"] = reals(S::wall_force(st), 2 * D, "wall force");
  j["stress_sum"] = reals(D == 2 ? st.stress_sum : st.stress_sum3, D * D, "stress sum");
  j["elastic"] = real_json(st.elastic, "elastic energy");
  j["thermal"] = Json{{"T", real_json(st.thermal.T, "T")}, {"k1_Tt", real_json(st.thermal.k1_Tt, "k1_Tt")}};
  j["luding"] = st.params;
  if (st.plastic_law()) {
    j["plastic_indentation"] = st.plastic;
    j["plastic_wall_mu"] = real_json(st.plastic_wall_mu, "plastic_wall_mu");
    j["plastic_area_max"] = real_json(st.plastic_area_max, "plastic_area_max");
  }
  Json cols = Json::object();
  for (const Column<D>& c : columns<D>()) {
    const auto& v = column(st.particles_of<D>(), st.radius_ref, c);
    Json a = Json::array();
    for (std::size_t k = c.comp; k < v.size(); k += c.stride) a.push_back(real_json(v[k], c.name));
    cols[c.name] = a;
  }
  j["particles"] = cols;
  // the state's law by its name, and its histories through their JSON (law_json.hpp)
  std::visit([&](const auto& h) {
    using H = typename std::decay_t<decltype(h)>::History;
    if constexpr (HistoryDim<H>::value == D) {
      j["law"] = sys::LawName<H>::value;
      j["pairs"] = pairs_json<D>(st, h.pair);
      j["wall_contacts"] = wall_contacts_json<D>(h.wall);
    }
  }, st.histories);
  return j;
}

}  // namespace

std::string format_state(const SolverState& st) {
  if (st.periodic)
    throw std::invalid_argument("state: a state in a periodic cell has no state file yet (the cell and the pairs' images "
                                "are not in the format)");
  if (st.histories_dim() != st.dim())
    throw std::invalid_argument(fmt::format("state: the histories are {}D, the particles {}D", st.histories_dim(), st.dim()));
  return sys::dump_archive(st.dim() == 3 ? state_json<3>(st) : state_json<2>(st));
}

// ---- reader ------------------------------------------------------------------------------------
namespace {

// The length scale of the limits: a0 (Luding), the mean radius_ref (another law).
double length_scale(const SolverState& st, bool luding) {
  if (luding) return st.params.a0;
  double s = 0.0;
  for (double a : st.radius_ref) s += a;
  return s / static_cast<double>(st.radius_ref.size());
}

// The state's law by its name ("law", sys::LawName): the alternative of SolverState::histories of
// that law and dimension D (empty).
template <int D>
void choose_law(const Field& f, SolverState& st) {
  std::vector<std::string_view> names;
  DemLaws::for_each<D>([&](auto h) { names.push_back(sys::LawName<typename decltype(h)::type>::value); });
  const std::size_t k = f.choice(names);
  std::size_t i = 0;
  DemLaws::for_each<D>([&](auto h) {
    if (i++ == k) st.histories.emplace<LawHistories<typename decltype(h)::type>>();
  });
}

// time, dt, box, moving walls, wall forces, stress sum, thermal state, the laws' parameters
template <int D>
void read_globals(const Field& r, SolverState& st) {
  using S = StateOf<D>;
  st.time = r["time"].real(0.0, StateLimits::kMaxTime);
  st.dt = r["dt"].real(0.0, StateLimits::kMaxDt);
  if (!(st.dt > 0.0)) r["dt"].fail(fmt::format("dt must be in (0, {:g}] s", StateLimits::kMaxDt));
  const Field b = r["box"];
  b.object({"enabled", "contact_walls", "min", "max"});
  st.box.enabled = b["enabled"].boolean();
  st.box.contact_walls = b["contact_walls"].boolean();
  b["min"].array(D);
  b["max"].array(D);
  double* lo[3] = {&st.box.x_min, &st.box.y_min, &st.box.z_min};
  double* hi[3] = {&st.box.x_max, &st.box.y_max, &st.box.z_max};
  for (std::size_t a = 0; a < D; ++a) {
    *lo[a] = b["min"][a].real();
    *hi[a] = b["max"][a].real();
  }
  if (D == 2) st.box.z_min = st.box.z_max = 0.0;
  const Field mw = r["moving_walls"];
  mw.array(D);
  MovingWall* w[3] = {&st.box.right, D == 3 ? &st.box.back : &st.box.top, &st.box.top};
  for (std::size_t k = 0; k < D; ++k) {
    const Field f = mw[k];
    f.object({"mode", "velocity", "pressure", "mass", "damping", "current_velocity"});
    w[k]->mode = static_cast<WallMode>(f["mode"].choice({"fixed", "strain", "stress", "affine"}));
    w[k]->velocity = f["velocity"].real();
    w[k]->pressure = f["pressure"].real();
    w[k]->mass = f["mass"].real();
    w[k]->damping = f["damping"].real();
    S::wall_velocity(st)[k] = f["current_velocity"].real();
    if (w[k]->mode == WallMode::Stress && !(w[k]->mass > 0.0 && w[k]->damping >= 0.0 && w[k]->pressure >= 0.0))
      f.fail("a stress-controlled wall needs mass > 0, damping >= 0 and pressure >= 0");
  }
  r["wall_force"].array(2 * D);
  for (std::size_t k = 0; k < 2 * D; ++k) S::wall_force(st)[k] = r["wall_force"][k].real();
  r["stress_sum"].array(D * D);
  for (std::size_t k = 0; k < D * D; ++k) (D == 2 ? st.stress_sum : st.stress_sum3)[k] = r["stress_sum"][k].real();
  st.elastic = r["elastic"].real();
  const Field th = r["thermal"];
  th.object({"T", "k1_Tt"});
  st.thermal.T = th["T"].real();
  st.thermal.k1_Tt = th["k1_Tt"].real();
  st.params = r["luding"].get<LudingParams>();
  choose_law<D>(r["law"], st);
  if (st.plastic_law()) {
    st.plastic = r["plastic_indentation"].get<contact::PlasticIndentationParams>();
    st.plastic_wall_mu = r["plastic_wall_mu"].extended_real(0.0, HUGE_VAL);
    st.plastic_area_max = r["plastic_area_max"].real(0.0, std::numeric_limits<double>::max());
  } else if (r.has("plastic_indentation") || r.has("plastic_wall_mu") || r.has("plastic_area_max")) {
    r["plastic_indentation"].fail("a state of the Luding law has no plastic-indentation parameters");
  }
}

// What needs the parameters: the box, the walls' loading ratio (Luding), the temperature.
template <int D>
void check_globals(const Field& r, const SolverState& st, bool luding) {
  const LudingParams& lp = st.params;
  if (st.box.enabled) {
    if (!(st.box.x_max > st.box.x_min && st.box.y_max > st.box.y_min))
      r["box"].fail("box must have x_max > x_min and y_max > y_min");
    if (D == 3 && !(st.box.z_max > st.box.z_min)) r["box"].fail("box must have z_max > z_min");
  }
  // 2D: 2p/k2 (p in N/m); 3D: 4 p a0/k2 (p in N/m^2, the force on a particle's (2 a0)^2 of wall)
  const MovingWall* w[3] = {&st.box.right, D == 3 ? &st.box.back : &st.box.top, &st.box.top};
  for (std::size_t k = 0; k < D; ++k) {
    const double ratio = D == 2 ? 2.0 * w[k]->pressure / lp.k2 : 4.0 * w[k]->pressure * lp.a0 / lp.k2;
    if (luding && w[k]->mode == WallMode::Stress && !(ratio <= StateLimits::kMaxLoading))
      r["moving_walls"][k]["pressure"].fail(fmt::format("loading ratio {} = {:.3g} is above {} (Luding section 4)",
                                                        D == 2 ? "2p/k2" : "4 p a0/k2", ratio, StateLimits::kMaxLoading));
    // a pressure that cannot hold the sample, and the stresses over p overflow (4.9e-324: inf in timeseries.csv)
    if (luding && w[k]->mode == WallMode::Stress && !(ratio >= StateLimits::kMinLoading))
      r["moving_walls"][k]["pressure"].fail(fmt::format("pressure {:g} gives the loading ratio {} = {:.3g}, below {}: the "
                                                        "wall would not hold the sample", w[k]->pressure,
                                                        D == 2 ? "2p/k2" : "4 p a0/k2", ratio, StateLimits::kMinLoading));
  }
  const Field th = r["thermal"];
  if (!(st.thermal.T > StateLimits::kAbsoluteZero))
    th["T"].fail(fmt::format("T = {:g} deg C is not above absolute zero", st.thermal.T));
  const double strain = std::fabs(lp.da_T * (st.thermal.T - lp.T_radius_ref));
  if (!(strain <= StateLimits::kMaxThermalStrain))
    th["T"].fail(fmt::format("|da_T (T - T_radius_ref)| = {:.3g} is above {}", strain, StateLimits::kMaxThermalStrain));
  if (!(st.thermal.k1_Tt >= 0.0 && st.thermal.k1_Tt <= lp.k1() * (1.0 + 1e-9)))
    th["k1_Tt"].fail("k1_Tt must be in [0, k1]");
}

// The particle columns, with the ranges of radius, mass and inertia.
template <int D>
void read_particles(const Field& r, SolverState& st, bool luding) {
  const Field pc = r["particles"];
  std::vector<std::string_view> names;
  for (const Column<D>& c : columns<D>()) names.push_back(c.name);
  if (!pc.json().is_object()) pc.fail(fmt::format("expected an object, found {}", pc.json().type_name()));
  for (const auto& [key, value] : pc.json().items())
    if (std::find(names.begin(), names.end(), key) == names.end()) pc[key].fail("unknown member");
  const std::size_t n = pc["x"].array(1, StateLimits::kMaxParticles);
  ParticlesT<D>& P = st.particles.emplace<ParticlesT<D>>();
  for (const Column<D>& c : columns<D>()) {
    const Field f = pc[c.name];
    f.array(n);
    auto& v = column(P, st.radius_ref, c);
    v.resize(c.stride * n);
    for (std::size_t i = 0; i < n; ++i) v[c.stride * i + c.comp] = f[i].real();
  }
  if constexpr (D == 3) P.rot.assign(ParticlesT<D>::kRot * n, 0.0);  // (the orientation is not tracked)
  const double L = length_scale(st, luding);
  const double rlo = L / StateLimits::kRadiusRange, rhi = L * StateLimits::kRadiusRange;
  constexpr double kI = contact::Dim<D>::kInertia;
  auto volume = [](double a) { return D == 2 ? std::numbers::pi * a * a : 4.0 / 3.0 * std::numbers::pi * a * a * a; };
  double rho = 0.0;  // a law other than Luding's: the mean density of the state
  if (!luding)
    for (std::size_t i = 0; i < n; ++i) rho += P.mass[i] / volume(st.radius_ref[i]) / static_cast<double>(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double a = P.r[i], a_ref = st.radius_ref[i], m = P.mass[i], I = P.inertia[i];
    if (!(a >= rlo && a <= rhi)) pc["radius"][i].fail(fmt::format("radius must be within [L / 100, 100 L] = [{:g}, {:g}]", rlo, rhi));
    if (!(a_ref >= rlo && a_ref <= rhi))
      pc["radius_ref"][i].fail(fmt::format("radius_ref must be within [L / 100, 100 L] = [{:g}, {:g}]", rlo, rhi));
    const LudingParams& lp = st.params;
    const double m_ref = !luding ? rho * volume(a_ref)
                         : D == 2         ? contact::luding_mass(lp, a_ref)
                                          : lp.rho_p * volume(a_ref);
    if (!(m >= 1e-3 * m_ref && m <= 1e3 * m_ref))
      pc["mass"][i].fail(fmt::format("mass must be within a factor 1000 of {}",
                                     !luding ? "the state's mean density times the volume"
                                     : D == 2         ? "rho_p pi a^2 h"
                                                      : "rho_p 4/3 pi a^3"));
    if (!(I >= 1e-3 * kI * m * a * a && I <= 1e3 * kI * m * a * a))
      pc["inertia"][i].fail(fmt::format("inertia must be within a factor 1000 of {}", D == 2 ? "m a^2 / 2" : "2/5 m a^2"));
  }
}

// Geometry and speeds (docs/dynamic.md "State file limits"), then pairs closer than the larger radius.
template <int D>
void check_particles(const Field& r, const SolverState& st, bool luding) {
  using S = StateOf<D>;
  const ParticlesT<D>& P = st.particles_of<D>();
  const Field pc = r["particles"];
  const std::size_t n = P.size();
  const double L = length_scale(st, luding);
  if (st.box.enabled) {
    const double b[6] = {st.box.x_min, st.box.y_min, st.box.z_min, st.box.x_max, st.box.y_max, st.box.z_max};
    for (int k = 0; k < 6; ++k)
      if ((D == 3 || k % 3 != 2) && !(std::fabs(b[k]) <= StateLimits::kMaxBox * L))
        r["box"].fail(fmt::format("box coordinates must be within +-{:g} L = {:g}", StateLimits::kMaxBox,
                                  StateLimits::kMaxBox * L));
  }
  double rmin = P.r[0], rmax = 0.0;
  for (double a : P.r) rmin = std::min(rmin, a), rmax = std::max(rmax, a);
  const double travel = StateLimits::kMaxTravel * rmin, dt = st.dt;
  auto xc = [&](std::size_t i, int a) { return a < D ? P.pos[D * i + static_cast<std::size_t>(a)] : 0.0; };
  for (std::size_t i = 0; i < n; ++i) {
    const double x = xc(i, 0), y = xc(i, 1), z = xc(i, 2);
    const bool inside = x >= st.box.x_min && x <= st.box.x_max && y >= st.box.y_min && y <= st.box.y_max &&
                        (D == 2 || (z >= st.box.z_min && z <= st.box.z_max));
    if (st.box.enabled && st.box.contact_walls && !inside)
      pc["x"][i].fail(fmt::format("particle {}: the centre ({:g}, {:g}, {:g}) is outside the box", i, x, y, z));
    const double far = StateLimits::kMaxBox * L;
    if (!(std::fabs(x) <= far && std::fabs(y) <= far && std::fabs(z) <= far))
      pc["x"][i].fail(fmt::format("particle {}: the centre must be within +-{:g} L", i, StateLimits::kMaxBox));
    double v = 0.0, f = 0.0, tq = 0.0;
    const double* const u = &P.vel[D * i];
    const double* const fi = &P.force[D * i];
    if constexpr (D == 2) {
      v = std::hypot(u[0], u[1]) + std::fabs(P.spin[i]) * P.r[i];
      f = std::hypot(fi[0], fi[1]);
      tq = std::fabs(P.torque[i]);
    } else {
      const double* const w = &P.spin[3 * i];
      const double* const t = &P.torque[3 * i];
      v = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]) + std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]) * P.r[i];
      f = std::sqrt(fi[0] * fi[0] + fi[1] * fi[1] + fi[2] * fi[2]);
      tq = std::sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
    }
    // the torque, as the force: its half kick must not turn the surface by 0.1 r_min in a step (a torque of
    // 1e300 passed before and wrote inf into vibrate's timeseries.csv: campaign of issue 27)
    const double dw = 0.5 * dt * tq / P.inertia[i];
    if (!(dw * dt * P.r[i] < travel))
      pc[D == 2 ? "torque" : "tx"][i].fail(fmt::format(
          "particle {}: torque {:.3g} would turn its surface {:.3g} in the next step, not below 0.1 r_min", i, tq,
          dw * dt * P.r[i]));
    if (!(v * dt < travel))
      pc["vx"][i].fail(fmt::format("particle {}: speed {:.3g} moves it {:.3g} per step, not below 0.1 r_min = {:.3g}",
                                   i, v, v * dt, travel));
    const double dv = 0.5 * dt * f / P.mass[i];
    if (!(dv * dt < travel))
      pc["fx"][i].fail(fmt::format("particle {}: force {:.3g} would move it {:.3g} in the next step, not below 0.1 r_min",
                                   i, f, dv * dt));
  }
  const MovingWall* w[3] = {&st.box.right, D == 3 ? &st.box.back : &st.box.top, &st.box.top};
  for (std::size_t k = 0; k < D; ++k) {
    const double s = std::max(std::fabs(S::wall_velocity(st)[k]), std::fabs(w[k]->velocity));
    if (!(s * dt < travel))
      r["moving_walls"][k].fail(fmt::format("the wall moves {:.3g} per step, not below 0.1 r_min = {:.3g}", s * dt, travel));
  }
  auto check = [&](std::size_t i, std::uint32_t j) {
    if (j <= i) return;
    const double dx = xc(j, 0) - xc(i, 0), dy = xc(j, 1) - xc(i, 1), dz = xc(j, 2) - xc(i, 2);
    const double lim = std::max(P.r[i], P.r[j]);
    if (dx * dx + dy * dy + dz * dz < lim * lim)
      pc["x"][j].fail(fmt::format("particles {} and {}: centre distance {:.3g} is below the larger radius {:.3g} "
                                  "(a duplicate?)", i, j, std::sqrt(dx * dx + dy * dy + dz * dz), lim));
  };
  std::array<std::vector<double>, D> axes;
  typename packing::CellGridT<D>::Axes spans;
  for (int a = 0; a < D; ++a) {
    axes[a] = P.axis(a);
    spans[a] = axes[a];
  }
  const packing::CellGridT<D> grid(spans, rmax);
  for (std::size_t i = 0; i < n; ++i) {
    typename packing::CellGridT<D>::Point at;
    for (int a = 0; a < D; ++a) at[a] = xc(i, a);
    grid.for_each_near(at, rmax, [&](std::uint32_t j) { check(i, j); });
  }
}

// A Luding history's force-free overlap delta_0 against the contact's geometry: the law keeps it in
// [0, max(the largest overlap, delta_fluid)], and an overlap is below r_i + r_j (a wall contact: 2 r_i).
// Unchecked, delta_0 = 1e300 gave f_min = -k_c delta_0 / (1 + c) = -inf in contacts_*.csv.
// i, j: the pair's particles (j < 0: particle i on a wall).
template <class H>
void check_history(const Field& h, const H& v, double reach, double delta_fluid, std::uint64_t i, std::int64_t j) {
  if constexpr (requires { v.delta0; }) {
    const double bound = std::max(reach, delta_fluid);
    if (!(v.delta0 >= 0.0 && v.delta0 <= bound))
      h["delta0"].fail(fmt::format("the force-free overlap {:.6g} m is outside [0, {:.6g} m], the largest overlap of {} "
                                   "(the radii sum) or the fluid limit", v.delta0, bound,
                                   j < 0 ? fmt::format("particle {} on a wall", i) : fmt::format("particles {} and {}", i, j)));
  }
}

// The pair table (sorted i < j < N) and the wall contacts (particle < N, wall < 2D, sorted), with
// the histories of the state's law.
template <int D, class H>
void read_contacts(const Field& r, SolverState& st, std::vector<H>& pair, std::vector<H>& wall) {
  const std::vector<double>& radius = st.particles_of<D>().r;
  const std::size_t n = radius.size();
  const Field pr = r["pairs"];
  pr.object({"i", "j", "history"});
  const std::size_t m = pr["i"].array(0, n * (n - 1) / 2);
  pr["j"].array(m);
  pr["history"].array(m);
  for (std::size_t k = 0; k < m; ++k) {
    const auto i = static_cast<std::uint64_t>(pr["i"][k].integer(0, static_cast<std::int64_t>(n) - 1));
    const auto j = static_cast<std::uint64_t>(pr["j"][k].integer(0, static_cast<std::int64_t>(n) - 1));
    if (!(i < j)) pr["j"][k].fail("pair indices must satisfy i < j < N");
    st.pair_key.push_back((i << 32) | j);
    if (k > 0 && !(st.pair_key[k - 1] < st.pair_key[k])) pr["i"][k].fail("pairs must be sorted by (i, j)");
    pair.push_back(pr["history"][k].get<H>());
    check_history(pr["history"][k], pair.back(), radius[i] + radius[j],
                  st.params.delta_fluid(), i, static_cast<std::int64_t>(j));
  }
  constexpr std::size_t W = 2 * D;
  wall.assign(W * n, H{});
  const Field wc = r["wall_contacts"];
  wc.object({"particle", "wall", "history"});
  const std::size_t mw = wc["particle"].array(0, W * n);
  wc["wall"].array(mw);
  wc["history"].array(mw);
  std::size_t last = 0;
  for (std::size_t k = 0; k < mw; ++k) {
    const auto i = static_cast<std::size_t>(wc["particle"][k].integer(0, static_cast<std::int64_t>(n) - 1));
    const auto w = static_cast<std::size_t>(wc["wall"][k].integer(0, static_cast<std::int64_t>(W) - 1));
    if (k > 0 && !(W * i + w > last)) wc["particle"][k].fail("wall contacts must be sorted by (particle, wall)");
    last = W * i + w;
    wall[last] = wc["history"][k].get<H>();
    check_history(wc["history"][k], wall[last], 2.0 * radius[i], st.params.delta_fluid(), i, -1);
  }
}

template <int D>
SolverState read_body(const Field& r) {
  r.object({"format", "kind", "version", "dim", "time", "dt", "box", "moving_walls", "wall_force", "stress_sum",
            "elastic", "thermal", "luding", "law", "plastic_indentation", "plastic_wall_mu", "plastic_area_max",
            "particles", "pairs",
            "wall_contacts"});
  SolverState st;
  read_globals<D>(r, st);
  // the limits of the Luding law's material (LMM05's units and loading), else the state's own scales
  const bool luding = st.holds<contact::LudingHistoryT<D>>();
  check_globals<D>(r, st, luding);
  read_particles<D>(r, st, luding);
  check_particles<D>(r, st, luding);
  std::visit([&](auto& h) {
    if constexpr (std::decay_t<decltype(h)>::kDim == D) read_contacts<D>(r, st, h.pair, h.wall);
  }, st.histories);
  return st;
}

}  // namespace

SolverState parse_state(std::string_view text, const std::string& name) {
  const Json j = sys::parse_archive(text, name);
  const Field root(j, name);
  sys::check_header(root, "dem", kDemStateVersion);
  const auto dim = root["dim"].integer(2, 3);
  return dim == 3 ? read_body<3>(root) : read_body<2>(root);
}

SolverState parse_state(std::istream& in, const std::string& name) {
  std::ostringstream s;
  s << in.rdbuf();
  return parse_state(s.str(), name);
}

SolverState read_state(std::istream& in) { return parse_state(in, "state"); }

SolverState read_state_file(const std::string& path) { return parse_state(sys::read_text_file(path, "state file"), path); }

}  // namespace netdem::dem
