// netsolve yield's records and files (yield_records.hpp): one probe's files and record,
// yield_points.csv assembled from the records, and yield-merge, which does
// the same from the probe files of several runs (docs/yield.md "Outputs").
#include "yield_records.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "output.hpp"
#include "status.hpp"
#include "run_status.hpp"

namespace netdem::app::netsolve::yield {

namespace fs = std::filesystem;
using nlohmann::json;
namespace qs = netdem::qs;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kPi = std::numbers::pi;

// a missing value is an empty field (no NaN in a result file; readers: float(x) if x else nan)
std::string num(double v) { return std::isfinite(v) ? fmt::format("{:.8g}", v) : ""; }
std::string csv_text(std::string s) {
  std::replace(s.begin(), s.end(), ',', ';');
  std::replace(s.begin(), s.end(), '\n', ' ');
  return s;
}

qs::YieldPoint analytic_point(const Analytic& an, double theta) {
  if (!an.ok) return {kNaN, kNaN};
  try {
    auto p = qs::affine_yield_point(an.in, theta);
    return {p.S11 / an.in.sigma_y, p.S22 / an.in.sigma_y};
  } catch (const std::exception&) {
    return {kNaN, kNaN};
  }
}

// ---------------------------------------------------------------------------------------------
// yield_points.csv from probe records (the .json of each probe); apps/scripts/plot_yield.py plots it.
const char* kYieldHeader =
    "probe,theta,S11,S22,S11_offset,S22_offset,S11_analytic,S22_analytic,S11_fabric,S22_fabric,strain,strain_offset,"
    "stress,stress_offset,elastic_slope,curvature,increments,unconverged,status,end\n";

/// The fabric-resolved affine bound of a probe (stored in the run's setup, one per direction).
double fabric_value(const json& r, const char* key) {
  const auto set = r.find("setup");
  if (set == r.end() || !set->contains("fabric")) return kNaN;
  const auto& v = (*set)["fabric"][key];
  const int k = r.at("probe").get<int>();
  return v.is_array() && k >= 0 && k < static_cast<int>(v.size()) ? from_json(v[static_cast<std::size_t>(k)]) : kNaN;
}

std::string yield_row(const json& r) {
  return fmt::format("{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n", r.at("probe").get<int>(),
                     num(from_json(r["theta"])), num(from_json(r["S11"])), num(from_json(r["S22"])),
                     num(from_json(r["S11_offset"])), num(from_json(r["S22_offset"])), num(from_json(r["S11_analytic"])),
                     num(from_json(r["S22_analytic"])), num(fabric_value(r, "S11")), num(fabric_value(r, "S22")),
                     num(from_json(r["strain"])), num(from_json(r["strain_offset"])),
                     num(from_json(r["stress"])), num(from_json(r["stress_offset"])), num(from_json(r["elastic_slope"])),
                     num(from_json(r["curvature"])), r.value("increments", 0), r.value("unconverged", 0),
                     csv_text(r.value("status", "")), csv_text(r.value("end", "")));
}

/// Reads probes/probe_*.json of a run folder.
std::vector<json> read_probe_records(const fs::path& dir) {
  std::vector<json> recs;
  const fs::path pd = dir / "probes";
  if (!fs::is_directory(pd)) throw std::runtime_error(fmt::format("'{}' has no probes/ folder (not a netsolve yield run)", dir.string()));
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(pd))
    if (e.path().extension() == ".json" && e.path().filename().string().rfind("probe_", 0) == 0) files.push_back(e.path());
  std::sort(files.begin(), files.end());
  for (const auto& f : files) {
    std::ifstream in(f);
    json j;
    try {
      in >> j;
    } catch (const std::exception&) {
      throw std::runtime_error(fmt::format("cannot parse '{}'", f.string()));
    }
    j["source"] = dir.string();
    recs.push_back(std::move(j));
  }
  return recs;
}

