// demsolve compact --dim 3: spheres, six walls or the full affine field (compact.hpp).
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

// ---- 3D (issue 16): spheres, six walls or the full affine field ------------------------------------
namespace {

/// A 3D strain-rate direction: hydrostatic, closed-die (along z, the deposition's gravity axis),
/// E11,E22,E33 or E11,E22,E33,E23,E13,E12.
struct Path3 {
  std::string name;
  std::array<double, 6> E{};  ///< E11, E22, E33, E23, E13, E12
  bool shear() const { return E[3] != 0.0 || E[4] != 0.0 || E[5] != 0.0; }
  double trace() const { return E[0] + E[1] + E[2]; }
  double norm() const {  // Frobenius: sqrt(E:E)
    return std::sqrt(E[0] * E[0] + E[1] * E[1] + E[2] * E[2] + 2.0 * (E[3] * E[3] + E[4] * E[4] + E[5] * E[5]));
  }
};

Path3 parse_path3(const std::string& text) {
  if (text == "hydrostatic") return {text, {-1, -1, -1, 0, 0, 0}};
  if (text == "closed-die") return {text, {0, 0, -1, 0, 0, 0}};
  std::vector<double> v;
  std::istringstream in(text);
  std::string item;
  bool ok = !text.empty() && text.back() != ',';
  while (ok && std::getline(in, item, ',')) {
    std::istringstream one(item);
    double x = 0.0;
    ok = static_cast<bool>(one >> x) && (one >> std::ws).eof() && std::isfinite(x);
    v.push_back(x);
  }
  ok = ok && (v.size() == 3 || v.size() == 6);
  if (!ok)
    throw UsageError(fmt::format("--path '{}' is not 'hydrostatic', 'closed-die', or 3 or 6 finite numbers E11,E22,E33"
                                 "[,E23,E13,E12] (--dim 3)", quote_input(text)));
  Path3 p{text, {v[0], v[1], v[2], 0, 0, 0}};
  if (v.size() == 6) p.E = {v[0], v[1], v[2], v[3], v[4], v[5]};
  if (!(p.norm() > 0.0)) throw UsageError(fmt::format("--path {} has no direction", quote_input(text)));
  return p;
}

/// One sample of the measured state in 3D (netsolve's sign: compression negative); components
/// 11, 22, 33, 23, 13, 12.
struct Sample3 {
  double S[6] = {}, Sc[6] = {};
  double Z = 0, contacts = 0, sliding = 0, mean_fn = 0;
  double dev_mean_ratio = 0, dev_ratio_of_means = 0, affine_ut = 0;
  double kinetic = 0, work = 0;
  void add(const Sample3& o, double w) {
    for (int k = 0; k < 6; ++k) S[k] += w * o.S[k], Sc[k] += w * o.Sc[k];
    Z += w * o.Z, contacts += w * o.contacts, sliding += w * o.sliding, mean_fn += w * o.mean_fn;
    dev_mean_ratio += w * o.dev_mean_ratio, dev_ratio_of_means += w * o.dev_ratio_of_means, affine_ut += w * o.affine_ut;
    kinetic += w * o.kinetic, work += w * o.work;
  }
};

/// A loaded sphere-sphere contact: its spring force (the law's normal force on the committed
/// branch, without the dashpot), overlap and normal.
struct Contact3 {
  std::uint32_t i = 0, j = 0;
  double f_n = 0, overlap = 0, n[3] = {0, 0, 0};
  bool sliding = false;
};

/// The loaded sphere-sphere contacts of the current state, from the solver's touching pairs and
/// their committed plastic histories (until DynamicSolver3::contacts() exists).
void loaded_contacts3(const DynamicSolver3& s, std::vector<std::pair<std::uint32_t, std::uint32_t>>& pairs,
                      std::vector<Contact3>& out) {
  out.clear();
  s.touching_pairs(pairs);
  const Particles& P = s.particles();
  for (const auto& [i, j] : pairs) {
    const double l[3] = {P.x[j] - P.x[i], P.y[j] - P.y[i], P.z[j] - P.z[i]};
    const double L = std::sqrt(l[0] * l[0] + l[1] * l[1] + l[2] * l[2]);
    const double ri = P.radius[i], rj = P.radius[j], u = ri + rj - L;
    const auto* h = s.plastic_history(i, j);
    double f = 0.0, k = 0.0;
    contact::NormalBranch b;
    contact::normal_force<3>(s.plastic_law(), ri * rj / (ri + rj), h ? h->u_max : 0.0, u, f, k, b);
    if (!(f > 0.0)) continue;
    Contact3 c;
    c.i = i, c.j = j, c.f_n = f, c.overlap = u;
    for (int a = 0; a < 3; ++a) c.n[a] = l[a] / L;
    c.sliding = h && h->sliding;
    out.push_back(c);
  }
}

/// The measures of the current state (as the 2D Meter, scene.cpp), over the loaded sphere contacts.
class Meter3 {
 public:
  Meter3(bool walls, double r_mean) : walls_(walls), r_mean_(r_mean) {}
  /// E: the macroscopic strain accumulated so far (11, 22, 33, 23, 13, 12).
  Sample3 measure(const DynamicSolver3& s, const std::array<double, 6>& E) {
    Sample3 m;
    const Stress3 b = walls_ ? s.wall_stress() : s.boundary_stress();
    const Stress3 c = s.contact_stress();
    static constexpr int ia[6] = {0, 1, 2, 1, 0, 0}, ib[6] = {0, 1, 2, 2, 2, 1};
    for (int k = 0; k < 6; ++k) {
      m.S[k] = -0.5 * (b.s[ia[k]][ib[k]] + b.s[ib[k]][ia[k]]);
      m.Sc[k] = -0.5 * (c.s[ia[k]][ib[k]] + c.s[ib[k]][ia[k]]);
    }
    loaded_contacts3(s, pairs_, cs_);
    const Particles& P = s.particles();
    std::unordered_map<std::uint64_t, std::array<double, 6>> formed;
    formed.reserve(cs_.size());
    int n_ratio = 0;
    double sum_fn = 0, sum_ratio = 0, sum_absdev = 0, sum_una = 0, sum_ta = 0;
    for (const auto& ct : cs_) {
      const std::uint64_t key = (std::uint64_t{ct.i} << 32) | ct.j;
      std::array<double, 6> ef = prev_;  // first seen: the strain at the previous sample
      if (const auto it = form_.find(key); it != form_.end()) ef = it->second;
      formed.emplace(key, ef);
      sum_fn += ct.f_n;
      m.sliding += ct.sliding ? 1.0 : 0.0;
      m.work += 0.5 * ct.f_n * ct.overlap;
      // Eq 16 with the strain since the contact formed: u_N^a = -n.dE.n (r_i + r_j), u_T^a = |dE n - (n.dE.n) n| (r_i + r_j)
      const double d[3][3] = {{E[0] - ef[0], E[5] - ef[5], E[4] - ef[4]},
                              {E[5] - ef[5], E[1] - ef[1], E[3] - ef[3]},
                              {E[4] - ef[4], E[3] - ef[3], E[2] - ef[2]}};
      double dn[3], ndn = 0.0;
      for (int a = 0; a < 3; ++a) {
        dn[a] = d[a][0] * ct.n[0] + d[a][1] * ct.n[1] + d[a][2] * ct.n[2];
        ndn += ct.n[a] * dn[a];
      }
      const double Rsum = P.radius[ct.i] + P.radius[ct.j];
      const double una = -ndn * Rsum;
      double t2 = 0.0;
      for (int a = 0; a < 3; ++a) t2 += (dn[a] - ndn * ct.n[a]) * (dn[a] - ndn * ct.n[a]);
      sum_absdev += std::fabs(ct.overlap - una);
      sum_una += una;
      if (una > 1e-12 * r_mean_) {
        sum_ratio += std::fabs(ct.overlap - una) / una;
        ++n_ratio;
      }
      sum_ta += std::sqrt(t2) * Rsum;
    }
    form_.swap(formed);
    prev_ = E;
    const auto n = static_cast<double>(P.size());
    const int loaded = static_cast<int>(cs_.size());
    m.contacts = loaded;
    m.Z = 2.0 * loaded / n;
    m.mean_fn = loaded > 0 ? sum_fn / loaded : 0.0;
    const int nl = std::max(loaded, 1);
    const double una_mean = sum_una / nl;
    m.dev_mean_ratio = n_ratio > 0 ? sum_ratio / n_ratio : 0.0;
    m.dev_ratio_of_means = una_mean > 0 ? (sum_absdev / nl) / una_mean : 0.0;
    m.affine_ut = una_mean > 0 ? (sum_ta / nl) / una_mean : 0.0;
    // kinetic energy of the motion relative to the affine field L (x - x_0) and of the spins
    is_pre_.assign(P.size(), 0);
    for (auto p : s.prescribed()) is_pre_[p] = 1;
    const Box& bx = s.box();
    for (std::size_t i = 0; i < P.size(); ++i) {
      m.kinetic += 0.5 * P.inertia[i] * (P.wx[i] * P.wx[i] + P.wy[i] * P.wy[i] + P.omega[i] * P.omega[i]);
      if (is_pre_[i]) continue;
      const double x[3] = {P.x[i] - bx.x_min, P.y[i] - bx.y_min, P.z[i] - bx.z_min};
      const double v[3] = {P.vx[i], P.vy[i], P.vz[i]};
      for (int a = 0; a < 3; ++a) {
        double w = v[a];
        for (int q = 0; q < 3; ++q) w -= s.strain_rate3(a, q) * x[q];
        m.kinetic += 0.5 * P.mass[i] * w * w;
      }
    }
    return m;
  }
  const std::vector<Contact3>& last_contacts() const { return cs_; }

