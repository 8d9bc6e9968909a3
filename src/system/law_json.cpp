// The laws' Params and History in the state archive (law_json.hpp).
#include "netdem/system/law_json.hpp"

#include <limits>
#include <stdexcept>

namespace netdem::sys {

namespace {
using contact::LudingParams;
const LudingField kLudingFields[] = {
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
    {"cooling_stiffness_update", nullptr, &LudingParams::cooling_stiffness_update},
    {"wall_sintering", nullptr, &LudingParams::wall_sintering},
};
constexpr double kMax = std::numeric_limits<double>::max();
}  // namespace

std::span<const LudingField> luding_fields() { return kLudingFields; }

}  // namespace netdem::sys

namespace netdem::contact {

using sys::Field;
using sys::Json;
using sys::real_json;

namespace {
// validate() of a Params read whole: its message at the pointer of the object
template <class P>
void validated(const Field& f, const P& p) {
  try {
    p.validate();
  } catch (const std::invalid_argument& e) {
    f.fail(e.what());
  }
}
Json tan_json(double v, const char* what) { return real_json(v, what); }
Json tan_json(const Eigen::Vector3d& v, const char* what) {
  return Json::array({real_json(v.x(), what), real_json(v.y(), what), real_json(v.z(), what)});
}
void read_tan(const Field& f, double& v) { v = f.real(); }
void read_tan(const Field& f, Eigen::Vector3d& v) {
  f.array(3);
  for (int a = 0; a < 3; ++a) v[a] = f[static_cast<std::size_t>(a)].real();
}
}  // namespace

void to_json(Json& j, const LudingParams& p) {
  j = Json::object();
  for (const auto& f : sys::luding_fields()) {
    if (f.d) j[f.name] = real_json(p.*f.d, f.name);
    else j[f.name] = p.*f.b;
  }
}

void from_json(const Json& j, LudingParams& p) {
  const Field f(j);
  if (!j.is_object()) f.fail(std::string("expected an object, found ") + j.type_name());
  p = LudingParams{};
  for (const auto& fl : sys::luding_fields()) {
    if (fl.d) p.*fl.d = f[fl.name].real(-sys::kMax, sys::kMax);
    else p.*fl.b = f[fl.name].boolean();
  }
  for (const auto& [key, value] : j.items()) {
    bool known = false;
    for (const auto& fl : sys::luding_fields()) known = known || key == fl.name;
    if (!known) f[key].fail("unknown member");
  }
  validated(f, p);
}

void to_json(Json& j, const PlasticIndentationParams& p) {
  j = Json{{"sigma_y", real_json(p.sigma_y, "sigma_y")},
           {"mu", real_json(p.mu, "mu")},
           {"k_t", real_json(p.k_t, "k_t")},
           {"unload_ratio", real_json(p.unload_ratio, "unload_ratio")},
           {"reversible", p.reversible},
           {"first_touch", real_json(p.first_touch, "first_touch")},
           {"damping_n", real_json(p.damping_n, "damping_n")},
           {"damping_t", real_json(p.damping_t, "damping_t")}};
}

void from_json(const Json& j, PlasticIndentationParams& p) {
  const Field f(j);
  f.object({"sigma_y", "mu", "k_t", "unload_ratio", "reversible", "first_touch", "damping_n", "damping_t"});
  p.sigma_y = f["sigma_y"].real();
  p.mu = f["mu"].extended_real(0.0, std::numeric_limits<double>::infinity());  // inf: sticking
  p.k_t = f["k_t"].real();
  p.unload_ratio = f["unload_ratio"].real();
  p.reversible = f["reversible"].boolean();
  p.first_touch = f["first_touch"].real();
  p.damping_n = f["damping_n"].real();
  p.damping_t = f["damping_t"].real();
  validated(f, p);
}

namespace {
template <int D>
void luding_history_to(Json& j, const LudingHistoryT<D>& h) {
  j = Json{{"delta_max", real_json(h.delta_max, "delta_max")},
           {"delta0", real_json(h.delta0, "delta0")},
           {"k2_line", real_json(h.k2_line, "k2_line")},
           {"k1_seen", real_json(h.k1_seen, "k1_seen")},
           {"xi", tan_json(h.xi, "xi")},
           {"fluid", h.fluid != 0},
           {"sliding", h.sliding != 0}};
}
template <int D>
void luding_history_from(const Json& j, LudingHistoryT<D>& h) {
  const Field f(j);
  f.object({"delta_max", "delta0", "k2_line", "k1_seen", "xi", "fluid", "sliding"});
  h.delta_max = f["delta_max"].real();
  h.delta0 = f["delta0"].real();
  h.k2_line = f["k2_line"].real();
  h.k1_seen = f["k1_seen"].real();
  read_tan(f["xi"], h.xi);
  h.fluid = f["fluid"].boolean() ? 1 : 0;
  h.sliding = f["sliding"].boolean() ? 1 : 0;
}
template <int D>
void plastic_history_to(Json& j, const PlasticIndentationHistoryT<D>& h) {
  j = Json{{"u_max", real_json(h.u_max, "u_max")}, {"f_t", tan_json(h.f_t, "f_t")}, {"sliding", h.sliding != 0}};
}
template <int D>
void plastic_history_from(const Json& j, PlasticIndentationHistoryT<D>& h) {
  const Field f(j);
  f.object({"u_max", "f_t", "sliding"});
  h.u_max = f["u_max"].real(0.0, sys::kMax);
  read_tan(f["f_t"], h.f_t);
  h.sliding = f["sliding"].boolean() ? 1 : 0;
}
}  // namespace

void to_json(Json& j, const LudingHistoryT<2>& h) { luding_history_to(j, h); }
void from_json(const Json& j, LudingHistoryT<2>& h) { luding_history_from(j, h); }
void to_json(Json& j, const LudingHistoryT<3>& h) { luding_history_to(j, h); }
void from_json(const Json& j, LudingHistoryT<3>& h) { luding_history_from(j, h); }
void to_json(Json& j, const PlasticIndentationHistoryT<2>& h) { plastic_history_to(j, h); }
void from_json(const Json& j, PlasticIndentationHistoryT<2>& h) { plastic_history_from(j, h); }
void to_json(Json& j, const PlasticIndentationHistoryT<3>& h) { plastic_history_to(j, h); }
void from_json(const Json& j, PlasticIndentationHistoryT<3>& h) { plastic_history_from(j, h); }

}  // namespace netdem::contact
