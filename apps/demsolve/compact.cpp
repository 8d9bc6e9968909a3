// demsolve compact: the explicit DEM with the plastic-indentation law (Redanz & Fleck 2001) as the
// dynamic referee of netsolve compact: the same packing, strain path, boundary layer, units
// (sigma_y = 1, R = 1, rho = 1, t* = R sqrt(rho/sigma_y) = 1) and files (history.csv with netsolve's
// column names and sign convention, summary.json, .vtp snapshots). See docs/dynamic.md
// "demsolve compact".
#include "compact.hpp"
#include "scene.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <sstream>
#include <unordered_map>
#include <vector>

#include <Eigen/Dense>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "netdem/contact/plastic_indentation.hpp"
#include "netdem/dynamic/solver.hpp"
#include "netdem/dynamic/state.hpp"
#include "netdem/packing/io.hpp"
#include "netdem/packing/packing.hpp"
#include "netdem/quasistatic/compaction.hpp"
#include "output.hpp"
#include "protocol.hpp"
#include "run_status.hpp"

namespace fs = std::filesystem;
using namespace netdem::dem;

namespace netdem::app::dem {

void check_compact_numbers(const DemCompactArgs& a) {
  if (!(std::isfinite(a.inertial_number) && a.inertial_number > 0.0 && a.inertial_number <= 1.0))
    throw UsageError(fmt::format("--inertial-number must be in (0, 1], got {}", a.inertial_number));
  if (!(std::isfinite(a.damping) && a.damping >= 0.0 && a.damping <= 1.0))
    throw UsageError(fmt::format("--damping must be in [0, 1] (fraction of critical damping), got {}", a.damping));
  if (!(std::isfinite(a.drag) && a.drag >= 0.0))
    throw UsageError(fmt::format("--drag must be a finite number >= 0, got {}", a.drag));
  if (!(std::isfinite(a.first_touch) && a.first_touch > 0.0 && a.first_touch <= 0.01))
    throw UsageError(fmt::format("--first-touch must be in (0, 0.01] (the explicit solver needs the bounded first-touch "
                                 "stiffness), got {}", a.first_touch));
  if (!(std::isfinite(a.k_t) && a.k_t >= 0.0)) throw UsageError(fmt::format("--k-t must be a finite number >= 0, got {}", a.k_t));
  if (!(std::isfinite(a.steps_per_contact) && a.steps_per_contact >= 10.0 && a.steps_per_contact <= 1e4))
    throw UsageError(fmt::format("--steps-per-contact must be in [10, 1e4], got {}", a.steps_per_contact));
  if (a.increments < 1 || a.increments > 1000000)
    throw UsageError(fmt::format("--increments must be in [1, 1e6], got {}", a.increments));
}

int run_dem_compact(const std::string& command, const DemCompactArgs& a, const fs::path& out) {
  if (a.pack.dim == 3) return run_dem_compact_3d(command, a, out);
  // ---- the door: every value before anything is written ----------------------------------------
  const qs::StrainPath path = qs::StrainPath::parse(a.path);
  check_compact_numbers(a);
  if (a.boundary != "layer" && a.boundary != "walls")
    throw UsageError(fmt::format("--boundary '{}' is not 'layer' or 'walls'", quote_input(a.boundary)));
  const bool walls = a.boundary == "walls";
  if (walls && path.E12 != 0.0)
    throw UsageError(fmt::format("--path {}: --boundary walls takes E12 = 0 only (the die walls stay axis-aligned)",
                                 quote_input(a.path)));
  if (walls && a.affine) throw UsageError("--affine and --boundary walls exclude each other (affine prescribes every centre)");
  const double mu = netdem::app::netsolve::parse_friction(a.friction);
  const auto snaps = netdem::app::netsolve::parse_number_list(a.snapshots, "--snapshots");
  RunDirOptions rdo;
  rdo.overwrite = a.overwrite;
  if (!a.packing_file.empty()) rdo.inputs.emplace_back(a.packing_file);
  check_run_dir(out, rdo);
  if (a.packing_file.empty()) netdem::app::netsolve::check_deposition_size(a.pack);
  activity() = a.packing_file.empty() ? "building the ballistic deposition" : "reading the packing " + a.packing_file;
  std::string source;
  const packing::Packing pk = [&] {
    try {
      return netdem::app::netsolve::input_packing(a.packing_file, a.pack, source, "demsolve compact");
    } catch (const UsageError& e) {  // a 3D packing file: say how to run it
      if (std::string(e.what()).find("is a 3D packing") != std::string::npos)
        throw UsageError(std::string(e.what()) + " without --dim 3");
      throw;
    }
  }();
  check_memory(pk.size());

  Particles P = particles_from(pk, 1.0);  // rho = 1: areal density of disks of unit depth
  // the die walls enclose every disk at the start (the deposition's top disks stick out of its box)
  Box box(walls ? netdem::app::netsolve::walls_box(pk) : pk.box);
  box.contact_walls = walls;
  box.right.mode = box.top.mode = WallMode::Affine;
  const DynamicOptions o = plastic_options(mu, a.k_t, a.normal_unloading == "reversible", a.first_touch, a.damping,
                                           a.drag, a.steps_per_contact);
  double area = 0.0;
  for (double r : P.radius) area += std::numbers::pi * r * r;
  const double D0 = area / ((box.x_max - box.x_min) * (box.y_max - box.y_min));
  qs::CompactionOptions co;
  co.path = path;
  co.target_density = a.to_density;
  co.increments = a.increments;
  try {
    co.validate(D0);
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
  // the rate: I = gamma' d sqrt(rho/P_ref), gamma' = |E'| (Frobenius), d = 2R, P_ref = sigma_y
  const double rho = 1.0, sigma_y = 1.0, d_mean = 2.0;
  const double gdot = a.inertial_number / (d_mean * std::sqrt(rho / sigma_y));
  const double norm = std::sqrt(path.E11 * path.E11 + path.E22 * path.E22 + 2.0 * path.E12 * path.E12);
  const double e11 = gdot * path.E11 / norm, e22 = gdot * path.E22 / norm, e12 = gdot * path.E12 / norm;
  const double T = std::log(D0 / a.to_density) / (e11 + e22);  // D = D0 exp(-(E11 + E22) t)

  activity() = "setting up the explicit solver";
  const std::size_t n = P.size();
  DynamicSolver s(std::move(P), LudingParams{}, box, o);
  s.set_strain_rate(e11, e22, e12);
  s.set_affine_velocities();
  const std::vector<std::uint32_t> pre = prescribed_particles(pk, a.affine, walls);
  // layer: the layer prescribed, its spins held; affine: every centre prescribed, the spins free but the layer's
  s.set_prescribed(pre, !a.affine);
  // affine: every centre prescribed, the spins free except the peripheral layer's, as netsolve and Redanz &
  // Fleck section 2.4 ("the rotation of particles in the peripheral layer is prevented")
  if (a.affine) s.hold_spins(prescribed_particles(pk, false, false));
  s.set_rotations(!a.no_rotation);
  const double dt_first = s.dt();
  const double steps_est = T / dt_first;
  if (!(steps_est <= a.max_steps))
    throw UsageError(fmt::format("the run needs at least {:.3g} time steps of {:.3g} t* (I = {:g}), more than --max-steps "
                                 "= {:.3g}: raise --inertial-number or --max-steps", steps_est, dt_first,
                                 a.inertial_number, a.max_steps));

  open_run_dir(out, command, rdo);
  packing::write_packing_csv(pk, out / "packing.csv");
  if (!a.quiet)
    std::fprintf(stderr, "demsolve compact: %zu particles, D0 = %.4f, seed %llu (%s); I = %g, gamma' = %.4g, t_end = %.4g, "
                 "dt = %.3g, about %.3g steps\n", n, D0, static_cast<unsigned long long>(pk.seed), source.c_str(),
                 a.inertial_number, gdot, T, dt_first, steps_est);
  // a centre outside the deformed domain: the box, or with shear the parallelogram x_0 + F (box_0 - x_0)
  const Box box0 = box;
  auto outside_box = [&](double x, double y) {
    const Box& b = s.box();
    if (e12 == 0.0) return x < b.x_min || x > b.x_max || y < b.y_min || y > b.y_max;
    const auto& F = s.box_deformation();
    const double det = F[0] * F[3] - F[1] * F[2], dx = x - box0.x_min, dy = y - box0.y_min;
    const double X = (F[3] * dx - F[1] * dy) / det, Y = (-F[2] * dx + F[0] * dy) / det;
    return X < 0.0 || X > box0.x_max - box0.x_min || Y < 0.0 || Y > box0.y_max - box0.y_min;
  };
  std::vector<ContactInfo> snap_buf;
  write_compact_snapshot(s, out, "initial", snap_buf);
  double r_mean = 0.0;
  for (double r : s.particles().radius) r_mean += r;
  r_mean /= static_cast<double>(n);
  Meter meter(walls, r_mean);
  std::string csv =
      "increment,E11,E22,E12,D,S11,S22,S12,S11_contacts,S22_contacts,S12_contacts,Z,contacts,sliding,mean_fn,"
      "dev_un_mean_ratio,dev_un_ratio_of_means,affine_ut,time,I,kinetic_ratio,steps,samples,dt,outside,D_in_box";
  if (walls) csv += ",wall_vs_contact_gap";
  csv += "\n";
  auto gap_of = [](const Sample& m) {
    const double d11 = m.S11 - m.S11c, d22 = m.S22 - m.S22c;
    const double c = std::hypot(m.S11c, m.S22c);
    return c > 0.0 ? std::hypot(d11, d22) / c : 0.0;
  };
  Sample last;
  double last_I = 0.0, max_gap = 0.0, last_gap = 0.0;
  std::int64_t steps = 0;
  int done = 0;
  auto write_row = [&](int k, const Sample& m, int samples) {
    const double t = s.time();
    const double Pc = -0.5 * (m.S11c + m.S22c);
    // the actual inertial number; undefined (an empty field, no inf in a result file) where P = 0
    const double I = Pc > 0.0 ? gdot * d_mean * std::sqrt(rho / Pc) : std::numeric_limits<double>::quiet_NaN();
    const double kr = m.work > 0.0 ? m.kinetic / m.work : 0.0;
    csv += fmt::format("{},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.6g},{:.6g},{:.6g},{:.9g},"
                       "{:.6g},{:.6g},{:.6g},{:.9g},{},{:.4e},{},{},{:.4e}",
                       k, e11 * t, e22 * t, e12 * t, s.density(), m.S11, m.S22, m.S12, m.S11c, m.S22c, m.S12c, m.Z,
                       m.contacts, m.sliding, m.mean_fn, m.dev_mean_ratio, m.dev_ratio_of_means, m.affine_ut, t,
                       std::isfinite(I) ? fmt::format("{:.6g}", I) : std::string(), kr,
                       steps, samples, s.dt());
    {  // centres outside the box (squeezed out between the peripheral disks) and the density without them
      const Particles& Q = s.particles();
      const Box& b = s.box();
      int outside = 0;
      double in = 0.0;
      for (std::size_t p = 0; p < Q.size(); ++p) {
        const bool o = outside_box(Q.x[p], Q.y[p]);
        outside += o;
        if (!o) in += std::numbers::pi * Q.radius[p] * Q.radius[p];
      }
      csv += fmt::format(",{},{:.9g}", outside, in / ((b.x_max - b.x_min) * (b.y_max - b.y_min)));
    }
    if (walls) {
      const double g = gap_of(m);
      csv += fmt::format(",{:.4e}", g);
      if (k > 0) {
        last_gap = g;
        if (s.density() >= D0 + 0.5 * (a.to_density - D0)) max_gap = std::max(max_gap, g);  // once loaded
      }
    }
    csv += "\n";
    last = m;
    last_I = I;
  };
  nlohmann::json summary;
  summary["command"] = command;
  summary["packing"] = source;
  summary["seed"] = pk.seed;
  summary["particles"] = n;
  summary["initial_density"] = D0;
  summary["sigma_y"] = 1.0;
  summary["friction"] = a.friction;
  summary["mode"] = a.affine ? "affine" : walls ? "walls" : "die";
  summary["boundary"] = a.affine ? "affine" : a.boundary;
  summary["prescribed"] = pre.size();
  summary["rotations"] = !a.no_rotation;
  summary["path"] = {{"name", path.name}, {"E11", path.E11}, {"E22", path.E22}, {"E12", path.E12}};
  summary["increments"] = a.increments;
  summary["to_density"] = a.to_density;
  summary["k_t"] = a.k_t;
  summary["first_touch"] = a.first_touch;
  summary["normal_unloading"] = a.normal_unloading;
  summary["inertial_number"] = a.inertial_number;
  summary["strain_rate"] = {{"E11", e11}, {"E22", e22}, {"E12", e12}, {"gamma_dot", gdot}};
  summary["t_end"] = T;
  summary["damping"] = {{"normal", a.damping}, {"tangential", a.damping}};
  summary["drag"] = a.drag;
  summary["steps_per_contact"] = a.steps_per_contact;
  summary["units"] = "sigma_y = 1, R = 1 (lengths of the packing), rho = 1, t* = R sqrt(rho/sigma_y) = 1";

  const auto t0 = std::chrono::steady_clock::now();
  Progress progress("compact", T, a.quiet);
  write_row(0, meter.measure(s, e11 * s.time(), e22 * s.time(), e12 * s.time()), 1);
  std::size_t next_snap = 0;
  // samples per window: about every 20 steps, at least 10 per window
  const auto every = static_cast<std::int64_t>(std::clamp(T / a.increments / dt_first / 10.0, 1.0, 20.0));
  activity() = "compacting";
  try {
    for (int k = 1; k <= a.increments; ++k) {
      const double t_end = T * k / a.increments;
      Sample acc;
      int samples = 0;
      std::int64_t since = 0;
      while (s.time() < t_end - 1e-12 * T) {
        s.step();
        ++steps;
        if (++since % every == 0 || !(s.time() < t_end - 1e-12 * T)) {
          acc.add(meter.measure(s, e11 * s.time(), e22 * s.time(), e12 * s.time()), 1.0);
          ++samples;
          progress.update(s.time());
        }
      }
      if (samples == 0) {
        acc.add(meter.measure(s, e11 * s.time(), e22 * s.time(), e12 * s.time()), 1.0);
        samples = 1;
      }
      Sample mean;
      mean.add(acc, 1.0 / samples);
      s.check_health();  // nothing unchecked reaches a file
      write_row(k, mean, samples);
      done = k;
      while (next_snap < snaps.size() && s.density() >= snaps[next_snap] - 1e-9) {
        write_compact_snapshot(s, out, fmt::format("D{:.3f}", snaps[next_snap]), snap_buf);
        ++next_snap;
      }
      if (k % 20 == 0) write_file_atomic(out / "history.csv", csv);  // checkpoint
    }
  } catch (const InstabilityError& e) {
    progress.finish();
    csv += "# stopped: " + one_line(e.what()) + "\n";
    write_file_atomic(out / "history.csv", csv);
    summary["increments_done"] = done;
    summary["steps"] = steps;
    // as report_unstable(), without state_last_good.txt (compact writes no state file)
    summary["status"] = "unstable";
    summary["status_reason"] = e.what();
    summary["unstable_quantity"] = e.quantity();
    summary["unstable_step"] = e.step();
    summary["unstable_time"] = e.time();
    write_file_atomic(out / "summary.json", summary.dump(2) + "\n");
    close_run_dir(out);
    std::fprintf(stderr, "demsolve: error: %s\n", one_line(e.what()).c_str());
    return exit_code::untrustworthy;
  }
  progress.finish();
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  write_file_atomic(out / "history.csv", csv);
  write_compact_snapshot(s, out, "final", snap_buf);
  // die mode prescribes only the peripheral layer: count centres squeezed out of the box (as netsolve)
  int outside = 0;
  for (std::size_t p = 0; p < n; ++p) {
    outside += outside_box(s.particles().x[p], s.particles().y[p]);
  }
  RunStatus status;
  std::vector<std::string> warnings;
  if (outside > 0) status.add("unstable", fmt::format("{} disk centres left the box between the peripheral disks", outside));
  if (last.Z < 2.0) status.add("unstable", fmt::format("final Z = {:.3g} < 2: the network is a mechanism", last.Z));
  if (walls && max_gap > 0.02)
    warnings.push_back(fmt::format("wall stress and contact stress differ by up to {:.3g} (above 2 %) in the second half "
                                   "of the compaction (wall_vs_contact_gap)", max_gap));
  summary["status"] = status.status;
  std::string reason = status.ok() ? "every instability check passed" : status.reason();
  for (const auto& w : warnings) reason += "; warning: " + w;
  summary["status_reason"] = reason;
  summary["warnings"] = warnings;
  summary["increments_done"] = done;
  summary["centres_outside_box"] = outside;
  summary["final"] = {{"D", s.density()},         {"S11", last.S11},           {"S22", last.S22},
                      {"S12", last.S12},          {"S11_contacts", last.S11c}, {"S22_contacts", last.S22c},
                      {"Z", last.Z},              {"contacts", last.contacts}, {"sliding", last.sliding},
                      {"E11", e11 * s.time()},    {"E22", e22 * s.time()},     {"E12", e12 * s.time()},
                      {"I", last_I},              {"kinetic_ratio", last.work > 0 ? last.kinetic / last.work : 0.0},
                      {"time", s.time()}};
  if (walls) {
    summary["wall_vs_contact_gap"] = last_gap;
    summary["max_wall_vs_contact_gap"] = max_gap;
    summary["wall_vs_contact_warning"] = max_gap > 0.02;
  }
  summary["dt"] = {{"first", dt_first}, {"last", s.dt()}};
  summary["steps"] = steps;
  summary["neighbour_rebuilds"] = s.rebuilds();
  summary["timing_s"] = {{"wall", wall}, {"particle_steps_per_s", static_cast<double>(steps) * n / std::max(wall, 1e-9)}};
  write_file_atomic(out / "summary.json", summary.dump(2) + "\n");
  close_run_dir(out);
  std::printf("D = %.4f: S11/sy = %.4f, S22/sy = %.4f (contacts %.4f, %.4f), Z = %.3f, I = %.3g, %lld steps, %.2f s -> %s\n",
              s.density(), last.S11, last.S22, last.S11c, last.S22c, last.Z, last_I, static_cast<long long>(steps), wall,
              out.c_str());
  for (const auto& w : warnings) std::fprintf(stderr, "demsolve: warning: %s\n", w.c_str());
  if (!status.ok()) {
    std::fprintf(stderr, "demsolve: error: %s: %s\n", status.status.c_str(), status.reason().c_str());
    return exit_code::untrustworthy;
  }
  return exit_code::ok;
}

}  // namespace netdem::app::dem
