// Two-particle sintering model: a documented reconstruction (see sintering_pair.hpp and
// the model note, docs/sintering_pair.md, cited as "note §n").
#include "netdem/contact/sintering_pair.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <map>
#include <numbers>
#include <sstream>
#include <stdexcept>

namespace netdem::contact::sinter {

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// ---- forward-mode dual numbers with three tangent directions (x, R, h) -------------------------
// note §4.5: the derivatives of E and V must be exact; central differences leave the domain at
// small x. Three directions suffice because particle k depends on (x, R_k, h_k) only.
struct D3 {
  double v = 0.0;
  double d[3] = {0.0, 0.0, 0.0};
};
inline D3 var(double v, int i) {
  D3 r;
  r.v = v;
  r.d[i] = 1.0;
  return r;
}
inline D3 operator+(const D3& a, const D3& b) {
  return {a.v + b.v, {a.d[0] + b.d[0], a.d[1] + b.d[1], a.d[2] + b.d[2]}};
}
inline D3 operator-(const D3& a, const D3& b) {
  return {a.v - b.v, {a.d[0] - b.d[0], a.d[1] - b.d[1], a.d[2] - b.d[2]}};
}
inline D3 operator*(const D3& a, const D3& b) {
  return {a.v * b.v,
          {a.d[0] * b.v + a.v * b.d[0], a.d[1] * b.v + a.v * b.d[1], a.d[2] * b.v + a.v * b.d[2]}};
}
inline D3 operator*(double s, const D3& a) { return {s * a.v, {s * a.d[0], s * a.d[1], s * a.d[2]}}; }
inline D3 operator+(double s, const D3& a) { return {s + a.v, {a.d[0], a.d[1], a.d[2]}}; }
inline D3 operator/(const D3& a, const D3& b) {
  const double inv = 1.0 / b.v, q = a.v * inv;
  return {q, {(a.d[0] - q * b.d[0]) * inv, (a.d[1] - q * b.d[1]) * inv, (a.d[2] - q * b.d[2]) * inv}};
}
inline D3 sqrt_d(const D3& a) {
  const double s = std::sqrt(a.v), k = 0.5 / s;
  return {s, {k * a.d[0], k * a.d[1], k * a.d[2]}};
}

// cap resistance f(c) of path II (note §3): uniform deposition over a cap fed from its rim circle
double cap_factor(double c) {
  c = std::min(c, 1.0 - 1e-12);
  return (-(1.0 + c) - 2.0 * std::log((1.0 - c) / 2.0)) / ((1.0 + c) * (1.0 + c));
}

// K_II of one particle: surface diffusion over the cap, then along the cone (note §3)
double k_surface(const ParticleGeometry& g, double x, double deltaD_s, double kT) {
  if (deltaD_s == 0.0) return 0.0;
  const double cone = std::fabs(g.r_t - x) > 1e-12 * g.r_t ? g.l_t * std::log(g.r_t / x) / (g.r_t - x)
                                                           : g.l_t / x;  // frustum shell, r_t -> x limit
  return 2.0 * kPi * deltaD_s / kT / (cap_factor(g.c) + cone);
}

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return {};
  const auto e = s.find_last_not_of(" \t\r");
  return s.substr(b, e - b + 1);
}

/// At most 80 printable characters of a bad input, for messages (the readers' quoting rule:
/// netdem::packing::quote_input).
std::string quote80(const std::string& s) {
  std::string out;
  for (std::size_t i = 0; i < s.size() && i < 80; ++i) {
    const auto c = static_cast<unsigned char>(s[i]);
    out += c >= 0x20 && c < 0x7f ? static_cast<char>(c) : '?';
  }
  if (s.size() > 80) out += "...";
  return out;
}

std::string number(double v) {
  std::ostringstream o;
  o << v;
  return o.str();
}

bool to_double(const std::string& s, double& v) {
  if (s.empty()) return false;
  errno = 0;
  char* end = nullptr;
  v = std::strtod(s.c_str(), &end);
  return errno == 0 && end == s.c_str() + s.size() && std::isfinite(v);
}

}  // namespace

// ================================================================================================
// Material

