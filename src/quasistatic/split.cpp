// LinearSolver::Impl, the split preconditioner (linear_solver_impl.hpp, LinearSolver::set_split):
// the CHOLMOD factor of the submatrix on the factored rows (the particles' translations), and the
// inverse of each group's diagonal block (a particle's rotations) for the other rows. GMRES then
// solves the full system with it. In a 3D network with rotations the translations' factor has a
// quarter of the full factor's nonzeros and an eighth of its flops, and GMRES needs about as many
// iterations with it as with the full factor (docs/performance.md "Issue 30, part 5").
#include <algorithm>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "linear_solver_impl.hpp"

namespace netdem::qs {

using detail::failure;

void LinearSolver::Impl::set_split(std::vector<int> group_of_row) {
  sp = Split{};
  analysed = false;  // the next factorisation analyses the new factored matrix
  factor_valid = false;
  if (group_of_row.empty()) return;
  const int nn = static_cast<int>(group_of_row.size());
  const int ng = *std::max_element(group_of_row.begin(), group_of_row.end()) + 1;
  sp.gstart.assign(static_cast<std::size_t>(std::max(ng, 0)) + 1, 0);
  for (const int g : group_of_row)
    if (g >= 0) ++sp.gstart[static_cast<std::size_t>(g) + 1];
  for (int g = 0; g < ng; ++g) {
    if (sp.gstart[g + 1] > LinearSolver::kMaxSplitGroup)
      throw std::invalid_argument(fmt::format("LinearSolver::set_split: group {} has {} rows, at most {}", g,
                                              sp.gstart[g + 1], LinearSolver::kMaxSplitGroup));
    sp.gstart[g + 1] += sp.gstart[g];
  }
  sp.grow.resize(static_cast<std::size_t>(ng > 0 ? sp.gstart[ng] : 0));
  std::vector<int> at(sp.gstart.begin(), sp.gstart.end() - 1);
  sp.sub_of.assign(static_cast<std::size_t>(nn), -1);
  for (int r = 0; r < nn; ++r) {
    if (const int g = group_of_row[r]; g >= 0) {
      sp.grow[at[g]++] = r;
    } else {
      sp.sub_of[r] = static_cast<int>(sp.frow.size());
      sp.frow.push_back(r);
    }
  }
  sp.ginv_at.resize(static_cast<std::size_t>(std::max(ng, 0)));
  int total = 0;
  for (int g = 0; g < ng; ++g) {
    sp.ginv_at[g] = total;
    const int m = sp.gstart[g + 1] - sp.gstart[g];
    total += m * m;
  }
  sp.ginv.assign(static_cast<std::size_t>(total), 0.0);
  sp.group = std::move(group_of_row);
}

// The submatrix of the factored rows and columns (both triangles, as the caller stores M): its
// pattern, the gather of its values from the full matrix, and the blocks of its ordering.
void LinearSolver::Impl::build_sub_pattern() {
  const int nf = static_cast<int>(sp.frow.size());
  const int* Fp = sp.full.outerIndexPtr();
  const int* Fi = sp.full.innerIndexPtr();
  std::vector<int> outer(static_cast<std::size_t>(nf) + 1, 0), inner;
  sp.gather.clear();
  for (int jf = 0; jf < nf; ++jf) {
    const int j = sp.frow[jf];
    for (int q = Fp[j]; q < Fp[j + 1]; ++q)
      if (const int i = sp.sub_of[Fi[q]]; i >= 0) {
        inner.push_back(i);
        sp.gather.push_back(q);
      }
    outer[jf + 1] = static_cast<int>(inner.size());
  }
  std::vector<double> values(inner.size(), 0.0);
  sp.sub = Eigen::Map<const SpMat>(nf, nf, static_cast<Eigen::Index>(inner.size()), outer.data(), inner.data(),
                                   values.data());
  sp.sub_blocks.clear();
  if (blocks.size() == sp.group.size())
    for (const int r : sp.frow) sp.sub_blocks.push_back(blocks[r]);
  sp.tin.setZero(nf);
  sp.tout.setZero(nf);
  sp.fresh_pattern = false;
}

LinearStatus LinearSolver::Impl::factorise_split(const SpMat& Min, bool pattern_changed) {
  if (Min.rows() != Min.cols())
    throw std::invalid_argument(
        fmt::format("LinearSolver::factorise: matrix must be square, got {}x{}", Min.rows(), Min.cols()));
  if (Min.rows() != static_cast<Eigen::Index>(sp.group.size()))
    throw std::invalid_argument(fmt::format("LinearSolver::factorise: the split preconditioner has {} rows, the "
                                            "matrix {}",
                                            sp.group.size(), Min.rows()));
  SpMat storage;
  const SpMat& src = detail::compressed(Min, storage);
  factor_valid = false;
  const bool changed = pattern_changed || sp.fresh_pattern || !detail::same_pattern(src, sp.full);
  if (changed) {
    sp.full = src;
    build_sub_pattern();
  } else {
    std::copy(src.valuePtr(), src.valuePtr() + src.nonZeros(), sp.full.valuePtr());
  }
  if (const auto [r, c] = detail::first_non_finite(sp.full); r >= 0)
    return failure(fmt::format("stiffness matrix has a non-finite entry at ({}, {})", r, c));
  for (std::size_t q = 0; q < sp.gather.size(); ++q) sp.sub.valuePtr()[q] = sp.full.valuePtr()[sp.gather[q]];
  if (LinearStatus st = factorise(sp.sub, changed); !st.ok) return st;  // pivot_status names full rows
  factor_valid = false;
  if (LinearStatus st = invert_groups(); !st.ok) return st;
  factor_valid = true;
  return {};
}

// Each group's diagonal block of M (its lower triangle, as the factorisation reads M), inverted
// through its Cholesky factor: a block that is not positive definite fails like a factor pivot.
LinearStatus LinearSolver::Impl::invert_groups() {
  using Block = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, LinearSolver::kMaxSplitGroup,
                              LinearSolver::kMaxSplitGroup>;
  const int* Fp = sp.full.outerIndexPtr();
  const int* Fi = sp.full.innerIndexPtr();
  const double* Fx = sp.full.valuePtr();
  const int ng = static_cast<int>(sp.ginv_at.size());
  for (int g = 0; g < ng; ++g) {
    const int g0 = sp.gstart[g], m = sp.gstart[g + 1] - g0;
    if (m == 0) continue;
    Block B = Block::Zero(m, m);
    for (int c = 0; c < m; ++c) {
      const int j = sp.grow[g0 + c];
      for (int q = Fp[j]; q < Fp[j + 1]; ++q) {
        const int i = Fi[q];
        if (i < j) continue;
        for (int r = c; r < m; ++r)
          if (sp.grow[g0 + r] == i) B(r, c) = B(c, r) = Fx[q];
      }
    }
    const Eigen::LLT<Block> llt(B);
    const double dmin = B.diagonal().minCoeff();
    if (llt.info() != Eigen::Success || !(dmin > 0.0)) {
      LinearStatus st = failure(fmt::format(
          "stiffness matrix not positive definite in the diagonal block of rows {}..{} (preconditioner of the "
          "unfactored rows; singular or indefinite network)",
          sp.grow[g0], sp.grow[g0 + m - 1]));
      st.column = sp.grow[g0];
      return st;
    }
    const Block inv = llt.solve(Block::Identity(m, m));
    std::copy(inv.data(), inv.data() + m * m, sp.ginv.begin() + sp.ginv_at[g]);
  }
  return {};
}

bool LinearSolver::Impl::precondition(const double* in, double* out) {
  if (!split()) return apply_factor(in, out);
  const int nf = static_cast<int>(sp.frow.size());
  for (int k = 0; k < nf; ++k) sp.tin[k] = in[sp.frow[k]];
  // the groups first: in may alias out
  double tmp[LinearSolver::kMaxSplitGroup];
  const int ng = static_cast<int>(sp.ginv_at.size());
  for (int g = 0; g < ng; ++g) {
    const int g0 = sp.gstart[g], m = sp.gstart[g + 1] - g0;
    const double* inv = sp.ginv.data() + sp.ginv_at[g];
    for (int r = 0; r < m; ++r) {
      double s = 0.0;
      for (int c = 0; c < m; ++c) s += inv[r + m * c] * in[sp.grow[g0 + c]];
      tmp[r] = s;
    }
    for (int r = 0; r < m; ++r) out[sp.grow[g0 + r]] = tmp[r];
  }
  if (nf > 0 && !apply_factor(sp.tin.data(), sp.tout.data())) return false;
  for (int k = 0; k < nf; ++k) out[sp.frow[k]] = sp.tout[k];
  return true;
}

}  // namespace netdem::qs
