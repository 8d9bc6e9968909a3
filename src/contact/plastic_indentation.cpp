#include "netdem/contact/plastic_indentation.hpp"

#include <stdexcept>
#include <string>

namespace netdem::contact {

namespace {
void require(bool ok, const std::string& msg) {
  if (!ok) throw std::invalid_argument(msg);
}
}  // namespace

void PlasticIndentationParams::validate() const {
  require(std::isfinite(sigma_y) && sigma_y > 0.0,
          "contact law: yield stress sigma_y must be positive and finite, got " + std::to_string(sigma_y));
  require(!std::isnan(mu) && mu >= 0.0,
          "contact law: friction coefficient mu must be >= 0 (or inf for sticking), got " + std::to_string(mu));
  require(std::isfinite(k_t) && k_t > 0.0,
          "contact law: tangential stiffness k_t must be positive and finite, got " + std::to_string(k_t));
  require(std::isfinite(unload_ratio) && unload_ratio >= 1.0,
          "contact law: unloading stiffness ratio must be >= 1 and finite, got " + std::to_string(unload_ratio));
  require(std::isfinite(first_touch) && first_touch >= 0.0 && first_touch <= 1e-2,
          "contact law: first-touch overlap u_c/(2R*) must be in [0, 0.01], got " + std::to_string(first_touch));
  require(std::isfinite(damping_n) && damping_n >= 0.0 && std::isfinite(damping_t) && damping_t >= 0.0,
          "contact law: damping ratios must be >= 0 and finite, got " + std::to_string(damping_n) + ", " +
              std::to_string(damping_t));
  require(!damped() || first_touch > 0.0, "contact law: the dashpots need a first-touch overlap > 0");
}

}  // namespace netdem::contact