void SinterMaterial::validate() const {
  auto need = [&](bool ok, const char* key, const char* rule, double v) {
    if (!ok) {
      std::ostringstream o;
      o << "material '" << name << "': " << key << " must be " << rule << ", got " << v;
      throw std::invalid_argument(o.str());
    }
  };
  auto pos = [](double v) { return std::isfinite(v) && v > 0.0; };
  auto nonneg = [](double v) { return std::isfinite(v) && v >= 0.0; };
  need(pos(omega), "Omega", "positive", omega);
  need(pos(gamma_s), "gamma_s", "positive", gamma_s);
  need(nonneg(gamma_gb) && gamma_gb < 2.0 * gamma_s, "gamma_gb", ">= 0 and < 2 gamma_s", gamma_gb);
  need(nonneg(D_vol0), "D_vol0", ">= 0", D_vol0);
  need(nonneg(Q_vol), "Q_vol", ">= 0", Q_vol);
  need(nonneg(deltaD_gb0), "deltaD_gb0", ">= 0", deltaD_gb0);
  need(nonneg(Q_gb), "Q_gb", ">= 0", Q_gb);
  need(nonneg(deltaD_s0), "deltaD_s0", ">= 0", deltaD_s0);
  need(nonneg(Q_s), "Q_s", ">= 0", Q_s);
  need(nonneg(c_III), "c_III", ">= 0", c_III);
  need(nonneg(c_IV), "c_IV", ">= 0", c_IV);
  need(nonneg(youngs_modulus), "E", ">= 0", youngs_modulus);
  need(poisson_ratio == -1.0 || (std::isfinite(poisson_ratio) && poisson_ratio >= 0.0 && poisson_ratio < 0.5), "nu",
       "in [0, 0.5) (or absent)", poisson_ratio);
  need(D_vol0 > 0.0 || deltaD_gb0 > 0.0 || deltaD_s0 > 0.0, "one of D_vol0, deltaD_gb0, deltaD_s0",
       "positive", 0.0);
  need(nonneg(T_transus) && T_transus < kMaxTemperature, "T_transus", "in [0, 1e4) K", T_transus);
  if (T_transus > 0.0) {
    for (const auto& [v, k] : {std::pair{D_vol0_low, "D_vol0_low"}, {Q_vol_low, "Q_vol_low"},
                               {deltaD_gb0_low, "deltaD_gb0_low"}, {Q_gb_low, "Q_gb_low"},
                               {deltaD_s0_low, "deltaD_s0_low"}, {Q_s_low, "Q_s_low"}})
      need(nonneg(v), k, ">= 0", v);
    need(D_vol0_low > 0.0 || deltaD_gb0_low > 0.0 || deltaD_s0_low > 0.0,
         "one of D_vol0_low, deltaD_gb0_low, deltaD_s0_low (T_transus is set)", "positive", 0.0);
  }
}

SinterMaterial parse_sinter_material(const std::string& text, const std::string& origin) {
  std::map<std::string, double> v;
  std::string name;
  std::istringstream in(text);
  std::string line;
  int lineno = 0;
  static const char* const known[] = {"Omega",  "gamma_s",    "gamma_gb", "D_vol0",    "Q_vol",
                                      "Q_gb",   "Q_s",        "c_III",    "c_IV",      "E",        "nu",
                                      "T_transus", "D_vol0_low", "Q_vol_low", "Q_gb_low", "Q_s_low",
                                      "D_gb0_low", "deltaD_gb0_low", "D_s0_low", "deltaD_s0_low",
                                      "D_gb0",  "deltaD_gb0", "delta_gb", "D_s0",      "deltaD_s0",
                                      "delta_s", "delta"};
  while (std::getline(in, line)) {
    ++lineno;
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    line = trim(line);
    if (line.empty()) continue;
    const auto eq = line.find('=');
    auto fail = [&](const std::string& what) {
      throw std::invalid_argument(origin + ":" + std::to_string(lineno) + ": " + what);
    };
    if (eq == std::string::npos) fail("expected 'key = value', got '" + quote80(line) + "'");
    const std::string key = trim(line.substr(0, eq)), val = trim(line.substr(eq + 1));
    if (key == "name") {
      if (val.empty()) fail("empty name");
      name = quote80(val);
      continue;
    }
    if (std::find(std::begin(known), std::end(known), key) == std::end(known)) fail("unknown key '" + quote80(key) + "'");
    double x = 0.0;
    if (!to_double(val, x)) fail("'" + key + "' = '" + quote80(val) + "' is not a finite number");
    // the ranges of the command line (--nu, --temperature), with the line that breaks them
    if (key == "nu" && !(x >= 0.0 && x < 0.5)) fail("Poisson's ratio nu = " + number(x) + " is outside [0, 0.5)");
    if (key == "T_transus" && !(x >= 0.0 && x < kMaxTemperature))
      fail("T_transus = " + number(x) + " K is outside [0, 1e4) K");
    v[key] = x;
  }
  auto get = [&](const char* k, double def) {
    const auto it = v.find(k);
    return it == v.end() ? def : it->second;
  };
  auto req = [&](const char* k) {
    const auto it = v.find(k);
    if (it == v.end()) throw std::invalid_argument(origin + ": missing key '" + k + "'");
    return it->second;
  };
  SinterMaterial m;
  m.name = name.empty() ? origin : name;
  m.omega = req("Omega");
  m.gamma_s = req("gamma_s");
  m.gamma_gb = req("gamma_gb");
  m.D_vol0 = get("D_vol0", 0.0);
  m.Q_vol = get("Q_vol", 0.0);
  m.Q_gb = get("Q_gb", 0.0);
  m.Q_s = get("Q_s", 0.0);
  m.c_III = get("c_III", 1.0);
  m.c_IV = get("c_IV", 1.0);
  m.youngs_modulus = get("E", 0.0);
  m.poisson_ratio = get("nu", -1.0);
  // an interface: deltaD0 given directly, or D0 times a width (delta_x, or the common delta)
  auto interface = [&](const char* dd, const char* d0, const char* width) {
    const bool has_dd = v.count(dd) != 0, has_d0 = v.count(d0) != 0;
    if (has_dd && has_d0)
      throw std::invalid_argument(origin + ": give either '" + dd + "' or '" + d0 + "' (with a width), not both");
    if (has_dd) return v[dd];
    if (!has_d0) return 0.0;
    const double w = v.count(width) ? v[width] : v.count("delta") ? v["delta"] : kNaN;
    if (!std::isfinite(w))
      throw std::invalid_argument(origin + ": '" + d0 + "' needs a width '" + width + "' or 'delta'");
    if (!(w > 0.0)) throw std::invalid_argument(origin + ": width '" + width + "' must be positive");
    return w * v[d0];
  };
  m.deltaD_gb0 = interface("deltaD_gb0", "D_gb0", "delta_gb");
  m.deltaD_s0 = interface("deltaD_s0", "D_s0", "delta_s");
  m.T_transus = get("T_transus", 0.0);
  m.D_vol0_low = get("D_vol0_low", 0.0);
  m.Q_vol_low = get("Q_vol_low", 0.0);
  m.Q_gb_low = get("Q_gb_low", 0.0);
  m.Q_s_low = get("Q_s_low", 0.0);
  m.deltaD_gb0_low = interface("deltaD_gb0_low", "D_gb0_low", "delta_gb");
  m.deltaD_s0_low = interface("deltaD_s0_low", "D_s0_low", "delta_s");
  if (m.T_transus == 0.0)
    for (const char* k : {"D_vol0_low", "Q_vol_low", "Q_gb_low", "Q_s_low", "D_gb0_low", "deltaD_gb0_low", "D_s0_low",
                          "deltaD_s0_low"})
      if (v.count(k)) throw std::invalid_argument(origin + ": '" + k + "' needs T_transus");
  m.validate();
  return m;
}

