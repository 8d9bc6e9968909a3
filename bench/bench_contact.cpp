// Throughput of the plastic-indentation contact law (src/contact, header-only hot path).
//
// A flat array of kStates pre-generated contact states (deterministic, seed 42) is swept once per
// benchmark iteration; items/s = contact evaluations per second. The mix is representative of a
// compaction increment with sticking friction (mu = inf -> mu_eff = 0.192):
//   30 % plastic loading + stick, 20 % plastic loading + gross slip,
//   20 % elastic unloading + stick, 10 % elastic unloading + slip, 20 % open (separated).
// Benchmarks:
//   BM_evaluate           contact-frame law netdem::contact::evaluate (scalars only)
//   BM_element_force      netdem::contact::pair_element (through the law interface) without
//                         tangent (6-vector force)
//   BM_element_tangent    element with the 6x6 material tangent (solver default)
//   BM_element_tangent_geometric  element with material + geometric tangent
//   BM_element_from_positions     pair_geometry() of the end configuration + element with tangent
//                                  (what the solver's assembly does per contact and Newton iteration)
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "netdem/contact/element.hpp"
#include "netdem/contact/kinematics.hpp"
#include "netdem/contact/plastic_indentation.hpp"

namespace nc = netdem::contact;

namespace {

constexpr std::size_t kStates = 100000;

struct LawState {
  nc::PlasticIndentationHistory h;
  double r_eff, u_n, dslip;
};

struct PairState {
  nc::PlasticIndentationHistory h;
  nc::PairGeometry g0, g1;
  nc::Vec xi1, xj1;  // end positions (for BM_element_from_positions)
  double ri, rj, dth_i, dth_j;
};

enum class Kind { LoadStick, LoadSlip, UnloadStick, UnloadSlip, Open };

Kind draw_kind(double u) {
  if (u < 0.30) return Kind::LoadStick;
  if (u < 0.50) return Kind::LoadSlip;
  if (u < 0.70) return Kind::UnloadStick;
  if (u < 0.80) return Kind::UnloadSlip;
  return Kind::Open;
}

const nc::PlasticIndentationParams& params() {
  static const nc::PlasticIndentationParams p{};  // sigma_y 1, mu inf, k_t 1e3, unload_ratio 1e3
  return p;
}

// End overlap and slip increment for a state of the given kind, from the committed history.
void draw_increment(Kind kind, double r_eff, const nc::PlasticIndentationHistory& h, std::mt19937_64& rng,
                    double& u_n, double& dslip) {
  std::uniform_real_distribution<double> U(0.0, 1.0);
  const auto& p = params();
  const double us = nc::separation_overlap(p, r_eff, h.u_max);  // = u_max (1 - 2/unload_ratio)
  const double band = h.u_max - us;
  switch (kind) {
    case Kind::LoadStick:
    case Kind::LoadSlip: u_n = h.u_max * (1.0 + 0.05 * U(rng)); break;
    case Kind::UnloadStick:
    case Kind::UnloadSlip: u_n = us + band * (0.5 + 0.5 * U(rng)); break;
    case Kind::Open: u_n = us - band * (0.1 + U(rng)); break;
  }
  double fn, kn;
  nc::NormalBranch b;
  nc::normal_force(p, r_eff, h.u_max, u_n, fn, kn, b);
  const double kt_force = p.k_t * fn / (3.0 * p.sigma_y);
  const double limit = p.mu_eff() * fn;
  const double sgn = U(rng) < 0.5 ? -1.0 : 1.0;
  const bool slip = kind == Kind::LoadSlip || kind == Kind::UnloadSlip;
  if (kt_force <= 0.0) {
    dslip = sgn * 1e-3 * U(rng);
  } else if (slip) {  // trial force 1.5-3x beyond the limit
    dslip = sgn * (std::fabs(h.f_t) + (1.5 + 1.5 * U(rng)) * limit) / kt_force;
  } else {  // trial force stays within +-limit (|f_t0| <= limit/2 below)
    dslip = sgn * 0.4 * U(rng) * limit / kt_force;
  }
}

nc::PlasticIndentationHistory draw_history(double r_eff, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> U(0.0, 1.0);
  nc::PlasticIndentationHistory h;
  h.u_max = 0.005 + 0.045 * U(rng);  // 0.5 .. 5 % of R
  const double limit = params().mu_eff() * nc::plastic_force(params(), r_eff, h.u_max);
  h.f_t = (U(rng) - 0.5) * limit;  // |f_t| <= limit / 2
  h.sliding = 0;
  return h;
}

const std::vector<LawState>& law_states() {
  static const std::vector<LawState> v = [] {
    std::mt19937_64 rng(42);
    std::uniform_real_distribution<double> U(0.0, 1.0);
    std::vector<LawState> s(kStates);
    for (auto& st : s) {
      const double ri = 0.9 + 0.2 * U(rng), rj = 0.9 + 0.2 * U(rng);
      st.r_eff = ri * rj / (ri + rj);
      st.h = draw_history(st.r_eff, rng);
      draw_increment(draw_kind(U(rng)), st.r_eff, st.h, rng, st.u_n, st.dslip);
    }
    return s;
  }();
  return v;
}

const std::vector<PairState>& pair_states() {
  static const std::vector<PairState> v = [] {
    std::mt19937_64 rng(43);
    std::uniform_real_distribution<double> U(0.0, 1.0);
    const double pi = std::acos(-1.0);
    std::vector<PairState> s(kStates);
    for (auto& st : s) {
      st.ri = 0.9 + 0.2 * U(rng);
      st.rj = 0.9 + 0.2 * U(rng);
      const double r_eff = st.ri * st.rj / (st.ri + st.rj);
      st.h = draw_history(r_eff, rng);
      double u1, dslip;
      draw_increment(draw_kind(U(rng)), r_eff, st.h, rng, u1, dslip);
      const double u0 = st.h.u_max * (1.0 - 0.02 * U(rng));  // start of the increment
      const double phi0 = 2.0 * pi * U(rng);
      const nc::Vec xi0(100.0 * U(rng), 100.0 * U(rng));
      const nc::Vec xj0 = xi0 + (st.ri + st.rj - u0) * nc::Vec(std::cos(phi0), std::sin(phi0));
      st.g0 = nc::pair_geometry(xi0, xj0, st.ri, st.rj);
      // rotations, then the normal rotation dphi that gives the wanted slip increment
      st.dth_i = 1e-3 * (U(rng) - 0.5);
      st.dth_j = 1e-3 * (U(rng) - 0.5);
      const double L1 = st.ri + st.rj - u1;
      const double Lm = 0.5 * (st.g0.L + L1);
      const double dphi = (dslip + 0.5 * Lm * (st.dth_i + st.dth_j)) / Lm;  // d_i ~ d_j ~ L/2
      const nc::Vec du(1e-3 * (U(rng) - 0.5), 1e-3 * (U(rng) - 0.5));
      st.xi1 = xi0 + du;
      st.xj1 = st.xi1 + L1 * nc::Vec(std::cos(phi0 + dphi), std::sin(phi0 + dphi));
      st.g1 = nc::pair_geometry(st.xi1, st.xj1, st.ri, st.rj);
    }
    return s;
  }();
  return v;
}

void BM_evaluate(benchmark::State& state) {
  const auto& s = law_states();
  const auto& p = params();
  long sliding = 0, open = 0;
  for (auto _ : state) {
    double acc = 0.0;
    for (const auto& st : s) {
      const auto r = nc::evaluate(p, st.h, st.r_eff, st.u_n, st.dslip);
      acc += r.f_n + r.f_t + r.dft_dslip + r.history.u_max;
      sliding += r.sliding;
      open += r.branch == nc::NormalBranch::Open;
    }
    benchmark::DoNotOptimize(acc);
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * static_cast<int64_t>(s.size()));
  const double n = static_cast<double>(state.iterations()) * static_cast<double>(s.size());
  state.counters["slip_frac"] = static_cast<double>(sliding) / n;
  state.counters["open_frac"] = static_cast<double>(open) / n;
}

template <int Mode>  // 0: force only, 1: material tangent, 2: material + geometric tangent
void BM_element(benchmark::State& state) {
  const auto& s = pair_states();
  const auto& p = params();
  nc::TangentOptions topt;
  topt.geometric = Mode == 2;
  const nc::PlasticIndentationLaw law(p);
  nc::PairElement<nc::PlasticIndentationLaw> e;
  long sliding = 0, open = 0;
  for (auto _ : state) {
    double acc = 0.0;
    for (const auto& st : s) {
      nc::pair_element(law, st.h, st.g0, st.g1, st.dth_i, st.dth_j, e, Mode == 0 ? nullptr : &topt);
      acc += e.force(0) + e.force(5);
      if constexpr (Mode != 0) acc += e.stiffness(0, 0) + e.stiffness(2, 5);
      sliding += e.law.sliding;
      open += !e.law.loaded;
    }
    benchmark::DoNotOptimize(acc);
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * static_cast<int64_t>(s.size()));
  const double n = static_cast<double>(state.iterations()) * static_cast<double>(s.size());
  state.counters["slip_frac"] = static_cast<double>(sliding) / n;
  state.counters["open_frac"] = static_cast<double>(open) / n;
}

void BM_element_from_positions(benchmark::State& state) {
  const auto& s = pair_states();
  const auto& p = params();
  nc::TangentOptions topt;
  const nc::PlasticIndentationLaw law(p);
  nc::PairElement<nc::PlasticIndentationLaw> e;
  for (auto _ : state) {
    double acc = 0.0;
    for (const auto& st : s) {
      const nc::PairGeometry g1 = nc::pair_geometry(st.xi1, st.xj1, st.ri, st.rj);
      nc::pair_element(law, st.h, st.g0, g1, st.dth_i, st.dth_j, e, &topt);
      acc += e.force(0) + e.stiffness(0, 0);
    }
    benchmark::DoNotOptimize(acc);
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * static_cast<int64_t>(s.size()));
}

}  // namespace

BENCHMARK(BM_evaluate)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_element<0>)->Name("BM_element_force")->Unit(benchmark::kMillisecond);
BENCHMARK(BM_element<1>)->Name("BM_element_tangent")->Unit(benchmark::kMillisecond);
BENCHMARK(BM_element<2>)->Name("BM_element_tangent_geometric")->Unit(benchmark::kMillisecond);
BENCHMARK(BM_element_from_positions)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
