// The staggered scheme's state file in the state archive (staggered_state.hpp).
#include "staggered_state.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

#include "netdem/field_error.hpp"
#include "netdem/system/archive.hpp"

namespace netdem::qs::staggered {

namespace {

using sys::Field;
using sys::Json;
using sys::real_json;

constexpr int kStaggeredStateVersion = 1;
constexpr double kMax = std::numeric_limits<double>::max();
constexpr std::int64_t kBig = std::int64_t{1} << 52;

// The options and the material: name, member (a double), in file order.
struct OptField {
  const char* name;
  double StaggeredOptions::*d;
};
const OptField kOptReals[] = {{"dt_initial", &StaggeredOptions::dt_initial}, {"dt_max", &StaggeredOptions::dt_max},
                              {"dt_min", &StaggeredOptions::dt_min},         {"alpha", &StaggeredOptions::alpha},
                              {"eps_lim", &StaggeredOptions::eps_lim},       {"grow_below", &StaggeredOptions::grow_below},
                              {"shrink_above", &StaggeredOptions::shrink_above}, {"x0_over_R", &StaggeredOptions::x0_over_R},
                              {"x_max_over_R", &StaggeredOptions::x_max_over_R},
                              {"boundary_factor", &StaggeredOptions::boundary_factor}, {"E", &StaggeredOptions::E},
                              {"nu", &StaggeredOptions::nu}, {"gmres_tolerance", &StaggeredOptions::gmres_tolerance}};
struct MatField {
  const char* name;
  double cs::SinterMaterial::*d;
};
const MatField kMatReals[] = {
    {"omega", &cs::SinterMaterial::omega},           {"gamma_s", &cs::SinterMaterial::gamma_s},
    {"gamma_gb", &cs::SinterMaterial::gamma_gb},     {"D_vol0", &cs::SinterMaterial::D_vol0},
    {"Q_vol", &cs::SinterMaterial::Q_vol},           {"deltaD_gb0", &cs::SinterMaterial::deltaD_gb0},
    {"Q_gb", &cs::SinterMaterial::Q_gb},             {"deltaD_s0", &cs::SinterMaterial::deltaD_s0},
    {"Q_s", &cs::SinterMaterial::Q_s},               {"c_III", &cs::SinterMaterial::c_III},
    {"c_IV", &cs::SinterMaterial::c_IV},             {"youngs_modulus", &cs::SinterMaterial::youngs_modulus},
    {"poisson_ratio", &cs::SinterMaterial::poisson_ratio}, {"T_transus", &cs::SinterMaterial::T_transus},
    {"D_vol0_low", &cs::SinterMaterial::D_vol0_low}, {"Q_vol_low", &cs::SinterMaterial::Q_vol_low},
    {"deltaD_gb0_low", &cs::SinterMaterial::deltaD_gb0_low}, {"Q_gb_low", &cs::SinterMaterial::Q_gb_low},
    {"deltaD_s0_low", &cs::SinterMaterial::deltaD_s0_low},   {"Q_s_low", &cs::SinterMaterial::Q_s_low}};

template <class V>
Json reals(const V& v, const char* what) {
  Json a = Json::array();
  for (double d : v) a.push_back(real_json(d, what));
  return a;
}
int flags6(const std::vector<std::uint8_t>& f, std::size_t i) {
  int b = 0;
  for (int k = 0; k < 6; ++k) b |= (f[6 * i + static_cast<std::size_t>(k)] ? 1 : 0) << k;
  return b;
}
void unflag6(std::vector<std::uint8_t>& f, std::size_t i, std::int64_t b) {
  for (int k = 0; k < 6; ++k) f[6 * i + static_cast<std::size_t>(k)] = static_cast<std::uint8_t>((b >> k) & 1);
}
std::vector<double> reals(const Field& f, std::size_t n, double lo = -kMax, double hi = kMax) {
  f.array(n);
  std::vector<double> v(n);
  for (std::size_t k = 0; k < n; ++k) v[k] = f[k].real(lo, hi);
  return v;
}
Eigen::Vector3d vec3(const Field& f) {
  const auto v = reals(f, 3);
  return {v[0], v[1], v[2]};
}

Json options_json(const StaggeredOptions& q) {
  Json j = Json{{"strategy", q.strategy}, {"new_contacts", q.new_contacts}, {"boundary_planes", q.boundary_planes},
                {"refactor_iterations", q.refactor_iterations}};
  for (const auto& f : kOptReals) j[f.name] = real_json(q.*f.d, f.name);
  // NaN: the planes at the spheres' bounding box (StaggeredOptions::plane_origin)
  j["plane_origin"] = std::isnan(q.plane_origin[0]) ? Json(nullptr) : reals(q.plane_origin, "plane_origin");
  return j;
}

Json contacts_json(const std::vector<Contact>& c) {
  Json j = Json::object();
  for (const char* k : {"a", "b", "frozen", "status", "q", "q0", "t", "h", "steps", "rejected", "rhs_evals", "restarts",
                        "t_created", "L_created", "dL_bar", "x_start"})
    j[k] = Json::array();
  for (const auto& k : c) {
    j["a"].push_back(k.a);
    j["b"].push_back(k.b);
    j["frozen"].push_back(k.frozen);
    j["status"].push_back(static_cast<int>(k.pair.status));
    j["q"].push_back(reals(k.pair.q, "q"));
    j["q0"].push_back(reals(k.pair.q0, "q0"));
    j["t"].push_back(real_json(k.pair.t, "t"));
    j["h"].push_back(real_json(k.pair.h, "h"));
    j["steps"].push_back(k.pair.steps);
    j["rejected"].push_back(k.pair.rejected);
    j["rhs_evals"].push_back(k.pair.rhs_evals);
    j["restarts"].push_back(k.pair.restarts);
    j["t_created"].push_back(real_json(k.t_created, "t_created"));
    j["L_created"].push_back(real_json(k.L_created, "L_created"));
    j["dL_bar"].push_back(real_json(k.dL_bar, "dL_bar"));
    j["x_start"].push_back(real_json(k.x_start, "x_start"));
  }
  return j;
}

}  // namespace

std::string format_staggered_state(const StaggeredState& s) {
  Json j = sys::make_archive("staggered", kStaggeredStateVersion);
  j["options"] = options_json(s.opt);
  Json mat = Json{{"name", s.mat.name}};
  for (const auto& f : kMatReals) mat[f.name] = real_json(s.mat.*f.d, f.name);
  j["material"] = mat;
  j["profile"] = s.profile_t.empty() ? Json{{"constant", real_json(s.profile_constant, "temperature")}}
                                     : Json{{"times", reals(s.profile_t, "time")}, {"temperatures", reals(s.profile_T, "T")}};
  j["clock"] = Json{{"t", real_json(s.t, "t")},       {"dt", real_json(s.dt, "dt")},
                    {"steps", s.nsteps},              {"need_factor", s.need_factor},
                    {"last_iterations", s.last_iterations}, {"rhs_evals", s.rhs_evals}};
  const Timers& T = s.timers;
  j["timers"] = Json{{"detect", real_json(T.detect, "timer")},   {"integrate", real_json(T.integrate, "timer")},
                     {"assemble", real_json(T.assemble, "timer")}, {"factorise", real_json(T.factorise, "timer")},
                     {"solve", real_json(T.solve, "timer")},     {"correct", real_json(T.correct, "timer")}};
  Json pc = Json::object();
  for (const char* k : {"x", "y", "z", "r", "x0", "y0", "z0", "r0", "fixed_user", "fixed_plane"}) pc[k] = Json::array();
  for (std::size_t i = 0; i < s.p.size(); ++i) {
    for (int a = 0; a < 3; ++a) {
      pc[std::string(1, "xyz"[a])].push_back(real_json(s.p.coord(i, a), "x"));
      pc[std::string(1, "xyz"[a]) + "0"].push_back(real_json(s.p0.coord(i, a), "x0"));
    }
    pc["r"].push_back(real_json(s.p.r[i], "r"));
    pc["r0"].push_back(real_json(s.p0.r[i], "r0"));
    pc["fixed_user"].push_back(flags6(s.fixed_user, i));
    pc["fixed_plane"].push_back(flags6(s.fixed_plane, i));
  }
  j["particles"] = pc;
  j["contacts"] = contacts_json(s.c);
  Json fixed = Json::array();
  for (std::size_t i = 0; 6 * i < s.ref_fixed.size(); ++i) fixed.push_back(flags6(s.ref_fixed, i));
  Json el = Json{{"e1", Json::array()}, {"e2", Json::array()}, {"e3", Json::array()},
                 {"lA0", Json::array()}, {"lB0", Json::array()}, {"Rm", Json::array()}};
  for (const auto& e : s.ref) {
    el["e1"].push_back(reals(e.e1, "e1"));
    el["e2"].push_back(reals(e.e2, "e2"));
    el["e3"].push_back(reals(e.e3, "e3"));
    el["lA0"].push_back(real_json(e.lA0, "lA0"));
    el["lB0"].push_back(real_json(e.lB0, "lB0"));
    el["Rm"].push_back(real_json(e.Rm, "Rm"));
  }
  j["factor"] = Json{{"fixed", fixed}, {"elements", el}};
  j["origin"] = Json::parse(s.origin_record);
  return sys::dump_archive(j);
}

namespace {

void read_options(const Field& f, StaggeredOptions& q) {
  f.object({"strategy", "new_contacts", "boundary_planes", "refactor_iterations", "plane_origin", "dt_initial", "dt_max",
            "dt_min", "alpha", "eps_lim", "grow_below", "shrink_above", "x0_over_R", "x_max_over_R", "boundary_factor",
            "E", "nu", "gmres_tolerance"});
  q.strategy = static_cast<int>(f["strategy"].integer(1, 2));
  q.new_contacts = f["new_contacts"].boolean();
  q.boundary_planes = f["boundary_planes"].boolean();
  q.refactor_iterations = static_cast<int>(f["refactor_iterations"].integer(0, 1000000));
  for (const auto& o : kOptReals) q.*o.d = f[o.name].real();
  if (f["plane_origin"].json().is_null()) q.plane_origin.fill(std::numeric_limits<double>::quiet_NaN());
  else {
    const auto v = reals(f["plane_origin"], 3);
    q.plane_origin = {v[0], v[1], v[2]};
  }
  try {
    q.validate();
  } catch (const netdem::FieldError& e) {  // at the member that is wrong (each is in the object)
    f[e.field()].fail(e.what());
  }
}

void read_material(const Field& f, cs::SinterMaterial& m) {
  if (!f.json().is_object()) f.fail("expected an object");
  for (const auto& [key, value] : f.json().items()) {
    bool known = key == "name";
    for (const auto& mf : kMatReals) known = known || key == mf.name;
    if (!known) f[key].fail("unknown member");
  }
  m.name = f["name"].string();
  if (m.name.size() > 200) f["name"].fail("a material name of more than 200 characters");
  for (const auto& mf : kMatReals) m.*mf.d = f[mf.name].real();
  try {
    m.validate();
  } catch (const std::invalid_argument& e) {
    f.fail(e.what());
  }
}

void read_particles(const Field& f, StaggeredState& s) {
  f.object({"x", "y", "z", "r", "x0", "y0", "z0", "r0", "fixed_user", "fixed_plane"});
  const std::size_t n = f["x"].array(1, 100000000);
  for (Particles* q : {&s.p, &s.p0}) {
    q->pos.assign(3 * n, 0.0);
    q->rot.assign(3 * n, 0.0);
    q->r.assign(n, 0.0);
  }
  s.fixed_user.assign(6 * n, 0);
  s.fixed_plane.assign(6 * n, 0);
  for (int a = 0; a < 3; ++a) {
    const std::string k(1, "xyz"[a]);
    const auto v = reals(f[k], n), v0 = reals(f[k + "0"], n);
    for (std::size_t i = 0; i < n; ++i) {
      s.p.pos[3 * i + static_cast<std::size_t>(a)] = v[i];
      s.p0.pos[3 * i + static_cast<std::size_t>(a)] = v0[i];
    }
  }
  const auto r = reals(f["r"], n), r0 = reals(f["r0"], n);
  f["fixed_user"].array(n);
  f["fixed_plane"].array(n);
  for (std::size_t i = 0; i < n; ++i) {
    if (!(r[i] > 0.0)) f["r"][i].fail("a radius must be positive");
    if (!(r0[i] > 0.0)) f["r0"][i].fail("an initial radius must be positive");
    s.p.r[i] = r[i];
    s.p0.r[i] = r0[i];
    unflag6(s.fixed_user, i, f["fixed_user"][i].integer(0, 63));
    unflag6(s.fixed_plane, i, f["fixed_plane"][i].integer(0, 63));
  }
}

void read_contacts(const Field& f, StaggeredState& s) {
  f.object({"a", "b", "frozen", "status", "q", "q0", "t", "h", "steps", "rejected", "rhs_evals", "restarts", "t_created",
            "L_created", "dL_bar", "x_start"});
  const auto n = static_cast<std::int64_t>(s.p.size());
  const std::size_t nc = f["a"].array(0, static_cast<std::size_t>(n) * static_cast<std::size_t>(n));
  for (const char* k : {"b", "frozen", "status", "q", "q0", "t", "h", "steps", "rejected", "rhs_evals", "restarts",
                        "t_created", "L_created", "dL_bar", "x_start"})
    f[k].array(nc);
  s.c.resize(nc);
  for (std::size_t i = 0; i < nc; ++i) {
    Contact& k = s.c[i];
    k.a = static_cast<int>(f["a"][i].integer(0, n - 1));
    k.b = static_cast<int>(f["b"][i].integer(0, n - 1));
    if (k.a == k.b) f["b"][i].fail("a contact needs two particles");
    k.frozen = f["frozen"][i].boolean();
    k.pair.status = static_cast<cs::PairStatus>(f["status"][i].integer(0, 5));
    const auto q = reals(f["q"][i], 5), q0 = reals(f["q0"][i], 5);
    std::copy(q.begin(), q.end(), k.pair.q.begin());
    std::copy(q0.begin(), q0.end(), k.pair.q0.begin());
    k.pair.t = f["t"][i].real();
    k.pair.h = f["h"][i].real(0.0, kMax);
    k.pair.steps = f["steps"][i].integer(0, kBig);
    k.pair.rejected = f["rejected"][i].integer(0, kBig);
    k.pair.rhs_evals = f["rhs_evals"][i].integer(0, kBig);
    k.pair.restarts = f["restarts"][i].integer(0, kBig);
    k.t_created = f["t_created"][i].real();
    {  // the centre distance at creation: about r_a + r_b (the pair touched then); a factor 4 either
       // way is generous and keeps dL_bar / L_created finite
      const double rab = s.p.r[static_cast<std::size_t>(k.a)] + s.p.r[static_cast<std::size_t>(k.b)];
      k.L_created = f["L_created"][i].real(0.25 * rab, 4.0 * rab);
    }
    k.dL_bar = f["dL_bar"][i].real();
    k.x_start = f["x_start"][i].real();
  }
}

void read_factor(const Field& f, StaggeredState& s) {
  f.object({"fixed", "elements"});
  const std::size_t n = s.p.size();
  const std::size_t nf = f["fixed"].array(0, n);
  if (nf != 0 && nf != n) f["fixed"].fail(fmt::format("expected 0 or {} elements, found {}", n, nf));
  s.ref_fixed.assign(6 * nf, 0);
  for (std::size_t i = 0; i < nf; ++i) unflag6(s.ref_fixed, i, f["fixed"][i].integer(0, 63));
  const Field e = f["elements"];
  e.object({"e1", "e2", "e3", "lA0", "lB0", "Rm"});
  const std::size_t ne = e["e1"].array(0, s.c.size());
  for (const char* k : {"e2", "e3", "lA0", "lB0", "Rm"}) e[k].array(ne);
  s.ref.resize(ne);
  for (std::size_t i = 0; i < ne; ++i) {
    s.ref[i].e1 = vec3(e["e1"][i]);
    s.ref[i].e2 = vec3(e["e2"][i]);
    s.ref[i].e3 = vec3(e["e3"][i]);
    s.ref[i].lA0 = e["lA0"][i].real();
    s.ref[i].lB0 = e["lB0"][i].real();
    s.ref[i].Rm = e["Rm"][i].real(0.0, kMax);
  }
}

}  // namespace

StaggeredState parse_staggered_state(std::string_view text, const std::string& origin) {
  const Json j = sys::parse_archive(text, origin);
  const Field r(j, origin);
  sys::check_header(r, "staggered", kStaggeredStateVersion);
  r.object({"format", "kind", "version", "options", "material", "profile", "clock", "timers", "particles", "contacts",
            "factor", "origin"});
  StaggeredState s;
  read_options(r["options"], s.opt);
  read_material(r["material"], s.mat);
  const Field pr = r["profile"];
  if (pr.has("constant")) {
    pr.object({"constant"});
    s.profile_constant = pr["constant"].real(0.0, kMax);
  } else {
    pr.object({"times", "temperatures"});
    const std::size_t np = pr["times"].array(1, 10000000);
    s.profile_t = reals(pr["times"], np);
    s.profile_T = reals(pr["temperatures"], np, 0.0, kMax);
  }
  const Field ck = r["clock"];
  ck.object({"t", "dt", "steps", "need_factor", "last_iterations", "rhs_evals"});
  s.t = ck["t"].real(0.0, kMax);
  s.dt = ck["dt"].real(0.0, kMax);
  // a step of 0 never grows (dt alpha^k = 0): a restart from it hung (campaign of issue 27)
  if (!(s.dt > 0.0)) ck["dt"].fail("must be > 0");
  s.nsteps = ck["steps"].integer(0, kBig);
  s.need_factor = ck["need_factor"].boolean();
  s.last_iterations = static_cast<int>(ck["last_iterations"].integer(0, 1000000000));
  s.rhs_evals = ck["rhs_evals"].integer(0, kBig);
  const Field tm = r["timers"];
  tm.object({"detect", "integrate", "assemble", "factorise", "solve", "correct"});
  s.timers = {tm["detect"].real(0.0, kMax),    tm["integrate"].real(0.0, kMax), tm["assemble"].real(0.0, kMax),
              tm["factorise"].real(0.0, kMax), tm["solve"].real(0.0, kMax),     tm["correct"].real(0.0, kMax)};
  read_particles(r["particles"], s);
  read_contacts(r["contacts"], s);
  read_factor(r["factor"], s);
  const Field og = r["origin"];
  if (!og.json().is_null() && !og.json().is_object()) og.fail("expected an object or null");
  if (og.json().dump().size() > 100000) og.fail("a record of origin of more than 100000 characters");
  s.origin_record = og.json().dump();
  return s;
}

}  // namespace netdem::qs::staggered
