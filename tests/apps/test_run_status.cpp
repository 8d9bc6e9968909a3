// The run status rules of netsolve (apps/netsolve/status.hpp) and the run-folder helpers of
// apps/common/output.hpp (README.md "Exit status", "Run folders").
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "../../apps/netsolve/status.hpp"
#include "output.hpp"

namespace fs = std::filesystem;
using netdem::app::netsolve::ConvergenceRecord;
using netdem::app::netsolve::ResidualGrowth;
using netdem::app::netsolve::RunStatus;

namespace {
int stop_at(const std::vector<double>& r, double tol, int* first = nullptr) {
  ResidualGrowth g;
  g.tol = tol;
  for (std::size_t k = 0; k < r.size(); ++k)
    if (g.add(static_cast<int>(k) + 1, r[k])) {
      if (first) *first = g.first_bad;
      return static_cast<int>(k) + 1;
    }
  return 0;
}

void touch(const fs::path& p, const std::string& text = "x\n") { std::ofstream(p) << text; }

struct TempDir {
  fs::path path;
  TempDir() {
    std::string t = (fs::temp_directory_path() / "netdem_run_status_XXXXXX").string();
    path = ::mkdtemp(t.data());
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};
}  // namespace

TEST(ResidualGrowth, StopsAGeometricDivergenceAtItsFifthGrowingIncrement) {
  // 0.01 converged-ish, then x2 per increment from increment 3 on
  std::vector<double> r = {0.01, 0.01, 0.04, 0.08, 0.16, 0.32, 0.64, 1.28};
  int first = 0;
  EXPECT_EQ(stop_at(r, 3e-3, &first), 7);  // increments 3..7 grew, 0.64 > 10 x 0.01 (increment 2)
  EXPECT_EQ(first, 3);
}

TEST(ResidualGrowth, KeepsARunThatClimbsToALevel) {
  // like the frictionless W = 40 run: x 6 over five growing increments, then flat
  std::vector<double> r = {0.029, 0.026, 0.030, 0.034, 0.057, 0.107, 0.141, 0.197, 0.215, 0.21, 0.22, 0.2, 0.21};
  EXPECT_EQ(stop_at(r, 3e-3), 0);
  // fluctuations around a level never stop
  std::vector<double> f;
  for (int k = 0; k < 200; ++k) f.push_back(0.6 + 0.05 * std::sin(0.7 * k));
  EXPECT_EQ(stop_at(f, 3e-3), 0);
  // growth below 10 x tol never stops
  std::vector<double> s = {1e-4, 2e-4, 4e-4, 8e-4, 1.6e-3, 3.2e-3, 6.4e-3, 1.28e-2, 2.5e-2};
  EXPECT_EQ(stop_at(s, 3e-3), 0);
}

TEST(ConvergenceRecord, ThresholdsOfExitThree) {
  auto judge = [](int n, int unconverged, double worst, bool last_ok) {
    ConvergenceRecord c;
    c.tol = 3e-3;
    for (int k = 1; k <= n; ++k) {
      const bool conv = k > unconverged || (k == n && last_ok);
      c.add(k, k == n ? last_ok : conv, k == 1 ? worst : 1e-3);
    }
    RunStatus s;
    c.judge(s, "");
    return s;
  };
  EXPECT_TRUE(judge(100, 0, 1e-3, true).ok());
  EXPECT_TRUE(judge(100, 5, 0.03, true).ok());            // 5 % and exactly 10 x tol: still ok
  EXPECT_EQ(judge(100, 6, 1e-3, true).status, "unconverged");  // more than 5 %
  EXPECT_EQ(judge(100, 1, 0.031, true).status, "unconverged"); // one residual above 10 x tol
  EXPECT_EQ(judge(100, 0, 1e-3, false).status, "unconverged"); // the last increment
  EXPECT_EQ(judge(100, 6, 1e-3, true).exit_code(false), 3);
  EXPECT_EQ(judge(100, 6, 1e-3, true).exit_code(true), 0);
  RunStatus u;
  u.add("unconverged", "a");
  u.add("unstable", "b");
  u.add("incomplete", "c");
  EXPECT_EQ(u.status, "unstable");  // the worst wins
  EXPECT_EQ(u.reason(), "a; b; c");
  RunStatus i;
  i.add("incomplete", "validity limit");
  EXPECT_EQ(i.exit_code(false), 0);
}

TEST(RunDir, MarkerFirstRemovedLastAndForeignFoldersRefused) {
  TempDir t;
  const fs::path d = t.path / "run";
  netdem::app::RunDirOptions o;
  netdem::app::check_run_dir(d, o);  // a new folder: fine, nothing created
  EXPECT_FALSE(fs::exists(d));
  netdem::app::open_run_dir(d, "netsolve compact --out run", o);
  EXPECT_TRUE(fs::exists(d / ".incomplete"));
  EXPECT_TRUE(fs::exists(d / "command.txt"));
  EXPECT_TRUE(netdem::app::run_dir_opened());
  touch(d / "summary.json");
  fs::create_directory(d / "probes");
  touch(d / "probes" / "probe_000.json");
  touch(d / "state.txt");
  netdem::app::close_run_dir(d);
  EXPECT_FALSE(fs::exists(d / ".incomplete"));
  touch(d / "notes.txt");  // the user's, after the run
  // another run into it: refused, nothing touched
  EXPECT_THROW(netdem::app::check_run_dir(d, o), netdem::app::UsageError);
  EXPECT_THROW(netdem::app::open_run_dir(d, "second", o), netdem::app::UsageError);
  EXPECT_TRUE(fs::exists(d / "summary.json"));
  // --overwrite clears the old run's files (and probes/), keeps nothing of the old run but the user's
  o.overwrite = true;
  netdem::app::open_run_dir(d, "second", o);
  EXPECT_FALSE(fs::exists(d / "summary.json"));
  EXPECT_FALSE(fs::exists(d / "state.txt"));
  EXPECT_FALSE(fs::exists(d / "probes"));
  EXPECT_TRUE(fs::exists(d / "notes.txt"));
  EXPECT_TRUE(fs::exists(d / ".incomplete"));
  std::ifstream in(d / "command.txt");
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "second");
}

