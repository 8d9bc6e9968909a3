#include "netdem/quasistatic/network_solver.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>

#include <Eigen/LU>
#include <fmt/format.h>
#include <omp.h>

#include "netdem/packing/packing.hpp"
#include "netdem/quasistatic/linear_solver.hpp"

namespace netdem::qs {

namespace ct = netdem::contact;

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

void require(bool ok, const std::string& msg) {
  if (!ok) throw std::invalid_argument(msg);
}

/// exp(A) for a small symmetric 2x2 matrix (series; |A| << 1 per increment).
Eigen::Matrix2d small_expm(const Eigen::Matrix2d& A) {
  Eigen::Matrix2d term = Eigen::Matrix2d::Identity(), sum = Eigen::Matrix2d::Identity();
  for (int k = 1; k <= 8; ++k) {
    term = term * A / static_cast<double>(k);
    sum += term;
  }
  return sum;
}

struct PairAux {
  Eigen::Matrix2d E_form = Eigen::Matrix2d::Zero();  ///< accumulated strain when the contact formed
  double slip = 0.0;    ///< accumulated slip with rotations (Eq 5)
  double centre = 0.0;  ///< accumulated tangential displacement of the centres (L dphi)
};

}  // namespace

void SolverOptions::validate() const {
  law.validate();
  require(std::isfinite(skin) && skin > 0.0, fmt::format("solver: skin must be positive, got {}", skin));
  require(max_newton >= 0 && max_newton <= 1000, fmt::format("solver: max_newton must be in [0, 1000], got {}", max_newton));
  require(!std::isnan(max_residual_tol) && max_residual_tol > 0.0,
          fmt::format("solver: max residual tolerance must be positive, got {}", max_residual_tol));
  require(std::isfinite(residual_tol) && residual_tol > 0.0,
          fmt::format("solver: residual tolerance must be positive, got {}", residual_tol));
  require(std::isfinite(max_step) && max_step > 0.0, fmt::format("solver: max_step must be positive, got {}", max_step));
  require(std::isfinite(max_rotation_step) && max_rotation_step > 0.0,
          fmt::format("solver: max_rotation_step must be positive, got {}", max_rotation_step));
  require(std::isfinite(regularisation) && regularisation >= 0.0 && regularisation < 1e-2,
          fmt::format("solver: regularisation must be in [0, 1e-2), got {}", regularisation));
  require(std::isfinite(linear_tolerance) && linear_tolerance > 0.0 && linear_tolerance < 1.0,
          fmt::format("solver: linear tolerance must be in (0, 1), got {}", linear_tolerance));
  require(std::isfinite(viscosity) && viscosity >= 0.0 && viscosity <= 1e3,
          fmt::format("solver: viscosity must be in [0, 1e3], got {}", viscosity));
  require(freeze_after >= 1 && freeze_after <= 100, fmt::format("solver: freeze_after must be in [1, 100], got {}", freeze_after));
  require(local_sweeps >= 0 && local_sweeps <= 100, fmt::format("solver: local_sweeps must be in [0, 100], got {}", local_sweeps));
  require(local_iterations >= 1 && local_iterations <= 100,
          fmt::format("solver: local_iterations must be in [1, 100], got {}", local_iterations));
  require(std::isfinite(local_threshold) && local_threshold >= 0.0,
          fmt::format("solver: local_threshold must be non-negative, got {}", local_threshold));
  require(backtracks >= 1 && backtracks <= 30, fmt::format("solver: backtracks must be in [1, 30], got {}", backtracks));
  require(threads >= 1 && threads <= 256, fmt::format("solver: threads must be in [1, 256], got {}", threads));
  require(chord_steps >= 0 && chord_steps <= 100, fmt::format("solver: chord_steps must be in [0, 100], got {}", chord_steps));
  require(kink_freeze_after >= 0 && kink_freeze_after <= 100,
          fmt::format("solver: kink_freeze_after must be in [0, 100], got {}", kink_freeze_after));
  require(max_cuts >= 0 && max_cuts <= 20, fmt::format("solver: max_cuts must be in [0, 20], got {}", max_cuts));
  require(std::isfinite(viscosity_strain) && viscosity_strain >= 0.0 && viscosity_strain <= 1.0,
          fmt::format("solver: viscosity_strain must be in [0, 1], got {}", viscosity_strain));
  require(std::isfinite(viscosity_start) && viscosity_start >= 0.0 && viscosity_start <= 1e3,
          fmt::format("solver: viscosity_start must be in [0, 1e3], got {}", viscosity_start));
  require(std::isfinite(viscosity_decay) && viscosity_decay > 0.0 && viscosity_decay < 1.0,
          fmt::format("solver: viscosity_decay must be in (0, 1), got {}", viscosity_decay));
  require(line_search_max >= 1 && line_search_max <= 100,
          fmt::format("solver: line_search_max must be in [1, 100], got {}", line_search_max));
  require(std::isfinite(line_search_tol) && line_search_tol > 0.0 && line_search_tol < 1.0,
          fmt::format("solver: line_search_tol must be in (0, 1), got {}", line_search_tol));
  require(std::isfinite(slide_stiffness_fraction) && slide_stiffness_fraction >= 0.0 && slide_stiffness_fraction <= 1.0,
          fmt::format("solver: slide_stiffness_fraction must be in [0, 1], got {}", slide_stiffness_fraction));
}

struct NetworkSolver::Impl {
  SolverOptions opt;
  int n = 0;
  std::vector<double> x, y, th, r;
  std::vector<std::uint8_t> periph;
  double solid_area = 0, D0 = 0, r_mean = 0, r_max = 0, box_area0 = 0;
  Eigen::Matrix2d Fbox = Eigen::Matrix2d::Identity();
  Eigen::Matrix2d E = Eigen::Matrix2d::Zero();

  // DOF map: dof[3p + c] = free index or -1 (prescribed)
  std::vector<int> dof;
  int nfree = 0;

  // pair table = neighbour list (i < j, sorted), with committed history
  std::vector<int> pi, pj;
  std::vector<ct::PlasticIndentationHistory> hist;
  std::vector<PairAux> aux;
  std::vector<double> xb, yb;  // positions at the last neighbour build
  Eigen::Matrix2d Fb = Eigen::Matrix2d::Identity();

  // committed forces
  std::vector<double> fn_c, ft_c;  // per pair
  std::vector<std::uint8_t> slide_c;
  std::vector<double> f_c;  // 3n contact forces on particles (committed state)

  // sparse pattern (free DOFs only, full storage)
  SpMat K, M;
  std::vector<int> pos;       // 36 per pair: position in valuePtr, -1 if a DOF is prescribed
  std::vector<int> diag_pos;  // per free DOF
  bool pattern_changed = true;

  // trial buffers
  std::vector<double> du, f;
  std::vector<double> pf;  // 6 per pair: the pair's force on (i, j) in the trial state (summed into f)
  std::vector<std::uint8_t> apart;  // per pair: never touched, apart, trial state and pf already zero
  std::vector<std::uint8_t> refreshed;  // per pair, scratch of refresh_particles
  // scratch of relax_worst (kept: it runs every Newton iteration)
  std::vector<double> relax_rp;
  std::vector<std::uint8_t> relax_done;
  std::vector<int> relax_moved;
  std::vector<std::pair<double, int>> relax_bad;
  std::vector<ct::PairGeometry> g0;
  std::vector<ct::PlasticIndentationResult> trial;
  std::vector<double> trial_slip;
  std::vector<double> du_prev;
  std::vector<std::uint8_t> last_sliding, flips;  // per pair, within the current increment
  std::vector<std::uint8_t> last_open, open_flips;
  std::vector<std::uint8_t> last_plastic, pe_flips;  // loading/unloading branch flips (2: not seen yet)
  std::vector<double> last_kn;
  std::vector<int> adj_start, adj_pair;  // pairs of each particle (CSR)
  std::vector<std::uint8_t> diag_branch;  // verbose diagnostics: branch + 4*sliding at the last iteration
  std::vector<double> du_aff;  // affine motion of the increment (drag reference)
  double eta = -1.0;           // viscous drag coefficient of the current increment
  double kl_ref = 1.0;         // mean translational diagonal (local regularisation)
  std::vector<double> du_start;  // du at the start of a line search
  Eigen::Matrix2d dE_prev = Eigen::Matrix2d::Zero();
  VecX rhs, sol;

