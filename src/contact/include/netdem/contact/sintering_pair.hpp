#pragma once
// Two-particle solid-state sintering model ("7DOF" state layout) for the staggered scheme of
// Ivannikov et al., Comput. Part. Mech. (DOI 10.1007/s40571-022-00486-6), Eqs 1-17.
//
// THIS IS A DOCUMENTED RECONSTRUCTION, NOT THE AUTHORS' MODEL. The Thomsen et al. papers, the
// paper's flux table (Table 1) and material tables are not public. What is implemented is the
// closed reconstruction of the model note (docs/sintering_pair.md; cited below as "note §n"),
// written afresh in C++ (the note's sintering_pair_proto.py was only used to compare numbers).
// User documentation: docs/sintering_pair.md.
//
// Geometry (note §2): two spherical caps of radius R_k whose centres are h_k from the grain-boundary
// (GB) plane, joined by two frusta ("cones") tangent to the caps, meeting the GB disc of radius x.
// The cone lengths u_A, u_B are slaved by tangency, so the dynamic state is the 5-vector
//     q = (x, R_A, h_A, R_B, h_B)    [m]
// and the outline's y1..y7 = (x, R_A, u_A, h_A, R_B, u_B, h_B) is reported by full_state().
//
// Conventions and units: SI throughout (m, s, K, J, N). The normal force F on the contact is
// COMPRESSIVE POSITIVE (F > 0 pushes the centres together; 0 for free sintering). The approach rate
// s_dot = -(dh_A/dt + dh_B/dt) > 0 when the centres approach. Shrinkage Delta L / L0 =
// 1 - (h_A + h_B)/(h_A0 + h_B0) > 0 on approach (Eq 13 divided by Eq 11). x_over_R means
// x / min(R_A0, R_B0) (initial radii). Chemical potentials mu are per atom [J].
//
// Library split: this header and sintering_pair.cpp (model, materials, temperature profiles, the
// written-out Dormand-Prince 5(4) and RK4 integrators) are part of netdem_contact, which stays
// free of SUNDIALS. The SUNDIALS backends (CVODE BDF cross-check, ARKODE ERKStep) live in the
// separate target netdem_contact_sundials (sintering_pair_sundials.hpp).
#include <algorithm>
#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace netdem::contact::sinter {

inline constexpr double kBoltzmann = 1.380649e-23;  ///< k_B [J/K]
inline constexpr double kGasConstant = 8.314462618;  ///< R [J/(mol K)] (Eq 5)

/// Index of the components of the dynamic state q (note §2 "state vector").
enum StateIndex : int { kX = 0, kRA = 1, kHA = 2, kRB = 3, kHB = 4 };
using State = std::array<double, 5>;       ///< q = (x, R_A, h_A, R_B, h_B) [m]
using FullState = std::array<double, 7>;   ///< y1..y7 = (x, R_A, u_A, h_A, R_B, u_B, h_B) [m]

// ------------------------------------------------------------------------------------------------
// Material (note §5)

/// Material parameter set. Arrhenius form D = D0 exp(-Q / (R T)) (Eq 5) for each mechanism; the
/// interface mechanisms carry the width products delta*D [m^3/s].
struct SinterMaterial {
  std::string name;
  double omega = 0.0;       ///< atomic volume Omega [m^3]
  double gamma_s = 0.0;     ///< surface energy [J/m^2]
  double gamma_gb = 0.0;    ///< grain-boundary energy [J/m^2]
  double D_vol0 = 0.0;      ///< lattice diffusion prefactor [m^2/s]
  double Q_vol = 0.0;       ///< lattice activation energy [J/mol]
  double deltaD_gb0 = 0.0;  ///< delta_gb * D_gb0 [m^3/s]
  double Q_gb = 0.0;        ///< GB activation energy [J/mol]
  double deltaD_s0 = 0.0;   ///< delta_s * D_s0 [m^3/s]
  double Q_s = 0.0;         ///< surface activation energy [J/mol]
  double c_III = 1.0;       ///< geometric factor of path III (note §3), calibratable
  double c_IV = 1.0;        ///< geometric factor of path IV (note §3), calibratable
  double youngs_modulus = 0.0;  ///< E [Pa] for the equivalent bar (Eqs 10, 17); 0 = not given
  double poisson_ratio = -1.0;  ///< nu of the bond element (Eq 35, G = E / (2 (1 + nu))); -1 = not given
  /// A second, low-temperature phase (alpha-Ti below the beta transus, say): below T_transus [K]
  /// the *_low Arrhenius parameters replace the ones above (Omega and the energies stay). 0 = one
  /// phase. The switch is a jump of the rates at T_transus; the integrators' error control sees it.
  double T_transus = 0.0;
  double D_vol0_low = 0.0, Q_vol_low = 0.0, deltaD_gb0_low = 0.0, Q_gb_low = 0.0, deltaD_s0_low = 0.0, Q_s_low = 0.0;
  /// Throws std::invalid_argument (one line) unless every value is finite and in range.
  void validate() const;
};

