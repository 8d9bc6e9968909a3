// LMM05 section 4.1 temperature protocol (see schedule.hpp).
#include "netdem/dynamic/schedule.hpp"

#include <cmath>
#include <stdexcept>

namespace netdem::dem {

void SinterProtocol::validate() const {
  const double len[5] = {t_heat, heat, sinter, cool, relax};
  const char* name[5] = {"preparation time", "heating time", "sintering time", "cooling time",
                         "relaxation time"};
  for (int k = 0; k < 5; ++k)
    if (!(std::isfinite(len[k]) && len[k] >= 0.0))
      throw std::invalid_argument(std::string(name[k]) + " must be a finite number >= 0");
  if (!(std::isfinite(T_cold) && std::isfinite(T_hot)))
    throw std::invalid_argument("temperatures must be finite");
  if (!(std::isfinite(t0) && t0 > 0.0 && std::isfinite(t0_sinter) && t0_sinter > 0.0))
    throw std::invalid_argument("relaxation times t0 must be positive");
}

std::vector<SinterPhase> SinterProtocol::phases() const {
  validate();
  return {{"prepare", t_heat, T_cold, T_cold, t0, false},
          {"heat", heat, T_cold, T_hot, t0, true},
          {"sinter", sinter, T_hot, T_hot, t0_sinter, true},
          {"cool", cool, T_hot, T_cold, t0, true},
          {"relax", relax, T_cold, T_cold, t0, true}};
}

double phase_end(const std::vector<SinterPhase>& phases, std::size_t k) {
  double t = 0.0;
  for (std::size_t i = 0; i <= k && i < phases.size(); ++i) t += phases[i].duration;
  return t;
}

ScheduleAt schedule_at(const std::vector<SinterPhase>& phases, double t) {
  if (phases.empty()) throw std::invalid_argument("schedule_at: no phases");
  double start = 0.0;
  for (std::size_t k = 0; k < phases.size(); ++k) {
    const SinterPhase& p = phases[k];
    const double end = start + p.duration;
    if (t <= end || k + 1 == phases.size()) {
      const double s = p.duration > 0.0 ? std::fmin(1.0, std::fmax(0.0, (t - start) / p.duration)) : 1.0;
      return {k, p.T_start + (p.T_end - p.T_start) * s, p.t0, p.friction};
    }
    start = end;
  }
  return {};  // not reached
}

}  // namespace netdem::dem
