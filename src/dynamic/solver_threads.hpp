#pragma once
// The pair loop on DynamicOptions::threads threads (the solver's sys::ThreadTeam). Included by solver.cpp only, inside its
// namespace netdem::dem, after solver_pairs_2d.hpp and solver_pairs_3d.hpp.
//
// Each thread runs the loop of solver_pairs_{2,3}d.hpp over its block of rows with Threaded = true:
// instead of adding a row's force and torques to its two particles, it writes each particle's
// signed share (+f and -d_j (n x f_t) for j, -f and -d_i (n x f_t) for i) to the row's slot in that
// particle's list (slot_buf_, row_slot_: each particle's rows in increasing row order), and the
// force, 2D branch and elastic energy to row_buf_. After a barrier each thread adds, for its block
// of particles, the slots of each particle in order to the accumulator: the additions one thread's
// loop makes, in the same order (x - y is x + (-y) to the bit). The stress and energy sums then run
// over the rows in row order on one thread. Every result is the same to the last bit for any
// number of threads (tests/dynamic/test_dem_threads.cpp).

namespace {
constexpr std::size_t kMinThreadedRows = 4096;  // fewer rows: one thread (the same results)

// The rows of each particle in increasing order: start (n + 1 offsets) and, per row k, the place of
// k in the list of its i (slot[2k]) and of its j (slot[2k + 1]). At a table build only. A row of a
// particle with itself cannot occur (the cell is at least two ranges wide: build_table_periodic).
void build_row_slots(std::size_t n, const std::vector<int>& pi, const std::vector<int>& pj, std::vector<int>& start,
                     std::vector<int>& slot) {
  start.assign(n + 1, 0);
  const std::size_t m = pi.size();
  for (std::size_t k = 0; k < m; ++k) {
    if (pi[k] == pj[k]) throw std::logic_error("DynamicSolverT: a table row of a particle with itself");
    ++start[static_cast<std::size_t>(pi[k]) + 1];
    ++start[static_cast<std::size_t>(pj[k]) + 1];
  }
  for (std::size_t p = 0; p < n; ++p) start[p + 1] += start[p];
  slot.resize(2 * m);
  std::vector<int> next(start.begin(), start.end() - 1);
  for (std::size_t k = 0; k < m; ++k) {
    slot[2 * k] = next[static_cast<std::size_t>(pi[k])]++;
    slot[2 * k + 1] = next[static_cast<std::size_t>(pj[k])]++;
  }
}

// Particles [p0, p1): the accumulators plus their slots in order (S = D + kRot doubles per slot: the
// signed force, then the torque), i.e. the rows of each particle in increasing row order.
template <int D>
void gather_slots(std::size_t p0, std::size_t p1, const int* start, const double* slots, double* f, double* t) {
  constexpr int R = D == 2 ? 1 : 3;
  constexpr int S = D + R;
  for (std::size_t p = p0; p < p1; ++p) {
    double fs[D], ts[R];
    for (int c = 0; c < D; ++c) fs[c] = f[D * p + static_cast<std::size_t>(c)];
    for (int c = 0; c < R; ++c) ts[c] = t[R * p + static_cast<std::size_t>(c)];
    const double* b = slots + S * static_cast<std::size_t>(start[p]);
    for (int q = start[p]; q < start[p + 1]; ++q, b += S) {
      for (int c = 0; c < D; ++c) fs[c] += b[c];
      for (int c = 0; c < R; ++c) ts[c] += b[D + c];
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
  if (!rows_csr_ok_ || row_start_.size() != n + 1) {
    build_row_slots(n, rows_.pi, rows_.pj, row_start_, row_slot_);
    rows_csr_ok_ = true;
  }
  constexpr std::size_t S = D == 2 ? 5 : 4, SS = D == 2 ? 3 : 6;  // per row; per slot
  if (row_buf_.size() < S * m) row_buf_.resize(S * m);  // (grows at table builds only)
  if (row_seen_.size() < m) row_seen_.resize(m);
  if (slot_buf_.size() < 2 * SS * m) slot_buf_.resize(2 * SS * m);
  double hc[3][3] = {}, Lr[3][3] = {};
  if constexpr (Periodic) hoist_cell(hc, Lr);
  if constexpr (D == 3 && Periodic) fill_absolute_velocities(Lr);
  double fn_part[256];
  sys::ThreadTeam& team = team_.get(threads);
  auto rows = [&](int ti, int nti) {
    const auto t = static_cast<std::size_t>(ti), nt = static_cast<std::size_t>(nti);
    ForceSums part;
    std::exception_ptr failed;  // (a law's error: every member still reaches the barrier)
    try {
      if constexpr (D == 2)
        pair_forces_2d<Law, InPlace, Periodic, true>(pair_law, part, m * t / nt, m * (t + 1) / nt);
      else
        pair_forces_3d<Law, InPlace, Periodic, true>(pair_law, part, m * t / nt, m * (t + 1) / nt);
    } catch (...) {
      failed = std::current_exception();
    }
    fn_part[t] = part.fn_max;
    team.barrier();  // every row written
    if (failed) std::rethrow_exception(failed);  // (the team rethrows the lowest member's)
    gather_slots<D>(n * t / nt, n * (t + 1) / nt, row_start_.data(), slot_buf_.data(), P_.force.data(),
                    P_.torque.data());
  };
  team.run(rows);
  const int used = team.size();
  threads_used_ = used;
  double fn_max = 0.0;
  for (int t = 0; t < used; ++t) fn_max = fn_part[t] > fn_max ? fn_part[t] : fn_max;
  // the sums over the rows in row order, as one thread takes them
  double sxx = 0, sxy = 0, syx = 0, syy = 0, el = 0, s3p[3][3] = {};
  const double* const buf = row_buf_.data();
  for (std::size_t k = 0; k < m; ++k) {
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
  a.fn_max = fn_max, a.el = el;
  if constexpr (D == 2) a.sxx = sxx, a.sxy = sxy, a.syx = syx, a.syy = syy;
  if constexpr (D == 3 && Periodic) std::copy(&s3p[0][0], &s3p[0][0] + 9, &a.s3[0][0]);
}
