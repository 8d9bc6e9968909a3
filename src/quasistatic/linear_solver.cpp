#include "netdem/quasistatic/linear_solver.hpp"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <cholmod.h>
#include <fmt/format.h>

#include "cholmod_omp.hpp"

#include <Eigen/SparseCore>

namespace netdem::qs {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

const char* cholmod_status_name(int status) {
  switch (status) {
    case CHOLMOD_NOT_INSTALLED: return "method not installed (CHOLMOD built without the Partition module?)";
    case CHOLMOD_OUT_OF_MEMORY: return "out of memory";
    case CHOLMOD_TOO_LARGE: return "problem too large (integer overflow)";
    case CHOLMOD_INVALID: return "invalid input";
    case CHOLMOD_GPU_PROBLEM: return "GPU problem";
    case CHOLMOD_NOT_POSDEF: return "not positive definite";
    case CHOLMOD_DSMALL: return "tiny diagonal entry";
    default: return "unknown status";
  }
}

LinearStatus failure(std::string message) {
  LinearStatus st;
  st.ok = false;
  st.message = std::move(message);
  return st;
}

/// Index (row, col) of the first non-finite stored value of a compressed matrix, or (-1, -1).
std::pair<int, int> first_non_finite(const SpMat& A) {
  // vectorised test first (called on every factorisation and solve); the search only on failure
  if (Eigen::Map<const VecX>(A.valuePtr(), A.nonZeros()).allFinite()) return {-1, -1};
  for (int j = 0; j < A.outerSize(); ++j)
    for (SpMat::InnerIterator it(A, j); it; ++it)
      if (!std::isfinite(it.value())) return {static_cast<int>(it.row()), j};
  return {-1, -1};
}

bool same_pattern(const SpMat& a, const SpMat& b) {  // both compressed
  if (a.rows() != b.rows() || a.cols() != b.cols() || a.nonZeros() != b.nonZeros()) return false;
  const auto n1 = static_cast<std::size_t>(a.outerSize()) + 1;
  const auto nnz = static_cast<std::size_t>(a.nonZeros());
  // std::equal (not memcmp): empty ranges with null pointers are well defined.
  return std::equal(a.outerIndexPtr(), a.outerIndexPtr() + n1, b.outerIndexPtr()) &&
         std::equal(a.innerIndexPtr(), a.innerIndexPtr() + nnz, b.innerIndexPtr());
}

bool same_values(const SpMat& a, const SpMat& b) {  // same pattern, both compressed
  const auto nnz = static_cast<std::size_t>(a.nonZeros());
  return std::equal(a.valuePtr(), a.valuePtr() + nnz, b.valuePtr());
}

int first_non_finite_row(const VecX& v) {
  for (Eigen::Index i = 0; i < v.size(); ++i)
    if (!std::isfinite(v[i])) return static_cast<int>(i);
  return -1;
}

using detail::SerialCholmod;  // cholmod_omp.hpp: CHOLMOD's OpenMP regions inline inside our calls

}  // namespace
}  // namespace netdem::qs


