// The DEM compaction protocol and its measures, disks and spheres (compaction.hpp).
#include "netdem/dynamic/compaction.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include <Eigen/Dense>
#include <fmt/format.h>

#include "netdem/field_error.hpp"
#include "netdem/contact/kinematics.hpp"
#include "netdem/system/affine_deviation.hpp"

namespace netdem::dem {

namespace {

/// Voigt components of a solver stress, netsolve's sign (compression negative), the symmetric part.
template <int D>
Voigt<D> voigt_of(const typename DynamicSolverT<D>::Stress& b) {
  Voigt<D> v{};
  for (int k = 0; k < kVoigt<D>; ++k) {
    const int r = sys::voigt_row<D>(k), c = sys::voigt_col<D>(k);
    double brc = 0.0, bcr = 0.0;
    if constexpr (D == 2) {
      const double m[2][2] = {{b.xx, b.xy}, {b.yx, b.yy}};
      brc = m[r][c], bcr = m[c][r];
    } else {
      brc = b.s[r][c], bcr = b.s[c][r];
    }
    v[static_cast<std::size_t>(k)] = r == c ? -brc : -0.5 * (brc + bcr);
  }
  return v;
}

/// The symmetric D x D tensor of Voigt components a - b.
template <int D>
Eigen::Matrix<double, D, D> tensor_of_difference(const Voigt<D>& a, const Voigt<D>& b) {
  Eigen::Matrix<double, D, D> m;
  for (int k = 0; k < kVoigt<D>; ++k) {
    const auto kk = static_cast<std::size_t>(k);
    m(sys::voigt_row<D>(k), sys::voigt_col<D>(k)) = m(sys::voigt_col<D>(k), sys::voigt_row<D>(k)) = a[kk] - b[kk];
  }
  return m;
}

/// Kinetic energy of the motion relative to the affine field (the particles not prescribed) and of
/// the spins.
template <int D>
double fluctuating_kinetic(const DynamicSolverT<D>& s, const std::vector<std::uint8_t>& is_pre) {
  const ParticlesT<D>& P = s.particles();
  const Box& bx = s.box();
  double e = 0.0;
  if (s.periodic()) return s.energies().kinetic;  // the velocities are the fluctuations
  for (std::size_t i = 0; i < P.size(); ++i) {
    if constexpr (D == 2) {
      e += 0.5 * P.inertia[i] * P.spin[i] * P.spin[i];
      if (is_pre[i]) continue;
      const double dx = P.pos[2 * i] - bx.x_min, dy = P.pos[2 * i + 1] - bx.y_min;
      double wx = P.vel[2 * i] - s.strain_rate_11() * dx;
      double wy = P.vel[2 * i + 1] - s.strain_rate_22() * dy;
      if (s.strain_rate_12() != 0.0) {
        wx -= s.strain_rate_12() * dy;
        wy -= s.strain_rate_12() * dx;
      }
      e += 0.5 * P.mass[i] * (wx * wx + wy * wy);
    } else {
      const double* const om = &P.spin[3 * i];
      e += 0.5 * P.inertia[i] * (om[0] * om[0] + om[1] * om[1] + om[2] * om[2]);
      if (is_pre[i]) continue;
      const double x[3] = {P.pos[3 * i] - bx.x_min, P.pos[3 * i + 1] - bx.y_min, P.pos[3 * i + 2] - bx.z_min};
      const double* const v = &P.vel[3 * i];
      for (int a = 0; a < 3; ++a) {
        double w = v[a];
        for (int q = 0; q < 3; ++q) w -= s.strain_rate3(a, q) * x[q];
        e += 0.5 * P.mass[i] * w * w;
      }
    }
  }
  return e;
}

template <int D>
double particle_measure(double r) {
  if constexpr (D == 2) {
    return std::numbers::pi * r * r;
  } else {
    return 4.0 / 3.0 * std::numbers::pi * r * r * r;
  }
}

template <int D>
double box_measure(const Box& b) {
  if constexpr (D == 2) {
    return (b.x_max - b.x_min) * (b.y_max - b.y_min);
  } else {
    return (b.x_max - b.x_min) * (b.y_max - b.y_min) * (b.z_max - b.z_min);
  }
}

/// Is particle p's centre outside the deformed domain: the box, or with shear rates the
/// parallelogram (parallelepiped) x_0 + F (box_0 - x_0)?
template <int D>
class OutsideTest {
 public:
  OutsideTest(const DynamicSolverT<D>& s, bool shear) : s_(s), box0_(s.box()), shear_(shear) {}
  bool operator()(std::size_t p) const {
    if (s_.periodic()) return false;  // a periodic cell has no outside
    const ParticlesT<D>& Q = s_.particles();
    const Box& b = s_.box();
    if constexpr (D == 2) {
      const double x = Q.pos[2 * p], y = Q.pos[2 * p + 1];
      if (!shear_) return x < b.x_min || x > b.x_max || y < b.y_min || y > b.y_max;
      const auto& F = s_.box_deformation();
      const double det = F[0] * F[3] - F[1] * F[2], dx = x - box0_.x_min, dy = y - box0_.y_min;
      const double X = (F[3] * dx - F[1] * dy) / det, Y = (-F[2] * dx + F[0] * dy) / det;
      return X < 0.0 || X > box0_.x_max - box0_.x_min || Y < 0.0 || Y > box0_.y_max - box0_.y_min;
    } else {
      const double x = Q.pos[3 * p], y = Q.pos[3 * p + 1], z = Q.pos[3 * p + 2];
      if (!shear_) return x < b.x_min || x > b.x_max || y < b.y_min || y > b.y_max || z < b.z_min || z > b.z_max;
      const auto& Fm = s_.affine_map3();
      Eigen::Matrix3d F;
      F << Fm[0], Fm[1], Fm[2], Fm[3], Fm[4], Fm[5], Fm[6], Fm[7], Fm[8];
      const Eigen::Vector3d X = F.partialPivLu().solve(Eigen::Vector3d(x - box0_.x_min, y - box0_.y_min, z - box0_.z_min));
      const double L0[3] = {box0_.x_max - box0_.x_min, box0_.y_max - box0_.y_min, box0_.z_max - box0_.z_min};
      for (int k = 0; k < 3; ++k)
        if (X(k) < 0.0 || X(k) > L0[k]) return true;
      return false;
    }
  }

