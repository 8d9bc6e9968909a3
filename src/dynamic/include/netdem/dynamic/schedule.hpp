#pragma once
// The temperature protocol of LMM05 section 4.1 (Fig 7): preparation at T_cold, frictionless;
// heating to T_hot; sintering at T_hot with the short relaxation time t0_sinter (the quenched
// time axis); cooling back to T_cold; relaxation. Every phase length, both temperatures and t0
// per phase are inputs; the defaults are the paper's.
#include <cstddef>
#include <string>
#include <vector>

namespace netdem::dem {

struct SinterPhase {
  std::string name;
  double duration = 0.0;            ///< [s]
  double T_start = 80.0, T_end = 80.0;  ///< linear ramp over the phase [deg C]
  double t0 = 1.0e3;                ///< relaxation time of Eq 11-12 during the phase [s]
  bool friction = true;             ///< particle friction mu on (off: mu = 0)
};

struct SinterProtocol {
  double t_heat = 0.2;     ///< preparation length (t_heat - 0)
  double heat = 0.1;       ///< t_sinter - t_heat
  double sinter = 1.0;     ///< t_s = t_cool - t_sinter
  double cool = 0.1;       ///< t_relax - t_cool
  double relax = 0.1;      ///< t_f - t_relax
  double T_cold = 80.0;    ///< [deg C]
  double T_hot = 140.0;    ///< [deg C]
  double t0 = 1.0e3;       ///< default relaxation time (Table 1) for all but the sintering phase
  double t0_sinter = 0.1;  ///< during sintering (section 4.1)
  /// Throws std::invalid_argument (one line) for a negative length, non-finite value, t0 <= 0.
  void validate() const;
  /// The five phases: prepare, heat, sinter, cool, relax.
  std::vector<SinterPhase> phases() const;
};

/// Where a protocol is at time t: phase index, temperature, t0, friction.
struct ScheduleAt {
  std::size_t phase = 0;
  double T = 80.0, t0 = 1.0e3;
  bool friction = false;
};

/// The protocol state at time t (t inside (start, end] of a phase belongs to that phase; t = 0 to
/// the first). Past the end: the last phase at its end temperature.
ScheduleAt schedule_at(const std::vector<SinterPhase>& phases, double t);
/// End time of phase k (sum of the durations up to and including k).
double phase_end(const std::vector<SinterPhase>& phases, std::size_t k);

}  // namespace netdem::dem