TEST(RunDir, OverwriteIsConservative) {
  TempDir t;
  netdem::app::RunDirOptions o;
  o.overwrite = true;
  // summary.json but no command.txt or .incomplete: not a netdem run folder
  const fs::path a = t.path / "a";
  fs::create_directory(a);
  touch(a / "summary.json");
  EXPECT_THROW(netdem::app::check_run_dir(a, o), netdem::app::UsageError);
  // an unknown subfolder
  touch(a / "command.txt");
  fs::create_directory(a / "mine");
  EXPECT_THROW(netdem::app::check_run_dir(a, o), netdem::app::UsageError);
  fs::remove(a / "mine");
  netdem::app::check_run_dir(a, o);  // now clearable
  // an input inside it
  o.inputs = {a / "packing.csv"};
  EXPECT_THROW(netdem::app::check_run_dir(a, o), netdem::app::UsageError);
  o.inputs.clear();
  // the current folder and its parents
  const fs::path cwd = fs::current_path();
  fs::current_path(a);
  EXPECT_THROW(netdem::app::check_run_dir(".", o), netdem::app::UsageError);
  fs::current_path(cwd);
  // an unrelated folder is used as it is and keeps its files
  const fs::path b = t.path / "b";
  fs::create_directory(b);
  touch(b / "notes.txt");
  netdem::app::RunDirOptions plain;
  netdem::app::open_run_dir(b, "run", plain);
  EXPECT_TRUE(fs::exists(b / "notes.txt"));
  // a file as --out
  touch(t.path / "f");
  EXPECT_THROW(netdem::app::check_run_dir(t.path / "f", plain), netdem::app::UsageError);
}

namespace {
/// A marker as open_run_dir writes it, for process `pid` started at `ticks` (field 22 of /proc/PID/stat).
void write_marker(const fs::path& d, long pid, const std::string& ticks) {
  std::ifstream b("/proc/sys/kernel/random/boot_id");
  std::string boot;
  std::getline(b, boot);
  char host[256] = "";
  ::gethostname(host, sizeof host - 1);
  std::ofstream m(d / ".incomplete");
  m << "unfinished netdem run (running, failed or killed): pid " << pid << ", started 2026-01-01T00:00:00Z\n"
    << "netsolve sinter --out x\nprocess " << ticks << " boot " << boot << " host " << host << "\nbefore: 0 entries\n";
}
std::string own_start_ticks() {
  std::ifstream in("/proc/self/stat");
  std::string s;
  std::getline(in, s);
  std::istringstream f(s.substr(s.rfind(')') + 2));
  std::string w;
  for (int field = 3; field <= 22; ++field) f >> w;
  return w;
}
}  // namespace