  LinearSolver lin;
  SolverTimings tim;

  // ---------------------------------------------------------------------------------------------
  void build_dofs() {
    dof.assign(3 * n, -1);
    nfree = 0;
    const bool rot_free = opt.rotations && opt.law.frictional();
    for (int p = 0; p < n; ++p) {
      const bool translations_free = opt.mode == BoundaryMode::Die && !periph[p];
      if (translations_free) {
        dof[3 * p] = nfree++;
        dof[3 * p + 1] = nfree++;
      }
      // peripheral rotations are always held (section 2.4); interior ones are unknowns in both modes
      if (rot_free && !periph[p]) dof[3 * p + 2] = nfree++;
    }
  }

  // Cell-list neighbour search: all pairs with gap < skin * r_mean. Merges the committed history.
  void build_neighbours() {
    const auto t0 = Clock::now();
    const double skin = opt.skin * r_mean;
    const double cell = 2.0 * r_max + skin;
    double xmin = x[0], xmax = x[0], ymin = y[0], ymax = y[0];
    for (int p = 1; p < n; ++p) {
      xmin = std::min(xmin, x[p]);
      xmax = std::max(xmax, x[p]);
      ymin = std::min(ymin, y[p]);
      ymax = std::max(ymax, y[p]);
    }
    const int nx = std::max(1, static_cast<int>((xmax - xmin) / cell) + 1);
    const int ny = std::max(1, static_cast<int>((ymax - ymin) / cell) + 1);
    std::vector<int> head(static_cast<std::size_t>(nx) * ny, -1), next(n, -1);
    auto cell_of = [&](int p, int& cx, int& cy) {
      cx = std::min(nx - 1, static_cast<int>((x[p] - xmin) / cell));
      cy = std::min(ny - 1, static_cast<int>((y[p] - ymin) / cell));
    };
    for (int p = n - 1; p >= 0; --p) {
      int cx, cy;
      cell_of(p, cx, cy);
      next[p] = head[cy * nx + cx];
      head[cy * nx + cx] = p;
    }
    std::vector<std::pair<int, int>> pairs;
    pairs.reserve(pi.size() + n);
    for (int p = 0; p < n; ++p) {
      int cx, cy;
      cell_of(p, cx, cy);
      for (int oy = -1; oy <= 1; ++oy)
        for (int ox = -1; ox <= 1; ++ox) {
          const int qx = cx + ox, qy = cy + oy;
          if (qx < 0 || qy < 0 || qx >= nx || qy >= ny) continue;
          for (int q = head[qy * nx + qx]; q >= 0; q = next[q]) {
            if (q <= p) continue;
            const double dx = x[q] - x[p], dy = y[q] - y[p];
            const double gap = std::sqrt(dx * dx + dy * dy) - r[p] - r[q];
            if (gap < skin) pairs.emplace_back(p, q);
          }
        }
    }
    std::sort(pairs.begin(), pairs.end());
    // merge the committed history (both lists sorted); pairs farther apart than the skin lose it
    std::vector<int> npi(pairs.size()), npj(pairs.size());
    std::vector<ct::PlasticIndentationHistory> nh(pairs.size());
    std::vector<PairAux> na(pairs.size());
    std::vector<double> nfn(pairs.size(), 0.0), nft(pairs.size(), 0.0);
    std::vector<std::uint8_t> nsl(pairs.size(), 0);
    std::size_t o = 0;
    for (std::size_t k = 0; k < pairs.size(); ++k) {
      npi[k] = pairs[k].first;
      npj[k] = pairs[k].second;
      while (o < pi.size() && std::make_pair(pi[o], pj[o]) < pairs[k]) ++o;
      if (o < pi.size() && pi[o] == pairs[k].first && pj[o] == pairs[k].second) {
        nh[k] = hist[o];
        na[k] = aux[o];
        nfn[k] = fn_c[o];
        nft[k] = ft_c[o];
        nsl[k] = slide_c[o];
      } else {
        na[k].E_form = E;
      }
    }
    pi.swap(npi);
    pj.swap(npj);
    apart.assign(pi.size(), 0);  // new pair indices: nothing is known to be zero
    hist.swap(nh);
    aux.swap(na);
    fn_c.swap(nfn);
    ft_c.swap(nft);
    slide_c.swap(nsl);
    xb = x;
    yb = y;
    Fb = Fbox;
    adj_start.assign(n + 1, 0);
    for (std::size_t k = 0; k < pi.size(); ++k) {
      ++adj_start[pi[k] + 1];
      ++adj_start[pj[k] + 1];
    }
    for (int p = 0; p < n; ++p) adj_start[p + 1] += adj_start[p];
    adj_pair.assign(2 * pi.size(), 0);
    std::vector<int> fill(adj_start.begin(), adj_start.end() - 1);
    for (std::size_t k = 0; k < pi.size(); ++k) {
      adj_pair[fill[pi[k]]++] = static_cast<int>(k);
      adj_pair[fill[pj[k]]++] = static_cast<int>(k);
    }
    build_pattern();
    tim.neighbours += seconds_since(t0);
  }

  // Sparsity pattern of the free-DOF matrix: diagonal 3x3 blocks + one block pair per neighbour
  // pair, written directly in compressed column form from the particle adjacency (adj_start,
  // adj_pair): column (p, b) holds the free DOFs of p and of its neighbours, in DOF order (DOFs
  // are numbered particle by particle).
  void build_pattern() {
    std::vector<int> near;  // p and its neighbours, sorted
    auto neighbourhood = [&](int p) {
      near.clear();
      near.push_back(p);
      for (int q = adj_start[p]; q < adj_start[p + 1]; ++q) {
        const auto k = static_cast<std::size_t>(adj_pair[q]);
        near.push_back(pi[k] == p ? pj[k] : pi[k]);
      }
      std::sort(near.begin(), near.end());
    };
    auto free_of = [&](int q) { return (dof[3 * q] >= 0) + (dof[3 * q + 1] >= 0) + (dof[3 * q + 2] >= 0); };
    K.resize(nfree, nfree);
    int* outer = K.outerIndexPtr();
    outer[0] = 0;
    for (int p = 0; p < n; ++p) {
      if (free_of(p) == 0) continue;
      neighbourhood(p);
      int rows = 0;
      for (const int q : near) rows += free_of(q);
      for (int b = 0; b < 3; ++b)
        if (const int d = dof[3 * p + b]; d >= 0) outer[d + 1] = rows;
    }
    for (int d = 0; d < nfree; ++d) outer[d + 1] += outer[d];
    K.resizeNonZeros(outer[nfree]);
    int* inner = K.innerIndexPtr();
    std::fill(K.valuePtr(), K.valuePtr() + outer[nfree], 0.0);
    for (int p = 0; p < n; ++p) {
      if (free_of(p) == 0) continue;
      neighbourhood(p);
      for (int b = 0; b < 3; ++b) {
        const int d = dof[3 * p + b];
        if (d < 0) continue;
        int at = outer[d];
        for (const int q : near)
          for (int a = 0; a < 3; ++a)
            if (const int r = dof[3 * q + a]; r >= 0) inner[at++] = r;
      }
    }
    M = K;
    auto find = [&](int row, int col) -> int {
      const int* inner = K.innerIndexPtr();
      const int b = K.outerIndexPtr()[col], e = K.outerIndexPtr()[col + 1];
      const int* it = std::lower_bound(inner + b, inner + e, row);
      return static_cast<int>(it - inner);
    };
    pos.assign(36 * pi.size(), -1);
    for (std::size_t k = 0; k < pi.size(); ++k) {
      const int nodes[2] = {pi[k], pj[k]};
      for (int a = 0; a < 6; ++a)
        for (int b = 0; b < 6; ++b) {
          const int ra = dof[3 * nodes[a / 3] + a % 3], cb = dof[3 * nodes[b / 3] + b % 3];
          if (ra >= 0 && cb >= 0) pos[36 * k + 6 * b + a] = find(ra, cb);
        }
    }
    diag_pos.resize(nfree);
    for (int d = 0; d < nfree; ++d) diag_pos[d] = find(d, d);
    pattern_changed = true;
  }