SinterMaterial read_sinter_material(const std::filesystem::path& file) {
  std::ifstream f(file);
  if (!f) throw std::invalid_argument("cannot read material file '" + file.string() + "'");
  std::ostringstream s;
  s << f.rdbuf();
  return parse_sinter_material(s.str(), file.string());
}

SinterMaterial builtin_sinter_material(const std::string& name) {
  return parse_sinter_material(builtin_sinter_material_text(name), name);
}

Diffusivities diffusivities(const SinterMaterial& m, double T) {
  Diffusivities d;
  d.T = T;
  d.kT = kBoltzmann * T;
  const double rt = kGasConstant * T;  // Eq 5: D = D0 exp(-Q / (R T))
  if (m.T_transus > 0.0 && T < m.T_transus) {  // the low-temperature phase
    d.deltaD_gb = m.deltaD_gb0_low > 0.0 ? m.deltaD_gb0_low * std::exp(-m.Q_gb_low / rt) : 0.0;
    d.deltaD_s = m.deltaD_s0_low > 0.0 ? m.deltaD_s0_low * std::exp(-m.Q_s_low / rt) : 0.0;
    d.D_vol = m.D_vol0_low > 0.0 ? m.D_vol0_low * std::exp(-m.Q_vol_low / rt) : 0.0;
    return d;
  }
  d.deltaD_gb = m.deltaD_gb0 > 0.0 ? m.deltaD_gb0 * std::exp(-m.Q_gb / rt) : 0.0;
  d.deltaD_s = m.deltaD_s0 > 0.0 ? m.deltaD_s0 * std::exp(-m.Q_s / rt) : 0.0;
  d.D_vol = m.D_vol0 > 0.0 ? m.D_vol0 * std::exp(-m.Q_vol / rt) : 0.0;
  return d;
}

// ================================================================================================
// Geometry (note §2)

bool particle_geometry(double x, double R, double h, ParticleGeometry& g) {
  const D3 X = var(x, 0), Rr = var(R, 1), H = var(h, 2);
  const D3 D2 = X * X + H * H;  // D^2 = x^2 + h^2
  const D3 l2 = D2 - Rr * Rr;
  if (!(l2.v > 0.0)) return false;  // rim inside the ball: no tangent cone (note §4.6)
  const D3 lt = sqrt_d(l2);                              // l = sqrt(D^2 - R^2), frustum slant
  const D3 rt = Rr * (X * Rr + H * lt) / D2;             // r_t = R (x R + h l) / D^2
  const D3 ut = H + Rr * (X * lt - H * Rr) / D2;         // u_t = h + R (x l - h R) / D^2
  if (!(ut.v > 0.0)) return false;
  const D3 c = (H - ut) / Rr;                            // c = (h - u_t) / R
  const D3 Acap = (2.0 * kPi) * (Rr * Rr) * (1.0 + c);   // A_cap = 2 pi R^2 (1 + c)
  const D3 c3 = c * c * c;
  const D3 Vcap = (kPi / 3.0) * (Rr * Rr * Rr) * (2.0 + (3.0 * c - c3));  // pi R^3 (2 + 3c - c^3)/3
  const D3 Vfr = (kPi / 3.0) * ut * (X * X + X * rt + rt * rt);            // pi u_t (x^2 + x r_t + r_t^2)/3
  const D3 Afr = kPi * (X + rt) * lt;                                      // pi (x + r_t) l
  const D3 V = Vcap + Vfr, A = Acap + Afr;
  g.V = V.v;
  g.A = A.v;
  g.A_cap = Acap.v;
  g.r_t = rt.v;
  g.u_t = ut.v;
  g.l_t = lt.v;
  g.c = c.v;
  for (int i = 0; i < 3; ++i) {
    g.dV[i] = V.d[i];
    g.dA[i] = A.d[i];
  }
  return true;
}

double pair_volume(const State& q) {
  ParticleGeometry a, b;
  if (!particle_geometry(q[kX], q[kRA], q[kHA], a) || !particle_geometry(q[kX], q[kRB], q[kHB], b)) return kNaN;
  return a.V + b.V;
}

double pair_energy(const State& q, const SinterMaterial& m) {
  ParticleGeometry a, b;
  if (!particle_geometry(q[kX], q[kRA], q[kHA], a) || !particle_geometry(q[kX], q[kRB], q[kHB], b)) return kNaN;
  return m.gamma_s * (a.A + b.A) + m.gamma_gb * kPi * q[kX] * q[kX];  // Eq 8, note §2
}

