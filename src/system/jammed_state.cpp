// The jammed state in the state archive (jammed_state.hpp): the writer, the reader and the one
// set of checks both use (check_state: a refusal names the JSON pointer of the field).
#include "netdem/system/jammed_state.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

#include <fmt/format.h>

#include "netdem/system/archive.hpp"
#include "netdem/system/law_json.hpp"

namespace netdem::sys {

namespace {

constexpr double kMax = std::numeric_limits<double>::max();
constexpr std::size_t kMaxParticles = 100000000;
constexpr const char* kAxis[3] = {"x", "y", "z"};

double lo(const packing::Box& b, int a) { return a == 0 ? b.x_min : a == 1 ? b.y_min : b.z_min; }
double hi(const packing::Box& b, int a) { return a == 0 ? b.x_max : a == 1 ? b.y_max : b.z_max; }

/// Whether the law gives a contact of overlap u and history h a normal force (the committed
/// branch: loading, elastic un/reloading, or open).
template <int D>
bool loaded(const contact::PlasticIndentationParams& law, double r_eff, const contact::PlasticIndentationHistoryT<D>& h,
            double u) {
  double f = 0.0, k = 0.0;
  contact::NormalBranch b = contact::NormalBranch::Open;
  contact::normal_force<D>(law, r_eff, h.u_max, u, f, k, b);
  return f > 0.0;
}

/// One history against its contact's geometry; `fail(pointer, problem)` throws.
template <int D, class Fail>
void check_history(const contact::PlasticIndentationParams& law, double r_eff, const contact::PlasticIndentationHistoryT<D>& h,
                   double u, const std::string& ptr, const std::string& who, const Fail& fail) {
  if (!(std::isfinite(h.u_max) && h.u_max >= 0.0)) fail(ptr + "/u_max", fmt::format("{}: u_max must be finite and >= 0", who));
  if (!std::isfinite(contact::tan_norm(h.f_t))) fail(ptr + "/f_t", fmt::format("{}: a non-finite tangential spring", who));
  // the law commits u_max = max(u_max, u) (reversible or not); the rounding of two ways to compute u aside
  if (h.u_max < u - 1e-9 * r_eff)
    fail(ptr + "/u_max", fmt::format("{}: u_max = {:.6g} is below the current overlap {:.6g}: a committed state has "
                                     "u_max >= overlap", who, h.u_max, u));
  const bool spring = !contact::tan_is_zero(h.f_t) || h.sliding != 0;
  if (spring && !law.frictional())
    fail(ptr + "/f_t", fmt::format("{}: a tangential spring or a sliding flag under a frictionless law", who));
  if (spring && !loaded<D>(law, r_eff, h, u))
    fail(ptr + "/f_t", fmt::format("{}: a tangential spring (|f_t| = {:.6g}) or a sliding flag on a contact that carries "
                                   "no normal force (overlap {:.6g}, u_max {:.6g}): the law clears both when a contact "
                                   "opens", who, contact::tan_norm(h.f_t), u, h.u_max));
}

/// Every check of a jammed state; `fail(pointer, problem)` throws (the writer's and the reader's
/// exception). The pointers are those of the file.
template <int D, class Fail>
void check_state(const JammedStateT<D>& s, const Fail& fail) {
  constexpr std::size_t kR = contact::Dim<D>::kRotDofs;
  const std::size_t n = s.particles.size();
  if (n == 0) fail("/particles/r", "no particles");
  if (s.particles.pos.size() != D * n || s.particles.rot.size() != kR * n)
    fail("/particles", fmt::format("the centres and rotations do not all have {} entries", n));
  for (double v : s.particles.pos)
    if (!std::isfinite(v)) fail("/particles", "a non-finite centre");
  for (double v : s.particles.rot)
    if (!std::isfinite(v)) fail("/particles", "a non-finite rotation");
  for (std::size_t p = 0; p < n; ++p)
    if (!(std::isfinite(s.particles.r[p]) && s.particles.r[p] > 0.0))
      fail(fmt::format("/particles/r/{}", p), fmt::format("particle {}: the radius {} must be positive", p, s.particles.r[p]));
  try {
    s.law.validate();
  } catch (const std::invalid_argument& e) {
    fail("/law", e.what());
  }
  if (!(s.wall_mu >= 0.0)) fail("/wall_mu", "the walls' friction must be >= 0 (inf: sticking)");
  if (!s.strain.allFinite()) fail("/strain", "a non-finite strain");
  try {
    packing::validate(s.packing());
  } catch (const std::invalid_argument& e) {
    fail("/particles", e.what());
  }
  const std::size_t np = s.pair_i.size();
  if (s.pair_j.size() != np || s.pair_history.size() != np) fail("/pairs", "i, j and history differ in length");
  for (std::size_t k = 0; k < np; ++k) {
    const int i = s.pair_i[k], j = s.pair_j[k];
    const std::string ptr = fmt::format("/pairs/history/{}", k);
    if (!(i >= 0 && i < j && static_cast<std::size_t>(j) < n))
      fail(fmt::format("/pairs/j/{}", k), fmt::format("pair {} ({}, {}): the indices must satisfy i < j < N = {}", k, i, j, n));
    if (k > 0 && !(std::make_pair(s.pair_i[k - 1], s.pair_j[k - 1]) < std::make_pair(i, j)))
      fail(fmt::format("/pairs/i/{}", k), "pairs must be sorted by (i, j) without repeats");
    const double ri = s.particles.r[static_cast<std::size_t>(i)], rj = s.particles.r[static_cast<std::size_t>(j)];
    check_history<D>(s.law, ri * rj / (ri + rj), s.pair_history[k], s.pair_overlap(k), ptr,
                     fmt::format("pair {} (particles {} and {})", k, i, j), fail);
  }
  const std::size_t nw = s.wall_particle.size();
  if (s.wall_side.size() != nw || s.wall_history.size() != nw)
    fail("/wall_contacts", "particle, wall and history differ in length");
  if (nw > 0 && !s.walls) fail("/wall_contacts", "wall contacts in a box without contact walls");
  contact::PlasticIndentationParams wall_law = s.law;
  wall_law.mu = s.wall_mu;
  for (std::size_t k = 0; k < nw; ++k) {
    const int p = s.wall_particle[k], w = s.wall_side[k];
    if (!(p >= 0 && static_cast<std::size_t>(p) < n && w >= 0 && w < JammedStateT<D>::kWalls))
      fail(fmt::format("/wall_contacts/particle/{}", k),
           fmt::format("wall contact {}: particle {} < N = {} and wall {} < {} required", k, p, n, w, JammedStateT<D>::kWalls));
    if (k > 0 && !(std::make_pair(s.wall_particle[k - 1], s.wall_side[k - 1]) < std::make_pair(p, w)))
      fail(fmt::format("/wall_contacts/particle/{}", k), "wall contacts must be sorted by (particle, wall) without repeats");
    check_history<D>(wall_law, s.particles.r[static_cast<std::size_t>(p)], s.wall_history[k], s.wall_overlap(k),
                     fmt::format("/wall_contacts/history/{}", k), fmt::format("wall contact {} (particle {}, wall {})", k, p, w),
                     fail);
  }
}

template <int D>
Json state_json(const JammedStateT<D>& s) {
  Json j = make_archive("jammed", kJammedStateVersion);
  j["dim"] = D;
  Json bmin = Json::array(), bmax = Json::array();
  for (int a = 0; a < D; ++a) {
    bmin.push_back(real_json(lo(s.box, a), "box"));
    bmax.push_back(real_json(hi(s.box, a), "box"));
  }
  j["box"] = Json{{"min", bmin}, {"max", bmax}, {"walls", s.walls}};
  Json e = Json::array();
  for (int r = 0; r < D; ++r)
    for (int c = 0; c < D; ++c) e.push_back(real_json(s.strain(r, c), "strain"));
  j["strain"] = e;
  j["seed"] = s.seed;
  j["law"] = s.law;
  j["wall_mu"] = real_json(s.wall_mu, "wall_mu");
  Json parts = Json::object();
  for (int a = 0; a < D; ++a) {
    Json v = Json::array();
    for (std::size_t p = 0; p < s.particles.size(); ++p) v.push_back(real_json(s.particles.coord(p, a), "centre"));
    parts[kAxis[a]] = v;
  }
  Json rot = Json::array(), r = Json::array();
  for (double v : s.particles.rot) rot.push_back(real_json(v, "rotation"));
  for (double v : s.particles.r) r.push_back(real_json(v, "r"));
  parts["rotation"] = rot;
  parts["r"] = r;
  j["particles"] = parts;
  j["pairs"] = Json{{"i", s.pair_i}, {"j", s.pair_j}, {"history", s.pair_history}};
  j["wall_contacts"] = Json{{"particle", s.wall_particle}, {"wall", s.wall_side}, {"history", s.wall_history}};
  return j;
}

template <int D>
JammedStateT<D> read_body(const Field& root) {
  using History = contact::PlasticIndentationHistoryT<D>;
  constexpr std::size_t kR = contact::Dim<D>::kRotDofs;
  root.object({"format", "kind", "version", "dim", "box", "strain", "seed", "law", "wall_mu", "particles", "pairs",
               "wall_contacts"});
  JammedStateT<D> s;
  const Field b = root["box"];
  b.object({"min", "max", "walls"});
  b["min"].array(D);
  b["max"].array(D);
  double* bl[3] = {&s.box.x_min, &s.box.y_min, &s.box.z_min};
  double* bh[3] = {&s.box.x_max, &s.box.y_max, &s.box.z_max};
  for (std::size_t a = 0; a < D; ++a) {
    *bl[a] = b["min"][a].real();
    *bh[a] = b["max"][a].real();
  }
  s.walls = b["walls"].boolean();
  root["strain"].array(D * D);
  for (std::size_t k = 0; k < D * D; ++k) s.strain(static_cast<int>(k / D), static_cast<int>(k % D)) = root["strain"][k].real();
  s.seed = static_cast<std::uint64_t>(root["seed"].integer(0, std::numeric_limits<std::int64_t>::max()));
  s.law = root["law"].get<contact::PlasticIndentationParams>();
  s.wall_mu = root["wall_mu"].extended_real(0.0, HUGE_VAL);
  const Field pc = root["particles"];
  if constexpr (D == 2) pc.object({"x", "y", "rotation", "r"});
  else pc.object({"x", "y", "z", "rotation", "r"});
  const std::size_t n = pc["r"].array(1, kMaxParticles);
  s.particles.pos.resize(D * n);
  for (std::size_t a = 0; a < D; ++a) {
    pc[kAxis[a]].array(n);
    for (std::size_t p = 0; p < n; ++p) s.particles.pos[D * p + a] = pc[kAxis[a]][p].real();
  }
  pc["rotation"].array(kR * n);
  s.particles.rot.resize(kR * n);
  for (std::size_t k = 0; k < kR * n; ++k) s.particles.rot[k] = pc["rotation"][k].real();
  s.particles.r.resize(n);
  for (std::size_t p = 0; p < n; ++p) s.particles.r[p] = pc["r"][p].real(-kMax, kMax);
  const auto last = static_cast<std::int64_t>(n) - 1;
  const Field pr = root["pairs"];
  pr.object({"i", "j", "history"});
  const std::size_t np = pr["i"].array(0, n * (n - 1) / 2);
  pr["j"].array(np);
  pr["history"].array(np);
  for (std::size_t k = 0; k < np; ++k) {
    s.pair_i.push_back(static_cast<int>(pr["i"][k].integer(0, last)));
    s.pair_j.push_back(static_cast<int>(pr["j"][k].integer(0, last)));
    s.pair_history.push_back(pr["history"][k].get<History>());
  }
  const Field wc = root["wall_contacts"];
  wc.object({"particle", "wall", "history"});
  const std::size_t nw = wc["particle"].array(0, JammedStateT<D>::kWalls * n);
  wc["wall"].array(nw);
  wc["history"].array(nw);
  for (std::size_t k = 0; k < nw; ++k) {
    s.wall_particle.push_back(static_cast<int>(wc["particle"][k].integer(0, last)));
    s.wall_side.push_back(static_cast<int>(wc["wall"][k].integer(0, JammedStateT<D>::kWalls - 1)));
    s.wall_history.push_back(wc["history"][k].get<History>());
  }
  check_state(s, [&](const std::string& ptr, const std::string& problem) {
    throw FieldError(root.file(), ptr, problem);
  });
  return s;
}

}  // namespace

template <int D>
double JammedStateT<D>::pair_overlap(std::size_t k) const {
  const auto i = static_cast<std::size_t>(pair_i[k]), j = static_cast<std::size_t>(pair_j[k]);
  return particles.r[i] + particles.r[j] - (particles.position(j) - particles.position(i)).norm();
}

template <int D>
double JammedStateT<D>::wall_overlap(std::size_t k) const {
  const auto p = static_cast<std::size_t>(wall_particle[k]);
  const int w = wall_side[k], a = w / 2;
  const double x = particles.coord(p, a);
  return particles.r[p] - (w % 2 == 0 ? x - lo(box, a) : hi(box, a) - x);
}

template <int D>
packing::Packing JammedStateT<D>::packing() const {
  packing::Packing pk;
  pk.dim = D;
  pk.box = box;
  pk.r = particles.r;
  pk.x = particles.axis(0);
  pk.y = particles.axis(1);
  if constexpr (D == 3) pk.z = particles.axis(2);
  pk.seed = seed;
  return pk;
}

std::string law_difference(const contact::PlasticIndentationParams& a, const contact::PlasticIndentationParams& b) {
  std::string d;
  auto cmp = [&](const char* what, double x, double y) {
    if (!(x == y)) d += fmt::format("{}{} {:g} vs {:g}", d.empty() ? "" : ", ", what, x, y);
  };
  cmp("sigma_y", a.sigma_y, b.sigma_y);
  cmp("friction mu", a.mu, b.mu);
  cmp("k_t", a.k_t, b.k_t);
  cmp("unload_ratio", a.unload_ratio, b.unload_ratio);
  cmp("reversible", a.reversible ? 1.0 : 0.0, b.reversible ? 1.0 : 0.0);
  cmp("first_touch", a.first_touch, b.first_touch);
  return d;
}

template <int D>
void JammedStateT<D>::validate() const {
  check_state(*this, [](const std::string& ptr, const std::string& problem) {
    throw std::invalid_argument(fmt::format("jammed state: {}: {}", ptr, problem));
  });
}

template <int D>
std::string format_jammed_state(const JammedStateT<D>& s) {
  s.validate();
  return dump_archive(state_json(s));
}

int jammed_state_dim(std::string_view text, const std::string& name) {
  const Json j = parse_archive(text, name);
  const Field root(j, name);
  check_header(root, "jammed", kJammedStateVersion);
  return static_cast<int>(root["dim"].integer(2, 3));
}

template <int D>
JammedStateT<D> parse_jammed_state(std::string_view text, const std::string& name) {
  const Json j = parse_archive(text, name);
  const Field root(j, name);
  check_header(root, "jammed", kJammedStateVersion);
  const auto dim = root["dim"].integer(2, 3);
  if (dim != D) root["dim"].fail(fmt::format("a {}D state, expected a {}D one", dim, D));
  return read_body<D>(root);
}

template <int D>
JammedStateT<D> read_jammed_state(const std::string& path) {
  return parse_jammed_state<D>(read_text_file(path, "jammed state file"), path);
}

template <int D>
void write_jammed_state(const JammedStateT<D>& s, const std::string& path) {
  write_text_file(path, format_jammed_state(s), "jammed state file");
}

#define NETDEM_JAMMED(D)                                                                          \
  template struct JammedStateT<D>;                                                                \
  template std::string format_jammed_state<D>(const JammedStateT<D>&);                           \
  template JammedStateT<D> parse_jammed_state<D>(std::string_view, const std::string&);          \
  template JammedStateT<D> read_jammed_state<D>(const std::string&);                             \
  template void write_jammed_state<D>(const JammedStateT<D>&, const std::string&);
NETDEM_JAMMED(2)
NETDEM_JAMMED(3)
#undef NETDEM_JAMMED

}  // namespace netdem::sys