  bool needs_rebuild() const {
    // displacement relative to the affine motion since the last build, plus the affine part of
    // the relative motion of two neighbours
    const Eigen::Matrix2d A = Fbox * Fb.inverse();
    double dmax = 0.0;
    for (int p = 0; p < n; ++p) {
      const Eigen::Vector2d xa = A * Eigen::Vector2d(xb[p], yb[p]);
      dmax = std::max(dmax, std::hypot(x[p] - xa.x(), y[p] - xa.y()));
    }
    const double affine_rel = (A - Eigen::Matrix2d::Identity()).norm() * (2.0 * r_max + opt.skin * r_mean);
    return 2.0 * dmax + affine_rel > opt.skin * r_mean;
  }

  // Trial evaluation of every pair from the committed state and the increment du.
  // Fills f (3n), pf, the trial results, and (if assemble) the values of K and M; without
  // assembly it is evaluate_forces().
  void evaluate(bool assemble, bool& any_nonsymmetric) {
    if (!assemble) {
      evaluate_forces();
      any_nonsymmetric = opt.law.frictional() || opt.geometric_stiffness;
      return;
    }
    std::fill(f.begin(), f.end(), 0.0);
    pf.resize(6 * pi.size());
    apart.resize(pi.size(), 0);
    std::fill(K.valuePtr(), K.valuePtr() + K.nonZeros(), 0.0);
    std::fill(M.valuePtr(), M.valuePtr() + M.nonZeros(), 0.0);
    any_nonsymmetric = false;
    ct::TangentOptions topt;
    topt.geometric = opt.geometric_stiffness;
    ct::PairElement e;
    double* Kv = K.valuePtr();
    double* Mv = M.valuePtr();
    const double slide_frac = opt.slide_stiffness_fraction;
    for (std::size_t k = 0; k < pi.size(); ++k) {
      const int i = pi[k], j = pj[k];
      const ct::PairGeometry g1 = ct::pair_geometry(ct::Vec(x[i] + du[3 * i], y[i] + du[3 * i + 1]),
                                                    ct::Vec(x[j] + du[3 * j], y[j] + du[3 * j + 1]), r[i], r[j]);
      const ct::PairGeometry& g = g0[k];
      // pairs that are apart and have never touched cost only the geometry
      if (g1.overlap <= 0.0 && hist[k].u_max <= 0.0) {
        set_apart(k);
        open_contact_stiffness(k, g1);
        continue;
      }
      apart[k] = 0;
      ct::element(opt.law, hist[k], g, g1, du[3 * i + 2], du[3 * j + 2], e, &topt);
      trial[k] = e.law;
      trial_slip[k] = e.dslip;
      for (int a = 0; a < 6; ++a) pf[6 * k + a] = e.force(a);
      for (int a = 0; a < 3; ++a) {
        f[3 * i + a] += e.force(a);
        f[3 * j + a] += e.force(3 + a);
      }
      if (e.law.branch == ct::NormalBranch::Open) {
        open_contact_stiffness(k, g1);
        continue;
      }
      if (last_open[k]) open_flips[k] = static_cast<std::uint8_t>(std::min(open_flips[k] + 1, 100));
      last_open[k] = 0;
      if (e.law.sliding) any_nonsymmetric = true;
      const ct::PairVec bn = ct::normal_gradient(g1), bt = ct::slip_gradient(g1);
      // Eq 2 is concave with a tangent that is singular at first touch, and Newton on the tangent
      // overshoots into separation: on the plastic branch the iteration matrix uses the secant of
      // Eq 2 over the increment (from the start overlap, or from touch) when it is stiffer.
      double kn_extra = 0.0;
      const double u_sep = ct::separation_overlap(opt.law, g1.r_eff, hist[k].u_max);
      if (e.law.branch == ct::NormalBranch::Plastic) {
        const double u_from = std::max(g.overlap, u_sep);
        if (g1.overlap > u_from) {
          const double ksec = ct::normal_secant(opt.law, g1.r_eff, hist[k].u_max, u_from, g1.overlap);
          kn_extra = std::max(0.0, ksec - e.law.k_n);
        }
      }
      // loading/unloading kink (the unloading branch is unload_ratio times stiffer): a contact that
      // keeps switching between the branches is held with the unloading stiffness, so that the
      // Newton step keeps it near u_max instead of jumping across the kink
      const std::uint8_t plastic = e.law.branch == ct::NormalBranch::Plastic ? 1 : 0;
      if (last_plastic[k] != 2 && last_plastic[k] != plastic)
        pe_flips[k] = static_cast<std::uint8_t>(std::min(pe_flips[k] + 1, 100));
      last_plastic[k] = plastic;
      if (opt.kink_freeze_after > 0 && plastic && pe_flips[k] >= opt.kink_freeze_after) {
        const double ku = opt.law.unload_ratio * ct::plastic_tangent(opt.law, g1.r_eff, g1.overlap);
        kn_extra = std::max(kn_extra, ku - e.law.k_n);
      }
      if (kn_extra > 0.0) e.stiffness.noalias() += kn_extra * bn * bn.transpose();
      // Iteration matrix (a modified Newton: robust on these non-smooth laws, see
      // docs/quasistatic.md). Sliding contacts keep a fraction slide_frac of their tangential
      // spring: the consistent tangent has none, which leaves the rotation of a particle whose
      // contacts all slide without stiffness. A contact whose stick/slip status flipped twice in
      // this increment keeps its full spring (elastic predictor; slower, but it cannot cycle).
      // The residual, not the matrix, defines the equilibrium.
      if (e.law.sliding != (last_sliding[k] != 0)) flips[k] = static_cast<std::uint8_t>(std::min(flips[k] + 1, 100));
      last_sliding[k] = e.law.sliding ? 1 : 0;
      const double frac = flips[k] >= opt.freeze_after ? 1.0 : slide_frac;
      if (e.law.sliding && frac > 0.0)
        e.stiffness.noalias() += frac * opt.law.k_t * e.law.area * bt * bt.transpose();
      const double kn_sym = e.law.k_n + kn_extra;
      last_kn[k] = kn_sym;
      // symmetric slip-status tangent for the preconditioner / direct solve
      const double kt = opt.law.frictional() ? opt.law.k_t * e.law.area * (e.law.sliding ? frac : 1.0) : 0.0;
      const int* pk = &pos[36 * k];
      for (int b = 0; b < 6; ++b)
        for (int a = 0; a < 6; ++a) {
          const int q = pk[6 * b + a];
          if (q < 0) continue;
          Kv[q] += e.stiffness(a, b);
          Mv[q] += kn_sym * bn(a) * bn(b) + kt * bt(a) * bt(b);
        }
    }
    // stick tangents differ slightly from M too; the geometric stiffness is not in M at all
    if (opt.law.frictional() || opt.geometric_stiffness) any_nonsymmetric = true;
  }

  /// Pair k has never touched and is apart: zero trial state and force.
  void set_apart(std::size_t k) {
    trial[k] = ct::PlasticIndentationResult{};
    trial_slip[k] = 0.0;
    std::fill_n(&pf[6 * k], 6, 0.0);
    apart[k] = 1;
  }

  /// Trial state and force (pf, no tangent) of pair k at the current du; e is scratch. A pair
  /// that has never touched and is clearly apart costs a squared distance (its zero trial state
  /// and force are written once, then flagged in `apart`).
  void pair_forces(std::size_t k, ct::PairElement& e) {
    const int i = pi[k], j = pj[k];
    if (hist[k].u_max <= 0.0) {
      const double dx = x[j] + du[3 * j] - x[i] - du[3 * i], dy = y[j] + du[3 * j + 1] - y[i] - du[3 * i + 1];
      const double rs = r[i] + r[j];
      if (dx * dx + dy * dy > rs * rs * (1.0 + 1e-9)) {  // overlap < 0 beyond any rounding
        if (!apart[k]) set_apart(k);
        return;
      }
    }
    apart[k] = 0;
    const ct::PairGeometry g1 = ct::pair_geometry(ct::Vec(x[i] + du[3 * i], y[i] + du[3 * i + 1]),
                                                  ct::Vec(x[j] + du[3 * j], y[j] + du[3 * j + 1]), r[i], r[j]);
    if (g1.overlap <= 0.0 && hist[k].u_max <= 0.0) {
      set_apart(k);
      return;
    }
    ct::element(opt.law, hist[k], g0[k], g1, du[3 * i + 2], du[3 * j + 2], e, nullptr);
    trial[k] = e.law;
    trial_slip[k] = e.dslip;
    for (int a = 0; a < 6; ++a) pf[6 * k + a] = e.force(a);
  }

