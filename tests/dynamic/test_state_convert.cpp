// apps/scripts/convert_state.py on state files written by the old text writers
// (tests/data/old_states, commit ee3802d): the old file is refused with how to convert it, the
// converted archive is read, every number is the double the old reader read (strtod: decimal for
// the DEM, hexadecimal for the network state), bit for bit, and a DEM state restarts.
#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <unistd.h>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "netdem/dynamic/solver.hpp"
#include "netdem/dynamic/state.hpp"
#include "netdem/quasistatic/network_solver.hpp"
#include "netdem/quasistatic/staggered.hpp"

using namespace netdem::dem;
namespace fs = std::filesystem;

namespace {

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> v;
  std::string t;
  std::istringstream in(s);
  while (std::getline(in, t, sep))
    if (!t.empty()) v.push_back(t);
  return v;
}

// The particle columns of the old text format by name: one value per particle (component c of
// every `stride` of the state's arrays).
template <int D>
std::map<std::string, std::vector<double>> columns_of(const SolverState& st) {
  const auto& P = st.particles_of<D>();
  auto comp = [](const std::vector<double>& v, std::size_t stride, std::size_t c) {
    std::vector<double> out;
    for (std::size_t k = c; k < v.size(); k += stride) out.push_back(v[k]);
    return out;
  };
  std::map<std::string, std::vector<double>> col = {
      {"x", comp(P.pos, D, 0)},   {"y", comp(P.pos, D, 1)},     {"vx", comp(P.vel, D, 0)},
      {"vy", comp(P.vel, D, 1)},  {"radius", P.r},              {"radius_ref", st.radius_ref},
      {"mass", P.mass},           {"inertia", P.inertia},       {"fx", comp(P.force, D, 0)},
      {"fy", comp(P.force, D, 1)}};
  if constexpr (D == 2) {
    col["omega"] = P.spin;
    col["theta"] = P.rot;
    col["torque"] = P.torque;
  } else {
    for (std::size_t a = 0; a < 3; ++a) {
      col[std::string("w") + "xyz"[a]] = comp(P.spin, 3, a);
      col[std::string("t") + "xyz"[a]] = comp(P.torque, 3, a);
    }
    col["z"] = comp(P.pos, 3, 2);
    col["vz"] = comp(P.vel, 3, 2);
    col["fz"] = comp(P.force, 3, 2);
  }
  return col;
}

// The lines of the old file, and the count of numbers that differ from the converted state.
std::size_t differing(const std::string& old_text, const SolverState& st) {
  std::vector<std::string> lines = split(old_text, '\n');
  const int D = st.dim();
  const auto col = D == 2 ? columns_of<2>(st) : columns_of<3>(st);
  std::size_t bad = 0, compared = 0;
  auto cmp = [&](const std::string& tok, double v) {
    ++compared;
    bad += !same_bits(std::strtod(tok.c_str(), nullptr), v);
  };
  std::size_t k = 0;
  for (; k < lines.size(); ++k) {
    const auto w = split(lines[k], ' ');
    if (w.size() == 2 && w[0] == "time") cmp(w[1], st.time);
    if (w.size() == 2 && w[0] == "dt") cmp(w[1], st.dt);
    if (lines[k].rfind("id,", 0) == 0) break;
  }
  const auto head = split(lines[k], ',');
  for (std::size_t i = 0; i < st.particle_count(); ++i) {
    const auto f = split(lines[k + 1 + i], ',');
    for (std::size_t c = 1; c < head.size(); ++c) cmp(f[c], col.at(head[c])[i]);
  }
  k += 1 + st.particle_count();
  const std::size_t ph = st.pair_key.size();
  for (std::size_t p = 0; p < ph; ++p) {
    const auto w = split(lines[k + 2 + p], ' ');  // after "pairs M" and its comment
    if (D == 2) {
      const auto& h = st.histories_of<netdem::contact::LudingHistoryT<2>>().pair[p];
      cmp(w[2], h.delta_max);
      cmp(w[3], h.delta0);
      cmp(w[5], h.k1_seen);
    } else {
      const auto& h = st.histories_of<netdem::contact::LudingHistoryT<3>>().pair[p];
      cmp(w[2], h.delta_max);
      cmp(w[3], h.delta0);
      cmp(w[4], h.k2_line);
    }
  }
  EXPECT_GT(compared, 100u);
  return bad;
}

}  // namespace

TEST(StateConvert, OldDemTextStatesConvertBitForBit) {
  const fs::path dir = NETDEM_OLD_STATES;
  const fs::path tmp = fs::temp_directory_path() / ("netdem_convert_" + std::to_string(::getpid()));
  fs::create_directories(tmp);
  for (const char* name : {"dem2d_v2", "dem3d_v2"}) {
    const fs::path old = dir / (std::string(name) + ".txt"), out = tmp / (std::string(name) + ".json");
    try {
      (void)read_state_file(old.string());
      ADD_FAILURE() << name << ": the old text file was read";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("convert it with apps/scripts/convert_state.py"), std::string::npos) << e.what();
    }
    const std::string cmd = "/usr/bin/python3 " + std::string(NETDEM_CONVERTER) + " " + old.string() + " " + out.string();
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
    const SolverState st = read_state_file(out.string());
    std::ifstream in(old);
    std::ostringstream text;
    text << in.rdbuf();
    EXPECT_EQ(differing(text.str(), st), 0u) << name;
    EXPECT_GT(st.pair_key.size(), 5u) << name << ": the file must hold contacts";
    // the converted state restarts and runs
    DynamicOptions o;
    if (st.dim() == 3) {
      DynamicSolver3 s(st, o);
      EXPECT_EQ(format_state(s.state()), format_state(st));
      s.run(200);
    } else {
      DynamicSolver s(st, o);
      EXPECT_EQ(format_state(s.state()), format_state(st));
      s.run(200);
    }
  }
  fs::remove_all(tmp);
}

