#pragma once
// Sparse linear solver of the quasi-static network solver.
//
// * Symmetric positive definite stiffness M: CHOLMOD supernodal LL' (C API), analysed (ordering +
//   symbolic factorisation) only when the sparsity pattern changes, refactorised numerically
//   otherwise (notes/implicit-solver.md §1.1). Singular / indefinite networks are reported, never
//   solved silently (§1.6).
// * General (non-symmetric frictional) tangent A: right-preconditioned restarted GMRES with the
//   CHOLMOD factor of the symmetric slip-status tangent M as the preconditioner (§2.3-2.4).
//
// Failure policy: numerical failures (not positive definite, non-finite input, GMRES not converged,
// CHOLMOD out of memory) come back as LinearStatus{ok = false, message}; x then never contains
// NaN/Inf. Caller bugs (non-square matrix, size mismatch, using a moved-from solver) throw
// std::invalid_argument / std::logic_error.
//
// Thread safety: one LinearSolver must not be used from two threads at once (it owns a
// cholmod_common and workspace). Distinct instances are independent and may run concurrently
// (with a serial BLAS, or OPENBLAS_NUM_THREADS=1 to avoid oversubscription).
#include <memory>
#include <string>

#include <Eigen/Core>
#include <Eigen/SparseCore>

namespace netdem::qs {

using SpMat = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;
using VecX = Eigen::VectorXd;

struct LinearSolverOptions {
  /// Fill-reducing ordering. Auto: CHOLMOD's default strategy (AMD, METIS tried only if AMD is
  /// poor) for fewer than 2e5 rows, NESDIS (CHOLMOD nested dissection) from 2e5 rows on.
  enum class Ordering { Auto, Amd, Nesdis } ordering = Ordering::Auto;
  double gmres_tolerance = 1e-10;  ///< relative residual |Ax-b|/|b| for the non-symmetric solve
  int gmres_max_iterations = 200;  ///< total GMRES iterations (all restart cycles)
  int gmres_restart = 50;          ///< Krylov subspace dimension per cycle
  /// A Cholesky pivot L_kk^2 <= pivot_tolerance * M_kk (M_kk the original diagonal entry) is
  /// reported as "not positive definite" (numerically singular): dpotrf only catches pivots
  /// <= 0, and a semidefinite M (mechanism) usually ends with a roundoff-sized positive pivot.
  /// A ratio below 1e-12 means cond(M) > 1e12, i.e. no trustworthy digits. 0 disables the check.
  double pivot_tolerance = 1e-12;
  /// Throws std::invalid_argument (one-line message) if an option is out of range.
  void validate() const;
};

struct LinearStatus {
  bool ok = true;
  /// One line, empty if ok, e.g. "stiffness matrix not positive definite at column 1234 (pivot
  /// 1187 of 3000 in the fill-reducing order; singular or indefinite network)".
  std::string message;
  /// CHOLMOD L->minor when not positive definite: the failing pivot in the PERMUTED
  /// (fill-reducing) order. Also set when the pivot-tolerance check fails. -1 otherwise.
  int minor = -1;
  /// The original (unpermuted) row/column of that pivot, L->Perm[minor]; -1 otherwise. For a
  /// network with kNodeDofs DOFs per particle, particle = column / kNodeDofs.
  int column = -1;
  int iterations = 0;  ///< GMRES iterations of the last solve (0 for a direct solve)
  double residual = 0;  ///< relative residual |Ax-b|/|b| of the last solve (0 if b = 0)
};

struct LinearSolverStats {
  long analyses = 0;          ///< cholmod_analyze calls (ordering + symbolic factorisation)
  long factorisations = 0;    ///< numeric factorisations attempted (incl. not positive definite)
  long solves = 0;            ///< calls of either solve() overload
  long gmres_iterations = 0;  ///< total GMRES iterations; each = one factor solve + one mat-vec
  double t_analyse = 0, t_factorise = 0, t_solve = 0;  ///< seconds (steady_clock)
  long factor_nnz = 0;  ///< nonzeros of the current factor L (fill; 0 before the first analysis)
};

/// Whether CHOLMOD's OpenMP regions run inline inside LinearSolver calls in this process (the
/// start-up self-test of src/quasistatic/cholmod_omp.cpp passed); if not, `why` says why.
/// Results are the same either way; inline is faster (docs/quasistatic.md "CHOLMOD and OpenMP").
bool cholmod_inline_openmp(std::string* why = nullptr);

class LinearSolver {
 public:
  explicit LinearSolver(LinearSolverOptions options = {});  // validates the options
  ~LinearSolver();
  LinearSolver(const LinearSolver&) = delete;
  LinearSolver& operator=(const LinearSolver&) = delete;
  LinearSolver(LinearSolver&&) noexcept;  // a moved-from solver may only be destroyed/assigned
  LinearSolver& operator=(LinearSolver&&) noexcept;

