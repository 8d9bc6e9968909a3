// The staggered quasi-static sintering scheme of Ivannikov et al. (staggered.hpp; docs/staggered.md).
#include "netdem/quasistatic/staggered.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <numbers>
#include <numeric>
#include <sstream>
#include <stdexcept>

#include <Eigen/Eigenvalues>
#include <fmt/format.h>

#include "netdem/packing/cell_grid.hpp"
#include "netdem/quasistatic/linear_solver.hpp"
#include "netdem/system/archive.hpp"
#include "staggered_state.hpp"

namespace netdem::qs::staggered {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

using cs::kHA;
using cs::kHB;
using cs::kRA;
using cs::kRB;
using cs::kX;
using cs::State;

// Spheres touch when their centre distance is below (1 + 1e-12) (r_a + r_b): a lattice of touching
// spheres is in contact whatever the rounding of its coordinates.
constexpr double kTouch = 1.0 + 1e-12;

[[noreturn]] void bad(const std::string& what) { throw std::invalid_argument(what); }

// Arrhenius values for the few temperatures of one step (the stage times of RK4).
struct DiffCache {
  const cs::SinterMaterial* m = nullptr;
  std::array<cs::Diffusivities, 4> d{};
  int next = 0;
  const cs::Diffusivities& at(double T) {
    for (const auto& e : d)
      if (e.T == T) return e;
    cs::Diffusivities& e = d[next];
    next = (next + 1) % 4;
    e = cs::diffusivities(*m, T);
    return e;
  }
};

struct RhsCtx {
  const cs::SinterMaterial* m;
  DiffCache* cache;
  cs::TemperatureProfile::Segment seg;
  long* evals;
  bool operator()(double t, const State& q, State& dq) const {
    ++*evals;
    return cs::pair_rhs(q, cache->at(seg(t)), 0.0, *m, cs::PathSwitches{}, dq);
  }
};

bool finite_state(const State& q) {
  for (double v : q)
    if (!std::isfinite(v)) return false;
  return true;
}

// One classical RK4 step (the paper's integrator) from q at t over h; k1 = f(t, q) given.
bool rk4(const RhsCtx& f, double t, double h, const State& q, const State& k1, State& out) {
  State y{}, k2{}, k3{}, k4{};
  for (int i = 0; i < 5; ++i) y[i] = q[i] + 0.5 * h * k1[i];
  if (!f(t + 0.5 * h, y, k2)) return false;
  for (int i = 0; i < 5; ++i) y[i] = q[i] + 0.5 * h * k2[i];
  if (!f(t + 0.5 * h, y, k3)) return false;
  for (int i = 0; i < 5; ++i) y[i] = q[i] + h * k3[i];
  if (!f(t + h, y, k4)) return false;
  for (int i = 0; i < 5; ++i) out[i] = q[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
  return finite_state(out);
}

// A trial step with its step-doubling estimate: one RK4 step of h against two of h/2; the error of
// the two half steps is their difference / (2^4 - 1), relative to x and to y4 + y7. ok = false when
// a stage left the model's domain.
struct Trial {
  bool ok = false;
  double error = std::numeric_limits<double>::infinity();  // relative, not yet divided by eps_lim
  State q{};
};
Trial trial_step(const RhsCtx& f, double t, double h, const State& q) {
  Trial r;
  State k1{};
  if (!f(t, q, k1)) return r;
  State full{}, half{}, two{};
  if (!rk4(f, t, h, q, k1, full)) return r;
  if (!rk4(f, t, 0.5 * h, q, k1, half)) return r;
  State k1h{};
  if (!f(t + 0.5 * h, half, k1h)) return r;
  if (!rk4(f, t + 0.5 * h, 0.5 * h, half, k1h, two)) return r;
  const double sf = full[kHA] + full[kHB], s2 = two[kHA] + two[kHB];
  const double ex = std::fabs(two[kX] - full[kX]) / std::fabs(two[kX]);
  const double es = std::fabs(s2 - sf) / std::fabs(s2);
  r.error = std::max(ex, es) / 15.0;
  r.ok = std::isfinite(r.error);
  r.q = two;
  return r;
}

// Strategy 2: the sub-steps of one contact over [t0, t1] (RK4 with step doubling; a failed
// sub-step is divided by alpha, a sub-step well within eps_lim (0.1) lets the next one grow by
// alpha). ok = false when a sub-step would fall below dt_min: domain = true if it failed because
// a stage left the model's domain (the caller freezes the contact), else because of accuracy.
struct ContactResult {
  State q{};
  long substeps = 0;
  double max_error = 0.0;
  bool ok = true, domain = false;
};
ContactResult advance_substeps(const State& q0, double R_min0, const RhsCtx& f, double t0, double t1,
                               const StaggeredOptions& opt, double x_max) {
  ContactResult r;
  r.q = q0;
  double tl = t0, h = t1 - t0;
  bool cut = false;
  while (tl < t1) {
    const double remaining = t1 - tl;
    bool last = false;
    if (h >= remaining * (1.0 - 1e-12)) {
      h = remaining;
      last = true;
    }
    const Trial tr = trial_step(f, tl, h, r.q);
    if (!tr.ok || tr.error > opt.eps_lim) {
      h /= opt.alpha;
      cut = true;
      if (h < opt.dt_min) {
        r.ok = false;
        r.domain = !tr.ok;
        return r;
      }
      continue;
    }
    r.q = tr.q;
    tl = last ? t1 : tl + h;
    ++r.substeps;
    r.max_error = std::max(r.max_error, tr.error / opt.eps_lim);
    if (cut && tr.error < 0.1 * opt.eps_lim) h *= opt.alpha;
    // the neck reached the freeze limit: the contact stops here (frozen after this step)
    if (cs::check_state(r.q, R_min0, x_max) == cs::PairStatus::NeckLimit) break;
  }
  return r;
}

}  // namespace

// ================================================================================================

void StaggeredOptions::validate() const {
  auto need = [](bool ok, const std::string& what) {
    if (!ok) bad("staggered: " + what);
  };
  auto pos = [](double v) { return std::isfinite(v) && v > 0.0; };
  need(strategy == 1 || strategy == 2, fmt::format("strategy must be 1 or 2, got {}", strategy));
  need(pos(dt_initial), fmt::format("dt_initial must be positive [s], got {}", dt_initial));
  need(pos(dt_max), fmt::format("dt_max must be positive [s], got {}", dt_max));
  need(pos(dt_min) && dt_min <= dt_initial && dt_min <= dt_max,
       fmt::format("dt_min must be positive and at most dt_initial and dt_max [s], got {}", dt_min));
  need(std::isfinite(alpha) && alpha > 1.0 && alpha <= 100.0, fmt::format("alpha must be in (1, 100], got {}", alpha));
  need(std::isfinite(eps_lim) && eps_lim > 0.0 && eps_lim < 1.0, fmt::format("eps_lim must be in (0, 1), got {}", eps_lim));
  need(std::isfinite(grow_below) && std::isfinite(shrink_above) && grow_below >= 0.0 && grow_below <= shrink_above &&
           shrink_above <= 1.0,
       fmt::format("the sub-step fractions must satisfy 0 <= grow ({}) <= shrink ({}) <= 1", grow_below, shrink_above));
  need(std::isfinite(x0_over_R) && x0_over_R > 0.0 && x0_over_R < 0.5,
       fmt::format("x0/R must be in (0, 0.5), got {}", x0_over_R));
  need(x_max_over_R == 0.0 || (std::isfinite(x_max_over_R) && x_max_over_R > x0_over_R && x_max_over_R <= 1.0),
       fmt::format("x_max/R must be 0 (the dihedral limit) or in (x0/R, 1], got {}", x_max_over_R));
  need(std::isfinite(boundary_factor) && boundary_factor >= 0.0 && boundary_factor < 10.0,
       fmt::format("boundary_factor must be in [0, 10), got {}", boundary_factor));
  for (double v : plane_origin)
    need(std::isnan(v) || std::isfinite(v), "plane_origin must be finite or NaN (the bounding box)");
  need(E == 0.0 || pos(E), fmt::format("E must be positive [Pa] (or 0: the material's), got {}", E));
  need(nu < 0.0 ? nu == -1.0 || (std::isfinite(nu) && nu > -1.0) : std::isfinite(nu) && nu < 0.5,
       fmt::format("nu must be in (-1, 0.5) (or -1: the material's), got {}", nu));
  need(std::isfinite(gmres_tolerance) && gmres_tolerance > 0.0 && gmres_tolerance < 1e-3,
       fmt::format("gmres_tolerance must be in (0, 1e-3), got {}", gmres_tolerance));
  need(refactor_iterations >= 1, fmt::format("refactor_iterations must be >= 1, got {}", refactor_iterations));
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

bool advance_free(cs::PairContact& c, const cs::SinterMaterial& m, const cs::TemperatureProfile& T, double t1,
                  const StaggeredOptions& o, long* substeps) {
  const double x_max = freeze_limit(m, o);
  DiffCache cache;
  cache.m = &m;
  while (c.t < t1) {
    long evals = 0;
    const auto seg = T.segment_at(c.t);
    const double te = std::min(t1, seg.t1);
    RhsCtx f{&m, &cache, seg, &evals};
    const ContactResult r = advance_substeps(c.q, c.R_min0(), f, c.t, te, o, x_max);
    if (!r.ok) return false;
    c.q = r.q;
    c.t = te;
    c.rhs_evals += evals;
    if (substeps != nullptr) *substeps += r.substeps;
    if (cs::check_state(c.q, c.R_min0(), x_max) != cs::PairStatus::Ok) return false;
  }
  return true;
}

// ================================================================================================

struct Staggered::Impl {
  StaggeredOptions opt;
  cs::SinterMaterial mat;
  cs::TemperatureProfile prof = cs::TemperatureProfile::constant(1000.0);
  contact::BondMaterial bmat;
  double x_max = 0.0;
  std::vector<Particle> p, p0;
  std::vector<Contact> c;
  std::vector<std::vector<int>> adj;  // particle -> contact indices
  packing::CellGrid3 grid;                        // detect(): the cell grid,
  std::array<std::vector<double>, 3> grid_xyz;    // the centres it sorts
  std::vector<std::pair<int, int>> found;         // and the new pairs (all reused)
  std::vector<std::uint8_t> fixed_user, fixed_plane, fixed;  // 6N flags
  double t = 0.0, dt = 0.0;
  long nsteps = 0;
  Timers timers;
  long rhs_evals = 0;
  DiffCache cache;
  // scaling of the linear system (powers of two: exact): K^ = c S K S, S = 1 (u), 1/ell (theta)
  double cscale = 1.0, ell = 1.0;
  // the network system
  bool pattern_dirty = true, need_factor = true;
  int last_iterations = 0;  // GMRES iterations of the solves since the last factorisation
  std::vector<int> dof;    // 6N -> free index or -1
  int nfree = 0;
  SpMat K;
  std::vector<int> slots;  // 144 per contact: index into K's values, -1 for a fixed DOF
  std::vector<contact::BondElement> ref;  // the elements of the last factorisation (its contacts)
  std::vector<std::uint8_t> ref_fixed;    // and its constraints
  std::vector<std::vector<int>> floating;  // clusters held at their first particle
  // work arrays of step()
  std::vector<State> qnew;
  std::vector<int> active;
  std::vector<int> domain_fail;  // strategy 1: the contacts whose trial step left the domain
  std::vector<std::uint8_t> freeze;
  std::vector<contact::BondElement> el;
  std::vector<Eigen::Vector3d> u;
  std::unique_ptr<LinearSolver> solver;
  std::string origin_record = "null";  // JSON: the run that made the sample (set_origin_record)

  void init_solver() {
    LinearSolverOptions lo;
    lo.gmres_tolerance = opt.gmres_tolerance;
    lo.gmres_max_iterations = 200;
    solver = std::make_unique<LinearSolver>(lo);
  }

  void setup_material() {
    mat.validate();
    bmat.E = opt.E > 0.0 ? opt.E : mat.youngs_modulus;
    bmat.nu = opt.nu != -1.0 ? opt.nu : mat.poisson_ratio;
    if (!(bmat.E > 0.0))
      bad("staggered: the bond needs Young's modulus: the material '" + mat.name + "' has no E (give the material's E or the option E)");
    if (bmat.nu == -1.0)
      bad("staggered: the bond needs Poisson's ratio: the material '" + mat.name + "' has no nu (give the material's nu or the option nu)");
    x_max = freeze_limit(mat, opt);
    if (!(x_max > opt.x0_over_R)) bad(fmt::format("staggered: the freeze limit x_max/R = {} is below x0/R", x_max));
    cache.m = &mat;
    cscale = std::ldexp(1.0, -std::ilogb(bmat.E));
  }

  int N() const { return static_cast<int>(p.size()); }

  void setup_particles() {
    if (p.empty()) bad("staggered: no particles");
    double rsum = 0.0;
    for (std::size_t i = 0; i < p.size(); ++i) {
      const auto& q = p[i];
      if (!q.x.allFinite()) bad(fmt::format("staggered: particle {} has a non-finite centre", i));
      if (!(std::isfinite(q.r) && q.r > 0.0)) bad(fmt::format("staggered: particle {} has radius {} (must be positive)", i, q.r));
      rsum += q.r;
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
          for (const auto& q : p) lo = std::min(lo, q.x[k] - q.r);
        }
        for (int i = 0; i < n; ++i)
          if (p[i].x[k] - lo <= opt.boundary_factor * p[i].r) fixed_plane[6 * i + k] = 1;
      }
    }
  }