// ---------------------------------------------------------------------------------------------
// One probe's files (probes/probe_NNN.csv and .json) and its record.
json probe_record(const qs::ProbeResult& p, int directions, const Analytic& an, const json& setup, const fs::path& out) {
  std::string csv = "increment,strain,stress,S11,S22,S12,D,Z,newton,converged,residual\n";
  for (std::size_t i = 0; i < p.curve.samples.size(); ++i) {
    const auto& q = p.curve.samples[i];
    csv += fmt::format("{},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.6g},{},{},{:.3e}\n", i, q.strain, q.stress, q.S11,
                       q.S22, q.S12, q.density, q.Z, q.newton, q.converged ? 1 : 0, q.residual);
  }
  const auto ap = analytic_point(an, p.theta);
  const auto& yc = p.curvature;
  const auto& yf = p.offset;
  json r;
  r["probe"] = p.index;
  r["directions"] = directions;
  r["theta"] = p.theta * 180.0 / kPi;
  r["S11"] = jnum(p.S11);
  r["S22"] = jnum(p.S22);
  r["S11_offset"] = jnum(p.S11_offset);
  r["S22_offset"] = jnum(p.S22_offset);
  r["S11_analytic"] = jnum(ap.S11);
  r["S22_analytic"] = jnum(ap.S22);
  r["strain"] = jnum(yc.found ? yc.strain : kNaN);
  r["strain_offset"] = jnum(yf.found ? yf.strain : kNaN);
  r["stress"] = jnum(yc.found ? yc.stress : kNaN);
  r["stress_offset"] = jnum(yf.found ? yf.stress : kNaN);
  r["elastic_slope"] = jnum(p.fit.ok ? p.fit.slope : kNaN);
  r["curvature"] = jnum(yc.found ? yc.curvature : kNaN);
  r["increments"] = static_cast<int>(p.curve.samples.size()) - 1;
  r["unconverged"] = p.curve.unconverged;
  r["status"] = p.status;
  r["end"] = p.curve.end;
  r["wall_s"] = p.wall_s;
  r["setup"] = setup;
  const auto stem = fmt::format("probe_{:03d}", p.index);
  netdem::app::write_file_atomic(out / "probes" / (stem + ".csv"), csv);
  netdem::app::write_file_atomic(out / "probes" / (stem + ".json"), r.dump(1) + "\n");
  return r;
}

}  // namespace

json jnum(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }
double from_json(const json& j) { return j.is_number() ? j.get<double>() : kNaN; }

Analytic make_analytic(const json& a) {
  Analytic r;
  try {
    r.in = qs::affine_yield_input(a.at("D0").get<double>(), a.at("D").get<double>(), a.at("Z0").get<double>(),
                                  a.at("sigma_y").get<double>(), a.at("dir11").get<double>(), a.at("dir22").get<double>());
    r.ok = true;
  } catch (const std::exception& e) {
    r.message = e.what();
  }
  return r;
}

std::string setup_title(const json& setup) {
  return fmt::format("{} precompaction to D = {}, friction {}, {}-{}", setup.value("precompact", "?"),
                     setup.value("to_density", 0.0), setup.value("friction", "?"), setup.value("compact_bc", "?"),
                     setup.value("probe_bc", "?"));
}

json failed_record(int index, int directions, const std::string& why, const Analytic& an, const json& setup) {
  const double theta = 2 * kPi * index / directions;
  const auto ap = analytic_point(an, theta);
  json r;
  r["probe"] = index;
  r["directions"] = directions;
  r["theta"] = theta * 180 / kPi;
  for (const char* k : {"S11", "S22", "S11_offset", "S22_offset", "strain", "strain_offset", "stress", "stress_offset",
                        "elastic_slope", "curvature"})
    r[k] = nullptr;
  r["S11_analytic"] = jnum(ap.S11);
  r["S22_analytic"] = jnum(ap.S22);
  r["increments"] = 0;
  r["unconverged"] = 0;
  r["status"] = why;
  r["end"] = why;
  r["setup"] = setup;
  return r;
}

