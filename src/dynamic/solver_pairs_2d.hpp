#pragma once
// The 2D particle-particle force loop of DynamicSolverT<2>. Included by solver.cpp only, inside its
// namespace netdem::dem, where NETDEM_FLATTEN and the helper add_image are defined.
//
// The rows of the Verlet table are taken in chunks of kRowChunk. Pass 1a gathers, per row, the
// branch, the touching test, the relative velocity and the spins (stored for the rows the law will
// see, in row order, without a branch); pass 1b is one flat loop over those (the square root, the
// division, n, the overlap and the relative velocity of the contact points: the rows are
// independent, so the square root and division of one row overlap those of the next, where one
// pass waited for them before the law of each row); pass 2 runs the law and the sums in row order.
// Every row sees the same operations in the same order as in one pass, so the results are the same
// to the last bit (docs/performance.md "Issue 31"). The chunk's arrays (16 doubles per row, 16 KB)
// stay in L1.

namespace {
// The threaded loops (solver_threads.hpp): a particle's share of a row (D force components, then R
// torque components) into its slot if it is a boundary particle (slot >= 0), else added to its
// accumulators f and t here (adding -x is subtracting x, to the bit).
template <int D, int R>
inline void add_share(int slot, double* slot_buf, double* f, double* t, const double (&s)[D + R]) {
  if (slot >= 0) {
    std::copy_n(s, D + R, slot_buf + (D + R) * slot);
    return;
  }
  for (int c = 0; c < D; ++c) f[c] += s[c];
  for (int c = 0; c < R; ++c) t[c] += s[D + c];
}
// A row the law does not see: its boundary particles' slots hold zeros (adding +0 leaves a sum as it
// is: no accumulator is -0).
template <int S>
inline void clear_shares(const int* row_slot, std::size_t k, double* slot_buf) {
  if (row_slot[2 * k] >= 0) std::fill_n(slot_buf + S * row_slot[2 * k], S, 0.0);
  if (row_slot[2 * k + 1] >= 0) std::fill_n(slot_buf + S * row_slot[2 * k + 1], S, 0.0);
}
}  // namespace

