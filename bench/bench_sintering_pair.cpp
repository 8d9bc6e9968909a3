// bench_sintering_pair: the per-contact sintering workload of the staggered scheme (issue #14), for
// the two-particle model (a documented reconstruction of the model note; docs/sintering_pair.md).
// Plain executable with its own timing loop (no Google Benchmark); prints a markdown table.
//
//   bench_sintering_pair [contacts=2400] [reps=1]
//
// Workload: N contacts, R_A and R_B uniform in 25 um +- 10 % (seed 1), Cu, 1293 K, to 5000 s.
//   * stepped: ~520 global steps (0.1 s growing by 1.2x per step up to the cap of 10 s), one
//     advance() per contact per step, and between steps each contact's h_A and h_B are perturbed
//     by a pre-drawn random amount (uniform +-1e-5 R per step, independent of the integrator), as
//     the mechanics step will move the centres; every perturbation forces a restart of that contact
//     only (its step memory is kept);
//   * uninterrupted: the same contacts from 0 to 5000 s in one advance() each.
// Error per contact = max(|dx|/x, |dshrinkage|/shrinkage) at 5000 s against DP45 at rtol 1e-12 on
// the same perturbation sequence; the table gives the median and maximum over contacts. Each
// integrator is run at several tolerances so that equal error can be read off the table.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "netdem/contact/sintering_pair.hpp"
#include "netdem/contact/sintering_pair_sundials.hpp"

namespace sp = netdem::contact::sinter;

namespace {

struct Workload {
  std::vector<double> RA, RB;
  std::vector<double> steps;  // global step ends
  std::vector<float> pert;    // [step][contact][2] relative perturbations (units of R_A, R_B)
};

Workload make_workload(int n) {
  Workload w;
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> rad(0.9 * 25e-6, 1.1 * 25e-6), u(-1.0, 1.0);
  for (int i = 0; i < n; ++i) {
    w.RA.push_back(rad(rng));
    w.RB.push_back(rad(rng));
  }
  double t = 0.0, dt = 0.1;
  while (t < 5000.0) {
    t = std::min(5000.0, t + dt);
    w.steps.push_back(t);
    dt = std::min(10.0, dt * 1.2);
  }
  w.pert.resize(w.steps.size() * n * 2);
  for (auto& p : w.pert) p = static_cast<float>(1e-5 * u(rng));
  return w;
}

struct Result {
  double seconds = 0.0;
  std::vector<double> x, s;  // final x/R and shrinkage per contact
  long steps = 0, evals = 0, failures = 0;
};

Result run(const Workload& w, const sp::IntegratorOptions& o, bool stepped) {
  static const auto cu = sp::builtin_sinter_material("cu");
  static const auto T = sp::TemperatureProfile::constant(1293.0);
  const sp::PairProblem p{&cu, &T, {}, 0.0};
  const std::size_t n = w.RA.size();
  std::vector<sp::PairContact> cs;
  cs.reserve(n);
  for (std::size_t i = 0; i < n; ++i) cs.push_back(sp::make_contact(w.RA[i], w.RB[i], 0.01));
  sp::PairIntegrator integ(o);
  Result r;
  const auto t0 = std::chrono::steady_clock::now();
  if (stepped) {
    for (std::size_t k = 0; k < w.steps.size(); ++k) {
      const float* pk = &w.pert[k * n * 2];
      for (std::size_t i = 0; i < n; ++i) {
        auto& c = cs[i];
        if (integ.advance(c, p, w.steps[k]) != sp::PairStatus::Ok) continue;
        if (k + 1 < w.steps.size()) {  // the mechanics moves the centres
          c.q[sp::kHA] += pk[2 * i] * c.q0[sp::kRA];
          c.q[sp::kHB] += pk[2 * i + 1] * c.q0[sp::kRB];
        }
      }
    }
  } else {
    for (auto& c : cs) integ.advance(c, p, 5000.0);
  }
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  for (const auto& c : cs) {
    r.x.push_back(c.x_over_R());
    r.s.push_back(sp::shrinkage(c.q, c.q0));
    r.steps += c.steps;
    r.evals += c.rhs_evals;
    r.failures += c.status != sp::PairStatus::Ok;
  }
  return r;
}

void row(const char* name, const std::string& tol, const Result& r, const Result& ref, std::size_t n) {
  std::vector<double> e(n);
  for (std::size_t i = 0; i < n; ++i)
    e[i] = std::max(std::fabs(r.x[i] / ref.x[i] - 1.0), std::fabs(r.s[i] / ref.s[i] - 1.0));
  std::sort(e.begin(), e.end());
  std::printf("| %-6s | %-10s | %8.3f | %9.2e | %9.2e | %8.1f | %9.1f | %ld |\n", name, tol.c_str(), r.seconds, e[n / 2],
              e[n - 1], static_cast<double>(r.steps) / n, static_cast<double>(r.evals) / n, r.failures);
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  const int n = argc > 1 ? std::atoi(argv[1]) : 2400;
  const Workload w = make_workload(n);
  std::printf("bench_sintering_pair: %d contacts, R = 25 um +- 10 %%, Cu, 1293 K, 5000 s, %zu global steps (last %g s)\n\n", n,
              w.steps.size(), w.steps.back() - w.steps[w.steps.size() - 2]);
  for (bool stepped : {true, false}) {
    sp::IntegratorOptions ro;
    ro.rtol = 1e-12;
    ro.atol_scale = 1e-2;
    const Result ref = run(w, ro, stepped);
    std::printf("### %s (reference: dp45 rtol 1e-12, %.2f s)\n\n", stepped ? "stepped, perturbed between steps" : "uninterrupted",
                ref.seconds);
    std::printf("| integrator | tolerance | time [s] | median err | max err | steps/contact | RHS/contact | failed |\n");
    std::printf("|---|---|---|---|---|---|---|---|\n");
    // one row per (integrator, tolerance); rk4's "tolerance" is its step factor c
    auto sweep = [&](sp::IntegratorKind kind, std::initializer_list<double> values) {
      for (double v : values) {
        sp::IntegratorOptions o;
        o.kind = kind;
        char tol[32];
        if (kind == sp::IntegratorKind::RK4) {
          o.rk4_c = v;
          std::snprintf(tol, sizeof tol, "c %.2f", v);
        } else {
          o.rtol = v;
          std::snprintf(tol, sizeof tol, "rtol %.0e", v);
        }
        row(sp::to_string(kind), tol, run(w, o, stepped), ref, n);
      }
    };
    sweep(sp::IntegratorKind::DP45, {1e-5, 1e-6, 1e-7, 1e-8});
    sweep(sp::IntegratorKind::ARKODE, {1e-5, 1e-6, 1e-7, 1e-8});
    sweep(sp::IntegratorKind::RK4, {0.1, 0.05, 0.02, 0.01});
    sweep(sp::IntegratorKind::CVODE, {1e-6, 1e-7, 1e-8, 1e-9});
    std::printf("\n");
  }
  return 0;
}
