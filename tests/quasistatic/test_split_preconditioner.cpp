// Tests of LinearSolver's split preconditioner (set_split): the CHOLMOD factor of the factored
// rows' submatrix and the inverse of each group's diagonal block, with GMRES on the whole matrix.
// References: dense Eigen LLT / PartialPivLU of the whole matrix, and a matrix on which the split
// preconditioner is the exact inverse (no coupling between the groups and the factored rows).
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include <Eigen/Dense>

#include "netdem/quasistatic/linear_solver.hpp"

namespace {

using netdem::qs::LinearSolver;
using netdem::qs::LinearSolverOptions;
using netdem::qs::LinearStatus;
using netdem::qs::SpMat;
using netdem::qs::VecX;
using Triplets = std::vector<Eigen::Triplet<double>>;

constexpr int kDof = 5;  // per node: three "translations" (factored) and two "rotations" (a group)

/// A random network: nodes on a ring and random chords, each edge an element G G^T (G random
/// 2 kDof x 4, positive semidefinite, coupling every DOF of its two nodes), plus a grounding
/// diagonal on every DOF: symmetric positive definite. With coupled = false the elements leave
/// out the rotations' coupling to everything but their own node's rotations (block diagonal
/// between the translations and each node's rotations). skew: a non-symmetric part added to A.
struct Net {
  SpMat M, A;
};
Net network(int nodes, bool coupled, double skew, std::mt19937_64& rng) {
  std::normal_distribution<double> N(0.0, 1.0);
  std::uniform_int_distribution<int> pick(0, nodes - 1);
  std::vector<std::pair<int, int>> edges;
  for (int i = 0; i < nodes; ++i) edges.emplace_back(i, (i + 1) % nodes);
  for (int k = 0; k < nodes; ++k) {
    const int i = pick(rng), j = pick(rng);
    if (i != j) edges.emplace_back(i, j);
  }
  Triplets tm, ta;
  for (const auto& [i, j] : edges) {
    Eigen::Matrix<double, 2 * kDof, 4> G;
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 2 * kDof; ++r) G(r, c) = N(rng);
    Eigen::Matrix<double, 2 * kDof, 2 * kDof> E = G * G.transpose();
    const int dof[2 * kDof] = {kDof * i,     kDof * i + 1, kDof * i + 2, kDof * i + 3, kDof * i + 4,
                               kDof * j,     kDof * j + 1, kDof * j + 2, kDof * j + 3, kDof * j + 4};
    for (int a = 0; a < 2 * kDof; ++a)
      for (int b = 0; b < 2 * kDof; ++b) {
        const bool rot_a = a % kDof >= 3, rot_b = b % kDof >= 3;
        if (!coupled && (rot_a || rot_b) && !(rot_a && rot_b && a / kDof == b / kDof)) continue;
        const double s = skew * N(rng);
        tm.emplace_back(dof[a], dof[b], E(a, b));
        ta.emplace_back(dof[a], dof[b], E(a, b) + (a < b ? s : 0.0));
      }
  }
  const int n = kDof * nodes;
  for (int d = 0; d < n; ++d) {
    tm.emplace_back(d, d, 0.5);
    ta.emplace_back(d, d, 0.5);
  }
  Net net{SpMat(n, n), SpMat(n, n)};
  net.M.setFromTriplets(tm.begin(), tm.end());
  net.A.setFromTriplets(ta.begin(), ta.end());
  return net;
}

std::vector<int> rotation_groups(int nodes) {  // translations factored, each node's rotations a group
  std::vector<int> g(static_cast<std::size_t>(kDof * nodes), -1);
  for (int p = 0; p < nodes; ++p) g[kDof * p + 3] = g[kDof * p + 4] = p;
  return g;
}

VecX random_vector(int n, std::mt19937_64& rng) {
  std::normal_distribution<double> N(0.0, 1.0);
  VecX b(n);
  for (int i = 0; i < n; ++i) b[i] = N(rng);
  return b;
}

double rel_err(const VecX& x, const VecX& ref) { return (x - ref).norm() / ref.norm(); }

