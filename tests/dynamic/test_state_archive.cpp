// The DEM state file in the state archive (src/dynamic/state.cpp, src/system, issue 26): the
// plastic-indentation law restarts bit for bit from its state file (2D and 3D, its pair and wall
// histories: u_max and the tangential spring), exact doubles (every bit pattern, an infinite
// friction), and corrupt fields refused at the door with one line naming the file and the field.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <variant>

#include "netdem/dynamic/solver.hpp"
#include "netdem/dynamic/state.hpp"
#include "netdem/system/archive.hpp"
#include "netdem/system/law_json.hpp"

using namespace netdem::dem;
namespace sys = netdem::sys;
namespace ct = netdem::contact;

namespace {

// A box of frictional unit disks (spheres) with jitter and random velocities under compression by
// two (three) strain-controlled walls: the plastic law with its section 3.4 unloading branch,
// dashpots and wall friction, so that pair and wall contacts load, unload and slide.
template <int D>
DynamicSolverT<D> plastic_box(double mu) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  ParticlesT<D> P;
  const int side = D == 2 ? 6 : 3;
  for (int k = 0; k < (D == 3 ? side : 1); ++k)
    for (int j = 0; j < side; ++j)
      for (int i = 0; i < side; ++i) {
        const double x = 1.02 + 2.04 * i + 0.01 * u(rng), y = 1.02 + 2.04 * j + 0.01 * u(rng);
        const double r = 1.0 + 0.01 * u(rng);
        // the draws in a fixed order (GCC's: a call's arguments are evaluated in an unspecified order;
        // a braced list is evaluated first to last)
        if constexpr (D == 2) {
          const double vy = 0.05 * u(rng), vx = 0.05 * u(rng);
          P.add_disk(x, y, r, 1.0, vx, vy);
        } else {
          const double vx = 0.05 * u(rng), vy = 0.05 * u(rng), vz = 0.05 * u(rng);
          const double z = 1.02 + 2.04 * k + 0.01 * u(rng);
          P.add_sphere(x, y, z, r, 1.0, {vx, vy, vz});
        }
      }
  Box box;
  box.x_max = box.y_max = 2.04 * side;
  if (D == 3) box.z_max = 2.04 * side;
  for (MovingWall* w : {&box.right, &box.top, &box.back}) {
    w->mode = WallMode::Strain;
    w->velocity = -0.05;
  }
  DynamicOptions o;
  o.model = ContactModel::PlasticIndentation;
  o.plastic.mu = mu;
  o.plastic.reversible = false;
  o.plastic.unload_ratio = 20.0;
  o.plastic.damping_n = o.plastic.damping_t = 0.3;
  o.plastic_wall_mu = 0.3;
  return DynamicSolverT<D>(std::move(P), o.plastic, box, o);
}

bool same_bits(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), sizeof(double) * a.size()) == 0);
}

// Runs n1 steps, saves, loads into a fresh solver (whose options carry another law: the file
// brings its own), runs n2 more in both and compares every particle array, the box, the walls and
// the histories (the state files) bit for bit.
template <int D>
void plastic_restart(double mu) {
  DynamicSolverT<D> a = plastic_box<D>(mu);
  a.run(2000);
  const std::string text = format_state(a.state());
  DynamicOptions other;
  other.model = ContactModel::PlasticIndentation;  // the default law: sigma_y 1, mu inf, no damping
  DynamicSolverT<D> b(parse_state(text, "mem"), other);
  EXPECT_EQ(format_state(b.state()), text) << "state -> file -> state is not the identity";
  EXPECT_EQ(b.plastic_law().mu, mu);
  // the file exercises the plastic histories: loaded (u_max > 0), unloaded and sheared pairs and walls
  const SolverState st = a.state();
  std::size_t pair_loaded = 0, pair_sheared = 0, wall_loaded = 0, wall_sheared = 0;
  auto count = [](const auto& hs, std::size_t& loaded, std::size_t& sheared) {
    for (const auto& h : hs) {
      loaded += h.u_max > 0.0;
      sheared += !ct::tan_is_zero(h.f_t);
    }
  };
  const auto& hs = st.template histories_of<ct::PlasticIndentationHistoryT<D>>();
  count(hs.pair, pair_loaded, pair_sheared);
  count(hs.wall, wall_loaded, wall_sheared);
  std::printf("  %dD: %zu particles, %zu pair histories (%zu sheared), %zu wall histories (%zu sheared), %zu bytes\n",
              D, a.particles().size(), pair_loaded, pair_sheared, wall_loaded, wall_sheared, text.size());
  EXPECT_GT(pair_loaded, 10u);
  EXPECT_GT(pair_sheared, 0u) << "the test must exercise the tangential spring of the pairs";
  EXPECT_GT(wall_loaded, 0u);
  EXPECT_GT(wall_sheared, 0u) << "the test must exercise the tangential spring of the walls";
  a.run(3000);
  b.run(3000);
  const ParticlesT<D> &A = a.particles(), &B = b.particles();
  EXPECT_TRUE(same_bits(A.pos, B.pos) && same_bits(A.vel, B.vel) && same_bits(A.spin, B.spin));
  EXPECT_TRUE(same_bits(A.force, B.force) && same_bits(A.torque, B.torque) && same_bits(A.rot, B.rot));
  EXPECT_EQ(a.box().x_max, b.box().x_max);
  EXPECT_EQ(a.box().y_max, b.box().y_max);
  EXPECT_EQ(a.box().z_max, b.box().z_max);
  EXPECT_EQ(a.dt(), b.dt());
  EXPECT_EQ(a.time(), b.time());
  EXPECT_EQ(format_state(a.state()), format_state(b.state())) << "the histories differ after the restart";
}

}  // namespace

