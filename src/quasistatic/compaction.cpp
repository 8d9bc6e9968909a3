#include "netdem/quasistatic/compaction.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>

#include "netdem/system/strain_path.hpp"

namespace netdem::qs {

Eigen::Matrix2d StrainPath::rate() const {
  Eigen::Matrix2d r;
  r << E11, E12, E12, E22;
  return r;
}

StrainPath StrainPath::hydrostatic() { return {"hydrostatic", -1.0, -1.0, 0.0}; }
StrainPath StrainPath::closed_die() { return {"closed-die", 0.0, -1.0, 0.0}; }

StrainPath StrainPath::parse(const std::string& text) {
  const auto p = sys::StrainPathT<2>::parse(text);  // the one parser of both solvers and dimensions
  return {p.name, p.E[0], p.E[1], p.E[2]};
}

void CompactionOptions::validate(double initial_density) const {
  if (increments < 1 || increments > 10000000)
    throw std::invalid_argument(fmt::format("number of increments must be in [1, 1e7], got {}", increments));
  if (!precompacts()) {
    validate_path(initial_density, "current density");
    return;
  }
  if (precompact_increments < 1 || precompact_increments > 10000000)
    throw std::invalid_argument(
        fmt::format("number of precompaction increments must be in [1, 1e7], got {}", precompact_increments));
  if (!(std::isfinite(precompact_density) && precompact_density < 1.0))
    throw std::invalid_argument(fmt::format("the precompaction density must be below 1, got {}", precompact_density));
  if (!(precompact_density > initial_density))
    throw std::invalid_argument(fmt::format("impossible precompaction: density {} is not above the start density {:.4f}",
                                            precompact_density, initial_density));
  validate_path(precompact_density, "precompaction density");
}

void CompactionOptions::validate_path(double density, const char* from) const {
  if (target_strain != 0.0) {
    if (!(target_strain >= kMinTargetStrain && target_strain <= kMaxTargetStrain))
      throw std::invalid_argument(
          fmt::format("target strain |E| must be in [{:g}, {:g}], got {}", kMinTargetStrain, kMaxTargetStrain, target_strain));
    const Eigen::Matrix2d r = path.rate();
    const double final_density = density * std::exp(-target_strain * r.trace() / r.norm());
    if (!(final_density < 1.0))
      throw std::invalid_argument(fmt::format("impossible target: strain |E| = {} along {} ends at density {:.4g} >= 1",
                                              target_strain, path.name, final_density));
    return;
  }
  if (!(std::isfinite(target_density) && target_density > 0.0 && target_density < 1.0))
    throw std::invalid_argument(fmt::format("target density must be in (0, 1), got {}", target_density));
  if (!(target_density > density))
    throw std::invalid_argument(fmt::format("impossible target: density {} is not above the {} {:.4f}", target_density,
                                            from, density));
  if (!(path.E11 + path.E22 < 0.0))
    throw std::invalid_argument(fmt::format(
        "impossible target: strain path {} (E11+E22 = {}) does not compact, so density {} is never reached", path.name,
        path.E11 + path.E22, target_density));
}

CompactionOptions CompactionOptions::precompaction() const {
  CompactionOptions c;
  c.path = StrainPath::hydrostatic();
  c.target_density = precompact_density;
  c.increments = precompact_increments;
  return c;
}

Eigen::Matrix2d CompactionOptions::increment_strain(double initial_density) const {
  const Eigen::Matrix2d rate = path.rate();
  if (target_strain != 0.0) return rate * (target_strain / rate.norm()) / increments;  // |E| = Frobenius norm
  // D = D0 exp(-(E11 + E22)): the volumetric strain still needed, split into equal increments
  const double trE = std::log(initial_density / target_density);
  return rate * (trE / rate.trace()) / increments;
}

void run_compaction(NetworkSolver& solver, const CompactionOptions& options,
                    const std::function<void(const CompactionRow&)>& on_row) {
  CompactionRow row;
  row.state = solver.measures();
  options.validate(row.state.density);
  int done = 0;
  if (options.precompacts()) {  // leg 0: hydrostatic to the precompaction density
    row.leg = 0;
    on_row(row);
    const Eigen::Matrix2d dE0 = options.precompaction().increment_strain(row.state.density);
    for (int k = 1; k <= options.precompact_increments; ++k) {
      row.increment = ++done;
      row.report = solver.increment(dE0);
      row.state = solver.measures();
      on_row(row);
    }
    row.leg = 1;
  } else {
    on_row(row);
  }
  // the path from the density reached (a target density: the volumetric strain still needed)
  const Eigen::Matrix2d dE = options.increment_strain(row.state.density);
  for (int k = 1; k <= options.increments; ++k) {
    row.increment = done + k;
    row.report = solver.increment(dE);
    row.state = solver.measures();
    on_row(row);
  }
}

}  // namespace netdem::qs
