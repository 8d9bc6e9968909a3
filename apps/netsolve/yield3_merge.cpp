// netsolve yield-merge --dim 3 (issue 30): one yield surface from the folders of a job array of
// `netsolve yield --dim 3 --probe i/N` runs. Each folder's summary.json must be a finished 3D yield
// run with the same setup and probe settings; its yield_points.csv rows are taken by probe index (an
// "ok" row before one that is not), its probes/probe_K.csv curve files copied. The merge writes
// yield_points.csv in probe order (the file of a single run with every probe, byte for byte, when the
// slices ran the same binary on the same machine), summary.json with the first folder's loading
// point and analytic surface, and the status "incomplete" when probes are missing, not ok, or a
// folder holds an unfinished run. docs/yield.md "3D".
#include <filesystem>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "compact_common.hpp"
#include "netdem/system/archive.hpp"
#include "output.hpp"
#include "run_status.hpp"
#include "status.hpp"

namespace netdem::app::netsolve {

namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

std::string read_text(const fs::path& p) { return sys::read_text_file(p.string(), "yield-merge input"); }

/// The fields of a CSV line (double-quoted fields may hold commas; yield3.cpp writes no quote inside).
std::vector<std::string> fields(const std::string& line) {
  std::vector<std::string> f(1);
  bool quoted = false;
  for (char c : line) {
    if (c == '"') {
      quoted = !quoted;
      continue;
    }
    if (c == ',' && !quoted) {
      f.emplace_back();
      continue;
    }
    f.back() += c;
  }
  return f;
}

/// One source folder: its summary, the header of yield_points.csv and its rows by probe index.
struct Source {
  json summary;
  std::string header;
  std::map<int, std::string> rows;
};

Source read_source(const std::string& dir) {
  Source s;
  const fs::path d = dir;
  if (!fs::is_regular_file(d / "summary.json") || !fs::is_regular_file(d / "yield_points.csv"))
    throw std::invalid_argument(fmt::format("yield-merge: '{}' has no summary.json and yield_points.csv (not a finished "
                                            "netsolve yield --dim 3 run)", dir));
  try {
    s.summary = json::parse(read_text(d / "summary.json"));
  } catch (const json::exception&) {
    throw std::invalid_argument(fmt::format("yield-merge: cannot parse '{}'", (d / "summary.json").string()));
  }
  if (s.summary.value("dim", 2) != 3 || !s.summary.contains("probes") || !s.summary.contains("setup"))
    throw std::invalid_argument(fmt::format("yield-merge: '{}' is not a finished netsolve yield --dim 3 run (summary.json "
                                            "has no dim 3, setup and probes)", dir));
  std::istringstream in(read_text(d / "yield_points.csv"));
  std::getline(in, s.header);
  for (std::string line; std::getline(in, line);) {
    if (line.empty()) continue;
    const std::vector<std::string> f = fields(line);
    int k = -1;
    try {
      k = std::stoi(f.at(0));
    } catch (const std::exception&) {
      throw std::invalid_argument(fmt::format("yield-merge: '{}': a row without a probe index: {}", dir, line.substr(0, 60)));
    }
    s.rows[k] = line + "\n";
  }
  return s;
}

/// What must agree between the slices: the setup and the probe settings (not the run's indices,
/// jobs or timings).
json comparable(const json& summary) {
  json p = summary.at("probes");
  for (const char* k : {"run", "ok", "indices", "jobs"}) p.erase(k);
  return json{{"setup", summary.at("setup")}, {"probes", p}, {"particles", summary.value("particles", 0)},
              {"seed", summary.value("seed", json(nullptr))}};
}

bool row_ok(const std::string& row) {
  const std::vector<std::string> f = fields(row.substr(0, row.size() - 1));
  return f.size() >= 2 && f[f.size() - 2] == "ok";
}

}  // namespace

int run_yield3_merge(const std::vector<std::string>& dirs, const std::string& out_dir, const std::string& command,
                     bool overwrite) {
  if (dirs.empty()) throw std::invalid_argument("yield-merge: no run folder given");
  std::vector<Source> src;
  for (const auto& d : dirs) src.push_back(read_source(d));
  const json ref = comparable(src[0].summary);
  std::map<int, std::string> best;
  std::map<int, fs::path> curve;
  for (std::size_t i = 0; i < src.size(); ++i) {
    if (comparable(src[i].summary) != ref || src[i].header != src[0].header)
      throw std::invalid_argument(fmt::format("yield-merge: '{}' was run with a different setup or probe settings than '{}'",
                                              dirs[i], dirs[0]));
    for (const auto& [k, row] : src[i].rows) {
      const auto it = best.find(k);
      if (it != best.end() && (row_ok(it->second) || !row_ok(row))) continue;
      best[k] = row;
      curve[k] = fs::path(dirs[i]) / "probes" / fmt::format("probe_{:03d}.csv", k);
    }
  }
  const int directions = ref.at("probes").value("directions", 0);
  const fs::path out = out_dir;
  RunDirOptions rdo;
  rdo.overwrite = overwrite;
  for (const auto& d : dirs) rdo.inputs.emplace_back(d);
  open_run_dir(out, command, rdo);
  make_output_dir(out / "probes");
  std::string csv = src[0].header + "\n";
  std::vector<int> missing, not_ok, found;
  for (int k = 0; k < directions; ++k) {
    const auto it = best.find(k);
    if (it == best.end()) {
      missing.push_back(k);
      continue;
    }
    csv += it->second;
    found.push_back(k);
    if (!row_ok(it->second)) not_ok.push_back(k);
    if (fs::is_regular_file(curve[k])) write_file_atomic(out / "probes" / curve[k].filename(), read_text(curve[k]));
  }
  write_file_atomic(out / "yield_points.csv", csv);
  std::vector<std::string> unfinished;
  for (const auto& d : dirs)
    if (fs::exists(fs::path(d) / kIncompleteMarker)) unfinished.push_back(d);
  RunStatus status;
  if (!missing.empty()) status.add("incomplete", fmt::format("{} of {} probes missing", missing.size(), directions));
  if (!not_ok.empty())
    status.add("incomplete", fmt::format("{} probes not ok (their status is in yield_points.csv)", not_ok.size()));
  if (!unfinished.empty())
    status.add("incomplete", fmt::format("{} source folders hold an unfinished run (.incomplete)", unfinished.size()));
  const json& first = src[0].summary;
  json j;
  j["command"] = command;
  status.write(j);
  j["dim"] = 3;
  for (const char* k : {"setup", "packing", "seed", "particles", "initial_density", "sigma_y", "precompaction", "analytic",
                        "unloading"})
    if (first.contains(k)) j[k] = first[k];
  j["sources"] = dirs;
  j["sources_unfinished"] = unfinished;
  j["probes"] = ref.at("probes");
  j["probes"]["found"] = found.size();
  j["probes"]["missing"] = missing;
  j["probes"]["not_ok"] = not_ok;
  j["probes"]["indices"] = found;
  write_file_atomic(out / "summary.json", j.dump(2) + "\n");
  close_run_dir(out);
  summary_printf("merged %zu of %d probes from %zu folders%s -> %s\n", found.size(), directions, dirs.size(),
                 missing.empty() ? "" : fmt::format(" ({} missing)", missing.size()).c_str(), out.c_str());
  return 0;
}

}  // namespace netdem::app::netsolve
