// LinearSolver::Impl, the CHOLMOD side (linear_solver_impl.hpp): the cholmod_common lifecycle, the
// fill-reducing ordering (CHOLMOD's, or METIS on the block graph), the symbolic analysis, the
// numeric factorisation (supernodal LL', through the permuted lower triangle kept from the
// analysis), the pivot checks, the factor solve (also GMRES's preconditioner) and the direct solve.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <mutex>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <cholmod.h>
#include <fmt/format.h>

#include "cholmod_omp.hpp"
#include "linear_solver_impl.hpp"

namespace netdem::qs {

using detail::Clock;
using detail::SerialCholmod;  // cholmod_omp.hpp: CHOLMOD's OpenMP regions inline inside our calls
using detail::cholmod_status_name;
using detail::failure;
using detail::seconds_since;

// ------------------------------------------------------------------------------------------------
// Lifecycle, views, ordering, factor solve

namespace {
/// One CHOLMOD analysis, factorisation or solve at a time in the process. Two LinearSolvers used at
/// once on two threads (netsolve yield --dim 3 --jobs 2, a probe per thread, each with its own
/// cholmod_common) gave other results than --jobs 1 in every run, and factors "not positive
/// definite" from the same matrices; with this lock the files are identical (cli_netsolve_yield3d
/// jobs_with_solves_identical). Where inside CHOLMOD, METIS or the serial OpenBLAS under its
/// supernodal kernels the shared state lies was not isolated; the lock covers all three.
std::mutex& cholmod_mutex() {
  static std::mutex m;
  return m;
}
}  // namespace

LinearSolver::Impl::Impl(const LinearSolverOptions& o) : opt(o) {
  cholmod_start(&cm);
  cm.print = 0;                         // failures are reported through LinearStatus
  cm.supernodal = CHOLMOD_SUPERNODAL;   // LL' always: reports singularity reliably (notes §1.6)
  cm.quick_return_if_not_posdef = 1;    // stop at the first failed supernode
}

LinearSolver::Impl::~Impl() {
  cholmod_free_factor(&L, &cm);
  cholmod_free_dense(&X, &cm);
  cholmod_free_dense(&Y, &cm);
  cholmod_free_dense(&E, &cm);
  cholmod_finish(&cm);
}

cholmod_sparse lower_view(int n, std::size_t nz, int* p, int* i, double* x) {
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

cholmod_sparse LinearSolver::Impl::view() {
  return lower_view(n(), static_cast<std::size_t>(M.nonZeros()), M.outerIndexPtr(), M.innerIndexPtr(), M.valuePtr());
}

void LinearSolver::Impl::set_ordering() {
  using O = LinearSolverOptions::Ordering;
  const O o = opt.ordering == O::Auto ? (n() >= 200000 ? O::Nesdis : O::Auto) : opt.ordering;
  if (o == O::Auto) {
    cm.nmethods = 0;  // CHOLMOD default: AMD, METIS only if AMD's fill is poor
  } else {
    cm.nmethods = 1;
    cm.method[0].ordering = o == O::Amd ? CHOLMOD_AMD : CHOLMOD_NESDIS;
  }
}

std::vector<int> LinearSolver::Impl::block_ordering() {
  const int nn = n();
  const std::vector<int>& rb = split() ? sp.sub_blocks : blocks;  // row -> block
  if (static_cast<int>(rb.size()) != nn || nn == 0) return {};
  const int nb = *std::max_element(rb.begin(), rb.end()) + 1;
  std::vector<int> bstart(nb + 1, 0), brows(nn);
  for (const int b : rb) ++bstart[b + 1];
  for (int b = 0; b < nb; ++b) bstart[b + 1] += bstart[b];
  {
    std::vector<int> at(bstart.begin(), bstart.end() - 1);
    for (int r = 0; r < nn; ++r) brows[at[rb[r]]++] = r;
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
        const int br = rb[Mi[q]];
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

bool LinearSolver::Impl::apply_factor(const double* in, double* out) {
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
  const std::lock_guard<std::mutex> one_at_a_time(cholmod_mutex());
  if (!cholmod_solve2(CHOLMOD_A, L, &B, nullptr, &X, nullptr, &Y, &E, &cm)) return false;
  const auto* xs = static_cast<const double*>(X->x);
  std::copy(xs, xs + n(), out);
  return true;
}

long LinearSolver::Impl::factor_nnz() const {
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

// ------------------------------------------------------------------------------------------------
// Analysis and numeric factorisation


LinearStatus LinearSolver::Impl::factorise(const SpMat& Min, bool pattern_changed) {
  if (adopt(Min, pattern_changed)) {
    if (LinearStatus st = analyse(); !st.ok) return st;
  }

  if (const auto [r, c] = detail::first_non_finite(M); r >= 0)
    return failure(fmt::format("stiffness matrix has a non-finite entry at ({}, {})", r, c));
  diag = M.diagonal();

  ++stats.factorisations;
  if (n() == 0) {
    factor_valid = true;
    return {};
  }
  if (LinearStatus st = check_pivots(numeric_factorise()); !st.ok) return st;
  factor_valid = true;
  return {};
}

bool LinearSolver::Impl::adopt(const SpMat& Min, bool pattern_changed) {
  if (Min.rows() != Min.cols())
    throw std::invalid_argument(
        fmt::format("LinearSolver::factorise: matrix must be square, got {}x{}", Min.rows(), Min.cols()));
  SpMat storage;
  const SpMat* src = &detail::compressed(Min, storage);
  factor_valid = false;
  const bool reanalyse = pattern_changed || !analysed || !detail::same_pattern(*src, M);
  if (reanalyse) {
    analysed = false;
    cholmod_free_factor(&L, &cm);
    M = *src;
  } else {
    std::copy(src->valuePtr(), src->valuePtr() + src->nonZeros(), M.valuePtr());
  }
  return reanalyse;
}

LinearStatus LinearSolver::Impl::analyse() {
  const int nn = n();
  if (nn > 0) {
    const auto t0 = Clock::now();
    set_ordering();
    cholmod_sparse A = view();
    const SerialCholmod serial;
    const std::lock_guard<std::mutex> one_at_a_time(cholmod_mutex());  // see cholmod_mutex()
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
  return {};
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

int LinearSolver::Impl::numeric_factorise() {
  const int nn = n();
  const auto t0 = Clock::now();
  cm.status = CHOLMOD_OK;
  {
    const SerialCholmod serial;
    const std::lock_guard<std::mutex> one_at_a_time(cholmod_mutex());
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
  return status;
}

// ------------------------------------------------------------------------------------------------
// Pivot checks

LinearStatus LinearSolver::Impl::check_pivots(int status) const {
  const int nn = n();
  if (status < CHOLMOD_OK)
    return failure(fmt::format("CHOLMOD factorisation of the {}x{} stiffness matrix failed: {}", nn, nn,
                               cholmod_status_name(status)));
  const auto minor = static_cast<long>(L->minor);
  if (status == CHOLMOD_NOT_POSDEF || minor < nn) {
    LinearStatus st = pivot_status(static_cast<int>(std::min<long>(minor, nn - 1)));
    st.message = fmt::format(
        "stiffness matrix not positive definite at column {} (pivot {} of {} in the fill-reducing order; "
        "singular or indefinite network)",
        st.column, st.minor, nn);
    return st;
  }
  double ratio = 0;
  if (const int k = small_pivot(ratio); k >= 0) {
    LinearStatus st = pivot_status(k);
    st.message = fmt::format(
        "stiffness matrix not positive definite at column {} (pivot {} of {} in the fill-reducing order is "
        "numerically zero: pivot/diagonal = {:.2e} <= {:.1e}; singular network)",
        st.column, k, nn, ratio, opt.pivot_tolerance);
    return st;
  }
  return {};
}

LinearStatus LinearSolver::Impl::pivot_status(int k) const {
  LinearStatus st;
  st.ok = false;
  st.minor = k;
  st.column = static_cast<const int*>(L->Perm)[k];
  if (split()) st.column = sp.frow[st.column];  // the full matrix's row
  return st;
}

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

// ------------------------------------------------------------------------------------------------
// Direct solve

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

}  // namespace netdem::qs
