#pragma once
// The 3D particle-particle force loop of DynamicSolverT<3>. Included by solver.cpp only, inside its
// namespace netdem::dem, where NETDEM_FLATTEN and the helpers add_image* are defined.
//
// As the 2D loop (solver_pairs_2d.hpp), in chunks of kRowChunk rows: pass 1a gathers, per row, the
// branch, the touching test, the relative velocity and the spins (stored for the rows the law will
// see, in row order, without a branch); pass 1b is one flat loop over those (the square root, the
// division, n, the overlap, the relative velocity of the contact points and the step's rotation);
// pass 2 runs the law and the sums in row order. Every row sees the same operations in the same
// order as in one pass: the same results to the last bit (docs/performance.md "Issue 31").
//
// Periodic (issue 29): the branch to the image of j, x_j + h n - x_i, and the velocities are the
// fluctuations about the affine field, so that the relative velocity adds L times the branch: as
// L (x_j - x_i) + L h n, with v + L x per particle (vel_abs_, one pass) and L h n only on the rows
// across a face, and the stress as the walled loop's sum over the particles (pair_stress_3d) plus
// f (x) h n on those rows (docs/performance.md "The 3D periodic force loop").
template <int D>
template <class Law, bool InPlace, bool Periodic, bool Threaded>
NETDEM_FLATTEN void DynamicSolverT<D>::pair_forces_3d(const Law& pair_law, ForceSums& a, std::size_t k_begin,
                                                      std::size_t k_end) {
  static_assert(D == 3);
  using H = typename Law::History;
  constexpr std::size_t kRowChunk = 64;
  const double dt = ts_.dt;
  H* const pair_hist = table<H>().pair.data();  // the law's table, taken once per evaluation
  double el = 0, fn_max = 0, s3p[3][3] = {};  // (periodic: f (x) h n over the rows across a face)
  // the energy and s3p per group of kSumGroup particles in row order; the caller adds the groups
  double* const grp = grp_sums_.data();
  std::size_t g_end = 0, g_now = 0;  // the current group: particles below g_end; g_now its index
  auto next_group = [&](std::size_t i) {  // stores the group's sums (if any), starts the group of i
    double* const q = grp + kGroupSums * g_now;
    if (g_end > 0) q[0] = el, std::copy(&s3p[0][0], &s3p[0][0] + 9, q + 1);
    el = 0.0, std::fill(&s3p[0][0], &s3p[0][0] + 9, 0.0);
    g_now = i / kSumGroup, g_end = (g_now + 1) * kSumGroup;
  };
  if constexpr (!Threaded)  // (threads: the caller, and the caller fills vel_abs_)
    if (pair_live_.size() != rows_.pairs()) pair_live_.assign(rows_.pairs(), 1);
  // the particle arrays, hoisted (the loop stores forces: the vectors' data pointers are not reloaded)
  const double* const p_x = P_.pos.data();
  const double* const p_w = P_.spin.data();
  const double* const p_radius = P_.r.data();
  double* const p_f = P_.force.data();
  double* const p_t = P_.torque.data();
  double hc[3][3] = {}, Lr[3][3] = {};  // periodic: the cell and the strain rate
  const int* const p_i = rows_.pi.data();  // the rows' particles and images
  const int* const p_j = rows_.pj.data();
  const auto* const shift = rows_.shift.data();
  const double* p_vr = P_.vel.data();  // the velocities the loop takes differences of (periodic: v + L x)
  if constexpr (Periodic) {
    hoist_cell(hc, Lr);
    if constexpr (!Threaded) fill_absolute_velocities(Lr);
    p_vr = vel_abs_.data();
  }
  bool g_touch[kRowChunk];
  // pass 1a, per row the law will see: the branch, L^2, r_i + r_j, r_i^2 - r_j^2, v_j - v_i, w_i, w_j
  double g_d[3][kRowChunk], g_L2[kRowChunk], g_s[kRowChunk], g_r2[kRowChunk], g_v[3][kRowChunk];
  double g_wi[3][kRowChunk], g_wj[3][kRowChunk];
  // pass 1b: n, overlap, centre-to-plane distances, v_n, the tangential velocity, the step's rotation
  double g_n[3][kRowChunk], g_ov[kRowChunk], g_di[kRowChunk], g_dj[kRowChunk], g_vn[kRowChunk];
  double g_t[3][kRowChunk], g_th[3][kRowChunk];
  // Threaded: a boundary particle's shares per slot, every other particle's added here
  // (solver_threads.hpp)
  double* const slot_buf = slot_buf_.data();
  const int* const row_slot = row_slot_.data();
  for (std::size_t k0 = k_begin; k0 < k_end; k0 += kRowChunk) {
    const std::size_t m = std::min(kRowChunk, k_end - k0);
    std::size_t mt = 0;
    for (std::size_t c = 0; c < m; ++c) {  // pass 1a
      const std::size_t k = k0 + c;
      const auto i = static_cast<std::size_t>(p_i[k]);
      const auto j = static_cast<std::size_t>(p_j[k]);
      const double* const xi = p_x + D * i;  // the centres of i and j
      const double* const xj = p_x + D * j;
      double dx = xj[0] - xi[0], dy = xj[1] - xi[1], dz = xj[2] - xi[2];
      const double ri = p_radius[i], rj = p_radius[j];
      if constexpr (Periodic) add_image<D>(shift[k].data(), hc, dx, dy, dz);
      const double L2 = dx * dx + dy * dy + dz * dz, s = ri + rj;
      const bool touch = L2 < s * s;
      g_touch[c] = touch;
      const double *const vi = p_vr + D * i, *const vj = p_vr + D * j;
      double v0 = vj[0] - vi[0], v1 = vj[1] - vi[1], v2 = vj[2] - vi[2];  // v_j - v_i (periodic: + L (x_j - x_i))
      if constexpr (Periodic) add_image_velocity<D>(shift[k].data(), hc, Lr, v0, v1, v2);  // L h n
      const double *const oi = p_w + D * i, *const oj = p_w + D * j;  // (kRot = D)
      // (stored at mt whatever the row; kept, mt + 1, when the law will see it: no branch)
      g_d[0][mt] = dx, g_d[1][mt] = dy, g_d[2][mt] = dz, g_L2[mt] = L2, g_s[mt] = s, g_r2[mt] = ri * ri - rj * rj;
      g_v[0][mt] = v0, g_v[1][mt] = v1, g_v[2][mt] = v2;
      for (int r = 0; r < 3; ++r) g_wi[r][mt] = oi[r], g_wj[r][mt] = oj[r];
      mt += law_sees<Law>(touch, pair_live_[k]) ? 1 : 0;
    }
    for (std::size_t t = 0; t < mt; ++t) {  // pass 1b
      const double L = std::sqrt(g_L2[t]), iL = 1.0 / L;
      const double n0 = g_d[0][t] * iL, n1 = g_d[1][t] * iL, n2 = g_d[2][t] * iL;  // n from i to j
      const double q = g_r2[t] * (0.5 * iL);
      const double di = 0.5 * L + q, dj = 0.5 * L - q;  // centre-to-contact-plane distances
      const double v0 = g_v[0][t], v1 = g_v[1][t], v2 = g_v[2][t];
      // W = d_i w_i + d_j w_j: L x the pair's rotation rate (kinematics.hpp)
      const double W0 = di * g_wi[0][t] + dj * g_wj[0][t], W1 = di * g_wi[1][t] + dj * g_wj[1][t],
                   W2 = di * g_wi[2][t] + dj * g_wj[2][t];
      // velocity of j's contact point relative to i's: v_j - v_i - (d_i w_i + d_j w_j) x n
      const double vn = v0 * n0 + v1 * n1 + v2 * n2;
      const double c0 = v0 - (W1 * n2 - W2 * n1), c1 = v1 - (W2 * n0 - W0 * n2), c2 = v2 - (W0 * n1 - W1 * n0);
      const double cn = c0 * n0 + c1 * n1 + c2 * n2;
      // the step's rotation: (n x v_rel + (W . n) n) dt / L
      const double Wn = W0 * n0 + W1 * n1 + W2 * n2, sc = iL * dt;
      g_n[0][t] = n0, g_n[1][t] = n1, g_n[2][t] = n2;
      g_ov[t] = g_s[t] - L, g_di[t] = di, g_dj[t] = dj, g_vn[t] = vn;
      g_t[0][t] = c0 - n0 * cn, g_t[1][t] = c1 - n1 * cn, g_t[2][t] = c2 - n2 * cn;  // the tangential part
      g_th[0][t] = (n1 * v2 - n2 * v1 + Wn * n0) * sc;
      g_th[1][t] = (n2 * v0 - n0 * v2 + Wn * n1) * sc;
      g_th[2][t] = (n0 * v1 - n1 * v0 + Wn * n2) * sc;
    }
    std::size_t t = 0;  // the next row the law sees
    for (std::size_t c = 0; c < m; ++c) {  // pass 2: the law, forces, torques and sums
      const std::size_t k = k0 + c;
      if (skip_row<Law>(g_touch[c], pair_live_[k], pair_hist[k])) {
        if constexpr (Threaded) clear_shares<6>(row_slot, k, slot_buf);
        continue;
      }
      pair_live_[k] = 1;
      const auto i = static_cast<std::size_t>(p_i[k]);
      const auto j = static_cast<std::size_t>(p_j[k]);
      if (i >= g_end) next_group(i);  // (rows sorted by i)
      const double n0 = g_n[0][t], n1 = g_n[1][t], n2 = g_n[2][t], di = g_di[t], dj = g_dj[t];
      const double t0 = g_t[0][t], t1 = g_t[1][t], t2 = g_t[2][t];
      contact::Kinematics<3> in;
      in.overlap = g_ov[t];
      in.v_n = -g_vn[t];
      in.v_t = Eigen::Vector3d(t0, t1, t2);
      in.dslip = Eigen::Vector3d(t0 * dt, t1 * dt, t2 * dt);
      in.dt = dt;
      in.transport = contact::step_transport(Eigen::Vector3d(n0, n1, n2),
                                             Eigen::Vector3d(g_th[0][t], g_th[1][t], g_th[2][t]));
      if constexpr (contact::kReadsPairProperties<Law>) {
        const double ri = p_radius[i], rj = p_radius[j], s = ri + rj;
        in.overlap_start = in.overlap - in.v_n * dt;
        in.r_eff = ri * rj / s;
        in.m_eff = P_.mass[i] * P_.mass[j] / (P_.mass[i] + P_.mass[j]);
      }
      double f_n;
      Eigen::Vector3d f_t;
      contact::update_contact<InPlace>(pair_law, pair_hist[k], in, f_n, f_t);
      if constexpr (Law::kHistoryOutlivesSeparation) pair_live_[k] = pair_law.has_history(pair_hist[k]) ? 1 : 0;
      if constexpr (contact::kHasContactArea<Law>) fn_max = f_n > fn_max ? f_n : fn_max;
      const double ft0 = f_t.x(), ft1 = f_t.y(), ft2 = f_t.z();
      const double f0 = f_n * n0 + ft0, f1 = f_n * n1 + ft1, f2 = f_n * n2 + ft2;  // on j
      // M_i = -d_i n x f_t, M_j = -d_j n x f_t
      const double m0 = n1 * ft2 - n2 * ft1, m1 = n2 * ft0 - n0 * ft2, m2 = n0 * ft1 - n1 * ft0;
      // Sigma V = sum f (x) l, l = x_j + h n - x_i: here the rows across a face add f (x) h n
      if constexpr (Periodic) add_image_stress<D>(shift[k].data(), hc, {f0, f1, f2}, s3p);
      if constexpr (contact::kHasElasticEnergy<Law>) el += pair_law.elastic_energy(in);
      if constexpr (Threaded) {  // the same shares; a boundary particle's later, in row order
        add_share<3, 3>(row_slot[2 * k + 1], slot_buf, p_f + D * j, p_t + D * j,
                        {f0, f1, f2, -(dj * m0), -(dj * m1), -(dj * m2)});
        add_share<3, 3>(row_slot[2 * k], slot_buf, p_f + D * i, p_t + D * i,
                        {-f0, -f1, -f2, -(di * m0), -(di * m1), -(di * m2)});
      } else {
        double *const fi = p_f + D * i, *const fj = p_f + D * j, *const ti = p_t + D * i, *const tj = p_t + D * j;
        fj[0] += f0, fj[1] += f1, fj[2] += f2;
        fi[0] -= f0, fi[1] -= f1, fi[2] -= f2;
        ti[0] -= di * m0, ti[1] -= di * m1, ti[2] -= di * m2;
        tj[0] -= dj * m0, tj[1] -= dj * m1, tj[2] -= dj * m2;
      }
      ++t;
    }
  }
  next_group(0);
  a.fn_max = fn_max;
}
