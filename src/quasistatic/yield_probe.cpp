#include "netdem/quasistatic/yield_probe.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>
#include <stdexcept>
#include <type_traits>

#include <Eigen/LU>
#include <fmt/format.h>

namespace netdem::qs {

namespace {

// What unload and probe_along read from a state, per dimension. 2D keeps the StateMeasures
// arithmetic of the 2D tool (its outputs are byte-identical to before the 3D form); 3D reads the
// symmetric Eq 13 stress of StressMeasuresT.
double stress_norm(const StateMeasures& m) {
  return std::sqrt(m.S11 * m.S11 + m.S22 * m.S22 + 2.0 * m.S12 * m.S12);
}
double stress_norm(const StressMeasuresT<3>& m) { return m.eq13.norm(); }
double strain_norm(const StateMeasures& m) {
  return std::sqrt(m.E11 * m.E11 + m.E22 * m.E22 + 2 * m.E12 * m.E12);
}
double strain_norm(const StressMeasuresT<3>& m) { return m.strain.norm(); }
StateMeasures measure(const NetworkSolverT<2>& s) { return s.measures(); }
StressMeasuresT<3> measure(const NetworkSolverT<3>& s) { return s.stress(); }

// The projection of a state's stress on the stress w = Sigma_0 / |Sigma_0| before unloading.
struct Projection2 {
  double w11, w22, w12;
  Projection2(const StateMeasures& m0, double s0) : w11(m0.S11 / s0), w22(m0.S22 / s0), w12(m0.S12 / s0) {}
  double operator()(const StateMeasures& m) const { return m.S11 * w11 + m.S22 * w22 + 2.0 * m.S12 * w12; }
};
struct Projection3 {
  Eigen::Matrix3d w;
  Projection3(const StressMeasuresT<3>& m0, double s0) : w(m0.eq13 / s0) {}
  double operator()(const StressMeasuresT<3>& m) const { return m.eq13.cwiseProduct(w).sum(); }
};
template <int D>
using ProjectionT = std::conditional_t<D == 2, Projection2, Projection3>;

// One probe sample: the state's stress / sigma_y and its work-conjugate Sigma : dir.
template <int D>
ProbeSample probe_sample(const NetworkSolverT<D>& solver, const Eigen::Matrix<double, D, D>& dir, double sigma_y,
                         Eigen::Matrix<double, D, D>* full) {
  ProbeSample p;
  if constexpr (D == 2) {
    const auto m = solver.measures();
    p.S11 = m.S11 / sigma_y;
    p.S22 = m.S22 / sigma_y;
    p.S12 = m.S12 / sigma_y;
    p.stress = p.S11 * dir(0, 0) + p.S22 * dir(1, 1);  // the 2D directions are diagonal
    if (dir(0, 1) != 0.0) p.stress += 2.0 * p.S12 * dir(0, 1);
    p.density = m.density;
    p.Z = m.Z;
    if (full) *full << p.S11, p.S12, p.S12, p.S22;
  } else {
    const auto m = solver.stress();
    const Eigen::Matrix<double, D, D> s = m.eq13 / sigma_y;
    p.S11 = s(0, 0);
    p.S22 = s(1, 1);
    p.S12 = s(0, 1);
    p.stress = s.cwiseProduct(dir).sum();
    p.density = m.density;
    p.Z = m.Z;
    if (full) *full = s;
  }
  return p;
}

}  // namespace

// ------------------------------------------------------------------------------------------------
template <int D>
UnloadResultT<D> unload(NetworkSolverT<D>& solver, const Eigen::Matrix<double, D, D>& direction, double sigma_y,
                        double unload_ratio, const UnloadOptions& options) {
  if (!(direction.norm() > 0.0) || !std::isfinite(direction.norm()))
    throw std::invalid_argument("unload: the compaction direction is zero or not finite");
  if (!(sigma_y > 0.0) || !(unload_ratio > 0.0) || !(options.tol > 0.0) || options.max_increments < 1)
    throw std::invalid_argument("unload: sigma_y, unload_ratio, tol and max_increments must be positive");
  const Eigen::Matrix<double, D, D> dir = direction / direction.norm();
  UnloadResultT<D> res;
  UnloadStepT<D> st;
  st.state = measure(solver);
  res.path.push_back(st);
  const double s0 = stress_norm(st.state);
  res.loading_norm = s0 / sigma_y;
  res.stress_norm = s0 / sigma_y;
  if (s0 < options.tol * sigma_y) {
    res.converged = true;
    return res;
  }
  const ProjectionT<D> proj(st.state, s0);  // on the stress's direction before unloading
  double step = options.first_step;
  if (!(step > 0.0)) {
    const double e = strain_norm(st.state);
    step = 0.2 * 2.0 * e / unload_ratio;
    if (!(step > 0.0)) step = 1e-6;
  }
  double p_prev = proj(st.state);
  double lambda = 0.0;
  double slope_last = 0.0;  // last positive secant slope of p
  double lambda_cap = std::numeric_limits<double>::infinity();
  for (int k = 1; k <= options.max_increments; ++k) {
    UnloadStepT<D> s;
    s.report = solver.increment(-step * dir);
    s.state = measure(solver);
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

template UnloadResultT<2> unload<2>(NetworkSolverT<2>&, const Eigen::Matrix2d&, double, double, const UnloadOptions&);
template UnloadResultT<3> unload<3>(NetworkSolverT<3>&, const Eigen::Matrix3d&, double, double, const UnloadOptions&);

// ------------------------------------------------------------------------------------------------
template <int D>
ProbeCurve probe_along(NetworkSolverT<D>& solver, const Eigen::Matrix<double, D, D>& dir_in, double sigma_y,
                       const ProbeOptions& o, std::vector<Eigen::Matrix<double, D, D>>* full) {
  using Mat = Eigen::Matrix<double, D, D>;
  if (!(o.first_step > 0.0) || !(o.max_step > 0.0) || !(o.max_strain > 0.0) || !(o.growth >= 1.0) ||
      o.max_increments < 1 || o.fine_increments < 0 || !(sigma_y > 0.0))
    throw std::invalid_argument("probe: steps, growth, limits and sigma_y must be positive");
  if (!dir_in.allFinite() || !(dir_in.norm() > 0.0))
    throw std::invalid_argument("probe: the strain-rate direction is zero or not finite");
  // a unit direction as it is (the 2D (cos, sin) directions), any other one normalised
  const Mat dir = std::abs(dir_in.norm() - 1.0) < 1e-15 ? dir_in : Mat(dir_in / dir_in.norm());
  ProbeCurve c;
  if (full) full->clear();
  Mat s = Mat::Zero();
  auto sample = [&](double strain, const IncrementReport* r) {
    ProbeSample p = probe_sample<D>(solver, dir, sigma_y, &s);
    p.strain = strain;
    if (r) {
      p.newton = r->newton_iterations;
      p.converged = r->converged;
      p.residual = r->residual;
    }
    return p;
  };
  c.samples.push_back(sample(0.0, nullptr));
  if (full) full->push_back(s);
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
    if (full) full->push_back(s);
    if (!schedule.record(h, c.samples.back().strain, c.samples.back().stress)) {
      c.end = schedule.end();
      break;
    }
  }
  return c;
}

template ProbeCurve probe_along<2>(NetworkSolverT<2>&, const Eigen::Matrix2d&, double, const ProbeOptions&,
                                   std::vector<Eigen::Matrix2d>*);
template ProbeCurve probe_along<3>(NetworkSolverT<3>&, const Eigen::Matrix3d&, double, const ProbeOptions&,
                                   std::vector<Eigen::Matrix3d>*);

ProbeCurve probe(NetworkSolver& solver, double theta, double sigma_y, const ProbeOptions& o) {
  Eigen::Matrix2d dir;
  dir << std::cos(theta), 0.0, 0.0, std::sin(theta);
  ProbeCurve c = probe_along<2>(solver, dir, sigma_y, o);
  c.theta = theta;
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

Eigen::Matrix3d fabric_affine_stress3(const NetworkSolver3& solver, const Eigen::Matrix3d& Edot, double mu_eff,
                                      double sigma_y) {
  if (!Edot.allFinite() || !(Edot.norm() > 0.0) || !(sigma_y > 0.0 && std::isfinite(sigma_y)) ||
      !(mu_eff >= 0.0 && std::isfinite(mu_eff)))
    throw std::invalid_argument("fabric_affine_stress3: need a finite nonzero rate, sigma_y > 0 and mu_eff >= 0");
  const Eigen::Matrix3d rate = 0.5 * (Edot + Edot.transpose()) / Edot.norm();
  const double volume = solver.box_deformation().determinant() * solver.solid_area() / solver.initial_density();
  Eigen::Matrix3d s = Eigen::Matrix3d::Zero();
  for (const auto& c : solver.contacts()) {
    const Eigen::Vector3d l(c.l[0], c.l[1], c.l[2]);
    const double L = l.norm();
    if (!(L > 0.0)) continue;
    const Eigen::Vector3d n = l / L, rn = rate * n;
    const double en = n.dot(rn);
    if (!(en < 0.0)) continue;  // not compressed by this strain rate
    s.noalias() -= c.f_n * L * n * n.transpose();
    const Eigen::Vector3d vt = rn - en * n;
    const double speed = vt.norm();
    if (mu_eff > 0.0 && speed > 1e-12) {
      const Eigen::Vector3d t = vt / speed;
      s.noalias() += 0.5 * mu_eff * c.f_n * L * (t * n.transpose() + n * t.transpose());
    }
  }
  return s / (volume * sigma_y);
}

}  // namespace netdem::qs
