// Periodic packings by the explicit DEM in a periodic cell (periodic_packing.hpp, docs/packing.md).
#include "netdem/dynamic/periodic_packing.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>
#include <vector>

#include <fmt/format.h>

#include "netdem/dynamic/solver.hpp"
#include "netdem/field_error.hpp"
#include "netdem/packing/periodic.hpp"
#include "netdem/system/rattlers.hpp"

namespace netdem::dem {

void PeriodicPackOptions::validate(int dim) const {
  if (dim != 2 && dim != 3) throw FieldError("dim", fmt::format("the dimension must be 2 or 3, got {}", dim));
  if (n < 16 || n > 1000000)
    throw FieldError("n", fmt::format("the number of particles n must be in [16, 1e6], got {}", n));
  if (!(std::isfinite(r_min) && std::isfinite(r_max) && r_min > 0.0 && r_min <= r_max && r_max <= 3.0 * r_min))
    throw FieldError("r_min", fmt::format("the radii must satisfy 0 < r_min <= r_max <= 3 r_min, got [{}, {}]", r_min, r_max));
  if (!(std::isfinite(friction) && friction >= 0.0 && friction <= 10.0))
    throw FieldError("friction", fmt::format("the packing law's friction must be in [0, 10], got {}", friction));
  if (!(std::isfinite(pressure) && pressure >= 1e-7 && pressure <= 1e-2))
    throw FieldError("pressure", fmt::format("the target pressure p / k_n must be in [1e-7, 1e-2], got {}", pressure));
  // (below the random sequential addition's jamming limits, 0.547 in 2D and 0.384 in 3D)
  if (!(std::isfinite(gas_density) && gas_density > 0.0 && gas_density <= (dim == 2 ? 0.45 : 0.3)))
    throw FieldError("gas_density", fmt::format("the gas density must be in (0, {}] (random sequential addition), got {}",
                                                dim == 2 ? 0.45 : 0.3, gas_density));
  if (!(pressure_tol > 0.0 && pressure_tol < 1.0 && force_tol > 0.0 && force_tol < 1.0))
    throw FieldError("pressure", "the pressure and force tolerances must be in (0, 1)");
  if (!(max_steps >= 1.0 && max_steps <= 1e10))
    throw FieldError("max_steps", fmt::format("the step limit must be in [1, 1e10], got {}", max_steps));
}

namespace {

template <int D>
double measure_of(double r) {
  return D == 2 ? std::numbers::pi * r * r : 4.0 / 3.0 * std::numbers::pi * r * r * r;
}

/// Random sequential addition in the periodic cube [0, L)^D (minimum image): radii uniform in
/// [r_min, r_max], each placed at the first random position that overlaps nothing placed, with a
/// bin grid of side >= 2 r_max (brute force when fewer than 3 bins per axis).
template <int D>
packing::Packing random_gas(const PeriodicPackOptions& o, std::mt19937_64& rng, double& L) {
  std::uniform_real_distribution<double> U(0.0, 1.0);
  std::vector<double> r(o.n);
  double solid = 0.0;
  for (double& v : r) {
    v = o.r_min + (o.r_max - o.r_min) * U(rng);
    solid += measure_of<D>(v);
  }
  L = std::pow(solid / o.gas_density, 1.0 / D);
  const int nb = std::max(1, static_cast<int>(std::floor(L / (2.0 * o.r_max))));
  const bool grid = nb >= 3;
  std::size_t bins = 1;
  for (int a = 0; a < D; ++a) bins *= static_cast<std::size_t>(grid ? nb : 1);
  std::vector<std::vector<std::uint32_t>> bin(bins);
  std::vector<std::array<double, D>> x;
  x.reserve(o.n);
  auto bin_of = [&](const std::array<double, D>& p, std::array<int, D>& b) {
    for (int a = 0; a < D; ++a) b[a] = grid ? std::min(nb - 1, static_cast<int>(p[a] / L * nb)) : 0;
  };
  auto index = [&](const std::array<int, D>& b) {
    std::size_t k = 0;
    for (int a = D - 1; a >= 0; --a) k = k * static_cast<std::size_t>(grid ? nb : 1) + static_cast<std::size_t>(b[a]);
    return k;
  };
  auto free_at = [&](const std::array<double, D>& p, double rp) {
    std::array<int, D> b;
    bin_of(p, b);
    const int span = grid ? 1 : 0;
    std::array<int, D> off;
    off.fill(-span);
    while (true) {
      std::array<int, D> q;
      for (int a = 0; a < D; ++a) q[a] = grid ? ((b[a] + off[a]) % nb + nb) % nb : 0;
      for (std::uint32_t j : bin[index(q)]) {
        double d2 = 0.0;
        for (int a = 0; a < D; ++a) {
          double d = x[j][a] - p[a];
          d -= L * std::round(d / L);
          d2 += d * d;
        }
        if (d2 < (rp + r[j]) * (rp + r[j])) return false;
      }
      int a = 0;  // the next neighbour bin (odometer over -span..span)
      while (a < D && ++off[a] > span) off[a++] = -span;
      if (a == D) return true;
    }
  };
  for (std::size_t i = 0; i < o.n; ++i) {
    std::array<double, D> p;
    bool placed = false;
    for (int attempt = 0; attempt < 1000000 && !placed; ++attempt) {
      for (int a = 0; a < D; ++a) p[a] = L * U(rng);
      placed = free_at(p, r[i]);
    }
    if (!placed) throw std::runtime_error("random sequential addition: no free place after 1e6 attempts");
    std::array<int, D> b;
    bin_of(p, b);
    bin[index(b)].push_back(static_cast<std::uint32_t>(i));
    x.push_back(p);
  }
  packing::Packing pk;
  pk.dim = D;
  pk.periodic = true;
  pk.seed = o.seed;
  pk.r = r;
  for (const auto& p : x) {
    pk.x.push_back(p[0]);
    pk.y.push_back(p[1]);
    if constexpr (D == 3) pk.z.push_back(p[2]);
  }
  pk.box = {0.0, 0.0, L, L};
  if constexpr (D == 3) pk.box.z_min = 0.0, pk.box.z_max = L;
  return pk;
}

template <int D>
double pressure_of(const DynamicSolverT<D>& s) {
  const auto sc = s.contact_stress();
  if constexpr (D == 2) {
    return 0.5 * (sc.xx + sc.yy);
  } else {
    return (sc.s[0][0] + sc.s[1][1] + sc.s[2][2]) / 3.0;
  }
}

template <int D>
void set_isotropic_rate(DynamicSolverT<D>& s, double e) {
  if constexpr (D == 2) {
    s.set_strain_rate(e, e, 0.0);
  } else {
    s.set_strain_rate3(e, e, e);
  }
}

/// The measures of the end state: coordination with and without rattlers, psi6 (2D), overlaps.
template <int D>
void measure(const DynamicSolverT<D>& s, PeriodicPackSummary& m, double r_mean, bool friction) {
  std::vector<ContactInfo> cs;
  s.contacts(cs);
  const std::size_t n = s.particles().size();
  double sum_ov = 0.0, max_ov = 0.0, sum_f = 0.0;
  for (const auto& c : cs) {
    sum_ov += c.overlap;
    max_ov = std::max(max_ov, c.overlap);
    sum_f += c.f_n;
  }
  m.contacts = cs.size();
  m.Z = 2.0 * static_cast<double>(cs.size()) / static_cast<double>(n);
  m.mean_overlap = cs.empty() ? 0.0 : sum_ov / static_cast<double>(cs.size()) / r_mean;
  m.max_overlap = max_ov / r_mean;
  // rattlers: fewer than D + 1 contacts (frictional: fewer than D), removed until none is left
  std::vector<int> pi, pj;
  for (const auto& c : cs) pi.push_back(static_cast<int>(c.i)), pj.push_back(static_cast<int>(c.j));
  const sys::Backbone bb = sys::prune_rattlers(n, pi, pj, {}, friction ? D : D + 1);
  m.rattler_fraction = static_cast<double>(bb.rattlers) / static_cast<double>(n);
  m.Z_backbone = bb.Z;
  if constexpr (D == 2) {  // hexatic order over each particle's contacts
    std::vector<std::complex<double>> psi(n, 0.0);
    std::vector<int> cnt(n, 0);
    for (const auto& c : cs) {
      const std::complex<double> e = std::polar(1.0, 6.0 * std::atan2(c.ny, c.nx));  // (theta + pi: the same)
      psi[c.i] += e, psi[c.j] += e;
      ++cnt[c.i], ++cnt[c.j];
    }
    std::complex<double> g = 0.0;
    double local = 0.0;
    std::size_t with = 0;
    for (std::size_t i = 0; i < n; ++i) {
      if (cnt[i] == 0) continue;
      const std::complex<double> p = psi[i] / static_cast<double>(cnt[i]);
      g += p;
      local += std::abs(p);
      ++with;
    }
    m.psi6_global = with > 0 ? std::abs(g) / static_cast<double>(with) : 0.0;
    m.psi6_local = with > 0 ? local / static_cast<double>(with) : 0.0;
  }
  const double f_mean = cs.empty() ? 0.0 : sum_f / static_cast<double>(cs.size());
  m.unbalanced = f_mean > 0.0 ? s.unbalanced_force_rms() / f_mean : std::numeric_limits<double>::infinity();
}

struct ServoState {
  double e_max = 0.0, e0 = 0.0, e_floor = 0.0, relax = 1.0, p_avg = 0.0;
  int side = -1;  ///< -1 below the target, +1 above
};

/// The servo on the pressure averaged over 2 t_c (a gas's collisions reach a small target for an
/// instant): e = -e_max (1 - p / p_t), clipped to [-e_max, e_max]; e_max halves at every crossing
/// of the target after the first (a bisection of the jamming density), down to e_floor. Runs until
/// the pressure (averaged and instantaneous) is within pressure_tol of the target and the RMS
/// unbalanced force below force_tol of the mean contact force (true), or to the step limit.
template <int D>
bool servo(DynamicSolverT<D>& s, double target, const PeriodicPackOptions& o, PeriodicPackSummary& m, double r_mean,
           std::int64_t limit, std::int64_t& k, ServoState& sv, const std::function<void(double)>& progress) {
  if (sv.e0 == 0.0) sv.e0 = sv.e_max;
  for (; k < limit; ++k) {
    const double p_now = pressure_of<D>(s);
    sv.p_avg += sv.relax * (p_now - sv.p_avg);
    const double p = sv.p_avg;
    const int now = p > target ? 1 : -1;
    if (now != sv.side) {
      if (sv.side == 1 || m.steps_to_first_contact_pressure > 0) sv.e_max = std::max(sv.e_floor, 0.5 * sv.e_max);
      if (m.steps_to_first_contact_pressure == 0 && now == 1) m.steps_to_first_contact_pressure = k;
      sv.side = now;
    }
    set_isotropic_rate<D>(s, -sv.e_max * std::clamp(1.0 - p / target, -1.0, 1.0));
    s.step();
    if (k % 200 != 0) continue;
    if (progress) progress(static_cast<double>(k) / static_cast<double>(limit));
    if (std::fabs(p / target - 1.0) < o.pressure_tol && std::fabs(p_now / target - 1.0) < o.pressure_tol) {
      measure<D>(s, m, r_mean, o.friction > 0.0);
      if (m.unbalanced < o.force_tol) return true;
    }
  }
  return false;
}

template <int D>
packing::Packing make(const PeriodicPackOptions& o, PeriodicPackSummary& m, const std::function<void(double)>& progress) {
  std::mt19937_64 rng(o.seed);
  double L = 0.0;
  const packing::Packing gas = random_gas<D>(o, rng, L);
  double r_mean = 0.0;
  for (double r : gas.r) r_mean += r;
  r_mean /= static_cast<double>(gas.size());
  const LudingParams lp = periodic_packing_law(D, r_mean, o.friction);
  const double m_mean = measure_of<D>(r_mean);  // rho = 1
  DynamicOptions opt;
  opt.model = ContactModel::Linear;
  opt.steps_per_contact = 25.0;
  opt.affine_drag = 0.0;
  ParticlesT<D> P = periodic_particles_from<D>(gas, 1.0);
  DynamicSolverT<D> s(std::move(P), lp, packing::periodic_cell<D>(gas), opt);
  m.dt = s.dt();
  // the drag on the fluctuations: 0.3 / t_c of the mean pair
  const double tc = std::numbers::pi * std::sqrt(0.5 * m_mean / lp.k2);
  s.set_affine_drag(0.3 / tc);
  // jammed first at p / k_n = 1e-3 (far enough from the jamming point to come to rest fast), then
  // held at the target if it is lower (the overlaps shrink with the pressure)
  const auto limit = static_cast<std::int64_t>(o.max_steps);
  ServoState sv;
  sv.e_max = 1e-4 / s.dt();  // the gas is compressed by 1e-4 of strain per step
  sv.e_floor = 1e-4 * sv.e_max;
  sv.relax = std::min(1.0, s.dt() / (2.0 * tc));
  std::int64_t k = 0;
  const double jam = std::max(o.pressure, 1e-3);
  bool done = servo<D>(s, jam, o, m, r_mean, limit, k, sv, progress);
  if (done && o.pressure < jam) {
    sv.side = 1;
    sv.e_max = std::max(sv.e_max, 1e-2 * sv.e0);
    done = servo<D>(s, o.pressure, o, m, r_mean, limit, k, sv, progress);
  }
  set_isotropic_rate<D>(s, 0.0);
  m.steps = k;
  measure<D>(s, m, r_mean, o.friction > 0.0);
  m.pressure = pressure_of<D>(s);
  m.density = s.density();
  if (!done) {
    m.status = "unconverged";
    m.reason = fmt::format("the step limit {:.3g} was reached before the packing came to rest at the target pressure "
                           "(p / k_n = {:.3g} for {:.3g}; unbalanced force {:.3g} of the mean contact force)",
                           o.max_steps, m.pressure, o.pressure, m.unbalanced);
  }
  packing::Packing pk = s.periodic_packing();
  pk.seed = o.seed;
  return pk;
}

}  // namespace

LudingParams periodic_packing_law(int dim, double r_mean, double friction) {
  LudingParams lp;
  lp.k2 = 1.0;
  lp.a0 = r_mean;
  lp.w0 = 0.0;
  lp.mu = friction;
  lp.mu_wall = 0.0;
  const double m_mean = dim == 3 ? measure_of<3>(r_mean) : measure_of<2>(r_mean);  // rho = 1
  lp.gamma_n = 2.0 * 0.3 * std::sqrt(lp.k2 * 0.5 * m_mean);
  lp.gamma_t = 0.5 * lp.gamma_n;
  return lp;
}

packing::Packing make_periodic_packing(int dim, const PeriodicPackOptions& o, PeriodicPackSummary& summary,
                                       const std::function<void(double)>& progress) {
  o.validate(dim);
  summary = PeriodicPackSummary{};
  return dim == 3 ? make<3>(o, summary, progress) : make<2>(o, summary, progress);
}

}  // namespace netdem::dem
