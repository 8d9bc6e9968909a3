// netsolve yield / yield-merge: yield surfaces of a precompacted network (issue #3; Redanz & Fleck,
// Acta Mater. 49 (2001) 4325, section 3.4, Figs 9-10). Algorithm and outputs: docs/yield.md.
//
//   netsolve yield [--precompact hydrostatic|closed-die] [--to-density 0.85] [--friction MU|inf]
//                  [--compact-bc affine|die] [--probe-bc affine|die] [--directions N]
//                  [--probe i/N | --probes LIST] [--jobs J] [--out DIR]
//   netsolve yield-merge DIR... [--out DIR]
//
// The command compacts (or restores a compacted state, --from-state), unloads, then runs the
// probes on --jobs threads, each on its own solver restored from the unloaded state
// (qs::run_probes, src/quasistatic/yield_driver.hpp); each finished probe writes
// probes/probe_NNN.csv and .json atomically, and yield_points.csv is assembled from the records.
// yield-merge does the same from the probe files of several runs. The physics lives in the
// library (compaction, switch_boundary_mode, unload, run_probes); this file parses and writes.
#ifdef __linux__
#include <sys/prctl.h>
#endif
#include <spawn.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <numbers>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "netdem/contact/plastic_indentation.hpp"
#include "netdem/packing/ballistic.hpp"
#include "netdem/packing/io.hpp"
#include "netdem/packing/packing.hpp"
#include "netdem/quasistatic/analytic_yield.hpp"
#include "netdem/quasistatic/compaction.hpp"
#include "netdem/quasistatic/network_solver.hpp"
#include "netdem/quasistatic/yield_driver.hpp"
#include "netdem/quasistatic/yield_probe.hpp"
#include "output.hpp"
#include "parse.hpp"
#include "setup.hpp"
#include "status.hpp"

namespace fs = std::filesystem;
using nlohmann::json;
namespace qs = netdem::qs;

int run_yield_command(int argc, char** argv);