  // ---------------------------------------------------------------------------------------------
  // contacts

  void add_contact(int a, int b, double d) {
    const double ra = p[a].r, rb = p[b].r;
    const double hA = (d * d + ra * ra - rb * rb) / (2.0 * d);  // the radical plane of the two spheres
    const double hB = d - hA;
    if (!(hA > 0.0 && hB > 0.0))
      throw std::runtime_error(fmt::format(
          "staggered: particles {} and {} overlap too far (centre distance {:.4g} m, radii {:.4g}, {:.4g})", a, b, d, ra, rb));
    const double Rmin = std::min(ra, rb);
    const double a2 = std::max(0.0, ra * ra - hA * hA);  // lens radius^2 (the same from either side)
    Contact k;
    k.a = a;
    k.b = b;
    // x0 = 0.01 R_min (the paper), raised above the lens radius of an overlapping pair so that the
    // cap-cone geometry exists (x^2 + h^2 > R^2 needs x > the lens radius)
    const double x0 = std::max(opt.x0_over_R * Rmin, 1.02 * std::sqrt(a2));
    k.pair.q = k.pair.q0 = State{x0, ra, hA, rb, hB};
    k.pair.t = t;
    k.t_created = t;
    k.L_created = d;
    k.x_start = x0;
    const cs::PairStatus s = cs::check_state(k.pair.q, Rmin, x_max);
    if (s == cs::PairStatus::NeckLimit) {
      k.frozen = true;
      k.pair.status = s;
    } else if (s != cs::PairStatus::Ok) {
      throw std::runtime_error(fmt::format("staggered: the new contact {}-{} has no valid geometry ({})", a, b,
                                           cs::to_string(s)));
    }
    adj[a].push_back(static_cast<int>(c.size()));
    adj[b].push_back(static_cast<int>(c.size()));
    c.push_back(k);
    pattern_dirty = true;
  }