namespace netdem::qs {

void LinearSolverOptions::validate() const {
  auto require = [](bool ok, const std::string& msg) {
    if (!ok) throw std::invalid_argument("LinearSolverOptions: " + msg);
  };
  require(ordering == Ordering::Auto || ordering == Ordering::Amd || ordering == Ordering::Nesdis,
          "ordering must be Auto, Amd or Nesdis");
  require(std::isfinite(gmres_tolerance) && gmres_tolerance > 0.0 && gmres_tolerance < 1.0,
          fmt::format("gmres_tolerance must be in (0, 1), got {}", gmres_tolerance));
  require(gmres_max_iterations >= 1,
          fmt::format("gmres_max_iterations must be >= 1, got {}", gmres_max_iterations));
  require(gmres_restart >= 1, fmt::format("gmres_restart must be >= 1, got {}", gmres_restart));
  require(std::isfinite(pivot_tolerance) && pivot_tolerance >= 0.0 && pivot_tolerance < 1.0,
          fmt::format("pivot_tolerance must be in [0, 1), got {}", pivot_tolerance));
}

// ------------------------------------------------------------------------------------------------
// Impl: owns the cholmod_common, the factor and the solve workspace.
//
// The CHOLMOD C API is used directly (not Eigen's CholmodSupernodalLLT) because it gives
// L->minor and L->Perm for the diagnostic message, lets us force the supernodal LL' method and
// the ordering, and cholmod_solve2 reuses its workspace across the many preconditioner
// applications of GMRES (Eigen's wrapper allocates a cholmod_dense per solve).
struct LinearSolver::Impl {
  LinearSolverOptions opt;
  LinearSolverStats stats;
  cholmod_common cm{};
  cholmod_factor* L = nullptr;
  cholmod_dense* X = nullptr;  // cholmod_solve2 output / workspace (reused)
  cholmod_dense* Y = nullptr;
  cholmod_dense* E = nullptr;
  SpMat M;          // compressed copy of the last factorised matrix (pattern + values)
  VecX diag;        // diagonal of M (for the pivot-tolerance check)
  bool analysed = false;      // L holds a symbolic analysis of M's pattern
  bool factor_valid = false;  // L holds a valid numeric factor of M
  Eigen::MatrixXd V;          // GMRES Krylov basis (kept between solves to avoid reallocation)
  Eigen::MatrixXd Z;          // GMRES preconditioned vectors M^-1 v_j (x += Z y without another solve)
  // tril(P M P') in CSC form with sorted rows (the matrix cholmod_factorize builds from M on every
  // call with two transposes); built once per analysis, refilled by a gather through smap
  std::vector<int> Sp, Si, smap;
  std::vector<double> Sx;
  std::vector<int> blocks;  // row -> block (node) for the nested-dissection ordering; empty: rows

  /// Nested-dissection ordering (METIS) of the block (node) graph of M, expanded to its rows in block
  /// order (a block's rows stay together, in increasing order). Empty if there are no blocks.
  std::vector<int> block_ordering() {
    const int nn = n();
    if (static_cast<int>(blocks.size()) != nn || nn == 0) return {};
    const int nb = *std::max_element(blocks.begin(), blocks.end()) + 1;
    std::vector<int> bstart(nb + 1, 0), brows(nn);
    for (const int b : blocks) ++bstart[b + 1];
    for (int b = 0; b < nb; ++b) bstart[b + 1] += bstart[b];
    {
      std::vector<int> at(bstart.begin(), bstart.end() - 1);
      for (int r = 0; r < nn; ++r) brows[at[blocks[r]]++] = r;
    }
    // lower triangle of the block graph (row block >= column block), pattern only
    std::vector<int> Qp(nb + 1, 0), Qi, mark(nb, -1);
    const int* Mp = M.outerIndexPtr();
    const int* Mi = M.innerIndexPtr();
    for (int bc = 0; bc < nb; ++bc) {
      const auto first = Qi.size();
      for (int t = bstart[bc]; t < bstart[bc + 1]; ++t) {
        const int c = brows[t];
        for (int q = Mp[c]; q < Mp[c + 1]; ++q) {
          const int br = blocks[Mi[q]];
          if (br >= bc && mark[br] != bc) {
            mark[br] = bc;
            Qi.push_back(br);
          }
        }
      }
      std::sort(Qi.begin() + static_cast<std::ptrdiff_t>(first), Qi.end());
      Qp[bc + 1] = static_cast<int>(Qi.size());
    }
    cholmod_sparse Q = lower_view(nb, Qi.size(), Qp.data(), Qi.data(), nullptr);
    Q.xtype = CHOLMOD_PATTERN;
    // METIS_NodeND on the block graph (no postorder: the analysis of M postorders)
    std::vector<int> bp(static_cast<std::size_t>(nb));
    if (!cholmod_metis(&Q, nullptr, 0, 0, bp.data(), &cm)) return {};
    std::vector<int> perm;
    perm.reserve(static_cast<std::size_t>(nn));
    for (int k = 0; k < nb; ++k)
      for (int t = bstart[bp[k]]; t < bstart[bp[k] + 1]; ++t) perm.push_back(brows[t]);
    return perm;
  }

  explicit Impl(const LinearSolverOptions& o) : opt(o) {
    cholmod_start(&cm);
    cm.print = 0;                         // failures are reported through LinearStatus
    cm.supernodal = CHOLMOD_SUPERNODAL;   // LL' always: reports singularity reliably (notes §1.6)
    cm.quick_return_if_not_posdef = 1;    // stop at the first failed supernode
  }
  ~Impl() {
    cholmod_free_factor(&L, &cm);
    cholmod_free_dense(&X, &cm);
    cholmod_free_dense(&Y, &cm);
    cholmod_free_dense(&E, &cm);
    cholmod_finish(&cm);
  }
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;

