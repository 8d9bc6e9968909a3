// Yield-probe curves and their yield points (yield_curve.hpp).
#include "netdem/system/yield_curve.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <utility>

#include <fmt/format.h>

namespace netdem::sys {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kPi = std::numbers::pi;
}  // namespace

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

ProbeOptions probe_options(const ProbeSettings& a) {
  ProbeOptions po;
  po.first_step = a.first_step;
  po.fine_increments = a.fine;
  po.growth = a.growth;
  po.max_strain = a.max_strain;
  po.offset = a.offset;
  po.max_step = std::max(a.first_step, a.offset / 4);
  return po;
}

ProbeResult evaluate_probe(ProbeCurve curve, int index, const ProbeSettings& a) {
  ProbeResult res;
  res.index = index;
  res.theta = 2 * std::numbers::pi * index / a.directions;
  res.curve = std::move(curve);
  std::vector<double> x, y, s11, s22;
  for (const auto& p : res.curve.samples) {
    x.push_back(p.strain);
    y.push_back(p.stress);
    s11.push_back(p.S11);
    s22.push_back(p.S22);
  }
  YieldOptions yo;
  yo.offset = a.offset;
  yo.window = a.window;
  yo.min_rise = 0.02 * a.loading_norm;
  res.curvature = yield_by_curvature(x, y, yo);
  res.offset = yield_by_offset(x, y, yo);
  res.fit = elastic_fit(x, y, yo.fit_points);
  res.S11 = res.curvature.found ? interpolate_at(s11, res.curvature.position) : kNaN;
  res.S22 = res.curvature.found ? interpolate_at(s22, res.curvature.position) : kNaN;
  res.S11_offset = res.offset.found ? interpolate_at(s11, res.offset.position) : kNaN;
  res.S22_offset = res.offset.found ? interpolate_at(s22, res.offset.position) : kNaN;
  std::string status;
  if (!res.curvature.found) status = "no curvature point: " + res.curvature.reason;
  if (!res.offset.found) status += (status.empty() ? "" : "; ") + std::string("no offset point: ") + res.offset.reason;
  res.status = status.empty() ? "ok" : status;
  return res;
}

}  // namespace netdem::sys
