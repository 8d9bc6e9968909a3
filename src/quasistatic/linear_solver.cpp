// LinearSolver, the public API (linear_solver_impl.hpp says which file owns which part of the
// Impl): the options validation, construction (process-wide OpenMP set-up), the checks of the
// arguments of factorise() and of both solve() overloads and their dispatch to the direct solve or
// GMRES, the statistics and the options.
#include "netdem/quasistatic/linear_solver.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "cholmod_omp.hpp"
#include "linear_solver_impl.hpp"

namespace netdem::qs {

namespace {

using detail::Clock;
using detail::failure;
using detail::first_non_finite;
using detail::same_pattern;
using detail::seconds_since;

bool same_values(const SpMat& a, const SpMat& b) {  // same pattern, both compressed
  const auto nnz = static_cast<std::size_t>(a.nonZeros());
  return std::equal(a.valuePtr(), a.valuePtr() + nnz, b.valuePtr());
}

int first_non_finite_row(const VecX& v) {
  for (Eigen::Index i = 0; i < v.size(); ++i)
    if (!std::isfinite(v[i])) return static_cast<int>(i);
  return -1;
}

[[noreturn]] void moved_from() { throw std::logic_error("LinearSolver: use of a moved-from solver"); }

}  // namespace

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

void LinearSolver::set_row_blocks(std::vector<int> block_of_row) {
  if (!impl_) moved_from();
  for (const int b : block_of_row)
    if (b < 0) throw std::invalid_argument("LinearSolver::set_row_blocks: negative block index");
  impl_->blocks = std::move(block_of_row);
  impl_->analysed = false;  // the next factorisation re-analyses with the new blocks
}

void LinearSolver::set_split(std::vector<int> group_of_row) {
  if (!impl_) moved_from();
  impl_->set_split(std::move(group_of_row));
}

bool LinearSolver::split() const { return impl_ && impl_->split(); }

LinearStatus LinearSolver::factorise(const SpMat& M, bool pattern_changed) {
  if (!impl_) moved_from();
  return impl_->split() ? impl_->factorise_split(M, pattern_changed) : impl_->factorise(M, pattern_changed);
}

LinearStatus LinearSolver::solve(const VecX& b, VecX& x) {
  if (!impl_) moved_from();
  Impl& s = *impl_;
  if (b.size() != s.size())
    throw std::invalid_argument(
        fmt::format("LinearSolver::solve: right-hand side has {} rows, matrix has {}", b.size(), s.size()));
  if (s.split()) return solve(s.sp.full, b, x);  // the preconditioner is not M's inverse: GMRES
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
  const int nn = s.size();
  if (A.rows() != nn || A.cols() != nn || b.size() != nn)
    throw std::invalid_argument(fmt::format(
        "LinearSolver::solve: A is {}x{} and b has {} rows, factorised matrix is {}x{}", A.rows(), A.cols(), b.size(), nn, nn));
  const auto t0 = Clock::now();
  ++s.stats.solves;
  LinearStatus st;
  SpMat storage;
  const SpMat* a = &detail::compressed(A, storage);
  const VecX bcopy = x.data() == b.data() ? b : VecX();  // x may alias b
  const VecX& rhs = x.data() == b.data() ? bcopy : b;
  if (!s.factor_valid) {
    x.setZero(nn);
    st = failure("no valid factorisation (preconditioner): the last factorise() failed or was never called");
  } else if (const int row = first_non_finite_row(rhs); row >= 0) {
    x.setZero(nn);
    st = failure(fmt::format("right-hand side has a non-finite entry at row {}", row));
  } else if (!s.split() && same_pattern(*a, s.M) && same_values(*a, s.M)) {
    st = s.direct_solve(rhs, x);  // A is the factorised matrix itself
  } else if (const auto [r, c] = first_non_finite(*a); r >= 0) {
    x.setZero(nn);
    st = failure(fmt::format("matrix has a non-finite entry at ({}, {})", r, c));
  } else if (nn == 0 || rhs.norm() == 0.0) {
    x.setZero(nn);
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
