#include "netdem/quasistatic/compaction.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>

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

Eigen::Matrix3d StrainPath3::rate() const {
  Eigen::Matrix3d r;
  for (int k = 0; k < sys::kVoigt<3>; ++k) {
    const double v = E[static_cast<std::size_t>(k)];
    r(sys::voigt_row<3>(k), sys::voigt_col<3>(k)) = v;
    r(sys::voigt_col<3>(k), sys::voigt_row<3>(k)) = v;
  }
  return r;
}

StrainPath3 StrainPath3::hydrostatic() { return parse("hydrostatic"); }

StrainPath3 StrainPath3::parse(const std::string& text) {
  const auto p = sys::StrainPathT<3>::parse(text);
  return {p.name, p.E};
}

namespace {
/// "E11+E22" (2D) or "E11+E22+E33": the trace in the messages.
template <int D>
constexpr const char* trace_name() {
  return D == 2 ? "E11+E22" : "E11+E22+E33";
}
}  // namespace

template <int D>
void CompactionOptionsT<D>::validate(double initial_density) const {
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

template <int D>
void CompactionOptionsT<D>::validate_path(double density, const char* from) const {
  const Mat r = path.rate();
  if (target_strain != 0.0) {
    if (!(target_strain >= kMinTargetStrain && target_strain <= kMaxTargetStrain))
      throw std::invalid_argument(
          fmt::format("target strain |E| must be in [{:g}, {:g}], got {}", kMinTargetStrain, kMaxTargetStrain, target_strain));
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
  if (!(r.trace() < 0.0))
    throw std::invalid_argument(fmt::format(
        "impossible target: strain path {} ({} = {}) does not compact, so density {} is never reached", path.name,
        trace_name<D>(), r.trace(), target_density));
}

template <int D>
CompactionOptionsT<D> CompactionOptionsT<D>::precompaction() const {
  CompactionOptionsT c;
  c.path = StrainPathOf<D>::hydrostatic();
  c.target_density = precompact_density;
  c.increments = precompact_increments;
  return c;
}

template <int D>
typename CompactionOptionsT<D>::Mat CompactionOptionsT<D>::increment_strain(double initial_density) const {
  const Mat rate = path.rate();
  if (target_strain != 0.0) return rate * (target_strain / rate.norm()) / increments;  // |E| = Frobenius norm
  // D = D0 exp(-tr E): the volumetric strain still needed, split into equal increments
  const double trE = std::log(initial_density / target_density);
  return rate * (trE / rate.trace()) / increments;
}

namespace {
template <int D>
CompactionMeasuresOf<D> row_measures(const NetworkSolverT<D>& solver) {
  if constexpr (D == 2) {
    return solver.measures();
  } else {
    return solver.stress();
  }
}
}  // namespace

template <int D>
void run_compaction(NetworkSolverT<D>& solver, const CompactionOptionsT<D>& options,
                    const std::type_identity_t<std::function<void(const CompactionRowT<D>&)>>& on_row) {
  using Mat = typename CompactionOptionsT<D>::Mat;
  CompactionRowT<D> row;
  row.state = row_measures(solver);
  options.validate(row.state.density);
  int done = 0;
  if (options.precompacts()) {  // leg 0: hydrostatic to the precompaction density
    row.leg = 0;
    on_row(row);
    const Mat dE0 = options.precompaction().increment_strain(row.state.density);
    for (int k = 1; k <= options.precompact_increments; ++k) {
      row.increment = ++done;
      row.report = solver.increment(dE0);
      row.state = row_measures(solver);
      on_row(row);
    }
    row.leg = 1;
  } else {
    on_row(row);
  }
  // the path from the density reached (a target density: the volumetric strain still needed)
  const Mat dE = options.increment_strain(row.state.density);
  for (int k = 1; k <= options.increments; ++k) {
    row.increment = done + k;
    row.report = solver.increment(dE);
    row.state = row_measures(solver);
    on_row(row);
  }
}

template struct CompactionOptionsT<2>;
template struct CompactionOptionsT<3>;
template void run_compaction<2>(NetworkSolverT<2>&, const CompactionOptionsT<2>&,
                                const std::type_identity_t<std::function<void(const CompactionRowT<2>&)>>&);
template void run_compaction<3>(NetworkSolverT<3>&, const CompactionOptionsT<3>&,
                                const std::type_identity_t<std::function<void(const CompactionRowT<3>&)>>&);

}  // namespace netdem::qs