FullState full_state(const State& q) {
  ParticleGeometry a, b;
  const bool oa = particle_geometry(q[kX], q[kRA], q[kHA], a), ob = particle_geometry(q[kX], q[kRB], q[kHB], b);
  return {q[kX], q[kRA], oa ? a.u_t : kNaN, q[kHA], q[kRB], ob ? b.u_t : kNaN, q[kHB]};
}

State initial_state(double R_A, double R_B, double x0_over_R) {
  return {x0_over_R * std::min(R_A, R_B), R_A, R_A, R_B, R_B};  // note §4.6: h_k = R_k
}

// ================================================================================================
// Right-hand side (note §4)

bool pair_rhs(const State& q, const Diffusivities& d, double F, const SinterMaterial& m,
              const PathSwitches& paths, State& dq, RhsDiagnostics* diag) {
  const double x = q[kX];
  if (!(x > 0.0)) return false;
  ParticleGeometry ga, gb;
  if (!particle_geometry(x, q[kRA], q[kHA], ga) || !particle_geometry(x, q[kRB], q[kHB], gb)) return false;
  const double Om = m.omega, kT = d.kT;
  const double Agb = kPi * x * x;
  // gradient of E = gamma_s A_s + gamma_gb pi x^2 along q (note §2)
  const double gE_x = m.gamma_s * (ga.dA[0] + gb.dA[0]) + 2.0 * kPi * m.gamma_gb * x;
  const double gE_RA = m.gamma_s * ga.dA[1], gE_hA = m.gamma_s * ga.dA[2];
  const double gE_RB = m.gamma_s * gb.dA[1], gE_hB = m.gamma_s * gb.dA[2];
  const double dVdx = ga.dV[0] + gb.dV[0];  // > 0 while u_t > 0 (note §4.1)
  // volume-map coefficients (note §4.1): neck share of R_k and h_k rates
  const double bRA = ga.dV[1] - ga.A_cap, bhA = ga.dV[2] - Agb;
  const double bRB = gb.dV[1] - gb.A_cap, bhB = gb.dV[2] - Agb;
  // chemical potentials mu = Omega B^-T grad E (note §4.2)
  const double mu_n = Om * gE_x / dVdx;
  const double mu_cA = (Om * gE_RA - mu_n * bRA) / ga.A_cap;
  const double mu_cB = (Om * gE_RB - mu_n * bRB) / gb.A_cap;
  const double mu_F = Om * F / Agb;  // external compressive force enters the GB potentials only
  const double mu_gA = (Om * gE_hA - mu_n * bhA) / Agb + mu_F;
  const double mu_gB = (Om * gE_hB - mu_n * bhB) / Agb + mu_F;
  // conductances K_p (note §3 table) [m^3 / (J s)]
  const double KI = paths.I * 4.0 * kPi * d.deltaD_gb / kT;  // half of 8 pi delta D / kT per side
  const double KIIA = paths.II * k_surface(ga, x, d.deltaD_s, kT);
  const double KIIB = paths.II * k_surface(gb, x, d.deltaD_s, kT);
  const double KIII = paths.III * m.c_III * kPi * x * d.D_vol / kT;
  const double KIV = paths.IV * m.c_IV * kPi * x * d.D_vol / kT;
  const double KVA = paths.V * Agb * d.D_vol / (kT * q[kHA]);
  const double KVB = paths.V * Agb * d.D_vol / (kT * q[kHB]);
  // lumped fluxes, source -> sink (note §4.3)
  const double JIA = KI * (mu_gA - mu_n), JIB = KI * (mu_gB - mu_n);
  const double JIIA = KIIA * (mu_cA - mu_n), JIIB = KIIB * (mu_cB - mu_n);
  const double JIIIA = KIII * (mu_gA - mu_n), JIIIB = KIII * (mu_gB - mu_n);
  const double JIVA = KIV * (mu_cA - mu_n), JIVB = KIV * (mu_cB - mu_n);
  const double JVA = KVA * (mu_gA - mu_cA), JVB = KVB * (mu_gB - mu_cB);
  // compartment balances (note §4.3)
  const double Vn = JIA + JIB + JIIA + JIIB + JIIIA + JIIIB + JIVA + JIVB;
  const double VcA = -JIIA - JIVA + JVA, VcB = -JIIB - JIVB + JVB;
  const double VgA = -JIA - JIIIA - JVA, VgB = -JIB - JIIIB - JVB;
  // rates: B^-1 in closed form (note §4.4)
  const double dhA = VgA / Agb, dhB = VgB / Agb;
  const double dRA = VcA / ga.A_cap, dRB = VcB / gb.A_cap;
  const double dx = (Vn - bRA * dRA - bhA * dhA - bRB * dRB - bhB * dhB) / dVdx;
  if (!(std::isfinite(dx) && std::isfinite(dhA) && std::isfinite(dhB) && std::isfinite(dRA) && std::isfinite(dRB)))
    return false;
  dq = {dx, dRA, dhA, dRB, dhB};
  if (diag != nullptr) {
    diag->mu_n = mu_n;
    diag->mu_c = {mu_cA, mu_cB};
    diag->mu_g = {mu_gA, mu_gB};
    diag->J = {JIA, JIB, JIIA, JIIB, JIIIA, JIIIB, JIVA, JIVB, JVA, JVB};
    diag->V_dot = {Vn, VcA, VgA, VcB, VgB};
    diag->E_dot = gE_x * dx + gE_RA * dRA + gE_hA * dhA + gE_RB * dRB + gE_hB * dhB;
    diag->volume_rate = dVdx * dx + ga.dV[1] * dRA + ga.dV[2] * dhA + gb.dV[1] * dRB + gb.dV[2] * dhB;
  }
  return true;
}

