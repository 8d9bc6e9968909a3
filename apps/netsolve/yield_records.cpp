// netsolve yield's records and files (yield_records.hpp): one probe's files and record,
// yield_points.csv and the surface plot assembled from the records, and yield-merge, which does
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

void write_assembly(const fs::path& out, const std::vector<json>& recs, const json& setup, const std::string& title) {
  std::string csv = kYieldHeader;
  for (const auto& r : recs) csv += yield_row(r);
  netdem::app::write_file_atomic(out / "yield_points.csv", csv);
  const Analytic an = make_analytic(setup.at("analytic"));
  netdem::app::write_file_atomic(out / "surface.svg",
                                 surface_svg(recs, an, from_json(setup["loading"]["S11"]), from_json(setup["loading"]["S22"]), title));
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

}  // namespace netdem::app::netsolve::yield