 private:
  const DynamicSolverT<D>& s_;
  Box box0_;
  bool shear_;
};

/// |S - Sc| / |Sc| over the diagonal (the walls carry no shear).
template <int D>
double wall_gap(const CompactionSampleT<D>& m) {
  if constexpr (D == 2) {
    const double d11 = m.S[0] - m.Sc[0], d22 = m.S[1] - m.Sc[1];
    const double c = std::hypot(m.Sc[0], m.Sc[1]);
    return c > 0.0 ? std::hypot(d11, d22) / c : 0.0;
  } else {
    const double d = std::sqrt((m.S[0] - m.Sc[0]) * (m.S[0] - m.Sc[0]) + (m.S[1] - m.Sc[1]) * (m.S[1] - m.Sc[1]) +
                               (m.S[2] - m.Sc[2]) * (m.S[2] - m.Sc[2]));
    const double c = std::sqrt(m.Sc[0] * m.Sc[0] + m.Sc[1] * m.Sc[1] + m.Sc[2] * m.Sc[2]);
    return c > 0.0 ? d / c : 0.0;
  }
}

}  // namespace

template <int D>
void CompactionSampleT<D>::add(const CompactionSampleT& o, double w) {
  for (std::size_t k = 0; k < S.size(); ++k) S[k] += w * o.S[k], Sc[k] += w * o.Sc[k], Sk[k] += w * o.Sk[k];
  Z += w * o.Z, contacts += w * o.contacts, sliding += w * o.sliding, mean_fn += w * o.mean_fn;
  dev_mean_ratio += w * o.dev_mean_ratio, dev_ratio_of_means += w * o.dev_ratio_of_means, affine_ut += w * o.affine_ut;
  dev_ut_centres += w * o.dev_ut_centres, dev_ut_rotations += w * o.dev_ut_rotations;
  kinetic += w * o.kinetic, work += w * o.work;
}

template <int D>
CompactionSampleT<D> CompactionMeterT<D>::measure(const DynamicSolverT<D>& s, const Voigt<D>& E) {
  CompactionSampleT<D> m;
  m.Sc = voigt_of<D>(s.contact_stress());
  m.S = s.periodic() ? m.Sc : voigt_of<D>(walls_ ? s.wall_stress() : s.boundary_stress());
  m.Sk = voigt_of<D>(s.kinetic_stress());
  s.contacts(cs_);
  const ParticlesT<D>& P = s.particles();
  auto& formed = formed_;  // (a member: its storage is reused from sample to sample)
  formed.clear();
  const auto by_key = [](const Formed& e, std::uint64_t k) { return e.key < k; };
  int loaded = 0;
  double sum_fn = 0, sum_tc = 0, sum_tr = 0;
  sys::AffineDeviation dev(r_mean_);
  for (const auto& ct : cs_) {
    if (ct.wall >= 0 || !(ct.f_spring > 0.0)) continue;
    Formed f;
    f.key = (std::uint64_t{ct.i} << 32) | ct.j;
    f.E_form = prev_;  // first seen: the strain at the previous sample
    const auto it = std::lower_bound(form_.begin(), form_.end(), f.key, by_key);
    const bool seen = it != form_.end() && it->key == f.key;
    if (seen) f.E_form = it->E_form;
    ++loaded;
    sum_fn += ct.f_spring;
    m.sliding += ct.sliding ? 1.0 : 0.0;
    m.work += 0.5 * ct.f_spring * ct.overlap;
    Eigen::Matrix<double, D, 1> n;
    if constexpr (D == 2) {
      n << ct.nx, ct.ny;
    } else {
      n << ct.nx, ct.ny, ct.nz;
    }
    // Eq 16 with the strain accumulated since the contact formed
    const auto a = sys::affine_approach<D>(n, tensor_of_difference<D>(E, f.E_form), P.r[ct.i] + P.r[ct.j]);
    dev.add(ct.overlap, a);
    if constexpr (D == 2) {  // Figs 7-8: the motion since the last sample, as netsolve's commit adds it
      f.nx = ct.nx, f.ny = ct.ny, f.L = P.r[ct.i] + P.r[ct.j] - ct.overlap, f.d_i = ct.d_i, f.d_j = ct.d_j;
      f.theta_i = P.rot[ct.i], f.theta_j = P.rot[ct.j];
      if (seen) {
        contact::PairGeometry g0, g1;
        g0.n = contact::Vec(it->nx, it->ny), g0.L = it->L, g0.d_i = it->d_i, g0.d_j = it->d_j;
        g1.n = contact::Vec(f.nx, f.ny), g1.L = f.L, g1.d_i = f.d_i, g1.d_j = f.d_j;
        const double centres = contact::slip_increment(g0, g1, 0.0, 0.0);  // L dphi
        f.centre = it->centre + centres;
        f.slip = it->slip + contact::slip_increment(g0, g1, f.theta_i - it->theta_i, f.theta_j - it->theta_j);
      }
      sum_tc += std::fabs(f.centre - a.tangential);
      sum_tr += std::fabs(f.slip - a.tangential);
    }
    formed.push_back(f);
  }
  // (the contacts come in the table's (i, j) order; sorted in case a table ever is not)
  const auto by_first = [](const Formed& x, const Formed& y) { return x.key < y.key; };
  if (!std::is_sorted(formed.begin(), formed.end(), by_first)) std::sort(formed.begin(), formed.end(), by_first);
  form_.swap(formed);
  prev_ = E;
  m.dev_ut_centres = dev.of_mean_affine_normal(sum_tc, loaded);
  m.dev_ut_rotations = dev.of_mean_affine_normal(sum_tr, loaded);
  m.contacts = loaded;
  m.Z = 2.0 * loaded / static_cast<double>(P.size());
  m.mean_fn = loaded > 0 ? sum_fn / loaded : 0.0;
  m.dev_mean_ratio = dev.mean_ratio();
  m.dev_ratio_of_means = dev.ratio_of_means(loaded);
  m.affine_ut = dev.affine_tangential(loaded);
  is_pre_.assign(P.size(), 0);
  for (auto p : s.prescribed()) is_pre_[p] = 1;
  m.kinetic = fluctuating_kinetic<D>(s, is_pre_);
  return m;
}

template <int D>
CompactionRateT<D> compaction_rate(const sys::StrainPathT<D>& path, double inertial_number, double initial_density,
                                   double target_density) {
  const double rho = 1.0, sigma_y = 1.0, d_mean = 2.0;
  CompactionRateT<D> r;
  r.gamma_dot = inertial_number / (d_mean * std::sqrt(rho / sigma_y));
  const double norm = path.norm();
  double tr = 0.0;
  for (int k = 0; k < kVoigt<D>; ++k) {
    const auto kk = static_cast<std::size_t>(k);
    r.rate[kk] = r.gamma_dot * path.E[kk] / norm;
    if (k < D) tr += r.rate[kk];
  }
  r.initial_density = initial_density;
  r.t_end = std::log(initial_density / target_density) / tr;  // D = D0 exp(-tr E' t)
  return r;
}

template <int D>
CompactionRateT<D> compaction_rate_to_strain(const sys::StrainPathT<D>& path, double inertial_number,
                                             double initial_density, double target_strain) {
  CompactionRateT<D> r = compaction_rate(path, inertial_number, initial_density, initial_density);
  r.t_end = target_strain / r.gamma_dot;  // |E'| = gamma' along any direction
  return r;
}

template <int D>
std::vector<CompactionLegT<D>> compaction_legs(const sys::StrainPathT<D>& path, const CompactionOptions& o, double D0) {
  std::vector<CompactionLegT<D>> legs;
  double start = D0;
  const bool precompacts = o.precompacts();
  if (precompacts) {
    const auto hydrostatic = sys::StrainPathT<D>::parse("hydrostatic");
    legs.push_back({compaction_rate(hydrostatic, o.inertial_number, D0, o.precompact_density), o.precompact_increments,
                    o.precompact_density, 0.0, true});
    start = o.precompact_density;
  }
  if (o.target_strain != 0.0)
    legs.push_back({compaction_rate_to_strain(path, o.inertial_number, start, o.target_strain), o.increments, 0.0,
                    o.target_strain, true});
  else
    legs.push_back({compaction_rate(path, o.inertial_number, start, o.target_density), o.increments, o.target_density,
                    0.0, precompacts});
  return legs;
}

template <int D>
void set_strain_rate(DynamicSolverT<D>& s, const Voigt<D>& e, bool simple_shear) {
  if (simple_shear) {
    Eigen::Matrix<double, D, D> L = Eigen::Matrix<double, D, D>::Zero();
    for (int k = 0; k < kVoigt<D>; ++k) {
      const int a = sys::voigt_row<D>(k), b = sys::voigt_col<D>(k);
      L(std::min(a, b), std::max(a, b)) = a == b ? e[static_cast<std::size_t>(k)] : 2.0 * e[static_cast<std::size_t>(k)];
    }
    s.set_velocity_gradient(L);  // refuses a solver without a periodic cell
    return;
  }
  if constexpr (D == 2) {
    s.set_strain_rate(e[0], e[1], e[2]);
  } else {
    s.set_strain_rate3(e[0], e[1], e[2], e[3], e[4], e[5]);
  }
}

void CompactionOptions::check_numbers() const {
  if (!(std::isfinite(inertial_number) && inertial_number > 0.0 && inertial_number <= 1.0))
    throw FieldError("inertial_number", fmt::format("the inertial number must be in (0, 1], got {}", inertial_number));
  if (increments < 1 || increments > 1000000)
    throw FieldError("increments", fmt::format("the number of increments must be in [1, 1e6], got {}", increments));
  if (!(max_steps >= 1.0))
    throw FieldError("max_steps", fmt::format("the step limit must be at least 1, got {}", max_steps));
}

template <int D>
void CompactionOptions::validate(const sys::StrainPathT<D>& path, double initial_density) const {
  check_numbers();
  if (simple_shear && !path.shear())
    throw FieldError("simple_shear", fmt::format("simple shear needs a path with a shear rate, {} has none", path.name));
  double start = initial_density;
  const char* from = "current density";
  if (precompacts()) {
    if (precompact_increments < 1 || precompact_increments > 1000000)
      throw FieldError("precompact_increments", fmt::format("the number of precompaction increments must be in [1, 1e6], "
                                                            "got {}", precompact_increments));
    if (!(std::isfinite(precompact_density) && precompact_density < 1.0))
      throw FieldError("precompact_density", fmt::format("the precompaction density must be below 1, got {}",
                                                         precompact_density));
    if (!(precompact_density > initial_density))
      throw FieldError("precompact_density", fmt::format("impossible precompaction: density {} is not above the start "
                                                         "density {:.4f}", precompact_density, initial_density));
    start = precompact_density;
    from = "precompaction density";
  }
  if (target_strain != 0.0) {
    if (!(target_strain >= kMinTargetStrain && target_strain <= kMaxTargetStrain))
      throw FieldError("to_strain", fmt::format("the target strain |E| must be in [{:g}, {:g}], got {}", kMinTargetStrain,
                                                kMaxTargetStrain, target_strain));
    const double end = start * std::exp(-target_strain * path.trace() / path.norm());
    if (!(end < 1.0))
      throw FieldError("to_strain", fmt::format("impossible target: strain |E| = {} along {} ends at density {:.4g} >= 1",
                                                target_strain, path.name, end));
  } else {
    if (!(std::isfinite(target_density) && target_density > 0.0 && target_density < 1.0))
      throw FieldError("to_density", fmt::format("the target density must be in (0, 1), got {}", target_density));
    if (!(target_density > start))
      throw FieldError("to_density", fmt::format("impossible target: density {} is not above the {} {:.4f}",
                                                 target_density, from, start));
    if (!(path.trace() < 0.0))
      throw FieldError("path", fmt::format("impossible target: strain path {} (trace {}) does not compact, so density {} "
                                           "is never reached", path.name, path.trace(), target_density));
  }
  if (walls && path.shear()) {
    std::string zero;
    for (int k = D; k < kVoigt<D>; ++k) zero += fmt::format("E{} = ", sys::voigt_labels<D>()[static_cast<std::size_t>(k)]);
    throw FieldError("path", fmt::format("the strain path {} has shear components; between walls it takes {}0 only (the "
                                         "walls stay axis-aligned)", path.name, zero));
  }
}

namespace {

/// One run of run_compaction: the legs one after the other, the windows of each, the rows.
template <int D>
class LegRunner {
 public:
  LegRunner(DynamicSolverT<D>& s, const std::vector<CompactionLegT<D>>& legs, const CompactionOptions& o,
            CompactionObserverT<D>& obs, CompactionSummaryT<D>& sum, double r_mean, bool shear, double T)
      : s_(s), legs_(legs), o_(o), obs_(obs), sum_(sum), meter_(o.walls, r_mean), outside_box_(s, shear), T_(T),
        t_start_(s.time()) {}