/// Parses the material file format of docs/sintering_pair.md: `key = value` lines, `#` comments,
/// SI units; later assignments override earlier ones. `origin` names the source in messages.
/// Keys: name, Omega, gamma_s, gamma_gb, D_vol0, Q_vol, Q_gb, Q_s, c_III, c_IV, E, nu, T_transus (with
/// the low phase's D_vol0_low, Q_vol_low, Q_gb_low, Q_s_low and its interfaces), and for each
/// interface either deltaD_gb0 / deltaD_s0 directly, or D_gb0 / D_s0 with a width delta_gb /
/// delta_s (or `delta` for both). Throws std::invalid_argument (one line) on any error.
SinterMaterial parse_sinter_material(const std::string& text, const std::string& origin);
/// Reads a material file (see parse_sinter_material).
SinterMaterial read_sinter_material(const std::filesystem::path& file);
/// The text of a shipped material file ("cu" or "ti"; src/contact/materials/*.txt, embedded at
/// build time). Throws std::invalid_argument for another name.
std::string builtin_sinter_material_text(const std::string& name);
/// builtin_sinter_material_text + parse. The shipped sets are NOT the paper's tables (note §5).
SinterMaterial builtin_sinter_material(const std::string& name);

/// Diffusivities at one temperature (Eq 5), of the low phase below m.T_transus.
struct Diffusivities {
  double T = 0.0;       ///< [K]
  double kT = 0.0;      ///< k_B T [J]
  double deltaD_gb = 0.0;  ///< [m^3/s]
  double deltaD_s = 0.0;   ///< [m^3/s]
  double D_vol = 0.0;      ///< [m^2/s]
};
Diffusivities diffusivities(const SinterMaterial& m, double T);

/// Multipliers of the five path types I..V (note §3 table); 1 = on, 0 = off.
struct PathSwitches {
  double I = 1.0, II = 1.0, III = 1.0, IV = 1.0, V = 1.0;
};

// ------------------------------------------------------------------------------------------------
// Geometry (note §2)

/// One particle (cap + tangent frustum), with derivatives with respect to (x, R, h).
struct ParticleGeometry {
  double V = 0.0, A = 0.0;      ///< volume [m^3] and free surface (cap + frustum) [m^2]
  double A_cap = 0.0;           ///< cap surface [m^2]
  double r_t = 0.0, u_t = 0.0;  ///< tangent point (radius, distance from the GB plane) [m]
  double l_t = 0.0;             ///< frustum slant length [m]
  double c = 0.0;               ///< cos of the polar angle of the tangent point
  std::array<double, 3> dV{};   ///< total dV/d(x, R, h) through the tangent point
  std::array<double, 3> dA{};   ///< total dA/d(x, R, h)
};

/// Geometry of one particle; returns false (geometry untouched) when the cone does not exist
/// (x^2 + h^2 <= R^2 or u_t <= 0; note §4.6).
bool particle_geometry(double x, double R, double h, ParticleGeometry& g);
/// Total volume V_A + V_B [m^3] (note §2); NaN outside the domain.
double pair_volume(const State& q);
/// Interfacial free energy E = gamma_s A_s + gamma_gb pi x^2 [J] (note §2; Eq 8); NaN outside.
double pair_energy(const State& q, const SinterMaterial& m);
/// y1..y7 of the outline from q (u_A, u_B from tangency); NaN entries outside the domain.
FullState full_state(const State& q);
/// Touching spheres h_k = R_k with a tangent-cone fillet of neck radius x0 = x0_over_R min(R_A, R_B)
/// (note §4.6). The fillet adds a small volume; tests measure volume relative to V(q0).
State initial_state(double R_A, double R_B, double x0_over_R = 0.01);
/// Delta L / L0 = 1 - (h_A + h_B) / (h_A0 + h_B0) (Eqs 11, 13).
inline double shrinkage(const State& q, const State& q0) {
  return 1.0 - (q[kHA] + q[kHB]) / (q0[kHA] + q0[kHB]);
}

// ------------------------------------------------------------------------------------------------
// Right-hand side (note §4)

/// Everything a right-hand-side evaluation knows (filled on request).
struct RhsDiagnostics {
  double mu_n = 0.0;                 ///< neck potential [J] (note §4.2)
  std::array<double, 2> mu_c{};      ///< cap potentials (A, B) [J]
  std::array<double, 2> mu_g{};      ///< GB potentials (A, B), including Omega F / (pi x^2) [J]
  /// Volume rates of the paths [m^3/s], source -> sink (note §4.3), order
  /// I_A, I_B, II_A, II_B, III_A, III_B, IV_A, IV_B, V_A, V_B.
  std::array<double, 10> J{};
  std::array<double, 5> V_dot{};     ///< compartment rates (n, c_A, g_A, c_B, g_B) [m^3/s]
  double E_dot = 0.0;                ///< dE/dt = grad E . dq/dt [J/s] (<= 0 for F = 0; note §4.5)
  double volume_rate = 0.0;          ///< grad V . dq/dt [m^3/s] (= 0 up to round-off)
};

