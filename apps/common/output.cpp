#include "output.hpp"
#include "run_status.hpp"
#include "scene_file.hpp"

#include "netdem/packing/io.hpp"

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <set>
#include <sstream>
#include <random>
#include <stdexcept>
#include <utility>

#include <fmt/format.h>

namespace netdem::app {

std::string shell_command(int argc, const char* const* argv) {
  std::string out;
  for (int k = 0; k < argc; ++k) {
    const std::string a = argv[k];
    const bool plain = !a.empty() && a.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789"
                                                         "_-+=.,:/@%") == std::string::npos;
    if (k) out += ' ';
    if (plain) {
      out += a;
      continue;
    }
    out += '\'';
    for (char c : a) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
    out += '\'';
  }
  return out;
}

void write_file_atomic(const std::filesystem::path& path, const std::string& text) {
  namespace fs = std::filesystem;
  const fs::path dir = path.has_parent_path() ? path.parent_path() : fs::path(".");
  std::random_device rd;
  const fs::path tmp = dir / fmt::format(".{}.tmp{:08x}", path.filename().string(), rd());
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error(fmt::format("cannot write '{}': cannot create a file in '{}'", path.string(), dir.string()));
    out.write(text.data(), static_cast<std::streamsize>(text.size()));
    out.flush();
    if (!out) {
      std::error_code ec;
      fs::remove(tmp, ec);
      throw std::runtime_error(fmt::format("cannot write '{}': write failed (disk full?)", path.string()));
    }
  }
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) {
    fs::remove(tmp, ec);
    throw std::runtime_error(fmt::format("cannot write '{}': {}", path.string(), ec.message()));
  }
}

void make_output_dir(const std::filesystem::path& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec || !std::filesystem::is_directory(dir))
    throw std::runtime_error(fmt::format("cannot create output folder '{}': {}", dir.string(),
                                         ec ? ec.message() : "not a directory"));
}

double mem_available() {
  std::ifstream in("/proc/meminfo");
  std::string key, unit;
  double kb = 0.0;
  while (in >> key >> kb >> unit)
    if (key == "MemAvailable:") return kb * 1024.0;
  return 0.0;
}

