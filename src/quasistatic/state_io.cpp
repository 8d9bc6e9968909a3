// The network-solver state file in the state archive of netdem_system (kind "network", version 1;
// docs/quasistatic.md "State file"): every double exact, every field checked at the door with a
// one-line std::invalid_argument "FILE: /json/pointer: problem".
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "netdem/quasistatic/network_solver.hpp"
#include "netdem/system/archive.hpp"
#include "netdem/system/law_json.hpp"

namespace netdem::qs {

namespace {

using sys::Field;
using sys::Json;
using sys::real_json;

constexpr int kNetworkStateVersion = 1;
constexpr double kMax = std::numeric_limits<double>::max();

Json reals(const std::vector<double>& v, const char* what) {
  Json a = Json::array();
  for (double d : v) a.push_back(real_json(d, what));
  return a;
}
std::vector<double> reals(const Field& f, std::size_t n, double lo = -kMax, double hi = kMax) {
  f.array(n);
  std::vector<double> v(n);
  for (std::size_t k = 0; k < n; ++k) v[k] = f[k].real(lo, hi);
  return v;
}
/// A D x D matrix, row-major [D * D] (both layouts).
template <int D>
Json matrix(const Eigen::Matrix<double, D, D>& m, const char* what) {
  Json a = Json::array();
  for (int r = 0; r < D; ++r)
    for (int c = 0; c < D; ++c) a.push_back(real_json(m(r, c), what));
  return a;
}
template <int D>
Eigen::Matrix<double, D, D> matrix(const Field& f) {
  const std::vector<double> v = reals(f, D * D);
  Eigen::Matrix<double, D, D> m;
  for (int r = 0; r < D; ++r)
    for (int c = 0; c < D; ++c) m(r, c) = v[static_cast<std::size_t>(D * r + c)];
  return m;
}

// ---- the parts both layouts (2D "network", 3D "network3d") share; S: the state of either ----

std::uint64_t read_seed(const Field& seed) {
  if (!seed.json().is_number_unsigned() && !(seed.json().is_number_integer() && seed.json().get<std::int64_t>() >= 0))
    seed.fail("expected a non-negative integer");
  return seed.json().get<std::uint64_t>();
}

/// Pair k of the member "pairs" p: its indices (i < j < N, sorted by (i, j)), history, E_form,
/// slip, centre and sliding flag.
template <int D, class S>
void read_pair(const Field& p, std::size_t k, std::int64_t last, S& s) {
  using History = typename decltype(s.history)::value_type;
  s.pair_i[k] = static_cast<int>(p["i"][k].integer(0, last));
  s.pair_j[k] = static_cast<int>(p["j"][k].integer(0, last));
  if (!(s.pair_i[k] < s.pair_j[k])) p["j"][k].fail("pair indices must satisfy i < j < N");
  if (k > 0 && !(std::make_pair(s.pair_i[k - 1], s.pair_j[k - 1]) < std::make_pair(s.pair_i[k], s.pair_j[k])))
    p["i"][k].fail("pairs must be sorted by (i, j)");
  s.history[k] = p["history"][k].get<History>();
  s.aux[k].E_form = matrix<D>(p["E_form"][k]);
  s.aux[k].slip = p["slip"][k].real();
  s.aux[k].centre = p["centre"][k].real();
  s.sliding[k] = p["sliding"][k].boolean() ? 1 : 0;
}

/// The optional members: the periodic cell (issue 29: the cell's vectors, empty: the box's edges;
/// each row's image; the held particle) and the wall contacts (2 D slots per particle).
template <int D, class S>
void write_optional(Json& j, const S& s) {
  if (s.periodic) {
    Json shift = Json::array();
    for (const auto& n : s.shift) {
      Json a = Json::array();
      for (int c = 0; c < D; ++c) a.push_back(n[static_cast<std::size_t>(c)]);
      shift.push_back(a);
    }
    j["periodic"] = Json{{"cell", reals(s.cell, "cell")}, {"shift", shift}, {"pinned", s.pinned}};
  }
  if (!s.wall_history.empty()) {
    Json hist = Json::array();
    for (const auto& h : s.wall_history) hist.push_back(h);
    j["walls"] = Json{{"history", hist}, {"f_n", reals(s.wall_f_n, "wall f_n")}};
  }
}

/// The optional periodic cell (absent: walls, die or affine) and wall contacts (absent: no walls,
/// or walls that no particle has touched yet) of a state of n particles.
template <int D, class S>
void read_optional(const Field& root, S& s, std::size_t n) {
  if (root.has("periodic")) {
    const Field p = root["periodic"];
    p.object({"cell", "shift", "pinned"});
    s.periodic = true;
    const std::size_t nc = p["cell"].array(0, D * D);
    if (nc != 0 && nc != D * D)
      p["cell"].fail(D == 2 ? "expected 0 or 4 numbers (the cell vectors a1, a2)"
                            : "expected 0 or 9 numbers (the cell vectors a1, a2, a3)");
    s.cell = reals(p["cell"], nc);
    const std::size_t np = s.pair_i.size();
    p["shift"].array(np);
    s.shift.resize(np);
    for (std::size_t k = 0; k < np; ++k) {
      p["shift"][k].array(D);
      for (std::size_t a = 0; a < D; ++a) s.shift[k][a] = static_cast<int>(p["shift"][k][a].integer(-1000000, 1000000));
    }
    s.pinned = static_cast<int>(p["pinned"].integer(0, static_cast<std::int64_t>(n) - 1));
  }
  if (root.has("walls")) {
    using History = typename decltype(s.wall_history)::value_type;
    const Field w = root["walls"];
    w.object({"history", "f_n"});
    const std::size_t slots = 2 * D * n;
    w["history"].array(slots);
    s.wall_history.resize(slots);
    for (std::size_t k = 0; k < slots; ++k) s.wall_history[k] = w["history"][k].get<History>();
    s.wall_f_n = reals(w["f_n"], slots, 0.0, kMax);
  }
}

Json timings_json(const SolverTimings& t) {
  return Json{{"assemble", real_json(t.assemble, "timing")},     {"analyse", real_json(t.analyse, "timing")},
              {"factorise", real_json(t.factorise, "timing")},   {"solve", real_json(t.solve, "timing")},
              {"neighbours", real_json(t.neighbours, "timing")}, {"total", real_json(t.total, "timing")},
              {"analyses", t.analyses},                          {"factorisations", t.factorisations},
              {"solves", t.solves},                              {"increments", t.increments},
              {"newton_iterations", t.newton_iterations}};
}

Json state_json(const NetworkState& s) {
  Json j = sys::make_archive("network", kNetworkStateVersion);
  std::vector<bool> per(s.peripheral.begin(), s.peripheral.end());
  j["particles"] = Json{{"x", reals(s.x, "x")},
                        {"y", reals(s.y, "y")},
                        {"theta", reals(s.theta, "theta")},
                        {"r", reals(s.r, "r")},
                        {"peripheral", per},
                        {"x_build", reals(s.x_build, "x_build")},
                        {"y_build", reals(s.y_build, "y_build")},
                        {"f_contact", reals(s.f_contact, "f_contact")},
                        {"du_prev", reals(s.du_prev, "du_prev")}};
  j["solid_area"] = real_json(s.solid_area, "solid_area");
  j["initial_density"] = real_json(s.initial_density, "initial_density");
  j["box_area0"] = real_json(s.box_area0, "box_area0");
  j["box0"] = Json{{"min", Json::array({real_json(s.box0.x_min, "box0"), real_json(s.box0.y_min, "box0")})},
                   {"max", Json::array({real_json(s.box0.x_max, "box0"), real_json(s.box0.y_max, "box0")})}};
  j["seed"] = s.seed;
  j["box_deformation"] = matrix<2>(s.box_deformation, "box_deformation");
  j["strain"] = matrix<2>(s.strain, "strain");
  j["box_deformation_build"] = matrix<2>(s.box_deformation_build, "box_deformation_build");
  j["dE_prev"] = matrix<2>(s.dE_prev, "dE_prev");
  Json e = Json::array(), slip = Json::array(), centre = Json::array(), hist = Json::array();
  for (std::size_t k = 0; k < s.pair_i.size(); ++k) {
    e.push_back(matrix<2>(s.aux[k].E_form, "E_form"));
    slip.push_back(real_json(s.aux[k].slip, "slip"));
    centre.push_back(real_json(s.aux[k].centre, "centre"));
    hist.push_back(s.history[k]);
  }
  std::vector<bool> sl(s.sliding.begin(), s.sliding.end());
  j["pairs"] = Json{{"i", s.pair_i},        {"j", s.pair_j},   {"history", hist}, {"E_form", e},
                    {"slip", slip},         {"centre", centre}, {"f_n", reals(s.f_n, "f_n")},
                    {"f_t", reals(s.f_t, "f_t")}, {"sliding", sl}};
  write_optional<2>(j, s);  // walls: 4 slots per particle (left, right, bottom, top)
  j["timings"] = timings_json(s.timings);
  return j;
}

void read_particles(const Field& root, NetworkState& s) {
  constexpr std::size_t kMaxParticles = 100000000;
  const Field p = root["particles"];
  p.object({"x", "y", "theta", "r", "peripheral", "x_build", "y_build", "f_contact", "du_prev"});
  const std::size_t n = p["x"].array(1, kMaxParticles);
  s.x = reals(p["x"], n);
  s.y = reals(p["y"], n);
  s.theta = reals(p["theta"], n);
  s.r = reals(p["r"], n, 0.0, kMax);
  for (std::size_t k = 0; k < n; ++k)
    if (!(s.r[k] > 0.0)) p["r"][k].fail("a radius must be positive");
  p["peripheral"].array(n);
  s.peripheral.resize(n);
  for (std::size_t k = 0; k < n; ++k) s.peripheral[k] = p["peripheral"][k].boolean() ? 1 : 0;
  s.x_build = reals(p["x_build"], n);
  s.y_build = reals(p["y_build"], n);
  s.f_contact = reals(p["f_contact"], 3 * n);
  if (p["du_prev"].json().is_array() && p["du_prev"].json().empty()) s.du_prev.clear();
  else s.du_prev = reals(p["du_prev"], 3 * n);  // the predictor: empty at the start, else 3 per particle
}

void read_globals(const Field& root, NetworkState& s) {
  s.solid_area = root["solid_area"].real(0.0, kMax);
  s.initial_density = root["initial_density"].real(0.0, kMax);
  s.box_area0 = root["box_area0"].real(0.0, kMax);
  const Field b = root["box0"];
  b.object({"min", "max"});
  const auto lo = reals(b["min"], 2), hi = reals(b["max"], 2);
  s.box0 = {lo[0], lo[1], hi[0], hi[1]};
  if (!(s.box0.x_max > s.box0.x_min && s.box0.y_max > s.box0.y_min)) b.fail("the initial box must have positive size");
  s.seed = read_seed(root["seed"]);
  s.box_deformation = matrix<2>(root["box_deformation"]);
  s.strain = matrix<2>(root["strain"]);
  s.box_deformation_build = matrix<2>(root["box_deformation_build"]);
  s.dE_prev = matrix<2>(root["dE_prev"]);
  if (!(s.box_deformation.determinant() > 0.0)) root["box_deformation"].fail("the determinant must be positive");
  if (!(s.box_deformation_build.determinant() > 0.0))
    root["box_deformation_build"].fail("the determinant must be positive");
}

void read_pairs(const Field& root, NetworkState& s) {
  const Field p = root["pairs"];
  p.object({"i", "j", "history", "E_form", "slip", "centre", "f_n", "f_t", "sliding"});
  const std::size_t n = s.x.size();
  const std::size_t np = p["i"].array(0, n * (n - 1) / 2);
  for (const char* key : {"j", "history", "E_form", "slip", "centre", "f_n", "f_t", "sliding"}) p[key].array(np);
  const auto last = static_cast<std::int64_t>(n) - 1;
  s.pair_i.resize(np);
  s.pair_j.resize(np);
  s.history.resize(np);
  s.aux.resize(np);
  s.sliding.resize(np);
  for (std::size_t k = 0; k < np; ++k) read_pair<2>(p, k, last, s);
  s.f_n = reals(p["f_n"], np, 0.0, kMax);
  s.f_t = reals(p["f_t"], np);
}

void read_timings(const Field& root, SolverTimings& T) {
  const Field t = root["timings"];
  t.object({"assemble", "analyse", "factorise", "solve", "neighbours", "total", "analyses", "factorisations", "solves",
            "increments", "newton_iterations"});
  T.assemble = t["assemble"].real(0.0, kMax);
  T.analyse = t["analyse"].real(0.0, kMax);
  T.factorise = t["factorise"].real(0.0, kMax);
  T.solve = t["solve"].real(0.0, kMax);
  T.neighbours = t["neighbours"].real(0.0, kMax);
  T.total = t["total"].real(0.0, kMax);
  constexpr std::int64_t kBig = std::int64_t{1} << 50;
  T.analyses = t["analyses"].integer(0, kBig);
  T.factorisations = t["factorisations"].integer(0, kBig);
  T.solves = t["solves"].integer(0, kBig);
  T.increments = t["increments"].integer(0, kBig);
  T.newton_iterations = t["newton_iterations"].integer(0, kBig);
}

}  // namespace

void save_state(const NetworkState& s, const std::string& path) {
  s.validate();
  sys::write_text_file(path, sys::dump_archive(state_json(s)), "state file");
}

NetworkState load_state(const std::string& path) {
  return load_state_text(sys::read_text_file(path, "state file"), path);
}

NetworkState load_state(std::istream& stream, const std::string& path) {
  std::ostringstream text;
  text << stream.rdbuf();
  return load_state_text(text.str(), path);
}

NetworkState load_state_text(std::string_view text, const std::string& path) {
  const Json j = sys::parse_archive(text, path);
  const Field root(j, path);
  sys::check_header(root, "network", kNetworkStateVersion);
  root.object({"format", "kind", "version", "particles", "solid_area", "initial_density", "box_area0", "box0", "seed",
               "box_deformation", "strain", "box_deformation_build", "dE_prev", "pairs", "periodic", "walls", "timings"});
  NetworkState s;
  read_particles(root, s);
  read_globals(root, s);
  read_pairs(root, s);
  read_optional<2>(root, s, s.x.size());
  read_timings(root, s.timings);
  try {
    s.validate();
  } catch (const std::invalid_argument& e) {
    root.fail(e.what());
  }
  return s;
}

// ------------------------------------------------------------------------------------------------
// The 3D state file (kind "network3d", version 1; docs/quasistatic.md "State file"): the generic
// layout of NetworkStateT<3>, matrices row-major, vectors flat (D or kNodeDofs per particle).

namespace {

constexpr int kNetwork3StateVersion = 1;

Json state3_json(const NetworkState3& s) {
  Json j = sys::make_archive("network3d", kNetwork3StateVersion);
  const auto& P = s.particles;
  std::vector<bool> per(s.peripheral.begin(), s.peripheral.end());
  j["particles"] = Json{{"pos", reals(P.pos, "pos")},           {"rot", reals(P.rot, "rot")},
                        {"r", reals(P.r, "r")},                 {"peripheral", per},
                        {"pos_build", reals(s.pos_build, "pos_build")}, {"f_contact", reals(s.f_contact, "f_contact")},
                        {"du_prev", reals(s.du_prev, "du_prev")}};
  j["solid_volume"] = real_json(s.solid_area, "solid_volume");
  j["initial_density"] = real_json(s.initial_density, "initial_density");
  j["box_volume0"] = real_json(s.box_area0, "box_volume0");
  const auto& b = s.box0;
  j["box0"] = Json{{"min", reals({b.x_min, b.y_min, b.z_min}, "box0")}, {"max", reals({b.x_max, b.y_max, b.z_max}, "box0")}};
  j["seed"] = s.seed;
  j["box_deformation"] = matrix<3>(s.box_deformation, "box_deformation");
  j["strain"] = matrix<3>(s.strain, "strain");
  j["box_deformation_build"] = matrix<3>(s.box_deformation_build, "box_deformation_build");
  j["dE_prev"] = matrix<3>(s.dE_prev, "dE_prev");
  Json e = Json::array(), slip = Json::array(), centre = Json::array(), hist = Json::array(), ft = Json::array();
  for (std::size_t k = 0; k < s.pair_i.size(); ++k) {
    e.push_back(matrix<3>(s.aux[k].E_form, "E_form"));
    slip.push_back(real_json(s.aux[k].slip, "slip"));
    centre.push_back(real_json(s.aux[k].centre, "centre"));
    hist.push_back(s.history[k]);
    ft.push_back(reals({s.f_t[k][0], s.f_t[k][1], s.f_t[k][2]}, "f_t"));
  }
  std::vector<bool> sl(s.sliding.begin(), s.sliding.end());
  j["pairs"] = Json{{"i", s.pair_i},   {"j", s.pair_j},        {"history", hist},           {"E_form", e},
                    {"slip", slip},    {"centre", centre},     {"f_n", reals(s.f_n, "f_n")}, {"f_t", ft},
                    {"sliding", sl}};
  write_optional<3>(j, s);  // walls: six slots per particle (wall 2a at the minimum of axis a, 2a + 1 at its maximum)
  j["timings"] = timings_json(s.timings);
  return j;
}

void read_particles3(const Field& root, NetworkState3& s) {
  constexpr std::size_t kMaxParticles = 100000000;
  const Field p = root["particles"];
  p.object({"pos", "rot", "r", "peripheral", "pos_build", "f_contact", "du_prev"});
  const std::size_t n = p["r"].array(1, kMaxParticles);
  s.particles.pos = reals(p["pos"], 3 * n);
  s.particles.rot = reals(p["rot"], 3 * n);
  s.particles.r = reals(p["r"], n, 0.0, kMax);
  for (std::size_t k = 0; k < n; ++k)
    if (!(s.particles.r[k] > 0.0)) p["r"][k].fail("a radius must be positive");
  p["peripheral"].array(n);
  s.peripheral.resize(n);
  for (std::size_t k = 0; k < n; ++k) s.peripheral[k] = p["peripheral"][k].boolean() ? 1 : 0;
  s.pos_build = reals(p["pos_build"], 3 * n);
  s.f_contact = reals(p["f_contact"], 6 * n);
  if (p["du_prev"].json().is_array() && p["du_prev"].json().empty()) s.du_prev.clear();
  else s.du_prev = reals(p["du_prev"], 6 * n);
}

void read_globals3(const Field& root, NetworkState3& s) {
  s.solid_area = root["solid_volume"].real(0.0, kMax);
  s.initial_density = root["initial_density"].real(0.0, kMax);
  s.box_area0 = root["box_volume0"].real(0.0, kMax);
  const Field b = root["box0"];
  b.object({"min", "max"});
  const auto lo = reals(b["min"], 3), hi = reals(b["max"], 3);
  s.box0.x_min = lo[0], s.box0.y_min = lo[1], s.box0.z_min = lo[2];
  s.box0.x_max = hi[0], s.box0.y_max = hi[1], s.box0.z_max = hi[2];
  if (!(hi[0] > lo[0] && hi[1] > lo[1] && hi[2] > lo[2])) b.fail("the initial box must have positive size");
  s.seed = read_seed(root["seed"]);
  s.box_deformation = matrix<3>(root["box_deformation"]);
  s.strain = matrix<3>(root["strain"]);
  s.box_deformation_build = matrix<3>(root["box_deformation_build"]);
  s.dE_prev = matrix<3>(root["dE_prev"]);
  if (!(s.box_deformation_build.determinant() > 0.0)) root["box_deformation_build"].fail("the determinant must be positive");
}

void read_pairs3(const Field& root, NetworkState3& s) {
  const Field p = root["pairs"];
  p.object({"i", "j", "history", "E_form", "slip", "centre", "f_n", "f_t", "sliding"});
  const std::size_t n = s.particles.size();
  const std::size_t np = p["i"].array(0, 64 * n);
  for (const char* key : {"j", "history", "E_form", "slip", "centre", "f_n", "f_t", "sliding"}) p[key].array(np);
  const auto last = static_cast<std::int64_t>(n) - 1;
  s.pair_i.resize(np);
  s.pair_j.resize(np);
  s.history.resize(np);
  s.aux.resize(np);
  s.sliding.resize(np);
  s.f_t.resize(np);
  for (std::size_t k = 0; k < np; ++k) {
    read_pair<3>(p, k, last, s);
    const auto t = reals(p["f_t"][k], 3);
    s.f_t[k] = Eigen::Vector3d(t[0], t[1], t[2]);
  }
  s.f_n = reals(p["f_n"], np, 0.0, kMax);
}

}  // namespace

void save_state(const NetworkState3& s, const std::string& path) {
  s.validate();
  sys::write_text_file(path, sys::dump_archive(state3_json(s)), "state file");
}

NetworkState3 load_state3(const std::string& path) {
  return load_state3_text(sys::read_text_file(path, "state file"), path);
}

NetworkState3 load_state3_text(std::string_view text, const std::string& path) {
  const Json j = sys::parse_archive(text, path);
  const Field root(j, path);
  sys::check_header(root, "network3d", kNetwork3StateVersion);
  root.object({"format", "kind", "version", "particles", "solid_volume", "initial_density", "box_volume0", "box0",
               "seed", "box_deformation", "strain", "box_deformation_build", "dE_prev", "pairs", "periodic", "walls",
               "timings"});
  NetworkState3 s;
  read_particles3(root, s);
  read_globals3(root, s);
  read_pairs3(root, s);
  read_optional<3>(root, s, s.particles.size());
  read_timings(root, s.timings);
  try {
    s.validate();
  } catch (const std::invalid_argument& e) {
    root.fail(e.what());
  }
  return s;
}

}  // namespace netdem::qs
