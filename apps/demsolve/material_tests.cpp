// demsolve compress and vibrate: the material tests of LMM05 section 4.4 on a saved state.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <numeric>
#include <stdexcept>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "netdem/dynamic/state.hpp"
#include "protocol.hpp"

namespace fs = std::filesystem;
using namespace netdem::dem;

namespace netdem::app::dem {

namespace {

void write_common(const std::string& command, const SolverState& st, const fs::path& out, nlohmann::json extra) {
  start_run_dir(out);
  write_file_atomic(out / "command.txt", command + "\n");
  nlohmann::json params;
  for (const auto& name : luding_param_names()) params[name] = get_luding_param(st.params, name);
  extra["command"] = command;
  extra["particles"] = st.particles.size();
  extra["dt_s"] = st.dt;
  extra["start_time_s"] = st.time;
  extra["temperature_C"] = st.thermal.T;
  extra["contact_params"] = params;
  write_file_atomic(out / "parameters.json", extra.dump(2) + "\n");
}

/// Keeps the material at the state's temperature (k1(T, t) keeps relaxing if it still moves).
void hold_temperature(DynamicSolver& s, double T, const LudingParams& p) { s.advance_temperature(T, s.dt(), p.t0); }

}  // namespace

int run_compress(const std::string& command, const CompressArgs& a, const fs::path& out) {
  if (!(std::isfinite(a.strain_rate) && a.strain_rate > 0.0))
    throw std::invalid_argument(fmt::format("--strain-rate must be a positive number of 1/s, got {}", a.strain_rate));
  if (!(std::isfinite(a.max_strain) && a.max_strain > 0.0 && a.max_strain < 0.9))
    throw std::invalid_argument(fmt::format("--max-strain must be in (0, 0.9), got {}", a.max_strain));
  if (!(std::isfinite(a.ramp_time) && a.ramp_time >= 0.0))
    throw std::invalid_argument(fmt::format("--ramp-time must be a number of seconds >= 0, got {}", a.ramp_time));
  if (!(std::isfinite(a.pressure) && a.pressure >= 0.0))
    throw std::invalid_argument(fmt::format("--pressure must be a positive number of N/m, got {}", a.pressure));
  SolverState st = load_state(a.state_file, a.param_overrides);
  const double p = a.pressure > 0.0 ? a.pressure : st.box.right.pressure;
  if (!(p > 0.0)) throw std::invalid_argument("the state has no wall pressure: give --pressure");
  DynamicOptions opt;
  opt.model = ContactModel::Full;
  DynamicSolver s(st, opt);
  const double z0 = s.box().y_max - s.box().y_min, t_start = s.time();
  MovingWall right = s.box().right, top = s.box().top;
  right.mode = WallMode::Stress;  // sigma_xx = p held by the right wall
  right.pressure = p;
  top.mode = WallMode::Strain;  // eps_zz = 1 - z/z0 = rate (t - t_start)
  top.velocity = a.ramp_time > 0.0 ? 0.0 : -a.strain_rate * z0;
  s.set_walls(right, top);
  write_common(command, st, out,
               {{"test", "compress"}, {"state_file", a.state_file}, {"strain_rate_per_s", a.strain_rate},
                {"max_strain", a.max_strain}, {"ramp_time_s", a.ramp_time}, {"pressure_N_per_m", p}, {"top_wall_velocity_m_per_s", -a.strain_rate * z0}});
  const double T = st.thermal.T, nu0 = s.density();
  // eps(t) = rate (t - t_ramp / 2) after the ramp
  const auto steps = static_cast<std::int64_t>(std::ceil((a.max_strain / a.strain_rate + 0.5 * a.ramp_time) / s.dt()));
  const std::int64_t every = std::max<std::int64_t>(1, steps / 2000);
  std::string csv = "t,eps_zz,szz,szz_over_p,sxx_over_p,szz_contacts,nu,C\n";
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
  std::vector<double> eps_v, szz_v;
  auto row = [&] {
    s.touching_pairs(pairs);
    const auto ws = s.wall_stress();
    const double eps = 1.0 - (s.box().y_max - s.box().y_min) / z0;
    const double C = (2.0 * static_cast<double>(pairs.size()) + static_cast<double>(s.wall_contacts())) /
                     static_cast<double>(s.particles().size());
    csv += fmt::format("{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.6g}\n", s.time() - t_start, eps, ws.yy,
                       ws.yy / p, ws.xx / p, s.contact_stress().yy, s.density(), C);
    eps_v.push_back(eps);
    szz_v.push_back(ws.yy);
  };
  // snapshots at the times of LMM05 Fig 20 (with the default rate, eps_zz = t)
  const double snap_t[] = {0.005, 0.02, 0.03, 0.035, 0.04};
  std::vector<ContactInfo> cs;
  write_snapshot(s, out, "eps0", cs);
  row();
  Progress progress("compress", static_cast<double>(steps), a.quiet);
  const auto t0 = std::chrono::steady_clock::now();
  std::size_t next_snap = 0;
  for (std::int64_t k = 1; k <= steps; ++k) {
    const double tt = static_cast<double>(k - 1) * s.dt();
    if (tt < a.ramp_time) {  // smooth start, v = v_f (1 - cos(pi t / t_ramp)) / 2
      top.velocity = -a.strain_rate * z0 * 0.5 * (1.0 - std::cos(std::numbers::pi * tt / a.ramp_time));
      s.set_walls(right, top);
    } else if (top.velocity != -a.strain_rate * z0) {
      top.velocity = -a.strain_rate * z0;
      s.set_walls(right, top);
    }
    hold_temperature(s, T, s.params());
    s.step();
    if (k % every == 0 || k == steps) {
      row();
      progress.update(static_cast<double>(k));
    }
    if (next_snap < std::size(snap_t) && s.time() - t_start >= snap_t[next_snap] - 0.5 * s.dt()) {
      write_snapshot(s, out, fmt::format("t{}", snap_t[next_snap]), cs);
      ++next_snap;
    }
  }
  progress.finish();
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  write_file_atomic(out / "compress.csv", csv);
  write_file_atomic(out / "state.txt", format_state(s.state()));
  write_snapshot(s, out, "final", cs);
  // failure: the peak of szz; stiffness: least-squares slope of szz over eps in [0, 0.005]
  const auto ipk = static_cast<std::size_t>(std::max_element(szz_v.begin(), szz_v.end()) - szz_v.begin());
  double se = 0, ss = 0, see = 0, ses = 0, m = 0;
  for (std::size_t k = 0; k < eps_v.size(); ++k)
    if (eps_v[k] >= 0.0 && eps_v[k] <= 0.005) {
      se += eps_v[k];
      ss += szz_v[k];
      see += eps_v[k] * eps_v[k];
      ses += eps_v[k] * szz_v[k];
      m += 1.0;
    }
  const double stiffness = m >= 3 ? (m * ses - se * ss) / (m * see - se * se) : std::nan("");
  nlohmann::json j{{"command", command},
                   {"state_file", a.state_file},
                   {"pressure_N_per_m", p},
                   {"strain_rate_per_s", a.strain_rate},
                   {"ramp_time_s", a.ramp_time},
                   {"peak_szz", szz_v[ipk]},
                   {"peak_szz_over_p", szz_v[ipk] / p},
                   {"peak_strain", eps_v[ipk]},
                   {"stiffness", stiffness},
                   {"stiffness_window", {0.0, 0.005}},
                   {"nu_initial", nu0},
                   {"nu_final", s.density()},
                   {"steps", steps},
                   {"wall_time_s", wall}};
  write_file_atomic(out / "summary.json", j.dump(2) + "\n");
  std::printf("compress: peak szz = %.4g N/m (%.3f p) at eps_zz = %.4f, stiffness %.4g N/m over eps in [0, 0.005], "
              "%.1f s -> %s\n",
              szz_v[ipk], szz_v[ipk] / p, eps_v[ipk], stiffness, wall, out.c_str());
  return 0;
}

int run_vibrate(const std::string& command, const VibrateArgs& a, const fs::path& out) {
  if (!(std::isfinite(a.frequency) && a.frequency > 0.0))
    throw std::invalid_argument(fmt::format("--frequency must be a positive number of Hz, got {}", a.frequency));
  if (!(std::isfinite(a.amplitude) && a.amplitude >= 0.0))
    throw std::invalid_argument(fmt::format("--amplitude must be a number of metres >= 0, got {}", a.amplitude));
  if (!(std::isfinite(a.time) && a.time > 0.0))
    throw std::invalid_argument(fmt::format("--time must be a positive number of seconds, got {}", a.time));
  if (!(std::isfinite(a.gravity) && a.gravity >= 0.0))
    throw std::invalid_argument(fmt::format("--gravity must be a number >= 0, got {}", a.gravity));
  SolverState st = load_state(a.state_file, a.param_overrides);
  // Confining stress removed: left, right and top walls moved far away (1 m), only the bottom
  // stays. The vibration y_floor = A sin(w t) is applied in the co-moving frame of the floor, as
  // the inertial force -m y_floor'' = m A w^2 sin(w t) added to gravity: exact for a rigid
  // translating floor (docs/sintering.md).
  st.box.x_min -= 1.0;
  st.box.x_max += 1.0;
  st.box.y_max += 1.0;
  st.box.right.mode = WallMode::Fixed;
  st.box.top.mode = WallMode::Fixed;
  st.wall_velocity[0] = st.wall_velocity[1] = 0.0;
  DynamicOptions opt;
  opt.model = ContactModel::Full;
  DynamicSolver s(st, opt);
  write_common(command, st, out,
               {{"test", "vibrate"}, {"state_file", a.state_file}, {"frequency_Hz", a.frequency},
                {"amplitude_m", a.amplitude}, {"time_s", a.time}, {"gravity_m_per_s2", a.gravity}});
  const double T = st.thermal.T, w = 2.0 * std::numbers::pi * a.frequency, t_start = s.time();
  const auto steps = static_cast<std::int64_t>(std::ceil(a.time / s.dt()));
  const std::int64_t every = std::max<std::int64_t>(1, steps / 1000);
  const std::size_t n = s.particles().size();
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
  std::vector<std::uint32_t> parent(n), size(n);
  auto clusters = [&](std::vector<std::uint32_t>& label) {  // union-find over touching pairs
    std::iota(parent.begin(), parent.end(), 0u);
    auto find = [&](std::uint32_t x) {
      while (parent[x] != x) x = parent[x] = parent[parent[x]];
      return x;
    };
    s.touching_pairs(pairs);
    for (auto [i, j] : pairs) parent[find(i)] = find(j);
    std::fill(size.begin(), size.end(), 0u);
    label.resize(n);
    for (std::uint32_t i = 0; i < n; ++i) ++size[label[i] = find(i)];
  };
  std::vector<std::uint32_t> label;
  std::string csv = "t,floor_y,Ekin,y_centre,largest_cluster,single_grains\n";
  auto row = [&] {
    clusters(label);
    double yc = 0.0;
    for (double y : s.particles().y) yc += y;
    const auto largest = *std::max_element(size.begin(), size.end());
    std::size_t singles = 0;
    for (std::uint32_t i = 0; i < n; ++i) singles += (label[i] == i && size[i] == 1);
    const double tt = s.time() - t_start;
    csv += fmt::format("{:.9g},{:.9g},{:.9g},{:.9g},{},{}\n", tt, a.amplitude * std::sin(w * tt), s.energies().kinetic,
                       yc / static_cast<double>(n), largest, singles);
  };
  std::vector<ContactInfo> cs;
  write_snapshot(s, out, "initial", cs);
  row();
  Progress progress("vibrate", static_cast<double>(steps), a.quiet);
  const auto t0 = std::chrono::steady_clock::now();
  for (std::int64_t k = 1; k <= steps; ++k) {
    const double tt = static_cast<double>(k) * s.dt();
    s.set_gravity(0.0, -a.gravity + a.amplitude * w * w * std::sin(w * tt));
    hold_temperature(s, T, s.params());
    s.step();
    if (k % every == 0 || k == steps) {
      row();
      progress.update(static_cast<double>(k));
    }
  }
  progress.finish();
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  clusters(label);
  std::vector<std::uint32_t> sizes;
  for (std::uint32_t i = 0; i < n; ++i)
    if (label[i] == i) sizes.push_back(size[i]);
  std::sort(sizes.rbegin(), sizes.rend());
  std::string cc = "cluster,size\n";
  for (std::size_t k = 0; k < sizes.size(); ++k) cc += fmt::format("{},{}\n", k, sizes[k]);
  // cluster id per particle, numbered by decreasing size
  std::vector<double> cid(n);
  {
    std::vector<std::uint32_t> roots;
    for (std::uint32_t i = 0; i < n; ++i)
      if (label[i] == i) roots.push_back(i);
    std::stable_sort(roots.begin(), roots.end(), [&](auto x, auto y) { return size[x] > size[y]; });
    std::vector<double> rank(n, 0.0);
    for (std::size_t k = 0; k < roots.size(); ++k) rank[roots[k]] = static_cast<double>(k);
    for (std::uint32_t i = 0; i < n; ++i) cid[i] = rank[label[i]];
  }
  write_file_atomic(out / "timeseries.csv", csv);
  write_file_atomic(out / "clusters.csv", cc);
  write_file_atomic(out / "state.txt", format_state(s.state()));
  write_snapshot(s, out, "final", cs, {Field{"cluster", 1, cid}});
  const std::size_t singles = static_cast<std::size_t>(std::count(sizes.begin(), sizes.end(), 1u));
  nlohmann::json j{{"command", command},
                   {"state_file", a.state_file},
                   {"clusters", sizes.size()},
                   {"largest_cluster", sizes.front()},
                   {"largest_cluster_fraction", static_cast<double>(sizes.front()) / static_cast<double>(n)},
                   {"single_grain_fraction", static_cast<double>(singles) / static_cast<double>(n)},
                   {"peak_floor_acceleration_over_g", a.gravity > 0 ? a.amplitude * w * w / a.gravity : 0.0},
                   {"steps", steps},
                   {"wall_time_s", wall}};
  write_file_atomic(out / "summary.json", j.dump(2) + "\n");
  std::printf("vibrate: %zu clusters, largest %u of %zu disks (%.3f), single grains %.3f, %.1f s -> %s\n", sizes.size(),
              sizes.front(), n, static_cast<double>(sizes.front()) / static_cast<double>(n),
              static_cast<double>(singles) / static_cast<double>(n), wall, out.c_str());
  return 0;
}

}  // namespace netdem::app::dem