  /// The strain: the leg's rate times its time so far, after the strain at the end of the last leg.
  Voigt<D> strain() const {
    const auto& rate = legs_[leg_].rate.rate;
    Voigt<D> E{};
    for (std::size_t k = 0; k < E.size(); ++k)
      E[k] = leg_ == 0 ? rate[k] * (s_.time() - t_start_) : E_start_[k] + rate[k] * (s_.time() - t_start_);
    return E;
  }
  CompactionSampleT<D> measure() { return meter_.measure(s_, strain()); }
  bool outside(std::size_t p) const { return outside_box_(p); }

  void report(int k, const CompactionSampleT<D>& m, int samples) {
    const CompactionLegT<D>& leg = legs_[leg_];
    CompactionRowT<D> r;
    r.increment = k;
    r.leg = static_cast<int>(leg_);
    r.time = s_.time();
    r.E = strain();
    r.density = s_.density();
    r.mean = m;
    double pc = 0.0;
    for (int a = 0; a < D; ++a) pc += m.Sc[static_cast<std::size_t>(a)];
    const double Pc = -pc / D;
    // the actual inertial number (rho = sigma_y = 1, d = 2); undefined where P = 0
    r.I = Pc > 0.0 ? leg.rate.gamma_dot * 2.0 * std::sqrt(1.0 / Pc) : std::numeric_limits<double>::quiet_NaN();
    r.kinetic_ratio = m.work > 0.0 ? m.kinetic / m.work : 0.0;
    r.steps = sum_.steps;
    r.samples = samples;
    r.dt = s_.dt();
    double in = 0.0;
    for (std::size_t p = 0; p < s_.particles().size(); ++p) {
      const bool out = outside_box_(p);
      r.outside += out;
      if (!out) in += particle_measure<D>(s_.particles().r[p]);
    }
    r.density_in_box = s_.periodic() ? s_.density() : in / box_measure<D>(s_.box());
    if (o_.walls) {
      r.wall_gap = wall_gap<D>(m);
      if (k > 0) {
        sum_.last_wall_gap = r.wall_gap;
        // the second half of the last leg: of its densification, or of its time (a strain target)
        const double D0 = leg.rate.initial_density;
        const bool second_half = leg.target_density > 0.0
                                     ? s_.density() >= D0 + 0.5 * (leg.target_density - D0)
                                     : s_.time() - t_start_ >= 0.5 * leg.rate.t_end;
        if (leg_ + 1 == legs_.size() && second_half) sum_.max_wall_gap = std::max(sum_.max_wall_gap, r.wall_gap);
      }
    }
    sum_.last = r;
    obs_.row(r);
  }