  /// M: symmetric positive definite, full storage (both triangles); only the lower triangle is
  /// read. Explicit zeros in the pattern are fine (potential contacts of a skin neighbour list).
  /// Re-analyses only if pattern_changed is true or M's pattern (size, nonZeros, outer and inner
  /// index arrays) differs from the analysed one; otherwise refactorises numerically.
  /// M is copied (O(nnz)); the caller may modify or destroy it afterwards.
  /// A 0x0 M is a valid (trivial) system. Throws std::invalid_argument if M is not square.
  LinearStatus factorise(const SpMat& M, bool pattern_changed);

  /// Rows that belong together (the DOFs of one particle): where the rows would get a
  /// nested-dissection ordering (from 2e5 rows on, or with Ordering::Nesdis), METIS orders the
  /// graph of the blocks instead and the order is expanded to their rows, which keeps a block's
  /// rows together and orders a 3x smaller graph with 9x fewer edges (W = 640 R: 0.94 -> 0.58 s
  /// per analysis, same fill). block_of_row.size() must equal the matrix size at the next analysis
  /// (otherwise the rows are ordered individually). Throws std::invalid_argument for a negative
  /// block index.
  void set_row_blocks(std::vector<int> block_of_row);

  /// The split preconditioner (docs/performance.md "Issue 30, part 5"): the rows with
  /// group_of_row[r] < 0 are factorised (CHOLMOD, the submatrix of M on those rows); the rows of
  /// each group g >= 0 (at most kMaxSplitGroup rows, e.g. the rotations of one particle) are
  /// preconditioned by the inverse of their diagonal block of M, their coupling to every other
  /// row left out (block Jacobi). The preconditioner is then no longer M's inverse, so every
  /// solve, solve(b, x) included, is GMRES on the full matrix. Empty: off (the default). Takes
  /// effect at the next factorise(); group_of_row.size() must equal its matrix size. Throws
  /// std::invalid_argument for a group with more than kMaxSplitGroup rows.
  void set_split(std::vector<int> group_of_row);
  static constexpr int kMaxSplitGroup = 6;
  /// Whether the split preconditioner is on (set_split with a non-empty vector).
  [[nodiscard]] bool split() const;

  /// Solves M x = b with the factor (direct; with the split preconditioner, GMRES on M). ok =
  /// false (x = 0) if there is no valid factor. residual is computed with the stored copy of M
  /// (one extra mat-vec).
  LinearStatus solve(const VecX& b, VecX& x);

  /// Solves A x = b for a general (possibly non-symmetric) A, same size as M, full storage, by
  /// right-preconditioned restarted GMRES with the factor of M as preconditioner, starting from
  /// x = 0. If A is identical to the factorised M (pattern and values) it is a direct solve
  /// (iterations = 0). ok = false if GMRES does not reach gmres_tolerance within
  /// gmres_max_iterations; x is then the best (finite) iterate and residual its true residual.
  LinearStatus solve(const SpMat& A, const VecX& b, VecX& x);

  [[nodiscard]] const LinearSolverStats& stats() const;
  [[nodiscard]] const LinearSolverOptions& options() const;
  /// True after a successful factorise() (until the next failed one).
  [[nodiscard]] bool has_factor() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace netdem::qs