// ---- run folders ------------------------------------------------------------------------------
namespace {
namespace fs = std::filesystem;
bool g_run_dir_opened = false;

/// The record a run leaves of its own files (written by close_run_dir), one name a line.
constexpr const char* kFilesRecord = ".netdem-files";

/// At most 80 printable characters of `s`, for messages (the readers' quoting rule).
std::string quoted(const std::string& s) { return netdem::packing::quote_input(s, 80); }

/// The first line of dir/command.txt (the run that wrote the folder), or "".
std::string recorded_command(const fs::path& dir) {
  std::ifstream in(dir / "command.txt");
  std::string line;
  std::getline(in, line);
  return line;
}

/// The first line of a small text file (/proc, the boot id), or "".
std::string first_line_of(const fs::path& p) {
  std::ifstream in(p);
  std::string line;
  std::getline(in, line);
  return line;
}

std::string host_name() {
  char h[256] = "";
  if (::gethostname(h, sizeof h - 1) != 0) return "";
  return h;
}

/// State and start time (field 22 of /proc/PID/stat, clock ticks since boot) of a process, or
/// false if it cannot be read.
bool process_start(long pid, char& state, unsigned long long& start) {
  const std::string s = first_line_of(fmt::format("/proc/{}/stat", pid));
  const auto close = s.rfind(')');  // the command name may hold spaces and parentheses
  if (close == std::string::npos) return false;
  std::istringstream in(s.substr(close + 1));
  std::string f;
  if (!(in >> state)) return false;
  for (int field = 4; field < 22; ++field)
    if (!(in >> f)) return false;
  return static_cast<bool>(in >> start);
}

/// What .incomplete says of the run that wrote it.
struct Marker {
  long pid = 0;
  std::string started;                ///< wall clock, as written
  bool has_start = false;             ///< the process start time was recorded (this version on)
  unsigned long long start_ticks = 0;
  std::string boot_id, host;
  bool has_kept = false;              ///< the entries the folder held before the run were recorded
  std::set<std::string> kept;
};

Marker read_marker(const fs::path& dir) {
  Marker m;
  std::ifstream in(dir / kIncompleteMarker);
  std::string line;
  if (std::getline(in, line)) {
    if (const auto p = line.find(": pid "); p != std::string::npos) m.pid = std::atol(line.c_str() + p + 6);
    if (const auto p = line.find(", started "); p != std::string::npos) m.started = line.substr(p + 10);
  }
  std::getline(in, line);  // the command
  while (std::getline(in, line)) {
    std::istringstream f(line);
    std::string key;
    f >> key;
    if (key == "process") {
      std::string w;
      f >> m.start_ticks >> w >> m.boot_id >> w >> m.host;
      m.has_start = !f.fail();
    } else if (key == "before:") {
      m.has_kept = true;
    } else if (key == "keep" && line.size() > 5) {
      m.kept.insert(line.substr(5));
    }
  }
  return m;
}

/// Why the run of dir/.incomplete may still be running ("" if it is gone: its process is dead, or
/// its pid now belongs to another process, or the machine has been restarted since).
std::string live_holder(const fs::path& dir, const std::string& name) {
  if (!fs::exists(dir / kIncompleteMarker)) return "";
  const Marker m = read_marker(dir);
  if (m.pid <= 0 || m.pid > (1L << 22)) return "";  // no pid (above Linux's pid_max limit): not a marker a run wrote
  const std::string marker = quoted((dir / kIncompleteMarker).string());
  const std::string when = m.started.empty() ? "" : fmt::format(", started {}", quoted(m.started));
  if (m.has_start && m.host != host_name())
    return fmt::format("--out '{}' is held by a run on the machine '{}' (pid {}{}); if `ps -p {}` on that machine "
                       "shows no such process, the run is gone: remove '{}' and run again",
                       name, quoted(m.host), m.pid, when, m.pid, marker);
  if (m.has_start && !m.boot_id.empty() && m.boot_id != first_line_of("/proc/sys/kernel/random/boot_id")) return "";
  if (::kill(static_cast<pid_t>(m.pid), 0) != 0 && errno == ESRCH) return "";
  char state = '?';
  unsigned long long start = 0;
  if (process_start(m.pid, state, start)) {
    if (state == 'Z' || state == 'X') return "";          // dead, not yet reaped
    if (m.has_start && start != m.start_ticks) return "";  // the pid was reused by another process
  }
  return fmt::format("--out '{}' is held by a run that is still running (pid {}{}), with or without --overwrite: "
                     "wait for it to end or stop it, or choose another folder (the run is gone when `ps -p {}` shows "
                     "no such process{})",
                     name, m.pid, when, m.pid, m.has_start ? "" : fmt::format(" or not a netdem run; then remove '{}'", marker));
}

/// True for the names a netdem run writes into its folder (folders of older versions, killed runs).
bool netdem_name(const std::string& n) {
  static const std::set<std::string> exact = {"command.txt", "summary.json", kIncompleteMarker, kFilesRecord,
                                              "parameters.json", "report.md", "probes", "scene.toml"};
  if (exact.count(n) != 0U) return true;
  const auto ends = [&](const char* e) {
    const std::string s(e);
    return n.size() > s.size() && n.compare(n.size() - s.size(), s.size(), s) == 0;
  };
  if (ends(".csv") || ends(".vtp") || ends(".pvd") || ends(".svg")) return true;  // .svg: plots of versions before issue 26
  if (n.size() > 1 && n[0] == '.' && n.find(".tmp") != std::string::npos) return true;  // write_file_atomic's, of a killed run
  return n.rfind("state", 0) == 0 && ends(".txt");
}

/// The top-level entries of `dir` (names).
std::set<std::string> entries(const fs::path& dir) {
  std::set<std::string> s;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) s.insert(e.path().filename().string());
  return s;
}

