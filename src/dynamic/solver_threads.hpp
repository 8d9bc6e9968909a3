#pragma once
// The pair loop on DynamicOptions::threads threads (the solver's sys::ThreadTeam). Included by solver.cpp only, inside its
// namespace netdem::dem, after solver_pairs_2d.hpp and solver_pairs_3d.hpp.
//
// The rows are sorted by (i, j), i < j. Thread t owns a block of particles [P_t, P_t+1) and the rows
// whose i is in it (a contiguous range, about m / threads rows). One thread adds a particle's shares
// to its accumulator in row order: the rows where it is j (coming from smaller i) first, then its
// own. A particle that only rows of its own block reach gets them in that order from its owner,
// which adds them directly. A boundary particle, reached by a row of an earlier block, gets every
// share (+f and -d_j (n x f_t) as j, -f and -d_i (n x f_t) as i) written to the row's slot in its
// list (slot_buf_, row_slot_: its rows in increasing row order), and after a barrier its owner adds
// the slots in order: the additions of one thread's loop, in the same order (x - y is x + (-y) to
// the bit). The stress and energy sums: the first block's rows in its loop, then the other rows
// from row_buf_ in row order on the first thread. Every result is the same to the last bit for
// any number of threads (tests/dynamic/test_dem_threads.cpp); only the boundary particles (a few
// per cent with Morton-ordered particles) pay for it.