template <int D>
template <class Law, bool InPlace, bool Periodic, bool Threaded>
NETDEM_FLATTEN void DynamicSolverT<D>::pair_forces_2d(const Law& pair_law, ForceSums& a, std::size_t k_begin,
                                                      std::size_t k_end) {
  static_assert(D == 2);
  using H = typename Law::History;
  constexpr std::size_t kRowChunk = 128;
  const double dt = ts_.dt;
  H* const pair_hist = table<H>().pair.data();  // the law's table, taken once per evaluation
  // the stress and energy per group of kSumGroup particles (the rows of its i), in row order: the
  // caller adds the groups in order (the same sums for any thread count)
  double sxx = 0, sxy = 0, syx = 0, syy = 0, el = 0, fn_max = 0;
  double* const grp = grp_sums_.data();
  std::size_t g_end = 0, g_now = 0;  // the current group: particles below g_end; g_now its index
  auto next_group = [&](std::size_t i) {  // stores the group's sums (if any), starts the group of i
    double* const q = grp + kGroupSums * g_now;
    if (g_end > 0) q[0] = sxx, q[1] = sxy, q[2] = syx, q[3] = syy, q[4] = el;
    sxx = sxy = syx = syy = el = 0.0;
    g_now = i / kSumGroup, g_end = (g_now + 1) * kSumGroup;
  };
  if constexpr (!Threaded)  // (threads: the caller)
    if (pair_live_.size() != rows_.pairs()) pair_live_.assign(rows_.pairs(), 1);
  // the particle arrays, hoisted (the loop stores forces: the vectors' data pointers are not reloaded)
  const double* const p_x = P_.pos.data();
  const double* const p_v = P_.vel.data();
  const double* const p_w = P_.spin.data();
  const double* const p_radius = P_.r.data();
  double* const p_f = P_.force.data();
  double* const p_t = P_.torque.data();
  double hc[3][3] = {}, Lr[3][3] = {};  // periodic: the cell and the strain rate, 3 x 3
  if constexpr (Periodic) hoist_cell(hc, Lr);
  const int* const p_i = rows_.pi.data();  // the rows' particles and images
  const int* const p_j = rows_.pj.data();
  const auto* const shift = rows_.shift.data();
  // pass 1a, per row of the chunk: touching; per row the law will see (touching, or a history that
  // outlives separation), in the order of the rows: the branch l = x_j (+ h n) - x_i, L^2, r_i + r_j,
  // r_i^2 - r_j^2, the relative velocity v_j - v_i (+ L l) and the spins; pass 1b (a flat loop over
  // those, vectorised): n, the overlap, the centre-to-chord distances and the relative velocity of
  // the contact points
  bool g_touch[kRowChunk];
  double g_dx[kRowChunk], g_dy[kRowChunk], g_L2[kRowChunk], g_s[kRowChunk], g_r2[kRowChunk];
  double g_vx[kRowChunk], g_vy[kRowChunk], g_wi[kRowChunk], g_wj[kRowChunk];
  double g_ov[kRowChunk], g_nx[kRowChunk], g_ny[kRowChunk], g_di[kRowChunk], g_dj[kRowChunk];
  double g_vn[kRowChunk], g_vt[kRowChunk];
  // Threaded (solver_threads.hpp): a boundary particle's signed share (force, torque: 3 per slot) in
  // the slot of the row in its list (row_slot >= 0), every other particle's added to its
  // accumulator here
  double* const slot_buf = slot_buf_.data();
  const int* const row_slot = row_slot_.data();
  for (std::size_t k0 = k_begin; k0 < k_end; k0 += kRowChunk) {
    const std::size_t m = std::min(kRowChunk, k_end - k0);
    std::size_t mt = 0;
    for (std::size_t c = 0; c < m; ++c) {  // pass 1a
      const std::size_t k = k0 + c;
      const auto i = static_cast<std::size_t>(p_i[k]);
      const auto j = static_cast<std::size_t>(p_j[k]);
      const double* const xi = p_x + D * i;
      const double* const xj = p_x + D * j;
      double dx = xj[0] - xi[0], dy = xj[1] - xi[1], dz = 0.0;
      const double ri = p_radius[i], rj = p_radius[j];
      if constexpr (Periodic) add_image<D>(shift[k].data(), hc, dx, dy, dz);
      const double L2 = dx * dx + dy * dy, s = ri + rj;
      const bool touch = L2 < s * s;
      g_touch[c] = touch;
      const double *const vi = p_v + D * i, *const vj = p_v + D * j;
      double rvx = vj[0] - vi[0], rvy = vj[1] - vi[1];
      if constexpr (Periodic) {  // the affine field's part: L (x_j + h n - x_i)
        rvx += Lr[0][0] * dx + Lr[0][1] * dy;
        rvy += Lr[1][0] * dx + Lr[1][1] * dy;
      }
      // (stored at mt whatever the row; kept, mt + 1, when the law will see it: no branch)
      g_dx[mt] = dx, g_dy[mt] = dy, g_L2[mt] = L2, g_s[mt] = s, g_r2[mt] = ri * ri - rj * rj;
      g_vx[mt] = rvx, g_vy[mt] = rvy, g_wi[mt] = p_w[i], g_wj[mt] = p_w[j];
      mt += law_sees<Law>(touch, pair_live_[k]) ? 1 : 0;
    }
    for (std::size_t t = 0; t < mt; ++t) {  // pass 1b
      const double L = std::sqrt(g_L2[t]), iL = 1.0 / L;
      const double nx = g_dx[t] * iL, ny = g_dy[t] * iL, tx = -ny, ty = nx;  // n from i to j, t = perp(n)
      const double q = g_r2[t] * (0.5 * iL);
      const double di = 0.5 * L + q, dj = 0.5 * L - q;  // centre-to-chord distances (kinematics.hpp)
      // velocity of j's contact point relative to i's: v_j - w_j d_j t - (v_i + w_i d_i t)
      const double rvx = g_vx[t], rvy = g_vy[t];
      g_ov[t] = g_s[t] - L, g_nx[t] = nx, g_ny[t] = ny, g_di[t] = di, g_dj[t] = dj;
      g_vn[t] = rvx * nx + rvy * ny;
      g_vt[t] = rvx * tx + rvy * ty - g_wi[t] * di - g_wj[t] * dj;
    }
    std::size_t t = 0;  // the next row the law sees
    for (std::size_t c = 0; c < m; ++c) {  // pass 2: the law, forces, torques and sums
      const std::size_t k = k0 + c;
      if (skip_row<Law>(g_touch[c], pair_live_[k], pair_hist[k])) {
        if constexpr (Threaded) clear_shares<3>(row_slot, k, slot_buf);
        continue;
      }
      pair_live_[k] = 1;
      const auto i = static_cast<std::size_t>(p_i[k]);
      const auto j = static_cast<std::size_t>(p_j[k]);
      if (i >= g_end) next_group(i);  // (rows sorted by i)
      const double nx = g_nx[t], ny = g_ny[t], tx = -ny, ty = nx, dx = g_dx[t], dy = g_dy[t];
      const double vt = g_vt[t];
      contact::ContactKinematics in;
      in.overlap = g_ov[t];
      in.v_n = -g_vn[t];
      in.v_t = vt;
      in.dslip = vt * dt;
      in.dt = dt;
      if constexpr (contact::kReadsPairProperties<Law>) {  // (the Luding law reads neither)
        const double ri = p_radius[i], rj = p_radius[j], s = ri + rj;
        in.overlap_start = in.overlap - in.v_n * dt;
        in.r_eff = ri * rj / s;
        in.m_eff = P_.mass[i] * P_.mass[j] / (P_.mass[i] + P_.mass[j]);
      }
      double f_n, f_t;
      contact::update_contact<InPlace>(pair_law, pair_hist[k], in, f_n, f_t);
      if constexpr (Law::kHistoryOutlivesSeparation) pair_live_[k] = pair_law.has_history(pair_hist[k]) ? 1 : 0;
      if constexpr (contact::kHasContactArea<Law>) fn_max = f_n > fn_max ? f_n : fn_max;
      const double fx = f_n * nx + f_t * tx, fy = f_n * ny + f_t * ty;  // force on j
      if constexpr (Threaded) {  // the same shares; a boundary particle's later, in row order
        add_share<2, 1>(row_slot[2 * k + 1], slot_buf, p_f + D * j, p_t + j, {fx, fy, -(g_dj[t] * f_t)});
        add_share<2, 1>(row_slot[2 * k], slot_buf, p_f + D * i, p_t + i, {-fx, -fy, -(g_di[t] * f_t)});
      } else {
        double *const fi = p_f + D * i, *const fj = p_f + D * j;
        fj[0] += fx;
        fj[1] += fy;
        fi[0] -= fx;
        fi[1] -= fy;
        p_t[i] -= g_di[t] * f_t;  // M_i = M_j = -d F_T (kinematics.hpp)
        p_t[j] -= g_dj[t] * f_t;
      }
      sxx += fx * dx;  // Sigma = (1/V) sum f (x) l, l = x_j - x_i
      sxy += fx * dy;
      syx += fy * dx;
      syy += fy * dy;
      if constexpr (contact::kHasElasticEnergy<Law>) el += pair_law.elastic_energy(in);
      ++t;
    }
  }
  next_group(0);
  a.fn_max = fn_max;
}
