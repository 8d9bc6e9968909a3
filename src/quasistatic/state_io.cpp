// The network-solver state file: plain text, one record per line, every floating-point value in
// hexadecimal notation (exact), so that a restored run continues bit-identically.
//
//   netdem-network-state 1
//   predictor 0|1
//   particles N
//   x y theta r peripheral x_build y_build f0 f1 f2 [du0 du1 du2]      (N lines; du if predictor 1)
//   scalars solid_area initial_density box_area0
//   box0 x_min y_min x_max y_max
//   seed S
//   box_deformation a11 a12 a21 a22      (and strain, box_deformation_build, dE_prev)
//   pairs P
//   i j u_max f_t hist_sliding E11 E12 E21 E22 slip centre f_n f_t sliding   (P lines)
//   timings assemble analyse factorise solve neighbours total analyses factorisations solves increments newton
//   end
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "netdem/packing/io.hpp"
#include "netdem/quasistatic/network_solver.hpp"

namespace netdem::qs {

namespace {

std::string hx(double v) { return fmt::format("{:a}", v); }

std::string quote(const std::string& t) { return packing::quote_input(t, 40); }

void put_matrix(std::string& out, const char* name, const Eigen::Matrix2d& m) {
  out += fmt::format("{} {} {} {} {}\n", name, hx(m(0, 0)), hx(m(0, 1)), hx(m(1, 0)), hx(m(1, 1)));
}

/// Line reader with one-line errors naming the file and line.
class Reader {
 public:
  static constexpr std::size_t kMaxLine = 4096;
  Reader(std::istream& in, const std::string& path) : path_(path), in_(in) {}
  /// Next line split into tokens; the first must be `key` (if not empty) and `count` tokens follow.
  std::vector<std::string> next(const std::string& key, std::size_t count) {
    std::string line;
    if (!std::getline(in_, line)) fail(fmt::format("ends early, expected '{}'", key.empty() ? "a record" : key));
    ++line_no_;
    // a record has at most 14 values: a longer line is not one (and is not split into a huge list)
    if (line.size() > kMaxLine) fail(fmt::format("line longer than {} characters", kMaxLine));
    std::istringstream ls(line);
    std::vector<std::string> tok;
    for (std::string t; ls >> t;) tok.push_back(t);
    std::size_t first = 0;
    if (!key.empty()) {
      if (tok.empty() || tok[0] != key) fail(fmt::format("expected '{}'", key));
      first = 1;
    }
    if (tok.size() - first != count) fail(fmt::format("expected {} values, got {}", count, tok.size() - first));
    return {tok.begin() + static_cast<std::ptrdiff_t>(first), tok.end()};
  }
  double real(const std::string& t) {
    errno = 0;
    char* end = nullptr;
    const double v = std::strtod(t.c_str(), &end);
    if (end == t.c_str() || *end != '\0' || errno == ERANGE) fail(fmt::format("'{}' is not a number", quote(t)));
    return v;
  }
  long integer(const std::string& t, long lo, long hi) {
    errno = 0;
    char* end = nullptr;
    const long v = std::strtol(t.c_str(), &end, 10);
    if (end == t.c_str() || *end != '\0' || errno == ERANGE || v < lo || v > hi)
      fail(fmt::format("'{}' is not an integer in [{}, {}]", quote(t), lo, hi));
    return v;
  }
  Eigen::Matrix2d matrix(const std::string& key) {
    const auto t = next(key, 4);
    Eigen::Matrix2d m;
    m << real(t[0]), real(t[1]), real(t[2]), real(t[3]);
    return m;
  }
  [[noreturn]] void fail(const std::string& m) const {
    throw std::runtime_error(fmt::format("{}:{}: {}", path_, line_no_, m));
  }