TEST(RunDir, LiveRunRefusedEvenWithOverwriteStaleMarkerCleared) {
  TempDir t;
  const fs::path d = t.path / "run";
  fs::create_directory(d);
  netdem::app::RunDirOptions o;
  o.overwrite = true;
  // held by a live process (this one): refused with its pid, nothing touched
  write_marker(d, ::getpid(), own_start_ticks());
  try {
    netdem::app::check_run_dir(d, o);
    ADD_FAILURE() << "a live run's folder was accepted";
  } catch (const netdem::app::UsageError& e) {
    EXPECT_NE(std::string(e.what()).find(fmt::format("pid {}", ::getpid())), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("still running"), std::string::npos) << e.what();
  }
  EXPECT_THROW(netdem::app::open_run_dir(d, "second", o), netdem::app::UsageError);
  EXPECT_TRUE(fs::exists(d / ".incomplete"));
  // the same pid with another start time: the pid was reused, the marker is stale
  write_marker(d, ::getpid(), own_start_ticks() + "1");
  netdem::app::check_run_dir(d, o);
  // a dead process: stale, may be overwritten
  const pid_t child = ::fork();
  if (child == 0) ::_exit(0);
  ::waitpid(child, nullptr, 0);
  write_marker(d, child, "1");
  netdem::app::check_run_dir(d, o);
  touch(d / "state.txt");  // the killed run's
  touch(d / "my.dat");     // not a name a run writes
  touch(d / ".summary.json.tmp0123abcd");  // write_file_atomic's temporary, left by the kill
  netdem::app::open_run_dir(d, "second", o);
  EXPECT_FALSE(fs::exists(d / "state.txt"));
  EXPECT_FALSE(fs::exists(d / ".summary.json.tmp0123abcd"));
  EXPECT_TRUE(fs::exists(d / "my.dat"));
  std::ifstream in(d / ".incomplete");
  std::string first;
  std::getline(in, first);
  EXPECT_NE(first.find(fmt::format("pid {},", ::getpid())), std::string::npos) << first;
  // ... and without --overwrite a stale marker is still another run's folder
  netdem::app::close_run_dir(d);
  EXPECT_TRUE(fs::exists(d / ".netdem-files"));
  o.overwrite = false;
  EXPECT_THROW(netdem::app::check_run_dir(d, o), netdem::app::UsageError);
}

// command.txt is a command a shell reruns: an empty argument, spaces and quotes survive the round
// trip through `sh -c` (each argument comes back as it was given), plain arguments stay unquoted.
TEST(ShellCommand, RoundTripsThroughTheShell) {
  const std::vector<std::string> args = {"netsolve", "compact", "--snapshots", "", "--out", "a b/it's", "--x=1,2", "$HOME", "*"};
  std::vector<const char*> argv;
  for (const auto& a : args) argv.push_back(a.c_str());
  const std::string cmd = netdem::app::shell_command(static_cast<int>(argv.size()), argv.data());
  EXPECT_EQ(cmd.rfind("netsolve compact --snapshots '' --out ", 0), 0u) << cmd;
  // the shell prints each argument on its own line, in brackets
  const fs::path d = fs::temp_directory_path() / fmt::format("netdem_shell_{}", ::getpid());
  fs::create_directories(d);
  {
    std::ofstream f(d / "run.sh");
    f << "show() { for a in \"$@\"; do printf '[%s]\\n' \"$a\"; done; }\nshow " << cmd.substr(cmd.find(' ') + 1) << "\n";
  }
  const std::string got_path = (d / "got.txt").string();
  ASSERT_EQ(std::system(fmt::format("sh {} > {}", (d / "run.sh").string(), got_path).c_str()), 0);
  std::ifstream in(got_path);
  std::stringstream got;
  got << in.rdbuf();
  std::string want;
  for (std::size_t k = 1; k < args.size(); ++k) want += "[" + args[k] + "]\n";
  EXPECT_EQ(got.str(), want);
  fs::remove_all(d);
}