  bool bonded(int a, int b) const {
    const auto& la = adj[a].size() <= adj[b].size() ? adj[a] : adj[b];
    for (int k : la)
      if ((c[k].a == a && c[k].b == b) || (c[k].a == b && c[k].b == a)) return true;
    return false;
  }

  // New contacts: spheres closer than r_a + r_b without a bond, found through the toolkit's cell
  // grid (cells of at least 2 r_max); pairs in index order, so the contact order does not depend
  // on the grid. The grid, the coordinate arrays and the list are reused (no allocation per step
  // once their sizes settle).
  int detect() {
    const int n = N();
    double rmax = 0.0;
    for (int k = 0; k < 3; ++k) grid_xyz[k].resize(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) {
      rmax = std::max(rmax, p[i].r);
      for (int k = 0; k < 3; ++k) grid_xyz[k][static_cast<std::size_t>(i)] = p[i].x[k];
    }
    grid.rebuild(grid_xyz[0], grid_xyz[1], grid_xyz[2], 2.0 * kTouch * rmax);
    found.clear();
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector3d& xi = p[i].x;
      grid.for_each_near(xi[0], xi[1], xi[2], kTouch * (p[i].r + rmax), [&](std::uint32_t jj) {
        const int j = static_cast<int>(jj);
        if (j <= i) return;
        const double rr = kTouch * (p[i].r + p[j].r);
        if ((p[j].x - xi).squaredNorm() < rr * rr && !bonded(i, j)) found.emplace_back(i, j);
      });
    }
    std::sort(found.begin(), found.end());
    for (const auto& [i, j] : found) add_contact(i, j, (p[j].x - p[i].x).norm());
    return static_cast<int>(found.size());
  }

  // ---------------------------------------------------------------------------------------------
  // constraints and the pattern of the network system

  void update_constraints() {
    const int n = N();
    fixed.assign(6 * n, 0);
    for (int i = 0; i < 6 * n; ++i) fixed[i] = fixed_user[i] | fixed_plane[i];
    // connected clusters (union-find over the bonds)
    std::vector<int> root(n);
    std::iota(root.begin(), root.end(), 0);
    auto find = [&](int i) {
      while (root[i] != i) i = root[i] = root[root[i]];
      return i;
    };
    for (const auto& k : c) {
      const int ra = find(k.a), rb = find(k.b);
      if (ra != rb) root[std::max(ra, rb)] = std::min(ra, rb);
    }
    std::vector<std::vector<int>> members(n);
    for (int i = 0; i < n; ++i) members[find(i)].push_back(i);
    floating.clear();
    for (int r = 0; r < n; ++r) {
      const auto& m = members[r];
      if (m.empty()) continue;
      if (m.size() == 1) {  // no bond: nothing holds it
        for (int k = 0; k < 6; ++k) fixed[6 * m[0] + k] = 1;
        continue;
      }
      // the rigid motions that the cluster's constraints leave: anchor the cluster at its first
      // particle to make the system regular; after the solve these motions are removed again by
      // a least-squares fit over the cluster (remove_rigid_motions), which does not depend on the
      // particle that was anchored (nor on the numbering)
      const Eigen::MatrixXd Nm = rigid_null_space(m);
      if (Nm.cols() > 0) {
        // fix as many DOFs of the first particle as there are free motions, chosen so that they
        // stop exactly those motions (rows of the particle's DOFs on the null space, greedily
        // independent): the cluster is then held, not over-constrained
        Eigen::Vector3d xc = Eigen::Vector3d::Zero();
        for (int i : m) xc += p[i].x;
        xc /= static_cast<double>(m.size());
        const Eigen::Vector3d rel = (p[m[0]].x - xc) / ell;
        std::array<Eigen::VectorXd, 6> v;  // each DOF's motion under the free modes
        for (int k = 0; k < 6; ++k) {
          Eigen::Matrix<double, 6, 1> row = Eigen::Matrix<double, 6, 1>::Zero();
          row[k] = 1.0;
          if (k < 3) row.tail<3>() = rel.cross(Eigen::Vector3d::Unit(k));
          v[k] = Nm.transpose() * row;
        }
        for (Eigen::Index pick = 0; pick < Nm.cols(); ++pick) {  // pivoted Gram-Schmidt
          int best = -1;
          double bn = 0.0;
          for (int k = 0; k < 6; ++k)
            if (!fixed[6 * m[0] + k] && v[k].norm() > bn) {
              bn = v[k].norm();
              best = k;
            }
          if (best < 0 || bn < 1e-8) break;
          fixed[6 * m[0] + best] = 1;
          const Eigen::VectorXd b = v[best] / bn;
          for (auto& w : v) w -= b * b.dot(w);
        }
        floating.push_back(m);
      }
    }
  }

  // The rigid motions (t, w) of a cluster that leave its own constraints (planes and fix(); not
  // the anchor) unmoved: the null space of C, one row per constrained DOF; a motion displaces x by
  // t + w x (x - x_c) / ell and turns every node by w / ell.
  Eigen::MatrixXd rigid_null_space(const std::vector<int>& m) const {
    Eigen::Vector3d xc = Eigen::Vector3d::Zero();
    for (int i : m) xc += p[i].x;
    xc /= static_cast<double>(m.size());
    Eigen::Matrix<double, 6, 6> CtC = Eigen::Matrix<double, 6, 6>::Zero();
    for (int i : m)
      for (int k = 0; k < 6; ++k) {
        if (!(fixed_user[6 * i + k] | fixed_plane[6 * i + k])) continue;
        Eigen::Matrix<double, 6, 1> row = Eigen::Matrix<double, 6, 1>::Zero();
        row[k] = 1.0;
        if (k < 3) row.tail<3>() = ((p[i].x - xc) / ell).cross(Eigen::Vector3d::Unit(k));  // e_k . (w x rel)
        CtC += row * row.transpose();
      }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> es(CtC);
    const double top = std::max(1.0, es.eigenvalues().maxCoeff());
    int k = 0;
    while (k < 6 && es.eigenvalues()[k] <= 1e-10 * top) ++k;
    return es.eigenvectors().leftCols(k);
  }

  // u: 3 translations per particle. For each anchored cluster, subtract the least-squares fit of
  // its free rigid motions to the cluster's displacements.
  void remove_rigid_motions(std::vector<Eigen::Vector3d>& u) const {
    for (const auto& m : floating) {
      const Eigen::MatrixXd Nm = rigid_null_space(m);
      const int k = static_cast<int>(Nm.cols());
      if (k == 0) continue;
      Eigen::Vector3d xc = Eigen::Vector3d::Zero();
      for (int i : m) xc += p[i].x;
      xc /= static_cast<double>(m.size());
      Eigen::MatrixXd A = Eigen::MatrixXd::Zero(k, k);
      Eigen::VectorXd b = Eigen::VectorXd::Zero(k);
      std::vector<Eigen::MatrixXd> M(m.size());
      for (std::size_t j = 0; j < m.size(); ++j) {
        Eigen::Matrix<double, 3, 6> T;
        T.leftCols<3>().setIdentity();
        T.rightCols<3>() = -contact::skew<double>((p[m[j]].x - xc) / ell);  // w x rel = -rel x w
        M[j] = T * Nm;
        A += M[j].transpose() * M[j];
        b += M[j].transpose() * u[m[j]];
      }
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(A);
      const double top = std::max(es.eigenvalues().maxCoeff(), 1e-300);
      Eigen::VectorXd alpha = Eigen::VectorXd::Zero(k);
      for (int l = 0; l < k; ++l)
        if (es.eigenvalues()[l] > 1e-12 * top)
          alpha += es.eigenvectors().col(l) * (es.eigenvectors().col(l).dot(b) / es.eigenvalues()[l]);
      for (std::size_t j = 0; j < m.size(); ++j) u[m[j]] -= M[j] * alpha;
    }
  }

  // The pattern of the current contacts and constraints. The factor of an earlier contact set is
  // kept (as the preconditioner of GMRES) when the constraints, and so the DOF numbering, did not
  // change: new bonds are a low-rank change of K, and the iteration count decides when to
  // refactorise.
  void build_pattern() {
    update_constraints();
    build_pattern_for(c.size(), fixed);
    need_factor = !(solver->has_factor() && fixed == ref_fixed);
  }

  // dof, nfree, K and slots for the first nc contacts and the constraints fx
  void build_pattern_for(std::size_t nc, const std::vector<std::uint8_t>& fx) {
    const int n = N();
    dof.assign(6 * n, -1);
    nfree = 0;
    for (int i = 0; i < 6 * n; ++i)
      if (!fx[i]) dof[i] = nfree++;
    std::vector<Eigen::Triplet<double, int>> tr;
    tr.reserve(nc * 144 + static_cast<std::size_t>(nfree));
    for (int i = 0; i < nfree; ++i) tr.emplace_back(i, i, 0.0);
    auto gdof = [&](const Contact& k, int l) { return 6 * (l < 6 ? k.a : k.b) + (l % 6); };
    for (std::size_t kc = 0; kc < nc; ++kc)
      for (int i = 0; i < 12; ++i)
        for (int j = 0; j < 12; ++j) {
          const int gi = dof[gdof(c[kc], i)], gj = dof[gdof(c[kc], j)];
          if (gi >= 0 && gj >= 0) tr.emplace_back(gi, gj, 0.0);
        }
    K.resize(nfree, nfree);
    K.setFromTriplets(tr.begin(), tr.end());
    K.makeCompressed();
    slots.assign(nc * 144, -1);
    const int* outer = K.outerIndexPtr();
    const int* inner = K.innerIndexPtr();
    for (std::size_t kc = 0; kc < nc; ++kc)
      for (int i = 0; i < 12; ++i)
        for (int j = 0; j < 12; ++j) {
          const int gi = dof[gdof(c[kc], i)], gj = dof[gdof(c[kc], j)];
          if (gi < 0 || gj < 0) continue;
          const int* b = inner + outer[gj];
          const int* e = inner + outer[gj + 1];
          const int* it = std::lower_bound(b, e, gi);
          slots[kc * 144 + 12 * i + j] = static_cast<int>(it - inner);
        }
    std::vector<int> blocks(static_cast<std::size_t>(nfree));
    for (int i = 0; i < 6 * n; ++i)
      if (dof[i] >= 0) blocks[dof[i]] = i / 6;
    solver->set_row_blocks(std::move(blocks));
    pattern_dirty = false;
  }

  double dof_scale(int l) const { return (l % 6) < 3 ? 1.0 : 1.0 / ell; }

  // K^ = c S K S from the elements e (one per contact of the pattern, in order)
  void assemble(const std::vector<contact::BondElement>& e) {
    double* v = K.valuePtr();
    std::fill(v, v + K.nonZeros(), 0.0);
    for (std::size_t kc = 0; kc < e.size(); ++kc) {
      const contact::BondMat12 Ke = contact::bond_stiffness(e[kc], bmat);
      const int* s = &slots[kc * 144];
      for (int i = 0; i < 12; ++i)
        for (int j = 0; j < 12; ++j)
          if (s[12 * i + j] >= 0) v[s[12 * i + j]] += cscale * dof_scale(i) * dof_scale(j) * Ke(i, j);
    }
  }

  contact::BondElement element(const Contact& k) const {
    return contact::make_bond(p[k.a].x, p[k.b].x, k.pair.q[kHA], k.pair.q[kHB], p[k.a].r, p[k.b].r);
  }

  // ---------------------------------------------------------------------------------------------
  // integration of the contacts over [t, t + h]

  StepRecord step(double t_end) {
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

  // The two-particle models of the active contacts over one accepted step [t, t + h] with F = 0,
  // into qnew (freeze[i] = 2: the contact left the model's domain); returns h.
  double integrate_contacts(StepRecord& rec, double t_end, double seg_end) {
    RhsCtx f{&mat, &cache, prof.segment_at(t), &rhs_evals};
    // per-step work arrays, kept in Impl (no allocation once the contact count has settled)
    qnew.resize(c.size());
    active.clear();
    for (std::size_t i = 0; i < c.size(); ++i)
      if (!c[i].frozen) active.push_back(static_cast<int>(i));
    freeze.assign(c.size(), 0);
    for (;;) {
      double h = std::min({dt, t_end - t, seg_end - t});
      if (h >= (std::min(t_end, seg_end) - t) * (1.0 - 1e-12)) h = std::min(t_end, seg_end) - t;
      rec.max_error = 0.0;
      rec.substeps = 0;
      rec.contacts_substepped = 0;
      if (opt.strategy != 1 || strategy1_attempt(rec, f, h)) {
        if (opt.strategy != 1) strategy2_step(rec, f, h);
        return h;
      }
    }
  }

  // Strategy 1: one step h for every contact, accepted when every error is below eps_lim (else dt
  // shrinks, Eq 45; contacts that leave the domain at dt_min are frozen); true if accepted.
  bool strategy1_attempt(StepRecord& rec, const RhsCtx& f, double h) {
    bool accepted = true;
    domain_fail.clear();
    for (int i : active) {
      const Trial tr = trial_step(f, t, h, c[i].pair.q);
      if (!tr.ok) domain_fail.push_back(i);
      if (!tr.ok || tr.error > opt.eps_lim) {
        accepted = false;
        continue;
      }
      qnew[i] = tr.q;
      rec.max_error = std::max(rec.max_error, tr.error / opt.eps_lim);
    }
    rec.substeps = static_cast<long>(active.size());
    if (accepted) {
      if (rec.max_error < 0.1) dt = std::min(opt.dt_max, opt.alpha * dt);  // Eqs 46-47
      return true;
    }
    ++rec.rejected;
    dt = h / opt.alpha;  // Eq 45
    if (dt < opt.dt_min) {
      if (domain_fail.empty())
        throw std::runtime_error(
            fmt::format("staggered: strategy 1 needs a step below dt_min = {:.3g} s at t = {:.6g} s", opt.dt_min, t));
      for (int i : domain_fail) {  // these contacts left the model's domain: freeze them
        c[i].frozen = true;
        c[i].pair.status = cs::PairStatus::ConeDegenerate;
        ++rec.newly_frozen;
      }
      active.erase(std::remove_if(active.begin(), active.end(), [&](int i) { return c[i].frozen; }), active.end());
      dt = opt.dt_min;
    }
    return false;
  }

  // Strategy 2: each contact sub-steps over [t, t + h] on its own; dt follows the fraction of
  // contacts that needed sub-steps.
  void strategy2_step(StepRecord& rec, const RhsCtx& f, double h) {
    for (int i : active) {
      const ContactResult r = advance_substeps(c[i].pair.q, c[i].pair.R_min0(), f, t, t + h, opt, x_max);
      if (!r.ok) {
        if (r.domain) {
          freeze[i] = 2;  // leaves the domain: frozen, no load this step
          qnew[i] = c[i].pair.q;
          continue;
        }
        throw std::runtime_error(fmt::format(
            "staggered: contact {}-{} needs a sub-step below dt_min = {:.3g} s at t = {:.6g} s", c[i].a, c[i].b,
            opt.dt_min, t));
      }
      qnew[i] = r.q;
      rec.substeps += r.substeps;
      if (r.substeps > 1) ++rec.contacts_substepped;
      rec.max_error = std::max(rec.max_error, r.max_error);
    }
    const double frac =
        active.empty() ? 0.0 : static_cast<double>(rec.contacts_substepped) / static_cast<double>(active.size());
    if (frac < opt.grow_below)
      dt = std::min(opt.dt_max, opt.alpha * dt);
    else if (frac > opt.shrink_above)
      dt = std::max(opt.dt_min, dt / opt.alpha);
  }

  // The sintering loads of the step (Eq 10) on the bond network; the scaled displacements.
  VecX solve_network(StepRecord& rec) {
    auto t0 = Clock::now();
    el.resize(c.size());
    for (std::size_t i = 0; i < c.size(); ++i) el[i] = element(c[i]);
    VecX fhat = VecX::Zero(nfree);
    for (int i : active) {
      if (freeze[i] == 2) continue;
      const double dL = (c[i].pair.q[kHA] - qnew[i][kHA]) + (c[i].pair.q[kHB] - qnew[i][kHB]);  // Delta(y4 + y7)
      const double F = contact::bond_axial_stiffness(el[i], bmat) * dL;  // Eq 10, compressive positive
      for (int k = 0; k < 3; ++k) {
        const int ia = dof[6 * c[i].a + k], ib = dof[6 * c[i].b + k];
        if (ia >= 0) fhat[ia] += cscale * F * el[i].e3[k];
        if (ib >= 0) fhat[ib] -= cscale * F * el[i].e3[k];
      }
    }
    // amortised refactorisation: once the solves since the last factor have taken more GMRES
    // iterations than a factorisation costs, refactorise (at least refactor_iterations). A
    // factorisation is ~n c^2 flops and an iteration ~4 n c, c = nnz(L) / n the mean column of the
    // factor; measured, a factorisation took the time of 24 iterations at c = 146 (Cu, 805 spheres)
    // and 25 at c = 265 (Ti, 3619), so the cost is taken as 0.1 c iterations. Deterministic: it
    // depends on the pattern, not on the clock.
    if (solver->has_factor() && nfree > 0) {
      const double cols = static_cast<double>(solver->stats().factor_nnz) / nfree;
      if (last_iterations > std::max(static_cast<double>(opt.refactor_iterations), 0.1 * cols)) need_factor = true;
    }
    assemble(el);
    timers.assemble += seconds_since(t0);
    VecX uhat = VecX::Zero(nfree);
    if (nfree == 0) return uhat;
    if (need_factor) {
      t0 = Clock::now();
      const LinearStatus fs = solver->factorise(K, false);
      timers.factorise += seconds_since(t0);
      if (!fs.ok) {
        const int col = fs.column;
        int part = -1, d = -1;
        for (int g = 0; g < static_cast<int>(dof.size()); ++g)
          if (dof[g] == col) {
            part = g / 6;
            d = g % 6;
          }
        throw std::runtime_error(fmt::format("staggered: the bond network is singular at t = {:.6g} s (particle {}, "
                                             "DOF {}): {}",
                                             t, part, d, fs.message));
      }
      ref = el;
      ref_fixed = fixed;
      need_factor = false;
      rec.refactorised = true;
    }
    t0 = Clock::now();
    LinearStatus ss = solver->solve(K, fhat, uhat);
    if (!ss.ok) {  // the reused factor is too far off: refactorise now
      const LinearStatus fs = solver->factorise(K, false);
      if (!fs.ok) throw std::runtime_error("staggered: the bond network became singular: " + fs.message);
      ref = el;
      ref_fixed = fixed;
      rec.refactorised = true;
      ss = solver->solve(K, fhat, uhat);
      if (!ss.ok) throw std::runtime_error("staggered: the network solve failed: " + ss.message);
    }
    timers.solve += seconds_since(t0);
    last_iterations = rec.refactorised ? ss.iterations : last_iterations + ss.iterations;
    rec.gmres_iterations = ss.iterations;
    rec.solves = 1;
    return uhat;
  }

  // Moves the nodes by the solve's translations, then corrects the shrinkage (Eqs 41-44) and
  // advances every contact's state to t_new (freezing those that left the model's domain).
  void move_and_correct(StepRecord& rec, const VecX& uhat, double t_new) {
    u.assign(N(), Eigen::Vector3d::Zero());
    for (int i = 0; i < N(); ++i)
      for (int k = 0; k < 3; ++k) {
        const int g = dof[6 * i + k];
        if (g >= 0) u[i][k] = uhat[g];  // translations are not scaled
      }
    remove_rigid_motions(u);
    for (int i = 0; i < N(); ++i) p[i].x += u[i];
    for (std::size_t i = 0; i < c.size(); ++i) {
      Contact& k = c[i];
      const State qold = k.pair.q;
      const State qf = (k.frozen || freeze[i] == 2) ? qold : qnew[i];
      const double d = (p[k.b].x - p[k.a].x).norm();
      const auto [y4, y7] = corrected_split(qold[kHA], qold[kHB], qf[kHA], qf[kHB], d, qold[kRA], qold[kRB]);
      k.dL_bar = (y4 + y7) - (qf[kHA] + qf[kHB]);  // Eq 44
      k.pair.q = qf;
      k.pair.q[kHA] = y4;
      k.pair.q[kHB] = y7;
      rec.max_shrink_error = std::max(rec.max_shrink_error, std::fabs(y4 + y7 - d) / d);
      if (k.frozen) continue;
      k.pair.t = t_new;
      ++k.pair.steps;
      if (freeze[i] == 2) {
        k.frozen = true;
        k.pair.status = cs::PairStatus::ConeDegenerate;
        ++rec.newly_frozen;
        continue;
      }
      const cs::PairStatus s = cs::check_state(k.pair.q, k.pair.R_min0(), x_max);
      if (s != cs::PairStatus::Ok) {
        k.frozen = true;
        k.pair.status = s;
        ++rec.newly_frozen;
      }
    }
  }
};