namespace {

using netdem::app::netsolve::parse_double;
using netdem::app::netsolve::parse_friction;
using netdem::app::netsolve::parse_int;

using Clock = std::chrono::steady_clock;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kPi = std::numbers::pi;

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

struct YieldArgs {
  // packing
  netdem::app::netsolve::PackArgs pack;  // a new deposition (lid: centre)
  std::string packing_file, from_state;
  // precompaction
  std::string precompact = "hydrostatic", compact_bc = "die", probe_bc;
  double to_density = 0.85;
  int increments = 100;
  // contact law and solver (--normal-unloading: the law during the precompaction)
  netdem::app::netsolve::LawArgs law;
  // probing
  int directions = 24;
  std::string probe_slice, probe_list;
  int jobs = 0;
  double offset = 1e-3, max_strain = 4e-3, window = 0.1, unload_tol = 1e-3, growth = 1.2;
  int fine = 20;
  bool quiet = false, overwrite = false, allow_unconverged = false;
  std::string out = "results/yield";
  int probe_worker = -1;          ///< hidden: run probe k from out/probes/unloaded_state.txt (a worker process)
  std::vector<std::string> argv;  ///< the command line, to start the workers
};


qs::BoundaryMode parse_bc(const std::string& s, const char* opt) {
  if (s == "affine") return qs::BoundaryMode::Affine;
  if (s == "die" || s == "lr" || s == "l.r.") return qs::BoundaryMode::Die;
  throw std::invalid_argument(fmt::format("{} '{}' is not 'affine' or 'die' (local relaxation)", opt, s));
}

const char* bc_name(qs::BoundaryMode m) { return m == qs::BoundaryMode::Affine ? "affine" : "die"; }

/// Probe indices of this run: all, a job-array slice "i/N" (indices k with k mod N == i) or a list.
std::vector<int> select_probes(const YieldArgs& a) {
  if (a.directions < 1 || a.directions > 100000)
    throw std::invalid_argument(fmt::format("--directions must be in [1, 100000], got {}", a.directions));
  if (!a.probe_slice.empty() && !a.probe_list.empty())
    throw std::invalid_argument("--probe and --probes exclude each other");
  std::vector<int> sel;
  if (!a.probe_slice.empty()) {
    const auto slash = a.probe_slice.find('/');
    long i = -1, n = -1;
    if (slash == std::string::npos || !parse_int(a.probe_slice.substr(0, slash), i) ||
        !parse_int(a.probe_slice.substr(slash + 1), n) || n < 1 || i < 0 || i >= n)
      throw std::invalid_argument(
          fmt::format("--probe '{}' is not a slice i/N with 0 <= i < N (probes k with k mod N == i)", a.probe_slice));
    for (int k = 0; k < a.directions; ++k)
      if (k % n == i) sel.push_back(k);
    if (sel.empty())
      throw std::invalid_argument(fmt::format("--probe {} selects no probe of --directions {}", a.probe_slice, a.directions));
    return sel;
  }
  if (!a.probe_list.empty()) {
    std::stringstream in(a.probe_list);
    std::string item;
    std::set<int> s;
    while (std::getline(in, item, ',')) {
      long v = -1;
      if (!parse_int(item, v) || v < 0 || v >= a.directions)
        throw std::invalid_argument(
            fmt::format("--probes: '{}' is not a probe index in [0, {}) (--directions {})", item, a.directions, a.directions));
      s.insert(static_cast<int>(v));
    }
    if (s.empty()) throw std::invalid_argument("--probes: empty list");
    return {s.begin(), s.end()};
  }
  for (int k = 0; k < a.directions; ++k) sel.push_back(k);
  return sel;
}

// a missing value is an empty field (no NaN in a result file; readers: float(x) if x else nan)
std::string num(double v) { return std::isfinite(v) ? fmt::format("{:.8g}", v) : ""; }
std::string csv_text(std::string s) {
  std::replace(s.begin(), s.end(), ',', ';');
  std::replace(s.begin(), s.end(), '\n', ' ');
  return s;
}
json jnum(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }
double from_json(const json& j) { return j.is_number() ? j.get<double>() : kNaN; }

// ---------------------------------------------------------------------------------------------
// The analytic affine surface of the run (docs/yield_analytic.md).
struct Analytic {
  bool ok = false;
  qs::AffineYieldInput in{};
  std::string message;
};

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
// yield_points.csv and the surface plot from probe records (the .json of each probe).
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

/// SVG of the surface: analytic affine curve, yield points by curvature (joined in theta order, as
/// the paper's linear interpolation, not closed), offset points and the loading point.
std::string surface_svg(const std::vector<json>& recs, const Analytic& an, double L11, double L22, const std::string& title) {
  std::vector<std::pair<double, double>> ana, cur, off;
  if (an.ok)
    for (int k = 0; k <= 720; ++k) {
      const auto p = analytic_point(an, 2 * kPi * k / 720.0);
      ana.emplace_back(p.S11, p.S22);
    }
  for (const auto& r : recs) {
    const double a = from_json(r["S11"]), b = from_json(r["S22"]);
    if (std::isfinite(a) && std::isfinite(b)) cur.emplace_back(a, b);
    const double c = from_json(r["S11_offset"]), d = from_json(r["S22_offset"]);
    if (std::isfinite(c) && std::isfinite(d)) off.emplace_back(c, d);
  }
  double lo = 0.0, hi = 0.0;
  auto grow = [&](double v) {
    if (std::isfinite(v)) {
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
  };
  for (const auto* v : {&ana, &cur, &off})
    for (const auto& p : *v) {
      grow(p.first);
      grow(p.second);
    }
  grow(L11);
  grow(L22);
  const double span = std::max(hi - lo, 1e-6);
  lo -= 0.08 * span;
  hi += 0.08 * span;
  const double W = 520, M = 60;
  auto X = [&](double v) { return M + (v - lo) / (hi - lo) * W; };
  auto Y = [&](double v) { return M + (hi - v) / (hi - lo) * W; };
  std::string s = fmt::format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{0}\" height=\"{0}\" font-family=\"sans-serif\" font-size=\"12\">\n"
      "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n<text x=\"{1}\" y=\"20\" font-size=\"13\">{2}</text>\n",
      W + 2 * M, M, title);
  s += fmt::format("<rect x=\"{0}\" y=\"{0}\" width=\"{1}\" height=\"{1}\" fill=\"none\" stroke=\"black\"/>\n", M, W);
  const double tick = std::pow(10.0, std::floor(std::log10(span / 2))) * (span / std::pow(10.0, std::floor(std::log10(span))) > 5 ? 2 : 1) / 2;
  for (double t = std::ceil(lo / tick) * tick; t <= hi; t += tick) {
    s += fmt::format("<line x1=\"{0:.1f}\" y1=\"{1}\" x2=\"{0:.1f}\" y2=\"{2}\" stroke=\"#ddd\"/><text x=\"{0:.1f}\" y=\"{3}\" text-anchor=\"middle\">{4:.2g}</text>\n",
                     X(t), M, M + W, M + W + 16, t);
    s += fmt::format("<line x1=\"{1}\" y1=\"{0:.1f}\" x2=\"{2}\" y2=\"{0:.1f}\" stroke=\"#ddd\"/><text x=\"{3}\" y=\"{0:.1f}\" text-anchor=\"end\">{4:.2g}</text>\n",
                     Y(t), M, M + W, M - 4, t);
  }
  s += fmt::format("<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">Σ11/σy</text>\n", M + W / 2, M + W + 36);
  s += fmt::format("<text x=\"16\" y=\"{}\" transform=\"rotate(-90 16 {})\" text-anchor=\"middle\">Σ22/σy</text>\n", M + W / 2, M + W / 2);
  auto poly = [&](const std::vector<std::pair<double, double>>& v, const char* style) {
    if (v.size() < 2) return;
    s += "<polyline fill=\"none\" " + std::string(style) + " points=\"";
    for (const auto& p : v) s += fmt::format("{:.1f},{:.1f} ", X(p.first), Y(p.second));
    s += "\"/>\n";
  };
  poly(ana, "stroke=\"#888\" stroke-dasharray=\"5,3\"");
  poly(cur, "stroke=\"#1f77b4\"");  // open: the part near the origin has no points (tensile probes)
  for (const auto& p : cur) s += fmt::format("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"3.5\" fill=\"#1f77b4\"/>\n", X(p.first), Y(p.second));
  for (const auto& p : off)
    s += fmt::format("<rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"7\" height=\"7\" fill=\"none\" stroke=\"#d62728\"/>\n", X(p.first) - 3.5, Y(p.second) - 3.5);
  if (std::isfinite(L11) && std::isfinite(L22))
    s += fmt::format("<path d=\"M{0:.1f},{1:.1f} m-6,0 l12,0 m-6,-6 l0,12\" stroke=\"black\" stroke-width=\"2\"/>\n", X(L11), Y(L22));
  const double lx = M + 10, ly = M + 16;
  s += fmt::format("<line x1=\"{0}\" y1=\"{1}\" x2=\"{2}\" y2=\"{1}\" stroke=\"#888\" stroke-dasharray=\"5,3\"/><text x=\"{3}\" y=\"{4}\">analytic affine (App. A)</text>\n", lx, ly, lx + 24, lx + 30, ly + 4);
  s += fmt::format("<circle cx=\"{}\" cy=\"{}\" r=\"3.5\" fill=\"#1f77b4\"/><text x=\"{}\" y=\"{}\">max curvature</text>\n", lx + 12, ly + 18, lx + 30, ly + 22);
  s += fmt::format("<rect x=\"{}\" y=\"{}\" width=\"7\" height=\"7\" fill=\"none\" stroke=\"#d62728\"/><text x=\"{}\" y=\"{}\">offset</text>\n", lx + 8.5, ly + 32.5, lx + 30, ly + 40);
  s += fmt::format("<path d=\"M{},{} m-6,0 l12,0 m-6,-6 l0,12\" stroke=\"black\" stroke-width=\"2\"/><text x=\"{}\" y=\"{}\">loading point</text>\n", lx + 12, ly + 54, lx + 30, ly + 58);
  s += "</svg>\n";
  return s;
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

void write_assembly(const fs::path& out, const std::vector<json>& recs, const json& setup, const std::string& title) {
  std::string csv = kYieldHeader;
  for (const auto& r : recs) csv += yield_row(r);
  netdem::app::write_file_atomic(out / "yield_points.csv", csv);
  const Analytic an = make_analytic(setup.at("analytic"));
  netdem::app::write_file_atomic(out / "surface.svg",
                                 surface_svg(recs, an, from_json(setup["loading"]["S11"]), from_json(setup["loading"]["S22"]), title));
}

std::string setup_title(const json& setup) {
  return fmt::format("{} precompaction to D = {}, friction {}, {}-{}", setup.value("precompact", "?"),
                     setup.value("to_density", 0.0), setup.value("friction", "?"), setup.value("compact_bc", "?"),
                     setup.value("probe_bc", "?"));
}

// ---------------------------------------------------------------------------------------------
// One probe's files (probes/probe_NNN.csv and .json) and its record.
json probe_record(const qs::ProbeResult& p, const YieldArgs& a, const Analytic& an, const json& setup, const fs::path& out) {
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
  r["directions"] = a.directions;
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

// ---------------------------------------------------------------------------------------------
/// The solver options of the two phases: the precompaction preset with the command's law and
/// Newton options, and the probe preset with the same law (docs/quasistatic.md "Presets").
void yield_options(const YieldArgs& a, qs::SolverOptions& pre, qs::SolverOptions& probe) {
  pre = qs::SolverOptions::yield_precompaction();
  pre.mode = parse_bc(a.compact_bc, "--compact-bc");
  netdem::app::netsolve::apply_law_args(a.law, pre);
  pre.validate();
  probe = qs::SolverOptions::yield_probe();
  probe.mode = parse_bc(a.probe_bc.empty() ? a.compact_bc : a.probe_bc, "--probe-bc");
  probe.law = pre.law;  // unloading switches it to the elastic branch (set_reversible_normal)
  probe.validate();
}

/// The compacted state of --from-state; its strain must lie along --precompact's path.
std::unique_ptr<qs::NetworkSolver> restore_compacted(const YieldArgs& a, const qs::StrainPath& path,
                                                     const qs::SolverOptions& pre) {
  const qs::NetworkState st = qs::load_state(a.from_state);
  const Eigen::Matrix2d E = st.strain, R = path.rate();
  const double cosine = (E.array() * R.array()).sum() / (E.norm() * R.norm());
  if (!(E.norm() > 0.0) || !(cosine > 1.0 - 1e-9))
    throw std::invalid_argument(fmt::format("--from-state {}: its strain (E11, E22, E12) = ({:.4g}, {:.4g}, {:.4g}) does not "
                                            "lie along --precompact {}",
                                            a.from_state, E(0, 0), E(1, 1), E(0, 1), path.name));
  return std::make_unique<qs::NetworkSolver>(st, pre);
}

/// The probe settings of the command line, with the fine step and the loading stress of the run.
qs::ProbeSettings probe_settings(const YieldArgs& a, double first_step, double loading_norm, double sigma_y) {
  qs::ProbeSettings ps;
  ps.directions = a.directions;
  ps.offset = a.offset;
  ps.max_strain = a.max_strain;
  ps.window = a.window;
  ps.growth = a.growth;
  ps.fine = a.fine;
  ps.first_step = first_step;
  ps.loading_norm = loading_norm;
  ps.sigma_y = sigma_y;
  return ps;
}

/// The files and record of a finished probe (a failed one gets the record of failed_record).
json write_probe(const qs::ProbeResult& p, const YieldArgs& a, const Analytic& an, const json& setup, const fs::path& out) {
  if (p.status.rfind("error: ", 0) != 0) return probe_record(p, a, an, setup, out);
  json r = failed_record(p.index, a.directions, csv_text(p.status), an, setup);
  netdem::app::write_file_atomic(out / "probes" / fmt::format("probe_{:03d}.json", p.index), r.dump(1) + "\n");
  return r;
}

/// Runs the probes in worker processes (this program with --probe-worker k, at most `jobs` at a
/// time), each restoring out/probes/unloaded_state.txt; a worker that fails gets a failed record.
void run_workers(const YieldArgs& a, const std::vector<int>& selection, int jobs, const fs::path& out, const Analytic& an,
                 const json& setup, const std::function<void(int, const json&)>& finished) {
  std::fflush(stdout);
  std::fflush(stderr);
  std::map<pid_t, int> running;
  std::size_t next = 0;
  auto reap = [&]() {
    int st = 0;
    const pid_t pid = ::waitpid(-1, &st, 0);
    if (pid <= 0) throw std::runtime_error("waitpid failed while probes were running");
    const auto it = running.find(pid);
    if (it == running.end()) return;
    const int idx = it->second;
    running.erase(it);
    const auto jf = out / "probes" / fmt::format("probe_{:03d}.json", idx);
    json r;
    bool have = false;
    if (WIFEXITED(st) && WEXITSTATUS(st) == 0 && fs::exists(jf)) {
      std::ifstream in(jf);
      try {
        in >> r;
        have = true;
      } catch (const std::exception&) {
      }
    }
    if (!have) {
      const std::string why = WIFSIGNALED(st) ? fmt::format("crashed: signal {}", WTERMSIG(st))
                                              : fmt::format("failed: exit status {}", WIFEXITED(st) ? WEXITSTATUS(st) : -1);
      r = failed_record(idx, a.directions, why, an, setup);
      netdem::app::write_file_atomic(jf, r.dump(1) + "\n");
    }
    finished(idx, r);
  };
  while (next < selection.size() || !running.empty()) {
    if (next < selection.size() && static_cast<int>(running.size()) < jobs) {
      const int idx = selection[next++];
      std::vector<std::string> args = a.argv;
      args.push_back("--probe-worker");
      args.push_back(std::to_string(idx));
      std::vector<char*> cargs;
      for (auto& s : args) cargs.push_back(s.data());
      cargs.push_back(nullptr);
      pid_t pid = 0;
      const int rc = ::posix_spawn(&pid, "/proc/self/exe", nullptr, nullptr, cargs.data(), environ);
      if (rc != 0) throw std::runtime_error(fmt::format("cannot start a probe worker: {}", std::strerror(rc)));
      running[pid] = idx;
    } else {
      reap();
    }
  }
}

/// Worker process: probe k from the unloaded state of the run folder, written as probe files.
int run_probe_worker(const YieldArgs& a) {
#ifdef __linux__
  ::prctl(PR_SET_PDEATHSIG, SIGKILL);  // a killed run leaves no probe running
#endif
  qs::SolverOptions so, po;
  yield_options(a, so, po);
  po.law.reversible = false;  // the state was saved on the elastic branch
  const fs::path out = a.out;
  const auto state = qs::load_state((out / "probes" / "unloaded_state.txt").string());
  json w;
  {
    std::ifstream in(out / "probes" / "worker.json");
    if (!in) throw std::runtime_error(fmt::format("probe worker: {} is missing", (out / "probes" / "worker.json").string()));
    in >> w;
  }
  const json setup = w.at("setup");
  const Analytic an = make_analytic(setup.at("analytic"));
  const qs::ProbeSettings ps =
      probe_settings(a, w.at("first_step").get<double>(), w.at("loading_norm").get<double>(), so.law.sigma_y);
  qs::run_probes(state, po, {a.probe_worker}, ps, [&](const qs::ProbeResult& p) { write_probe(p, a, an, setup, out); });
  return 0;
}

int run_yield(const YieldArgs& a, const std::string& command) {
  using namespace netdem;
  if (a.probe_worker >= 0) return run_probe_worker(a);
  const auto t_start = Clock::now();
  // ---- validate everything before the output folder exists
  qs::SolverOptions so, po;
  yield_options(a, so, po);
  const auto compact_mode = so.mode, probe_mode = po.mode;
  if (compact_mode != probe_mode && so.law.mu != 0.0)
    throw std::invalid_argument(
        "--compact-bc differs from --probe-bc: only frictionless runs (--friction 0) can switch, the solver is rebuilt "
        "from the compacted state and would lose the tangential contact forces");
  if (a.precompact != "hydrostatic" && a.precompact != "closed-die")
    throw std::invalid_argument(fmt::format("--precompact '{}' is not 'hydrostatic' or 'closed-die'", a.precompact));
  qs::CompactionOptions co;
  co.path = qs::StrainPath::parse(a.precompact);
  co.target_density = a.to_density;
  co.increments = a.increments;
  const auto selection = select_probes(a);
  if (!(a.offset > 0.0) || !(a.max_strain > a.offset) || !(a.window > 0.0) || !(a.unload_tol > 0.0) || !(a.growth >= 1.0) ||
      a.fine < 5 || !std::isfinite(a.max_strain) || !std::isfinite(a.window) || !std::isfinite(a.unload_tol) ||
      !std::isfinite(a.growth))
    throw std::invalid_argument(
        "probe options: need finite --offset > 0, --max-strain > --offset, --window > 0, --unload-tol > 0, --growth >= 1, "
        "and --fine >= 5");
  const int jobs = a.jobs > 0 ? a.jobs : std::max(1u, std::thread::hardware_concurrency());
  if (a.jobs < 0) throw std::invalid_argument(fmt::format("--jobs must be >= 1 (0: number of cores), got {}", a.jobs));
  if (!a.from_state.empty() && !a.packing_file.empty()) throw std::invalid_argument("--from-state and --packing exclude each other");

  {
    app::RunDirOptions rdo;
    rdo.overwrite = a.overwrite;
    rdo.inputs = {a.packing_file, a.from_state};
    app::check_run_dir(a.out, rdo);  // before any work: a refused folder is exit 2, nothing touched
  }
  if (!a.from_state.empty() && fs::is_directory(a.from_state))
    throw app::UsageError(fmt::format("--from-state '{}' is a folder, not a state file (netsolve compact --save-state writes "
                                      "DIR/state.txt)", a.from_state.substr(0, 80)));
  std::string source;
  packing::Packing pk;
  std::unique_ptr<qs::NetworkSolver> solver;
  if (a.from_state.empty()) {
    if (a.packing_file.empty()) app::netsolve::check_deposition_size(a.pack, true);
    app::netsolve::activity() = a.packing_file.empty() ? "building the ballistic deposition" : "reading the packing " + a.packing_file;
    pk = app::netsolve::input_packing(a.packing_file, a.pack, source, "netsolve yield");
    co.validate(pk.density());
  } else {
    solver = restore_compacted(a, co.path, so);
    source = "state " + a.from_state;
  }

  const fs::path out = a.out;
  app::RunDirOptions rdo;
  rdo.overwrite = a.overwrite;
  rdo.inputs = {a.packing_file, a.from_state};
  app::open_run_dir(out, command, rdo);
  app::make_output_dir(out / "probes");
  // probe files of an earlier run in this folder would mix into yield-merge: remove them
  for (const auto& e : fs::directory_iterator(out / "probes")) {
    const auto name = e.path().filename().string();
    if (name.rfind("probe_", 0) == 0 && (e.path().extension() == ".csv" || e.path().extension() == ".json"))
      fs::remove(e.path());
  }
  if (!solver) packing::write_packing_csv(pk, out / "packing.csv");
  const double sy = so.law.sigma_y;
  if (!a.quiet)
    std::fprintf(stderr, "netsolve yield: %zu particles, D0 = %.4f (%s); %s %s-%s, friction %s, %zu of %d probes, %d jobs\n",
                 solver ? solver->size() : pk.size(), solver ? solver->initial_density() : pk.density(), source.c_str(),
                 a.precompact.c_str(), bc_name(compact_mode), bc_name(probe_mode), a.law.friction.c_str(), selection.size(),
                 a.directions, jobs);

  // ---- precompaction (or the restored state)
  auto t0 = Clock::now();
  int unconverged = 0;
  qs::StateMeasures loaded;
  app::netsolve::ConvergenceRecord conv;
  conv.tol = so.residual_tol;
  app::netsolve::activity() = "precompacting";
  if (!solver) {
    solver = std::make_unique<qs::NetworkSolver>(pk, so);
    std::string hist = "increment,E11,E22,D,S11,S22,S12,Z,contacts,residual,newton,converged,net_force_ratio,eq13_vs_contacts\n";
    app::Progress progress("precompact", co.increments, a.quiet);
    app::netsolve::ResidualGrowth growth;  // the stop rule of `compact` (docs/quasistatic.md "Run status")
    growth.tol = so.residual_tol;
    std::string stopped;
    int done = 0;
    const auto on_row = [&](const qs::CompactionRow& row) {
      const auto& m = row.state;
      hist += fmt::format("{},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.6g},{},{:.3e},{},{},{:.3e},{:.3e}\n", row.increment, m.E11,
                          m.E22, m.density, m.S11 / sy, m.S22 / sy, m.S12 / sy, m.Z, m.contacts, row.report.residual,
                          row.report.newton_iterations, row.report.converged ? 1 : 0, m.net_force_ratio,
                          m.eq13_vs_contacts);
      if (row.increment > 0) {
        unconverged += !row.report.converged;
        conv.add(row.increment, row.report.converged, row.report.newton_residual);
      }
      done = row.increment;
      progress.update(row.increment);
      loaded = m;
      if (row.increment > 0 && growth.add(row.increment, row.report.newton_residual))
        throw app::netsolve::StopRun{growth.message(row.increment, row.report.newton_residual)};
    };
    try {
      qs::run_compaction(*solver, co, on_row);
    } catch (const app::netsolve::StopRun& s) {
      stopped = s.reason;
    } catch (const qs::DivergedError& e) {
      stopped = fmt::format("increment {}: {}", done + 1, e.what());
    }
    progress.finish();
    if (!stopped.empty()) hist += "# stopped: " + stopped + "\n";
    app::write_file_atomic(out / "history.csv", hist);
    if (!stopped.empty()) {  // no unloading or probes from a diverged precompaction
      app::netsolve::RunStatus st;
      st.add("unstable", "precompaction stopped: " + stopped);
      conv.judge(st, "precompaction");
      json j;
      j["command"] = command;
      st.write(j);
      j["allow_unconverged"] = a.allow_unconverged;
      j["precompaction"] = {{"increments_done", done}, {"increments", co.increments}, {"unconverged_increments", unconverged},
                            {"max_newton_residual", conv.max_newton_residual}, {"D", loaded.density}, {"Z", loaded.Z}};
      app::write_file_atomic(out / "summary.json", j.dump(2) + "\n");
      app::close_run_dir(out);
      std::fprintf(stderr, "netsolve yield: error: unstable: precompaction: %s (history.csv keeps increments 0..%d)\n",
                   stopped.c_str(), done);
      return app::exit_code::untrustworthy;
    }
  } else {
    loaded = solver->measures();
  }
  const double D0 = solver->initial_density();
  const double t_compact = seconds_since(t0);

  json setup;
  setup["precompact"] = a.precompact;
  setup["to_density"] = a.from_state.empty() ? a.to_density : loaded.density;
  setup["friction"] = a.law.friction;
  setup["normal_unloading"] = a.law.normal_unloading;
  setup["first_touch"] = a.law.first_touch;
  setup["compact_bc"] = bc_name(compact_mode);
  setup["probe_bc"] = bc_name(probe_mode);
  setup["directions"] = a.directions;
  setup["packing"] = source;
  setup["particles"] = solver->size();
  setup["sigma_y"] = sy;
  setup["offset"] = a.offset;
  setup["window"] = a.window;
  setup["analytic"] = {{"D0", D0},       {"D", loaded.density},      {"Z0", loaded.Z},
                       {"sigma_y", sy},  {"dir11", co.path.E11},     {"dir22", co.path.E22}};
  setup["loading"] = {{"S11", loaded.S11 / sy}, {"S22", loaded.S22 / sy}, {"S12", loaded.S12 / sy}};
  {  // fabric-resolved affine bound at the loading point, one point per probe direction
    json f11 = json::array(), f22 = json::array();
    for (int k = 0; k < a.directions; ++k) {
      const auto p = qs::fabric_affine_point(*solver, 2 * kPi * k / a.directions, sy);
      f11.push_back(jnum(p.S11));
      f22.push_back(jnum(p.S22));
    }
    setup["fabric"] = {{"S11", f11}, {"S22", f22}};
  }
  const Analytic an = make_analytic(setup["analytic"]);

  // ---- the probe phase's options; a switch of boundary mode rebuilds the solver (frictionless only)
  json handover = nullptr;
  if (probe_mode != compact_mode) {
    qs::HandoverReport h;
    solver = qs::switch_boundary_mode(*solver, solver->initial_box(), solver->seed(), po, h);
    handover = {{"contacts", h.contacts},
                {"contacts_unloaded_before_handover", h.contacts_unloaded},
                {"S11_before", h.S11_before}, {"S22_before", h.S22_before},
                {"S11_after", h.S11_after},   {"S22_after", h.S22_after},
                {"zero_strain_increments", h.zero_strain_increments}, {"unconverged", h.unconverged},
                {"centres_outside_box", h.centres_outside_box}, {"box_area_growth", h.box_area_growth}};
    packing::write_packing_csv(h.compacted, out / "packing_compacted.csv");
  } else {
    solver = std::make_unique<qs::NetworkSolver>(solver->state(), po);
  }

  // ---- unloading: from here on the section 3.4 elastic un/reloading branch, every contact
  // starting at its current overlap
  solver->set_reversible_normal(false);
  t0 = Clock::now();
  qs::UnloadOptions uo;
  uo.tol = a.unload_tol;
  uo.first_step = 0.2 * 2.0 * std::hypot(loaded.E11, loaded.E22) / so.law.unload_ratio;
  const auto un = qs::unload(*solver, co.path.rate(), sy, so.law.unload_ratio, uo);
  std::string ucsv = "increment,strain,S11,S22,S12,D,Z,contacts,newton,converged\n";
  for (std::size_t k = 0; k < un.path.size(); ++k) {
    const auto& m = un.path[k].state;
    ucsv += fmt::format("{},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.6g},{},{},{}\n", k, un.path[k].strain, m.S11 / sy,
                        m.S22 / sy, m.S12 / sy, m.density, m.Z, m.contacts, un.path[k].report.newton_iterations,
                        k == 0 || un.path[k].report.converged ? 1 : 0);
  }
  app::write_file_atomic(out / "unload.csv", ucsv);
  const double t_unload = seconds_since(t0);
  if (!a.quiet && !un.converged) std::fprintf(stderr, "netsolve yield: warning: %s\n", un.message.c_str());
  const double first_step = un.strain > 0 ? un.strain / 10 : 1e-6;
  const double loading_norm = std::sqrt(loaded.S11 * loaded.S11 + loaded.S22 * loaded.S22 + 2 * loaded.S12 * loaded.S12) / sy;

  // ---- probes: each on its own solver restored from the unloaded state, in `jobs` worker processes
  t0 = Clock::now();
  const qs::ProbeSettings ps = probe_settings(a, first_step, loading_norm, sy);
  // the unloaded state and the probe settings, which the worker processes (and anyone who wants to
  // rerun a probe) start from
  qs::save_state(solver->state(), (out / "probes" / "unloaded_state.txt").string());
  app::write_file_atomic(out / "probes" / "worker.json",
                         json({{"setup", setup}, {"first_step", first_step}, {"loading_norm", loading_norm}}).dump(1) + "\n");
  std::map<int, json> records;
  std::size_t done = 0;
  auto finished = [&](int idx, const json& r) {
    ++done;
    if (!a.quiet)
      std::fprintf(stderr, "probe %3d (theta %6.1f deg): %s [%zu/%zu]\n", idx, from_json(r["theta"]),
                   r.value("status", "?").c_str(), done, selection.size());
    records[idx] = r;
  };
  if (jobs == 1 || selection.size() == 1) {
    qs::run_probes(solver->state(), solver->options(), selection, ps, [&](const qs::ProbeResult& p) {
      finished(p.index, write_probe(p, a, an, setup, out));
    });
  } else {
    run_workers(a, selection, jobs, out, an, setup, finished);
  }
  const double t_probes = seconds_since(t0);

  std::vector<json> recs;
  double probe_wall_sum = 0;
  int ok = 0;
  for (int idx : selection) {
    recs.push_back(records[idx]);
    probe_wall_sum += records[idx].value("wall_s", 0.0);
    ok += records[idx].value("status", "") == "ok";
  }
  write_assembly(out, recs, setup, setup_title(setup));

  // ---- status: the precompaction's convergence, the unloading; a failed probe is its own record
  app::netsolve::RunStatus status;
  conv.judge(status, "precompaction");
  // an unloading that stops at its noise floor within 10 x --unload-tol is the documented
  // behaviour (docs/yield.md; the default scene ends at 1.9e-3 against 1e-3): recorded in
  // "unloading", not a failure; beyond that the probes start from a loaded state
  if (!un.converged && !(un.stress_norm <= app::netsolve::ConvergenceRecord::kResidualFactor * a.unload_tol))
    status.add("unconverged", fmt::format("unloading ended at |Sigma| = {:.3g} sigma_y, above 10 x --unload-tol = {:.3g}: {}",
                                          un.stress_norm, 10 * a.unload_tol, un.message));
  const double total = seconds_since(t_start);
  json j;
  j["command"] = command;
  status.write(j);
  j["allow_unconverged"] = a.allow_unconverged;
  j["setup"] = setup;
  j["seed"] = solver->seed();
  j["initial_density"] = D0;
  j["precompaction"] = {{"D", loaded.density}, {"Z", loaded.Z},           {"S11", loaded.S11 / sy},
                        {"S22", loaded.S22 / sy}, {"S12", loaded.S12 / sy}, {"E11", loaded.E11},
                        {"E22", loaded.E22},   {"contacts", loaded.contacts}, {"unconverged_increments", unconverged},
                        {"increments", co.increments}, {"max_newton_residual", conv.max_newton_residual},
                        {"last_increment_converged", conv.last_converged}};
  if (!a.from_state.empty()) {
    j["precompaction"]["from_state"] = a.from_state;
    j["precompaction"]["unconverged_increments"] = nullptr;  // not known from the state
    j["precompaction"]["increments"] = nullptr;
    j["precompaction"]["max_newton_residual"] = nullptr;
    j["precompaction"]["last_increment_converged"] = nullptr;
  }
  j["analytic"] = {{"ok", an.ok}, {"message", an.message}};
  if (an.ok) {
    const auto lp = qs::affine_loading_point(an.in);
    j["analytic"]["loading_point"] = {{"S11", lp.S11 / sy}, {"S22", lp.S22 / sy}};
    j["analytic"]["E11"] = an.in.E11;
    j["analytic"]["E22"] = an.in.E22;
  }
  j["handover"] = handover;
  j["unloading"] = {{"converged", un.converged}, {"increments", static_cast<int>(un.path.size()) - 1},
                    {"strain", un.strain},       {"stress_norm", un.stress_norm},
                    {"loading_norm", un.loading_norm}, {"message", un.message}};
  j["probes"] = {{"run", selection.size()},  {"ok", ok},  {"directions", a.directions}, {"jobs", jobs},
                 {"first_step", first_step}, {"offset", a.offset}, {"max_strain", a.max_strain}, {"window", a.window},
                 {"indices", selection}};
  j["solver"] = {{"precompaction", {{"tol", so.residual_tol}, {"viscosity", so.viscosity},
                                    {"viscosity_strain", so.viscosity_strain}, {"chord_steps", so.chord_steps},
                                    {"linear_tol", so.linear_tolerance}, {"max_newton", so.max_newton}}},
                 {"probes", {{"tol", po.residual_tol}, {"viscosity", po.viscosity},
                             {"viscosity_strain", po.viscosity_strain}, {"chord_steps", po.chord_steps},
                             {"linear_tol", po.linear_tolerance}, {"max_newton", po.max_newton}}}};
  j["timing_s"] = {{"total", total},
                   {"compaction", t_compact},
                   {"unloading", t_unload},
                   {"probes", t_probes},
                   {"probe_wall_sum", probe_wall_sum},
                   {"share", {{"compaction", t_compact / total}, {"unloading", t_unload / total}, {"probes", t_probes / total}}}};
  app::write_file_atomic(out / "summary.json", j.dump(2) + "\n");
  app::close_run_dir(out);
  std::printf("D = %.4f (Z = %.3f): loading point S11/sy = %.4f, S22/sy = %.4f; unloaded to |S| = %.1e in %d increments; "
              "%d/%zu probes ok; %.1f s (compaction %.1f, unloading %.1f, probes %.1f) -> %s\n",
              loaded.density, loaded.Z, loaded.S11 / sy, loaded.S22 / sy, un.stress_norm, static_cast<int>(un.path.size()) - 1,
              ok, selection.size(), total, t_compact, t_unload, t_probes, out.c_str());
  if (!status.ok())
    std::fprintf(stderr, "netsolve yield: %s: %s: %s\n", a.allow_unconverged ? "warning (--allow-unconverged)" : "error",
                 status.status.c_str(), status.reason().c_str());
  return status.exit_code(a.allow_unconverged);
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
  write_assembly(out, recs, setup, setup_title(setup) + " (merged)");
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
  std::printf("merged %zu of %d probes from %zu folders%s -> %s\n", recs.size(), directions, dirs.size(),
              missing.empty() ? "" : fmt::format(" ({} missing)", missing.size()).c_str(), out.c_str());
  return 0;
}

}  // namespace

/// Entry point of `netsolve yield` and `netsolve yield-merge` (argv[1] is the subcommand).
int run_yield_command(int argc, char** argv) {
  std::string command;
  for (int k = 0; k < argc; ++k) command += (k ? " " : "") + std::string(argv[k]);
  const std::string sub = argv[1];
  CLI::App app{"netsolve " + sub};
  YieldArgs a;
  a.law = netdem::app::netsolve::law_args(qs::SolverOptions::yield_precompaction());
  for (int k = 0; k < argc; ++k) a.argv.emplace_back(argv[k]);
  std::vector<std::string> dirs;
  std::string merge_out = "results/yield_merged";
  if (sub == "yield") {
    app.description(
        "netsolve yield: precompact, unload elastically, reload along N strain-rate directions in the (E11, E22) plane "
        "and locate the yield points (Redanz & Fleck 2001 section 3.4; docs/yield.md)");
    app.add_option("--width", a.pack.width, "box width W of a new deposition in units of R")->capture_default_str();
    app.add_option("--r-min", a.pack.r_min, "smallest radius / R")->capture_default_str();
    app.add_option("--r-max", a.pack.r_max, "largest radius / R")->capture_default_str();
    app.add_flag("--mono", a.pack.mono, "monosized disks");
    app.add_option("--seed", a.pack.seed, "random seed of the deposition, a whole number in [0, 2^64)")
        ->check(netdem::app::netsolve::seed_validator())
        ->capture_default_str();
    app.add_option("--packing", a.packing_file, "packing CSV instead of a new deposition")
        ->check(CLI::Validator([](std::string& v) { return v.empty() ? std::string("is empty: give a packing CSV file") : std::string(); }, "FILE"));
    app.add_option("--from-state", a.from_state,
                   "start from a compacted state (state.txt of `netsolve compact --save-state`) instead of precompacting; "
                   "its strain must lie along --precompact");
    app.add_option("--precompact", a.precompact, "hydrostatic | closed-die")->capture_default_str();
    app.add_option("--to-density", a.to_density, "precompaction density D")->capture_default_str();
    app.add_option("--increments", a.increments, "precompaction increments")->capture_default_str();
    app.add_option("--compact-bc", a.compact_bc, "affine | die (local relaxation) during precompaction")->capture_default_str();
    app.add_option("--probe-bc", a.probe_bc, "affine | die during unloading and probing (default: --compact-bc)");
    app.add_option("--directions", a.directions, "probes, theta_k = 360 k / N degrees, (E11dot, E22dot) = (cos, sin)")->capture_default_str();
    app.add_option("--probe", a.probe_slice, "run only the slice i/N: probes k with k mod N == i (job arrays)");
    app.add_option("--probes", a.probe_list, "run only these probe indices, e.g. 0,3,5");
    app.add_option("--jobs", a.jobs, "probes run at the same time (0: number of cores)")->capture_default_str();
    app.add_option("--offset", a.offset, "offset strain of the offset yield point")->capture_default_str();
    app.add_option("--max-strain", a.max_strain, "longest probe |dE|")->capture_default_str();
    app.add_option("--window", a.window, "curvature smoothing width (normalised arc length)")->capture_default_str();
    app.add_option("--fine", a.fine, "equal fine probe steps (unloading strain / 10 each) before the steps grow")->capture_default_str();
    app.add_option("--growth", a.growth, "growth factor of the probe steps after the fine ones")->capture_default_str();
    app.add_option("--unload-tol", a.unload_tol, "unload until |Sigma| < tol sigma_y")->capture_default_str();
    netdem::app::netsolve::add_law_options(
        app, a.law,
        "normal law during the precompaction: 'reversible' (Eq 2 both ways, the paper's compaction) or "
        "'elastic' (section 3.4 branch throughout); unloading and probes always use the elastic branch");
    app.add_flag("--quiet", a.quiet, "no progress on stderr");
    app.add_flag("--allow-unconverged", a.allow_unconverged,
                 "exit 0 for a run that summary.json marks 'unconverged' (precompaction or unloading; the status is kept)");
    app.add_flag("--overwrite", a.overwrite, "replace the files of an earlier run in --out (README.md 'Run folders')");
    app.add_option("--out", a.out, "output folder")->capture_default_str();
    app.add_option("--probe-worker", a.probe_worker, "internal: run one probe from the run folder's unloaded state")
        ->group("");
  } else {
    app.description("netsolve yield-merge: assemble yield_points.csv and surface.svg from the probe files of several yield runs");
    app.add_option("dirs", dirs, "run folders (each with probes/)")->required();
    app.add_option("--out", merge_out, "output folder")->capture_default_str();
    app.add_flag("--overwrite", a.overwrite, "replace the files of an earlier merge in --out (README.md 'Run folders')");
  }
  try {
    app.parse(argc - 1, argv + 1);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    std::fprintf(stderr, "netsolve %s: error: %s (see --help)\n", sub.c_str(), e.what());
    return 2;
  }
  return netdem::app::netsolve::guarded("netsolve " + sub, [&]() {
    if (sub == "yield") return run_yield(a, command);
    return run_merge(dirs, merge_out, command, a.overwrite);
  });
}