EffectiveLaw effective_law(const State& q, const Diffusivities& d, const SinterMaterial& m, const PathSwitches& paths) {
  // s_dot is exactly affine in F (note §4.7). F1 is chosen large against the sintering force so
  // that s_dot(F1) - s_dot(0) carries no cancellation.
  const double F1 = 1e3 * 2.0 * kPi * m.gamma_s * std::min(q[kRA], q[kRB]);
  State r0{}, r1{};
  if (!pair_rhs(q, d, 0.0, m, paths, r0) || !pair_rhs(q, d, F1, m, paths, r1))
    throw std::domain_error("effective_law: state outside the cap-cone domain");
  const double s0 = -(r0[kHA] + r0[kHB]), s1 = -(r1[kHA] + r1[kHB]);
  EffectiveLaw e;
  if (s1 == s0) {  // no densifying path (I, III, V) active: a rigid contact, no sintering force
    e.eta = std::numeric_limits<double>::infinity();
    e.F_s = 0.0;
    e.s_dot_free = s0;
    return e;
  }
  e.eta = F1 / (s1 - s0);   // eta_eff (note §4.7)
  e.F_s = e.eta * s0;       // F_s,eff = eta_eff s_dot(F = 0)
  e.s_dot_free = s0;
  return e;
}

double bouvard_mcmeeking_viscosity(double x, const Diffusivities& d, const SinterMaterial& m) {
  const double Delta_b = m.omega * d.deltaD_gb / d.kT;  // note §8.1: D_eff = Omega delta D / (k_B T)
  return kPi * x * x * x * x / (8.0 * Delta_b);
}

double equivalent_bar_force(double E, const State& q0, const State& q, bool current_radii) {
  const double dL = (q0[kHA] + q0[kHB]) - (q[kHA] + q[kHB]);                            // Eq 13
  const double Rm = current_radii ? 0.5 * (q[kRA] + q[kRB]) : 0.5 * (q0[kRA] + q0[kRB]);  // Eq 15 / 16
  return 0.5 * kPi * E * Rm * dL;  // Eq 17 = Eq 10 with A = pi R_m^2 (Eq 14), L0 = 2 R_m (Eq 11)
}

// ================================================================================================
// Validity

PairStatus check_state(const State& q, double R_min0, double x_over_R_max) {
  for (double v : q)
    if (!std::isfinite(v)) return PairStatus::NonFinite;
  ParticleGeometry g;
  if (!particle_geometry(q[kX], q[kRA], q[kHA], g) || !particle_geometry(q[kX], q[kRB], q[kHB], g))
    return PairStatus::ConeDegenerate;
  if (q[kX] / R_min0 > x_over_R_max) return PairStatus::NeckLimit;
  if (q[kX] / R_min0 < kNeckVanished) return PairStatus::NeckVanished;
  return PairStatus::Ok;
}

const char* to_string(PairStatus s) {
  switch (s) {
    case PairStatus::Ok: return "ok";
    case PairStatus::NeckLimit: return "neck_limit";
    case PairStatus::ConeDegenerate: return "cone_degenerate";
    case PairStatus::NeckVanished: return "neck_vanished";
    case PairStatus::NonFinite: return "non_finite";
    case PairStatus::StepFailure: return "step_failure";
  }
  return "unknown";
}

std::string describe(PairStatus s, double xmax) {
  std::ostringstream o;
  switch (s) {
    case PairStatus::Ok: return "within the validity limits (note section 4.6)";
    case PairStatus::NeckLimit:
      o << "the neck passed x/R_min = " << xmax
        << ", the end of the model's useful range (note section 4.6); the geometry degenerates beyond";
      return o.str();
    case PairStatus::ConeDegenerate:
      return "the cap-cone geometry no longer exists (x^2 + h^2 <= R^2 or u_t <= 0; note section 4.6)";
    case PairStatus::NeckVanished:
      return "the neck shrank below x/R_min = 1e-4: a tensile force beyond the sintering force pulls the particles apart";
    case PairStatus::NonFinite: return "a state or rate became non-finite";
    case PairStatus::StepFailure: return "the integrator could not make a step (step size underflow or step cap)";
  }
  return "unknown";
}

// ================================================================================================
// Temperature profile

TemperatureProfile TemperatureProfile::constant(double T) {
  if (!(std::isfinite(T) && T > 0.0 && T < kMaxTemperature)) {
    std::ostringstream o;
    o << "temperature must be in (0, 1e4) K, got " << T;
    throw std::invalid_argument(o.str());
  }
  TemperatureProfile p;
  p.t_ = {0.0};
  p.T_ = {T};
  return p;
}

