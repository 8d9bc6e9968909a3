// The yield-surface driver: boundary-mode hand-over, one probe with its yield points, and the
// probes of a surface on several threads from one state (yield_driver.hpp).
#include "netdem/quasistatic/yield_driver.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <limits>
#include <numbers>
#include <stdexcept>

#include <Eigen/LU>
#include <fmt/format.h>

#include "netdem/contact/plastic_indentation.hpp"

namespace netdem::qs {

std::unique_ptr<NetworkSolver> switch_boundary_mode(const NetworkSolver& solver, const packing::Box& box0,
                                                    std::uint64_t seed, const SolverOptions& next, HandoverReport& rep) {
  if (next.law.frictional())
    throw std::invalid_argument(
        "boundary-mode switch: only frictionless runs can switch, the solver is rebuilt from the compacted state and "
        "would lose the tangential contact forces");
  const StateMeasures before = solver.measures();
  packing::Packing& hp = rep.compacted;
  hp = packing::Packing{};
  hp.x = solver.x();
  hp.y = solver.y();
  hp.r = solver.radius();
  hp.seed = seed;
  const Eigen::Matrix2d F = solver.box_deformation();
  const Eigen::Vector2d c0 = F * Eigen::Vector2d(box0.x_min, box0.y_min), c1 = F * Eigen::Vector2d(box0.x_max, box0.y_max);
  hp.box = {std::min(c0.x(), c1.x()), std::min(c0.y(), c1.y()), std::max(c0.x(), c1.x()), std::max(c0.y(), c1.y())};
  // A die compaction can squeeze a disk between two peripheral disks until its centre leaves the
  // box; the rebuilt packing must hold every centre, so the box grows just enough (reported: it
  // lowers D and the stresses of the new solver by the area ratio).
  const double area_box = (hp.box.x_max - hp.box.x_min) * (hp.box.y_max - hp.box.y_min);
  rep.centres_outside_box = 0;
  for (std::size_t p = 0; p < hp.x.size(); ++p) {
    const double m = 1e-9 * hp.r[p];
    if (hp.x[p] <= hp.box.x_min || hp.x[p] >= hp.box.x_max || hp.y[p] <= hp.box.y_min || hp.y[p] >= hp.box.y_max)
      ++rep.centres_outside_box;
    hp.box.x_min = std::min(hp.box.x_min, hp.x[p] - m);
    hp.box.x_max = std::max(hp.box.x_max, hp.x[p] + m);
    hp.box.y_min = std::min(hp.box.y_min, hp.y[p] - m);
    hp.box.y_max = std::max(hp.box.y_max, hp.y[p] + m);
  }
  rep.box_area_growth = (hp.box.x_max - hp.box.x_min) * (hp.box.y_max - hp.box.y_min) / area_box - 1.0;
  rep.contacts = rep.contacts_unloaded = 0;
  const auto& law = solver.options().law;
  for (const auto& c : solver.contacts()) {
    const double ri = hp.r[c.i], rj = hp.r[c.j];
    const double fp = contact::plastic_force(law, ri * rj / (ri + rj), c.overlap);
    ++rep.contacts;
    rep.contacts_unloaded += c.f_n < fp * (1 - 1e-6);
  }
  auto out = std::make_unique<NetworkSolver>(hp, next);
  // A new solver has no committed contact forces yet: zero-strain increments evaluate them (and,
  // affine -> die, let the interior relax once the affine constraint is released).
  int relax = 0;
  rep.unconverged = 0;
  for (; relax < 10; ++relax) {
    const auto r = out->increment(Eigen::Matrix2d::Zero());
    rep.unconverged += !r.converged;
    if (r.converged && relax >= 1) break;
  }
  const StateMeasures after = out->measures();
  const double sy = law.sigma_y;
  rep.S11_before = before.S11 / sy;
  rep.S22_before = before.S22 / sy;
  rep.S11_after = after.S11 / sy;
  rep.S22_after = after.S22 / sy;
  rep.zero_strain_increments = relax + 1;
  return out;
}

ProbeResult run_probe(NetworkSolver& solver, int index, const ProbeSettings& a) {
  const auto t0 = std::chrono::steady_clock::now();
  ProbeCurve curve = probe(solver, 2 * std::numbers::pi * index / a.directions, a.sigma_y, probe_options(a));
  ProbeResult res = evaluate_probe(std::move(curve), index, a);
  res.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return res;
}

std::vector<ProbeResult> run_probes(const NetworkState& start, const SolverOptions& options,
                                    const std::vector<int>& indices, const ProbeSettings& settings,
                                    const std::function<void(const ProbeResult&)>& on_done) {
  start.validate();
  options.validate();
  std::vector<ProbeResult> results;
  results.reserve(indices.size());
  for (const int index : indices) {
    ProbeResult r;
    try {
      NetworkSolver solver(start, options);
      r = run_probe(solver, index, settings);
    } catch (const std::exception& e) {
      r = ProbeResult{};
      r.index = index;
      r.theta = 2 * std::numbers::pi * index / settings.directions;
      r.status = std::string("error: ") + e.what();
    }
    results.push_back(std::move(r));
    if (on_done) on_done(results.back());
  }
  return results;
}

}  // namespace netdem::qs
