// The material tests of LMM05 section 4.4 (netdem/dynamic/material_tests.hpp, docs/sintering.md).
#include "netdem/dynamic/material_tests.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <numbers>
#include <numeric>
#include <stdexcept>

#include "netdem/field_error.hpp"

namespace netdem::dem {

namespace {
/// Keeps the material at temperature T (k1(T, t) keeps relaxing if it still moves).
template <int D>
void hold_temperature(DynamicSolverT<D>& s, double T) { s.advance_temperature(T, s.dt(), s.params().t0); }
}  // namespace

void CompressionTest::validate() const {
  if (!(std::isfinite(strain_rate) && strain_rate > 0.0))
    throw FieldError("strain_rate", fmt::format("the compression strain rate must be a positive number of 1/s, got {}", strain_rate));
  if (!(std::isfinite(max_strain) && max_strain > 0.0 && max_strain < 0.9))
    throw FieldError("max_strain", fmt::format("the maximum strain must be in (0, 0.9), got {}", max_strain));
  if (!(std::isfinite(ramp_time) && ramp_time >= 0.0))
    throw FieldError("ramp_time", fmt::format("the ramp time must be a number of seconds >= 0, got {}", ramp_time));
}

std::int64_t CompressionTest::steps(double dt) const {
  // eps(t) = rate (t - t_ramp / 2) after the ramp
  return static_cast<std::int64_t>(std::ceil((max_strain / strain_rate + 0.5 * ramp_time) / dt));
}

std::int64_t VibrationTest::steps(double dt) const { return static_cast<std::int64_t>(std::ceil(time / dt)); }

namespace {
double height(const packing::Box& b, int dim) { return dim == 2 ? b.y_max - b.y_min : b.z_max - b.z_min; }
double top_stress(const Stress2& s) { return s.yy; }
double top_stress(const Stress3& s) { return s.s[2][2]; }
}  // namespace

template <int D>
double vertical_strain(const DynamicSolverT<D>& s, double z0) { return 1.0 - height(s.box(), D) / z0; }

template <int D>
CompressionRun run_compression(DynamicSolverT<D>& s, const CompressionTest& a, double pressure, std::int64_t samples,
                               TestObserverT<D>& obs) {
  a.validate();
  CompressionRun run;
  run.z0 = height(s.box(), D);
  const double z0 = run.z0;
  MovingWall right = s.box().right, top = s.box().top, back = s.box().back;
  right.mode = WallMode::Stress;  // sigma_xx = p held by the right wall
  right.pressure = pressure;
  back.mode = WallMode::Stress;  // 3D: sigma_yy = p held by the back wall
  back.pressure = pressure;
  top.mode = WallMode::Strain;  // eps_zz = 1 - z/z0 = rate (t - t_start)
  top.velocity = a.ramp_time > 0.0 ? 0.0 : -a.strain_rate * z0;
  auto set_walls = [&] {
    if constexpr (D == 2)
      s.set_walls(right, top);
    else
      s.set_walls(right, back, top);
  };
  set_walls();
  const double T = s.thermal().T;
  run.steps = a.steps(s.dt());
  const std::int64_t every = std::max<std::int64_t>(1, run.steps / std::max<std::int64_t>(1, samples));
  auto sample = [&](std::int64_t k) {
    run.eps.push_back(vertical_strain(s, z0));
    run.szz.push_back(top_stress(s.wall_stress()));
    obs.sample(s, k);
  };
  sample(0);
  for (std::int64_t k = 1; k <= run.steps; ++k) {
    const double tt = static_cast<double>(k - 1) * s.dt();
    if (tt < a.ramp_time) {  // smooth start, v = v_f (1 - cos(pi t / t_ramp)) / 2
      top.velocity = -a.strain_rate * z0 * 0.5 * (1.0 - std::cos(std::numbers::pi * tt / a.ramp_time));
      set_walls();
    } else if (top.velocity != -a.strain_rate * z0) {
      top.velocity = -a.strain_rate * z0;
      set_walls();
    }
    hold_temperature(s, T);
    s.step();
    if (k % every == 0 || k == run.steps) sample(k);
    obs.stepped(s, k);
  }
  return run;
}

CompressionFigures compression_figures(const CompressionRun& run, double window) {
  CompressionFigures f;
  f.peak = static_cast<std::size_t>(std::max_element(run.szz.begin(), run.szz.end()) - run.szz.begin());
  double se = 0, ss = 0, see = 0, ses = 0, m = 0;
  for (std::size_t k = 0; k < run.eps.size(); ++k)
    if (run.eps[k] >= 0.0 && run.eps[k] <= window) {
      se += run.eps[k];
      ss += run.szz[k];
      see += run.eps[k] * run.eps[k];
      ses += run.eps[k] * run.szz[k];
      m += 1.0;
    }
  f.stiffness = m >= 3 ? (m * ses - se * ss) / (m * see - se * se) : std::nan("");
  return f;
}

void VibrationTest::validate() const {
  if (!(std::isfinite(frequency) && frequency > 0.0))
    throw FieldError("frequency", fmt::format("the vibration frequency must be a positive number of Hz, got {}", frequency));
  if (!(std::isfinite(amplitude) && amplitude >= 0.0))
    throw FieldError("amplitude", fmt::format("the vibration amplitude must be a number of metres >= 0, got {}", amplitude));
  if (!(std::isfinite(time) && time > 0.0))
    throw FieldError("time", fmt::format("the vibration time must be a positive number of seconds, got {}", time));
  if (!(std::isfinite(gravity) && gravity >= 0.0))
    throw FieldError("gravity", fmt::format("the gravity must be a number >= 0, got {}", gravity));
}

void open_box_for_vibration(SolverState& st) {
  st.box.x_min -= 1.0;
  st.box.x_max += 1.0;
  st.box.y_max += 1.0;
  st.box.right.mode = WallMode::Fixed;
  st.box.top.mode = WallMode::Fixed;
  st.wall_velocity[0] = st.wall_velocity[1] = 0.0;
}

std::int64_t run_vibration(DynamicSolver& s, const VibrationTest& a, std::int64_t samples, TestObserver& obs) {
  a.validate();
  const double T = s.thermal().T, w = 2.0 * std::numbers::pi * a.frequency;
  const std::int64_t steps = a.steps(s.dt());
  const std::int64_t every = std::max<std::int64_t>(1, steps / std::max<std::int64_t>(1, samples));
  obs.sample(s, 0);
  for (std::int64_t k = 1; k <= steps; ++k) {
    const double tt = static_cast<double>(k) * s.dt();
    s.set_gravity(0.0, -a.gravity + a.amplitude * w * w * std::sin(w * tt));
    hold_temperature(s, T);
    s.step();
    if (k % every == 0 || k == steps) obs.sample(s, k);
    obs.stepped(s, k);
  }
  return steps;
}

void Clusters::update(const DynamicSolver& s) {
  const std::size_t n = s.particles().size();
  parent_.resize(n);
  size_.resize(n);
  std::iota(parent_.begin(), parent_.end(), 0u);
  auto find = [&](std::uint32_t x) {
    while (parent_[x] != x) x = parent_[x] = parent_[parent_[x]];
    return x;
  };
  s.touching_pairs(pairs_);
  for (auto [i, j] : pairs_) parent_[find(i)] = find(j);
  std::fill(size_.begin(), size_.end(), 0u);
  label_.resize(n);
  for (std::uint32_t i = 0; i < n; ++i) ++size_[label_[i] = find(i)];
}

std::uint32_t Clusters::largest() const { return size_.empty() ? 0u : *std::max_element(size_.begin(), size_.end()); }

std::size_t Clusters::single_grains() const {
  std::size_t singles = 0;
  for (std::uint32_t i = 0; i < label_.size(); ++i) singles += (label_[i] == i && size_[i] == 1);
  return singles;
}

std::vector<std::uint32_t> Clusters::sizes() const {
  std::vector<std::uint32_t> sizes;
  for (std::uint32_t i = 0; i < label_.size(); ++i)
    if (label_[i] == i) sizes.push_back(size_[i]);
  std::sort(sizes.rbegin(), sizes.rend());
  return sizes;
}

std::vector<double> Clusters::rank() const {
  const std::size_t n = label_.size();
  std::vector<std::uint32_t> roots;
  for (std::uint32_t i = 0; i < n; ++i)
    if (label_[i] == i) roots.push_back(i);
  std::stable_sort(roots.begin(), roots.end(), [&](auto x, auto y) { return size_[x] > size_[y]; });
  std::vector<double> r(n, 0.0), cid(n);
  for (std::size_t k = 0; k < roots.size(); ++k) r[roots[k]] = static_cast<double>(k);
  for (std::uint32_t i = 0; i < n; ++i) cid[i] = r[label_[i]];
  return cid;
}

template double vertical_strain<2>(const DynamicSolverT<2>&, double);
template double vertical_strain<3>(const DynamicSolverT<3>&, double);
template CompressionRun run_compression<2>(DynamicSolverT<2>&, const CompressionTest&, double, std::int64_t,
                                           TestObserverT<2>&);
template CompressionRun run_compression<3>(DynamicSolverT<3>&, const CompressionTest&, double, std::int64_t,
                                           TestObserverT<3>&);

}  // namespace netdem::dem
