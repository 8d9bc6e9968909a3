#pragma once
// Output helpers shared by the command-line tools: atomic files, CSV, VTK PolyData, progress.
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace netdem::app {

/// Writes `text` to `path` through a temporary file in the same folder and a rename, so that a
/// reader never sees a half-written file. Throws std::runtime_error (one line) on failure.
void write_file_atomic(const std::filesystem::path& path, const std::string& text);

/// Creates the output folder (and parents). Throws std::runtime_error (one line) on failure.
void make_output_dir(const std::filesystem::path& dir);

/// make_output_dir, then removes the summary.json of an earlier run in that folder: summary.json is
/// written last and marks a finished run, so a run that fails must not leave the old one behind
/// next to its own first files.
void start_run_dir(const std::filesystem::path& dir);

/// A named point-data field for VTK output.
struct Field {
  std::string name;
  int components = 1;
  std::vector<double> values;  ///< components * points values
};

/// Particles as VTK PolyData vertices (ParaView: glyph by "radius").
std::string vtp_particles(const std::vector<double>& x, const std::vector<double>& y, const std::vector<Field>& point_data);
/// Contact network as VTK PolyData lines between centres, with cell data per contact.
std::string vtp_network(const std::vector<double>& x, const std::vector<double>& y, const std::vector<int>& i,
                        const std::vector<int>& j, const std::vector<Field>& cell_data);

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
