// 3D ballistic deposition with steepest descent (issue 16). Rules in ballistic3d.hpp and
// docs/packing.md ("3D ballistic deposition").
#include "netdem/packing/ballistic3d.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "netdem/packing/cell_grid.hpp"
#include "deposition_checks.hpp"
#include "netdem/packing/random_fill.hpp"

namespace netdem::packing {

void Deposition3dOptions::validate() const {
  auto fail = [](const std::string& msg) { throw std::invalid_argument("3D deposition options: " + msg); };
  detail::check_deposition_sizes("3D deposition options", width, height, radius, r_min, r_max);
  if (lateral == Lateral::Periodic && width < 4 * r_max)
    fail(fmt::format("periodic width {} is smaller than two largest diameters 4 r_max = {}", width, 4 * r_max));
  if (width < 2 * r_max) fail(fmt::format("width {} is smaller than the largest diameter 2 r_max = {}", width, 2 * r_max));
  if (box_height() < 2 * r_max)
    fail(fmt::format("height {} is smaller than the largest diameter 2 r_max = {}", box_height(), 2 * r_max));
  if (max_rejections == 0) fail("max_rejections must be >= 1");
}

namespace {

constexpr double kTwoPi = 2 * std::numbers::pi;
// Tolerances (relative to the length compared with, or to unit normals); as in 2D where they exist.
constexpr double kContactTol = 1e-10;  // relative gap below which a sphere (wall, floor) is touching
constexpr double kGrazing = 1e-6;      // n_z <= this: carries no weight for a fall, a fall passes it
constexpr double kAdmissible = 1e-10;  // n . d >= -this: admissible; KKT multiplier >= -this: valid
constexpr double kStill = 1e-9;
constexpr double kTop = 1e-9;          // a two-support equilibrium this far above its circle's centre is unstable        // |projected gravity| below this: no motion (rest or on top)
constexpr double kSkip = 1e-9;         // an event closer than this angle to the start of a path of an
                                       // obstacle already touching is the contact itself, not a new touch
constexpr long kMaxSteps = 100000;     // per sphere; a guard against a logic error

struct V3 {
  double x = 0, y = 0, z = 0;
};
V3 operator+(V3 a, V3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
V3 operator-(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
V3 operator*(double s, V3 a) { return {s * a.x, s * a.y, s * a.z}; }
double dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
double norm(V3 a) { return std::sqrt(dot(a, a)); }
V3 unit(V3 a) { return (1.0 / norm(a)) * a; }
V3 cross(V3 a, V3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }

constexpr int kFloor = -1, kWallX0 = -2, kWallX1 = -3, kWallY0 = -4, kWallY1 = -5;

/// An obstacle for the centre of the moving sphere: a sphere |c - p| >= R (id >= 0, p the image
/// centre), or a plane n . c >= off (id < 0).
struct Obstacle {
  int id = 0;
  V3 p;
  double R = 0;
  V3 n;
  double off = 0;
  bool sphere() const { return id >= 0; }
  bool same(const Obstacle& o) const { return id == o.id && (!sphere() || (p.x == o.p.x && p.y == o.p.y)); }
  V3 normal_at(V3 c) const { return sphere() ? unit(c - p) : n; }
  /// Coefficients of f(t) = a0 + a1 cos t + a2 sin t along c(t) = C + rho (cos t u + sin t v):
  /// |c - p|^2 - R^2 for a sphere, n . c - off for a plane. f > 0 is free.
  std::array<double, 3> along(V3 C, double rho, V3 u, V3 v) const {
    if (sphere()) {
      const V3 q = C - p;
      return {dot(q, q) + rho * rho - R * R, 2 * rho * dot(u, q), 2 * rho * dot(v, q)};
    }
    return {dot(n, C) - off, rho * dot(n, u), rho * dot(n, v)};
  }
  /// n_z along the circle as k0 + k1 cos t + k2 sin t.
  std::array<double, 3> nz_along(V3 C, double rho, V3 u, V3 v) const {
    if (sphere()) return {(C.z - p.z) / R, rho * u.z / R, rho * v.z / R};
    return {n.z, 0.0, 0.0};
  }
};

/// Smallest t in [0, 2 pi) where a0 + a1 cos t + a2 sin t crosses zero downwards, or +inf.
double down_crossing(const std::array<double, 3>& a) {
  const double m = std::hypot(a[1], a[2]);
  if (!(m > 0)) return std::numeric_limits<double>::infinity();
  const double q = -a[0] / m;
  if (!(q > -1.0 && q < 1.0)) return std::numeric_limits<double>::infinity();
  double t = std::atan2(a[2], a[1]) + std::acos(q);
  t = std::fmod(t, kTwoPi);
  if (t < 0) t += kTwoPi;
  return t;
}

struct Contact {
  Obstacle ob;
  V3 n;  // unit normal from the obstacle towards the moving sphere
};

class Depositor3 {
 public:
  /// Box [0, w]^2 x [0, h] in local coordinates; `out` holds the fixed spheres (insert()).
  Depositor3(double w, double h, double rmax, bool periodic, Packing& out)
      : out_(out), w_(w), rmax_(rmax), periodic_(periodic) {
    n_xy_ = std::max(1L, static_cast<long>(std::floor(w / (2 * rmax))));
    c_xy_ = w / static_cast<double>(n_xy_);
    c_z_ = 2 * rmax;
    n_z_ = std::max(1L, static_cast<long>(std::ceil(h / c_z_)) + 1);
    GridLayout3 g;  // square columns that tile the periodic width, layers of 2 r_max
    g.cell = {c_xy_, c_xy_, c_z_};
    g.count = {n_xy_, n_xy_, n_z_};
    grid_ = GrowingCellGrid3(g);
  }

  void insert(V3 c, double r) {
    const auto id = static_cast<std::uint32_t>(out_.size());
    out_.x.push_back(c.x);
    out_.y.push_back(c.y);
    out_.z.push_back(c.z);
    out_.r.push_back(r);
    const long iz = layer(c.z);
    top_z_ = std::max(top_z_, c.z + r);
    grid_.insert(id, {c.x, c.y, c.z});
    top_layer_ = std::max(top_layer_, iz);
  }

  /// Settles a sphere of radius r dropped at (x0, y0); returns its centre (periodic: unwrapped).
  V3 settle(double r, double x0, double y0, Deposition3dReport& rep) {
    V3 c{x0, y0, top_z_ + 2 * (r + rmax_)};  // above every fixed sphere
    contacts_.clear();
    fall(c, r);
    for (long step = 0; step < kMaxSteps; ++step) {
      rep.max_steps = std::max(rep.max_steps, static_cast<std::size_t>(step + 1));
      gather(c, r);
      if (!move(c, r, rep)) return c;
    }
    throw std::runtime_error(fmt::format("ballistic_deposition_3d: sphere {} did not settle in {} steps (x0 = {}, y0 = {})",
                                         out_.size(), kMaxSteps, x0, y0));
  }

  V3 wrap(V3 c) const {
    if (!periodic_) return c;
    c.x -= w_ * std::floor(c.x / w_);
    c.y -= w_ * std::floor(c.y / w_);
    if (c.x >= w_) c.x = 0;  // rounding of a tiny negative coordinate
    if (c.y >= w_) c.y = 0;
    return c;
  }

 private:
  long layer(double z) const { return grid_.layout().coord(2, z); }

  /// Calls f(obstacle) for every fixed sphere image in the cells overlapping the box of half side
  /// `reach` (x, y) around q and z in [z_lo, z_hi].
  template <class F>
  void for_each_near(V3 q, double reach, long iz0, long iz1, F&& f) const {
    long x0 = static_cast<long>(std::floor((q.x - reach) / c_xy_)), x1 = static_cast<long>(std::floor((q.x + reach) / c_xy_));
    long y0 = static_cast<long>(std::floor((q.y - reach) / c_xy_)), y1 = static_cast<long>(std::floor((q.y + reach) / c_xy_));
    if (!periodic_) {
      x0 = std::max(x0, 0L), y0 = std::max(y0, 0L), x1 = std::min(x1, n_xy_ - 1), y1 = std::min(y1, n_xy_ - 1);
    }
    for (long iz = iz0; iz >= iz1; --iz)
      for (long by = y0; by <= y1; ++by)
        for (long bx = x0; bx <= x1; ++bx) {
          const long wx = ((bx % n_xy_) + n_xy_) % n_xy_, wy = ((by % n_xy_) + n_xy_) % n_xy_;
          const double sx = static_cast<double>((bx - wx) / n_xy_) * w_, sy = static_cast<double>((by - wy) / n_xy_) * w_;
          for (std::uint32_t k : grid_.cell(grid_.layout().index({wx, wy, iz}))) {
            Obstacle o;
            o.id = static_cast<int>(k);
            o.p = {out_.x[k] + sx, out_.y[k] + sy, out_.z[k]};
            o.R = out_.r[k];  // caller adds r
            f(o);
          }
        }
  }

  bool in_contact(const Obstacle& o) const {
    return std::any_of(contacts_.begin(), contacts_.end(), [&](const Contact& c) { return c.ob.same(o); });
  }

  /// Vertical fall from c to the first sphere (exact tangency) or the floor z = r.
  void fall(V3& c, double r) {
    double best = r;
    const double reach = r + rmax_;
    for (long iz = std::min(layer(c.z), top_layer_); iz >= 0; --iz) {
      if (best >= static_cast<double>(iz + 1) * c_z_ + reach) break;  // centres of layer iz are below (iz + 1) c_z
      for_each_near(c, reach, iz, iz, [&](Obstacle o) {
        o.R += r;
        const double dx = c.x - o.p.x, dy = c.y - o.p.y, h = std::sqrt(dx * dx + dy * dy);
        if (h >= o.R) return;
        const double rise = std::sqrt((o.R - h) * (o.R + h));
        if (rise <= kGrazing * o.R || in_contact(o)) return;
        const double zc = o.p.z + rise;
        if (zc > c.z + kContactTol * o.R) return;
        best = std::max(best, zc);
      });
    }
    c.z = best;
  }

  /// Obstacles that a path around C of radius rho can touch, and the planes.
  void candidates(V3 C, double rho, double r) {
    cand_.clear();
    const double reach = rho + r + rmax_;
    for_each_near(C, reach, layer(C.z + reach), layer(C.z - reach), [&](Obstacle o) {
      o.R += r;
      cand_.push_back(o);
    });
    for (const Obstacle& p : planes(r)) cand_.push_back(p);
  }

  std::vector<Obstacle> planes(double r) const {
    std::vector<Obstacle> v;
    Obstacle f;
    f.id = kFloor, f.n = {0, 0, 1}, f.off = r;
    v.push_back(f);
    if (!periodic_) {
      Obstacle a;
      a.id = kWallX0, a.n = {1, 0, 0}, a.off = r;
      v.push_back(a);
      a.id = kWallX1, a.n = {-1, 0, 0}, a.off = r - w_;
      v.push_back(a);
      a.id = kWallY0, a.n = {0, 1, 0}, a.off = r;
      v.push_back(a);
      a.id = kWallY1, a.n = {0, -1, 0}, a.off = r - w_;
      v.push_back(a);
    }
    return v;
  }

  void gather(V3 c, double r) {
    contacts_.clear();
    const double reach = (r + rmax_) * (1 + kContactTol);
    for_each_near(c, reach, layer(c.z + reach), layer(c.z - reach), [&](Obstacle o) {
      o.R += r;
      const V3 d = c - o.p;
      const double lim = o.R * (1 + kContactTol);
      if (dot(d, d) > lim * lim) return;
      contacts_.push_back({o, unit(d)});
    });
    for (const Obstacle& p : planes(r))
      if (dot(p.n, c) - p.off <= kContactTol * r) contacts_.push_back({p, p.n});
  }

  /// KKT solution of min |d - g| s.t. n_i . d >= 0 over the active sets of size 0..3 (in order).
  bool project(std::vector<int>& active, V3& d) const {
    const V3 g{0, 0, -1};
    const int m = static_cast<int>(contacts_.size());
    auto others_ok = [&](V3 dd, const std::vector<int>& s, bool fall) {
      for (int j = 0; j < m; ++j) {
        if (std::find(s.begin(), s.end(), j) != s.end()) continue;
        const Contact& cj = contacts_[static_cast<std::size_t>(j)];
        const double tol = fall && cj.ob.sphere() ? kGrazing : kAdmissible;
        if (dot(cj.n, dd) < -tol) return false;
      }
      return true;
    };
    active.clear();
    if (others_ok(g, active, true)) {
      d = g;
      return true;
    }
    // sets of size 1, 2, 3 (lexicographic): Gram system G mu = (n_z), d = g + sum mu n
    std::vector<int> s;
    for (int size = 1; size <= 3; ++size) {
      std::vector<int> idx(static_cast<std::size_t>(size));
      for (int k = 0; k < size; ++k) idx[static_cast<std::size_t>(k)] = k;
      while (true) {
        if (size <= m) {
          double G[3][3], b[3], mu[3];
          for (int a = 0; a < size; ++a) {
            const V3 na = contacts_[static_cast<std::size_t>(idx[static_cast<std::size_t>(a)])].n;
            b[a] = na.z;
            for (int c = 0; c < size; ++c) G[a][c] = dot(na, contacts_[static_cast<std::size_t>(idx[static_cast<std::size_t>(c)])].n);
          }
          if (solve(size, G, b, mu)) {
            bool ok = true;
            for (int a = 0; a < size; ++a) ok = ok && mu[a] >= -kAdmissible;
            if (ok) {
              V3 dd = g;
              for (int a = 0; a < size; ++a) dd = dd + mu[a] * contacts_[static_cast<std::size_t>(idx[static_cast<std::size_t>(a)])].n;
              if (others_ok(dd, idx, false)) {
                active = idx;
                d = dd;
                return true;
              }
            }
          }
        }
        // next combination
        int k = size - 1;
        while (k >= 0 && idx[static_cast<std::size_t>(k)] == m - size + k) --k;
        if (k < 0) break;
        ++idx[static_cast<std::size_t>(k)];
        for (int j = k + 1; j < size; ++j) idx[static_cast<std::size_t>(j)] = idx[static_cast<std::size_t>(j - 1)] + 1;
      }
    }
    return false;
  }

  /// Gaussian elimination with partial pivoting; false if (nearly) singular.
  static bool solve(int n, double G[3][3], double b[3], double x[3]) {
    double A[3][4];
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) A[i][j] = G[i][j];
      A[i][n] = b[i];
    }
    for (int c = 0; c < n; ++c) {
      int piv = c;
      for (int i = c + 1; i < n; ++i)
        if (std::fabs(A[i][c]) > std::fabs(A[piv][c])) piv = i;
      if (std::fabs(A[piv][c]) < 1e-12) return false;
      if (piv != c)
        for (int j = 0; j <= n; ++j) std::swap(A[c][j], A[piv][j]);
      for (int i = c + 1; i < n; ++i) {
        const double f = A[i][c] / A[c][c];
        for (int j = c; j <= n; ++j) A[i][j] -= f * A[c][j];
      }
    }
    for (int i = n - 1; i >= 0; --i) {
      double s = A[i][n];
      for (int j = i + 1; j < n; ++j) s -= A[i][j] * x[j];
      x[i] = s / A[i][i];
    }
    return true;
  }

  /// One motion from c (contacts_ gathered); false when the sphere rests.
  bool move(V3& c, double r, Deposition3dReport& rep) {
    std::vector<int> active;
    V3 d;
    if (!project(active, d)) {
      ++rep.unresolved;
      return false;
    }
    if (active.empty()) {
      fall(c, r);
      return true;
    }
    const double dn = norm(d);
    if (dn <= kStill) {
      const Contact& a0 = contacts_[static_cast<std::size_t>(active[0])];
      if (active.size() == 1 && a0.ob.sphere()) {  // exactly on top of one sphere: unstable
        static const V3 dirs[8] = {{1, 0, 0},   {-1, 0, 0},  {0, 1, 0},    {0, -1, 0},
                                   {1, 1, 0},   {1, -1, 0},  {-1, 1, 0},   {-1, -1, 0}};
        for (V3 h : dirs) {
          h = unit(h);
          bool ok = true;
          for (std::size_t j = 0; j < contacts_.size(); ++j)
            if (j != static_cast<std::size_t>(active[0]) && dot(contacts_[j].n, h) < -kAdmissible) ok = false;
          if (!ok) continue;
          ++rep.on_top;
          roll1(c, r, a0, h);
          return true;
        }
      }
      if (active.size() == 2 && (a0.ob.sphere() || contacts_[static_cast<std::size_t>(active[1])].ob.sphere())) {
        // two supports with gravity in the plane of their normals: an equilibrium on the circle of
        // positions touching both, stable at its lowest point, unstable above the circle's centre
        // (e.g. on two spheres that touch the same wall, all three centres in the wall's plane):
        // then the sphere rolls along the circle, towards +t if admissible, else -t
        const Contact& b0 = contacts_[static_cast<std::size_t>(active[1])];
        const Circle ci = circle(a0, b0);
        if (ci.rho > 0 && dot(unit(c - ci.C), V3{0, 0, 1}) > kTop) {
          V3 t = cross(a0.n, b0.n);
          if (norm(t) > 0) {
            t = unit(t);
            if (t.x < 0 || (t.x == 0 && t.y < 0)) t = -1.0 * t;  // orientation independent of the contact order
            for (V3 h : {t, -1.0 * t}) {
              bool ok = true;
              for (std::size_t j = 0; j < contacts_.size(); ++j)
                if (dot(contacts_[j].n, h) < -kAdmissible) ok = false;
              if (!ok) continue;
              ++rep.on_top;
              roll2(c, r, a0, b0, h);
              return true;
            }
          }
        }
      }
      bool floor = false;
      for (const Contact& k : contacts_) floor = floor || k.ob.id == kFloor;
      if (floor) ++rep.floor;
      else if (active.size() >= 3) ++rep.three;
      else ++rep.two;
      return false;
    }
    if (active.size() == 1) {
      roll1(c, r, contacts_[static_cast<std::size_t>(active[0])], (1.0 / dn) * d);
      return true;
    }
    if (active.size() == 2) {
      roll2(c, r, contacts_[static_cast<std::size_t>(active[0])], contacts_[static_cast<std::size_t>(active[1])],
            (1.0 / dn) * d);
      return true;
    }
    ++rep.unresolved;  // three independent active normals leave no motion; a nonzero d is rounding
    return false;
  }

  /// First touch of a candidate obstacle (not in `skip`) along the circle, before t_end.
  double first_touch(V3 C, double rho, V3 u, V3 v, double t_end, const Obstacle* skip1, const Obstacle* skip2) const {
    double t_best = t_end;
    for (const Obstacle& o : cand_) {
      if ((skip1 && o.same(*skip1)) || (skip2 && o.same(*skip2))) continue;
      const double t = down_crossing(o.along(C, rho, u, v));
      if (!(t < t_best)) continue;
      if (t < kSkip && in_contact(o)) continue;  // the touching contact itself
      t_best = t;
    }
    return t_best;
  }

  /// Roll over sphere a starting in the unit tangent direction v (the meridian), to the equator
  /// or the first touch.
  void roll1(V3& c, double r, const Contact& a, V3 v) {
    const Obstacle& o = a.ob;
    const V3 u = a.n;
    v = unit(v - dot(v, u) * u);
    const double rho = o.R;
    // equator: n_z(t) = u_z cos t + v_z sin t crosses zero downwards
    double t_end = down_crossing({0.0, u.z, v.z});
    if (!std::isfinite(t_end)) t_end = std::numbers::pi / 2;
    candidates(o.p, rho, r);
    const double t = first_touch(o.p, rho, u, v, t_end, &o, nullptr);
    c = o.p + rho * (std::cos(t) * u + std::sin(t) * v);
  }

  /// Roll on the circle of positions touching both a and b (at least one a sphere), downhill
  /// along the unit tangent v, to the lowest point, a lift-off or the first touch.
  struct Circle {
    V3 C, axis;
    double rho = 0;  // 0: degenerate
  };
  /// The circle of centre positions touching both a and b (at least one a sphere).
  static Circle circle(const Contact& a, const Contact& b) {
    const Obstacle* s = a.ob.sphere() ? &a.ob : &b.ob;  // a sphere
    const Obstacle* o = a.ob.sphere() ? &b.ob : &a.ob;
    Circle ci;
    double rho2;
    if (o->sphere()) {
      const V3 e = o->p - s->p;
      const double D = norm(e);
      ci.axis = (1.0 / D) * e;
      const double sd = (D * D + s->R * s->R - o->R * o->R) / (2 * D);
      ci.C = s->p + sd * ci.axis;
      rho2 = s->R * s->R - sd * sd;
    } else {
      ci.axis = o->n;
      const double t = o->off - dot(o->n, s->p);
      ci.C = s->p + t * ci.axis;
      rho2 = s->R * s->R - t * t;
    }
    ci.rho = rho2 > 0 ? std::sqrt(rho2) : 0.0;
    return ci;
  }

  void roll2(V3& c, double r, const Contact& a, const Contact& b, V3 v) {
    const Circle ci = circle(a, b);
    if (!(ci.rho > 0)) return;  // degenerate (tangent supports): the next stop re-evaluates
    const V3 C = ci.C, axis = ci.axis;
    const double rho = ci.rho;
    V3 u = c - C;
    u = unit(u - dot(u, axis) * axis);
    v = v - dot(v, axis) * axis;
    v = unit(v - dot(v, u) * u);
    // lowest point of the circle: z(t) = C_z + rho (u_z cos t + v_z sin t), minimum at atan2(v_z, u_z) + pi
    double t_end = std::atan2(v.z, u.z) + std::numbers::pi;
    t_end = std::fmod(t_end, kTwoPi);
    if (t_end < 0) t_end += kTwoPi;
    // lift-off: mu_a ~ n_az - cab n_bz, mu_b ~ n_bz - cab n_az (the Gram matrix is constant on the circle)
    const double cab = dot(a.n, b.n);
    const auto ka = a.ob.nz_along(C, rho, u, v), kb = b.ob.nz_along(C, rho, u, v);
    for (int w = 0; w < 2; ++w) {
      std::array<double, 3> f{};
      for (int k = 0; k < 3; ++k)
        f[static_cast<std::size_t>(k)] = w == 0 ? ka[static_cast<std::size_t>(k)] - cab * kb[static_cast<std::size_t>(k)]
                                                : kb[static_cast<std::size_t>(k)] - cab * ka[static_cast<std::size_t>(k)];
      const double t = down_crossing(f);
      if (t > kSkip && t < t_end) t_end = t;
    }
    candidates(C, rho, r);
    const double t = first_touch(C, rho, u, v, t_end, &a.ob, &b.ob);
    c = C + rho * (std::cos(t) * u + std::sin(t) * v);
  }

  Packing& out_;
  double w_, rmax_;
  bool periodic_;
  long n_xy_ = 1, n_z_ = 1, top_layer_ = 0;
  double top_z_ = 0;  // highest top of a fixed sphere
  double c_xy_ = 1, c_z_ = 1;
  GrowingCellGrid3 grid_{GridLayout3{}};
  std::vector<Contact> contacts_;
  std::vector<Obstacle> cand_;
};

}  // namespace

Packing ballistic_deposition_3d(const Deposition3dOptions& o, Deposition3dReport* report) {
  o.validate();
  const double R = o.radius, W = o.width * R, H = o.box_height() * R;
  const double rmin = o.r_min * R, rmax = o.r_max * R;
  const bool periodic = o.lateral == Lateral::Periodic;
  Packing p;
  p.dim = 3;
  p.box = {0.0, 0.0, W, W, 0.0, H};
  p.seed = o.seed;
  Deposition3dReport rep;
  Depositor3 dep(W, H, rmax, periodic, p);
  std::mt19937_64 rng(o.seed);
  std::size_t rejections = 0;
  while (rejections < o.max_rejections) {
    const double r = rmin == rmax ? rmin : rmin + (rmax - rmin) * uniform01(rng);
    const double ux = uniform01(rng), uy = uniform01(rng);
    const double x0 = periodic ? W * ux : r + (W - 2 * r) * ux;
    const double y0 = periodic ? W * uy : r + (W - 2 * r) * uy;
    Deposition3dReport one;
    const V3 c = dep.wrap(dep.settle(r, x0, y0, one));
    rep.max_steps = std::max(rep.max_steps, one.max_steps);
    if (c.z + r > H) {
      ++rejections;
      ++rep.discarded;
      continue;
    }
    rejections = 0;
    dep.insert(c, r);
    rep.floor += one.floor, rep.three += one.three, rep.two += one.two, rep.on_top += one.on_top;
    rep.unresolved += one.unresolved;
  }
  if (report) *report = rep;
  return p;
}

std::array<double, 3> drop_sphere(const Packing& base, double x0, double y0, double r, Lateral lateral) {
  if (base.dim != 3) throw std::invalid_argument("drop_sphere: the base must be a 3D packing (dim = 3)");
  const Box& b = base.box;
  if (!(std::isfinite(b.width()) && std::isfinite(b.height()) && std::isfinite(b.depth()) && b.width() > 0 &&
        b.height() > 0 && b.depth() > 0))
    throw std::invalid_argument("drop_sphere: the box must be finite with positive size");
  if (!(r > 0 && std::isfinite(r))) throw std::invalid_argument(fmt::format("drop_sphere: r must be > 0, got {}", r));
  if (std::fabs(b.width() - b.height()) > 1e-12 * b.width())
    throw std::invalid_argument("drop_sphere: the box must be square in x and y");
  const bool periodic = lateral == Lateral::Periodic;
  const double W = b.width();
  if (periodic ? !(x0 >= b.x_min && x0 < b.x_max && y0 >= b.y_min && y0 < b.y_max)
               : !(x0 >= b.x_min + r && x0 <= b.x_max - r && y0 >= b.y_min + r && y0 <= b.y_max - r))
    throw std::invalid_argument(fmt::format("drop_sphere: start ({}, {}) is outside the admissible range", x0, y0));
  double rmax = r;
  for (std::size_t i = 0; i < base.size(); ++i) {
    if (!(base.r[i] > 0 && std::isfinite(base.r[i]) && std::isfinite(base.x[i]) && std::isfinite(base.y[i]) &&
          std::isfinite(base.z[i])))
      throw std::invalid_argument(fmt::format("drop_sphere: base sphere {} is not finite with r > 0", i));
    rmax = std::max(rmax, base.r[i]);
  }
  if (periodic && W < 2 * (r + rmax)) throw std::invalid_argument("drop_sphere: periodic box narrower than 2 (r + r_max)");
  // local coordinates: the box corner at the origin; the grid spans every base sphere
  double top = b.depth();
  for (std::size_t i = 0; i < base.size(); ++i) top = std::max(top, base.z[i] - b.z_min + base.r[i]);
  Packing local;
  local.dim = 3;
  Depositor3 dep(W, top + 2 * rmax, rmax, periodic, local);
  for (std::size_t i = 0; i < base.size(); ++i) {
    double x = base.x[i] - b.x_min, y = base.y[i] - b.y_min;
    if (periodic) x -= W * std::floor(x / W), y -= W * std::floor(y / W);
    dep.insert({x, y, base.z[i] - b.z_min}, base.r[i]);
  }
  Deposition3dReport rep;
  const V3 c = dep.wrap(dep.settle(r, x0 - b.x_min, y0 - b.y_min, rep));
  return {c.x + b.x_min, c.y + b.y_min, c.z + b.z_min};
}

}  // namespace netdem::packing