 private:
  bool walls_;
  double r_mean_;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs_;
  std::vector<Contact3> cs_;
  std::vector<std::uint8_t> is_pre_;
  std::unordered_map<std::uint64_t, std::array<double, 6>> form_;
  std::array<double, 6> prev_{};
};

/// particles_<tag>.vtp (x, y, z; radius, prescribed, velocity, spin) and contacts_<tag>.vtp (the
/// loaded sphere-sphere contacts: normal force, overlap, sliding).
void write_snapshot3(const DynamicSolver3& s, const fs::path& out, const std::string& tag,
                     std::vector<std::pair<std::uint32_t, std::uint32_t>>& pairs, std::vector<Contact3>& cs) {
  const Particles& P = s.particles();
  std::vector<double> pre(P.size(), 0.0);
  for (auto p : s.prescribed()) pre[p] = 1.0;
  Field vel{"velocity", 3, {}}, spin{"spin", 3, {}};
  for (std::size_t i = 0; i < P.size(); ++i) {
    vel.values.insert(vel.values.end(), {P.vx[i], P.vy[i], P.vz[i]});
    spin.values.insert(spin.values.end(), {P.wx[i], P.wy[i], P.omega[i]});
  }
  write_file_atomic(out / fmt::format("particles_{}.vtp", tag),
                    vtp_particles_3d(P.x, P.y, &P.z, {{"radius", 1, P.radius}, {"prescribed", 1, pre}, vel, spin}));
  loaded_contacts3(s, pairs, cs);
  std::vector<int> ci, cj;
  Field fn{"normal_force", 1, {}}, ov{"overlap", 1, {}}, sl{"sliding", 1, {}};
  for (const auto& c : cs) {
    ci.push_back(static_cast<int>(c.i));
    cj.push_back(static_cast<int>(c.j));
    fn.values.push_back(c.f_n);
    ov.values.push_back(c.overlap);
    sl.values.push_back(c.sliding ? 1.0 : 0.0);
  }
  write_file_atomic(out / fmt::format("contacts_{}.vtp", tag), vtp_network_3d(P.x, P.y, &P.z, ci, cj, {fn, ov, sl}));
}

/// The packing of --dim 3: a 3D packing file, or netsolve pack --dim 3's deposition.
packing::Packing input_packing_3d(const DemCompactArgs& a, std::string& source) {
  if (!a.packing_file.empty()) {
    if (fs::is_directory(a.packing_file))
      throw UsageError(fmt::format("--packing '{}' is a folder, not a packing CSV file (netsolve pack writes DIR/packing.csv)",
                                   quote_input(a.packing_file)));
    source = a.packing_file;
    packing::Packing p = packing::read_packing_csv(a.packing_file);
    if (p.dim != 3)
      throw UsageError(fmt::format("--packing {} is a 2D packing; --dim 3 needs a 3D packing file (id,x,y,z,r with "
                                   "'# dim 3', netsolve pack --dim 3)", quote_input(a.packing_file)));
    for (const auto& c : p.comments)
      if (c.find("lateral periodic") != std::string::npos)
        throw UsageError(fmt::format("--packing {} is a periodic deposition; the explicit DEM has no periodic boundaries "
                                     "(use --lateral walls)", quote_input(a.packing_file)));
    return p;
  }
  source = fmt::format("3D ballistic deposition, W = {} R, r = R[{}, {}], seed {}, lateral walls", a.pack.width,
                       a.pack.mono ? 1.0 : a.pack.r_min, a.pack.mono ? 1.0 : a.pack.r_max, a.pack.seed);
  return netdem::app::netsolve::make_packing_3d(a.pack);
}

}  // namespace