/// The entries of `dir` that its old run wrote: the run's own record if it finished; if it was
/// killed or failed, the netdem names it did not find there; for a folder of an older version
/// (neither record), the netdem names.
std::vector<std::string> old_run_files(const fs::path& dir) {
  std::vector<std::string> out;
  const auto now = entries(dir);
  if (fs::exists(dir / kIncompleteMarker)) {
    const Marker m = read_marker(dir);
    for (const auto& n : now)
      if (netdem_name(n) && (!m.has_kept || m.kept.count(n) == 0U)) out.push_back(n);
    return out;
  }
  std::ifstream in(dir / kFilesRecord);
  if (in) {
    std::set<std::string> listed = {kFilesRecord, "command.txt", "summary.json"};
    std::string line;
    while (std::getline(in, line))
      if (!line.empty()) listed.insert(line);
    for (const auto& n : now)
      if (listed.count(n) != 0U) out.push_back(n);
    return out;
  }
  for (const auto& n : now)
    if (netdem_name(n)) out.push_back(n);
  return out;
}

/// The canonical form of p, or p made absolute and normal if it does not exist.
fs::path canonical_or_absolute(const fs::path& p) {
  std::error_code ec;
  fs::path c = fs::weakly_canonical(p, ec);
  if (ec) c = fs::absolute(p, ec).lexically_normal();
  return c;
}

/// True if `inner` is `outer` or lies below it (both canonical).
bool lies_in(const fs::path& inner, const fs::path& outer) {
  auto i = inner.begin();
  for (auto o = outer.begin(); o != outer.end(); ++o, ++i) {
    if (o->empty()) continue;  // a trailing separator
    if (i == inner.end() || *i != *o) return false;
  }
  return true;
}

/// Why `dir` (a folder that holds a run) must not be cleared, or "" if it may be. Conservative:
/// never /, the home folder, the current folder or one of its parents; only top-level files and a
/// probes/ folder of files (what netsolve and demsolve write); no input of this run inside.
std::string why_not_clear(const fs::path& dir, const RunDirOptions& o) {
  const fs::path c = canonical_or_absolute(dir);
  if (c == c.root_path()) return "it is the root folder";
  if (const char* home = std::getenv("HOME"); home != nullptr && *home != '\0' && c == canonical_or_absolute(home))
    return "it is the home folder";
  std::error_code ec;
  const fs::path cwd = fs::current_path(ec);
  if (!ec && lies_in(canonical_or_absolute(cwd), c)) return "it is the current folder or one of its parents";
  if (!fs::is_regular_file(dir / "command.txt") && !fs::exists(dir / kIncompleteMarker))
    return "it has no command.txt or .incomplete, so it does not look like a netdem run folder";
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    const auto st = e.symlink_status();
    if (fs::is_regular_file(st) || fs::is_symlink(st)) continue;
    if (fs::is_directory(st) && e.path().filename() == "probes") {
      for (const auto& f : fs::directory_iterator(e.path(), ec))
        if (!fs::is_regular_file(f.symlink_status()) && !fs::is_symlink(f.symlink_status()))
          return fmt::format("its probes/ folder holds '{}', which no netdem run writes", quoted(f.path().filename().string()));
      continue;
    }
    return fmt::format("it holds '{}', which is not a file a netdem run writes", quoted(e.path().filename().string()));
  }
  if (ec) return fmt::format("it cannot be listed: {}", ec.message());
  for (const auto& in : o.inputs) {
    if (in.empty()) continue;
    if (lies_in(canonical_or_absolute(in), c)) return fmt::format("the input '{}' lies in it", quoted(in.string()));
  }
  return "";
}
}  // namespace