/// The files and record of a finished probe (a failed one gets the record of failed_record).
json write_probe(const qs::ProbeResult& p, int directions, const Analytic& an, const json& setup, const fs::path& out) {
  if (p.status.rfind("error: ", 0) != 0) return probe_record(p, directions, an, setup, out);
  json r = failed_record(p.index, directions, csv_text(p.status), an, setup);
  netdem::app::write_file_atomic(out / "probes" / fmt::format("probe_{:03d}.json", p.index), r.dump(1) + "\n");
  return r;
}

void write_yield_points(const fs::path& out, const std::vector<json>& recs) {
  std::string csv = kYieldHeader;
  for (const auto& r : recs) csv += yield_row(r);
  netdem::app::write_file_atomic(out / "yield_points.csv", csv);
}

int run_merge(const std::vector<std::string>& dirs, const std::string& out_dir, const std::string& command, bool overwrite) {
  if (dirs.empty()) throw std::invalid_argument("yield-merge: no run folder given");
  std::map<int, json> best;
  json setup = nullptr;
  int directions = -1;
  for (const auto& d : dirs) {
    for (auto& r : read_probe_records(d)) {
      json s = r.at("setup");
      if (setup.is_null()) {
        setup = s;
        directions = r.at("directions").get<int>();
      } else {
        json a = setup, b = s;
        for (auto* x : {&a, &b}) {  // the measured state may differ in the last digits between machines
          x->erase("analytic");
          x->erase("loading");
        }
        if (a != b || r.at("directions").get<int>() != directions)
          throw std::invalid_argument(fmt::format("yield-merge: '{}' was run with a different setup ({} vs {})", d,
                                                  setup_title(s), setup_title(setup)));
      }
      const int idx = r.at("probe").get<int>();
      const auto it = best.find(idx);
      if (it == best.end() || (it->second.value("status", "") != "ok" && r.value("status", "") == "ok")) best[idx] = r;
    }
  }
  if (best.empty()) throw std::invalid_argument("yield-merge: no probe files found");
  const fs::path out = out_dir;
  netdem::app::RunDirOptions rdo;
  rdo.overwrite = overwrite;
  for (const auto& d : dirs) rdo.inputs.emplace_back(d);
  netdem::app::open_run_dir(out, command, rdo);
  std::vector<json> recs;
  std::vector<int> missing;
  for (int k = 0; k < directions; ++k) {
    if (best.count(k)) {
      recs.push_back(best[k]);
    } else {
      missing.push_back(k);
    }
  }
  write_yield_points(out, recs);
  // the merge records each probe's status (yield_points.csv, "probes" below) and does not fail for
  // a failed probe: "incomplete" says that probes are missing or not ok, exit 0 either way
  std::vector<int> not_ok;
  for (const auto& r : recs)
    if (r.value("status", "") != "ok") not_ok.push_back(r.at("probe").get<int>());
  std::vector<std::string> unfinished;
  for (const auto& d : dirs)
    if (fs::exists(fs::path(d) / netdem::app::kIncompleteMarker)) unfinished.push_back(d);
  netdem::app::netsolve::RunStatus status;
  if (!missing.empty()) status.add("incomplete", fmt::format("{} of {} probes missing", missing.size(), directions));
  if (!not_ok.empty()) status.add("incomplete", fmt::format("{} probes not ok (their status is in yield_points.csv)", not_ok.size()));
  if (!unfinished.empty())
    status.add("incomplete", fmt::format("{} source folders hold an unfinished run (.incomplete)", unfinished.size()));
  json j;
  j["command"] = command;
  status.write(j);
  j["setup"] = setup;
  j["sources"] = dirs;
  j["sources_unfinished"] = unfinished;
  j["probes"] = {{"found", recs.size()}, {"directions", directions}, {"missing", missing}, {"not_ok", not_ok}};
  netdem::app::write_file_atomic(out / "summary.json", j.dump(2) + "\n");
  netdem::app::close_run_dir(out);
  netdem::app::summary_printf("merged %zu of %d probes from %zu folders%s -> %s\n", recs.size(), directions, dirs.size(),
              missing.empty() ? "" : fmt::format(" ({} missing)", missing.size()).c_str(), out.c_str());
  return 0;
}

}  // namespace netdem::app::netsolve::yield
