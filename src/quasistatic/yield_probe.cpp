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

constexpr double kPi = 3.14159265358979323846;

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
ElasticFit elastic_fit(const std::vector<double>& x, const std::vector<double>& y, int fit_points) {
  // Least-squares line over every window of fit_points + 1 consecutive samples; the steepest one
  // is the elastic line. On a curve that starts linear this is the first window; a toe (contacts
  // closing gaps first, e.g. after an unloading that opened them) is skipped, as in the toe
  // compensation of tensile tests.
  ElasticFit best;
  const int n = static_cast<int>(std::min(x.size(), y.size()));
  const int m = std::max(1, fit_points) + 1;
  if (n < 2) return best;
  for (int i0 = 0; i0 == 0 || i0 + m <= n; ++i0) {
    const int i1 = std::min(n, i0 + m);
    const int k = i1 - i0;
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (int i = i0; i < i1; ++i) {
      sx += x[i];
      sy += y[i];
      sxx += x[i] * x[i];
      sxy += x[i] * y[i];
    }
    const double det = k * sxx - sx * sx;
    if (!(det > 0.0)) continue;
    ElasticFit f;
    f.slope = (k * sxy - sx * sy) / det;
    f.y0 = (sy - f.slope * sx) / k;
    f.ok = std::isfinite(f.slope) && std::isfinite(f.y0);
    if (f.ok && (!best.ok || f.slope > best.slope)) best = f;
  }
  return best;
}

double interpolate_at(const std::vector<double>& v, double position) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  if (!(position > 0.0)) return v.front();
  const auto last = static_cast<double>(v.size() - 1);
  if (position >= last) return v.back();
  const auto i = static_cast<std::size_t>(position);
  const double t = position - static_cast<double>(i);
  return (1.0 - t) * v[i] + t * v[i + 1];
}

namespace {

// Common checks: elastic line and stress rise. Returns false with est.reason set.
bool prepare(const std::vector<double>& x, const std::vector<double>& y, const YieldOptions& o, ElasticFit& fit,
             double& rise, std::size_t& peak, YieldEstimate& est) {
  if (x.size() != y.size()) throw std::invalid_argument("yield: x and y differ in length");
  if (x.size() < static_cast<std::size_t>(std::max(3, o.fit_points + 2))) {
    est.reason = fmt::format("too few samples ({})", x.size());
    return false;
  }
  for (std::size_t i = 0; i < x.size(); ++i)
    if (!std::isfinite(x[i]) || !std::isfinite(y[i])) {
      est.reason = "non-finite sample";
      return false;
    }
  fit = elastic_fit(x, y, o.fit_points);
  if (!fit.ok || !(fit.slope > 0.0)) {
    est.reason = "no elastic rise (stress does not increase on reloading)";
    return false;
  }
  peak = 0;
  for (std::size_t i = 1; i < y.size(); ++i)
    if (y[i] > y[peak]) peak = i;
  rise = y[peak] - fit.y0;
  if (!(rise > o.min_rise) || !(rise > 0.0)) {
    est.reason = "no load (stress rise below the minimum: tensile or dilatant direction)";
    return false;
  }
  return true;
}

}  // namespace