TEST(SplitPreconditioner, SolvesTheWholeSystem) {
  std::mt19937_64 rng(11);
  const int nodes = 150;
  const Net net = network(nodes, true, 0.3, rng);
  const VecX b = random_vector(kDof * nodes, rng);
  const Eigen::MatrixXd Md(net.M), Ad(net.A);
  const VecX ref_m = Eigen::LLT<Eigen::MatrixXd>(Md).solve(b);
  const VecX ref_a = Eigen::PartialPivLU<Eigen::MatrixXd>(Ad).solve(b);

  const LinearSolverOptions o{.gmres_tolerance = 1e-12, .gmres_max_iterations = 500};
  LinearSolver full(o), split(o);
  split.set_split(rotation_groups(nodes));
  EXPECT_TRUE(split.split());
  EXPECT_FALSE(full.split());
  ASSERT_TRUE(full.factorise(net.M, true).ok);
  const LinearStatus fs = split.factorise(net.M, true);
  ASSERT_TRUE(fs.ok) << fs.message;
  // the factor holds the translations only: far fewer nonzeros than the whole matrix's
  EXPECT_LT(split.stats().factor_nnz, full.stats().factor_nnz / 2);

  VecX x;
  LinearStatus st = split.solve(b, x);  // M x = b: GMRES now, not a direct solve
  ASSERT_TRUE(st.ok) << st.message;
  EXPECT_GT(st.iterations, 1);
  EXPECT_LE(st.residual, 1e-12);
  EXPECT_LT(rel_err(x, ref_m), 1e-9);
  st = split.solve(net.M, b, x);  // the factorised M given again: GMRES too
  ASSERT_TRUE(st.ok) << st.message;
  EXPECT_GT(st.iterations, 1);
  EXPECT_LT(rel_err(x, ref_m), 1e-9);
  st = split.solve(net.A, b, x);  // the non-symmetric tangent
  ASSERT_TRUE(st.ok) << st.message;
  EXPECT_LT(rel_err(x, ref_a), 1e-9);
  VecX bx = b;  // x aliasing b
  ASSERT_TRUE(split.solve(net.A, bx, bx).ok);
  EXPECT_LT(rel_err(bx, ref_a), 1e-9);

  // new values on the same pattern: refactorised without a new analysis; the answer follows them
  const long analyses = split.stats().analyses;
  SpMat M2 = net.M;
  for (int d = 0; d < M2.rows(); ++d) M2.coeffRef(d, d) += 1.0;
  ASSERT_TRUE(split.factorise(M2, false).ok);
  EXPECT_EQ(split.stats().analyses, analyses);
  ASSERT_TRUE(split.solve(b, x).ok);
  EXPECT_LT(rel_err(x, Eigen::LLT<Eigen::MatrixXd>(Eigen::MatrixXd(M2)).solve(b)), 1e-9);

  // set_split({}) turns it off: a direct solve again
  split.set_split({});
  EXPECT_FALSE(split.split());
  ASSERT_TRUE(split.factorise(net.M, true).ok);
  st = split.solve(b, x);
  ASSERT_TRUE(st.ok);
  EXPECT_EQ(st.iterations, 0);
  EXPECT_LT(rel_err(x, ref_m), 1e-10);
}

// Without coupling between the translations and the rotations, the factor of the translations
// and the inverted rotation blocks are M's exact inverse: GMRES ends after one iteration. This
// fails if a block is inverted wrongly, a row is mapped to the wrong place or a block misses an
// entry.
TEST(SplitPreconditioner, IsExactWithoutCoupling) {
  std::mt19937_64 rng(12);
  const int nodes = 120;
  const Net net = network(nodes, false, 0.0, rng);
  const VecX b = random_vector(kDof * nodes, rng);
  LinearSolver split(LinearSolverOptions{.gmres_tolerance = 1e-11});
  split.set_split(rotation_groups(nodes));
  ASSERT_TRUE(split.factorise(net.M, true).ok);
  VecX x;
  const LinearStatus st = split.solve(b, x);
  ASSERT_TRUE(st.ok) << st.message;
  EXPECT_EQ(st.iterations, 1);
  EXPECT_LT(rel_err(x, Eigen::LLT<Eigen::MatrixXd>(Eigen::MatrixXd(net.M)).solve(b)), 1e-11);
}

TEST(SplitPreconditioner, ReportsFailuresAtTheWholeMatrixsRows) {
  std::mt19937_64 rng(13);
  const int nodes = 50;
  const Net net = network(nodes, true, 0.0, rng);
  const int n = kDof * nodes;
  // a zero translation row and column: the factor's pivot failure names the whole matrix's row
  for (const int row : {kDof * 17 + 1, kDof * 3}) {
    SpMat Z = net.M;
    for (int k = 0; k < Z.outerSize(); ++k)
      for (SpMat::InnerIterator it(Z, k); it; ++it)
        if (it.row() == row || it.col() == row) it.valueRef() = 0.0;
    LinearSolver split;
    split.set_split(rotation_groups(nodes));
    const LinearStatus st = split.factorise(Z, true);
    ASSERT_FALSE(st.ok);
    EXPECT_EQ(st.column, row) << st.message;
    EXPECT_FALSE(split.has_factor());
  }
  // an indefinite rotation block
  SpMat B = net.M;
  B.coeffRef(kDof * 9 + 4, kDof * 9 + 4) = -1.0;
  LinearSolver split;
  split.set_split(rotation_groups(nodes));
  const LinearStatus st = split.factorise(B, true);
  ASSERT_FALSE(st.ok);
  EXPECT_EQ(st.column, kDof * 9 + 3) << st.message;
  EXPECT_NE(st.message.find("not positive definite"), std::string::npos);
  VecX x;
  EXPECT_FALSE(split.solve(random_vector(n, rng), x).ok);  // no factor: no solve
  // misuse: a group larger than kMaxSplitGroup, a matrix of another size
  std::vector<int> big(static_cast<std::size_t>(n), -1);
  for (int r = 0; r <= LinearSolver::kMaxSplitGroup; ++r) big[r] = 0;
  EXPECT_THROW(split.set_split(big), std::invalid_argument);
  split.set_split(rotation_groups(nodes - 1));
  EXPECT_THROW((void)split.factorise(net.M, true), std::invalid_argument);
}

}  // namespace
