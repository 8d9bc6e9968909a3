// The staggered quasi-static sintering scheme of Ivannikov et al. (staggered.hpp; docs/staggered.md):
// the options, the set-up, one step (Fig 6), the accessors, the measures and save/load. The other
// files of the scheme and what each owns: staggered_impl.hpp.
#include "netdem/quasistatic/staggered.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <stdexcept>

#include <Eigen/Eigenvalues>
#include <fmt/format.h>

#include "netdem/field_error.hpp"
#include "netdem/system/archive.hpp"
#include "staggered_impl.hpp"
#include "staggered_state.hpp"

namespace netdem::qs::staggered {

// ================================================================================================

// One set of ranges, here only: the app (netsolve sinter) checks none of these again. A bad value
// throws netdem::FieldError naming the quantity, with the field's name for the caller.
void StaggeredOptions::validate() const {
  auto need = [](bool ok, const char* field, const std::string& what) {
    if (!ok) throw FieldError(field, what);
  };
  auto pos = [](double v) { return std::isfinite(v) && v > 0.0; };
  need(strategy == 1 || strategy == 2, "strategy", fmt::format("the time-marching strategy must be 1 or 2, got {}", strategy));
  need(pos(dt_min), "dt_min", fmt::format("the smallest (sub-)step must be a positive time in seconds, got {}", dt_min));
  need(pos(dt_initial) && dt_initial >= dt_min, "dt_initial",
       fmt::format("the first global step must be a time in seconds of at least the smallest step {}, got {}", dt_min, dt_initial));
  need(pos(dt_max) && dt_max >= dt_min, "dt_max",
       fmt::format("the largest global step must be a time in seconds of at least the smallest step {}, got {}", dt_min, dt_max));
  need(std::isfinite(alpha) && alpha > 1.0 && alpha <= 100.0, "alpha",
       fmt::format("the step factor alpha of Eqs 45 and 47 must be in (1, 100], got {}", alpha));
  need(std::isfinite(eps_lim) && eps_lim > 0.0 && eps_lim < 1.0, "eps_lim",
       fmt::format("the relative error limit per (sub-)step must be in (0, 1), got {}", eps_lim));
  need(std::isfinite(grow_below) && std::isfinite(shrink_above) && grow_below >= 0.0 && grow_below <= shrink_above &&
           shrink_above <= 1.0,
       "grow_below",
       fmt::format("the sub-step fractions must satisfy 0 <= grow ({}) <= shrink ({}) <= 1", grow_below, shrink_above));
  // x0 is the neck of touching spheres (h = R) that starts a contact (notes section 4.6), the same
  // initial state as the pair model's make_contact(), which takes x0 / R in (0, 0.5): a seed of the
  // initial stage, not a grown neck (the model's useful range ends near x / R_min = 0.6). Below
  // kNeckVanished the model calls the neck vanished, and every contact would be refused as made.
  need(std::isfinite(x0_over_R) && x0_over_R > cs::kNeckVanished && x0_over_R < 0.5, "x0_over_R",
       fmt::format("the initial neck x0 / R_min must be in ({:g}, 0.5), got {}", cs::kNeckVanished, x0_over_R));
  need(x_max_over_R == 0.0 || (std::isfinite(x_max_over_R) && x_max_over_R > x0_over_R && x_max_over_R <= 1.0),
       "x_max_over_R",
       fmt::format("the freeze limit x_max / R_min must be 0 (the dihedral limit) or in (x0 / R_min = {}, 1], got {}",
                   x0_over_R, x_max_over_R));
  need(std::isfinite(boundary_factor) && boundary_factor >= 0.0 && boundary_factor < 10.0, "boundary_factor",
       fmt::format("the boundary-plane distance factor must be in [0, 10), got {}", boundary_factor));
  for (double v : plane_origin)
    need(std::isnan(v) || std::isfinite(v), "plane_origin", "the boundary planes must be at finite coordinates or NaN (the bounding box)");
  need(E == 0.0 || pos(E), "E", fmt::format("the bonds' Young's modulus must be positive [Pa] (or 0: the material's), got {}", E));
  // the material's own range (SinterMaterial::validate): a sintered metal or ceramic is not auxetic
  need(nu == -1.0 || (std::isfinite(nu) && nu >= 0.0 && nu < 0.5), "nu",
       fmt::format("the bonds' Poisson's ratio must be in [0, 0.5) (or -1: the material's), got {}", nu));
  need(std::isfinite(gmres_tolerance) && gmres_tolerance > 0.0 && gmres_tolerance < 1e-3, "gmres_tolerance",
       fmt::format("the GMRES tolerance must be in (0, 1e-3), got {}", gmres_tolerance));
  need(refactor_iterations >= 1, "refactor_iterations",
       fmt::format("the GMRES iterations before a refactorisation must be >= 1, got {}", refactor_iterations));
}

void StaggeredOptions::validate(const cs::SinterMaterial& m) const {
  validate();
  m.validate();
  if (!(E > 0.0 || m.youngs_modulus > 0.0))
    throw FieldError("E", fmt::format("the bonds need a Young's modulus: the material '{}' has none (give it E, or give the "
                                      "bonds' own E)", m.name));
  if (nu == -1.0 && m.poisson_ratio == -1.0)
    throw FieldError("nu", fmt::format("the bonds need a Poisson's ratio: the material '{}' has none (give it nu, or give "
                                       "the bonds' own nu)", m.name));
  const double x_max = freeze_limit(m, *this);
  if (!(x_max > x0_over_R))
    throw FieldError("x0_over_R", fmt::format("the initial neck x0 / R_min = {} is not below the freeze limit {} (the "
                                              "dihedral limit of the material '{}')", x0_over_R, x_max, m.name));
}

std::pair<double, double> corrected_split(double y4_prev, double y7_prev, double y4_free, double y7_free, double d_new,
                                          double R_A, double R_B) {
  const double dy4 = y4_prev - y4_free, dy7 = y7_prev - y7_free;  // Eq 43
  const double s = dy4 + dy7;
  // Eq 41 with the sign mended: the centre distance changed by D = d_new - (y4_prev + y7_prev),
  // negative when the particles approach; D is split as the free model split its own change.
  const double w4 = std::fabs(s) < 1e-14 * std::min(R_A, R_B) ? R_A / (R_A + R_B) : dy4 / s;
  const double D = d_new - (y4_prev + y7_prev);
  const double y4 = y4_prev + w4 * D;
  return {y4, d_new - y4};
}

double freeze_limit(const cs::SinterMaterial& m, const StaggeredOptions& o) {
  if (o.x_max_over_R > 0.0) return o.x_max_over_R;
  const double cpsi = m.gamma_gb / (2.0 * m.gamma_s);  // cos(psi/2), the dihedral angle psi
  return std::sqrt(std::max(0.0, 1.0 - cpsi * cpsi));
}

// ================================================================================================
// Staggered::Impl: set-up and one step (Fig 6)

void Staggered::Impl::setup_material() {
  opt.validate(mat);
  bmat.E = opt.E > 0.0 ? opt.E : mat.youngs_modulus;
  bmat.nu = opt.nu != -1.0 ? opt.nu : mat.poisson_ratio;
  x_max = freeze_limit(mat, opt);
  cache.m = &mat;
  cscale = std::ldexp(1.0, -std::ilogb(bmat.E));
}

void Staggered::Impl::setup_particles() {
  if (p.r.empty()) bad("staggered: no particles");
  if (!p.consistent())
    bad(fmt::format("staggered: the particle set holds {} radii, {} centre coordinates and {} rotations (3 of each per radius)",
                    p.r.size(), p.pos.size(), p.rot.size()));
  double rsum = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const double r = p.r[i];
    if (!p.position(i).allFinite()) bad(fmt::format("staggered: particle {} has a non-finite centre", i));
    if (!(std::isfinite(r) && r > 0.0)) bad(fmt::format("staggered: particle {} has radius {} (must be positive)", i, r));
    rsum += r;
  }
  ell = std::ldexp(1.0, std::ilogb(rsum / static_cast<double>(p.size())));
  const int n = N();
  adj.assign(n, {});
  fixed_user.assign(6 * n, 0);
  fixed_plane.assign(6 * n, 0);
  if (opt.boundary_planes) {
    for (int k = 0; k < 3; ++k) {
      double lo = opt.plane_origin[k];
      if (std::isnan(lo)) {
        lo = std::numeric_limits<double>::infinity();
        for (int i = 0; i < n; ++i) lo = std::min(lo, p.coord(i, k) - p.r[i]);
      }
      for (int i = 0; i < n; ++i)
        if (p.coord(i, k) - lo <= opt.boundary_factor * p.r[i]) fixed_plane[6 * i + k] = 1;
    }
  }
}