TEST(StateArchive, PlasticLawRestartsBitExactlyFromItsStateFile2D) { plastic_restart<2>(0.3); }

// 3D with the sticking law (mu = inf): the infinity goes through the file as "inf"
TEST(StateArchive, PlasticLawRestartsBitExactlyFromItsStateFile3D) {
  plastic_restart<3>(std::numeric_limits<double>::infinity());
}

// The state's histories are one variant over the laws of DemLaws and both dimensions: a state
// holds its law's alternative (state()), and histories of another law or dimension are refused with
// one line by the restart and by the writer.
TEST(StateArchive, HistoriesAreTheLawsAlternative) {
  static_assert(std::variant_size_v<decltype(SolverState::histories)> == 4, "two laws, two dimensions");
  const SolverState st = plastic_box<2>(0.3).state();
  ASSERT_TRUE(st.plastic_law());
  ASSERT_TRUE(st.holds<ct::PlasticIndentationHistoryT<2>>());
  EXPECT_EQ(st.histories_dim(), 2);
  EXPECT_EQ(st.histories_of<ct::PlasticIndentationHistoryT<2>>().wall.size(), 4 * st.particle_count());
  DynamicOptions o;
  o.model = ContactModel::PlasticIndentation;
  SolverState other = st;  // the same sizes, of the other dimension
  auto& h3 = other.histories.emplace<LawHistories<ct::PlasticIndentationHistoryT<3>>>();
  h3.pair.resize(st.pair_key.size());
  h3.wall.resize(st.histories_of<ct::PlasticIndentationHistoryT<2>>().wall.size());
  EXPECT_TRUE(other.plastic_law());
  try {
    DynamicSolver s(other, o);
    ADD_FAILURE() << "a state with 3D histories of 2D particles was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "state: inconsistent array sizes");
  }
  try {
    (void)format_state(other);
    ADD_FAILURE() << "a state with 3D histories of 2D particles was written";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "state: the histories are 3D, the particles 2D");
  }
  // the file's "law" names the alternative (sys::LawName), and the reader takes it back
  EXPECT_EQ(parse_state(format_state(st), "mem").histories.index(), st.histories.index());
}

