// Replays the state-file inputs of tests/fuzz/regressions/state/ (issue 13 item 5): every file
// either parses or is refused with one std::invalid_argument line naming the file line; a parsed
// state then runs a few thousand steps, ending normally or at a detected instability, never with
// a non-finite state. Files named refuse_* must be refused, ok_* must parse and run. A fuzz target
// for the reader is netdem::dem::read_state on the input bytes (the same contract).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

#include "netdem/dynamic/solver.hpp"
#include "netdem/dynamic/state.hpp"

using namespace netdem::dem;

namespace {

namespace fs = std::filesystem;

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

/// The contract of a fuzz target: "refused", "parsed" (and ran), or a test failure.
std::string replay(const std::string& bytes, std::string& message) {
  std::istringstream in(bytes);
  SolverState st;
  try {
    st = read_state(in);
  } catch (const std::invalid_argument& e) {
    message = e.what();
    return "refused";
  }
  DynamicOptions o;
  o.check_every = 100;
  try {
    DynamicSolver s(st, o);
    for (int k = 0; k < 2000; ++k) s.step();
    s.check_health();
  } catch (const InstabilityError& e) {
    message = e.what();
  } catch (const std::invalid_argument& e) {
    message = e.what();
  }
  return "parsed";
}

}  // namespace

TEST(StateRegressions, EveryFileParsesOrIsRefusedOnOneLine) {
  const fs::path dir = NETDEM_STATE_REGRESSIONS;
  ASSERT_TRUE(fs::is_directory(dir)) << dir;
  int files = 0, refused = 0;
  // "state:<digits>: " at the start (no std::regex: GCC 12's -Wmaybe-uninitialized false positive
  // in <regex> under ASan + -O2 -Werror)
  auto names_line = [](const std::string& m) {
    const std::string head = "state:";
    if (m.rfind(head, 0) != 0) return false;
    std::size_t k = head.size(), digits = 0;
    while (k < m.size() && m[k] >= '0' && m[k] <= '9') ++k, ++digits;
    return digits > 0 && m.compare(k, 2, ": ") == 0;
  };
  for (const auto& e : fs::directory_iterator(dir)) {
    if (!e.is_regular_file()) continue;
    ++files;
    const std::string name = e.path().filename().string();
    std::string msg;
    const std::string got = replay(slurp(e.path()), msg);
    if (got == "refused") {
      ++refused;
      EXPECT_EQ(msg.find('\n'), std::string::npos) << name << ": " << msg;
      EXPECT_TRUE(names_line(msg)) << name << ": the message names no line: " << msg;
      EXPECT_EQ(msg.find("state:0:"), std::string::npos) << name << ": " << msg;
      EXPECT_LT(msg.size(), 400u) << name;
    }
    if (name.rfind("refuse_", 0) == 0) {
      EXPECT_EQ(got, "refused") << name;
    }
    if (name.rfind("ok_", 0) == 0) {
      EXPECT_EQ(got, "parsed") << name << ": " << msg;
    }
  }
  EXPECT_GE(files, 15);
  EXPECT_GE(refused, 14);
}

TEST(StateRegressions, ReproducersNameTheirProblem) {
  const fs::path dir = NETDEM_STATE_REGRESSIONS;
  const std::pair<const char*, const char*> cases[] = {
      {"refuse_wall_mass_zero.txt", "mass > 0"},
      {"refuse_same_position.txt", "below the larger radius"},
      {"refuse_far_outside.txt", "outside the box"},
      {"refuse_radius_1e300.txt", "a0 / 100"},
      {"refuse_velocity_1e300.txt", "0.1 r_min"},
      {"refuse_pressure_1e12.txt", "2p/k2"},
      {"refuse_below_absolute_zero.txt", "absolute zero"},
      {"refuse_binary_first_line.txt", "state:1:"},
  };
  for (const auto& [file, needle] : cases) {
    std::string msg;
    EXPECT_EQ(replay(slurp(dir / file), msg), "refused") << file;
    EXPECT_NE(msg.find(needle), std::string::npos) << file << ": " << msg;
    for (char c : msg) EXPECT_FALSE(static_cast<unsigned char>(c) < 0x20) << file << ": control character";
  }
}
