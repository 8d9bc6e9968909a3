// demsolve compress and vibrate: the material tests of LMM05 section 4.4 on a saved state; the
// tests themselves are in netdem/dynamic/material_tests.hpp, this file parses, calls and writes.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <stdexcept>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "netdem/dynamic/material_tests.hpp"
#include "netdem/dynamic/protocol.hpp"
#include "netdem/dynamic/state.hpp"
#include "protocol.hpp"
#include "run_status.hpp"

namespace fs = std::filesystem;
using namespace netdem::dem;

namespace netdem::app::dem {

namespace {

void write_common(const std::string& command, const SolverState& st, const fs::path& out, nlohmann::json extra,
                  bool overwrite, const std::string& input) {
  RunDirOptions rdo;
  rdo.overwrite = overwrite;
  rdo.inputs = {input};
  open_run_dir(out, command, rdo);
  nlohmann::json params;
  for (const auto& name : luding_param_names()) params[name] = get_luding_param(st.params, name);
  extra["command"] = command;
  extra["particles"] = st.particle_count();
  extra["dt_s"] = st.dt;
  extra["start_time_s"] = st.time;
  extra["temperature_C"] = st.thermal.T;
  extra["contact_params"] = params;
  write_file_atomic(out / "parameters.json", extra.dump(2) + "\n");
}

}  // namespace

namespace {
template <int D>
int run_compress_body(const std::string& command, const CompressArgs& a, const fs::path& out, const CompressionTest& test,
                      SolverState& st);
}  // namespace

int run_compress(const std::string& command, const CompressArgs& a, const fs::path& out) {
  CompressionTest test;
  test.strain_rate = a.strain_rate;
  test.max_strain = a.max_strain;
  test.ramp_time = a.ramp_time;
  test.validate();
  if (!(std::isfinite(a.pressure) && a.pressure >= 0.0))
    throw std::invalid_argument(fmt::format("--pressure must be a positive number of N/m, got {}", a.pressure));
  SolverState st = load_state(a.state_file, a.param_overrides);
  return st.dim() == 3 ? run_compress_body<3>(command, a, out, test, st) : run_compress_body<2>(command, a, out, test, st);
}

namespace {
template <int D>
int run_compress_body(const std::string& command, const CompressArgs& a, const fs::path& out, const CompressionTest& test,
                      SolverState& st) {
  const double p = a.pressure > 0.0 ? a.pressure : st.box.right.pressure;
  if (!(p > 0.0)) throw std::invalid_argument("the state has no wall pressure: give --pressure");
  const std::string warning = check_loading(p, st.params, a.pressure > 0.0 ? "--pressure" : "the state's wall pressure", D);
  check_temperature(st.thermal.T, st.params, "the state's temperature");
  check_memory(st.particle_count());
  DynamicOptions opt;
  opt.model = ContactModel::Full;
  opt.threads = a.threads;
  DynamicSolverT<D> s(st, opt);
  const double z0 = D == 2 ? s.box().y_max - s.box().y_min : s.box().z_max - s.box().z_min, t_start = s.time();
  check_run_limits(s, (a.max_strain / a.strain_rate + 0.5 * a.ramp_time) / s.dt(), a.max_steps, a.allow_long);
  {  // the top wall's travel per contact duration (Eq 6, mean pair) below 0.1 r_min
    double rmin = s.particles().r[0];
    for (double r : s.particles().r) rmin = std::min(rmin, r);
    const double v = a.strain_rate * z0, tc = s.time_step().tc_mean, vmax = 0.1 * rmin / tc;
    if (!(v <= vmax))
      throw UsageError(fmt::format("--strain-rate {:g} 1/s moves the top wall at {:.3g} m/s, {:.3g} m per contact "
                                   "duration (t_c = {:.3g} s), above 0.1 r_min = {:.3g} m: the test is no longer "
                                   "quasi-static (at most {:.3g} 1/s)",
                                   a.strain_rate, v, v * tc, tc, 0.1 * rmin, vmax / z0));
  }
  write_common(command, st, out,
               {{"test", "compress"}, {"state_file", a.state_file}, {"strain_rate_per_s", a.strain_rate},
                {"max_strain", a.max_strain}, {"ramp_time_s", a.ramp_time}, {D == 2 ? "pressure_N_per_m" : "pressure_N_per_m2", p}, {"top_wall_velocity_m_per_s", -a.strain_rate * z0}},
               a.overwrite, a.state_file);
  const double nu0 = s.density();

  /// compress.csv rows, and snapshots at the times of LMM05 Fig 20 (default rate: eps_zz = t)
  struct Writer final : TestObserverT<D> {
    double z0, p, t_start;
    const fs::path& out;
    SnapshotSeries series = protocol_snapshot_series(out);  // its time: compress.csv's t
    Progress progress;
    std::string csv = D == 2 ? "t,eps_zz,szz,szz_over_p,sxx_over_p,szz_contacts,nu,C\n"
                             : "t,eps_zz,szz,szz_over_p,sxx_over_p,syy_over_p,szz_contacts,nu,C\n";
    std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
    std::vector<ContactInfo> cs;
    const double snap_t[5] = {0.005, 0.02, 0.03, 0.035, 0.04};
    std::size_t next_snap = 0;
    Writer(double z0_, double p_, double t_start_, const fs::path& out_, double steps, bool quiet)
        : z0(z0_), p(p_), t_start(t_start_), out(out_), progress("compress", steps, quiet) {}
    void sample(const DynamicSolverT<D>& s, std::int64_t k) override {
      if (k == 0) {
        s.check_health();
        write_snapshot(s, series, "eps0", s.time() - t_start, cs);
      }
      const auto ws = s.wall_stress();
      const double C = count_contacts(s, pairs).coordination(s.particles().size());
      if constexpr (D == 2)
        csv += fmt::format("{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.6g}\n", s.time() - t_start,
                           vertical_strain(s, z0), ws.yy, ws.yy / p, ws.xx / p, s.contact_stress().yy, s.density(), C);
      else
        csv += fmt::format("{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.6g}\n", s.time() - t_start,
                           vertical_strain(s, z0), ws.s[2][2], ws.s[2][2] / p, ws.s[0][0] / p, ws.s[1][1] / p,
                           s.contact_stress().s[2][2], s.density(), C);
      if (k > 0) progress.update(static_cast<double>(k));
    }
    void stepped(const DynamicSolverT<D>& s, std::int64_t) override {
      if (next_snap < std::size(snap_t) && s.time() - t_start >= snap_t[next_snap] - 0.5 * s.dt()) {
        s.check_health();
        write_snapshot(s, series, fmt::format("t{}", snap_t[next_snap]), s.time() - t_start, cs);
        ++next_snap;
      }
    }
  };
  Writer writer(z0, p, t_start, out, static_cast<double>(test.steps(s.dt())), a.quiet);
  const auto t0 = std::chrono::steady_clock::now();
  nlohmann::json fail{{"command", command}, {"state_file", a.state_file}, {"test", "compress"}};
  CompressionRun run;
  try {
    run = run_compression(s, test, p, 2000, writer);
    s.check_health();
  } catch (const InstabilityError& e) {
    writer.progress.finish();
    return report_unstable(e, s, out, fail);
  }
  writer.progress.finish();
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  write_file_atomic(out / "compress.csv", writer.csv);
  write_file_atomic(out / "state.txt", format_state(s.state()));
  write_snapshot(s, writer.series, "final", s.time() - t_start, writer.cs);
  // failure: the peak of szz; stiffness: least-squares slope of szz over eps in [0, 0.005]
  const CompressionFigures fig = compression_figures(run, 0.005);
  const std::size_t ipk = fig.peak;
  nlohmann::json j{{"command", command},
                   {"state_file", a.state_file},
                   {D == 2 ? "pressure_N_per_m" : "pressure_N_per_m2", p},
                   {"strain_rate_per_s", a.strain_rate},
                   {"ramp_time_s", a.ramp_time},
                   {"peak_szz", run.szz[ipk]},
                   {"peak_szz_over_p", run.szz[ipk] / p},
                   {"peak_strain", run.eps[ipk]},
                   {"stiffness", fig.stiffness},
                   {"stiffness_window", {0.0, 0.005}},
                   {"nu_initial", nu0},
                   {"nu_final", s.density()},
                   {"steps", run.steps},
                   {"wall_time_s", wall},
                   {"status", "ok"},
                   {"status_reason", warning.empty() ? "every instability check passed"
                                                     : "every instability check passed; warning: " + warning}};
  if constexpr (D == 3) j["dim"] = 3;
  write_file_atomic(out / "summary.json", j.dump(2) + "\n");
  close_run_dir(out);
  netdem::app::summary_printf("compress: peak szz = %.4g %s (%.3f p) at eps_zz = %.4f, stiffness %.4g %s over eps in [0, 0.005], "
              "%.1f s -> %s\n",
              run.szz[ipk], D == 2 ? "N/m" : "N/m^2", run.szz[ipk] / p, run.eps[ipk], fig.stiffness,
              D == 2 ? "N/m" : "N/m^2", wall, out.c_str());
  return 0;
}
}  // namespace


int run_vibrate(const std::string& command, const VibrateArgs& a, const fs::path& out) {
  VibrationTest test;
  test.frequency = a.frequency;
  test.amplitude = a.amplitude;
  test.time = a.time;
  test.gravity = a.gravity;
  test.validate();
  if (!(a.amplitude <= 0.1)) throw UsageError(fmt::format("--amplitude must be at most 0.1 m, got {:g}", a.amplitude));
  if (!(a.gravity <= 1e4)) throw UsageError(fmt::format("--gravity must be at most 1e4 m/s^2, got {:g}", a.gravity));
  if (a.gravity > 0.0 && a.gravity < 1e-6)  // accelerations are reported in units of g
    throw UsageError(fmt::format("--gravity must be 0 or at least 1e-6 m/s^2, got {:g}", a.gravity));
  SolverState st = load_state(a.state_file, a.param_overrides);
  if (st.dim() == 3)
    throw UsageError(fmt::format("{} is a 3D state: demsolve vibrate is 2D only (prepare, sinter and compress take 3D)",
                                 quote_input(a.state_file)));
  check_temperature(st.thermal.T, st.params, "the state's temperature");
  check_memory(st.particle_count());
  open_box_for_vibration(st);
  DynamicOptions opt;
  opt.model = ContactModel::Full;
  opt.threads = a.threads;
  DynamicSolver s(st, opt);
  const double w = 2.0 * std::numbers::pi * a.frequency, t_start = s.time();
  check_run_limits(s, a.time / s.dt(), a.max_steps, a.allow_long);
  {  // the floor's period resolved (>= 20 steps) and its peak speed A w below 0.1 r_min per step
    double rmin = s.particles().r[0];
    for (double r : s.particles().r) rmin = std::min(rmin, r);
    if (!(a.frequency * s.dt() <= 0.05))
      throw UsageError(fmt::format("--frequency {:g} Hz gives {:.3g} time steps of {:.3g} s per period, fewer than 20 "
                                   "(peak floor acceleration {:.3g} g)",
                                   a.frequency, 1.0 / (a.frequency * s.dt()), s.dt(), a.amplitude * w * w / 9.81));
    if (!(a.amplitude * w * s.dt() < 0.1 * rmin))
      throw UsageError(fmt::format("--amplitude {:g} m at {:g} Hz moves the floor {:.3g} m per step, not below 0.1 "
                                   "r_min = {:.3g} m (peak floor acceleration {:.3g} g)",
                                   a.amplitude, a.frequency, a.amplitude * w * s.dt(), 0.1 * rmin,
                                   a.amplitude * w * w / 9.81));
  }
  write_common(command, st, out,
               {{"test", "vibrate"}, {"state_file", a.state_file}, {"frequency_Hz", a.frequency},
                {"amplitude_m", a.amplitude}, {"time_s", a.time}, {"gravity_m_per_s2", a.gravity}},
               a.overwrite, a.state_file);
  const std::size_t n = s.particles().size();

  /// timeseries.csv rows: floor position, kinetic energy, centre height, clusters
  struct Writer final : TestObserver {
    double amplitude, w, t_start;
    const fs::path& out;
    SnapshotSeries series = protocol_snapshot_series(out);  // its time: timeseries.csv's t
    Progress progress;
    Clusters clusters;
    std::string csv = "t,floor_y,Ekin,y_centre,largest_cluster,single_grains\n";
    std::vector<ContactInfo> cs;
    Writer(double amplitude_, double w_, double t_start_, const fs::path& out_, double steps, bool quiet)
        : amplitude(amplitude_), w(w_), t_start(t_start_), out(out_), progress("vibrate", steps, quiet) {}
    void sample(const DynamicSolver& s, std::int64_t k) override {
      if (k == 0) {
        s.check_health();
        write_snapshot(s, series, "initial", s.time() - t_start, cs);
      }
      clusters.update(s);
      double yc = 0.0;
      for (std::size_t p = 0; p < s.particles().size(); ++p) yc += s.particles().coord(p, 1);
      const double tt = s.time() - t_start;
      csv += fmt::format("{:.9g},{:.9g},{:.9g},{:.9g},{},{}\n", tt, amplitude * std::sin(w * tt), s.energies().kinetic,
                         yc / static_cast<double>(s.particles().size()), clusters.largest(), clusters.single_grains());
      if (k > 0) progress.update(static_cast<double>(k));
    }
  };
  Writer writer(a.amplitude, w, t_start, out, static_cast<double>(test.steps(s.dt())), a.quiet);
  const auto t0 = std::chrono::steady_clock::now();
  std::int64_t steps = 0;
  try {
    steps = run_vibration(s, test, 1000, writer);
    s.check_health();
  } catch (const InstabilityError& e) {
    writer.progress.finish();
    return report_unstable(e, s, out, {{"command", command}, {"state_file", a.state_file}, {"test", "vibrate"}});
  }
  writer.progress.finish();
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  Clusters& clusters = writer.clusters;
  clusters.update(s);
  const std::vector<std::uint32_t> sizes = clusters.sizes();
  std::string cc = "cluster,size\n";
  for (std::size_t k = 0; k < sizes.size(); ++k) cc += fmt::format("{},{}\n", k, sizes[k]);
  write_file_atomic(out / "timeseries.csv", writer.csv);
  write_file_atomic(out / "clusters.csv", cc);
  write_file_atomic(out / "state.txt", format_state(s.state()));
  // cluster id per particle, numbered by decreasing size
  write_snapshot(s, writer.series, "final", s.time() - t_start, writer.cs, {Field{"cluster", 1, clusters.rank()}});
  const std::size_t singles = static_cast<std::size_t>(std::count(sizes.begin(), sizes.end(), 1u));
  nlohmann::json j{{"command", command},
                   {"state_file", a.state_file},
                   {"clusters", sizes.size()},
                   {"largest_cluster", sizes.front()},
                   {"largest_cluster_fraction", static_cast<double>(sizes.front()) / static_cast<double>(n)},
                   {"single_grain_fraction", static_cast<double>(singles) / static_cast<double>(n)},
                   {"peak_floor_acceleration_over_g", a.gravity > 0 ? a.amplitude * w * w / a.gravity : 0.0},
                   {"steps", steps},
                   {"wall_time_s", wall},
                   {"status", "ok"},
                   {"status_reason", "every instability check passed"}};
  write_file_atomic(out / "summary.json", j.dump(2) + "\n");
  close_run_dir(out);
  netdem::app::summary_printf("vibrate: %zu clusters, largest %u of %zu disks (%.3f), single grains %.3f, %.1f s -> %s\n", sizes.size(),
              sizes.front(), n, static_cast<double>(sizes.front()) / static_cast<double>(n),
              static_cast<double>(singles) / static_cast<double>(n), wall, out.c_str());
  return 0;
}

}  // namespace netdem::app::dem