TemperatureProfile::TemperatureProfile(std::vector<double> t, std::vector<double> T) : t_(std::move(t)), T_(std::move(T)) {
  if (t_.empty() || t_.size() != T_.size()) throw std::invalid_argument("temperature profile: no breakpoints");
  for (std::size_t i = 0; i < t_.size(); ++i) {
    if (!std::isfinite(t_[i])) throw std::invalid_argument("temperature profile: non-finite time");
    if (!(std::isfinite(T_[i]) && T_[i] > 0.0 && T_[i] < kMaxTemperature)) {
      std::ostringstream o;
      o << "temperature profile: T must be in (0, 1e4) K, got " << T_[i] << " at t = " << t_[i];
      throw std::invalid_argument(o.str());
    }
    if (i > 0 && t_[i] < t_[i - 1]) {
      std::ostringstream o;
      o << "temperature profile: times must not decrease, got " << t_[i - 1] << " then " << t_[i];
      throw std::invalid_argument(o.str());
    }
    if (i > 1 && t_[i] == t_[i - 1] && t_[i - 1] == t_[i - 2]) {
      std::ostringstream o;
      o << "temperature profile: more than two breakpoints at t = " << t_[i];
      throw std::invalid_argument(o.str());
    }
  }
}

TemperatureProfile::Segment TemperatureProfile::segment_at(double t) const {
  constexpr double inf = std::numeric_limits<double>::infinity();
  const std::size_t n = t_.size();
  if (t < t_[0]) return {-inf, t_[0], T_[0], T_[0]};
  // the last breakpoint i with t_i <= t (the right one of a jump)
  const std::size_t i = static_cast<std::size_t>(std::upper_bound(t_.begin(), t_.end(), t) - t_.begin()) - 1;
  if (i + 1 >= n) return {t_[n - 1], inf, T_[n - 1], T_[n - 1]};
  return {t_[i], t_[i + 1], T_[i], T_[i + 1]};
}

TemperatureProfile TemperatureProfile::parse_csv(const std::string& text, const std::string& origin) {
  std::istringstream in(text);
  std::string line;
  int lineno = 0;
  bool header = false;
  std::vector<double> t, T;
  while (std::getline(in, line)) {
    ++lineno;
    line = trim(line);
    if (line.empty() || line[0] == '#') continue;
    const auto comma = line.find(',');
    const std::string a = trim(line.substr(0, comma)), b = comma == std::string::npos ? "" : trim(line.substr(comma + 1));
    if (!header) {
      if (a != "time" || b != "T")
        throw std::invalid_argument(origin + ":" + std::to_string(lineno) + ": expected the header 'time,T', got '" + quote80(line) + "'");
      header = true;
      continue;
    }
    double tv = 0.0, Tv = 0.0;
    if (comma == std::string::npos || !to_double(a, tv) || !to_double(b, Tv))
      throw std::invalid_argument(origin + ":" + std::to_string(lineno) + ": expected 'time,T' numbers, got '" + quote80(line) + "'");
    if (!(Tv > 0.0 && Tv < kMaxTemperature))  // the range of --temperature
      throw std::invalid_argument(origin + ":" + std::to_string(lineno) + ": T = " + number(Tv) + " K is outside (0, 1e4) K");
    t.push_back(tv);
    T.push_back(Tv);
  }
  if (t.empty()) throw std::invalid_argument(origin + ": no 'time,T' rows");
  try {
    return TemperatureProfile(std::move(t), std::move(T));
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(origin + ": " + e.what());
  }
}

TemperatureProfile TemperatureProfile::read_csv(const std::filesystem::path& file) {
  std::ifstream f(file);
  if (!f) throw std::invalid_argument("cannot read temperature profile '" + file.string() + "'");
  std::ostringstream s;
  s << f.rdbuf();
  return parse_csv(s.str(), file.string());
}

// ================================================================================================
// Integration (one contact at a time)

const char* to_string(IntegratorKind k) {
  switch (k) {
    case IntegratorKind::DP45: return "dp45";
    case IntegratorKind::RK4: return "rk4";
    case IntegratorKind::CVODE: return "cvode";
    case IntegratorKind::ARKODE: return "arkode";
  }
  return "unknown";
}

IntegratorKind parse_integrator(const std::string& s) {
  if (s == "dp45") return IntegratorKind::DP45;
  if (s == "rk4") return IntegratorKind::RK4;
  if (s == "cvode") return IntegratorKind::CVODE;
  if (s == "arkode") return IntegratorKind::ARKODE;
  throw std::invalid_argument("integrator '" + s + "' is not dp45, rk4, cvode or arkode");
}

void IntegratorOptions::validate() const {
  auto bad = [](const std::string& what, double v) {
    std::ostringstream o;
    o << what << ", got " << v;
    throw std::invalid_argument(o.str());
  };
  if (!(std::isfinite(rtol) && rtol >= 1e-14 && rtol < 1.0)) bad("rtol must be in [1e-14, 1)", rtol);
  if (!(std::isfinite(atol_scale) && atol_scale > 0.0)) bad("atol_scale must be positive", atol_scale);
  // below 1e-4 (200 x finer than the default 0.02) a run only creeps to its step cap (issue 27)
  if (!(std::isfinite(rk4_c) && rk4_c >= 1e-4 && rk4_c <= 1.0)) bad("rk4 step factor c must be in [1e-4, 1]", rk4_c);
  if (!(std::isfinite(x_over_R_max) && x_over_R_max > 0.0)) bad("x_over_R_max must be positive", x_over_R_max);
  if (max_steps < 1) bad("max_steps must be >= 1", static_cast<double>(max_steps));
}

