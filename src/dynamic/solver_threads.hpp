#pragma once
// The pair loop on DynamicOptions::threads threads (the solver's sys::ThreadTeam). Included by solver.cpp only, inside its
// namespace netdem::dem, after solver_pairs_2d.hpp and solver_pairs_3d.hpp.
//
// The rows are sorted by (i, j), i < j. Thread t owns a block of particles [P_t, P_t+1), whole groups
// of kSumGroup particles, and the rows whose i is in it (a contiguous range, about m / threads
// rows). One thread adds to a particle first the rows where it is j (from smaller i), then its
// own, in row order. A particle that only rows of its own block reach gets them in that order from
// its owner, which adds them directly. A boundary particle, reached by a row of an earlier block,
// gets every share (+f and -d_j (n x f_t) as j, -f and -d_i (n x f_t) as i) written to the row's
// slot in its list (slot_buf_, row_slot_: its rows in increasing row order), and after a barrier
// its owner adds the slots in order: the additions of one thread's loop, in the same order (x - y
// is x + (-y) to the bit). The stress and energy are summed per group of kSumGroup particles in
// row order and the groups added in order, on one thread or many. Every result is the same to the
// last bit for any number of threads (tests/dynamic/test_dem_threads.cpp); only the boundary
// particles (a few per cent with Morton-ordered particles) pay, and no per-row data crosses threads.

namespace {
constexpr std::size_t kMinThreadedRows = 4096;  // fewer rows: one thread (the same results)

// The blocks of nt threads over the rows (pi sorted, pj): blk_p (nt + 1 particle bounds), blk_k
// (nt + 1 row bounds), the boundary particles by block (list, off), and per row k the slot of its i
// (slot[2k]) and of its j (slot[2k + 1]) in the boundary particle's list, -1 for any other particle;
// start: the boundary particles' slot offsets (list.size() + 1). At a table build or a new count.
// The blocks start at multiples of the group size G.
void build_blocks(std::size_t n, int nt, std::size_t G, const std::vector<int>& pi, const std::vector<int>& pj,
                  std::vector<std::size_t>& blk_p, std::vector<std::size_t>& blk_k, std::vector<int>& list,
                  std::vector<int>& off, std::vector<int>& start, std::vector<int>& slot) {
  const std::size_t m = pi.size(), T = static_cast<std::size_t>(nt);
  for (std::size_t k = 0; k < m; ++k) {
    if (pi[k] >= pj[k]) throw std::logic_error("DynamicSolverT: a table row with i >= j");
    if (k > 0 && pi[k] < pi[k - 1]) throw std::logic_error("DynamicSolverT: table rows not sorted by i");
  }
  blk_p.assign(T + 1, 0);
  blk_k.assign(T + 1, 0);
  blk_p[T] = n;
  blk_k[T] = m;
  for (std::size_t t = 1; t < T; ++t) {
    const std::size_t b = m == 0 ? 0 : std::min(m - 1, m * t / T);
    blk_p[t] = m == 0 ? n : std::max(blk_p[t - 1], std::min(n, static_cast<std::size_t>(pi[b]) / G * G));
    blk_k[t] = static_cast<std::size_t>(std::lower_bound(pi.begin(), pi.end(), static_cast<int>(blk_p[t])) - pi.begin());
  }
  std::vector<int> idx(n, -1);  // the boundary particles' places in list
  for (std::size_t t = 0; t < T; ++t)
    for (std::size_t k = blk_k[t]; k < blk_k[t + 1]; ++k)
      if (static_cast<std::size_t>(pj[k]) >= blk_p[t + 1]) idx[static_cast<std::size_t>(pj[k])] = 0;
  list.clear();
  off.assign(T + 1, 0);
  for (std::size_t t = 0; t < T; ++t) {
    for (std::size_t p = blk_p[t]; p < blk_p[t + 1]; ++p)
      if (idx[p] == 0) {
        idx[p] = static_cast<int>(list.size());
        list.push_back(static_cast<int>(p));
      }
    off[t + 1] = static_cast<int>(list.size());
  }
  start.assign(list.size() + 1, 0);
  for (std::size_t k = 0; k < m; ++k) {
    for (const int p : {pi[k], pj[k]})
      if (idx[static_cast<std::size_t>(p)] >= 0) ++start[static_cast<std::size_t>(idx[static_cast<std::size_t>(p)]) + 1];
  }
  for (std::size_t b = 0; b < list.size(); ++b) start[b + 1] += start[b];
  slot.assign(2 * m, -1);
  std::vector<int> next(start.begin(), start.end() - 1);
  for (std::size_t k = 0; k < m; ++k) {
    const int a = idx[static_cast<std::size_t>(pi[k])], b = idx[static_cast<std::size_t>(pj[k])];
    if (a >= 0) slot[2 * k] = next[static_cast<std::size_t>(a)]++;
    if (b >= 0) slot[2 * k + 1] = next[static_cast<std::size_t>(b)]++;
  }
}

// The boundary particles list[b0 .. b1): the accumulators plus their slots in order (S = D + kRot
// doubles per slot: the signed force, then the torque), i.e. each one's rows in increasing row order.
template <int D>
void gather_slots(int b0, int b1, const int* list, const int* start, const double* slots, double* f, double* t) {
  constexpr int R = D == 2 ? 1 : 3;
  constexpr int S = D + R;
  for (int b = b0; b < b1; ++b) {
    const auto p = static_cast<std::size_t>(list[b]);
    double fs[D], ts[R];
    for (int c = 0; c < D; ++c) fs[c] = f[D * p + static_cast<std::size_t>(c)];
    for (int c = 0; c < R; ++c) ts[c] = t[R * p + static_cast<std::size_t>(c)];
    const double* s = slots + S * static_cast<std::size_t>(start[b]);
    for (int q = start[b]; q < start[b + 1]; ++q, s += S) {
      for (int c = 0; c < D; ++c) fs[c] += s[c];
      for (int c = 0; c < R; ++c) ts[c] += s[D + c];
    }
    for (int c = 0; c < D; ++c) f[D * p + static_cast<std::size_t>(c)] = fs[c];
    for (int c = 0; c < R; ++c) t[R * p + static_cast<std::size_t>(c)] = ts[c];
  }
}
}  // namespace