 private:
  std::string path_;
  std::istream& in_;
  long line_no_ = 0;
};

}  // namespace

void save_state(const NetworkState& s, const std::string& path) {
  s.validate();
  if (!s.wall_history.empty())
    throw std::invalid_argument("the state file does not hold wall contacts (--boundary walls) yet");
  const bool pred = !s.du_prev.empty();
  std::string out = "netdem-network-state 1\n";
  out += fmt::format("predictor {}\n", pred ? 1 : 0);
  out += fmt::format("particles {}\n", s.x.size());
  for (std::size_t p = 0; p < s.x.size(); ++p) {
    out += fmt::format("{} {} {} {} {} {} {} {} {} {}", hx(s.x[p]), hx(s.y[p]), hx(s.theta[p]), hx(s.r[p]),
                       int(s.peripheral[p]), hx(s.x_build[p]), hx(s.y_build[p]), hx(s.f_contact[3 * p]),
                       hx(s.f_contact[3 * p + 1]), hx(s.f_contact[3 * p + 2]));
    if (pred) out += fmt::format(" {} {} {}", hx(s.du_prev[3 * p]), hx(s.du_prev[3 * p + 1]), hx(s.du_prev[3 * p + 2]));
    out += '\n';
  }
  out += fmt::format("scalars {} {} {}\n", hx(s.solid_area), hx(s.initial_density), hx(s.box_area0));
  out += fmt::format("box0 {} {} {} {}\nseed {}\n", hx(s.box0.x_min), hx(s.box0.y_min), hx(s.box0.x_max), hx(s.box0.y_max),
                     s.seed);
  put_matrix(out, "box_deformation", s.box_deformation);
  put_matrix(out, "strain", s.strain);
  put_matrix(out, "box_deformation_build", s.box_deformation_build);
  put_matrix(out, "dE_prev", s.dE_prev);
  out += fmt::format("pairs {}\n", s.pair_i.size());
  for (std::size_t k = 0; k < s.pair_i.size(); ++k) {
    const auto& h = s.history[k];
    const auto& a = s.aux[k];
    out += fmt::format("{} {} {} {} {} {} {} {} {} {} {} {} {} {}\n", s.pair_i[k], s.pair_j[k], hx(h.u_max), hx(h.f_t),
                       int(h.sliding), hx(a.E_form(0, 0)), hx(a.E_form(0, 1)), hx(a.E_form(1, 0)), hx(a.E_form(1, 1)),
                       hx(a.slip), hx(a.centre), hx(s.f_n[k]), hx(s.f_t[k]), int(s.sliding[k]));
  }
  const auto& t = s.timings;
  out += fmt::format("timings {} {} {} {} {} {} {} {} {} {} {}\nend\n", hx(t.assemble), hx(t.analyse), hx(t.factorise),
                     hx(t.solve), hx(t.neighbours), hx(t.total), t.analyses, t.factorisations, t.solves, t.increments,
                     t.newton_iterations);
  const std::string tmp = path + ".tmp";
  {
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    if (!f) throw std::runtime_error(fmt::format("cannot write the state file {}", tmp));
    f << out;
    f.flush();
    if (!f) throw std::runtime_error(fmt::format("cannot write the state file {}", tmp));
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) throw std::runtime_error(fmt::format("cannot rename {} to {}: {}", tmp, path, ec.message()));
}

namespace {

void read_particles(Reader& in, NetworkState& s) {
  constexpr long kMaxParticles = 100000000;
  const bool pred = in.integer(in.next("predictor", 1)[0], 0, 1) == 1;
  const auto n = static_cast<std::size_t>(in.integer(in.next("particles", 1)[0], 1, kMaxParticles));
  // the arrays grow with the lines actually read: a count alone never allocates (a 20-byte file
  // claiming 10^8 particles ends early instead of allocating gigabytes)
  for (std::size_t p = 0; p < n; ++p) {
    for (auto* v : {&s.x, &s.y, &s.theta, &s.r, &s.x_build, &s.y_build}) v->resize(p + 1);
    s.peripheral.resize(p + 1);
    s.f_contact.resize(3 * (p + 1));
    if (pred) s.du_prev.resize(3 * (p + 1));
    const auto t = in.next("", pred ? 13 : 10);
    s.x[p] = in.real(t[0]);
    s.y[p] = in.real(t[1]);
    s.theta[p] = in.real(t[2]);
    s.r[p] = in.real(t[3]);
    s.peripheral[p] = static_cast<std::uint8_t>(in.integer(t[4], 0, 1));
    s.x_build[p] = in.real(t[5]);
    s.y_build[p] = in.real(t[6]);
    for (int c = 0; c < 3; ++c) s.f_contact[3 * p + c] = in.real(t[7 + c]);
    if (pred)
      for (int c = 0; c < 3; ++c) s.du_prev[3 * p + c] = in.real(t[10 + c]);
  }
}

void read_globals(Reader& in, NetworkState& s) {
  const auto sc = in.next("scalars", 3);
  s.solid_area = in.real(sc[0]);
  s.initial_density = in.real(sc[1]);
  s.box_area0 = in.real(sc[2]);
  const auto b0 = in.next("box0", 4);
  s.box0 = {in.real(b0[0]), in.real(b0[1]), in.real(b0[2]), in.real(b0[3])};
  const std::string t = in.next("seed", 1)[0];
  errno = 0;
  char* end = nullptr;
  if (t.empty() || t[0] == '-') in.fail("seed must be a non-negative integer");
  s.seed = std::strtoull(t.c_str(), &end, 10);
  if (*end != '\0' || errno == ERANGE) in.fail(fmt::format("'{}' is not a seed", quote(t)));
  s.box_deformation = in.matrix("box_deformation");
  s.strain = in.matrix("strain");
  s.box_deformation_build = in.matrix("box_deformation_build");
  s.dE_prev = in.matrix("dE_prev");
}

void read_pairs(Reader& in, NetworkState& s) {
  constexpr long kMaxPairs = 1000000000;
  const auto np = static_cast<std::size_t>(in.integer(in.next("pairs", 1)[0], 0, kMaxPairs));
  const long last = static_cast<long>(s.x.size()) - 1;
  for (std::size_t k = 0; k < np; ++k) {  // grow with the lines read (see read_particles)
    s.pair_i.resize(k + 1);
    s.pair_j.resize(k + 1);
    s.history.resize(k + 1);
    s.aux.resize(k + 1);
    s.f_n.resize(k + 1);
    s.f_t.resize(k + 1);
    s.sliding.resize(k + 1);
    const auto t = in.next("", 14);
    s.pair_i[k] = static_cast<int>(in.integer(t[0], 0, last));
    s.pair_j[k] = static_cast<int>(in.integer(t[1], 0, last));
    s.history[k].u_max = in.real(t[2]);
    s.history[k].f_t = in.real(t[3]);
    s.history[k].sliding = static_cast<std::uint8_t>(in.integer(t[4], 0, 1));
    s.aux[k].E_form << in.real(t[5]), in.real(t[6]), in.real(t[7]), in.real(t[8]);
    s.aux[k].slip = in.real(t[9]);
    s.aux[k].centre = in.real(t[10]);
    s.f_n[k] = in.real(t[11]);
    s.f_t[k] = in.real(t[12]);
    s.sliding[k] = static_cast<std::uint8_t>(in.integer(t[13], 0, 1));
  }
}

void read_timings(Reader& in, SolverTimings& T) {
  const auto tm = in.next("timings", 11);
  T.assemble = in.real(tm[0]);
  T.analyse = in.real(tm[1]);
  T.factorise = in.real(tm[2]);
  T.solve = in.real(tm[3]);
  T.neighbours = in.real(tm[4]);
  T.total = in.real(tm[5]);
  constexpr long kBig = 1L << 50;
  T.analyses = in.integer(tm[6], 0, kBig);
  T.factorisations = in.integer(tm[7], 0, kBig);
  T.solves = in.integer(tm[8], 0, kBig);
  T.increments = in.integer(tm[9], 0, kBig);
  T.newton_iterations = in.integer(tm[10], 0, kBig);
}

}  // namespace

NetworkState load_state(const std::string& path) {
  if (std::filesystem::is_directory(path)) throw std::runtime_error(fmt::format("{}: is a directory, not a state file", path));
  std::ifstream f(path, std::ios::binary);
  if (!f) throw std::runtime_error(fmt::format("{}: cannot be opened", path));
  return load_state(f, path);
}

NetworkState load_state(std::istream& stream, const std::string& path) {
  Reader in(stream, path);
  NetworkState s;
  if (in.next("netdem-network-state", 1)[0] != "1") in.fail("unsupported state file version");
  read_particles(in, s);
  read_globals(in, s);
  read_pairs(in, s);
  read_timings(in, s.timings);
  in.next("end", 0);
  try {
    s.validate();
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(fmt::format("{}: {}", path, e.what()));
  }
  return s;
}

}  // namespace netdem::qs
