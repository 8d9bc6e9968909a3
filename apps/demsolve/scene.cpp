// demsolve's scene measures and snapshots (scene.hpp).
#include "scene.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include <fmt/format.h>

#include "output.hpp"
#include "run_status.hpp"

namespace fs = std::filesystem;
using namespace netdem::dem;

namespace netdem::app::dem {

template <int D>
void write_compact_snapshot(const DynamicSolverT<D>& s, SnapshotSeries& series, const std::string& tag,
                            std::vector<ContactInfo>& cs) {
  const fs::path out = series.dir();
  const ParticlesT<D>& P = s.particles();
  const std::vector<double> x = P.axis(0), y = P.axis(1), z = D == 3 ? P.axis(D - 1) : std::vector<double>{};
  std::vector<double> pre(P.size(), 0.0);
  for (auto p : s.prescribed()) pre[p] = 1.0;
  Field vel{"velocity", 3, {}};
  for (std::size_t i = 0; i < P.size(); ++i)
    vel.values.insert(vel.values.end(), {P.vel[D * i], P.vel[D * i + 1], D == 3 ? P.vel[D * i + D - 1] : 0.0});
  if constexpr (D == 2) {
    write_file_atomic(out / fmt::format("particles_{}.vtp", tag),
                      vtp_particles(x, y,
                                    {{"radius", 1, P.r}, {"theta", 1, P.rot}, {"peripheral", 1, pre}, vel,
                                     {"omega", 1, P.spin}}));
  } else {
    write_file_atomic(out / fmt::format("particles_{}.vtp", tag),
                      vtp_particles_3d(x, y, &z, {{"radius", 1, P.r}, {"prescribed", 1, pre}, vel, {"spin", 3, P.spin}}));
  }
  s.contacts(cs);
  std::vector<int> ci, cj;
  Field fn{"normal_force", 1, {}}, ft{"tangential_force", 1, {}}, ov{"overlap", 1, {}}, sl{"sliding", 1, {}};
  for (const auto& c : cs) {
    if (c.wall >= 0 || !(c.f_spring > 0.0)) continue;  // the meter's loaded contacts (compaction.hpp)
    if (s.periodic()) {  // a contact through an image is not drawn (a line across the cell)
      const double dx = x[c.j] - x[c.i], dy = y[c.j] - y[c.i], dz = D == 3 ? z[c.j] - z[c.i] : 0.0;
      if (std::sqrt(dx * dx + dy * dy + dz * dz) > c.d_i + c.d_j + 1e-9 * (c.d_i + c.d_j)) continue;
    }
    ci.push_back(static_cast<int>(c.i));
    cj.push_back(static_cast<int>(c.j));
    fn.values.push_back(c.f_spring);
    ft.values.push_back(c.f_t);
    ov.values.push_back(c.overlap);
    sl.values.push_back(c.sliding ? 1.0 : 0.0);
  }
  if (s.periodic()) {  // the cell, as lines between its corners (2D: 4, 3D: 12 edges)
    const auto& cell = s.cell();
    std::vector<double> cx, cy, cz;
    for (int corner = 0; corner < (1 << D); ++corner) {
      auto p = cell.origin;
      for (int a = 0; a < D; ++a)
        if ((corner >> a) & 1) p += cell.h.col(a);
      cx.push_back(p(0));
      cy.push_back(p(1));
      cz.push_back(D == 3 ? p(D - 1) : 0.0);
    }
    std::vector<int> ei, ej;
    for (int c = 0; c < (1 << D); ++c)
      for (int a = 0; a < D; ++a)
        if (!((c >> a) & 1)) ei.push_back(c), ej.push_back(c | (1 << a));
    write_file_atomic(out / fmt::format("cell_{}.vtp", tag), vtp_network_3d(cx, cy, D == 3 ? &cz : nullptr, ei, ej, {}));
  }
  const auto file = out / fmt::format("contacts_{}.vtp", tag);
  if constexpr (D == 2) {
    write_file_atomic(file, vtp_network(x, y, ci, cj, {fn, ft, ov, sl}));
  } else {
    write_file_atomic(file, vtp_network_3d(x, y, &z, ci, cj, {fn, ft, ov, sl}));
  }
  series.add(s.density(), tag);
}

SnapshotSeries compact_snapshot_series(const fs::path& out, bool periodic) {
  std::vector<std::string> kinds = {"particles", "contacts"};
  if (periodic) kinds.emplace_back("cell");
  return SnapshotSeries(out / "snapshots.pvd", kinds);
}

template void write_compact_snapshot<2>(const DynamicSolverT<2>&, SnapshotSeries&, const std::string&,
                                        std::vector<ContactInfo>&);
template void write_compact_snapshot<3>(const DynamicSolverT<3>&, SnapshotSeries&, const std::string&,
                                        std::vector<ContactInfo>&);

DynamicOptions plastic_options(double mu, double k_t, bool reversible, double first_touch, double damping, double drag,
                               double steps_per_contact) {
  DynamicOptions o;
  o.model = ContactModel::PlasticIndentation;
  o.steps_per_contact = steps_per_contact;
  o.plastic.sigma_y = 1.0;
  o.plastic.mu = mu;
  o.plastic.k_t = k_t;
  o.plastic.reversible = reversible;
  o.plastic.first_touch = first_touch;
  o.plastic.damping_n = o.plastic.damping_t = damping;
  o.plastic_wall_mu = 0.0;  // frictionless die walls
  o.affine_drag = drag;
  o.validate();
  return o;
}

RunDirOptions check_scene_run_dir(const fs::path& out, bool overwrite, const std::string& packing_file,
                                  const netdem::app::netsolve::PackArgs& pack) {
  RunDirOptions rdo;
  rdo.overwrite = overwrite;
  if (!packing_file.empty()) rdo.inputs.emplace_back(packing_file);
  check_run_dir(out, rdo);
  if (packing_file.empty()) netdem::app::netsolve::check_deposition_size(pack);
  activity() = packing_file.empty() ? "building the ballistic deposition" : "reading the packing " + packing_file;
  return rdo;
}

std::vector<std::uint32_t> prescribed_particles(const packing::Packing& pk, bool affine, bool walls) {
  std::vector<std::uint32_t> pre;
  const auto n = static_cast<std::uint32_t>(pk.size());
  if (affine) {
    for (std::uint32_t p = 0; p < n; ++p) pre.push_back(p);
  } else if (!walls) {
    const auto layer = packing::peripheral_layer(pk);
    for (std::uint32_t p = 0; p < n; ++p)
      if (layer[p]) pre.push_back(p);
  }
  return pre;
}

}  // namespace netdem::app::dem
