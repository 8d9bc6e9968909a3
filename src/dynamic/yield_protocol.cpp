// The DEM's yield-surface protocol (yield_protocol.hpp).
#include "netdem/dynamic/yield_protocol.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <mutex>
#include <numbers>
#include <thread>

#include <fmt/format.h>

namespace netdem::dem {

namespace {

constexpr double kPi = std::numbers::pi;

/// A message on one line (control characters as spaces): it ends up in a CSV field.
std::string single_line(const std::string& m) {
  std::string o = m;
  for (char& c : o)
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = ' ';
  return o;
}

}  // namespace

void WindowRunner::set_rate(double e11, double e22) {
  E11 = strain11(), E22 = strain22();
  t_rate = s_.time();
  s_.set_strain_rate(e11, e22);
}

Window WindowRunner::run(double t_end, int target) {
  Window w;
  const double span = t_end - s_.time();
  const auto every = static_cast<std::int64_t>(std::clamp(span / s_.dt() / target, 1.0, 20.0));
  YieldSample acc;
  std::int64_t since = 0;
  do {
    s_.step();
    ++w.steps;
    if (++since % every == 0 || !(s_.time() < t_end - 1e-12 * std::fabs(t_end))) {
      acc.add(measure(), 1.0);
      ++w.samples;
    }
  } while (s_.time() < t_end - 1e-12 * std::fabs(t_end));
  w.mean.add(acc, 1.0 / w.samples);
  s_.check_health();
  return w;
}

YieldSample WindowRunner::settle(const SettleOptions& o, bool& settled, std::int64_t& steps) {
  const double e11 = s_.strain_rate_11(), e22 = s_.strain_rate_22();
  set_rate(0.0, 0.0);
  s_.set_affine_drag(o.drag);
  const double t_end = s_.time() + o.t_max;
  YieldSample m = measure();
  settled = false;
  for (;;) {
    for (int k = 0; k < 50; ++k, ++steps) s_.step();
    m = measure();
    if (s_.unbalanced_force_rms() <= o.tol * o.f_ref && m.kinetic <= o.tol * o.tol * o.work_ref) {
      settled = true;
      break;
    }
    if (!(s_.time() < t_end)) break;
  }
  s_.check_health();
  s_.set_affine_drag(0.0);
  set_rate(e11, e22);
  return m;
}

double stress_norm(const YieldSample& m) {
  return std::sqrt(m.S[0] * m.S[0] + m.S[1] * m.S[1] + 2.0 * m.S[2] * m.S[2]);
}

sys::YieldPoint fabric_affine_point(const DynamicSolver& s, const std::vector<ContactInfo>& cs, double theta) {
  const double e11 = std::cos(theta), e22 = std::sin(theta);
  const Box& b = s.box();
  const double area = s.periodic() ? s.cell().measure() : (b.x_max - b.x_min) * (b.y_max - b.y_min);
  double s11 = 0.0, s22 = 0.0;
  for (const auto& c : cs) {
    if (c.wall >= 0 || !(c.f_n > 0.0)) continue;
    if (e11 * c.nx * c.nx + e22 * c.ny * c.ny >= 0.0) continue;
    const double L = c.d_i + c.d_j;
    s11 -= c.f_n * L * c.nx * c.nx;
    s22 -= c.f_n * L * c.ny * c.ny;
  }
  return {s11 / area, s22 / area};
}

UnloadOutcome unload(DynamicSolver& s, WindowRunner& win, const YieldSample& loaded, double gdot_p,
                     const SettleOptions& settle, const UnloadOptions& o,
                     const std::function<void(const UnloadRow&)>& on_row) {
  const double s0 = stress_norm(loaded);
  const double w11 = loaded.S[0] / s0, w22 = loaded.S[1] / s0, w12 = loaded.S[2] / s0;
  auto proj = [&](const YieldSample& m) { return m.S[0] * w11 + m.S[1] * w22 + 2.0 * m.S[2] * w12; };
  auto row = [&](int k, double strain, const YieldSample& m, std::int64_t st) {
    if (on_row) on_row({k, strain, m, s.density(), st});
  };
  UnloadOutcome r;
  r.unloaded = loaded;
  row(0, 0.0, loaded, 0);
  double h = o.first_step;
  double p_prev = proj(loaded), slope_last = 0.0;
  double lambda_cap = std::numeric_limits<double>::infinity();
  try {
    // the first hold settles the precompacted state on the elastic branch (zero strain)
    bool settled = false;
    r.unloaded = win.settle(settle, settled, r.steps);
    r.unsettled += !settled;
    p_prev = proj(r.unloaded);
    double un_prev = stress_norm(r.unloaded);
    for (r.increments = 1; r.increments <= o.max_increments; ++r.increments) {
      const Window ramp = win.run(s.time() + h / gdot_p, 1);
      r.steps += ramp.steps;
      r.unloaded = win.settle(settle, settled, r.steps);
      r.unsettled += !settled;
      r.strain += h;
      row(r.increments, r.strain, r.unloaded, r.steps);
      const double un = stress_norm(r.unloaded);
      if (un < o.tol) break;
      // netsolve's noise floor: once |Sigma| is below 5 % of the loading stress, a rise means the
      // floor is reached (the held states of a die network are equilibria to the settle tolerance)
      if (un < 0.05 * s0 && un > un_prev) {
        r.message = fmt::format("noise floor: |Sigma| rose from {:.3g} to {:.3g} sigma_y (tolerance {:.3g}); probing from "
                                "there", un_prev, un, o.tol);
        break;
      }
      un_prev = un;
      const double p = proj(r.unloaded);
      if (!(p > 0.0)) {
        r.message = fmt::format("the stress projection on the loading stress crossed zero at |Sigma| = {:.3g} sigma_y", un);
        break;
      }
      const double slope = (p_prev - p) / h;
      if (r.increments == 1 && slope > 0.0) lambda_cap = 3.0 * p_prev / slope;
      if (slope > 0.0) slope_last = slope;
      const double next = slope_last > 0.0 ? p / slope_last : h;
      h = std::clamp(next, 1e-3 * h, 4.0 * h);
      if (r.strain >= lambda_cap * (1 - 1e-9)) {
        r.message = fmt::format("|Sigma| = {:.3g} sigma_y at 3 x the linear spring-back strain", un);
        break;
      }
      h = std::min(h, lambda_cap - r.strain);
      p_prev = p;
    }
  } catch (const InstabilityError& e) {
    r.message = std::string("unstable: ") + single_line(e.what());
  }
  r.stress_norm = stress_norm(r.unloaded);
  r.converged = r.message.empty() && r.stress_norm < o.tol;
  if (r.message.empty() && !r.converged)
    r.message = fmt::format("|Sigma| = {:.3g} sigma_y after {} unloading increments (tolerance {:.3g})", r.stress_norm,
                            r.increments, o.tol);
  return r;
}

DemProbeRun run_probe(const DynamicSolver& unloaded, const WindowRunner& ref, YieldMeter meter, int index,
                      const sys::ProbeSettings& ps, double gdot, const YieldSample& start, const SettleOptions& settle,
                      const std::function<void(double)>& on_increment) {
  const auto t0 = std::chrono::steady_clock::now();
  DemProbeRun out;
  DynamicSolver s = unloaded;
  WindowRunner w(s, meter);
  w.E11 = ref.strain11(), w.E22 = ref.strain22();
  w.t_rate = s.time();
  const double theta = 2 * kPi * index / ps.directions;
  const double ct = std::cos(theta), st = std::sin(theta);
  w.set_rate(gdot * ct, gdot * st);
  s.set_affine_velocities();
  sys::ProbeCurve c;
  c.theta = theta;
  auto sample_of = [&](const YieldSample& m, double strain, int steps) {
    sys::ProbeSample p;
    p.strain = strain;
    p.S11 = m.S[0], p.S22 = m.S[1], p.S12 = m.S[2];
    p.stress = p.S11 * ct + p.S22 * st;
    p.density = s.density();
    p.Z = m.Z;
    p.newton = steps;
    return p;
  };
  c.samples.push_back(sample_of(start, 0.0, 0));
  out.kinetic.push_back(start.work > 0 ? start.kinetic / start.work : 0.0);
  sys::ProbeSchedule schedule(sys::probe_options(ps), 0.0, c.samples[0].stress);
  for (;;) {
    const double h = schedule.next();
    if (!(h > 0.0)) {
      c.end = schedule.end();
      break;
    }
    YieldSample m;
    bool settled = false;
    try {
      const Window ramp = w.run(s.time() + h / gdot, 1);
      out.steps += ramp.steps;
      m = w.settle(settle, settled, out.steps);
    } catch (const InstabilityError& e) {
      c.end = std::string("unstable: ") + single_line(e.what());
      break;
    }
    c.samples.push_back(sample_of(m, schedule.strain() + h, static_cast<int>(out.steps)));
    c.samples.back().converged = settled;
    c.unconverged += !settled;
    out.kinetic.push_back(m.work > 0 ? m.kinetic / m.work : 0.0);
    if (!schedule.record(h, c.samples.back().strain, c.samples.back().stress)) {
      c.end = schedule.end();
      break;
    }
    if (on_increment) on_increment(schedule.strain());
  }
  out.result = sys::evaluate_probe(std::move(c), index, ps);
  out.result.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

std::vector<DemProbeRun> run_probes(const DynamicSolver& unloaded, const WindowRunner& ref, const YieldMeter& meter,
                                    const std::vector<int>& indices, int jobs, const sys::ProbeSettings& ps,
                                    double gdot, const YieldSample& start, const SettleOptions& settle,
                                    const std::function<void(std::size_t, double)>& on_progress,
                                    const std::function<void(std::size_t, const DemProbeRun&)>& on_done) {
  std::vector<DemProbeRun> runs(indices.size());
  std::mutex mtx;
  std::atomic<std::size_t> next{0};
  // progress: each running probe's strain over its expected length (the stop rule ends most
  // compressive probes near 1.3 x the offset strain past the knee: 2 x offset)
  auto report = [&](std::size_t q, double f) {
    if (!on_progress) return;
    std::lock_guard<std::mutex> lock(mtx);
    on_progress(q, f);
  };
  auto worker = [&] {
    for (;;) {
      const std::size_t q = next.fetch_add(1);
      if (q >= indices.size()) return;
      const int idx = indices[q];
      DemProbeRun r;
      try {
        r = run_probe(unloaded, ref, meter, idx, ps, gdot, start, settle,
                      [&](double strain) { report(q, std::min(0.95, strain / (2.0 * ps.offset))); });
      } catch (const std::exception& e) {
        r.result.index = idx;
        r.result.theta = 2 * kPi * idx / ps.directions;
        r.result.status = std::string("error: ") + single_line(e.what());
      }
      report(q, 1.0);
      std::lock_guard<std::mutex> lock(mtx);
      runs[q] = std::move(r);
      if (on_done) on_done(q, runs[q]);
    }
  };
  std::vector<std::thread> threads;
  for (int t = 1; t < jobs; ++t) threads.emplace_back(worker);
  worker();
  for (auto& t : threads) t.join();
  return runs;
}

}  // namespace netdem::dem