// The network state of netsolve compact --save-state (hexadecimal doubles): every particle record
// and pair record of the old file equals the converted archive's, bit for bit.
TEST(StateConvert, OldNetworkTextStateConvertsBitForBit) {
  const fs::path old = fs::path(NETDEM_OLD_STATES) / "network.txt";
  const fs::path out = fs::temp_directory_path() / ("netdem_convert_net_" + std::to_string(::getpid()) + ".json");
  try {
    (void)netdem::qs::load_state(old.string());
    ADD_FAILURE() << "the old text file was read";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("convert it with apps/scripts/convert_state.py"), std::string::npos) << e.what();
  }
  const std::string cmd = "/usr/bin/python3 " + std::string(NETDEM_CONVERTER) + " " + old.string() + " " + out.string();
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  const netdem::qs::NetworkState s = netdem::qs::load_state(out.string());
  fs::remove(out);
  std::ifstream in(old);
  std::ostringstream text;
  text << in.rdbuf();
  const auto lines = split(text.str(), '\n');
  std::size_t k = 0, bad = 0, compared = 0;
  auto cmp = [&](const std::string& tok, double v) {
    ++compared;
    bad += !same_bits(std::strtod(tok.c_str(), nullptr), v);
  };
  while (lines[k].rfind("particles ", 0) != 0) ++k;
  ASSERT_EQ(std::stoul(split(lines[k], ' ')[1]), s.x.size());
  for (std::size_t p = 0; p < s.x.size(); ++p) {
    const auto w = split(lines[k + 1 + p], ' ');
    cmp(w[0], s.x[p]);
    cmp(w[1], s.y[p]);
    cmp(w[2], s.theta[p]);
    cmp(w[3], s.r[p]);
    cmp(w[5], s.x_build[p]);
    for (int c = 0; c < 3; ++c) cmp(w[7 + c], s.f_contact[3 * p + c]);
  }
  while (lines[k].rfind("pairs ", 0) != 0) ++k;
  ASSERT_EQ(std::stoul(split(lines[k], ' ')[1]), s.pair_i.size());
  for (std::size_t p = 0; p < s.pair_i.size(); ++p) {
    const auto w = split(lines[k + 1 + p], ' ');
    cmp(w[2], s.history[p].u_max);
    cmp(w[3], s.history[p].f_t);
    cmp(w[9], s.aux[p].slip);
    cmp(w[11], s.f_n[p]);
    cmp(w[12], s.f_t[p]);
  }
  EXPECT_GT(s.pair_i.size(), 5u);
  EXPECT_GT(compared, 100u);
  EXPECT_EQ(bad, 0u);
}

// The staggered state of netsolve sinter (hexadecimal doubles, a checkpoint at t = 50 s): the
// particles and the pair states equal the old file's bit for bit, the record of origin comes from
// the summary.json beside the old state (seed 7), and the converted state steps on to 100 s.
TEST(StateConvert, OldStaggeredTextStateConvertsBitForBit) {
  namespace st = netdem::qs::staggered;
  const fs::path old = fs::path(NETDEM_OLD_STATES) / "staggered.txt";
  const fs::path out = fs::temp_directory_path() / ("netdem_convert_stag_" + std::to_string(::getpid()) + ".json");
  std::ifstream in(old);
  std::ostringstream text;
  text << in.rdbuf();
  try {
    (void)st::Staggered::load(text.str(), old.string());
    ADD_FAILURE() << "the old text file was read";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("convert it with apps/scripts/convert_state.py"), std::string::npos) << e.what();
  }
  const std::string cmd = "/usr/bin/python3 " + std::string(NETDEM_CONVERTER) + " " + old.string() + " " + out.string();
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  std::ifstream jin(out);
  std::ostringstream json;
  json << jin.rdbuf();
  fs::remove(out);
  st::Staggered s = st::Staggered::load(json.str(), "converted");
  EXPECT_NE(s.origin_record().find("\"seed\":7"), std::string::npos) << s.origin_record();
  std::vector<std::string> tok;
  for (const auto& line : split(text.str(), '\n'))
    for (const auto& t : split(line, ' ')) tok.push_back(t);
  std::size_t k = 0, bad = 0, compared = 0;
  auto cmp = [&](const std::string& t, double v) {
    ++compared;
    bad += !same_bits(std::strtod(t.c_str(), nullptr), v);
  };
  while (tok[k] != "particles") ++k;
  const std::size_t n = std::stoul(tok[++k]);
  ASSERT_EQ(n, s.particles().size());
  for (std::size_t i = 0; i < n; ++i) {
    for (int a = 0; a < 3; ++a) cmp(tok[++k], s.particles().coord(i, a));
    cmp(tok[++k], s.particles().r[i]);
    for (int a = 0; a < 3; ++a) cmp(tok[++k], s.initial_particles().coord(i, a));
    cmp(tok[++k], s.initial_particles().r[i]);
    ++k;  // the flags
  }
  ASSERT_EQ(tok[++k], "contacts");
  ASSERT_EQ(std::stoul(tok[++k]), s.contacts().size());
  for (const auto& c : s.contacts()) {
    k += 4;  // a b frozen status
    for (double v : c.pair.q) cmp(tok[++k], v);
    for (double v : c.pair.q0) cmp(tok[++k], v);
    k += 10;
  }
  EXPECT_GT(s.contacts().size(), 5u);
  EXPECT_GT(compared, 100u);
  EXPECT_EQ(bad, 0u);
  EXPECT_EQ(s.time(), 50.0);
  while (s.time() < 100.0) s.step(100.0);
  EXPECT_EQ(s.time(), 100.0);
}
