// netsolve pack --periodic (pack_periodic.hpp): the command line's files around the library's route.
#include "pack_periodic.hpp"

#include <chrono>
#include <cstdio>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "netdem/field_error.hpp"
#include "netdem/packing/io.hpp"
#include "netdem/packing/periodic.hpp"
#include "output.hpp"
#include "run_status.hpp"
#include "setup.hpp"

namespace fs = std::filesystem;

namespace netdem::app::netsolve {

namespace {
// The cell's edges as lines between its corners (2D: 4, 3D: 12).
std::string cell_vtp(const packing::Packing& pk) {
  std::vector<double> cx, cy, cz;
  const int D = pk.dim;
  const auto corner = [&](int c, int a) {
    double v = a == 0 ? pk.box.x_min : a == 1 ? pk.box.y_min : pk.box.z_min;
    for (int b = 0; b < D; ++b)
      if ((c >> b) & 1) {
        if (pk.cell.empty())
          v += b == a ? (a == 0 ? pk.box.width() : a == 1 ? pk.box.height() : pk.box.depth()) : 0.0;
        else
          v += pk.cell[static_cast<std::size_t>(D * b + a)];
      }
    return v;
  };
  for (int c = 0; c < (1 << D); ++c) {
    cx.push_back(corner(c, 0));
    cy.push_back(corner(c, 1));
    cz.push_back(D == 3 ? corner(c, 2) : 0.0);
  }
  std::vector<int> ei, ej;
  for (int c = 0; c < (1 << D); ++c)
    for (int a = 0; a < D; ++a)
      if (!((c >> a) & 1)) ei.push_back(c), ej.push_back(c | (1 << a));
  return vtp_network_3d(cx, cy, D == 3 ? &cz : nullptr, ei, ej, {});
}
}  // namespace

int run_pack_periodic(const PeriodicPackArgs& a, int dim, bool overwrite, const std::string& command,
                      const fs::path& out) {
  RunDirOptions rdo;
  rdo.overwrite = overwrite;
  try {
    a.pack.validate(dim);
  } catch (const FieldError& e) {  // the library's fields under this command's option names
    const std::string f = e.field();
    const std::string opt = f == "friction" ? "--pack-friction" : f == "pressure" ? "--jam-pressure" : f == "r_min" ? "--r-min"
                                                                                                               : "--" + f;
    throw UsageError(opt + ": " + e.what());
  }
  check_run_dir(out, rdo);
  activity() = fmt::format("compressing a periodic gas of {} {} to its jamming point", a.pack.n, dim == 2 ? "disks" : "spheres");
  open_run_dir(out, command, rdo);
  const auto t0 = std::chrono::steady_clock::now();
  Progress progress("pack --periodic (of the step limit)", 1.0, a.quiet);
  dem::PeriodicPackSummary m;
  const packing::Packing pk = dem::make_periodic_packing(dim, a.pack, m, [&](double f) { progress.update(f); });
  progress.finish();
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  activity() = "writing the packing";
  packing::write_packing_csv(pk, out / "packing.csv");
  if (dim == 2)
    write_file_atomic(out / "particles.vtp", vtp_particles(pk.x, pk.y, {{"radius", 1, pk.r}}));
  else
    write_file_atomic(out / "particles.vtp", vtp_particles_3d(pk.x, pk.y, &pk.z, {{"radius", 1, pk.r}}));
  write_file_atomic(out / "cell.vtp", cell_vtp(pk));
  std::string status = m.status, reason = m.status == "ok" ? "at rest at the target pressure" : m.reason;
  if (m.status == "ok" && m.max_overlap > kMaxPeriodicOverlap) {
    status = "unconverged";
    reason = fmt::format("the largest overlap {:.3g} R is above {:g} R", m.max_overlap, kMaxPeriodicOverlap);
  }
  nlohmann::json j;
  j["command"] = command;
  j["dim"] = dim;
  j["route"] = "periodic";
  j["seed"] = a.pack.seed;
  j["particles"] = pk.size();
  j["radii"] = {{"r_min", a.pack.r_min}, {"r_max", a.pack.r_max}, {"distribution", "uniform"}};
  j["law"] = {{"model", "linear spring-dashpot (DEM ContactModel::Linear), k_n = 1, tangential k_t = 0.2 k_n"},
              {"friction", a.pack.friction},
              {"target_pressure_over_k_n", a.pack.pressure}};
  j["units"] = "R = 1 (the mean radius of the distribution), k_n = 1, rho = 1";
  j["density"] = m.density;
  j["pressure_over_k_n"] = m.pressure;
  j["coordination"] = m.Z;
  j["coordination_without_rattlers"] = m.Z_backbone;
  j["rattler_fraction"] = m.rattler_fraction;
  j["contacts"] = m.contacts;
  if (dim == 2) j["psi6"] = {{"global", m.psi6_global}, {"local", m.psi6_local}};
  j["overlap_over_R"] = {{"max", m.max_overlap}, {"mean", m.mean_overlap}, {"limit", kMaxPeriodicOverlap}};
  j["unbalanced_force_over_mean_contact_force"] = m.unbalanced;
  j["steps"] = m.steps;
  j["dt"] = m.dt;
  j["cell"] = {{"width", pk.box.width()}, {"height", pk.box.height()}};
  if (dim == 3) j["cell"]["depth"] = pk.box.depth();
  j["timing_s"] = {{"wall", wall}};
  j["status"] = status;
  j["status_reason"] = reason;
  write_file_atomic(out / "summary.json", j.dump(2) + "\n");
  close_run_dir(out);
  std::string psi = dim == 2 ? fmt::format(", psi6 = {:.3f} (local {:.3f})", m.psi6_global, m.psi6_local) : std::string();
  netdem::app::summary_printf("seed %llu (periodic, %dD): %zu particles, D = %.4f, Z = %.3f (%.3f without %.1f %% rattlers)%s, "
              "overlap max %.2e R, mean %.2e R, %lld steps, %.1f s -> %s\n",
              static_cast<unsigned long long>(a.pack.seed), dim, pk.size(), m.density, m.Z, m.Z_backbone,
              100.0 * m.rattler_fraction, psi.c_str(), m.max_overlap, m.mean_overlap, static_cast<long long>(m.steps),
              wall, (out / "packing.csv").c_str());
  if (status != "ok") {
    std::fprintf(stderr, "netsolve: error: %s: %s\n", status.c_str(), reason.c_str());
    return exit_code::untrustworthy;
  }
  return exit_code::ok;
}

}  // namespace netdem::app::netsolve