StepRecord Staggered::Impl::step(double t_end) {
  if (!(t_end > t)) throw std::runtime_error(fmt::format("staggered: step to t_end = {} is not after t = {}", t_end, t));
  StepRecord rec;
  auto t0 = Clock::now();
  if (opt.new_contacts) rec.new_contacts = detect();  // (the initial contacts were made at construction)
  timers.detect += seconds_since(t0);
  t0 = Clock::now();
  if (pattern_dirty) build_pattern();
  timers.assemble += seconds_since(t0);

  const double seg_end = prof.segment_at(t).t1;
  t0 = Clock::now();
  const double h = integrate_contacts(rec, t_end, seg_end);
  timers.integrate += seconds_since(t0);
  const VecX uhat = solve_network(rec);
  t0 = Clock::now();
  const double t_new = (h == std::min(t_end, seg_end) - t) ? std::min(t_end, seg_end) : t + h;
  move_and_correct(rec, uhat, t_new);
  timers.correct += seconds_since(t0);
  t = t_new;
  ++nsteps;
  rec.t = t;
  rec.T = prof(t);
  rec.dt = h;
  return rec;
}

// ================================================================================================

Staggered::Staggered() : impl_(std::make_unique<Impl>()) {}
Staggered::~Staggered() = default;
Staggered::Staggered(Staggered&&) noexcept = default;
Staggered& Staggered::operator=(Staggered&&) noexcept = default;

