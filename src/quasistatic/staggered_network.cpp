// The staggered scheme: the bond network (staggered_impl.hpp; docs/staggered.md): constraints and
// the clusters held at one particle, the sparsity pattern and its slots, the scaled assembly and
// the solve with the sintering loads (CHOLMOD, the factor reused as the preconditioner of GMRES).
#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <numeric>
#include <stdexcept>

#include <Eigen/Eigenvalues>
#include <fmt/format.h>

#include "staggered_impl.hpp"

namespace netdem::qs::staggered {

void Staggered::Impl::init_solver() {
  LinearSolverOptions lo;
  lo.gmres_tolerance = opt.gmres_tolerance;
  lo.gmres_max_iterations = 200;
  solver = std::make_unique<LinearSolver>(lo);
}

void Staggered::Impl::update_constraints() {
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
      for (int i : m) xc += centre(i);
      xc /= static_cast<double>(m.size());
      const Eigen::Vector3d rel = (centre(m[0]) - xc) / ell;
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
Eigen::MatrixXd Staggered::Impl::rigid_null_space(const std::vector<int>& m) const {
  Eigen::Vector3d xc = Eigen::Vector3d::Zero();
  for (int i : m) xc += centre(i);
  xc /= static_cast<double>(m.size());
  Eigen::Matrix<double, 6, 6> CtC = Eigen::Matrix<double, 6, 6>::Zero();
  for (int i : m)
    for (int k = 0; k < 6; ++k) {
      if (!(fixed_user[6 * i + k] | fixed_plane[6 * i + k])) continue;
      Eigen::Matrix<double, 6, 1> row = Eigen::Matrix<double, 6, 1>::Zero();
      row[k] = 1.0;
      if (k < 3) row.tail<3>() = ((centre(i) - xc) / ell).cross(Eigen::Vector3d::Unit(k));  // e_k . (w x rel)
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
void Staggered::Impl::remove_rigid_motions(std::vector<Eigen::Vector3d>& u) const {
  for (const auto& m : floating) {
    const Eigen::MatrixXd Nm = rigid_null_space(m);
    const int k = static_cast<int>(Nm.cols());
    if (k == 0) continue;
    Eigen::Vector3d xc = Eigen::Vector3d::Zero();
    for (int i : m) xc += centre(i);
    xc /= static_cast<double>(m.size());
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(k, k);
    Eigen::VectorXd b = Eigen::VectorXd::Zero(k);
    std::vector<Eigen::MatrixXd> M(m.size());
    for (std::size_t j = 0; j < m.size(); ++j) {
      Eigen::Matrix<double, 3, 6> T;
      T.leftCols<3>().setIdentity();
      T.rightCols<3>() = -contact::skew<double>((centre(m[j]) - xc) / ell);  // w x rel = -rel x w
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
void Staggered::Impl::build_pattern() {
  update_constraints();
  build_pattern_for(c.size(), fixed);
  need_factor = !(solver->has_factor() && fixed == ref_fixed);
}

// dof, nfree, K and slots for the first nc contacts and the constraints fx
void Staggered::Impl::build_pattern_for(std::size_t nc, const std::vector<std::uint8_t>& fx) {
  const int n = N();
  dof.assign(6 * n, -1);
  nfree = 0;
  for (int i = 0; i < 6 * n; ++i)
    if (!fx[i]) dof[i] = nfree++;
  // the network solver's pattern and slots (pair_pattern.hpp); a particle with a free DOF has a bond
  // here (update_constraints fixes the others), so the structure is that of the bonds' blocks
  pattern.build(K, n, 6, dof, nfree, nc, [&](std::size_t k) { return std::pair<int, int>(c[k].a, c[k].b); });
  std::vector<int> blocks(static_cast<std::size_t>(nfree));
  for (int i = 0; i < 6 * n; ++i)
    if (dof[i] >= 0) blocks[dof[i]] = i / 6;
  solver->set_row_blocks(std::move(blocks));
  pattern_dirty = false;
}

// K^ = c S K S from the elements e (one per contact of the pattern, in order)
void Staggered::Impl::assemble(const std::vector<contact::BondElement>& e) {
  double* v = K.valuePtr();
  std::fill(v, v + K.nonZeros(), 0.0);
  for (std::size_t kc = 0; kc < e.size(); ++kc) {
    const contact::BondMat12 Ke = contact::bond_stiffness(e[kc], bmat);
    pattern.for_each_entry<12>(kc, [&](int q, int i, int j) { v[q] += cscale * dof_scale(i) * dof_scale(j) * Ke(i, j); });
  }
}

// The sintering loads of the step (Eq 10) on the bond network; the scaled displacements.
VecX Staggered::Impl::solve_network(StepRecord& rec) {
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

}  // namespace netdem::qs::staggered
