// demsolve's scene measures and snapshots (scene.hpp).
#include "scene.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include <fmt/format.h>

#include "output.hpp"

namespace fs = std::filesystem;
using namespace netdem::dem;

namespace netdem::app::dem {

Sample Meter::measure(const DynamicSolver& s, double E11, double E22, double E12) {
  Sample m;
  const Stress2 b = walls_ ? s.wall_stress() : s.boundary_stress();
  const Stress2 c = s.contact_stress();
  m.S11 = -b.xx, m.S22 = -b.yy, m.S12 = -0.5 * (b.xy + b.yx);
  m.S11c = -c.xx, m.S22c = -c.yy, m.S12c = -0.5 * (c.xy + c.yx);
  s.contacts(cs_);
  const Particles& P = s.particles();
  std::unordered_map<std::uint64_t, std::array<double, 3>> formed;
  formed.reserve(cs_.size());
  int loaded = 0, n_ratio = 0;
  double sum_fn = 0, sum_ratio = 0, sum_absdev = 0, sum_una = 0, sum_ta = 0;
  for (const auto& ct : cs_) {
    if (ct.wall >= 0 || !(ct.f_n > 0.0)) continue;
    const std::uint64_t key = (std::uint64_t{ct.i} << 32) | ct.j;
    std::array<double, 3> ef{prev_E11_, prev_E22_, prev_E12_};  // first seen: the strain at the previous sample
    if (const auto it = form_.find(key); it != form_.end()) ef = it->second;
    formed.emplace(key, ef);
    ++loaded;
    sum_fn += ct.f_n;
    m.sliding += ct.sliding ? 1.0 : 0.0;
    m.work += 0.5 * ct.f_n * ct.overlap;
    // Eq 16 with the strain accumulated since the contact formed (netsolve's measures.cpp)
    const double d11 = E11 - ef[0], d22 = E22 - ef[1], d12 = E12 - ef[2];
    const double Rsum = P.radius[ct.i] + P.radius[ct.j];
    const double nx = ct.nx, ny = ct.ny;
    // n.dE.n and t.dE.n, t = perp(n) = (-ny, nx) (the d12 terms vanish on diagonal paths)
    double una = -(nx * nx * d11 + ny * ny * d22) * Rsum;
    double uta = (-ny * nx * d11 + nx * ny * d22) * Rsum;
    if (d12 != 0.0) {
      una -= 2.0 * nx * ny * d12 * Rsum;
      uta += (nx * nx - ny * ny) * d12 * Rsum;
    }
    sum_absdev += std::fabs(ct.overlap - una);
    sum_una += una;
    if (una > 1e-12 * r_mean_) {
      sum_ratio += std::fabs(ct.overlap - una) / una;
      ++n_ratio;
    }
    sum_ta += std::fabs(uta);
  }
  form_.swap(formed);
  prev_E11_ = E11;
  prev_E22_ = E22;
  prev_E12_ = E12;
  const auto n = static_cast<double>(P.size());
  m.contacts = loaded;
  m.Z = 2.0 * loaded / n;
  m.mean_fn = loaded > 0 ? sum_fn / loaded : 0.0;
  const int nl = std::max(loaded, 1);
  const double una_mean = sum_una / nl;
  m.dev_mean_ratio = n_ratio > 0 ? sum_ratio / n_ratio : 0.0;
  m.dev_ratio_of_means = una_mean > 0 ? (sum_absdev / nl) / una_mean : 0.0;
  m.affine_ut = una_mean > 0 ? (sum_ta / nl) / una_mean : 0.0;
  // kinetic energy of the motion relative to the affine field (the non-prescribed particles)
  const auto& pre = s.prescribed();
  std::vector<std::uint8_t> is_pre(P.size(), 0);
  for (auto p : pre) is_pre[p] = 1;
  for (std::size_t i = 0; i < P.size(); ++i) {
    m.kinetic += 0.5 * P.inertia[i] * P.omega[i] * P.omega[i];
    if (is_pre[i]) continue;
    const double dx = P.x[i] - s.box().x_min, dy = P.y[i] - s.box().y_min;
    double wx = P.vx[i] - s.strain_rate_11() * dx;
    double wy = P.vy[i] - s.strain_rate_22() * dy;
    if (s.strain_rate_12() != 0.0) {
      wx -= s.strain_rate_12() * dy;
      wy -= s.strain_rate_12() * dx;
    }
    m.kinetic += 0.5 * P.mass[i] * (wx * wx + wy * wy);
  }
  return m;
}

/// netsolve's snapshot files and field names (apps/netsolve/main.cpp write_snapshot), plus the
/// velocities: particles_<tag>.vtp, contacts_<tag>.vtp (disk-disk contacts).
void write_compact_snapshot(const DynamicSolver& s, const fs::path& out, const std::string& tag,
                            std::vector<ContactInfo>& cs) {
  const Particles& P = s.particles();
  std::vector<double> pre(P.size(), 0.0);
  for (auto p : s.prescribed()) pre[p] = 1.0;
  Field vel{"velocity", 3, {}};
  for (std::size_t i = 0; i < P.size(); ++i) vel.values.insert(vel.values.end(), {P.vx[i], P.vy[i], 0.0});
  write_file_atomic(out / fmt::format("particles_{}.vtp", tag),
                    vtp_particles(P.x, P.y,
                                  {{"radius", 1, P.radius}, {"theta", 1, P.theta}, {"peripheral", 1, pre}, vel,
                                   {"omega", 1, P.omega}}));
  s.contacts(cs);
  std::vector<int> ci, cj;
  Field fn{"normal_force", 1, {}}, ft{"tangential_force", 1, {}}, ov{"overlap", 1, {}}, sl{"sliding", 1, {}};
  for (const auto& c : cs) {
    if (c.wall >= 0 || !(c.f_n > 0.0)) continue;
    ci.push_back(static_cast<int>(c.i));
    cj.push_back(static_cast<int>(c.j));
    fn.values.push_back(c.f_n);
    ft.values.push_back(c.f_t);
    ov.values.push_back(c.overlap);
    sl.values.push_back(c.sliding ? 1.0 : 0.0);
  }
  write_file_atomic(out / fmt::format("contacts_{}.vtp", tag), vtp_network(P.x, P.y, ci, cj, {fn, ft, ov, sl}));
}

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
