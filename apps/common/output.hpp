#pragma once
// Output helpers shared by the command-line tools: atomic files, CSV, VTK PolyData, progress.
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace netdem::app {

/// Exit codes of the command-line tools (README.md "Exit status", docs/quasistatic.md):
/// 0 ok, 1 run error, 2 command-line error (nothing written), 3 finished but untrustworthy
/// (summary.json says why; --allow-unconverged turns it into 0 and keeps the status).
namespace exit_code {
constexpr int ok = 0;
constexpr int run_error = 1;
constexpr int usage = 2;
constexpr int untrustworthy = 3;
}  // namespace exit_code

/// A refused command line (a bad value, a foreign output folder): exit 2, nothing written.
class UsageError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// Writes `text` to `path` through a temporary file in the same folder and a rename, so that a
/// reader never sees a half-written file. Throws std::runtime_error (one line) on failure.
void write_file_atomic(const std::filesystem::path& path, const std::string& text);
/// The command line as a shell would rerun it (command.txt, summary.json "command"): the arguments
/// joined by spaces, an argument that is empty or holds a character the shell treats specially in
/// single quotes (so that `--snapshots ''` survives the round trip).
std::string shell_command(int argc, const char* const* argv);

/// Creates the output folder (and parents). Throws std::runtime_error (one line) on failure.
void make_output_dir(const std::filesystem::path& dir);

// ---- run folders: a folder never mixes two runs (README.md "Run folders") -----------------------
//   check_run_dir   before any work: refuses (UsageError) a folder held by a run that is still
//                   running (the pid and process start time in .incomplete), with or without
//                   overwrite; a folder that holds another run's files (command.txt, summary.json or
//                   .incomplete) unless overwrite; an --out that is a file or cannot be written, and
//                   an input file inside a folder --overwrite clears; touches nothing.
//   open_run_dir    check_run_dir, then writes the marker .incomplete first (pid, process start
//                   time, the entries the folder held before: the user's), then (overwrite) removes
//                   the old run's files only and lists them on stderr (one line), then command.txt.
//   close_run_dir   writes .netdem-files (the run's own files: what --overwrite will remove) and
//                   removes .incomplete: the last thing a run does. A run that fails or is killed
//                   leaves .incomplete, so a folder with it never holds a finished run.

/// The marker of an unfinished run.
inline constexpr const char* kIncompleteMarker = ".incomplete";

struct RunDirOptions {
  bool overwrite = false;                          ///< --overwrite: clear an old run's folder first
  std::vector<std::filesystem::path> inputs;       ///< input files/folders, which must not lie in a folder to clear
  std::string overwrite_flag = "--overwrite";      ///< how the tool spells the option (messages)
};

/// True if `dir` holds a run's files: command.txt, summary.json or .incomplete.
bool holds_run(const std::filesystem::path& dir);
/// The checks of open_run_dir without touching anything; throws UsageError (one line).
void check_run_dir(const std::filesystem::path& dir, const RunDirOptions& options);
/// Checks, clears (overwrite), creates `dir`, writes .incomplete and command.txt (`command` + newline).
/// Throws UsageError for a refused folder (nothing touched), std::runtime_error on a write failure.
void open_run_dir(const std::filesystem::path& dir, const std::string& command, const RunDirOptions& options);
/// Removes .incomplete (call after the last file, summary.json, is written).
void close_run_dir(const std::filesystem::path& dir);
/// True once open_run_dir succeeded in this process: an error after it is a run error (exit 1),
/// one before it a refused command line (exit 2).
bool run_dir_opened();
/// Starts a command afresh in this process (the Python module runs several): no run folder
/// opened yet, the activity "starting".
void reset_run_state();

/// MemAvailable of /proc/meminfo in bytes, or 0 if unknown (demsolve's memory estimate;
/// apps/netsolve/setup.hpp has its own copy, mem_available_bytes, to be replaced by this one).
double mem_available();

/// A named point-data field for VTK output.
struct Field {
  std::string name;
  int components = 1;
  std::vector<double> values;  ///< components * points values
};

/// Particles as VTK PolyData vertices (ParaView: glyph by "radius").
std::string vtp_particles(const std::vector<double>& x, const std::vector<double>& y, const std::vector<Field>& point_data);
/// The same with the real z of every point (3D packings); z == nullptr writes z = 0 (as above).
std::string vtp_particles_3d(const std::vector<double>& x, const std::vector<double>& y, const std::vector<double>* z,
                             const std::vector<Field>& point_data);
/// Contact network as VTK PolyData lines between centres, with cell data per contact.
std::string vtp_network(const std::vector<double>& x, const std::vector<double>& y, const std::vector<int>& i,
                        const std::vector<int>& j, const std::vector<Field>& cell_data);
/// The same with the real z of every centre (3D); z == nullptr writes z = 0 (as above).
std::string vtp_network_3d(const std::vector<double>& x, const std::vector<double>& y, const std::vector<double>* z,
                           const std::vector<int>& i, const std::vector<int>& j, const std::vector<Field>& cell_data);

// ---- ParaView collections (.pvd) ---------------------------------------------------------------
/// One data set of a .pvd collection: the value ParaView steps through (`timestep`), the block it
/// fills at that time (`part`), its file (relative to the .pvd's folder) and the block's name
/// ("": no name attribute).
struct PvdDataSet {
  double timestep = 0.0;
  int part = 0;
  std::string file;
  std::string name;
};
/// The text of a .pvd collection of `sets`, in their order (the timesteps with 17 digits: exact).
std::string pvd_text(const std::vector<PvdDataSet>& sets);
/// Writes pvd_text(sets) to `path` atomically (write_file_atomic).
void write_pvd(const std::filesystem::path& path, const std::vector<PvdDataSet>& sets);

/// A run's snapshot series and its .pvd (snapshots.pvd in the run folder), so that ParaView opens
/// one file and steps through the snapshots. One .pvd with a part per kind rather than one .pvd per
/// kind: each time step holds the whole state (particles, contacts, the periodic cell) as the named
/// blocks of one data set (Extract Block picks the particles for a glyph), as netsolve sinter's
/// snapshots.pvd does. Nothing is written before the first snapshot.
class SnapshotSeries {
 public:
  /// `kinds`: the files of a snapshot TAG are KIND_TAG.vtp, part k the k-th kind, its block named so.
  SnapshotSeries(std::filesystem::path pvd, std::vector<std::string> kinds);
  /// Records snapshot `tag` at `timestep` and rewrites the .pvd atomically (a run stopped later
  /// keeps a valid .pvd of the snapshots so far). A snapshot whose timestep is not above the last
  /// one listed is left out (returns false; its files stay): the same state written again under
  /// another name (`final` after the last phase or the last density reached), which ParaView would
  /// draw twice at one time.
  bool add(double timestep, const std::string& tag);
  /// The run folder (the .pvd's).
  std::filesystem::path dir() const { return pvd_.parent_path(); }
  const std::vector<PvdDataSet>& sets() const { return sets_; }

 private:
  std::filesystem::path pvd_;
  std::vector<std::string> kinds_;
  std::vector<PvdDataSet> sets_;
};

/// Called by every Progress::update and finish with the fraction done, quiet or not, when set (the
/// Python module's progress callback and its Ctrl-C check). It may throw to stop the run: the
/// exception leaves the command (a type not derived from std::exception passes guarded()).
std::function<void(double)>& progress_hook();

/// Progress on stderr: percent, rate and ETA, at most twice a second; silent if quiet.
class Progress {
 public:
  Progress(std::string what, double total, bool quiet);
  void update(double done);
  void finish();

 private:
  std::string what_;
  double total_;
  bool quiet_;
  std::chrono::steady_clock::time_point start_, last_;
  bool printed_ = false;
};

}  // namespace netdem::app
