#pragma once
// The material tests of Luding, Manetsberger & Muellers (2005) section 4.4 on a sample state, as
// library functions (demsolve compress / vibrate parse, call these and write): the bi-axial
// compression (sigma_xx = p held by the right wall, the top wall at a constant strain rate after
// a smooth ramp) with its failure peak and stiffness, and the vibration on a flat bottom in
// gravity (walls moved away, the floor's motion as an inertial force) with the clusters of
// touching grains. Output is the caller's, through TestObserver. See docs/sintering.md.
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "netdem/dynamic/solver.hpp"

namespace netdem::dem {

/// What the caller records while a test steps.
template <int D>
class TestObserverT {
 public:
  virtual ~TestObserverT() = default;
  /// At the start (step 0), every `every` steps and after the last step.
  virtual void sample(const DynamicSolverT<D>& s, std::int64_t step) = 0;
  /// After every step (after its sample, if any).
  virtual void stepped(const DynamicSolverT<D>& s, std::int64_t step) {
    (void)s;
    (void)step;
  }
};
using TestObserver = TestObserverT<2>;

/// LMM05 section 4.4.1: eps_zz = 1 - z / z0 at the strain rate, after the top wall's speed rose
/// as v_f (1 - cos(pi t / ramp_time)) / 2 over ramp_time.
struct CompressionTest {
  double strain_rate = 1.0;  ///< d eps_zz / dt [1/s], top wall velocity -rate z0
  double max_strain = 0.1;
  double ramp_time = 0.005;  ///< [s]
  /// Throws std::invalid_argument (one line) for a non-positive rate, max_strain outside (0, 0.9),
  /// a negative ramp time.
  void validate() const;
  /// Steps of the test: (max_strain / rate + ramp_time / 2) / dt rounded up.
  std::int64_t steps(double dt) const;
};

struct CompressionRun {
  double z0 = 0.0;  ///< box height at the start [m]
  std::int64_t steps = 0;
  std::vector<double> eps, szz;  ///< eps_zz and the top wall stress at every sample [N/m]
};

/// Vertical strain 1 - z / z0 of the current box (the height: y in 2D, z in 3D).
template <int D>
double vertical_strain(const DynamicSolverT<D>& s, double z0);

/// Sets the walls of the test (right: stress-controlled at `pressure` [N/m], top: strain-
/// controlled) and steps max_strain / rate + ramp_time / 2 seconds at the state's temperature
/// (k1(T, t) keeps relaxing with the parameters' t0); about `samples` samples. 3D: the triaxial
/// test, sigma_xx = sigma_yy = p [N/m^2] held by the right and back walls, the top (z_max) wall
/// strain-controlled; szz is the top wall's stress.
template <int D>
CompressionRun run_compression(DynamicSolverT<D>& s, const CompressionTest& test, double pressure, std::int64_t samples,
                               TestObserverT<D>& observer);

struct CompressionFigures {
  std::size_t peak = 0;      ///< sample index of the largest szz (failure)
  double stiffness = 0.0;    ///< least-squares slope d szz / d eps over eps in [0, window]; NaN if < 3 samples
};
CompressionFigures compression_figures(const CompressionRun& run, double window = 0.005);

/// LMM05 Figs 21-22: the sample on its flat bottom vibrated as y_floor = A sin(2 pi f t).
struct VibrationTest {
  double frequency = 100.0;   ///< [Hz]
  double amplitude = 2.0e-4;  ///< [m]
  double time = 0.1;          ///< [s]
  double gravity = 9.81;      ///< [m/s^2]
  void validate() const;      ///< one-line std::invalid_argument for a bad value
  std::int64_t steps(double dt) const;  ///< time / dt rounded up
};

/// Confining stress removed: left, right and top walls moved 1 m away and fixed, only the bottom
/// stays (applied to a state before the solver is built).
void open_box_for_vibration(SolverState& state);

/// Steps test.time seconds in the co-moving frame of the floor: gravity -g + A w^2 sin(w t) (the
/// inertial force of the rigid translating floor), the state's temperature held. Returns the
/// steps done.
std::int64_t run_vibration(DynamicSolver& s, const VibrationTest& test, std::int64_t samples, TestObserver& observer);

/// Clusters of touching grains (union-find over the touching pairs), storage reused.
class Clusters {
 public:
  /// Recomputes the clusters of the current state.
  void update(const DynamicSolver& s);
  /// label[i]: the root particle of i's cluster; size[root]: its cluster size (0 for non-roots).
  const std::vector<std::uint32_t>& label() const { return label_; }
  const std::vector<std::uint32_t>& size() const { return size_; }
  std::uint32_t largest() const;
  std::size_t single_grains() const;
  /// Cluster sizes in decreasing order.
  std::vector<std::uint32_t> sizes() const;
  /// Per particle, the rank of its cluster by decreasing size (ties by root id).
  std::vector<double> rank() const;

 private:
  std::vector<std::uint32_t> parent_, size_, label_;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs_;
};

}  // namespace netdem::dem