  // evaluate(false), on opt.threads threads: the pairs (in parallel), then f gathered per particle
  // over its pairs in increasing pair order, i.e. the same sums in the same order as the
  // assembling loop (bit-identical results for any number of threads).
  void evaluate_forces() {
    pf.resize(6 * pi.size());
    apart.resize(pi.size(), 0);
    const auto np = static_cast<std::ptrdiff_t>(pi.size());
    const int levels = omp_get_max_active_levels();
    omp_set_max_active_levels(1);  // LinearSolver sets 0 to keep CHOLMOD serial
#pragma omp parallel num_threads(opt.threads)
    {
      ct::PairElement e;
#pragma omp for schedule(static)
      for (std::ptrdiff_t kk = 0; kk < np; ++kk) {
        pair_forces(static_cast<std::size_t>(kk), e);
      }
#pragma omp for schedule(static)
      for (int p = 0; p < n; ++p) {
        double s0 = 0.0, s1 = 0.0, s2 = 0.0;
        for (int q = adj_start[p]; q < adj_start[p + 1]; ++q) {
          const auto k = static_cast<std::size_t>(adj_pair[q]);
          const double* fk = &pf[6 * k + (pi[k] == p ? 0 : 3)];
          s0 += fk[0];
          s1 += fk[1];
          s2 += fk[2];
        }
        f[3 * p] = s0;
        f[3 * p + 1] = s1;
        f[3 * p + 2] = s2;
      }
    }
    omp_set_max_active_levels(levels);
  }

  // Open/closed cycling: a pair that closed and opened again within this increment keeps the
  // normal stiffness it last had while closed, so that the Newton step lands near touch instead
  // of jumping across it (iteration matrix only).
  void open_contact_stiffness(std::size_t k, const ct::PairGeometry& g1) {
    if (!last_open[k]) open_flips[k] = static_cast<std::uint8_t>(std::min(open_flips[k] + 1, 100));
    last_open[k] = 1;
    if (open_flips[k] < 2 || last_kn[k] <= 0.0) return;
    const double kn = last_kn[k];
    const ct::PairVec bn = ct::normal_gradient(g1);
    const int* pk = &pos[36 * k];
    for (int b = 0; b < 6; ++b)
      for (int a = 0; a < 6; ++a) {
        const int q = pk[6 * b + a];
        if (q < 0) continue;
        const double v = kn * bn(a) * bn(b);
        K.valuePtr()[q] += v;
        M.valuePtr()[q] += v;
      }
  }

  /// Re-evaluates (forces only) the pairs of the given particles after their du changed, keeping
  /// f, pf and the trial state consistent with du without a full evaluate().
  void refresh_particles(const std::vector<int>& ps) {
    ct::PairElement e;
    for (const int p : ps)
      for (int q = adj_start[p]; q < adj_start[p + 1]; ++q) {
        const auto k = static_cast<std::size_t>(adj_pair[q]);
        if (refreshed[k]) continue;
        refreshed[k] = 1;
        const int i = pi[k], j = pj[k];
        for (int a = 0; a < 3; ++a) {
          f[3 * i + a] -= pf[6 * k + a];
          f[3 * j + a] -= pf[6 * k + 3 + a];
        }
        pair_forces(k, e);
        for (int a = 0; a < 3; ++a) {
          f[3 * i + a] += pf[6 * k + a];
          f[3 * j + a] += pf[6 * k + 3 + a];
        }
      }
    for (const int p : ps)
      for (int q = adj_start[p]; q < adj_start[p + 1]; ++q) refreshed[static_cast<std::size_t>(adj_pair[q])] = 0;
  }

  double mean_normal_force() const {
    double s = 0.0;
    int c = 0;
    for (const auto& t : trial)
      if (t.branch != ct::NormalBranch::Open) {
        s += t.f_n;
        ++c;
      }
    return c > 0 ? s / c : 0.0;
  }

  /// Max |contact force| on the free DOFs / fbar (moments divided by the mean radius): the
  /// out-of-balance contact force, i.e. the viscous drag that holds the increment.
  double unbalance(double fbar, double* rms = nullptr) const {
    double m = 0.0, s2 = 0.0;
    int c = 0;
    for (int p = 0; p < n; ++p)
      for (int a = 0; a < 3; ++a)
        if (dof[3 * p + a] >= 0) {
          const double v = std::fabs(f[3 * p + a]) / (a == 2 ? r_mean : 1.0);
          m = std::max(m, v);
          s2 += v * v;
          ++c;
        }
    if (rms) *rms = c > 0 ? std::sqrt(s2 / c) / std::max(fbar, 1e-300) : 0.0;
    return m / std::max(fbar, 1e-300);
  }

  /// Newton residual r = f_contact - eta (du - du_affine) on the free DOFs, as max-norm / fbar.
  /// If fill_rhs, also stores r in rhs for the linear solve.
  double residual(double fbar, bool fill_rhs, double* max_norm = nullptr) {
    const double eta_t = std::max(eta, 0.0), eta_r = eta_t * r_mean * r_mean;
    double m = 0.0, s2 = 0.0;
    for (int p = 0; p < n; ++p)
      for (int a = 0; a < 3; ++a)
        if (const int d = dof[3 * p + a]; d >= 0) {
          const double rv = f[3 * p + a] - (a == 2 ? eta_r : eta_t) * (du[3 * p + a] - du_aff[3 * p + a]);
          if (fill_rhs) rhs(d) = rv;
          const double v = std::fabs(rv) / (a == 2 ? r_mean : 1.0);
          m = std::max(m, v);
          s2 += v * v;
        }
    const double scale = 1.0 / std::max(fbar, 1e-300);
    if (max_norm) *max_norm = m * scale;
    return std::sqrt(s2 / std::max(nfree, 1)) * scale;
  }

  /// Diagnostics (verbose): the particles with the largest Newton residual.
  void print_worst(double fbar) const {
    const double eta_t = std::max(eta, 0.0), eta_r = eta_t * r_mean * r_mean;
    std::vector<std::pair<double, int>> worst;
    for (int p = 0; p < n; ++p) {
      double m = 0.0;
      for (int a = 0; a < 3; ++a)
        if (dof[3 * p + a] >= 0) {
          const double rv = f[3 * p + a] - (a == 2 ? eta_r : eta_t) * (du[3 * p + a] - du_aff[3 * p + a]);
          m = std::max(m, std::fabs(rv) / (a == 2 ? r_mean : 1.0));
        }
      worst.emplace_back(m / std::max(fbar, 1e-300), p);
    }
    const std::size_t nw = std::min<std::size_t>(6, worst.size());
    std::partial_sort(worst.begin(), worst.begin() + static_cast<std::ptrdiff_t>(nw), worst.end(), std::greater<>());
    std::vector<int> closed(n, 0), slid(n, 0);
    for (std::size_t k = 0; k < pi.size(); ++k)
      if (trial[k].branch != ct::NormalBranch::Open) {
        ++closed[pi[k]];
        ++closed[pj[k]];
        if (trial[k].sliding) {
          ++slid[pi[k]];
          ++slid[pj[k]];
        }
      }
    for (std::size_t w = 0; w < nw; ++w) {
      const int p = worst[w].second;
      std::fprintf(stderr, "    worst p=%d |r|/fbar=%.3e contacts=%d sliding=%d non-affine motion %.3e R\n", p,
                   worst[w].first, closed[p], slid[p],
                   std::hypot(du[3 * p] - du_aff[3 * p], du[3 * p + 1] - du_aff[3 * p + 1]) / r_mean);
      if (w >= 2) continue;
      for (std::size_t k = 0; k < pi.size(); ++k)
        if ((pi[k] == p || pj[k] == p) && trial[k].branch != ct::NormalBranch::Open)
          std::fprintf(stderr, "      pair %d-%d f_n %.4e k_n %.4e (iteration matrix %.4e) branch %d u_max %.3e\n", pi[k],
                       pj[k], trial[k].f_n, trial[k].k_n, last_kn[k], static_cast<int>(trial[k].branch), hist[k].u_max);
    }
  }

