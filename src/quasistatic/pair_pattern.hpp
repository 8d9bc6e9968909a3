#pragma once
// Private: the sparsity pattern, the slots and the assembly of an implicit network of pair
// elements over the DOFs of two nodes (issue 26), shared by the network solver (its 6x6 or 12x12
// contact elements, NetworkSolverT<D>) and the staggered scheme (its 12x12 bonds).
//
//   * nodes of kN DOFs; dof[kN p + c] = free index or -1 (prescribed or fixed), the free DOFs
//     numbered node by node;
//   * the matrix: nfree x nfree, full storage, compressed columns; column (p, b) holds the free
//     DOFs of p and of the nodes paired with p, in DOF order (the diagonal block of every node with
//     a free DOF, one block pair per pair). Entries of pairs apart stay as explicit zeros, so the
//     pattern changes only when the pairs do (and CHOLMOD analyses it only then);
//   * the slots: per pair k, (2 kN)^2 value indices, slots(k)[2 kN b + a] for row a and column b of
//     the pair's element (a, b over the first node's DOFs, then the second's), -1 where a DOF is
//     not free; per free DOF the index of its diagonal entry.
// Both solvers add their element matrices through the slots in pair order (for_each_entry: the
// one assembly loop, for any element over the DOFs of two nodes), so the sums do not depend on
// how the pattern was built.
#include <algorithm>
#include <cstddef>
#include <utility>
#include <vector>

#include "netdem/quasistatic/linear_solver.hpp"

namespace netdem::qs {

class PairPattern {
 public:
  /// K's structure (values zero) and the slots for np pairs pair(k) = (i, j), i != j, over n
  /// nodes of node_dofs DOFs each (a pair given twice gets the same slots).
  template <class PairOf>
  void build(SpMat& K, int n, int node_dofs, const std::vector<int>& dof, int nfree, std::size_t np, PairOf&& pair) {
    const int kN = node_dofs, kP = 2 * node_dofs;
    kP2_ = static_cast<std::size_t>(kP) * static_cast<std::size_t>(kP);
    // the partners of each node (CSR)
    start_.assign(static_cast<std::size_t>(n) + 1, 0);
    for (std::size_t k = 0; k < np; ++k) {
      const auto [i, j] = pair(k);
      ++start_[static_cast<std::size_t>(i) + 1];
      ++start_[static_cast<std::size_t>(j) + 1];
    }
    for (int p = 0; p < n; ++p) start_[p + 1] += start_[p];
    partner_.resize(static_cast<std::size_t>(start_[n]));
    fill_.assign(start_.begin(), start_.end() - 1);
    for (std::size_t k = 0; k < np; ++k) {
      const auto [i, j] = pair(k);
      partner_[fill_[i]++] = j;
      partner_[fill_[j]++] = i;
    }
    auto neighbourhood = [&](int p) {  // p and its partners, sorted, each once
      near_.assign(1, p);
      near_.insert(near_.end(), partner_.begin() + start_[p], partner_.begin() + start_[p + 1]);
      std::sort(near_.begin(), near_.end());
      near_.erase(std::unique(near_.begin(), near_.end()), near_.end());
    };
    auto free_of = [&](int q) {
      int c = 0;
      for (int a = 0; a < kN; ++a) c += dof[kN * q + a] >= 0;
      return c;
    };
    K.resize(nfree, nfree);
    int* outer = K.outerIndexPtr();
    outer[0] = 0;
    for (int p = 0; p < n; ++p) {
      if (free_of(p) == 0) continue;
      neighbourhood(p);
      int rows = 0;
      for (const int q : near_) rows += free_of(q);
      for (int b = 0; b < kN; ++b)
        if (const int d = dof[kN * p + b]; d >= 0) outer[d + 1] = rows;
    }
    for (int d = 0; d < nfree; ++d) outer[d + 1] += outer[d];
    K.resizeNonZeros(outer[nfree]);
    int* inner = K.innerIndexPtr();
    std::fill(K.valuePtr(), K.valuePtr() + outer[nfree], 0.0);
    for (int p = 0; p < n; ++p) {
      if (free_of(p) == 0) continue;
      neighbourhood(p);
      for (int b = 0; b < kN; ++b) {
        const int d = dof[kN * p + b];
        if (d < 0) continue;
        int at = outer[d];
        for (const int q : near_)
          for (int a = 0; a < kN; ++a)
            if (const int row = dof[kN * q + a]; row >= 0) inner[at++] = row;
      }
    }
    auto find = [&](int row, int col) -> int {
      const int* b = inner + outer[col];
      const int* e = inner + outer[col + 1];
      return static_cast<int>(std::lower_bound(b, e, row) - inner);
    };
    slot_.assign(kP2_ * np, -1);
    for (std::size_t k = 0; k < np; ++k) {
      const auto [i, j] = pair(k);
      const int nodes[2] = {i, j};
      int* s = &slot_[kP2_ * k];
      for (int a = 0; a < kP; ++a)
        for (int b = 0; b < kP; ++b) {
          const int ra = dof[kN * nodes[a / kN] + a % kN], cb = dof[kN * nodes[b / kN] + b % kN];
          if (ra >= 0 && cb >= 0) s[kP * b + a] = find(ra, cb);
        }
    }
    diag_.resize(static_cast<std::size_t>(nfree));
    for (int d = 0; d < nfree; ++d) diag_[d] = find(d, d);
  }

  /// The value indices of pair k's element entries (row a, column b at [2 kN b + a]; -1: not free).
  const int* slots(std::size_t k) const { return &slot_[kP2_ * k]; }
  /// The assembly of pair k's element: fn(q, a, b) for every entry (row a, column b of the
  /// element, 0 <= a, b < kP = 2 kN) whose DOFs are both free, q its value index. Distinct entries
  /// of one element have distinct q, so a sum over the pairs in pair order does not depend on the
  /// order within an element.
  template <int kP, class Fn>
  void for_each_entry(std::size_t k, Fn&& fn) const {
    const int* s = slots(k);
    for (int b = 0; b < kP; ++b)
      for (int a = 0; a < kP; ++a)
        if (const int q = s[kP * b + a]; q >= 0) fn(q, a, b);
  }
  /// The value index of the diagonal entry of free DOF d.
  int diag(int d) const { return diag_[static_cast<std::size_t>(d)]; }

 private:
  std::size_t kP2_ = 0;
  std::vector<int> slot_, diag_;
  std::vector<int> start_, partner_, fill_, near_;  // scratch of build()
};

}  // namespace netdem::qs