bool holds_run(const std::filesystem::path& dir) {
  std::error_code ec;
  return fs::exists(dir / "command.txt", ec) || fs::exists(dir / "summary.json", ec) || fs::exists(dir / kIncompleteMarker, ec);
}

void check_run_dir(const std::filesystem::path& dir, const RunDirOptions& o) {
  if (dir.empty()) throw UsageError("--out is empty: give an output folder");
  const std::string name = quoted(dir.string());
  std::error_code ec;
  const auto st = fs::status(dir, ec);
  if (fs::exists(st)) {
    if (!fs::is_directory(st)) throw UsageError(fmt::format("--out '{}' exists and is not a folder", name));
    if (::access(dir.c_str(), W_OK | X_OK) != 0)
      throw UsageError(fmt::format("cannot write into the output folder '{}': {}", name, std::strerror(errno)));
    if (!holds_run(dir)) return;  // empty, or only files no run wrote: nothing to mix with
    if (const std::string live = live_holder(dir, name); !live.empty()) throw UsageError(live);
    const std::string cmd = recorded_command(dir);
    const std::string which = cmd.empty() ? (fs::exists(dir / kIncompleteMarker) ? "an unfinished run" : "another run")
                                          : fmt::format("the run '{}'", quoted(cmd));
    if (!o.overwrite)
      throw UsageError(fmt::format("--out '{}' holds the files of {}; pass {} to replace them, or choose another folder", name,
                                   which, o.overwrite_flag));
    const std::string why = why_not_clear(dir, o);
    if (!why.empty()) throw UsageError(fmt::format("{} will not clear '{}': {}", o.overwrite_flag, name, why));
    return;
  }
  // a new folder: its nearest existing parent must be a folder we can write into
  fs::path p = canonical_or_absolute(dir).parent_path();
  while (!p.empty() && !fs::exists(p, ec) && p != p.root_path()) p = p.parent_path();
  if (!p.empty() && fs::exists(p, ec)) {
    if (!fs::is_directory(p, ec))
      throw UsageError(fmt::format("cannot create the output folder '{}': '{}' is not a folder", name, quoted(p.string())));
    if (::access(p.c_str(), W_OK | X_OK) != 0)
      throw UsageError(fmt::format("cannot create the output folder '{}': cannot write into '{}': {}", name, quoted(p.string()),
                                   std::strerror(errno)));
  }
}