  /// Residual (contact force - drag) and tangent of a set of m particles (1 or 2) alone, with all
  /// other particles held at their current trial positions: 3 entries per particle.
  void local_eval(const int* ps, int m, Eigen::VectorXd& res, Eigen::MatrixXd& Kl) const {
    res.setZero(3 * m);
    Kl.setZero(3 * m, 3 * m);
    ct::TangentOptions topt;
    topt.geometric = opt.geometric_stiffness;
    ct::PairElement e;
    auto slot = [&](int p) {
      for (int t = 0; t < m; ++t)
        if (ps[t] == p) return t;
      return -1;
    };
    for (int sp = 0; sp < m; ++sp)
      for (int q = adj_start[ps[sp]]; q < adj_start[ps[sp] + 1]; ++q) {
        const int k = adj_pair[q], i = pi[k], j = pj[k];
        const int si = slot(i), sj = slot(j);
        if ((si >= 0 && si < sp) || (sj >= 0 && sj < sp)) continue;  // pair inside the set: once
        const ct::PairGeometry g1 = ct::pair_geometry(ct::Vec(x[i] + du[3 * i], y[i] + du[3 * i + 1]),
                                                      ct::Vec(x[j] + du[3 * j], y[j] + du[3 * j + 1]), r[i], r[j]);
        if (g1.overlap <= 0.0 && hist[k].u_max <= 0.0) continue;
        ct::element(opt.law, hist[k], g0[k], g1, du[3 * i + 2], du[3 * j + 2], e, &topt);
        const int sl[2] = {si, sj};
        for (int A = 0; A < 2; ++A)
          if (sl[A] >= 0) res.segment<3>(3 * sl[A]) += e.force.segment<3>(3 * A);
        if (e.law.branch == ct::NormalBranch::Open) continue;
        if (e.law.sliding && opt.slide_stiffness_fraction > 0.0) {
          const ct::PairVec bt = ct::slip_gradient(g1);
          e.stiffness.noalias() += opt.slide_stiffness_fraction * opt.law.k_t * e.law.area * bt * bt.transpose();
        }
        for (int A = 0; A < 2; ++A)
          for (int B = 0; B < 2; ++B)
            if (sl[A] >= 0 && sl[B] >= 0) Kl.block<3, 3>(3 * sl[A], 3 * sl[B]) += e.stiffness.block<3, 3>(3 * A, 3 * B);
      }
    const double eta_t = std::max(eta, 0.0);
    for (int t = 0; t < m; ++t)
      for (int a = 0; a < 3; ++a) {
        const int p = ps[t];
        const double ea = a == 2 ? eta_t * r_mean * r_mean : eta_t;
        res(3 * t + a) -= ea * (du[3 * p + a] - du_aff[3 * p + a]);
        Kl(3 * t + a, 3 * t + a) += ea + 1e-9 * kl_ref * (a == 2 ? r_mean * r_mean : 1.0);
      }
  }

  /// Nonlinear Gauss-Seidel on a set of 1 or 2 particles: damped Newton on their own free DOFs.
  void relax_set(const int* ps, int m, double fbar) {
    int idx[6], nf = 0;  // local index 3 t + a of the free DOFs
    for (int t = 0; t < m; ++t)
      for (int a = 0; a < 3; ++a)
        if (dof[3 * ps[t] + a] >= 0) idx[nf++] = 3 * t + a;
    if (nf == 0) return;
    auto norm = [&](const Eigen::VectorXd& v) {
      double s2 = 0.0;
      for (int c = 0; c < nf; ++c) s2 += std::pow(v(idx[c]) / (idx[c] % 3 == 2 ? r_mean : 1.0), 2);
      return std::sqrt(s2);
    };
    auto at = [&](int c) -> double& { return du[3 * ps[idx[c] / 3] + idx[c] % 3]; };
    Eigen::VectorXd res, res2;
    Eigen::MatrixXd Kl, Kl2;
    local_eval(ps, m, res, Kl);
    double rn = norm(res);
    for (int it = 0; it < opt.local_iterations && rn > 0.1 * opt.residual_tol * fbar; ++it) {
      Eigen::MatrixXd A(nf, nf);
      Eigen::VectorXd b(nf);
      for (int c = 0; c < nf; ++c) {
        b(c) = res(idx[c]);
        for (int d = 0; d < nf; ++d) A(c, d) = Kl(idx[c], idx[d]);
      }
      Eigen::VectorXd step = A.partialPivLu().solve(b);
      if (!step.allFinite()) return;
      // same per-particle limits as the global step
      double scale = 1.0;
      for (int c = 0; c < nf; ++c) {
        const double lim = idx[c] % 3 == 2 ? opt.max_rotation_step : opt.max_step * r_mean;
        if (std::fabs(step(c)) > lim) scale = std::min(scale, lim / std::fabs(step(c)));
      }
      step *= scale;
      double old[6];
      for (int c = 0; c < nf; ++c) old[c] = at(c);
      bool accepted = false;
      for (double alpha = 1.0; alpha > 0.01; alpha *= 0.5) {
        for (int c = 0; c < nf; ++c) at(c) = old[c] + alpha * step(c);
        local_eval(ps, m, res2, Kl2);
        const double rn2 = norm(res2);
        if (rn2 < rn) {
          rn = rn2;
          res = res2;
          Kl = Kl2;
          accepted = true;
          break;
        }
      }
      if (!accepted) {
        for (int c = 0; c < nf; ++c) at(c) = old[c];
        return;
      }
    }
  }

  /// One Gauss-Seidel sweep over the particles whose residual exceeds local_threshold x the RMS
  /// residual (and the tolerance), largest first. With local_pairs, a particle whose most loaded
  /// contact partner is above the threshold too is relaxed together with it (the residual often
  /// sits on a pair with one contact cycling open/closed). Needs f from the current trial state.
  int relax_worst(double fbar, double rms) {
    const double eta_t = std::max(eta, 0.0), eta_r = eta_t * r_mean * r_mean;
    const double thr = std::max(opt.local_threshold * rms, opt.residual_tol) * fbar;
    auto& bad = relax_bad;
    auto& rp = relax_rp;
    bad.clear();
    rp.resize(n);
    for (int p = 0; p < n; ++p) {
      double s2 = 0.0;
      for (int a = 0; a < 3; ++a)
        if (dof[3 * p + a] >= 0) {
          const double rv = f[3 * p + a] - (a == 2 ? eta_r : eta_t) * (du[3 * p + a] - du_aff[3 * p + a]);
          s2 += std::pow(rv / (a == 2 ? r_mean : 1.0), 2);
        }
      rp[p] = std::sqrt(s2);
      if (rp[p] > thr) bad.emplace_back(rp[p], p);
    }
    std::sort(bad.begin(), bad.end(), std::greater<>());
    auto& done = relax_done;
    auto& moved = relax_moved;
    done.assign(n, 0);
    moved.clear();
    for (const auto& b : bad) {
      int ps[2] = {b.second, -1}, m = 1;
      if (done[ps[0]]) continue;
      if (opt.local_pairs) {
        double best = thr;
        for (int q = adj_start[ps[0]]; q < adj_start[ps[0] + 1]; ++q) {
          const int k = adj_pair[q], o = pi[k] == ps[0] ? pj[k] : pi[k];
          if (!done[o] && rp[o] > best && trial[k].branch != ct::NormalBranch::Open) {
            best = rp[o];
            ps[1] = o;
          }
        }
        if (ps[1] >= 0) m = 2;
      }
      relax_set(ps, m, fbar);
      for (int t = 0; t < m; ++t) {
        done[ps[t]] = 1;
        moved.push_back(ps[t]);
      }
    }
    refreshed.resize(pi.size(), 0);
    refresh_particles(moved);  // f and the trial state follow the relaxed du
    return static_cast<int>(bad.size());
  }

  /// Line-search slope: sol . r at the current trial state (r = f_contact - drag on the free DOFs).
  double slope() const {
    const double eta_t = std::max(eta, 0.0), eta_r = eta_t * r_mean * r_mean;
    double sum = 0.0;
    for (int p = 0; p < n; ++p)
      for (int a = 0; a < 3; ++a)
        if (const int d = dof[3 * p + a]; d >= 0)
          sum += sol(d) * (f[3 * p + a] - (a == 2 ? eta_r : eta_t) * (du[3 * p + a] - du_aff[3 * p + a]));
    return sum;
  }