/// dq/dt at state q for diffusivities d (temperature d.T) and compressive normal force F [N]
/// (note §4.1-4.4). Returns false (dq untouched) outside the cone's domain. No allocation.
bool pair_rhs(const State& q, const Diffusivities& d, double F, const SinterMaterial& m,
              const PathSwitches& paths, State& dq, RhsDiagnostics* diag = nullptr);

/// The contact law seen by the mechanics (note §4.7): s_dot = (F + F_s) / eta, s_dot affine in F.
struct EffectiveLaw {
  double eta = 0.0;         ///< effective neck viscosity [N s/m]
  double F_s = 0.0;         ///< effective sintering force [N] (pulls the centres together)
  double s_dot_free = 0.0;  ///< approach rate at F = 0 [m/s]
};
/// eta = F1 / (s_dot(F1) - s_dot(0)) and F_s = eta s_dot(0) from two right-hand-side evaluations
/// (note §4.7). Without a densifying path (I, III, V all off or zero) eta = +inf and F_s = 0.
/// Throws std::domain_error outside the domain.
EffectiveLaw effective_law(const State& q, const Diffusivities& d, const SinterMaterial& m,
                           const PathSwitches& paths = {});
/// Bouvard-McMeeking neck viscosity pi x^4 / (8 Delta_b), Delta_b = Omega deltaD_gb / (k_B T)
/// (note §4.7, §8.1).
double bouvard_mcmeeking_viscosity(double x, const Diffusivities& d, const SinterMaterial& m);
/// Equivalent-bar force F_n = E A Delta L / L0 = (pi/2) E R_m Delta L (Eqs 10-17), compressive
/// positive for Delta L = (h_A0 + h_B0) - (h_A + h_B) > 0. R_m = (R_A0 + R_B0)/2 (Eq 16), or the
/// current mean radius (Eq 15) when current_radii.
double equivalent_bar_force(double youngs_modulus, const State& q0, const State& q,
                            bool current_radii = false);

// ------------------------------------------------------------------------------------------------
// Validity (note §4.6)

enum class PairStatus : std::uint8_t {
  Ok = 0,
  NeckLimit,       ///< x / min(R_A0, R_B0) passed the useful range (default 0.6)
  ConeDegenerate,  ///< x^2 + h^2 <= R^2 or u_t <= 0: the cap-cone geometry no longer exists
  NeckVanished,    ///< x / min(R_A0, R_B0) < 1e-4: the neck closed (a tension beyond F_s pulls it apart)
  NonFinite,       ///< a non-finite state or rate
  StepFailure,     ///< the integrator could not make a step (step size underflow / step cap)
};
const char* to_string(PairStatus s);
/// True for the expected ends at a validity limit of the model (NeckLimit, ConeDegenerate,
/// NeckVanished: "incomplete", exit 0), false for Ok and for the failures (NonFinite, StepFailure:
/// "unstable", exit 3), whatever the integrator.
constexpr bool validity_limit(PairStatus s) {
  return s == PairStatus::NeckLimit || s == PairStatus::ConeDegenerate || s == PairStatus::NeckVanished;
}
/// A stalled integration ends every integrator: kStalledSteps steps in a row shorter than
/// kStalledStep times the time (doubling t would take 1e12 steps), or (DP45, RK4) kStalledSteps
/// steps cut because a stage left the cap-cone geometry, fewer than 10 clean steps apart. It ends
/// ConeDegenerate when stages left the geometry (a contact that slides onto the limit u_t -> 0 with
/// a diverging rate, e.g. radii 5e-5 and 1e-3 m at t = 6.86e-5 s: the validity limit is reached,
/// not stepped across), StepFailure otherwise.
inline constexpr double kStalledStep = 1e-12;
inline constexpr long kStalledSteps = 1000;
/// The neck x / min(R_A0, R_B0) below which check_state() calls it vanished (PairStatus::NeckVanished).
inline constexpr double kNeckVanished = 1e-4;
/// One-sentence reason for a status (for summary.json and messages).
std::string describe(PairStatus s, double x_over_R_max);

// ------------------------------------------------------------------------------------------------
// Temperature against time (Eq 5 with T(t); note §6)

/// Temperatures are in (0, kMaxTemperature) K everywhere: the command line (--temperature), the
/// profiles and the material files (T_transus).
inline constexpr double kMaxTemperature = 1e4;

