#pragma once
// Private: the parts of the sparse linear solver (LinearSolver::Impl) and which file owns what.
//
//   linear_solver.cpp   the public API: options validation, construction, the checks of the
//                       arguments and the dispatch of both solve() overloads, stats and options
//   cholmod_factor.cpp  Impl's CHOLMOD side: the cholmod_common lifecycle, the ordering (incl. the
//                       block nested-dissection ordering), analysis, numeric factorisation, the
//                       pivot checks, the factor solve and the direct solve
//   gmres.cpp           the right-preconditioned restarted GMRES (Impl::Gmres)
//   split.cpp           the split preconditioner (Impl::Split): the factor of a submatrix and
//                       the inverses of the other rows' diagonal blocks
//
// The CHOLMOD C API is used directly (not Eigen's CholmodSupernodalLLT) because it gives
// L->minor and L->Perm for the diagnostic message, lets us force the supernodal LL' method and
// the ordering, and cholmod_solve2 reuses its workspace across the many preconditioner
// applications of GMRES (Eigen's wrapper allocates a cholmod_dense per solve).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include <cholmod.h>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include "netdem/quasistatic/linear_solver.hpp"

namespace netdem::qs {

namespace detail {

// Helpers shared by the three files.

using Clock = std::chrono::steady_clock;
inline double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

inline const char* cholmod_status_name(int status) {
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

inline LinearStatus failure(std::string message) {
  LinearStatus st;
  st.ok = false;
  st.message = std::move(message);
  return st;
}

/// Index (row, col) of the first non-finite stored value of a compressed matrix, or (-1, -1).
inline std::pair<int, int> first_non_finite(const SpMat& A) {
  // vectorised test first (called on every factorisation and solve); the search only on failure
  if (Eigen::Map<const VecX>(A.valuePtr(), A.nonZeros()).allFinite()) return {-1, -1};
  for (int j = 0; j < A.outerSize(); ++j)
    for (SpMat::InnerIterator it(A, j); it; ++it)
      if (!std::isfinite(it.value())) return {static_cast<int>(it.row()), j};
  return {-1, -1};
}

/// A itself if it is compressed, otherwise a compressed copy of it made in `storage`.
inline const SpMat& compressed(const SpMat& A, SpMat& storage) {
  if (A.isCompressed()) return A;
  storage = A;
  storage.makeCompressed();
  return storage;
}

inline bool same_pattern(const SpMat& a, const SpMat& b) {  // both compressed
  if (a.rows() != b.rows() || a.cols() != b.cols() || a.nonZeros() != b.nonZeros()) return false;
  const auto n1 = static_cast<std::size_t>(a.outerSize()) + 1;
  const auto nnz = static_cast<std::size_t>(a.nonZeros());
  // std::equal (not memcmp): empty ranges with null pointers are well defined.
  return std::equal(a.outerIndexPtr(), a.outerIndexPtr() + n1, b.outerIndexPtr()) &&
         std::equal(a.innerIndexPtr(), a.innerIndexPtr() + nnz, b.innerIndexPtr());
}

}  // namespace detail

// ------------------------------------------------------------------------------------------------
// Impl: owns the cholmod_common, the factor and the solve workspace.
/// A CHOLMOD view (no copy) of the lower triangle of an n x n CSC matrix with sorted rows (values
/// may be null for a pattern). Used by the factorisation and by the OpenMP self-test.
cholmod_sparse lower_view(int n, std::size_t nz, int* p, int* i, double* x);

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
  // (of the full matrix: with the split preconditioner the ordering uses sp.sub_blocks)

  /// The split preconditioner (LinearSolver::set_split). M, L and everything above are then the
  /// factored submatrix's; `full` is the whole matrix that GMRES solves.
  struct Split {
    std::vector<int> group;     // full row -> group (< 0: factored); empty: off
    std::vector<int> frow;      // factored rows (full indices, increasing)
    std::vector<int> sub_of;    // full row -> factored row, or -1
    std::vector<int> gstart, grow;  // the groups' rows: grow[gstart[g] .. gstart[g + 1])
    std::vector<int> gather;    // value q of the submatrix <- value gather[q] of full
    std::vector<int> sub_blocks;  // `blocks` restricted to the factored rows
    std::vector<double> ginv;   // each group's inverse diagonal block, column-major, concatenated
    std::vector<int> ginv_at;   // start of group g's inverse in ginv
    SpMat full;                 // compressed copy of the whole matrix
    SpMat sub;                  // the factored submatrix (pattern built per analysis)
    VecX tin, tout;             // the factored rows' part of a vector
    bool fresh_pattern = true;  // the next factorisation builds the submatrix's pattern
  } sp;
  [[nodiscard]] bool split() const { return !sp.group.empty(); }
  /// The size of the systems solved: the full matrix's with the split preconditioner, else n().
  [[nodiscard]] int size() const { return split() ? static_cast<int>(sp.full.rows()) : n(); }
  /// out = P^{-1} in, the preconditioner (the factor's solve, or the split preconditioner).
  bool precondition(const double* in, double* out);

  // cholmod_factor.cpp
  explicit Impl(const LinearSolverOptions& o);
  ~Impl();
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;

  [[nodiscard]] int n() const { return static_cast<int>(M.rows()); }

  /// Non-owning CHOLMOD view of a square compressed-column matrix whose lower triangle is used
  /// (stype = -1, sorted and packed).
  /// Non-owning CHOLMOD view of M.
  cholmod_sparse view();
  void set_ordering();
  /// Nested-dissection ordering (METIS) of the block (node) graph of M, expanded to its rows in block
  /// order (a block's rows stay together, in increasing order). Empty if there are no blocks.
  std::vector<int> block_ordering();
  /// out = M^{-1} in (n doubles each; in may alias out).
  bool apply_factor(const double* in, double* out);

  LinearStatus factorise(const SpMat& Min, bool pattern_changed);
  /// Copies Min into M (throws if not square); true if its pattern must be (re)analysed.
  bool adopt(const SpMat& Min, bool pattern_changed);
  /// Ordering and symbolic factorisation of M's pattern, then build_permuted().
  LinearStatus analyse();
  void build_permuted();
  /// Numeric factorisation of M into the analysed L; returns the CHOLMOD status.
  int numeric_factorise();
  /// Not positive definite (status, L->minor) or a pivot below the tolerance: the failure status.
  LinearStatus check_pivots(int status) const;
  /// A failure status at pivot k of the permuted order (minor, column; the caller sets the message).
  [[nodiscard]] LinearStatus pivot_status(int k) const;
  /// nnz(L) from the symbolic factor: supernodal -> lower trapezoid of each supernode.
  [[nodiscard]] long factor_nnz() const;
  /// Pivot-tolerance check on the diagonal of L; returns the permuted column or -1.
  int small_pivot(double& ratio) const;
  LinearStatus direct_solve(const VecX& b, VecX& x);

  // split.cpp
  void set_split(std::vector<int> group_of_row);
  LinearStatus factorise_split(const SpMat& Min, bool pattern_changed);
  void build_sub_pattern();
  LinearStatus invert_groups();

  // gmres.cpp
  struct Gmres;  // the state of one GMRES solve
  LinearStatus gmres(const SpMat& A, const VecX& b, VecX& x);
};

}  // namespace netdem::qs