namespace {
constexpr std::size_t kMinThreadedRows = 4096;  // fewer rows: one thread (the same results)
// A row of sum_rows_after_first against a row of the loop (perf, bench_dem N = 3e4 2D, 1e5 3D)
template <int D>
constexpr double kTailCost = D == 2 ? 0.27 : 0.05;

// The blocks of nt threads over the rows (pi sorted, pj): blk_p (nt + 1 particle bounds), blk_k
// (nt + 1 row bounds), the boundary particles by block (list, off), and per row k the slot of its i
// (slot[2k]) and of its j (slot[2k + 1]) in the boundary particle's list, -1 for any other particle;
// start: the boundary particles' slot offsets (list.size() + 1). At a table build or a new count.
// The first thread also sums the other blocks' rows (sum_rows_after_first), at tail_cost of a row
// of the loop each: it takes r0 = m (1/(nt-1) - c) / (1 - c + 1/(nt-1)) rows, so that
// r0 + c (m - r0) = (m - r0)/(nt - 1), the rows of each other thread. (Any split gives the same
// results; only the balance depends on it.)
void build_blocks(std::size_t n, int nt, double tail_cost, const std::vector<int>& pi, const std::vector<int>& pj,
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
  const double o = T > 1 ? 1.0 / static_cast<double>(T - 1) : 0.0, md = static_cast<double>(m);
  const double r0 = std::max(0.0, md * (o - tail_cost) / (1.0 - tail_cost + o)), r = (md - r0) * o;
  for (std::size_t t = 1; t < T; ++t) {
    const auto b = std::min(m - 1, static_cast<std::size_t>(r0 + r * static_cast<double>(t - 1)));
    blk_p[t] = m == 0 ? n : static_cast<std::size_t>(pi[b]);
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
  const int threads = opt_.threads;
  threads_used_ = 1;
  if (threads <= 1 || m < kMinThreadedRows) {
    if constexpr (D == 2)
      pair_forces_2d<Law, InPlace, Periodic, false>(pair_law, a, 0, m);
    else
      pair_forces_3d<Law, InPlace, Periodic, false>(pair_law, a, 0, m);
    return;
  }
  if (pair_live_.size() != m) pair_live_.assign(m, 1);
  sys::ThreadTeam& team = team_.get(threads);
  const int nt = team.size();
  if (!rows_csr_ok_ || blk_threads_ != nt) {
    build_blocks(n, nt, kTailCost<D>, rows_.pi, rows_.pj, blk_p_, blk_k_, bnd_list_, bnd_off_, row_start_, row_slot_);
    blk_threads_ = nt;
    rows_csr_ok_ = true;
  }
  constexpr std::size_t S = D == 2 ? 5 : 4, SS = D == 2 ? 3 : 6;  // per row; per slot
  if (row_buf_.size() < S * m) row_buf_.resize(S * m);  // (grows at table builds only)
  if (row_seen_.size() < m) row_seen_.resize(m);
  const auto slots = static_cast<std::size_t>(row_start_.back());
  if (slot_buf_.size() < SS * slots) slot_buf_.resize(SS * slots);
  double hc[3][3] = {}, Lr[3][3] = {};
  if constexpr (Periodic) hoist_cell(hc, Lr);
  if constexpr (D == 3 && Periodic) fill_absolute_velocities(Lr);
  double fn_part[256];
  ForceSums first;  // the first block's sums, then every row's
  auto rows = [&](int ti, int) {
    const auto t = static_cast<std::size_t>(ti);
    ForceSums part;
    std::exception_ptr failed;  // (a law's error: every member still reaches the barrier)
    try {
      if constexpr (D == 2)
        pair_forces_2d<Law, InPlace, Periodic, true>(pair_law, part, blk_k_[t], blk_k_[t + 1], t == 0);
      else
        pair_forces_3d<Law, InPlace, Periodic, true>(pair_law, part, blk_k_[t], blk_k_[t + 1], t == 0);
    } catch (...) {
      failed = std::current_exception();
    }
    fn_part[t] = part.fn_max;
    if (t == 0) first = part;
    team.barrier();  // every row written
    if (failed) std::rethrow_exception(failed);  // (the team rethrows the lowest member's)
    gather_slots<D>(bnd_off_[t], bnd_off_[t + 1], bnd_list_.data(), row_start_.data(), slot_buf_.data(),
                    P_.force.data(), P_.torque.data());
    if (t == 0) sum_rows_after_first<Law, Periodic>(first, hc);
  };
  team.run(rows);
  threads_used_ = nt;
  double fn_max = 0.0;
  for (int t = 0; t < nt; ++t) fn_max = fn_part[t] > fn_max ? fn_part[t] : fn_max;
  a.fn_max = fn_max, a.el = first.el;
  if constexpr (D == 2) a.sxx = first.sxx, a.sxy = first.sxy, a.syx = first.syx, a.syy = first.syy;
  if constexpr (D == 3 && Periodic) std::copy(&first.s3[0][0], &first.s3[0][0] + 9, &a.s3[0][0]);
}

// The stress and energy sums over the rows after the first block, in row order, continuing the
// first block's (a), as one thread takes them.
template <int D>
template <class Law, bool Periodic>
void DynamicSolverT<D>::sum_rows_after_first(ForceSums& a, const double (&hc)[3][3]) const {
  constexpr std::size_t S = D == 2 ? 5 : 4;
  double sxx = a.sxx, sxy = a.sxy, syx = a.syx, syy = a.syy, el = a.el, s3p[3][3];
  std::copy(&a.s3[0][0], &a.s3[0][0] + 9, &s3p[0][0]);
  const double* const buf = row_buf_.data();
  (void)hc;
  for (std::size_t k = blk_k_[1]; k < rows_.pairs(); ++k) {
    if (!row_seen_[k]) continue;
    const double* const b = buf + S * k;
    if constexpr (D == 2) {
      sxx += b[0] * b[2];
      sxy += b[0] * b[3];
      syx += b[1] * b[2];
      syy += b[1] * b[3];
    } else if constexpr (Periodic) {
      add_image_stress<D>(rows_.shift[k].data(), hc, {b[0], b[1], b[2]}, s3p);
    }
    if constexpr (contact::kHasElasticEnergy<Law>) el += b[S - 1];
  }
  a.el = el;
  if constexpr (D == 2) a.sxx = sxx, a.sxy = sxy, a.syx = syx, a.syy = syy;
  if constexpr (D == 3 && Periodic) std::copy(&s3p[0][0], &s3p[0][0] + 9, &a.s3[0][0]);
}