// Every double goes through the archive to the same bits: random bit patterns (subnormals, -0,
// the extremes), and +-inf as strings; NaN is refused when written and when read.
TEST(StateArchive, DoublesRoundTripBitExactly) {
  std::mt19937_64 rng(11);
  std::vector<double> v = {0.0, -0.0, std::numeric_limits<double>::denorm_min(), std::numeric_limits<double>::min(),
                           std::numeric_limits<double>::max(), -std::numeric_limits<double>::max(), 0.1, 1.0 / 3.0};
  while (v.size() < 200000) {
    const std::uint64_t bits = rng();
    double d;
    std::memcpy(&d, &bits, sizeof d);
    if (std::isfinite(d)) v.push_back(d);
  }
  sys::Json a = sys::Json::array();
  for (double d : v) a.push_back(sys::real_json(d, "v"));
  const sys::Json back = sys::parse_archive(sys::dump_archive(a), "mem");
  const sys::Field f(back, "mem");
  f.array(v.size());
  std::size_t differ = 0;
  for (std::size_t k = 0; k < v.size(); ++k) {
    const double d = f[k].real();
    differ += std::memcmp(&d, &v[k], sizeof d) != 0;
  }
  EXPECT_EQ(differ, 0u);
  const double inf = std::numeric_limits<double>::infinity();
  const sys::Json e = sys::parse_archive(sys::dump_archive(sys::Json::array({sys::real_json(inf, "mu"), sys::real_json(-inf, "mu")})), "mem");
  EXPECT_EQ(sys::Field(e)[std::size_t{0}].extended_real(-inf, inf), inf);
  EXPECT_EQ(sys::Field(e)[std::size_t{1}].extended_real(-inf, inf), -inf);
  EXPECT_THROW((void)sys::Field(e)[std::size_t{0}].real(), sys::FieldError) << "a finite field takes no infinity";
  EXPECT_THROW((void)sys::real_json(std::nan(""), "mu"), std::invalid_argument);
  SolverState st = plastic_box<2>(0.3).state();
  st.particles_of<2>().vel[6] = std::nan("");  // (vx of particle 3)
  EXPECT_THROW((void)format_state(st), std::invalid_argument);
}

