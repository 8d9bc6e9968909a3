// Replays the state-file inputs of tests/fuzz/regressions/state/ (issue 13 item 5; converted to the
// state archive of issue 26 by apps/scripts/convert_state.py): every file either parses or is
// refused with one std::invalid_argument line naming the field (its JSON pointer); a parsed
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
  if (st.plastic_law()) o.model = ContactModel::PlasticIndentation;
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
  // "state: /<pointer>: " at the start (no std::regex: GCC 12's -Wmaybe-uninitialized false
  // positive in <regex> under ASan + -O2 -Werror)
  auto names_field = [](const std::string& m) {
    const std::string head = "state: /";
    if (m.rfind(head, 0) != 0) return false;
    const auto colon = m.find(": ", head.size());
    return colon != std::string::npos && m.find(' ', head.size()) > colon;
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
      EXPECT_TRUE(names_field(msg)) << name << ": the message names no field: " << msg;
      EXPECT_LT(msg.size(), 400u) << name;
    }
    if (name.rfind("refuse_", 0) == 0) {
      EXPECT_EQ(got, "refused") << name;
    }
    if (name.rfind("ok_", 0) == 0) {
      EXPECT_EQ(got, "parsed") << name << ": " << msg;
    }
  }
  EXPECT_GE(files, 25);
  EXPECT_GE(refused, 22);
}

TEST(StateRegressions, ReproducersNameTheirProblem) {
  const fs::path dir = NETDEM_STATE_REGRESSIONS;
  const std::pair<const char*, const char*> cases[] = {
      {"refuse_wall_mass_zero.json", "/moving_walls/0: a stress-controlled wall needs mass > 0"},
      {"refuse_same_position.json", "below the larger radius"},
      {"refuse_far_outside.json", "outside the box"},
      {"refuse_radius_1e300.json", "/particles/radius/0: radius must be within [L / 100, 100 L]"},
      {"refuse_velocity_1e300.json", "0.1 r_min"},
      {"refuse_pressure_1e12.json", "/pressure: loading ratio 2p/k2"},
      {"refuse_below_absolute_zero.json", "/thermal/T: T = "},
      {"refuse_binary_first_line.bin", "state: /: not a JSON state archive"},
      {"refuse_old_text_format.txt", "state: /: an old text state file (before issue 26): convert it with"},
      {"refuse_truncated.json", "state: /: not a JSON state archive (syntax error at byte"},
      {"refuse_nan.json", "expected a number, found string \"nan\""},
      {"refuse_plastic_u_max_negative.json", "/pairs/history/0/u_max: -0.001 is below 0"},
      {"refuse_plastic_mu_nan.json", "/plastic_indentation/mu: expected a number, \"inf\" or \"-inf\""},
      {"refuse_plastic_wall_f_t_size.json", "/wall_contacts/history/0/f_t: expected 3 elements, found 2"},
  };
  for (const auto& [file, needle] : cases) {
    std::string msg;
    EXPECT_EQ(replay(slurp(dir / file), msg), "refused") << file;
    EXPECT_NE(msg.find(needle), std::string::npos) << file << ": " << msg;
    for (char c : msg) EXPECT_FALSE(static_cast<unsigned char>(c) < 0x20) << file << ": control character";
  }
}