  /// The next leg: its strain rate from now on (the free velocities follow the affine field).
  void next_leg() {
    E_start_ = strain();
    const auto& from = legs_[leg_].rate.rate;
    ++leg_;
    const auto& to = legs_[leg_].rate.rate;
    Eigen::Matrix<double, D, D> dL;
    for (int k = 0; k < kVoigt<D>; ++k) {
      const auto kk = static_cast<std::size_t>(k);
      dL(sys::voigt_row<D>(k), sys::voigt_col<D>(k)) = dL(sys::voigt_col<D>(k), sys::voigt_row<D>(k)) = to[kk] - from[kk];
    }
    set_strain_rate(s_, to, o_.simple_shear);
    s_.shift_affine_velocities(dL);
    t_start_ = s_.time();
  }

  /// The windows of the current leg, rows numbered from k0 + 1; false if the step limit stopped it.
  bool run_leg(int k0) {
    const CompactionLegT<D>& leg = legs_[leg_];
    const double T = leg.rate.t_end, t0 = t_start_;
    // samples per window: about every 20 steps, at least 10 per window
    const auto every = static_cast<std::int64_t>(std::clamp(T / leg.increments / s_.dt() / 10.0, 1.0, 20.0));
    for (int k = 1; k <= leg.increments; ++k) {
      const double t_end = t0 + T * k / leg.increments;
      const bool exact = leg.exact_end && k == leg.increments;
      CompactionSampleT<D> acc;
      int samples = 0;
      std::int64_t since = 0;
      while (s_.time() < t_end - 1e-12 * T) {
        if (!(static_cast<double>(sum_.steps) < o_.max_steps)) {  // the time step fell below the door's estimate
          const std::string target =
              leg.target_density > 0.0 ? fmt::format("{}", leg.target_density) : fmt::format("|E| = {}", leg.target_strain);
          sum_.status = "incomplete";
          sum_.reason = fmt::format("stopped at the step limit of {:.3g} time steps at t = {:.4g} of {:.4g} (density {:.4f}, "
                                    "target {}; the time step fell from {:.3g} to {:.3g})", o_.max_steps, s_.time(), T_,
                                    s_.density(), target, sum_.dt_first, s_.dt());
          return false;
        }
        if (exact) {
          s_.step_to(t_end);
        } else {
          s_.step();
        }
        ++sum_.steps;
        if (++since % every == 0 || !(s_.time() < t_end - 1e-12 * T)) {
          acc.add(measure(), 1.0);
          ++samples;
          obs_.progress(s_.time());
        }
      }
      if (samples == 0) {
        acc.add(measure(), 1.0);
        samples = 1;
      }
      CompactionSampleT<D> mean;
      mean.add(acc, 1.0 / samples);
      s_.check_health();  // nothing unchecked reaches a file
      report(k0 + k, mean, samples);
      sum_.increments_done = k0 + k;
      if ((k0 + k) % 20 == 0) obs_.checkpoint(k0 + k);
    }
    return true;
  }