  [[nodiscard]] int n() const { return static_cast<int>(M.rows()); }

  /// Non-owning CHOLMOD view of a square compressed-column matrix whose lower triangle is used
  /// (stype = -1, sorted and packed).
  static cholmod_sparse lower_view(int n, std::size_t nz, int* p, int* i, double* x) {
    cholmod_sparse A{};
    A.nrow = A.ncol = static_cast<size_t>(n);
    A.nzmax = nz;
    A.p = p;
    A.i = i;
    A.x = x;
    A.stype = -1;
    A.itype = CHOLMOD_INT;
    A.xtype = CHOLMOD_REAL;
    A.dtype = CHOLMOD_DOUBLE;
    A.sorted = 1;
    A.packed = 1;
    return A;
  }

  /// Non-owning CHOLMOD view of M.
  cholmod_sparse view() {
    return lower_view(n(), static_cast<std::size_t>(M.nonZeros()), M.outerIndexPtr(), M.innerIndexPtr(), M.valuePtr());
  }

  void set_ordering() {
    using O = LinearSolverOptions::Ordering;
    const O o = opt.ordering == O::Auto ? (n() >= 200000 ? O::Nesdis : O::Auto) : opt.ordering;
    if (o == O::Auto) {
      cm.nmethods = 0;  // CHOLMOD default: AMD, METIS only if AMD's fill is poor
    } else {
      cm.nmethods = 1;
      cm.method[0].ordering = o == O::Amd ? CHOLMOD_AMD : CHOLMOD_NESDIS;
    }
  }

  /// out = M^{-1} in (n doubles each; in may alias out).
  bool apply_factor(const double* in, double* out) {
    cholmod_dense B{};
    B.nrow = static_cast<size_t>(n());
    B.ncol = 1;
    B.nzmax = B.nrow;
    B.d = B.nrow;
    B.x = const_cast<double*>(in);  // NOLINT: read-only in cholmod_solve2
    B.z = nullptr;
    B.xtype = CHOLMOD_REAL;
    B.dtype = CHOLMOD_DOUBLE;
    const SerialCholmod serial;
    if (!cholmod_solve2(CHOLMOD_A, L, &B, nullptr, &X, nullptr, &Y, &E, &cm)) return false;
    const auto* xs = static_cast<const double*>(X->x);
    std::copy(xs, xs + n(), out);
    return true;
  }