template <int D>
template <class Law, bool InPlace, bool Periodic>
void DynamicSolverT<D>::pair_forces(const Law& pair_law, ForceSums& a) {
  const std::size_t m = rows_.pairs(), n = P_.size();
  const std::size_t groups = sum_groups();
  grp_sums_.assign(kGroupSums * groups, 0.0);  // (no allocation once grown)
  if constexpr (D == 3) pst_sums_.resize(9 * groups);
  const int threads = opt_.threads;
  threads_used_ = 1;
  if (threads <= 1 || m < kMinThreadedRows) {
    if constexpr (D == 2) {
      pair_forces_2d<Law, InPlace, Periodic, false>(pair_law, a, 0, m);
    } else {
      pair_forces_3d<Law, InPlace, Periodic, false>(pair_law, a, 0, m);
      particle_stress_groups(0, groups);
    }
    add_group_sums<Periodic>(a);
    return;
  }
  if (pair_live_.size() != m) pair_live_.assign(m, 1);
  sys::ThreadTeam& team = team_.get(threads);
  const int nt = team.size();
  if (!rows_csr_ok_ || blk_threads_ != nt) {
    build_blocks(n, nt, kSumGroup, rows_.pi, rows_.pj, blk_p_, blk_k_, bnd_list_, bnd_off_, row_start_, row_slot_);
    blk_threads_ = nt;
    rows_csr_ok_ = true;
  }
  constexpr std::size_t SS = D == 2 ? 3 : 6;  // per slot
  const auto slots = static_cast<std::size_t>(row_start_.back());
  if (slot_buf_.size() < SS * slots) slot_buf_.resize(SS * slots);  // (grows at table builds only)
  if constexpr (D == 3 && Periodic) {
    double hc[3][3] = {}, Lr[3][3] = {};
    hoist_cell(hc, Lr);
    fill_absolute_velocities(Lr);
  }
  double fn_part[256];
  auto rows = [&](int ti, int) {
    const auto t = static_cast<std::size_t>(ti);
    ForceSums part;
    std::exception_ptr failed;  // (a law's error: every member still reaches the barrier)
    try {
      if constexpr (D == 2)
        pair_forces_2d<Law, InPlace, Periodic, true>(pair_law, part, blk_k_[t], blk_k_[t + 1]);
      else
        pair_forces_3d<Law, InPlace, Periodic, true>(pair_law, part, blk_k_[t], blk_k_[t + 1]);
    } catch (...) {
      failed = std::current_exception();
    }
    fn_part[t] = part.fn_max;
    team.barrier();  // every row written
    if (failed) std::rethrow_exception(failed);  // (the team rethrows the lowest member's)
    gather_slots<D>(bnd_off_[t], bnd_off_[t + 1], bnd_list_.data(), row_start_.data(), slot_buf_.data(),
                    P_.force.data(), P_.torque.data());
    // 3D: the block's particles' forces are final: their groups of pair_stress_3d's sum
    if constexpr (D == 3) particle_stress_groups(blk_p_[t] / kSumGroup, (blk_p_[t + 1] + kSumGroup - 1) / kSumGroup);
  };
  team.run(rows);
  threads_used_ = nt;
  double fn_max = 0.0;
  for (int t = 0; t < nt; ++t) fn_max = fn_part[t] > fn_max ? fn_part[t] : fn_max;
  a.fn_max = fn_max;
  add_group_sums<Periodic>(a);
}

// The stress and energy: the groups' sums (each in row order) added in group order.
template <int D>
template <bool Periodic>
void DynamicSolverT<D>::add_group_sums(ForceSums& a) const {
  double s[kGroupSums] = {};
  for (std::size_t g = 0; g < grp_sums_.size(); g += kGroupSums)
    for (std::size_t c = 0; c < kGroupSums; ++c) s[c] += grp_sums_[g + c];
  if constexpr (D == 2) {
    a.sxx = s[0], a.sxy = s[1], a.syx = s[2], a.syy = s[3], a.el = s[4];
  } else {
    a.el = s[0];
    if constexpr (Periodic) std::copy(s + 1, s + 10, &a.s3[0][0]);
  }
}
