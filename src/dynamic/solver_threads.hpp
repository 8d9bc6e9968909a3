#pragma once
// The pair loop on DynamicOptions::threads threads (the solver's sys::ThreadTeam). Included by solver.cpp only, inside its
// namespace netdem::dem, after solver_pairs_2d.hpp and solver_pairs_3d.hpp.
//
// Each thread runs the loop of solver_pairs_{2,3}d.hpp over its block of rows with Threaded = true:
// a row's force on j, its two torque products (2D: also its branch) and its elastic energy go to
// row_buf_ instead of into the particles' sums. After a barrier each thread sums, for its block of
// particles, the rows of each particle in increasing row order (row_start_, row_list_), starting from
// the accumulator's value: the same additions in the same order as one thread's loop (which adds row
// k's force to j and subtracts it from i, then subtracts the torque products from i and j). The
// stress and energy sums then run over the rows in row order on one thread. Every result is the same
// to the last bit for any number of threads (tests/dynamic/test_dem_threads.cpp).

namespace {
constexpr std::size_t kMinThreadedRows = 4096;  // fewer rows: one thread (the same results)

// The rows of each particle in increasing order: start (n + 1 offsets) and list; a row whose two
// particles are one (a periodic self-image) is listed once. At a table build only.
void build_row_lists(std::size_t n, const std::vector<int>& pi, const std::vector<int>& pj, std::vector<int>& start,
                     std::vector<int>& list) {
  start.assign(n + 1, 0);
  const std::size_t m = pi.size();
  for (std::size_t k = 0; k < m; ++k) {
    ++start[static_cast<std::size_t>(pi[k]) + 1];
    if (pj[k] != pi[k]) ++start[static_cast<std::size_t>(pj[k]) + 1];
  }
  for (std::size_t p = 0; p < n; ++p) start[p + 1] += start[p];
  list.resize(static_cast<std::size_t>(start[n]));
  std::vector<int> next(start.begin(), start.end() - 1);
  for (std::size_t k = 0; k < m; ++k) {
    list[static_cast<std::size_t>(next[static_cast<std::size_t>(pi[k])]++)] = static_cast<int>(k);
    if (pj[k] != pi[k]) list[static_cast<std::size_t>(next[static_cast<std::size_t>(pj[k])]++)] = static_cast<int>(k);
  }
}

// Particles [p0, p1): f += the force on j of each row where p is j, f -= it where p is i, then the
// torque products, in increasing row order (S doubles per row: D force, R torque on i, R on j, ...).
template <int D>
void gather_rows(std::size_t p0, std::size_t p1, const int* start, const int* list, const int* pi, const int* pj,
                 const std::uint8_t* seen, const double* buf, double* f, double* t) {
  constexpr int R = D == 2 ? 1 : 3;
  constexpr std::size_t S = D == 2 ? 7 : 10;
  for (std::size_t p = p0; p < p1; ++p) {
    double fs[D], ts[R];
    for (int c = 0; c < D; ++c) fs[c] = f[D * p + static_cast<std::size_t>(c)];
    for (int c = 0; c < R; ++c) ts[c] = t[R * p + static_cast<std::size_t>(c)];
    const int me = static_cast<int>(p);
    for (int q = start[p]; q < start[p + 1]; ++q) {
      const auto k = static_cast<std::size_t>(list[q]);
      if (!seen[k]) continue;
      const double* const b = buf + S * k;
      const bool is_j = pj[k] == me, is_i = pi[k] == me;
      if (is_j)
        for (int c = 0; c < D; ++c) fs[c] += b[c];
      if (is_i)
        for (int c = 0; c < D; ++c) fs[c] -= b[c];
      if (is_i)
        for (int c = 0; c < R; ++c) ts[c] -= b[D + c];
      if (is_j)
        for (int c = 0; c < R; ++c) ts[c] -= b[D + R + c];
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
    build_row_lists(n, rows_.pi, rows_.pj, row_start_, row_list_);
    rows_csr_ok_ = true;
  }
  constexpr std::size_t S = D == 2 ? 7 : 10;
  if (row_buf_.size() < S * m) row_buf_.resize(S * m);  // (grows at table builds only)
  if (row_seen_.size() < m) row_seen_.resize(m);
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
    gather_rows<D>(n * t / nt, n * (t + 1) / nt, row_start_.data(), row_list_.data(), rows_.pi.data(), rows_.pj.data(),
                   row_seen_.data(), row_buf_.data(), P_.force.data(), P_.torque.data());
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
      sxx += b[0] * b[4];
      sxy += b[0] * b[5];
      syx += b[1] * b[4];
      syy += b[1] * b[5];
    } else if constexpr (Periodic) {
      add_image_stress<D>(rows_.shift[k].data(), hc, {b[0], b[1], b[2]}, s3p);
    }
    if constexpr (contact::kHasElasticEnergy<Law>) el += b[S - 1];
  }
  a.fn_max = fn_max, a.el = el;
  if constexpr (D == 2) a.sxx = sxx, a.sxy = sxy, a.syx = syx, a.syy = syy;
  if constexpr (D == 3 && Periodic) std::copy(&s3p[0][0], &s3p[0][0] + 9, &a.s3[0][0]);
}