YieldEstimate yield_by_curvature(const std::vector<double>& x, const std::vector<double>& y, const YieldOptions& o) {
  YieldEstimate est;
  ElasticFit fit;
  double rise = 0;
  std::size_t peak = 0;
  if (!prepare(x, y, o, fit, rise, peak, est)) return est;
  if (!(o.window > 0.0)) throw std::invalid_argument("yield: curvature window must be positive");
  // normalised coordinates: elastic slope 1, largest stress rise 1
  const std::size_t n = x.size();
  std::vector<double> X(n), Y(n);
  for (std::size_t i = 0; i < n; ++i) {
    X[i] = x[i] * fit.slope / rise;
    Y[i] = (y[i] - fit.y0) / rise;
  }
  // segments (zero-length ones carry no direction and are skipped)
  std::vector<double> s(n, 0.0), psi(n, 0.0);
  std::vector<char> has_dir(n, 0);
  for (std::size_t j = 0; j + 1 < n; ++j) {
    const double dx = X[j + 1] - X[j], dy = Y[j + 1] - Y[j];
    const double L = std::hypot(dx, dy);
    s[j + 1] = s[j] + L;
    if (L > 0.0) {
      psi[j] = std::atan2(dy, dx);
      has_dir[j] = 1;
    }
  }
  // turning angles at the vertices between two directed segments
  std::vector<double> sv, dpsi;
  int last = -1;
  for (std::size_t j = 0; j + 1 < n; ++j) {
    if (!has_dir[j]) continue;
    if (last >= 0) {
      double d = psi[j] - psi[static_cast<std::size_t>(last)];
      while (d > kPi) d -= 2 * kPi;
      while (d <= -kPi) d += 2 * kPi;
      sv.push_back(s[j]);
      dpsi.push_back(d);
    }
    last = static_cast<int>(j);
  }
  if (dpsi.empty()) {
    est.reason = "straight curve (no knee)";
    return est;
  }
  const double h = o.window;
  const double norm = 1.0 / (std::sqrt(2.0 * kPi) * h);
  auto kappa = [&](double at) {
    double k = 0;
    for (std::size_t v = 0; v < sv.size(); ++v) {
      const double z = (at - sv[v]) / h;
      if (std::fabs(z) < 8.0) k += dpsi[v] * std::exp(-0.5 * z * z);
    }
    return k * norm;
  };
  const double s_end = s[peak];
  const int grid = std::max(200, static_cast<int>(std::ceil(20.0 * s_end / h)));
  double best = 0.0, s_best = -1.0;
  // only knees above the minimum stress rise count (a wiggle of a curve that hardly carries load
  // is no yield point)
  const double y_min = o.min_rise / rise;
  auto rise_at = [&](double at) {
    std::size_t j = 0;
    while (j + 2 < n && s[j + 1] < at) ++j;
    const double L = s[j + 1] - s[j];
    const double t = L > 0.0 ? std::clamp((at - s[j]) / L, 0.0, 1.0) : 0.0;
    return (1 - t) * Y[j] + t * Y[j + 1];
  };
  for (int g = 0; g <= std::min(grid, 200000); ++g) {
    const double at = s_end * g / grid;
    if (y_min > 0.0 && rise_at(at) < y_min) continue;
    const double k = kappa(at);
    if (k < best) {
      best = k;
      s_best = at;
    }
  }
  // a straight line's rounding noise is no knee: the turning must be at least 1e-3 rad per unit
  // normalised arc length (a 45 deg knee smoothed over the window has about 3)
  if (!(s_best >= 0.0) || best > -1e-3) {
    est.reason = "no knee (the curve never turns towards lower slope before the peak above the minimum rise)";
    return est;
  }
  // arc length -> fractional sample index
  std::size_t j = 0;
  while (j + 2 < n && s[j + 1] < s_best) ++j;
  const double L = s[j + 1] - s[j];
  est.position = static_cast<double>(j) + (L > 0.0 ? std::clamp((s_best - s[j]) / L, 0.0, 1.0) : 0.0);
  est.strain = interpolate_at(x, est.position);
  est.stress = interpolate_at(y, est.position);
  est.curvature = best;
  est.found = true;
  return est;
}

YieldEstimate yield_by_offset(const std::vector<double>& x, const std::vector<double>& y, const YieldOptions& o) {
  YieldEstimate est;
  ElasticFit fit;
  double rise = 0;
  std::size_t peak = 0;
  if (!prepare(x, y, o, fit, rise, peak, est)) return est;
  if (!(o.offset > 0.0)) throw std::invalid_argument("yield: offset must be positive");
  auto d = [&](std::size_t i) { return y[i] - (fit.y0 + fit.slope * (x[i] - o.offset)); };
  for (std::size_t i = 1; i < x.size(); ++i) {
    const double d0 = d(i - 1), d1 = d(i);
    if (d0 > 0.0 && d1 <= 0.0) {
      est.position = static_cast<double>(i - 1) + d0 / (d0 - d1);
      est.strain = interpolate_at(x, est.position);
      est.stress = interpolate_at(y, est.position);
      est.found = true;
      return est;
    }
  }
  est.reason = fmt::format("the curve does not reach the {:g} offset line within the probe (|dE| <= {:.3g})", o.offset,
                           x.back());
  return est;
}

// ------------------------------------------------------------------------------------------------
ProbeSchedule::ProbeSchedule(const ProbeOptions& o, double x0, double y0) : o_(o), step_(o.first_step) {
  xs_.push_back(x0);
  ys_.push_back(y0);
}

double ProbeSchedule::next() {
  if (!end_.empty()) return 0.0;
  ++k_;
  if (k_ > o_.max_increments) {
    end_ = "max increments";
    return 0.0;
  }
  if (strain_ >= o_.max_strain * (1 - 1e-12)) {
    end_ = "max strain";
    return 0.0;
  }
  if (k_ > o_.fine_increments) step_ = std::min(o_.max_step, std::max(step_, o_.first_step) * o_.growth);
  return std::min(step_, o_.max_strain - strain_);
}

bool ProbeSchedule::record(double h, double x, double y) {
  strain_ += h;
  xs_.push_back(x);
  ys_.push_back(y);
  if (xs_.size() >= static_cast<std::size_t>(o_.fit_points) + 1) fit_ = elastic_fit(xs_, ys_, o_.fit_points);
  if (fit_.ok && fit_.slope > 0.0 && x_cross_ < 0.0 && strain_ >= o_.offset) {
    if (y <= fit_.y0 + fit_.slope * (x - o_.offset)) x_cross_ = x;
  }
  if (x_cross_ > 0.0 && strain_ >= o_.past_offset * x_cross_) {
    end_ = "past offset";
    return false;
  }
  return true;
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
  const auto& x = solver.x();
  const auto& y = solver.y();
  const double area = solver.box_deformation().determinant() * solver.solid_area() / solver.initial_density();
  double s11 = 0.0, s22 = 0.0;
  for (const auto& c : solver.contacts()) {
    const double dx = x[c.j] - x[c.i], dy = y[c.j] - y[c.i];
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