  /// Per-particle step limits: a single soft mode must not freeze the whole network.
  void clip_step() {
    for (int p = 0; p < n; ++p) {
      const int dx = dof[3 * p], dy = dof[3 * p + 1], dr = dof[3 * p + 2];
      if (dx >= 0) {
        const double t = std::hypot(sol(dx), sol(dy)), tl = opt.max_step * r_mean;
        if (t > tl) {
          sol(dx) *= tl / t;
          sol(dy) *= tl / t;
        }
      }
      if (dr >= 0) sol(dr) = std::clamp(sol(dr), -opt.max_rotation_step, opt.max_rotation_step);
    }
  }

  /// Mean translational diagonal of the iteration matrix (rotational if no translation is free).
  double mean_diagonal() const {
    double sum = 0.0, rot = 0.0;
    int c = 0, cr = 0;
    for (int p = 0; p < n; ++p)
      for (int a = 0; a < 3; ++a)
        if (const int d = dof[3 * p + a]; d >= 0) {
          if (a < 2) {
            sum += M.valuePtr()[diag_pos[d]];
            ++c;
          } else {
            rot += M.valuePtr()[diag_pos[d]];
            ++cr;
          }
        }
    if (c > 0 && sum > 0.0) return sum / c;
    if (cr > 0 && rot > 0.0) return rot / cr / (r_mean * r_mean);
    return opt.law.sigma_y;
  }

  /// Adds the viscous drag and the tiny regularisation to the diagonal of K and M.
  void regularise() {
    const double ref = mean_diagonal();
    const double eps = opt.regularisation * ref;
    const double eta_t = std::max(eta, 0.0), eta_r = eta_t * r_mean * r_mean;
    for (int p = 0; p < n; ++p)
      for (int a = 0; a < 3; ++a)
        if (const int d = dof[3 * p + a]; d >= 0) {
          const double add = eps * (a == 2 ? r_mean * r_mean : 1.0) + (a == 2 ? eta_r : eta_t);
          K.valuePtr()[diag_pos[d]] += add;
          M.valuePtr()[diag_pos[d]] += add;
        }
  }
};

NetworkSolver::NetworkSolver(const packing::Packing& pk, const SolverOptions& options) : impl_(std::make_unique<Impl>()) {
  options.validate();
  packing::validate(pk);
  auto& s = *impl_;
  s.opt = options;
  LinearSolverOptions lo;
  lo.gmres_tolerance = options.linear_tolerance;
  s.lin = LinearSolver(lo);
  s.n = static_cast<int>(pk.size());
  s.x = pk.x;
  s.y = pk.y;
  s.r = pk.r;
  s.th.assign(s.n, 0.0);
  s.periph = packing::peripheral_layer(pk);
  s.solid_area = pk.solid_area();
  s.box_area0 = pk.box.area();
  s.D0 = s.solid_area / s.box_area0;
  s.r_mean = std::accumulate(s.r.begin(), s.r.end(), 0.0) / s.n;
  s.r_max = *std::max_element(s.r.begin(), s.r.end());
  s.build_dofs();
  {
    std::vector<int> particle_of_dof(static_cast<std::size_t>(s.nfree));
    for (int q = 0; q < 3 * s.n; ++q)
      if (s.dof[q] >= 0) particle_of_dof[s.dof[q]] = q / 3;
    s.lin.set_row_blocks(std::move(particle_of_dof));
  }
  s.du.assign(3 * s.n, 0.0);
  s.f.assign(3 * s.n, 0.0);
  s.f_c.assign(3 * s.n, 0.0);
  s.build_neighbours();
}

NetworkSolver::~NetworkSolver() = default;

IncrementReport NetworkSolver::increment(const Eigen::Matrix2d& dE) {
  if (!dE.allFinite()) throw std::runtime_error("increment: strain increment is not finite");
  return substep(dE, 0);
}

// Adaptive sub-stepping: an increment that does not converge is restarted from the committed
// state as two halves (recursively, up to max_cuts levels); the deepest level is accepted as it
// is (its residual is carried, as without sub-stepping). The next call starts at full size again.
IncrementReport NetworkSolver::substep(const Eigen::Matrix2d& dE, int depth) {
  const bool last_level = depth >= impl_->opt.max_cuts;
  IncrementReport rep = attempt(dE, last_level);
  if (rep.converged || last_level) return rep;
  IncrementReport a = substep(0.5 * dE, depth + 1);
  IncrementReport b = substep(0.5 * dE, depth + 1);
  IncrementReport out = b;
  out.newton_iterations = rep.newton_iterations + a.newton_iterations + b.newton_iterations;
  out.linear_iterations = rep.linear_iterations + a.linear_iterations + b.linear_iterations;
  out.converged = a.converged && b.converged;
  out.residual = std::max(a.residual, b.residual);
  out.residual_rms = std::max(a.residual_rms, b.residual_rms);
  out.newton_residual = std::max(a.newton_residual, b.newton_residual);
  out.reanalysed = rep.reanalysed || a.reanalysed || b.reanalysed;
  out.new_contacts = a.new_contacts + b.new_contacts;
  out.lost_contacts = a.lost_contacts + b.lost_contacts;
  out.cuts = 1 + a.cuts + b.cuts;
  out.substeps = a.substeps + b.substeps;
  return out;
}