PairContact make_contact(double R_A, double R_B, double x0_over_R) {
  if (!(std::isfinite(R_A) && R_A > 0.0 && std::isfinite(R_B) && R_B > 0.0)) {
    std::ostringstream o;
    o << "radii must be positive [m], got " << R_A << ", " << R_B;
    throw std::invalid_argument(o.str());
  }
  if (!(std::isfinite(x0_over_R) && x0_over_R > 0.0 && x0_over_R < 0.5)) {
    std::ostringstream o;
    o << "initial neck x0/R must be in (0, 0.5), got " << x0_over_R;
    throw std::invalid_argument(o.str());
  }
  PairContact c;
  c.q = c.q0 = initial_state(R_A, R_B, x0_over_R);
  return c;
}

namespace {

// Dormand & Prince (1980) RK5(4)7M coefficients (the standard tableau).
constexpr double a21 = 1.0 / 5.0;
constexpr double a31 = 3.0 / 40.0, a32 = 9.0 / 40.0;
constexpr double a41 = 44.0 / 45.0, a42 = -56.0 / 15.0, a43 = 32.0 / 9.0;
constexpr double a51 = 19372.0 / 6561.0, a52 = -25360.0 / 2187.0, a53 = 64448.0 / 6561.0, a54 = -212.0 / 729.0;
constexpr double a61 = 9017.0 / 3168.0, a62 = -355.0 / 33.0, a63 = 46732.0 / 5247.0, a64 = 49.0 / 176.0,
                 a65 = -5103.0 / 18656.0;
constexpr double b1 = 35.0 / 384.0, b3 = 500.0 / 1113.0, b4 = 125.0 / 192.0, b5 = -2187.0 / 6784.0, b6 = 11.0 / 84.0;
// error coefficients e = b(5th) - b(4th)
constexpr double e1 = 71.0 / 57600.0, e3 = -71.0 / 16695.0, e4 = 71.0 / 1920.0, e5 = -17253.0 / 339200.0,
                 e6 = 22.0 / 525.0, e7 = -1.0 / 40.0;
constexpr double c2 = 1.0 / 5.0, c3 = 3.0 / 10.0, c4 = 4.0 / 5.0, c5 = 8.0 / 9.0;

// Arrhenius values at T, recomputed only when T changes (a constant segment costs no exp()).
struct DiffCache {
  const SinterMaterial* m;
  Diffusivities d;
  const Diffusivities& at(double T) {
    if (T != d.T) d = diffusivities(*m, T);
    return d;
  }
};

struct Rhs {
  const PairProblem& p;
  DiffCache cache;
  long* evals;
  TemperatureProfile::Segment seg;  // the piece of T(t) of the current segment
  bool left_geometry = false;       // an evaluation failed at a state outside the cap-cone geometry
  bool operator()(double t, const State& q, State& dq) {
    ++*evals;
    if (pair_rhs(q, cache.at(seg(t)), p.F, *p.material, p.paths, dq)) return true;
    left_geometry = left_geometry || check_state(q, 1.0, HUGE_VAL) == PairStatus::ConeDegenerate;
    return false;
  }
};

inline State axpy(const State& y, double h, std::initializer_list<std::pair<double, const State*>> terms) {
  State r = y;
  for (int i = 0; i < 5; ++i) {
    double s = 0.0;
    for (const auto& [w, k] : terms) s += w * (*k)[i];
    r[i] += h * s;
  }
  return r;
}

}  // namespace