int run_dem_compact_3d(const std::string& command, const DemCompactArgs& a, const fs::path& out) {
  // ---- the door: every value before anything is written ----------------------------------------
  const Path3 path = parse_path3(a.path);
  check_compact_numbers(a);
  if (a.boundary != "layer" && a.boundary != "walls")
    throw UsageError(fmt::format("--boundary '{}' is not 'layer' or 'walls'", quote_input(a.boundary)));
  const bool walls = a.boundary == "walls";
  if (walls && a.affine) throw UsageError("--affine and --boundary walls exclude each other (affine prescribes every centre)");
  if (!walls && !a.affine)
    throw UsageError("--dim 3 takes --boundary walls or --affine (--boundary layer, netsolve's peripheral layer, is 2D only)");
  if (walls && path.shear())
    throw UsageError(fmt::format("--path {}: --boundary walls takes E23 = E13 = E12 = 0 only (the walls stay axis-aligned)",
                                 quote_input(a.path)));
  if (a.pack.lateral != "walls")
    throw UsageError(fmt::format("--lateral '{}': the explicit DEM has no periodic boundaries (demsolve compact --dim 3 "
                                 "takes --lateral walls)", quote_input(a.pack.lateral)));
  if (a.pack.lid != "centre" && a.pack.lid != "inside")
    throw UsageError(fmt::format("--lid '{}' is not 'centre' or 'inside'", quote_input(a.pack.lid)));
  const double mu = netdem::app::netsolve::parse_friction(a.friction);
  const auto snaps = netdem::app::netsolve::parse_number_list(a.snapshots, "--snapshots");
  if (!(std::isfinite(a.to_density) && a.to_density > 0.0 && a.to_density < 1.0))
    throw UsageError(fmt::format("target density must be in (0, 1), got {}", a.to_density));
  if (!(path.trace() < 0.0))
    throw UsageError(fmt::format("impossible target: strain path {} (E11+E22+E33 = {}) does not compact, so density {} is "
                                 "never reached", quote_input(a.path), path.trace(), a.to_density));
  RunDirOptions rdo;
  rdo.overwrite = a.overwrite;
  if (!a.packing_file.empty()) rdo.inputs.emplace_back(a.packing_file);
  check_run_dir(out, rdo);
  if (a.packing_file.empty()) netdem::app::netsolve::check_deposition_size(a.pack);
  activity() = a.packing_file.empty() ? "building the 3D ballistic deposition" : "reading the packing " + a.packing_file;
  std::string source;
  const packing::Packing pk = input_packing_3d(a, source);
  check_memory(pk.size());
  const std::size_t n = pk.size();
  if (n == 0) throw UsageError("the packing has no spheres");

  Particles P = spheres_from(pk, 1.0);  // rho = 1
  // the walls enclose every sphere at the start
  packing::Box b0 = pk.box;
  if (walls)
    for (std::size_t i = 0; i < n; ++i) {
      b0.x_min = std::min(b0.x_min, pk.x[i] - pk.r[i]), b0.x_max = std::max(b0.x_max, pk.x[i] + pk.r[i]);
      b0.y_min = std::min(b0.y_min, pk.y[i] - pk.r[i]), b0.y_max = std::max(b0.y_max, pk.y[i] + pk.r[i]);
      b0.z_min = std::min(b0.z_min, pk.z[i] - pk.r[i]), b0.z_max = std::max(b0.z_max, pk.z[i] + pk.r[i]);
    }
  Box box(b0);
  box.contact_walls = walls;
  box.right.mode = box.back.mode = box.top.mode = WallMode::Affine;
  const DynamicOptions o = plastic_options(mu, a.k_t, a.normal_unloading == "reversible", a.first_touch, a.damping,
                                           a.drag, a.steps_per_contact);
  double vol = 0.0;
  for (double r : P.radius) vol += 4.0 / 3.0 * std::numbers::pi * r * r * r;
  const double V0 = (box.x_max - box.x_min) * (box.y_max - box.y_min) * (box.z_max - box.z_min);
  const double D0 = vol / V0;
  if (!(a.to_density > D0))
    throw UsageError(fmt::format("impossible target: density {} is not above the current density {:.4f}", a.to_density, D0));
  // the rate: I = gamma' d sqrt(rho/P_ref), gamma' = |E'| (Frobenius), d = 2R, P_ref = sigma_y
  const double rho = 1.0, sigma_y = 1.0, d_mean = 2.0;
  const double gdot = a.inertial_number / (d_mean * std::sqrt(rho / sigma_y));
  std::array<double, 6> e{};
  for (int k = 0; k < 6; ++k) e[static_cast<std::size_t>(k)] = gdot * path.E[static_cast<std::size_t>(k)] / path.norm();
  const double T = std::log(D0 / a.to_density) / (e[0] + e[1] + e[2]);  // D = D0 exp(-tr E' t)

  activity() = "setting up the explicit solver";
  DynamicSolver3 s(std::move(P), LudingParams{}, box, o);
  s.set_strain_rate3(e[0], e[1], e[2], e[3], e[4], e[5]);
  s.set_affine_velocities();
  // affine: every centre prescribed, every spin free (3D has no peripheral layer yet); walls: none prescribed
  std::vector<std::uint32_t> pre;
  if (a.affine)
    for (std::uint32_t p = 0; p < n; ++p) pre.push_back(p);
  s.set_prescribed(pre, false);
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
    std::fprintf(stderr, "demsolve compact --dim 3: %zu spheres, D0 = %.4f, seed %llu (%s); I = %g, gamma' = %.4g, "
                 "t_end = %.4g, dt = %.3g, about %.3g steps\n", n, D0, static_cast<unsigned long long>(pk.seed),
                 source.c_str(), a.inertial_number, gdot, T, dt_first, steps_est);
  // a centre outside the deformed domain: the box, or with shear the parallelepiped x_0 + F (box_0 - x_0)
  const Box box0 = box;
  const double L0[3] = {box0.x_max - box0.x_min, box0.y_max - box0.y_min, box0.z_max - box0.z_min};
  auto outside_box = [&](double x, double y, double z) {
    const Box& b = s.box();
    if (!path.shear())
      return x < b.x_min || x > b.x_max || y < b.y_min || y > b.y_max || z < b.z_min || z > b.z_max;
    const auto& Fm = s.affine_map3();
    Eigen::Matrix3d F;
    F << Fm[0], Fm[1], Fm[2], Fm[3], Fm[4], Fm[5], Fm[6], Fm[7], Fm[8];
    const Eigen::Vector3d X = F.partialPivLu().solve(Eigen::Vector3d(x - box0.x_min, y - box0.y_min, z - box0.z_min));
    for (int k = 0; k < 3; ++k)
      if (X(k) < 0.0 || X(k) > L0[k]) return true;
    return false;
  };
  std::vector<std::pair<std::uint32_t, std::uint32_t>> snap_pairs;
  std::vector<Contact3> snap_buf;
  write_snapshot3(s, out, "initial", snap_pairs, snap_buf);
  double r_mean = 0.0;
  for (double r : s.particles().radius) r_mean += r;
  r_mean /= static_cast<double>(n);
  Meter3 meter(walls, r_mean);
  std::string csv =
      "increment,E11,E22,E33,E23,E13,E12,D,S11,S22,S33,S23,S13,S12,S11_contacts,S22_contacts,S33_contacts,S23_contacts,"
      "S13_contacts,S12_contacts,Z,contacts,sliding,mean_fn,dev_un_mean_ratio,dev_un_ratio_of_means,affine_ut,time,I,"
      "kinetic_ratio,steps,samples,dt,outside,D_in_box";
  if (walls) csv += ",wall_vs_contact_gap";
  csv += "\n";
  auto gap_of = [](const Sample3& m) {  // the diagonal (the walls carry no shear)
    const double d = std::sqrt((m.S[0] - m.Sc[0]) * (m.S[0] - m.Sc[0]) + (m.S[1] - m.Sc[1]) * (m.S[1] - m.Sc[1]) +
                               (m.S[2] - m.Sc[2]) * (m.S[2] - m.Sc[2]));
    const double c = std::sqrt(m.Sc[0] * m.Sc[0] + m.Sc[1] * m.Sc[1] + m.Sc[2] * m.Sc[2]);
    return c > 0.0 ? d / c : 0.0;
  };
  auto strain = [&] {
    std::array<double, 6> E{};
    for (std::size_t k = 0; k < 6; ++k) E[k] = e[k] * s.time();
    return E;
  };
  Sample3 last;
  double last_I = 0.0, max_gap = 0.0, last_gap = 0.0;
  std::int64_t steps = 0;
  int done = 0;
  auto write_row = [&](int k, const Sample3& m, int samples) {
    const double t = s.time();
    const double Pc = -(m.Sc[0] + m.Sc[1] + m.Sc[2]) / 3.0;
    // the actual inertial number; undefined (an empty field, no inf in a result file) where P = 0
    const double I = Pc > 0.0 ? gdot * d_mean * std::sqrt(rho / Pc) : std::numeric_limits<double>::quiet_NaN();
    const double kr = m.work > 0.0 ? m.kinetic / m.work : 0.0;
    csv += fmt::format("{},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g}", k, e[0] * t, e[1] * t, e[2] * t, e[3] * t,
                       e[4] * t, e[5] * t, s.density());
    for (double v : m.S) csv += fmt::format(",{:.9g}", v);
    for (double v : m.Sc) csv += fmt::format(",{:.9g}", v);
    csv += fmt::format(",{:.6g},{:.6g},{:.6g},{:.9g},{:.6g},{:.6g},{:.6g},{:.9g},{},{:.4e},{},{},{:.4e}", m.Z, m.contacts,
                       m.sliding, m.mean_fn, m.dev_mean_ratio, m.dev_ratio_of_means, m.affine_ut, t,
                       std::isfinite(I) ? fmt::format("{:.6g}", I) : std::string(), kr, steps, samples, s.dt());
    {  // centres outside the deformed domain and the density without them
      const Particles& Q = s.particles();
      const Box& b = s.box();
      int outside = 0;
      double in = 0.0;
      for (std::size_t p = 0; p < Q.size(); ++p) {
        const bool o = outside_box(Q.x[p], Q.y[p], Q.z[p]);
        outside += o;
        if (!o) in += 4.0 / 3.0 * std::numbers::pi * Q.radius[p] * Q.radius[p] * Q.radius[p];
      }
      csv += fmt::format(",{},{:.9g}", outside, in / ((b.x_max - b.x_min) * (b.y_max - b.y_min) * (b.z_max - b.z_min)));
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
  static const char* const kComp[6] = {"11", "22", "33", "23", "13", "12"};
  nlohmann::json summary;
  summary["command"] = command;
  summary["dim"] = 3;
  summary["packing"] = source;
  summary["seed"] = pk.seed;
  summary["particles"] = n;
  summary["initial_density"] = D0;
  summary["sigma_y"] = 1.0;
  summary["friction"] = a.friction;
  summary["mode"] = a.affine ? "affine" : "walls";
  summary["boundary"] = a.affine ? "affine" : a.boundary;
  summary["prescribed"] = pre.size();
  summary["rotations"] = !a.no_rotation;
  summary["path"] = {{"name", path.name}};
  for (int k = 0; k < 6; ++k) summary["path"][std::string("E") + kComp[k]] = path.E[static_cast<std::size_t>(k)];
  summary["increments"] = a.increments;
  summary["to_density"] = a.to_density;
  summary["k_t"] = a.k_t;
  summary["first_touch"] = a.first_touch;
  summary["normal_unloading"] = a.normal_unloading;
  summary["inertial_number"] = a.inertial_number;
  summary["strain_rate"] = {{"gamma_dot", gdot}};
  for (int k = 0; k < 6; ++k) summary["strain_rate"][std::string("E") + kComp[k]] = e[static_cast<std::size_t>(k)];
  summary["t_end"] = T;
  summary["damping"] = {{"normal", a.damping}, {"tangential", a.damping}};
  summary["drag"] = a.drag;
  summary["steps_per_contact"] = a.steps_per_contact;
  summary["units"] = "sigma_y = 1, R = 1 (lengths of the packing), rho = 1, t* = R sqrt(rho/sigma_y) = 1";
  summary["contact_forces"] = "Z, mean_fn, sliding: the loaded sphere-sphere contacts, spring force without the dashpot";

  const auto t0 = std::chrono::steady_clock::now();
  Progress progress("compact", T, a.quiet);
  write_row(0, meter.measure(s, strain()), 1);
  std::size_t next_snap = 0;
  const auto every = static_cast<std::int64_t>(std::clamp(T / a.increments / dt_first / 10.0, 1.0, 20.0));
  activity() = "compacting";
  try {
    for (int k = 1; k <= a.increments; ++k) {
      const double t_end = T * k / a.increments;
      Sample3 acc;
      int samples = 0;
      std::int64_t since = 0;
      while (s.time() < t_end - 1e-12 * T) {
        s.step();
        ++steps;
        if (++since % every == 0 || !(s.time() < t_end - 1e-12 * T)) {
          acc.add(meter.measure(s, strain()), 1.0);
          ++samples;
          progress.update(s.time());
        }
      }
      if (samples == 0) {
        acc.add(meter.measure(s, strain()), 1.0);
        samples = 1;
      }
      Sample3 mean;
      mean.add(acc, 1.0 / samples);
      s.check_health();  // nothing unchecked reaches a file
      write_row(k, mean, samples);
      done = k;
      while (next_snap < snaps.size() && s.density() >= snaps[next_snap] - 1e-9) {
        write_snapshot3(s, out, fmt::format("D{:.3f}", snaps[next_snap]), snap_pairs, snap_buf);
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
  write_snapshot3(s, out, "final", snap_pairs, snap_buf);
  int outside = 0;
  for (std::size_t p = 0; p < n; ++p) outside += outside_box(s.particles().x[p], s.particles().y[p], s.particles().z[p]);
  RunStatus status;
  std::vector<std::string> warnings;
  if (outside > 0) status.add("unstable", fmt::format("{} sphere centres left the box", outside));
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
  nlohmann::json fin = {{"D", s.density()}, {"Z", last.Z}, {"contacts", last.contacts}, {"sliding", last.sliding},
                        {"I", last_I}, {"kinetic_ratio", last.work > 0 ? last.kinetic / last.work : 0.0},
                        {"time", s.time()}};
  for (int k = 0; k < 6; ++k) {
    const auto kk = static_cast<std::size_t>(k);
    fin[std::string("S") + kComp[k]] = last.S[k];
    fin[std::string("S") + kComp[k] + "_contacts"] = last.Sc[k];
    fin[std::string("E") + kComp[k]] = e[kk] * s.time();
  }
  summary["final"] = fin;
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
  std::printf("D = %.4f: S11/sy = %.4f, S22/sy = %.4f, S33/sy = %.4f (contacts %.4f, %.4f, %.4f), Z = %.3f, I = %.3g, "
              "%lld steps, %.2f s -> %s\n", s.density(), last.S[0], last.S[1], last.S[2], last.Sc[0], last.Sc[1], last.Sc[2],
              last.Z, last_I, static_cast<long long>(steps), wall, out.c_str());
  for (const auto& w : warnings) std::fprintf(stderr, "demsolve: warning: %s\n", w.c_str());
  if (!status.ok()) {
    std::fprintf(stderr, "demsolve: error: %s: %s\n", status.status.c_str(), status.reason().c_str());
    return exit_code::untrustworthy;
  }
  return exit_code::ok;
}

}  // namespace netdem::app::dem