Staggered::Staggered(Particles particles, cs::SinterMaterial material, cs::TemperatureProfile temperature,
                     StaggeredOptions options)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.opt = options;
  m.mat = std::move(material);
  m.prof = std::move(temperature);
  m.setup_material();
  m.p = std::move(particles);
  m.setup_particles();
  m.p0 = m.p;
  m.dt = m.opt.dt_initial;
  m.init_solver();
  m.detect();  // the initial contacts
}

void Staggered::fix(int particle, int d) {
  if (particle < 0 || particle >= impl_->N() || d < 0 || d > 5)
    bad(fmt::format("staggered: fix({}, {}): no such particle or DOF", particle, d));
  impl_->fixed_user[6 * particle + d] = 1;
  impl_->pattern_dirty = true;
}

StepRecord Staggered::step(double t_end) { return impl_->step(t_end); }
double Staggered::time() const { return impl_->t; }
double Staggered::dt() const { return impl_->dt; }
long Staggered::steps() const { return impl_->nsteps; }
const Particles& Staggered::particles() const { return impl_->p; }
const Particles& Staggered::initial_particles() const { return impl_->p0; }
const std::vector<Contact>& Staggered::contacts() const { return impl_->c; }
const StaggeredOptions& Staggered::options() const { return impl_->opt; }
const cs::SinterMaterial& Staggered::material() const { return impl_->mat; }
const cs::TemperatureProfile& Staggered::temperature() const { return impl_->prof; }
const Timers& Staggered::timers() const { return impl_->timers; }
double Staggered::x_max_over_R() const { return impl_->x_max; }
int Staggered::fixed_dofs() const {
  if (impl_->pattern_dirty) impl_->build_pattern();
  return static_cast<int>(std::count(impl_->fixed.begin(), impl_->fixed.end(), std::uint8_t{1}));
}

std::array<int, 3> Staggered::plane_particles() const {
  std::array<int, 3> n{0, 0, 0};
  for (std::size_t i = 0; i < impl_->p.size(); ++i)
    for (std::size_t k = 0; k < 3; ++k) n[k] += impl_->fixed_plane[6 * i + k];
  return n;
}

Eigen::Matrix3d Staggered::homogeneous_strain() const {
  const auto& p = impl_->p;
  const auto& p0 = impl_->p0;
  const double n = static_cast<double>(p.size());
  Eigen::Vector3d xm = Eigen::Vector3d::Zero(), Xm = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < p.size(); ++i) {
    xm += p.position(i);
    Xm += p0.position(i);
  }
  xm /= n;
  Xm /= n;
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero(), B = Eigen::Matrix3d::Zero();
  for (std::size_t i = 0; i < p.size(); ++i) {
    const Eigen::Vector3d dX = p0.position(i) - Xm, u = (p.position(i) - xm) - dX;  // the displacement about the mean
    A += u * dX.transpose();
    B += dX * dX.transpose();
  }
  // x - xm = (I + F)(X - Xm): F = A B^-1 (least squares); B is singular for a planar or linear set
  Eigen::Matrix3d F = Eigen::Matrix3d::Zero();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(B);
  const double top = es.eigenvalues().maxCoeff();
  Eigen::Matrix3d Binv = Eigen::Matrix3d::Zero();
  for (int k = 0; k < 3; ++k) {
    const double l = es.eigenvalues()[k];
    if (l > 1e-12 * top) Binv += es.eigenvectors().col(k) * es.eigenvectors().col(k).transpose() / l;
  }
  F = A * Binv;
  return F;
}