IncrementReport NetworkSolver::attempt(const Eigen::Matrix2d& dE, bool accept_unconverged) {
  auto& s = *impl_;
  const auto t_start = Clock::now();
  IncrementReport rep;
  if (s.needs_rebuild()) {
    s.build_neighbours();
    rep.reanalysed = true;
  }
  const std::size_t np = s.pi.size();
  s.g0.resize(np);
  s.trial.resize(np);
  s.trial_slip.resize(np);
  for (std::size_t k = 0; k < np; ++k) {
    const int i = s.pi[k], j = s.pj[k];
    s.g0[k] = ct::pair_geometry(ct::Vec(s.x[i], s.y[i]), ct::Vec(s.x[j], s.y[j]), s.r[i], s.r[j]);
  }
  // prescribed motion (Eqs 14-15 on current coordinates) = the affine motion of the increment
  const Eigen::Matrix2d A = small_expm(dE) - Eigen::Matrix2d::Identity();
  s.du_aff.assign(3 * s.n, 0.0);
  for (int p = 0; p < s.n; ++p) {
    const Eigen::Vector2d u = A * Eigen::Vector2d(s.x[p], s.y[p]);
    s.du_aff[3 * p] = u.x();
    s.du_aff[3 * p + 1] = u.y();
  }
  // predictor for the free DOFs: the previous increment's displacement (scaled) on an unchanged
  // strain path, else the affine motion
  const double dn = dE.norm(), dpn = s.dE_prev.norm();
  const bool reuse = !s.du_prev.empty() && dpn > 0.0 && dn > 0.0 &&
                     (dE.array() * s.dE_prev.array()).sum() / (dn * dpn) > 0.999;
  const double scale = reuse ? dn / dpn : 0.0;
  for (int q = 0; q < 3 * s.n; ++q) s.du[q] = (s.dof[q] >= 0 && reuse) ? scale * s.du_prev[q] : s.du_aff[q];
  s.last_sliding.assign(np, 0);
  s.flips.assign(np, 0);
  s.last_open.assign(np, 0);
  s.open_flips.assign(np, 0);
  s.last_kn.assign(np, 0.0);
  s.last_plastic.assign(np, 2);
  s.pe_flips.assign(np, 0);
  for (std::size_t k = 0; k < np; ++k) {
    s.last_sliding[k] = s.slide_c[k];
    s.last_open[k] = s.fn_c[k] > 0.0 ? 0 : 1;
  }
  s.rhs.resize(s.nfree);
  s.sol.resize(s.nfree);
  // Viscous regularisation (pseudo-time): the free DOFs feel a drag eta (du - du_affine) relative
  // to the affine motion, so mechanisms and collapsing regions get a finite stiffness eta and
  // move at a finite rate instead of making the tangent singular. Homogeneous (affine) motion is
  // not resisted, and the drag vanishes as the increments shrink; its size, max|f_contact| /
  // mean contact force, is reported as the unbalanced force of the increment.
  s.eta = -1.0;
  double eta_target = 0.0, eta_floor = 0.0;
  double fbar = 1.0;
  bool f_valid = false;  // f, pf and the trial state belong to the current du
  for (int it = 0;; ++it) {
    const bool want_tangent = it < s.opt.max_newton;
    // chord steps: between fresh tangents, iterations reuse the last assembled K and its factor
    const bool fresh = s.opt.chord_steps <= 0 || it % (s.opt.chord_steps + 1) == 0;
    bool nonsym = false;
    auto ta = Clock::now();
    const bool assemble = want_tangent && s.nfree > 0 && fresh;
    if (assemble || !f_valid) {
      s.evaluate(assemble, nonsym);
    } else {  // a chord step from a state the line search and the local sweep left current
      nonsym = s.opt.law.frictional() || s.opt.geometric_stiffness;
    }
    s.tim.assemble += seconds_since(ta);
    if (s.eta < 0.0 && want_tangent && s.nfree > 0) {
      // viscosity continuation: start at viscosity_start, reduce by viscosity_decay per Newton
      // iteration down to the target viscosity; only the target counts as converged
      const double md = s.mean_diagonal();
      s.kl_ref = md;
      eta_target = s.opt.viscosity * md;
      if (s.opt.viscosity_strain > 0.0 && dE.norm() > 0.0) eta_target *= s.opt.viscosity_strain / dE.norm();
      eta_floor = 1e-6 * md;
      s.eta = std::max(eta_target, s.opt.viscosity_start * md);
    }
    fbar = s.mean_normal_force();
    if (fbar <= 0.0) fbar = s.opt.law.sigma_y * s.r_mean * 1e-6;
    double newton_max = 0.0;
    const double newton_res = s.nfree > 0 ? s.residual(fbar, true, &newton_max) : 0.0;  // RMS
    rep.newton_residual = newton_res;
    if (!std::isfinite(newton_res))
      throw std::runtime_error("increment: non-finite contact forces (diverged Newton iteration)");
    if (s.opt.verbose) {
      int tr[3][3] = {}, ss = 0;
      if (it == 0) s.diag_branch.assign(np, 0);
      for (std::size_t k = 0; k < np; ++k) {
        const int b = static_cast<int>(s.trial[k].branch), sl = s.trial[k].sliding ? 1 : 0;
        const int ob = s.diag_branch[k] & 3, osl = s.diag_branch[k] >> 2;
        if (it > 0) {
          if (ob != b) ++tr[ob][b];
          if (b != 0 && ob != 0 && sl != osl) ++ss;
        }
        s.diag_branch[k] = static_cast<std::uint8_t>(b + 4 * sl);
      }
      std::fprintf(stderr,
                   "  iteration %d: residual rms %.3e max %.3e (mean contact force %.3e) O>P %d O>E %d P>O %d P>E %d "
                   "E>O %d E>P %d stick/slip %d\n",
                   it, newton_res, newton_max, fbar, tr[0][1], tr[0][2], tr[1][0], tr[1][2], tr[2][0], tr[2][1], ss);
    }
    const bool at_target = s.eta <= eta_target * (1.0 + 1e-12);
    if ((at_target && newton_res <= s.opt.residual_tol && newton_max <= s.opt.max_residual_tol) || s.nfree == 0) {
      rep.converged = true;
      break;
    }
    if (!want_tangent) break;
    LinearStatus st;
    if (fresh) {
      s.regularise();
      st = s.lin.factorise(s.M, s.pattern_changed);
      s.pattern_changed = false;
      if (!st.ok) throw std::runtime_error("increment: " + st.message);
    }
    st = nonsym ? s.lin.solve(s.K, s.rhs, s.sol) : s.lin.solve(s.rhs, s.sol);
    if (!st.ok) {
      // GMRES hit its cap: fall back to the symmetric slip-status tangent (defect correction)
      st = s.lin.solve(s.rhs, s.sol);
      if (!st.ok) throw std::runtime_error("increment: " + st.message);
    }
    rep.linear_iterations += st.iterations;
    s.clip_step();
    double alpha = 1.0;
    // f and trial are those of the current du after the line search unless it went back to an
    // earlier step (then the local sweep re-evaluates)
    bool f_current = true;
    s.du_start = s.du;
    auto apply = [&](double a) {
      for (int p = 0; p < s.n; ++p)
        for (int c = 0; c < 3; ++c)
          if (const int d = s.dof[3 * p + c]; d >= 0) s.du[3 * p + c] = s.du_start[3 * p + c] + a * s.sol(d);
    };
    // slope s(a) = step . r(du + a step) = -dE/da, where E is the incremental potential
    // (frictionless: the contact potentials plus the drag; with friction a work-like merit)
    const double s0 = s.slope();
    if (s.opt.line_search == LineSearch::Energy && s0 > 0.0) {
      // Crisfield's line search: a zero of s(a) on [0, 1] by safeguarded regula falsi; accept the
      // full step while the merit still decreases there. Unlike the residual norm, the merit is
      // smooth across contact opening/closing, and a symmetric positive iteration matrix always
      // gives a descent direction.
      double a_lo = 0.0, s_lo = s0, a_hi = -1.0, s_hi = 0.0;
      for (int ls = 0; ls < s.opt.line_search_max; ++ls) {
        apply(alpha);
        bool dummy;
        s.evaluate(false, dummy);
        const double sa = s.slope();
        if (std::fabs(sa) <= s.opt.line_search_tol * s0 || (sa > 0.0 && a_hi < 0.0)) break;
        if (sa > 0.0) {
          a_lo = alpha;
          s_lo = sa;
        } else {
          a_hi = alpha;
          s_hi = sa;
        }
        const double w = a_hi - a_lo;
        alpha = std::clamp(a_lo + w * s_lo / (s_lo - s_hi), a_lo + 0.05 * w, a_hi - 0.05 * w);
      }
    } else {
      // backtracking line search on the RMS residual: the first step that lowers it, else the
      // best step tried
      const double r_before = newton_res;
      double best_alpha = 1.0, best_r = std::numeric_limits<double>::infinity();
      for (int ls = 0; ls < s.opt.backtracks; ++ls, alpha *= 0.5) {
        apply(alpha);
        bool dummy;
        s.evaluate(false, dummy);
        const double r = s.residual(std::max(s.mean_normal_force(), 1e-300), false);
        if (r < best_r) {
          best_r = r;
          best_alpha = alpha;
        }
        if (r < r_before) break;
      }
      if (best_alpha != alpha || best_r >= r_before) {
        alpha = best_alpha;
        apply(alpha);
        f_current = false;  // f and trial belong to the last step tried, not to best_alpha
      }
    }
    if (s.opt.verbose) std::fprintf(stderr, "    line search step %.4f\n", alpha);
    for (int sweep = 0; sweep < s.opt.local_sweeps; ++sweep) {
      // nonlinear Gauss-Seidel on the worst particles (the global step has just been taken)
      if (!f_current) {
        bool dummy;
        s.evaluate(false, dummy);
        f_current = true;
      }
      const double fb = std::max(s.mean_normal_force(), 1e-300);
      const double rms = s.residual(fb, false);
      const int relaxed = s.relax_worst(fb, rms);
      if (s.opt.verbose) std::fprintf(stderr, "    local relaxation: %d particles\n", relaxed);
      if (relaxed == 0) break;
    }
    f_valid = f_current;  // relax_worst refreshes the pairs of the particles it moved
    ++rep.newton_iterations;
    if (s.eta > eta_target) {
      s.eta *= s.opt.viscosity_decay;
      if (s.eta <= eta_target * 1.0001 || s.eta < eta_floor) s.eta = eta_target;
    }
  }
  rep.residual = s.nfree > 0 ? s.unbalance(fbar, &rep.residual_rms) : 0.0;
  if (s.opt.verbose && s.nfree > 0) s.print_worst(fbar);
  if (!rep.converged && !accept_unconverged) {  // the caller cuts the increment: nothing is committed
    s.tim.newton_iterations += rep.newton_iterations;
    s.tim.total += seconds_since(t_start);
    if (s.opt.verbose) std::fprintf(stderr, "  increment not converged: cut\n");
    return rep;
  }
  // commit
  const Eigen::Matrix2d E_old = s.E;
  for (std::size_t k = 0; k < np; ++k) {
    const auto& t = s.trial[k];
    const bool was_loaded = s.fn_c[k] > 0.0;
    const bool loaded = t.branch != ct::NormalBranch::Open;
    if (loaded && s.hist[k].u_max <= 0.0) {  // first touch: start the affine-deviation bookkeeping
      s.aux[k] = PairAux{};
      s.aux[k].E_form = E_old;
    }
    if (loaded && !was_loaded) ++rep.new_contacts;
    if (!loaded && was_loaded) ++rep.lost_contacts;
    if (loaded || s.hist[k].u_max > 0.0) {
      s.hist[k] = t.history;
      s.aux[k].slip += s.trial_slip[k];
      // tangential displacement of the centres, L dphi (only needed here: not in evaluate())
      const int i = s.pi[k], j = s.pj[k];
      const ct::PairGeometry& g = s.g0[k];
      const ct::PairGeometry g1 =
          ct::pair_geometry(ct::Vec(s.x[i] + s.du[3 * i], s.y[i] + s.du[3 * i + 1]),
                            ct::Vec(s.x[j] + s.du[3 * j], s.y[j] + s.du[3 * j + 1]), s.r[i], s.r[j]);
      s.aux[k].centre += std::atan2(ct::cross(g.n, g1.n), g.n.dot(g1.n)) * 0.5 * (g.L + g1.L);
    }
    s.fn_c[k] = t.f_n;
    s.ft_c[k] = t.f_t;
    s.slide_c[k] = t.sliding ? 1 : 0;
    rep.sliding += t.sliding;
  }
  for (int p = 0; p < s.n; ++p) {
    s.x[p] += s.du[3 * p];
    s.y[p] += s.du[3 * p + 1];
    s.th[p] += s.du[3 * p + 2];
  }
  s.f_c = s.f;
  s.E += dE;
  s.Fbox = small_expm(dE) * s.Fbox;
  s.du_prev = s.du;
  s.dE_prev = dE;
  const auto& ls = s.lin.stats();
  s.tim.analyses = ls.analyses;
  s.tim.factorisations = ls.factorisations;
  s.tim.solves = ls.solves;
  s.tim.analyse = ls.t_analyse;
  s.tim.factorise = ls.t_factorise;
  s.tim.solve = ls.t_solve;
  s.tim.increments += 1;
  s.tim.newton_iterations += rep.newton_iterations;
  s.tim.total += seconds_since(t_start);
  return rep;
}

