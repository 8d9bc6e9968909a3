// netsolve sinter's files (sinter_files.hpp).
#include "sinter_files.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include <fmt/format.h>

#include "netdem/packing/laminar.hpp"
#include "output.hpp"

namespace netdem::app::netsolve {

namespace fs = std::filesystem;
namespace sp = netdem::contact::sinter;
namespace st = netdem::qs::staggered;
using nlohmann::json;

/// Eq 48 of the green-body packing along x, y, z (the laminar.csv of netsolve pack --route green-body).
std::string laminar_csv(const netdem::packing::Packing& pk, double lamina) {
  std::string lam = "# Eq 48 of Ivannikov et al.: laminae of width ~q_s along x, y, z; lengths in metres\n";
  lam += fmt::format("# q_s {:.9g}\n", lamina);
  lam += "axis,lamina,lo,hi,density\n";
  const char* names[3] = {"x", "y", "z"};
  for (int ax = 0; ax < 3; ++ax) {
    const auto prof = netdem::packing::laminar_density(pk, ax, lamina);
    for (std::size_t s = 0; s < prof.density.size(); ++s)
      lam += fmt::format("{},{},{:.9g},{:.9g},{:.6f}\n", names[ax], s, prof.lo[s], prof.hi[s], prof.density[s]);
  }
  return lam;
}

// ---- snapshots
void write_snapshot(const fs::path& out, int k, const st::Staggered& s) {
  const auto& P = s.particles();
  const auto& P0 = s.initial_particles();
  const std::vector<double> x = P.axis(0), y = P.axis(1), z = P.axis(2);
  Field rad{"radius", 1, {}}, disp{"displacement", 3, {}};
  for (std::size_t i = 0; i < P.size(); ++i) {
    rad.values.push_back(P.r[i]);
    for (int d = 0; d < 3; ++d) disp.values.push_back(i < P0.size() ? P.coord(i, d) - P0.coord(i, d) : 0.0);
  }
  write_file_atomic(out / fmt::format("particles_{:03d}.vtp", k), netdem::app::vtp_particles_3d(x, y, &z, {rad, disp}));
  std::vector<int> ia, ib;
  Field neck{"neck_x_over_R", 1, {}}, frozen{"frozen", 1, {}}, dlb{"dL_bar", 1, {}};
  for (const auto& c : s.contacts()) {
    ia.push_back(c.a);
    ib.push_back(c.b);
    neck.values.push_back(c.pair.x_over_R());
    frozen.values.push_back(c.frozen ? 1.0 : 0.0);
    dlb.values.push_back(c.dL_bar);
  }
  write_file_atomic(out / fmt::format("bonds_{:03d}.vtp", k), netdem::app::vtp_network_3d(x, y, &z, ia, ib, {neck, frozen, dlb}));
}

std::string pvd(const std::vector<std::pair<int, double>>& snaps) {
  std::vector<PvdDataSet> sets;  // no block names: the .pvd's bytes as before the shared writer
  for (const auto& [k, t] : snaps) {
    // one entry per time, as SnapshotSeries: a step that passes several snapshot times (or ends the
    // run at the last of them) writes them all of one state, which ParaView would draw twice
    if (!sets.empty() && !(t > sets.back().timestep)) continue;
    sets.push_back({t, 0, fmt::format("particles_{:03d}.vtp", k), ""});
    sets.push_back({t, 1, fmt::format("bonds_{:03d}.vtp", k), ""});
  }
  return pvd_text(sets);
}

json options_json(const st::StaggeredOptions& o) {
  return {{"strategy", o.strategy},
          {"dt_initial", o.dt_initial},
          {"dt_max", o.dt_max},
          {"dt_min", o.dt_min},
          {"alpha", o.alpha},
          {"eps_lim", o.eps_lim},
          {"grow_below", o.grow_below},
          {"shrink_above", o.shrink_above},
          {"new_contacts", o.new_contacts},
          {"x0_over_R", o.x0_over_R},
          {"x_max_over_R", o.x_max_over_R},
          {"boundary_planes", o.boundary_planes},
          {"boundary_factor", o.boundary_factor},
          {"plane_origin", std::isnan(o.plane_origin[0]) ? json("bounding box of the spheres")
                                                         : json({o.plane_origin[0], o.plane_origin[1], o.plane_origin[2]})},
          {"E", o.E},
          {"nu", o.nu},
          {"gmres_tolerance", o.gmres_tolerance},
          {"refactor_iterations", o.refactor_iterations}};
}

json material_json(const sp::SinterMaterial& m, const std::string& source) {
  return {{"name", m.name},           {"source", source},          {"Omega", m.omega},         {"gamma_s", m.gamma_s},
          {"gamma_gb", m.gamma_gb},   {"D_vol0", m.D_vol0},        {"Q_vol", m.Q_vol},         {"deltaD_gb0", m.deltaD_gb0},
          {"Q_gb", m.Q_gb},           {"deltaD_s0", m.deltaD_s0},  {"Q_s", m.Q_s},             {"c_III", m.c_III},
          {"c_IV", m.c_IV},           {"E", m.youngs_modulus},     {"nu", m.poisson_ratio}};
}

}  // namespace netdem::app::netsolve
