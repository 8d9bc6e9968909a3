#include "netdem/contact/luding.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace netdem::contact {

namespace {
void need(bool ok, const char* name, const char* rule, double v) {
  if (!ok)
    throw std::invalid_argument(std::string("luding contact law: ") + name + " must be " + rule +
                                ", got " + std::to_string(v));
}
bool fin(double v) { return std::isfinite(v); }
}  // namespace

void LudingParams::validate() const {
  need(fin(k2) && k2 > 0.0, "k2", "positive and finite", k2);
  need(fin(k1_ratio) && k1_ratio > 0.0 && k1_ratio <= 1.0, "k1/k2", "in (0, 1]", k1_ratio);
  // (an attractive branch 1e3 times stiffer than the unloading spring has no physical use and
  // overflows the attraction limit f_min)
  need(fin(kc_ratio) && kc_ratio >= 0.0 && kc_ratio <= 1e3, "k_c/k2", "in [0, 1e3]", kc_ratio);
  need(fin(alpha) && alpha > 0.0, "k_t/k2 (alpha)", "positive and finite", alpha);
  need(fin(gamma_n) && gamma_n >= 0.0, "gamma_0", ">= 0 and finite", gamma_n);
  need(fin(gamma_t) && gamma_t >= 0.0, "gamma_t", ">= 0 and finite", gamma_t);
  need(fin(mu) && mu >= 0.0, "mu", ">= 0 and finite", mu);
  need(fin(mu_wall) && mu_wall >= 0.0, "mu_wall", ">= 0 and finite", mu_wall);
  need(fin(T_melt), "T_melt", "finite", T_melt);
  need(fin(T_var) && T_var > 0.0, "T_var", "positive and finite", T_var);
  need(fin(da_T) && da_T >= 0.0, "delta a_T", ">= 0 and finite", da_T);
  need(fin(delta_fluid_rel) && delta_fluid_rel > 0.0, "delta_fluid/a0", "positive and finite",
       delta_fluid_rel);
  need(fin(t0) && t0 > 0.0, "t0", "positive and finite", t0);
  need(fin(t0_sinter) && t0_sinter > 0.0, "t0 (sintering)", "positive and finite", t0_sinter);
  need(fin(a0) && a0 > 0.0, "a0", "positive and finite", a0);
  need(fin(w0) && w0 >= 0.0 && w0 < 1.0, "w0", "in [0, 1)", w0);
  need(fin(h) && h > 0.0, "h", "positive and finite", h);
  need(fin(rho_p) && rho_p > 0.0, "rho_p", "positive and finite", rho_p);
  need(fin(m_wall) && m_wall > 0.0, "m_wall", "positive and finite", m_wall);
  need(fin(gamma_wall) && gamma_wall >= 0.0, "gamma_wall", ">= 0 and finite", gamma_wall);
  need(fin(T_radius_ref) && std::fabs(da_T * (T_melt - T_radius_ref)) < 1.0, "T_radius_ref",
       "finite with |da_T (T_melt - T_ref)| < 1", T_radius_ref);
}

}  // namespace netdem::contact