// Corrupt fields of a plastic-law state: each refused with one line "mem: POINTER: problem".
TEST(StateArchive, CorruptFieldsAreRefusedAtTheDoorOnOneLine) {
  DynamicSolver s = plastic_box<2>(0.3);
  s.run(1500);
  const sys::Json good = sys::parse_archive(format_state(s.state()), "mem");
  ASSERT_GT(good["pairs"]["i"].size(), 2u);
  ASSERT_GT(good["wall_contacts"]["particle"].size(), 1u);
  EXPECT_NO_THROW((void)parse_state(good.dump(), "mem"));
  auto refuse = [&](const char* what, auto&& edit, const std::string& needle) {
    sys::Json j = good;
    edit(j);
    try {
      (void)parse_state(j.dump(), "mem");
      ADD_FAILURE() << what << ": accepted";
    } catch (const std::invalid_argument& e) {
      const std::string m = e.what();
      EXPECT_NE(m.find("mem: " + needle), std::string::npos) << what << ": " << m;
      EXPECT_EQ(m.find('\n'), std::string::npos) << what << ": " << m;
      EXPECT_LT(m.size(), 300u) << what << ": " << m;
    }
  };
  using J = sys::Json;
  refuse("dt", [](J& j) { j["dt"] = -1.0; }, "/dt: -1.0 is outside [0, 1]");
  refuse("time", [](J& j) { j["time"] = 2e6; }, "/time: 2000000.0 is outside [0, 1e+06]");
  refuse("radius", [](J& j) { j["particles"]["radius"][3] = 1e300; }, "/particles/radius/3: radius must be within");
  refuse("mass", [](J& j) { j["particles"]["mass"][2] = 0.0; }, "/particles/mass/2: mass must be within");
  refuse("inertia", [](J& j) { j["particles"]["inertia"][1] = -1.0; }, "/particles/inertia/1: inertia");
  refuse("column size", [](J& j) { j["particles"]["vy"].erase(0); }, "/particles/vy: expected 36 elements, found 35");
  refuse("speed", [](J& j) { j["particles"]["vx"][5] = 1e6; }, "/particles/vx/5: particle 5: speed");
  // a torque as the force (campaign of issue 27: a torque of 1e300 wrote inf into vibrate's timeseries.csv)
  refuse("torque", [](J& j) { j["particles"]["torque"][5] = 1e300; }, "/particles/torque/5: particle 5: torque");
  refuse("duplicate", [](J& j) { j["particles"]["x"][1] = j["particles"]["x"][0]; j["particles"]["y"][1] = j["particles"]["y"][0]; },
         "/particles/x/1: particles 0 and 1");
  refuse("outside", [](J& j) { j["particles"]["x"][4] = -5.0; }, "/particles/x/4: particle 4: the centre");
  refuse("pair order", [](J& j) { std::swap(j["pairs"]["i"][0], j["pairs"]["j"][0]); }, "/pairs/j/0: pair indices");
  refuse("pair sort", [](J& j) { std::swap(j["pairs"]["i"][0], j["pairs"]["i"][1]); std::swap(j["pairs"]["j"][0], j["pairs"]["j"][1]); std::swap(j["pairs"]["history"][0], j["pairs"]["history"][1]); },
         "/pairs/i/1: pairs must be sorted");
  refuse("pair index", [](J& j) { j["pairs"]["j"][0] = 36; }, "/pairs/j/0: 36 is outside [0, 35]");
  refuse("history size", [](J& j) { j["pairs"]["history"].erase(0); }, "/pairs/history: expected");
  refuse("u_max", [](J& j) { j["pairs"]["history"][1]["u_max"] = -1e-3; }, "/pairs/history/1/u_max: -0.001 is below 0");
  refuse("f_t", [](J& j) { j["pairs"]["history"][0]["f_t"] = "inf"; }, "/pairs/history/0/f_t: must be a finite number");
  refuse("f_t type", [](J& j) { j["pairs"]["history"][0]["f_t"] = J::array({1.0, 2.0, 3.0}); }, "/pairs/history/0/f_t: expected a number, found array");
  refuse("sliding", [](J& j) { j["pairs"]["history"][0]["sliding"] = 2; }, "/pairs/history/0/sliding: expected true or false");
  refuse("wall index", [](J& j) { j["wall_contacts"]["wall"][0] = 4; }, "/wall_contacts/wall/0: 4 is outside [0, 3]");
  refuse("wall sort", [](J& j) { j["wall_contacts"]["particle"][1] = j["wall_contacts"]["particle"][0]; j["wall_contacts"]["wall"][1] = j["wall_contacts"]["wall"][0]; },
         "/wall_contacts/particle/1: wall contacts must be sorted");
  refuse("wall history", [](J& j) { j["wall_contacts"]["history"][0]["u_max"] = "x"; }, "/wall_contacts/history/0/u_max: expected a number");
  refuse("law", [](J& j) { j["law"] = "hertz"; }, "/law: \"hertz\" is not one of luding, plastic_indentation");
  refuse("sigma_y", [](J& j) { j["plastic_indentation"]["sigma_y"] = -1.0; }, "/plastic_indentation: ");
  refuse("mu nan", [](J& j) { j["plastic_indentation"]["mu"] = "nan"; }, "/plastic_indentation/mu: expected a number, \"inf\" or \"-inf\"");
  refuse("mu negative", [](J& j) { j["plastic_indentation"]["mu"] = "-inf"; }, "/plastic_indentation/mu: \"-inf\" is outside");
  refuse("missing", [](J& j) { j["plastic_indentation"].erase("k_t"); }, "/plastic_indentation/k_t: missing");
  refuse("unknown", [](J& j) { j["extra"] = 1; }, "/extra: unknown member");
  {  // a member nested 1e5 deep: SIGSEGV where the value was dumped for the message (campaign of issue 27)
    std::string text = good.dump();
    const std::string from = "\"version\":1";
    ASSERT_NE(text.find(from), std::string::npos);
    text.replace(text.find(from), from.size(), "\"version\":" + std::string(100000, '[') + std::string(100000, ']'));
    try {
      (void)parse_state(text, "mem");
      ADD_FAILURE() << "deep nesting: accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("mem: /: not a state archive (nested more than 64 levels deep at byte"),
                std::string::npos) << e.what();
    }
    // a wrong type is named by its type and size, not dumped
    J j = good;
    j["version"] = J::array({1, 2, 3});
    try {
      (void)parse_state(j.dump(), "mem");
      ADD_FAILURE() << "array version: accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("/version: expected an integer, found array (array of 3 elements)"),
                std::string::npos) << e.what();
    }
  }
  refuse("wall mode", [](J& j) { j["moving_walls"][1]["mode"] = std::string(500, 'z'); }, "/moving_walls/1/mode: \"zzzz");
  refuse("box", [](J& j) { j["box"]["max"][0] = -1.0; }, "/box: box must have x_max > x_min");
  refuse("format", [](J& j) { j["format"] = "other"; }, "/format: expected \"netdem-state\"");
  refuse("dim", [](J& j) { j["dim"] = 3; }, "/box/min: expected 3 elements, found 2");
  // a bad input is quoted with at most 80 characters
  try {
    sys::Json j = good;
    j["moving_walls"][1]["mode"] = std::string(500, 'z');
    (void)parse_state(j.dump(), "mem");
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()).find(std::string(81, 'z')), std::string::npos) << e.what();
  }
  // a Luding state is not a plastic one, and a plastic state needs the plastic model
  DynamicOptions luding;
  EXPECT_THROW(DynamicSolver(parse_state(good.dump(), "mem"), luding), std::invalid_argument);
}