double Staggered::density() const {
  const auto& p = impl_->p;
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  double V = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    lo = lo.cwiseMin(p.position(i) - Eigen::Vector3d::Constant(p.r[i]));
    hi = hi.cwiseMax(p.position(i) + Eigen::Vector3d::Constant(p.r[i]));
    const double r0 = impl_->p0.r[i];
    V += 4.0 / 3.0 * std::numbers::pi * r0 * r0 * r0;
  }
  return V / (hi - lo).prod();
}

// ================================================================================================
// save / load: the state as plain data (StaggeredState), its file in staggered_state.cpp

std::string Staggered::save() const {
  const Impl& m = *impl_;
  StaggeredState s;
  s.opt = m.opt;
  s.mat = m.mat;
  s.profile_t = m.prof.times();
  s.profile_T = m.prof.temperatures();
  if (s.profile_t.empty()) s.profile_constant = m.prof(0.0);
  s.t = m.t;
  s.dt = m.dt;
  s.nsteps = m.nsteps;
  s.need_factor = m.need_factor;
  s.last_iterations = m.last_iterations;
  s.rhs_evals = m.rhs_evals;
  s.timers = m.timers;
  s.p = m.p;
  s.p0 = m.p0;
  s.fixed_user = m.fixed_user;
  s.fixed_plane = m.fixed_plane;
  s.c = m.c;
  s.ref_fixed = m.ref_fixed;
  s.ref = m.ref;
  s.origin_record = m.origin_record;
  return format_staggered_state(s);
}

Staggered Staggered::load(const std::string& text, const std::string& origin) {
  StaggeredState st = parse_staggered_state(text, origin);
  auto fail = [&](const std::string& what) { bad(origin + ": " + what); };
  Staggered s;
  Impl& m = *s.impl_;
  m.opt = st.opt;
  m.mat = st.mat;
  try {
    m.prof = st.profile_t.empty() ? cs::TemperatureProfile::constant(st.profile_constant)
                                  : cs::TemperatureProfile(st.profile_t, st.profile_T);
    m.setup_material();
  } catch (const std::invalid_argument& e) {
    fail(e.what());
  }
  m.t = st.t;
  m.dt = st.dt;
  m.nsteps = st.nsteps;
  m.rhs_evals = st.rhs_evals;
  m.timers = st.timers;
  m.p = std::move(st.p);
  m.p0 = std::move(st.p0);
  try {
    m.setup_particles();
  } catch (const std::invalid_argument& e) {
    fail(e.what());
  }
  m.fixed_user = std::move(st.fixed_user);
  m.fixed_plane = std::move(st.fixed_plane);
  m.c.reserve(st.c.size());
  for (const Contact& k : st.c) {
    if (!finite_state(k.pair.q) || !finite_state(k.pair.q0)) fail(fmt::format("contact {}: non-finite state", m.c.size()));
    m.adj[k.a].push_back(static_cast<int>(m.c.size()));
    m.adj[k.b].push_back(static_cast<int>(m.c.size()));
    m.c.push_back(k);
  }
  m.ref_fixed = std::move(st.ref_fixed);
  m.ref = std::move(st.ref);
  m.origin_record = std::move(st.origin_record);
  m.init_solver();
  m.pattern_dirty = true;
  // the factor of the saved run, rebuilt from its contacts, constraints and elements: the same
  // pattern, the same values, the same bits
  const std::size_t nref = m.ref.size(), nc = m.c.size();
  if (!st.need_factor && nref > 0 && !m.ref_fixed.empty()) {
    m.build_pattern_for(nref, m.ref_fixed);
    if (m.nfree > 0) {
      m.assemble(m.ref);
      const LinearStatus fs = m.solver->factorise(m.K, false);
      if (!fs.ok) fail("the saved factor geometry is singular: " + fs.message);
    }
  }
  if (nc > 0) {
    m.build_pattern();
    if (st.need_factor) m.need_factor = true;
  }
  m.last_iterations = st.last_iterations;
  return s;
}

void Staggered::set_origin_record(const std::string& json_object) {
  const auto j = sys::Json::parse(json_object, nullptr, false);
  if (j.is_discarded() || !(j.is_object() || j.is_null()))
    bad("staggered: the record of origin must be a JSON object or null");
  impl_->origin_record = j.dump();
}

const std::string& Staggered::origin_record() const { return impl_->origin_record; }

}  // namespace netdem::qs::staggered
