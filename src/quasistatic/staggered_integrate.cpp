// The staggered scheme: the two-particle models over a step (staggered_impl.hpp; docs/staggered.md
// "Time marching"): RK4 with step doubling, strategy 1 (one global step, rejected when a contact
// misses eps_lim) and strategy 2 (per-contact sub-steps), and advance_free, the tests' reference.
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

#include "staggered_impl.hpp"

namespace netdem::qs::staggered {

namespace {

// One classical RK4 step (the paper's integrator) from q at t over h; k1 = f(t, q) given.
bool rk4(const RhsCtx& f, double t, double h, const State& q, const State& k1, State& out) {
  State y{}, k2{}, k3{}, k4{};
  for (int i = 0; i < 5; ++i) y[i] = q[i] + 0.5 * h * k1[i];
  if (!f(t + 0.5 * h, y, k2)) return false;
  for (int i = 0; i < 5; ++i) y[i] = q[i] + 0.5 * h * k2[i];
  if (!f(t + 0.5 * h, y, k3)) return false;
  for (int i = 0; i < 5; ++i) y[i] = q[i] + h * k3[i];
  if (!f(t + h, y, k4)) return false;
  for (int i = 0; i < 5; ++i) out[i] = q[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
  return finite_state(out);
}

// A trial step with its step-doubling estimate: one RK4 step of h against two of h/2; the error of
// the two half steps is their difference / (2^4 - 1), relative to x and to y4 + y7. ok = false when
// a stage left the model's domain.
struct Trial {
  bool ok = false;
  double error = std::numeric_limits<double>::infinity();  // relative, not yet divided by eps_lim
  State q{};
};
Trial trial_step(const RhsCtx& f, double t, double h, const State& q) {
  Trial r;
  State k1{};
  if (!f(t, q, k1)) return r;
  State full{}, half{}, two{};
  if (!rk4(f, t, h, q, k1, full)) return r;
  if (!rk4(f, t, 0.5 * h, q, k1, half)) return r;
  State k1h{};
  if (!f(t + 0.5 * h, half, k1h)) return r;
  if (!rk4(f, t + 0.5 * h, 0.5 * h, half, k1h, two)) return r;
  const double sf = full[kHA] + full[kHB], s2 = two[kHA] + two[kHB];
  const double ex = std::fabs(two[kX] - full[kX]) / std::fabs(two[kX]);
  const double es = std::fabs(s2 - sf) / std::fabs(s2);
  r.error = std::max(ex, es) / 15.0;
  r.ok = std::isfinite(r.error);
  r.q = two;
  return r;
}

// Strategy 2: the sub-steps of one contact over [t0, t1] (RK4 with step doubling; a failed
// sub-step is divided by alpha, a sub-step well within eps_lim (0.1) lets the next one grow by
// alpha). ok = false when a sub-step would fall below dt_min: domain = true if it failed because
// a stage left the model's domain (the caller freezes the contact), else because of accuracy.
struct ContactResult {
  State q{};
  long substeps = 0;
  double max_error = 0.0;
  bool ok = true, domain = false;
};
ContactResult advance_substeps(const State& q0, double R_min0, const RhsCtx& f, double t0, double t1,
                               const StaggeredOptions& opt, double x_max) {
  ContactResult r;
  r.q = q0;
  double tl = t0, h = t1 - t0;
  bool cut = false;
  while (tl < t1) {
    const double remaining = t1 - tl;
    bool last = false;
    if (h >= remaining * (1.0 - 1e-12)) {
      h = remaining;
      last = true;
    }
    const Trial tr = trial_step(f, tl, h, r.q);
    if (!tr.ok || tr.error > opt.eps_lim) {
      h /= opt.alpha;
      cut = true;
      if (h < opt.dt_min) {
        r.ok = false;
        r.domain = !tr.ok;
        return r;
      }
      continue;
    }
    r.q = tr.q;
    tl = last ? t1 : tl + h;
    ++r.substeps;
    r.max_error = std::max(r.max_error, tr.error / opt.eps_lim);
    if (cut && tr.error < 0.1 * opt.eps_lim) h *= opt.alpha;
    // the neck reached the freeze limit: the contact stops here (frozen after this step)
    if (cs::check_state(r.q, R_min0, x_max) == cs::PairStatus::NeckLimit) break;
  }
  return r;
}

}  // namespace


bool advance_free(cs::PairContact& c, const cs::SinterMaterial& m, const cs::TemperatureProfile& T, double t1,
                  const StaggeredOptions& o, long* substeps) {
  const double x_max = freeze_limit(m, o);
  DiffCache cache;
  cache.m = &m;
  while (c.t < t1) {
    long evals = 0;
    const auto seg = T.segment_at(c.t);
    const double te = std::min(t1, seg.t1);
    RhsCtx f{&m, &cache, seg, &evals};
    const ContactResult r = advance_substeps(c.q, c.R_min0(), f, c.t, te, o, x_max);
    if (!r.ok) return false;
    c.q = r.q;
    c.t = te;
    c.rhs_evals += evals;
    if (substeps != nullptr) *substeps += r.substeps;
    if (cs::check_state(c.q, c.R_min0(), x_max) != cs::PairStatus::Ok) return false;
  }
  return true;
}

// The two-particle models of the active contacts over one accepted step [t, t + h] with F = 0,
// into qnew (freeze[i] = 2: the contact left the model's domain); returns h.
double Staggered::Impl::integrate_contacts(StepRecord& rec, double t_end, double seg_end) {
  RhsCtx f{&mat, &cache, prof.segment_at(t), &rhs_evals};
  // per-step work arrays, kept in Impl (no allocation once the contact count has settled)
  qnew.resize(c.size());
  active.clear();
  for (std::size_t i = 0; i < c.size(); ++i)
    if (!c[i].frozen) active.push_back(static_cast<int>(i));
  freeze.assign(c.size(), 0);
  for (;;) {
    double h = std::min({dt, t_end - t, seg_end - t});
    if (h >= (std::min(t_end, seg_end) - t) * (1.0 - 1e-12)) h = std::min(t_end, seg_end) - t;
    rec.max_error = 0.0;
    rec.substeps = 0;
    rec.contacts_substepped = 0;
    if (opt.strategy != 1 || strategy1_attempt(rec, f, h)) {
      if (opt.strategy != 1) strategy2_step(rec, f, h);
      return h;
    }
  }
}

// Strategy 1: one step h for every contact, accepted when every error is below eps_lim (else dt
// shrinks, Eq 45; contacts that leave the domain at dt_min are frozen); true if accepted.
bool Staggered::Impl::strategy1_attempt(StepRecord& rec, const RhsCtx& f, double h) {
  bool accepted = true;
  domain_fail.clear();
  for (int i : active) {
    const Trial tr = trial_step(f, t, h, c[i].pair.q);
    if (!tr.ok) domain_fail.push_back(i);
    if (!tr.ok || tr.error > opt.eps_lim) {
      accepted = false;
      continue;
    }
    qnew[i] = tr.q;
    rec.max_error = std::max(rec.max_error, tr.error / opt.eps_lim);
  }
  rec.substeps = static_cast<long>(active.size());
  if (accepted) {
    if (rec.max_error < 0.1) dt = std::min(opt.dt_max, opt.alpha * dt);  // Eqs 46-47
    return true;
  }
  ++rec.rejected;
  dt = h / opt.alpha;  // Eq 45
  if (dt < opt.dt_min) {
    if (domain_fail.empty())
      throw std::runtime_error(
          fmt::format("staggered: strategy 1 needs a step below dt_min = {:.3g} s at t = {:.6g} s", opt.dt_min, t));
    for (int i : domain_fail) {  // these contacts left the model's domain: freeze them
      c[i].frozen = true;
      c[i].pair.status = cs::PairStatus::ConeDegenerate;
      ++rec.newly_frozen;
    }
    active.erase(std::remove_if(active.begin(), active.end(), [&](int i) { return c[i].frozen; }), active.end());
    dt = opt.dt_min;
  }
  return false;
}

// Strategy 2: each contact sub-steps over [t, t + h] on its own; dt follows the fraction of
// contacts that needed sub-steps.
void Staggered::Impl::strategy2_step(StepRecord& rec, const RhsCtx& f, double h) {
  for (int i : active) {
    const ContactResult r = advance_substeps(c[i].pair.q, c[i].pair.R_min0(), f, t, t + h, opt, x_max);
    if (!r.ok) {
      if (r.domain) {
        freeze[i] = 2;  // leaves the domain: frozen, no load this step
        qnew[i] = c[i].pair.q;
        continue;
      }
      throw std::runtime_error(fmt::format(
          "staggered: contact {}-{} needs a sub-step below dt_min = {:.3g} s at t = {:.6g} s", c[i].a, c[i].b,
          opt.dt_min, t));
    }
    qnew[i] = r.q;
    rec.substeps += r.substeps;
    if (r.substeps > 1) ++rec.contacts_substepped;
    rec.max_error = std::max(rec.max_error, r.max_error);
  }
  const double frac =
      active.empty() ? 0.0 : static_cast<double>(rec.contacts_substepped) / static_cast<double>(active.size());
  if (frac < opt.grow_below)
    dt = std::min(opt.dt_max, opt.alpha * dt);
  else if (frac > opt.shrink_above)
    dt = std::max(opt.dt_min, dt / opt.alpha);
}

}  // namespace netdem::qs::staggered