namespace {
/// The text of .incomplete: who runs (pid, wall-clock start; process start time, boot and machine,
/// to tell a live run from a dead one whose pid was reused), the command, and the entries the
/// folder held before the run (the user's: --overwrite keeps them).
std::string marker_text(const std::string& command, const std::set<std::string>& kept) {
  const auto now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  char when[32] = "";
  std::tm tm{};
  if (gmtime_r(&now, &tm) != nullptr) std::strftime(when, sizeof when, "%Y-%m-%dT%H:%M:%SZ", &tm);
  std::string s = fmt::format("unfinished netdem run (running, failed or killed): pid {}, started {}\n{}\n", ::getpid(),
                              when, command);
  char state = '?';
  unsigned long long start = 0;
  if (process_start(::getpid(), state, start)) {
    const std::string boot = first_line_of("/proc/sys/kernel/random/boot_id");
    const std::string host = host_name();
    if (!boot.empty() && !host.empty() && boot.find(' ') == std::string::npos && host.find(' ') == std::string::npos)
      s += fmt::format("process {} boot {} host {}\n", start, boot, host);
  }
  s += fmt::format("before: {} entries\n", kept.size());
  for (const auto& k : kept)
    if (k.find('\n') == std::string::npos) s += "keep " + k + "\n";
  return s;
}

/// Writes the marker: created exclusively if the folder had none (a run that started at the same
/// moment is caught by check_run_dir again), replaced if it had a stale one.
void write_marker(const fs::path& dir, const std::string& text, bool had_marker, const RunDirOptions& o) {
  const fs::path m = dir / kIncompleteMarker;
  if (!had_marker) {
    const int fd = ::open(m.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (fd < 0 && errno == EEXIST) {
      check_run_dir(dir, o);  // throws for a live run, or without overwrite
      write_file_atomic(m, text);
      return;
    }
    if (fd < 0)
      throw std::runtime_error(fmt::format("cannot write into the output folder '{}': {}", quoted(dir.string()),
                                           std::strerror(errno)));
    const bool ok = ::write(fd, text.data(), text.size()) == static_cast<ssize_t>(text.size());
    const int err = errno;
    ::close(fd);
    if (!ok)
      throw std::runtime_error(fmt::format("cannot write into the output folder '{}': {}", quoted(dir.string()),
                                           std::strerror(err ? err : EIO)));
    return;
  }
  write_file_atomic(m, text);
}

/// One line on stderr: what --overwrite removed (and what it kept).
void report_removed(const fs::path& dir, const std::vector<std::string>& removed, const std::set<std::string>& kept) {
  std::string names;
  std::size_t shown = 0;
  for (const auto& n : removed) {
    if (n == kIncompleteMarker || n == kFilesRecord) continue;
    if (shown < 12) names += (shown == 0 ? "" : ", ") + quoted(n) + (fs::is_directory(dir / n) ? "/" : "");
    ++shown;
  }
  if (shown > 12) names += fmt::format(", ... ({} in all)", shown);
  std::string keep;
  std::size_t k = 0;
  for (const auto& n : kept)
    if (k++ < 5) keep += (k == 1 ? "" : ", ") + quoted(n);
  if (kept.size() > 5) keep += ", ...";
  std::fprintf(stderr, "%s: --overwrite removed the earlier run's files from '%s': %s%s\n", program_invocation_short_name,
               quoted(dir.string()).c_str(), shown == 0 ? "none" : names.c_str(),
               kept.empty() ? "" : fmt::format("; kept {} other{}: {}", kept.size(), kept.size() == 1 ? "" : "s", keep).c_str());
}
}  // namespace

void open_run_dir(const std::filesystem::path& dir, const std::string& command, const RunDirOptions& o) {
  check_run_dir(dir, o);
  const bool clear = o.overwrite && holds_run(dir);
  const bool had_marker = fs::exists(dir / kIncompleteMarker);
  const std::vector<std::string> old = clear ? old_run_files(dir) : std::vector<std::string>{};
  make_output_dir(dir);
  std::set<std::string> kept = entries(dir);  // the user's: what the old run did not write
  for (const auto& n : old) kept.erase(n);
  kept.erase(kIncompleteMarker);
  // the marker first: from here on the folder is an unfinished run until close_run_dir
  write_marker(dir, marker_text(command, kept), had_marker, o);
  if (clear) {  // why_not_clear allowed it: top-level files and probes/
    std::error_code ec;
    for (const auto& n : old) {
      if (n == kIncompleteMarker) continue;
      const fs::path p = dir / n;
      if (fs::is_directory(fs::symlink_status(p))) {
        fs::remove_all(p, ec);
      } else {
        fs::remove(p, ec);
      }
      if (ec) throw std::runtime_error(fmt::format("cannot clear '{}': {}: {}", quoted(dir.string()), quoted(p.string()), ec.message()));
    }
    report_removed(dir, old, kept);
  }
  write_file_atomic(dir / "command.txt", command + "\n");
  if (!scene_text().empty()) write_file_atomic(dir / "scene.toml", scene_text());
  g_run_dir_opened = true;
}

void close_run_dir(const std::filesystem::path& dir) {
  std::error_code ec;
  if (!fs::exists(dir / kIncompleteMarker, ec)) return;
  // the record of the run's own files: what the folder holds now and did not hold before the run
  const Marker m = read_marker(dir);
  if (m.has_kept) {
    std::string list;
    for (const auto& n : entries(dir))
      if (n != kIncompleteMarker && n != kFilesRecord && m.kept.count(n) == 0U && n.find('\n') == std::string::npos &&
          n.rfind(".", 0) != 0)
        list += n + "\n";
    write_file_atomic(dir / kFilesRecord, list);
  }
  fs::remove(dir / kIncompleteMarker, ec);
  if (ec) throw std::runtime_error(fmt::format("cannot remove '{}': {}", (dir / kIncompleteMarker).string(), ec.message()));
}

bool run_dir_opened() { return g_run_dir_opened; }

std::string& scene_text() {
  static std::string text;
  return text;
}

void reset_run_state() {
  g_run_dir_opened = false;
  scene_text().clear();
  activity() = "starting";
}

std::function<void(double)>& progress_hook() {
  static std::function<void(double)> hook;
  return hook;
}

namespace {
void append_fields(std::string& s, const std::vector<Field>& fields) {
  for (const auto& f : fields) {
    s += fmt::format("        <DataArray type=\"Float64\" Name=\"{}\" NumberOfComponents=\"{}\" format=\"ascii\">\n          ",
                     f.name, f.components);
    for (double v : f.values) s += fmt::format("{:.9g} ", v);
    s += "\n        </DataArray>\n";
  }
}
void append_points(std::string& s, const std::vector<double>& x, const std::vector<double>& y,
                   const std::vector<double>* z = nullptr) {
  s += "      <Points>\n        <DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n          ";
  if (z) {
    for (std::size_t p = 0; p < x.size(); ++p) s += fmt::format("{:.12g} {:.12g} {:.12g} ", x[p], y[p], (*z)[p]);
  } else {
    for (std::size_t p = 0; p < x.size(); ++p) s += fmt::format("{:.12g} {:.12g} 0 ", x[p], y[p]);
  }
  s += "\n        </DataArray>\n      </Points>\n";
}
}  // namespace

std::string vtp_particles(const std::vector<double>& x, const std::vector<double>& y, const std::vector<Field>& pd) {
  return vtp_particles_3d(x, y, nullptr, pd);
}

std::string vtp_particles_3d(const std::vector<double>& x, const std::vector<double>& y, const std::vector<double>* z,
                             const std::vector<Field>& pd) {
  std::string s = "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <PolyData>\n";
  s += fmt::format("    <Piece NumberOfPoints=\"{}\" NumberOfVerts=\"{}\" NumberOfLines=\"0\" NumberOfStrips=\"0\" NumberOfPolys=\"0\">\n",
                   x.size(), x.size());
  append_points(s, x, y, z);
  s += "      <PointData>\n";
  append_fields(s, pd);
  s += "      </PointData>\n      <Verts>\n        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n          ";
  for (std::size_t p = 0; p < x.size(); ++p) s += fmt::format("{} ", p);
  s += "\n        </DataArray>\n        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n          ";
  for (std::size_t p = 0; p < x.size(); ++p) s += fmt::format("{} ", p + 1);
  s += "\n        </DataArray>\n      </Verts>\n    </Piece>\n  </PolyData>\n</VTKFile>\n";
  return s;
}

std::string vtp_network(const std::vector<double>& x, const std::vector<double>& y, const std::vector<int>& i,
                        const std::vector<int>& j, const std::vector<Field>& cd) {
  return vtp_network_3d(x, y, nullptr, i, j, cd);
}

std::string vtp_network_3d(const std::vector<double>& x, const std::vector<double>& y, const std::vector<double>* z,
                           const std::vector<int>& i, const std::vector<int>& j, const std::vector<Field>& cd) {
  std::string s = "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <PolyData>\n";
  s += fmt::format("    <Piece NumberOfPoints=\"{}\" NumberOfVerts=\"0\" NumberOfLines=\"{}\" NumberOfStrips=\"0\" NumberOfPolys=\"0\">\n",
                   x.size(), i.size());
  append_points(s, x, y, z);
  s += "      <CellData>\n";
  append_fields(s, cd);
  s += "      </CellData>\n      <Lines>\n        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n          ";
  for (std::size_t k = 0; k < i.size(); ++k) s += fmt::format("{} {} ", i[k], j[k]);
  s += "\n        </DataArray>\n        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n          ";
  for (std::size_t k = 0; k < i.size(); ++k) s += fmt::format("{} ", 2 * (k + 1));
  s += "\n        </DataArray>\n      </Lines>\n    </Piece>\n  </PolyData>\n</VTKFile>\n";
  return s;
}

namespace {
/// `s` as an XML attribute value (the names the tools write need none of this).
std::string xml_attribute(const std::string& s) {
  std::string o;
  for (char c : s) {
    switch (c) {
      case '&': o += "&amp;"; break;
      case '<': o += "&lt;"; break;
      case '>': o += "&gt;"; break;
      case '"': o += "&quot;"; break;
      default: o += c;
    }
  }
  return o;
}
}  // namespace

std::string pvd_text(const std::vector<PvdDataSet>& sets) {
  std::string s = "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <Collection>\n";
  for (const auto& d : sets) {
    s += fmt::format("    <DataSet timestep=\"{:.17g}\" group=\"\" part=\"{}\" file=\"{}\"", d.timestep, d.part,
                     xml_attribute(d.file));
    if (!d.name.empty()) s += fmt::format(" name=\"{}\"", xml_attribute(d.name));
    s += "/>\n";
  }
  return s + "  </Collection>\n</VTKFile>\n";
}

void write_pvd(const std::filesystem::path& path, const std::vector<PvdDataSet>& sets) {
  write_file_atomic(path, pvd_text(sets));
}

SnapshotSeries::SnapshotSeries(std::filesystem::path pvd, std::vector<std::string> kinds)
    : pvd_(std::move(pvd)), kinds_(std::move(kinds)) {}

bool SnapshotSeries::add(double timestep, const std::string& tag) {
  if (!std::isfinite(timestep) || (!sets_.empty() && !(timestep > sets_.back().timestep))) return false;
  for (std::size_t k = 0; k < kinds_.size(); ++k)
    sets_.push_back({timestep, static_cast<int>(k), fmt::format("{}_{}.vtp", kinds_[k], tag), kinds_[k]});
  write_pvd(pvd_, sets_);
  return true;
}

Progress::Progress(std::string what, double total, bool quiet)
    : what_(std::move(what)), total_(total), quiet_(quiet), start_(std::chrono::steady_clock::now()), last_(start_) {}

void Progress::update(double done) {
  // in [0, 1]: a run by simulated time ends a step past its total (demsolve yield's precompaction)
  if (progress_hook()) progress_hook()(total_ > 0 ? std::clamp(done / total_, 0.0, 1.0) : 0.0);
  if (quiet_) return;
  const auto now = std::chrono::steady_clock::now();
  if (std::chrono::duration<double>(now - last_).count() < 0.5) return;
  last_ = now;
  const double el = std::chrono::duration<double>(now - start_).count();
  const double frac = total_ > 0 ? done / total_ : 0.0;
  const double rate = el > 0 ? done / el : 0.0;
  const double eta = rate > 0 ? (total_ - done) / rate : 0.0;
  std::fprintf(stderr, "\r%s: %5.1f%%  %.1f/s  ETA %.0f s   ", what_.c_str(), 100.0 * frac, rate, eta);
  printed_ = true;
}

void Progress::finish() {
  if (progress_hook()) progress_hook()(1.0);
  if (quiet_) return;
  const double el = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  std::fprintf(stderr, "%s%s: done in %.2f s\n", printed_ ? "\r" : "", what_.c_str(), el);
}

}  // namespace netdem::app