// ================================================================================================

Staggered::Staggered() : impl_(std::make_unique<Impl>()) {}
Staggered::~Staggered() = default;
Staggered::Staggered(Staggered&&) noexcept = default;
Staggered& Staggered::operator=(Staggered&&) noexcept = default;

Staggered::Staggered(std::vector<Particle> particles, cs::SinterMaterial material, cs::TemperatureProfile temperature,
                     StaggeredOptions options)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  options.validate();
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
const std::vector<Particle>& Staggered::particles() const { return impl_->p; }
const std::vector<Particle>& Staggered::initial_particles() const { return impl_->p0; }
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

Eigen::Matrix3d Staggered::homogeneous_strain() const {
  const auto& p = impl_->p;
  const auto& p0 = impl_->p0;
  const double n = static_cast<double>(p.size());
  Eigen::Vector3d xm = Eigen::Vector3d::Zero(), Xm = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < p.size(); ++i) {
    xm += p[i].x;
    Xm += p0[i].x;
  }
  xm /= n;
  Xm /= n;
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero(), B = Eigen::Matrix3d::Zero();
  for (std::size_t i = 0; i < p.size(); ++i) {
    const Eigen::Vector3d dX = p0[i].x - Xm, u = (p[i].x - xm) - dX;  // the displacement about the mean
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
    lo = lo.cwiseMin(p[i].x - Eigen::Vector3d::Constant(p[i].r));
    hi = hi.cwiseMax(p[i].x + Eigen::Vector3d::Constant(p[i].r));
    const double r0 = impl_->p0[i].r;
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