PairStatus advance(PairContact& c, const PairProblem& p, double t_end, const IntegratorOptions& opts) {
  if (opts.kind != IntegratorKind::DP45 && opts.kind != IntegratorKind::RK4)
    throw std::invalid_argument("advance(): CVODE and ARKODE run through sintering_pair_sundials.hpp");
  if (p.material == nullptr || p.temperature == nullptr) throw std::invalid_argument("advance(): incomplete problem");
  if (c.status != PairStatus::Ok) return c.status;
  const double Rmin = c.R_min0();
  const double atol = opts.atol_scale * opts.rtol * Rmin;
  Rhs f{p, DiffCache{p.material, Diffusivities{}}, &c.rhs_evals, {}};
  f.cache.d.T = -1.0;
  long steps = 0;
  auto fail = [&](PairStatus s) {
    c.status = s;
    return s;
  };
  while (c.t < t_end) {
    // one segment: up to the next temperature breakpoint (restart there: no FSAL across it)
    f.seg = p.temperature->segment_at(c.t);
    const double seg_end = std::min(t_end, f.seg.t1);
    ++c.restarts;
    State k1{};
    if (!f(c.t, c.q, k1)) {
      const PairStatus s = check_state(c.q, Rmin, opts.x_over_R_max);
      return fail(s == PairStatus::Ok ? PairStatus::NonFinite : s);
    }
    if (opts.kind == IntegratorKind::RK4) {
      // the paper's RK4 (Ivannikov et al. section 2.2) with dt = c x / |dx/dt| (note §4.6); a step
      // whose stages leave the cap-cone geometry is cut by 4 until it stalls there (kStalledStep)
      double cut = 1.0;
      long geo_cuts = 0, clean = 0;  // steps cut at the geometry, clean steps since the last
      while (c.t < seg_end) {
        if (++steps > opts.max_steps) return fail(PairStatus::StepFailure);
        double dt = cut * opts.rk4_c * c.q[kX] / std::fabs(k1[kX]);
        if (!(dt > 0.0) || !std::isfinite(dt)) dt = seg_end - c.t;
        bool last = false;
        if (c.t + 1.000001 * dt >= seg_end) {  // land on the stop (no sliver of a step after it)
          dt = seg_end - c.t;
          last = true;
        }
        State k2{}, k3{}, k4{};
        const bool ok = f(c.t + 0.5 * dt, axpy(c.q, 0.5 * dt, {{1.0, &k1}}), k2) &&
                        f(c.t + 0.5 * dt, axpy(c.q, 0.5 * dt, {{1.0, &k2}}), k3) && f(c.t + dt, axpy(c.q, dt, {{1.0, &k3}}), k4);
        if (!ok) {
          if (!f.left_geometry) return fail(PairStatus::StepFailure);
          if (++geo_cuts >= kStalledSteps || dt < kStalledStep * c.t || cut < 1e-30) return fail(PairStatus::ConeDegenerate);
          f.left_geometry = false;
          clean = 0;
          cut *= 0.25;
          continue;
        }
        if (++clean >= 10) geo_cuts = 0;
        cut = std::min(1.0, 2.0 * cut);
        c.q = axpy(c.q, dt / 6.0, {{1.0, &k1}, {2.0, &k2}, {2.0, &k3}, {1.0, &k4}});
        c.t = last ? seg_end : c.t + dt;
        ++c.steps;
        const PairStatus s = check_state(c.q, Rmin, opts.x_over_R_max);
        if (s != PairStatus::Ok) return fail(s);
        if (c.t < seg_end && !f(c.t, c.q, k1)) return fail(PairStatus::NonFinite);
      }
      continue;
    }
    // Dormand-Prince 5(4), FSAL, per-contact step memory c.h
    double h = c.h;
    if (!(h > 0.0)) {
      // first step of a fresh contact: a small fraction of the neck's own time scale x / |dx/dt|
      h = 1e-3 * c.q[kX] / std::max(std::fabs(k1[kX]), 1e-300);
      h *= std::pow(opts.rtol / 1e-6, 0.2);
    }
    long stalled = 0;              // attempts in a row shorter than kStalledStep t
    long geo_cuts = 0, clean = 0;  // steps cut at the geometry (kStalledSteps: at its limit), clean steps since
    while (c.t < seg_end) {
      if (++steps > opts.max_steps) return fail(PairStatus::StepFailure);
      const double remaining = seg_end - c.t;
      double hs = h;
      bool last = false;
      if (hs >= remaining * (1.0 - 1e-12)) {
        hs = remaining;
        last = true;
      }
      stalled = hs < kStalledStep * c.t ? stalled + 1 : 0;
      if (geo_cuts >= kStalledSteps) return fail(PairStatus::ConeDegenerate);
      if (stalled >= kStalledSteps || !(hs > 0.0) || c.t + hs == c.t)  // a stall or a step size underflow
        return fail(geo_cuts > 0 ? PairStatus::ConeDegenerate : PairStatus::StepFailure);
      State k2{}, k3{}, k4{}, k5{}, k6{}, k7{};
      const double t = c.t;
      bool ok = f(t + c2 * hs, axpy(c.q, hs, {{a21, &k1}}), k2) &&
                f(t + c3 * hs, axpy(c.q, hs, {{a31, &k1}, {a32, &k2}}), k3) &&
                f(t + c4 * hs, axpy(c.q, hs, {{a41, &k1}, {a42, &k2}, {a43, &k3}}), k4) &&
                f(t + c5 * hs, axpy(c.q, hs, {{a51, &k1}, {a52, &k2}, {a53, &k3}, {a54, &k4}}), k5) &&
                f(t + hs, axpy(c.q, hs, {{a61, &k1}, {a62, &k2}, {a63, &k3}, {a64, &k4}, {a65, &k5}}), k6);
      State y5{};
      double err = 0.0;
      if (ok) {
        y5 = axpy(c.q, hs, {{b1, &k1}, {b3, &k3}, {b4, &k4}, {b5, &k5}, {b6, &k6}});
        ok = f(t + hs, y5, k7);
      }
      if (ok) {
        for (int i = 0; i < 5; ++i) {
          const double e = hs * (e1 * k1[i] + e3 * k3[i] + e4 * k4[i] + e5 * k5[i] + e6 * k6[i] + e7 * k7[i]);
          // weights: x relative to itself; R_k and h_k relative to their change since q0, so that
          // rtol bounds the error of the shrinkage and coarsening, not of R (~100x looser)
          const double ref = i == kX ? 0.0 : c.q0[i];
          const double w = atol + opts.rtol * std::max(std::fabs(c.q[i] - ref), std::fabs(y5[i] - ref));
          err = std::max(err, std::fabs(e) / w);
        }
        ok = std::isfinite(err);
      }
      if (!ok) {  // a stage left the domain: cut the step
        if (f.left_geometry) {
          ++geo_cuts;
          clean = 0;
          f.left_geometry = false;
        }
        h = 0.25 * hs;
        ++c.rejected;
        continue;
      }
      const double fac = std::clamp(0.9 * std::pow(std::max(err, 1e-10), -0.2), 0.2, 5.0);
      if (err <= 1.0) {
        c.q = y5;
        c.t = last ? seg_end : t + hs;
        k1 = k7;  // FSAL
        ++c.steps;
        if (++clean >= 10) geo_cuts = 0;
        // the step memory: the controller's proposal, not a step clipped to land on a stop
        h = hs < h ? std::max(h, hs * fac) : hs * fac;
        const PairStatus s = check_state(c.q, Rmin, opts.x_over_R_max);
        if (s != PairStatus::Ok) {
          c.h = h;
          return fail(s);
        }
      } else {
        h = hs * std::min(fac, 1.0);
        ++c.rejected;
      }
    }
    c.h = h;
  }
  return c.status;
}

}  // namespace netdem::contact::sinter
