#include "output.hpp"

#include "netdem/packing/io.hpp"

#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <random>
#include <stdexcept>

#include <fmt/format.h>

namespace netdem::app {

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

/// At most 80 printable characters of `s`, for messages (the readers' quoting rule).
std::string quoted(const std::string& s) { return netdem::packing::quote_input(s, 80); }

/// The first line of dir/command.txt (the run that wrote the folder), or "".
std::string recorded_command(const fs::path& dir) {
  std::ifstream in(dir / "command.txt");
  std::string line;
  std::getline(in, line);
  return line;
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

void open_run_dir(const std::filesystem::path& dir, const std::string& command, const RunDirOptions& o) {
  check_run_dir(dir, o);
  const bool clear = o.overwrite && holds_run(dir);
  make_output_dir(dir);
  {  // the marker first: from here on the folder is an unfinished run until close_run_dir
    const auto now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
    char when[32] = "";
    std::tm tm{};
    if (gmtime_r(&now, &tm) != nullptr) std::strftime(when, sizeof when, "%Y-%m-%dT%H:%M:%SZ", &tm);
    std::ofstream m(dir / kIncompleteMarker, std::ios::trunc);
    m << "unfinished netdem run (running, failed or killed): pid " << ::getpid() << ", started " << when << "\n"
      << command << "\n";
    m.flush();
    if (!m) throw std::runtime_error(fmt::format("cannot write into the output folder '{}': {}", quoted(dir.string()),
                                                 std::strerror(errno ? errno : EIO)));
  }
  if (clear) {  // why_not_clear allowed it: top-level files and probes/
    std::error_code ec;
    std::vector<fs::path> old;
    for (const auto& e : fs::directory_iterator(dir)) old.push_back(e.path());
    for (const auto& p : old) {
      if (p.filename() == kIncompleteMarker) continue;
      if (fs::is_directory(fs::symlink_status(p))) {
        fs::remove_all(p, ec);
      } else {
        fs::remove(p, ec);
      }
      if (ec) throw std::runtime_error(fmt::format("cannot clear '{}': {}: {}", quoted(dir.string()), quoted(p.string()), ec.message()));
    }
  }
  write_file_atomic(dir / "command.txt", command + "\n");
  g_run_dir_opened = true;
}

void close_run_dir(const std::filesystem::path& dir) {
  std::error_code ec;
  fs::remove(dir / kIncompleteMarker, ec);
  if (ec) throw std::runtime_error(fmt::format("cannot remove '{}': {}", (dir / kIncompleteMarker).string(), ec.message()));
}

bool run_dir_opened() { return g_run_dir_opened; }

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

Progress::Progress(std::string what, double total, bool quiet)
    : what_(std::move(what)), total_(total), quiet_(quiet), start_(std::chrono::steady_clock::now()), last_(start_) {}

void Progress::update(double done) {
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
  if (quiet_) return;
  const double el = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  std::fprintf(stderr, "%s%s: done in %.2f s\n", printed_ ? "\r" : "", what_.c_str(), el);
}

}  // namespace netdem::app