 private:
  DynamicSolverT<D>& s_;
  const std::vector<CompactionLegT<D>>& legs_;
  const CompactionOptions& o_;
  CompactionObserverT<D>& obs_;
  CompactionSummaryT<D>& sum_;
  CompactionMeterT<D> meter_;
  OutsideTest<D> outside_box_;
  double T_;                ///< the duration of all legs
  std::size_t leg_ = 0;
  double t_start_;          ///< the time at the start of the leg
  Voigt<D> E_start_{};      ///< the strain at the start of the leg
};

}  // namespace

template <int D>
CompactionSummaryT<D> run_compaction(DynamicSolverT<D>& s, const std::vector<CompactionLegT<D>>& legs,
                                     const CompactionOptions& o, CompactionObserverT<D>& obs) {
  if (legs.empty()) throw FieldError("increments", "a compaction needs at least one leg");
  double T = 0.0;
  bool shear = false;
  for (const auto& leg : legs) {
    T += leg.rate.t_end;
    for (int k = D; k < kVoigt<D>; ++k) shear = shear || leg.rate.rate[static_cast<std::size_t>(k)] != 0.0;
  }
  CompactionSummaryT<D> sum;
  sum.dt_first = s.dt();
  const double steps_est = T / sum.dt_first;
  if (!(steps_est <= o.max_steps))
    throw FieldError("max_steps", fmt::format("the run needs at least {:.3g} time steps of {:.3g} t* (inertial number "
                                              "{:g}), more than the step limit {:.3g}: raise the inertial number or the "
                                              "step limit", steps_est, sum.dt_first, o.inertial_number, o.max_steps));
  double r_mean = 0.0;
  for (double r : s.particles().r) r_mean += r;
  r_mean /= static_cast<double>(s.particles().size());
  LegRunner<D> run(s, legs, o, obs, sum, r_mean, shear, T);
  run.report(0, run.measure(), 1);
  try {
    int k0 = 0;
    for (std::size_t l = 0; l < legs.size(); ++l) {
      if (l > 0) run.next_leg();
      if (!run.run_leg(k0)) return sum;
      k0 += legs[l].increments;
    }
  } catch (const InstabilityError& e) {
    sum.status = "unstable";
    sum.reason = e.what();
    sum.instability = true;
    sum.instability_what = e.what();
    sum.instability_quantity = e.quantity();
    sum.instability_step = e.step();
    sum.instability_time = e.time();
    return sum;
  }
  for (std::size_t p = 0; p < s.particles().size(); ++p) sum.outside += run.outside(p);
  std::vector<std::string> reasons;
  if (sum.outside > 0)
    reasons.push_back(D == 2 ? fmt::format("{} disk centres left the box between the peripheral disks", sum.outside)
                             : fmt::format("{} sphere centres left the box", sum.outside));
  if (sum.last.mean.Z < 2.0)
    reasons.push_back(fmt::format("final Z = {:.3g} < 2: the network is a mechanism", sum.last.mean.Z));
  if (!reasons.empty()) {
    sum.status = "unstable";
    for (const auto& r : reasons) sum.reason += (sum.reason.empty() ? "" : "; ") + r;
  }
  if (o.walls && sum.max_wall_gap > 0.02)
    sum.warnings.push_back(fmt::format("wall stress and contact stress differ by up to {:.3g} (above 2 %) in the second "
                                       "half of the compaction (wall_vs_contact_gap)", sum.max_wall_gap));
  return sum;
}

template <int D>
CompactionSummaryT<D> run_compaction(DynamicSolverT<D>& s, const CompactionRateT<D>& rate, const CompactionOptions& o,
                                     CompactionObserverT<D>& obs) {
  const std::vector<CompactionLegT<D>> legs{{rate, o.increments, o.target_density, 0.0, false}};
  return run_compaction(s, legs, o, obs);
}

#define NETDEM_COMPACTION(D)                                                                                           \
  template struct CompactionSampleT<D>;                                                                                \
  template class CompactionMeterT<D>;                                                                                  \
  template CompactionRateT<D> compaction_rate<D>(const sys::StrainPathT<D>&, double, double, double);                  \
  template CompactionRateT<D> compaction_rate_to_strain<D>(const sys::StrainPathT<D>&, double, double, double);        \
  template std::vector<CompactionLegT<D>> compaction_legs<D>(const sys::StrainPathT<D>&, const CompactionOptions&,     \
                                                             double);                                                  \
  template void set_strain_rate<D>(DynamicSolverT<D>&, const Voigt<D>&, bool);                                               \
  template void CompactionOptions::validate<D>(const sys::StrainPathT<D>&, double) const;                              \
  template CompactionSummaryT<D> run_compaction<D>(DynamicSolverT<D>&, const CompactionRateT<D>&,                      \
                                                   const CompactionOptions&, CompactionObserverT<D>&);                \
  template CompactionSummaryT<D> run_compaction<D>(DynamicSolverT<D>&, const std::vector<CompactionLegT<D>>&,          \
                                                   const CompactionOptions&, CompactionObserverT<D>&);
NETDEM_COMPACTION(2)
NETDEM_COMPACTION(3)
#undef NETDEM_COMPACTION

}  // namespace netdem::dem
