// LinearSolver::Impl, the non-symmetric solve (linear_solver_impl.hpp): right-preconditioned
// restarted GMRES(m) with the CHOLMOD factor of M as the preconditioner (Impl::Gmres, one solve).
//
// Modified Gram-Schmidt Arnoldi, Givens rotations. Written here rather than using Eigen's
// unsupported GMRES because that one is LEFT preconditioned: its stopping test is on
// |M^-1 r| / |M^-1 b|, not on the true relative residual |Ax-b|/|b| that the caller asks for, and
// it wants a preconditioner class with compute(A). With right preconditioning, A M^-1 y = b,
// x = M^-1 y, GMRES minimises the true residual, so the Givens estimate is the true residual (up to
// roundoff) and the test is the requested one.
#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include "linear_solver_impl.hpp"

namespace netdem::qs {

/// The state of one GMRES solve of A x = b: the Hessenberg matrix, the rotations and the
/// iteration count; the Krylov basis V and the preconditioned vectors Z are the Impl's (reused).
struct LinearSolver::Impl::Gmres {
  Impl& s;
  const SpMat& A;
  const VecX& b;
  const int nn;
  const int maxit;
  const int m;
  const double bnorm;
  const double target;
  Eigen::MatrixXd& V;
  Eigen::MatrixXd& Z;
  Eigen::MatrixXd H;
  VecX cs, sn, g, w;
  int it = 0;
  bool singular = false;

  Gmres(Impl& impl, const SpMat& A_, const VecX& b_)
      : s(impl),
        A(A_),
        b(b_),
        nn(impl.size()),
        maxit(impl.opt.gmres_max_iterations),
        m(std::min(impl.opt.gmres_restart, maxit)),
        bnorm(b_.norm()),
        target(impl.opt.gmres_tolerance * bnorm),
        V(impl.V),
        Z(impl.Z) {
    if (V.rows() != nn || V.cols() < m + 1) V.resize(nn, m + 1);
    if (Z.rows() != nn || Z.cols() < m) Z.resize(nn, m);  // z_j = M^-1 v_j, kept for the update
    H = Eigen::MatrixXd::Zero(m + 1, m);
    cs.resize(m);
    sn.resize(m);
    g.resize(m + 1);
    w.resize(nn);
  }

  LinearStatus run(VecX& x);
  int cycle(const VecX& r, double beta);
  bool arnoldi(int j, double& wnorm0, double& hn);
  [[nodiscard]] LinearStatus result(double beta, VecX& x) const;
};

LinearStatus LinearSolver::Impl::gmres(const SpMat& A, const VecX& b, VecX& x) {
  Gmres solver(*this, A, b);
  return solver.run(x);
}

/// The restart cycles from x = 0 until the tolerance, the iteration limit or a breakdown.
LinearStatus LinearSolver::Impl::Gmres::run(VecX& x) {
  x.setZero(nn);
  VecX r = b;
  double beta = bnorm;
  while (beta > target && it < maxit && !singular) {
    const int k = cycle(r, beta);
    if (k < 0)
      return detail::failure(
          fmt::format("CHOLMOD solve failed inside GMRES: {}", detail::cholmod_status_name(s.cm.status)));
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
  s.stats.gmres_iterations += it;
  return result(beta, x);
}

/// One restart cycle from the residual r (norm beta): the number of Arnoldi vectors used (H and g
/// then hold the rotated least-squares problem), or -1 if a factor solve failed.
int LinearSolver::Impl::Gmres::cycle(const VecX& r, double beta) {
  V.col(0) = r / beta;
  g.setZero();
  g[0] = beta;
  int k = 0;  // number of Arnoldi vectors used in this cycle
  for (int j = 0; j < m && it < maxit; ++j) {
    double wnorm0 = 0, hn = 0;
    if (!arnoldi(j, wnorm0, hn)) return -1;
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
  return k;
}

/// Arnoldi step j: w = A M^-1 v_j orthogonalised against v_0..v_j into column j of H, with the
/// previous rotations applied; wnorm0 = |A M^-1 v_j|, hn = |w|. false if the factor solve failed.
bool LinearSolver::Impl::Gmres::arnoldi(int j, double& wnorm0, double& hn) {
  if (!s.precondition(V.col(j).data(), Z.col(j).data())) return false;
  w.noalias() = A * Z.col(j);
  ++it;
  wnorm0 = w.norm();
  for (int i = 0; i <= j; ++i) {  // modified Gram-Schmidt
    H(i, j) = V.col(i).dot(w);
    w.noalias() -= H(i, j) * V.col(i);
  }
  hn = w.norm();
  for (int i = 0; i < j; ++i) {  // previous rotations on the new column
    const double t = cs[i] * H(i, j) + sn[i] * H(i + 1, j);
    H(i + 1, j) = -sn[i] * H(i, j) + cs[i] * H(i + 1, j);
    H(i, j) = t;
  }
  return true;
}

/// The status of the solve from the final true residual norm beta (x = 0 if not finite).
LinearStatus LinearSolver::Impl::Gmres::result(double beta, VecX& x) const {
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
                          st.residual, s.opt.gmres_tolerance, it, m);
  }
  return st;
}

}  // namespace netdem::qs
