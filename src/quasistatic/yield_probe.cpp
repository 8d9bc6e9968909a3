#include "netdem/quasistatic/yield_probe.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>
#include <stdexcept>

#include <Eigen/LU>
#include <fmt/format.h>

namespace netdem::qs {

namespace {

double stress_norm(const StateMeasures& m) {
  return std::sqrt(m.S11 * m.S11 + m.S22 * m.S22 + 2.0 * m.S12 * m.S12);
}


}  // namespace

// ------------------------------------------------------------------------------------------------
UnloadResult unload(NetworkSolver& solver, const Eigen::Matrix2d& direction, double sigma_y, double unload_ratio,
                    const UnloadOptions& options) {
  if (!(direction.norm() > 0.0) || !std::isfinite(direction.norm()))
    throw std::invalid_argument("unload: the compaction direction is zero or not finite");
  if (!(sigma_y > 0.0) || !(unload_ratio > 0.0) || !(options.tol > 0.0) || options.max_increments < 1)
    throw std::invalid_argument("unload: sigma_y, unload_ratio, tol and max_increments must be positive");
  const Eigen::Matrix2d dir = direction / direction.norm();
  UnloadResult res;
  UnloadStep st;
  st.state = solver.measures();
  res.path.push_back(st);
  const double s0 = stress_norm(st.state);
  res.loading_norm = s0 / sigma_y;
  res.stress_norm = s0 / sigma_y;
  if (s0 < options.tol * sigma_y) {
    res.converged = true;
    return res;
  }
  // projection of the stress on its direction before unloading
  const double w11 = st.state.S11 / s0, w22 = st.state.S22 / s0, w12 = st.state.S12 / s0;
  auto proj = [&](const StateMeasures& m) { return m.S11 * w11 + m.S22 * w22 + 2.0 * m.S12 * w12; };
  double step = options.first_step;
  if (!(step > 0.0)) {
    const double e = std::sqrt(st.state.E11 * st.state.E11 + st.state.E22 * st.state.E22 + 2 * st.state.E12 * st.state.E12);
    step = 0.2 * 2.0 * e / unload_ratio;
    if (!(step > 0.0)) step = 1e-6;
  }
  double p_prev = proj(st.state);
  double lambda = 0.0;
  double slope_last = 0.0;  // last positive secant slope of p
  double lambda_cap = std::numeric_limits<double>::infinity();
  for (int k = 1; k <= options.max_increments; ++k) {
    UnloadStep s;
    s.report = solver.increment(-step * dir);
    s.state = solver.measures();
    lambda += step;
    s.strain = lambda;
    res.path.push_back(s);
    res.strain = lambda;
    res.stress_norm = stress_norm(s.state) / sigma_y;
    if (res.stress_norm < options.tol) {
      res.converged = true;
      return res;
    }
    // noise floor: close to zero stress a die network with unconverged increments is noisy; once
    // |Sigma| is below 5% of the loading stress, a rise of |Sigma| means the floor is reached
    const double prev_norm = stress_norm(res.path[res.path.size() - 2].state) / sigma_y;
    if (res.stress_norm < 0.05 * res.loading_norm && res.stress_norm > prev_norm) {
      res.message = fmt::format("noise floor: |Sigma| rose from {:.3g} to {:.3g} sigma_y (tolerance {:.3g}); probing from there",
                                prev_norm, res.stress_norm, options.tol);
      return res;
    }
    // p = Sigma : w > 0 while loaded (w = Sigma/|Sigma| before unloading); secant prediction of the
    // reversal strain left to p = 0
    const double p = proj(s.state);
    if (!(p > 0.0)) {
      res.message = fmt::format("the stress projection on the loading stress crossed zero at |Sigma| = {:.3g} sigma_y "
                                "(tolerance {:.3g}); probing from there",
                                res.stress_norm, options.tol);
      return res;
    }
    const double slope = (p_prev - p) / step;
    if (k == 1 && slope > 0.0) lambda_cap = 3.0 * p_prev / slope;  // 3 x the linear spring-back
    if (slope > 0.0) slope_last = slope;
    // a noisy network (unconverged increments near zero stress) can make p rise: keep the last
    // positive slope rather than stepping blindly, and never go past 3 x the linear spring-back
    const double next = slope_last > 0.0 ? p / slope_last : step;
    step = std::clamp(next, 1e-3 * step, 4.0 * step);
    if (lambda >= lambda_cap * (1 - 1e-9)) {
      res.message = fmt::format("|Sigma| = {:.3g} sigma_y at 3 x the linear spring-back strain (tolerance {:.3g}); "
                                "probing from there",
                                res.stress_norm, options.tol);
      return res;
    }
    step = std::min(step, lambda_cap - lambda);
    p_prev = p;
  }
  res.message = fmt::format("|Sigma| = {:.3g} sigma_y after {} unloading increments (tolerance {:.3g})", res.stress_norm,
                            options.max_increments, options.tol);
  return res;
}

// ------------------------------------------------------------------------------------------------
ProbeCurve probe(NetworkSolver& solver, double theta, double sigma_y, const ProbeOptions& o) {
  if (!(o.first_step > 0.0) || !(o.max_step > 0.0) || !(o.max_strain > 0.0) || !(o.growth >= 1.0) ||
      o.max_increments < 1 || o.fine_increments < 0 || !(sigma_y > 0.0))
    throw std::invalid_argument("probe: steps, growth, limits and sigma_y must be positive");
  ProbeCurve c;
  c.theta = theta;
  const double ct = std::cos(theta), st = std::sin(theta);
  Eigen::Matrix2d dir;
  dir << ct, 0.0, 0.0, st;
  auto sample = [&](double strain, const IncrementReport* r) {
    const auto m = solver.measures();
    ProbeSample p;
    p.strain = strain;
    p.S11 = m.S11 / sigma_y;
    p.S22 = m.S22 / sigma_y;
    p.S12 = m.S12 / sigma_y;
    p.stress = p.S11 * ct + p.S22 * st;
    p.density = m.density;
    p.Z = m.Z;
    if (r) {
      p.newton = r->newton_iterations;
      p.converged = r->converged;
      p.residual = r->residual;
    }
    return p;
  };
  c.samples.push_back(sample(0.0, nullptr));
  ProbeSchedule schedule(o, c.samples[0].strain, c.samples[0].stress);
  for (;;) {
    const double h = schedule.next();
    if (!(h > 0.0)) {
      c.end = schedule.end();
      break;
    }
    IncrementReport r;
    try {
      r = solver.increment(h * dir);
    } catch (const std::exception& e) {
      c.end = std::string("singular: ") + e.what();
      break;
    }
    c.samples.push_back(sample(schedule.strain() + h, &r));
    c.unconverged += !r.converged;
    if (!std::isfinite(c.samples.back().stress)) {
      c.end = "singular: non-finite stress";
      c.samples.pop_back();
      break;
    }
    if (!schedule.record(h, c.samples.back().strain, c.samples.back().stress)) {
      c.end = schedule.end();
      break;
    }
  }
  return c;
}

YieldPoint fabric_affine_point(const NetworkSolver& solver, double theta, double sigma_y) {
  if (!(std::isfinite(theta) && std::isfinite(sigma_y) && sigma_y > 0.0))
    throw std::invalid_argument(fmt::format("fabric_affine_point: need a finite theta and sigma_y > 0, got {} and {}", theta, sigma_y));
  const double e11 = std::cos(theta), e22 = std::sin(theta);
  const double area = solver.box_deformation().determinant() * solver.solid_area() / solver.initial_density();
  double s11 = 0.0, s22 = 0.0;
  for (const auto& c : solver.contacts()) {
    // the branch to j's image in a periodic cell (x_j - x_i across a face would be the cell's width)
    const double dx = c.l[0], dy = c.l[1];
    const double L = std::hypot(dx, dy);
    if (!(L > 0.0)) continue;
    const double nx = dx / L, ny = dy / L;
    if (e11 * nx * nx + e22 * ny * ny >= 0.0) continue;  // not compressed by this strain rate
    s11 -= c.f_n * L * nx * nx;
    s22 -= c.f_n * L * ny * ny;
  }
  return {s11 / (area * sigma_y), s22 / (area * sigma_y)};
}

}  // namespace netdem::qs