  LinearStatus factorise(const SpMat& Min, bool pattern_changed);
  void build_permuted();
  LinearStatus direct_solve(const VecX& b, VecX& x);
  LinearStatus gmres(const SpMat& A, const VecX& b, VecX& x);
  /// nnz(L) from the symbolic factor: supernodal -> lower trapezoid of each supernode.
  [[nodiscard]] long factor_nnz() const {
    long nz = 0;
    if (L->is_super) {
      const auto* super = static_cast<const int*>(L->super);
      const auto* pi = static_cast<const int*>(L->pi);
      for (size_t s = 0; s < L->nsuper; ++s) {
        const long nscol = super[s + 1] - super[s], nsrow = pi[s + 1] - pi[s];
        nz += nscol * nsrow - nscol * (nscol - 1) / 2;
      }
    } else {
      const auto* cnt = static_cast<const int*>(L->ColCount);
      for (size_t k = 0; k < L->n; ++k) nz += cnt[k];
    }
    return nz;
  }
  /// Pivot-tolerance check on the diagonal of L; returns the permuted column or -1.
  int small_pivot(double& ratio) const;
};

int LinearSolver::Impl::small_pivot(double& ratio) const {
  if (opt.pivot_tolerance <= 0.0) return -1;
  const int nn = n();
  const auto* Lx = static_cast<const double*>(L->x);
  const auto* perm = static_cast<const int*>(L->Perm);
  auto check = [&](int k, double pivot) {  // pivot = L_kk^2 (LL') or D_kk (LDL')
    const double a = diag[perm[k]];
    if (pivot <= opt.pivot_tolerance * std::abs(a)) {
      ratio = a != 0.0 ? pivot / std::abs(a) : 0.0;
      return true;
    }
    return false;
  };
  if (L->is_super) {
    const auto* super = static_cast<const int*>(L->super);
    const auto* pi = static_cast<const int*>(L->pi);
    const auto* px = static_cast<const int*>(L->px);
    for (size_t s = 0; s < L->nsuper; ++s) {
      const int k1 = super[s], k2 = super[s + 1];
      const int nsrow = pi[s + 1] - pi[s];
      for (int jj = 0; jj < k2 - k1; ++jj) {
        const double lkk = Lx[px[s] + static_cast<std::ptrdiff_t>(jj) * nsrow + jj];
        if (check(k1 + jj, lkk * lkk)) return k1 + jj;
      }
    }
  } else {
    const auto* Lp = static_cast<const int*>(L->p);
    for (int k = 0; k < nn; ++k) {
      const double d = Lx[Lp[k]];
      if (check(k, L->is_ll ? d * d : d)) return k;
    }
  }
  return -1;
}

void LinearSolver::Impl::build_permuted() {
  Sp.clear();
  Si.clear();
  Sx.clear();
  smap.clear();
  if (L == nullptr || !L->is_super || n() == 0) return;
  const int nn = n();
  const auto* perm = static_cast<const int*>(L->Perm);
  std::vector<int> inv(nn);
  for (int k = 0; k < nn; ++k) inv[perm[k]] = k;
  // entry (i, j), i >= j, of the stored lower triangle goes to permuted (max, min) of (inv i, inv j);
  // bucketed by permuted column (counting sort), then each column's rows sorted
  const int* Mp = M.outerIndexPtr();
  const int* Mi = M.innerIndexPtr();
  Sp.assign(nn + 1, 0);
  for (int j = 0; j < nn; ++j)
    for (int q = Mp[j]; q < Mp[j + 1]; ++q)
      if (Mi[q] >= j) ++Sp[std::min(inv[Mi[q]], inv[j]) + 1];
  for (int c = 0; c < nn; ++c) Sp[c + 1] += Sp[c];
  std::vector<std::pair<int, int>> entry(static_cast<std::size_t>(Sp[nn]));  // (permuted row, q)
  {
    std::vector<int> at(Sp.begin(), Sp.end() - 1);
    for (int j = 0; j < nn; ++j)
      for (int q = Mp[j]; q < Mp[j + 1]; ++q) {
        const int i = Mi[q];
        if (i < j) continue;
        const int a = inv[i], b = inv[j];
        entry[static_cast<std::size_t>(at[std::min(a, b)]++)] = {std::max(a, b), q};
      }
  }
  Si.resize(entry.size());
  smap.resize(entry.size());
  for (int c = 0; c < nn; ++c) {
    std::sort(entry.begin() + Sp[c], entry.begin() + Sp[c + 1]);
    for (int t = Sp[c]; t < Sp[c + 1]; ++t) {
      Si[t] = entry[t].first;
      smap[t] = entry[t].second;
    }
  }
  Sx.assign(smap.size(), 0.0);
}

LinearStatus LinearSolver::Impl::factorise(const SpMat& Min, bool pattern_changed) {
  if (Min.rows() != Min.cols())
    throw std::invalid_argument(
        fmt::format("LinearSolver::factorise: matrix must be square, got {}x{}", Min.rows(), Min.cols()));
  SpMat compressed;
  const SpMat* src = &Min;
  if (!Min.isCompressed()) {
    compressed = Min;
    compressed.makeCompressed();
    src = &compressed;
  }
  factor_valid = false;
  const bool reanalyse = pattern_changed || !analysed || !same_pattern(*src, M);
  if (reanalyse) {
    analysed = false;
    cholmod_free_factor(&L, &cm);
    M = *src;
  } else {
    std::copy(src->valuePtr(), src->valuePtr() + src->nonZeros(), M.valuePtr());
  }
  const int nn = n();

  if (reanalyse) {
    if (nn > 0) {
      const auto t0 = Clock::now();
      set_ordering();
      cholmod_sparse A = view();
      const SerialCholmod serial;
      std::vector<int> perm;
      if (cm.nmethods == 1 && cm.method[0].ordering == CHOLMOD_NESDIS) perm = block_ordering();
      if (!perm.empty()) {  // symbolic factorisation with the block ordering
        cm.nmethods = 1;
        cm.method[0].ordering = CHOLMOD_GIVEN;
        L = cholmod_analyze_p(&A, perm.data(), nullptr, 0, &cm);
      } else {
        L = cholmod_analyze(&A, &cm);
      }
      stats.t_analyse += seconds_since(t0);
      ++stats.analyses;
      if (L == nullptr)
        return failure(fmt::format("CHOLMOD analysis of the {}x{} stiffness matrix failed: {}", nn, nn,
                                   cholmod_status_name(cm.status)));
      stats.factor_nnz = factor_nnz();
      build_permuted();
    } else {
      ++stats.analyses;  // trivial 0x0 system: nothing to analyse
      stats.factor_nnz = 0;
    }
    analysed = true;
  }

  if (const auto [r, c] = first_non_finite(M); r >= 0)
    return failure(fmt::format("stiffness matrix has a non-finite entry at ({}, {})", r, c));
  diag = M.diagonal();

  ++stats.factorisations;
  if (nn == 0) {
    factor_valid = true;
    return {};
  }
  const auto t0 = Clock::now();
  cm.status = CHOLMOD_OK;
  {
    const SerialCholmod serial;
    if (L->is_super && !Sp.empty()) {
      // what cholmod_factorize does for a supernodal factor and stype < 0 (final_asis: no
      // conversion), without its two transposes (allocation + 2 passes over M per call):
      // the permuted lower triangle S is gathered from M through smap, bit for bit the same
      for (std::size_t t = 0; t < smap.size(); ++t) Sx[t] = M.valuePtr()[smap[t]];
      cholmod_sparse S = lower_view(nn, Sx.size(), Sp.data(), Si.data(), Sx.data());
      double beta[2] = {0.0, 0.0};
      cholmod_super_numeric(&S, nullptr, beta, L, &cm);
    } else {
      cholmod_sparse A = view();
      cholmod_factorize(&A, L, &cm);
    }
  }
  const int status = cm.status;  // read immediately: later CHOLMOD calls reset it
  stats.t_factorise += seconds_since(t0);

  if (status < CHOLMOD_OK)
    return failure(fmt::format("CHOLMOD factorisation of the {}x{} stiffness matrix failed: {}", nn, nn,
                               cholmod_status_name(status)));
  const auto minor = static_cast<long>(L->minor);
  if (status == CHOLMOD_NOT_POSDEF || minor < nn) {
    LinearStatus st;
    st.ok = false;
    st.minor = static_cast<int>(std::min<long>(minor, nn - 1));
    st.column = static_cast<const int*>(L->Perm)[st.minor];
    st.message = fmt::format(
        "stiffness matrix not positive definite at column {} (pivot {} of {} in the fill-reducing order; "
        "singular or indefinite network)",
        st.column, st.minor, nn);
    return st;
  }
  double ratio = 0;
  if (const int k = small_pivot(ratio); k >= 0) {
    LinearStatus st;
    st.ok = false;
    st.minor = k;
    st.column = static_cast<const int*>(L->Perm)[k];
    st.message = fmt::format(
        "stiffness matrix not positive definite at column {} (pivot {} of {} in the fill-reducing order is "
        "numerically zero: pivot/diagonal = {:.2e} <= {:.1e}; singular network)",
        st.column, k, nn, ratio, opt.pivot_tolerance);
    return st;
  }
  factor_valid = true;
  return {};
}

LinearStatus LinearSolver::Impl::direct_solve(const VecX& b, VecX& x) {
  const int nn = n();
  const double bnorm = b.norm();
  if (nn == 0 || bnorm == 0.0) {
    x.setZero(nn);
    return {};
  }
  x.resize(nn);
  if (!apply_factor(b.data(), x.data())) {
    x.setZero(nn);
    return failure(fmt::format("CHOLMOD solve failed: {}", cholmod_status_name(cm.status)));
  }
  LinearStatus st;
  st.residual = (b - M.selfadjointView<Eigen::Lower>() * x).norm() / bnorm;
  if (!x.allFinite() || !std::isfinite(st.residual)) {
    x.setZero(nn);
    return failure("direct solve produced a non-finite solution (overflow: matrix too ill-conditioned)");
  }
  return st;
}

// Right-preconditioned restarted GMRES(m), modified Gram-Schmidt Arnoldi, Givens rotations.
// Written here rather than using Eigen's unsupported GMRES because that one is LEFT
// preconditioned: its stopping test is on |M^-1 r| / |M^-1 b|, not on the true relative residual
// |Ax-b|/|b| that the caller asks for, and it wants a preconditioner class with compute(A).
// With right preconditioning, A M^-1 y = b, x = M^-1 y, GMRES minimises the true residual, so
// the Givens estimate is the true residual (up to roundoff) and the test is the requested one.
LinearStatus LinearSolver::Impl::gmres(const SpMat& A, const VecX& b, VecX& x) {
  const int nn = n();
  const int maxit = opt.gmres_max_iterations;
  const int m = std::min(opt.gmres_restart, maxit);
  const double bnorm = b.norm();
  const double target = opt.gmres_tolerance * bnorm;
  if (V.rows() != nn || V.cols() < m + 1) V.resize(nn, m + 1);
  if (Z.rows() != nn || Z.cols() < m) Z.resize(nn, m);  // z_j = M^-1 v_j, kept for the update
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(m + 1, m);
  VecX cs(m), sn(m), g(m + 1), w(nn);

  x.setZero(nn);
  VecX r = b;
  double beta = bnorm;
  int it = 0;
  bool singular = false;
  while (beta > target && it < maxit && !singular) {
    V.col(0) = r / beta;
    g.setZero();
    g[0] = beta;
    int k = 0;  // number of Arnoldi vectors used in this cycle
    for (int j = 0; j < m && it < maxit; ++j) {
      if (!apply_factor(V.col(j).data(), Z.col(j).data()))
        return failure(fmt::format("CHOLMOD solve failed inside GMRES: {}", cholmod_status_name(cm.status)));
      w.noalias() = A * Z.col(j);
      ++it;
      const double wnorm0 = w.norm();
      for (int i = 0; i <= j; ++i) {  // modified Gram-Schmidt
        H(i, j) = V.col(i).dot(w);
        w.noalias() -= H(i, j) * V.col(i);
      }
      const double hn = w.norm();
      for (int i = 0; i < j; ++i) {  // previous rotations on the new column
        const double t = cs[i] * H(i, j) + sn[i] * H(i + 1, j);
        H(i + 1, j) = -sn[i] * H(i, j) + cs[i] * H(i + 1, j);
        H(i, j) = t;
      }
      const double rho = std::hypot(H(j, j), hn);
      if (rho == 0.0) {  // A M^-1 v_j in span(v_0..v_{j-1}) with zero projection: A singular
        singular = true;
        break;
      }
      cs[j] = H(j, j) / rho;
      sn[j] = hn / rho;
      H(j, j) = rho;
      g[j + 1] = -sn[j] * g[j];
      g[j] = cs[j] * g[j];
      k = j + 1;
      if (hn <= 1e-14 * wnorm0) break;  // (lucky) breakdown: the Krylov space is invariant
      V.col(j + 1) = w / hn;
      if (std::abs(g[j + 1]) <= target) break;
    }
    if (k > 0) {
      // x += M^-1 V y = Z y (the stored preconditioned vectors: no extra factor solve)
      const VecX y = H.topLeftCorner(k, k).triangularView<Eigen::Upper>().solve(g.head(k));
      x.noalias() += Z.leftCols(k) * y;
    } else {
      singular = true;  // no progress possible
    }
    r.noalias() = b - A * x;  // true residual (guards against drift of the Givens estimate)
    beta = r.norm();
    if (!std::isfinite(beta)) break;
  }
  stats.gmres_iterations += it;

  LinearStatus st;
  st.iterations = it;
  st.residual = beta / bnorm;
  if (!std::isfinite(beta) || !x.allFinite()) {
    x.setZero(nn);
    st.ok = false;
    st.residual = 1.0;
    st.message = fmt::format("GMRES produced a non-finite iterate after {} iterations", it);
  } else if (beta > target) {
    st.ok = false;
    st.message =
        singular
            ? fmt::format("GMRES breakdown after {} iterations (matrix singular on the Krylov subspace), "
                          "relative residual {:.3e}",
                          it, st.residual)
            : fmt::format("GMRES did not converge: relative residual {:.3e} > tolerance {:.1e} after {} "
                          "iterations (restart {}); the non-symmetric part is too strong for the "
                          "symmetric preconditioner",
                          st.residual, opt.gmres_tolerance, it, m);
  }
  return st;
}

// ------------------------------------------------------------------------------------------------

LinearSolver::LinearSolver(LinearSolverOptions options) {
  options.validate();
  // Debian's CHOLMOD 3 opens OpenMP regions with a hard-coded num_threads(4) in the supernodal
  // factorisation: on a 2-core machine they spin and cost 3x (docs/performance.md). The solver is
  // serial by design (one core per job; parallelism is across probes/runs): no nested or active
  // OpenMP parallelism for this thread.
  omp_set_max_active_levels(0);
  detail::inline_omp_active();  // the self-test of the inline OpenMP regions, once per process
  impl_ = std::make_unique<Impl>(options);
}
LinearSolver::~LinearSolver() = default;
LinearSolver::LinearSolver(LinearSolver&&) noexcept = default;
LinearSolver& LinearSolver::operator=(LinearSolver&&) noexcept = default;

namespace {
[[noreturn]] void moved_from() { throw std::logic_error("LinearSolver: use of a moved-from solver"); }
}  // namespace

void LinearSolver::set_row_blocks(std::vector<int> block_of_row) {
  if (!impl_) moved_from();
  for (const int b : block_of_row)
    if (b < 0) throw std::invalid_argument("LinearSolver::set_row_blocks: negative block index");
  impl_->blocks = std::move(block_of_row);
  impl_->analysed = false;  // the next factorisation re-analyses with the new blocks
}

LinearStatus LinearSolver::factorise(const SpMat& M, bool pattern_changed) {
  if (!impl_) moved_from();
  return impl_->factorise(M, pattern_changed);
}

LinearStatus LinearSolver::solve(const VecX& b, VecX& x) {
  if (!impl_) moved_from();
  Impl& s = *impl_;
  if (b.size() != s.n())
    throw std::invalid_argument(
        fmt::format("LinearSolver::solve: right-hand side has {} rows, matrix has {}", b.size(), s.n()));
  const auto t0 = Clock::now();
  ++s.stats.solves;
  LinearStatus st;
  if (!s.factor_valid) {
    x.setZero(s.n());
    st = failure("no valid factorisation: the last factorise() failed or was never called");
  } else if (const int row = first_non_finite_row(b); row >= 0) {
    x.setZero(s.n());
    st = failure(fmt::format("right-hand side has a non-finite entry at row {}", row));
  } else if (x.data() == b.data()) {
    const VecX bcopy = b;
    st = s.direct_solve(bcopy, x);
  } else {
    st = s.direct_solve(b, x);
  }
  s.stats.t_solve += seconds_since(t0);
  return st;
}

LinearStatus LinearSolver::solve(const SpMat& A, const VecX& b, VecX& x) {
  if (!impl_) moved_from();
  Impl& s = *impl_;
  if (A.rows() != s.n() || A.cols() != s.n() || b.size() != s.n())
    throw std::invalid_argument(
        fmt::format("LinearSolver::solve: A is {}x{} and b has {} rows, factorised matrix is {}x{}", A.rows(),
                    A.cols(), b.size(), s.n(), s.n()));
  const auto t0 = Clock::now();
  ++s.stats.solves;
  LinearStatus st;
  SpMat compressed;
  const SpMat* a = &A;
  if (!A.isCompressed()) {
    compressed = A;
    compressed.makeCompressed();
    a = &compressed;
  }
  const VecX bcopy = x.data() == b.data() ? b : VecX();  // x may alias b
  const VecX& rhs = x.data() == b.data() ? bcopy : b;
  if (!s.factor_valid) {
    x.setZero(s.n());
    st = failure("no valid factorisation (preconditioner): the last factorise() failed or was never called");
  } else if (const int row = first_non_finite_row(rhs); row >= 0) {
    x.setZero(s.n());
    st = failure(fmt::format("right-hand side has a non-finite entry at row {}", row));
  } else if (same_pattern(*a, s.M) && same_values(*a, s.M)) {
    st = s.direct_solve(rhs, x);  // A is the factorised matrix itself
  } else if (const auto [r, c] = first_non_finite(*a); r >= 0) {
    x.setZero(s.n());
    st = failure(fmt::format("matrix has a non-finite entry at ({}, {})", r, c));
  } else if (s.n() == 0 || rhs.norm() == 0.0) {
    x.setZero(s.n());
  } else {
    st = s.gmres(*a, rhs, x);
  }
  s.stats.t_solve += seconds_since(t0);
  return st;
}

const LinearSolverStats& LinearSolver::stats() const {
  static const LinearSolverStats empty{};
  return impl_ ? impl_->stats : empty;
}
const LinearSolverOptions& LinearSolver::options() const {
  static const LinearSolverOptions defaults{};
  return impl_ ? impl_->opt : defaults;
}
bool LinearSolver::has_factor() const { return impl_ && impl_->factor_valid; }

}  // namespace netdem::qs