void NetworkSolver::set_reversible_normal(bool reversible) {
  auto& s = *impl_;
  if (!reversible && s.opt.law.reversible) {
    for (std::size_t k = 0; k < s.pi.size(); ++k) {
      const int i = s.pi[k], j = s.pj[k];
      const double u =
          ct::pair_geometry(ct::Vec(s.x[i], s.y[i]), ct::Vec(s.x[j], s.y[j]), s.r[i], s.r[j]).overlap;
      s.hist[k].u_max = std::max(u, 0.0);
      if (u <= 0.0) {
        s.hist[k].f_t = 0.0;
        s.hist[k].sliding = 0;
      }
    }
  }
  s.opt.law.reversible = reversible;
}

StateMeasures NetworkSolver::measures() const {
  const auto& s = *impl_;
  StateMeasures m;
  m.E11 = s.E(0, 0);
  m.E22 = s.E(1, 1);
  m.E12 = s.E(0, 1);
  const double V = s.box_area0 * s.Fbox.determinant();
  m.density = s.solid_area / V;
  // Eq 13: reactions of the prescribed particles (translational DOFs prescribed)
  Eigen::Matrix2d S = Eigen::Matrix2d::Zero();
  for (int p = 0; p < s.n; ++p) {
    if (s.dof[3 * p] >= 0) continue;
    const Eigen::Vector2d Fapp(-s.f_c[3 * p], -s.f_c[3 * p + 1]);
    S += Fapp * Eigen::Vector2d(s.x[p], s.y[p]).transpose();
  }
  S /= V;
  m.S11 = S(0, 0);
  m.S22 = S(1, 1);
  m.S12 = 0.5 * (S(0, 1) + S(1, 0));
  m.S_asym = 0.5 * (S(0, 1) - S(1, 0));
  // Love-Weber average over the contacts and the affine-deviation measures
  Eigen::Matrix2d SC = Eigen::Matrix2d::Zero();
  double sum_ratio = 0, sum_absdev = 0, sum_una = 0, sum_tc = 0, sum_tr = 0, sum_ta = 0;
  int n_ratio = 0, loaded = 0;
  double sum_fn = 0;
  for (std::size_t k = 0; k < s.pi.size(); ++k) {
    if (s.fn_c[k] <= 0.0) continue;
    const int i = s.pi[k], j = s.pj[k];
    const auto g = ct::pair_geometry(ct::Vec(s.x[i], s.y[i]), ct::Vec(s.x[j], s.y[j]), s.r[i], s.r[j]);
    const Eigen::Vector2d fj = s.fn_c[k] * g.n + s.ft_c[k] * g.t;
    SC -= fj * (g.L * g.n).transpose();
    ++loaded;
    sum_fn += s.fn_c[k];
    m.sliding += s.slide_c[k];
    // Eq 16 with the strain accumulated since the contact formed
    const Eigen::Matrix2d dEc = s.E - s.aux[k].E_form;
    const double Rsum = s.r[i] + s.r[j];
    const double una = -(g.n.dot(dEc * g.n)) * Rsum;
    const double uta = g.t.dot(dEc * g.n) * Rsum;
    const double un = g.overlap;
    sum_absdev += std::fabs(un - una);
    sum_una += una;
    if (una > 1e-12 * s.r_mean) {
      sum_ratio += std::fabs(un - una) / una;
      ++n_ratio;
    }
    sum_tc += std::fabs(s.aux[k].centre - uta);
    sum_tr += std::fabs(s.aux[k].slip - uta);
    sum_ta += std::fabs(uta);
  }
  SC /= V;
  m.S11_contacts = SC(0, 0);
  m.S22_contacts = SC(1, 1);
  m.S12_contacts = 0.5 * (SC(0, 1) + SC(1, 0));
  if (loaded == 0) {  // initial state: count geometric contacts
    for (std::size_t k = 0; k < s.pi.size(); ++k) {
      const int i = s.pi[k], j = s.pj[k];
      const double L = std::hypot(s.x[j] - s.x[i], s.y[j] - s.y[i]);
      if (L <= (s.r[i] + s.r[j]) * (1.0 + 1e-6)) ++loaded;
    }
  }
  m.contacts = loaded;
  m.Z = 2.0 * loaded / s.n;
  m.mean_normal_force = loaded > 0 ? sum_fn / loaded : 0.0;
  const int nl = std::max(loaded, 1);
  const double una_mean = sum_una / nl;
  m.dev_normal_mean_ratio = n_ratio > 0 ? sum_ratio / n_ratio : 0.0;
  m.dev_normal_ratio_of_means = una_mean > 0 ? (sum_absdev / nl) / una_mean : 0.0;
  m.dev_tangential_centres = una_mean > 0 ? (sum_tc / nl) / una_mean : 0.0;
  m.dev_tangential_rotations = una_mean > 0 ? (sum_tr / nl) / una_mean : 0.0;
  m.affine_tangential = una_mean > 0 ? (sum_ta / nl) / una_mean : 0.0;
  return m;
}

const SolverTimings& NetworkSolver::timings() const { return impl_->tim; }
std::size_t NetworkSolver::size() const { return static_cast<std::size_t>(impl_->n); }
const std::vector<double>& NetworkSolver::x() const { return impl_->x; }
const std::vector<double>& NetworkSolver::y() const { return impl_->y; }
const std::vector<double>& NetworkSolver::theta() const { return impl_->th; }
const std::vector<double>& NetworkSolver::radius() const { return impl_->r; }
const std::vector<std::uint8_t>& NetworkSolver::peripheral() const { return impl_->periph; }
Eigen::Matrix2d NetworkSolver::box_deformation() const { return impl_->Fbox; }
double NetworkSolver::solid_area() const { return impl_->solid_area; }
double NetworkSolver::initial_density() const { return impl_->D0; }
int NetworkSolver::free_dofs() const { return impl_->nfree; }

std::vector<ContactView> NetworkSolver::contacts() const {
  const auto& s = *impl_;
  std::vector<ContactView> out;
  for (std::size_t k = 0; k < s.pi.size(); ++k) {
    if (s.fn_c[k] <= 0.0) continue;
    const int i = s.pi[k], j = s.pj[k];
    const double L = std::hypot(s.x[j] - s.x[i], s.y[j] - s.y[i]);
    out.push_back({i, j, s.fn_c[k], s.ft_c[k], s.r[i] + s.r[j] - L, s.slide_c[k] != 0});
  }
  return out;
}

}  // namespace netdem::qs