/// Piecewise-linear T(t) through breakpoints (t_i, T_i); constant before the first and after the
/// last one. Two equal consecutive times make a jump (a step in T); T(t) is right-continuous there.
class TemperatureProfile {
 public:
  /// One linear piece [t0, t1) of the profile, T(t) = T0 + (t - t0)/(t1 - t0) (T1 - T0).
  struct Segment {
    double t0 = 0.0, t1 = 0.0, T0 = 0.0, T1 = 0.0;
    double operator()(double t) const {
      if (T1 == T0 || !(t1 - t0 < 1e300)) return T0;  // constant piece (exact, no rounding)
      const double w = std::clamp((t - t0) / (t1 - t0), 0.0, 1.0);
      return T0 + w * (T1 - T0);
    }
  };
  /// A constant temperature (no breakpoints).
  static TemperatureProfile constant(double T);
  /// Breakpoints (t_i, T_i): t non-decreasing, at most two equal in a row (a jump), 0 < T < 1e4 K;
  /// throws std::invalid_argument (one line).
  TemperatureProfile(std::vector<double> t, std::vector<double> T);
  /// Parses a `time,T` CSV (header line `time,T` required; SI: s and K; `#` comment lines).
  static TemperatureProfile parse_csv(const std::string& text, const std::string& origin);
  static TemperatureProfile read_csv(const std::filesystem::path& file);
  /// The linear piece that contains t (t0 <= t < t1; t1 = +inf after the last breakpoint). The
  /// integrators evaluate T through the piece of the current segment, so a step never sees the
  /// other side of a breakpoint.
  Segment segment_at(double t) const;
  double operator()(double t) const { return segment_at(t)(t); }
  const std::vector<double>& times() const { return t_; }
  const std::vector<double>& temperatures() const { return T_; }

 private:
  TemperatureProfile() = default;
  std::vector<double> t_, T_;
};

// ------------------------------------------------------------------------------------------------
// One contact and its integration (one integrator per contact; no pooling of error norms)

enum class IntegratorKind : std::uint8_t { DP45 = 0, RK4, CVODE, ARKODE };
const char* to_string(IntegratorKind k);
/// "dp45" | "rk4" | "cvode" | "arkode"; throws std::invalid_argument otherwise.
IntegratorKind parse_integrator(const std::string& s);

struct IntegratorOptions {
  IntegratorKind kind = IntegratorKind::DP45;
  /// Relative tolerance (DP45, CVODE, ARKODE): of x itself, and of the changes R_k - R_k0 and
  /// h_k - h_k0 (so that it bounds the relative error of the shrinkage, not of h ~ R).
  double rtol = 1e-6;
  /// Absolute tolerance of every component = atol_scale * rtol * min(R_A0, R_B0) [m].
  double atol_scale = 1e-3;
  double rk4_c = 0.02;       ///< RK4 step dt = c x / |dx/dt| (the paper's integrator; note §4.6), in [1e-4, 1]
  double x_over_R_max = 0.6; ///< useful range of the neck (note §4.6)
  long max_steps = 10'000'000;  ///< per advance() call
  void validate() const;
};

/// One contact: its state, the initial radii/centre distance, and the integrator's memory.
struct PairContact {
  State q{};             ///< current state [m]
  State q0{};            ///< initial state (defines L0, x_over_R, shrinkage)
  double t = 0.0;        ///< current time [s]
  double h = 0.0;        ///< last proposed step size [s] (per-contact step memory; 0 = unknown)
  PairStatus status = PairStatus::Ok;
  // statistics (cumulative)
  long steps = 0, rejected = 0, rhs_evals = 0, restarts = 0;
  double R_min0() const { return q0[kRA] < q0[kRB] ? q0[kRA] : q0[kRB]; }
  double x_over_R() const { return q[kX] / R_min0(); }
};
/// A fresh contact at t = 0 (initial_state).
PairContact make_contact(double R_A, double R_B, double x0_over_R = 0.01);

/// Everything an integration needs besides the contact.
struct PairProblem {
  const SinterMaterial* material = nullptr;
  const TemperatureProfile* temperature = nullptr;
  PathSwitches paths{};
  double F = 0.0;  ///< compressive normal force [N], constant over the advance
};

/// Advances one contact from c.t to t_end with DP45 or RK4 (opts.kind), stopping and restarting at
/// every breakpoint of the temperature profile; stops early, with c.status set, when the contact
/// leaves the validity limits. Returns c.status. No allocation. CVODE / ARKODE: see
/// sintering_pair_sundials.hpp (this function throws std::invalid_argument for them).
PairStatus advance(PairContact& c, const PairProblem& p, double t_end, const IntegratorOptions& opts);

/// Validity check of one state (note §4.6).
PairStatus check_state(const State& q, double R_min0, double x_over_R_max);

}  // namespace netdem::contact::sinter
