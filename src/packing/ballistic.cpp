// Ballistic deposition with steepest descent, Redanz & Fleck (2001) section 2.2. The motion rules,
// the stop rule and the random-draw order are documented in ballistic.hpp and docs/packing.md.
#include "netdem/packing/ballistic.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "netdem/packing/cell_grid.hpp"
#include "netdem/packing/random_fill.hpp"  // uniform01
#include "deposition_checks.hpp"

namespace netdem::packing {

void DepositionOptions::validate() const {
  auto fail = [](const std::string& msg) { throw std::invalid_argument("deposition options: " + msg); };
  detail::check_deposition_sizes("deposition options", width, height, radius, r_min, r_max);
  if (width < 2 * r_max) fail(fmt::format("width {} is smaller than the largest diameter 2 r_max = {}", width, 2 * r_max));
  if (box_height() < 2 * r_max)
    fail(fmt::format("height {} is smaller than the largest diameter 2 r_max = {}", box_height(), 2 * r_max));
  if (max_rejections == 0) fail("max_rejections must be >= 1");
}

namespace {

constexpr double kPi = std::numbers::pi;
// Tolerances, all relative to the length they compare with (r + r_k, r, or unit normals).
constexpr double kContactTol = 1e-10;  // gap / (r + r_k) below which a disk (wall, floor) is touching
// Contact normal n_y at or below kGrazing: beside, carries no weight, and a fall passes it. A disk
// dropped into a gap of exactly its diameter (common in monosized packings: the gap is exact up
// to rounding) would otherwise "bridge" the gap at a height ~sqrt(rounding) above the equators,
// an ill-conditioned rest that amplifies rounding to ~1e-8 R and propagates through the lattice.
// Passing a contact with n_y <= kGrazing costs an overlap <= (r + r_k) kGrazing^2 / 2 = 5e-13.
constexpr double kGrazing = 1e-6;
constexpr double kTop = 1e-10;         // |n_x| below this: exactly on top of a disk (unstable)
constexpr double kAdmissible = 1e-10;  // motion d admissible for a contact if n . d >= -kAdmissible
constexpr double kArcEnd = 1e-9;       // angular distance treated as "at the end of a blocked arc"
constexpr long kMaxSteps = 1'000'000;  // per disk; a guard against a logic error, never reached

constexpr int kLeftWall = -1, kRightWall = -2, kFloor = -3, kEquator = -4;

double wrap_2pi(double a) {
  a = std::fmod(a, 2 * kPi);
  return a < 0 ? a + 2 * kPi : a;
}

struct Contact {
  int id;         // disk id, or kLeftWall / kRightWall / kFloor
  double nx, ny;  // unit normal from the obstacle towards the moving disk
};

enum class MoveKind { kRest, kFall, kRoll };
struct Move {
  MoveKind kind = MoveKind::kRest;
  int on = -1;  // disk rolled over
  int dir = 0;  // +1: towards +x, -1: towards -x
};

class Depositor {
 public:
  /// Box [0, w] x [0, h]; `out` holds the fixed disks (appended by insert()), all of radius <= rmax.
  Depositor(double w, double h, double rmax, Packing& out)
      : out_(out),
        w_(w),
        rmax_(rmax),
        cell_(2 * rmax_),
        grid_(layout(w, h, cell_)) {}

  /// Settles a disk of radius r dropped at abscissa x0 (section 2.2: path of steepest descent).
  void settle(double r, double x0, double& px, double& py) {
    px = x0;
    py = std::numeric_limits<double>::infinity();
    contacts_.clear();
    fall(px, py, r);
    for (long step = 0; step < kMaxSteps; ++step) {
      gather(px, py, r);
      const Move m = decide();
      switch (m.kind) {
        case MoveKind::kRest: return;
        case MoveKind::kFall: fall(px, py, r); break;
        case MoveKind::kRoll: roll(m.on, m.dir, px, py, r); break;
      }
    }
    throw std::runtime_error(fmt::format("ballistic_deposition: disk {} did not settle in {} steps (x0 = {})",
                                         out_.size(), kMaxSteps, x0));
  }

  void insert(double x, double y, double r) {
    const int id = static_cast<int>(out_.size());
    out_.x.push_back(x);
    out_.y.push_back(y);
    out_.r.push_back(r);
    grid_.insert(static_cast<std::uint32_t>(id), x, y);
    top_row_ = std::max(top_row_, row(y));
  }

 private:
  /// Cells of side 2 r_max from the origin, ceil(w / cell) x ceil(h / cell) (the fall's row bound
  /// below relies on the rows starting at y = 0).
  static GridLayout layout(double w, double h, double cell) {
    GridLayout g;
    g.cell = {cell, cell};
    g.count = {std::max(1L, static_cast<long>(std::ceil(w / cell))), std::max(1L, static_cast<long>(std::ceil(h / cell)))};
    return g;
  }
  long col(double x) const { return grid_.layout().coord(0, x); }
  long row(double y) const { return grid_.layout().coord(1, y); }
  const std::vector<std::uint32_t>& cell(long c, long r) const { return grid_.cell(c, r); }
  bool in_contact(int id) const {
    return std::any_of(contacts_.begin(), contacts_.end(), [id](const Contact& c) { return c.id == id; });
  }
  double xs(int k) const { return out_.x[static_cast<std::size_t>(k)]; }
  double ys(int k) const { return out_.y[static_cast<std::size_t>(k)]; }
  double rs(int k) const { return out_.r[static_cast<std::size_t>(k)]; }

  /// Vertical free fall from (px, py) to the first disk (circle-circle tangency) or the floor.
  /// Disks in the current contact set are ignored (they are beside or above: decide() checked).
  /// A vertical side wall never stops a fall: sliding down a wall is a free fall along it.
  void fall(double px, double& py, double r) {
    const double y_start = py;
    double best = r;  // the floor
    const double reach = r + rmax_;
    const long c0 = col(px - reach), c1 = col(px + reach);
    for (long rw = std::min(row(y_start), top_row_); rw >= 0; --rw) {
      // every disk of row rw has y_k < (rw + 1) cell, hence a contact height < that + reach
      if (best >= static_cast<double>(rw + 1) * cell_ + reach) break;
      for (long c = c0; c <= c1; ++c)
        for (int k : cell(c, rw)) {
          const double m = r + rs(k), dx = std::fabs(xs(k) - px);
          if (dx >= m) continue;
          const double rise = std::sqrt((m - dx) * (m + dx));  // exact tangency, section 2.2
          if (rise <= kGrazing * m || in_contact(k)) continue;  // grazing a side neighbour
          const double yc = ys(k) + rise;
          if (yc > y_start + kContactTol * m) continue;  // above the start: rounding only
          best = std::max(best, yc);
        }
    }
    py = best;
  }

  /// Contact set at (px, py): disks within kContactTol relative gap, side walls and floor.
  void gather(double px, double py, double r) {
    contacts_.clear();
    const double reach = (r + rmax_) * (1 + kContactTol);
    grid_.for_each_near(px, py, reach, [&](int k) {
      const double dx = px - xs(k), dy = py - ys(k), lim = (r + rs(k)) * (1 + kContactTol);
      const double d2 = dx * dx + dy * dy;
      if (d2 > lim * lim) return;
      const double d = std::sqrt(d2);
      contacts_.push_back({k, dx / d, dy / d});
    });
    if (px - r <= kContactTol * r) contacts_.push_back({kLeftWall, 1.0, 0.0});
    if (w_ - r - px <= kContactTol * r) contacts_.push_back({kRightWall, -1.0, 0.0});
    if (py - r <= kContactTol * r) contacts_.push_back({kFloor, 0.0, 1.0});
  }

  /// Steepest descent under gravity g = (0,-1): the projection of g onto the cone of admissible
  /// motions {d : n_c . d >= 0}. In 2D the projection is g itself (free fall), the downhill tangent
  /// of one supporting disk (rolling), or zero (rest: the supports hold the disk, section 2.2).
  Move decide() const {
    bool free = true;
    for (const Contact& c : contacts_) free = free && c.ny <= kGrazing;
    if (free) return {MoveKind::kFall};
    auto admissible = [&](double tx, double ty, std::size_t skip) {
      for (std::size_t i = 0; i < contacts_.size(); ++i)
        if (i != skip && contacts_[i].nx * tx + contacts_[i].ny * ty < -kAdmissible) return false;
      return true;
    };
    Move best;
    double best_descent = -1;
    for (std::size_t i = 0; i < contacts_.size(); ++i) {
      const Contact& c = contacts_[i];
      if (c.id < 0 || c.ny <= kGrazing) continue;  // walls never support; the floor always holds
      if (std::fabs(c.nx) <= kTop) {
        // exactly on top of disk c: unstable equilibrium, the disk rolls off to +x if it can,
        // else to -x (away from a wall or side neighbour on the +x side)
        for (int s : {1, -1})
          if (best_descent < 0 && admissible(s, 0, i)) {
            best = {MoveKind::kRoll, c.id, s};
            best_descent = 0;
          }
        continue;
      }
      const int s = c.nx > 0 ? 1 : -1;
      const double descent = c.nx * c.nx;  // |projection of g onto the tangent|^2
      if (descent > best_descent && admissible(s * c.ny, -std::fabs(c.nx), i)) {
        best = {MoveKind::kRoll, c.id, s};
        best_descent = descent;
      }
    }
    return best;
  }

  /// Rolls the disk over disk j in direction s, keeping contact, until the first event: contact
  /// with another disk, a side wall or the floor, or j's equator (then it falls off). Angles psi are
  /// measured from j's vertical, positive in the direction of motion; the path is psi0 -> pi/2.
  /// The event is located by angle; the new position is then computed exactly (circle-circle,
  /// circle-line intersection) so contacts hold to rounding.
  void roll(int j, int s, double& px, double& py, double r) {
    const double xj = xs(j), yj = ys(j), l = r + rs(j);
    const double psi0 = s * std::atan2(px - xj, py - yj);
    double best = kPi / 2;
    int event = kEquator;
    const double reach = l + r + rmax_;
    grid_.for_each_in(xj - reach, xj + reach, yj - r - rmax_, yj + reach, [&](int k) {
      if (k == j) return;
      const double dx = xs(k) - xj, dy = ys(k) - yj, m = r + rs(k), d2 = dx * dx + dy * dy;
      if (d2 >= (l + m) * (l + m)) return;
      const double d = std::sqrt(d2);
      const double cb = (l * l + d2 - m * m) / (2 * l * d);
      if (cb >= 1) return;  // tangent from outside: grazing, no hit
      const double beta = std::acos(std::max(cb, -1.0));  // half-angle of the blocked arc
      if (beta <= kGrazing) return;  // grazing (overlap < 1e-12 (r + r_k)); see kGrazing
      const double alpha = s * std::atan2(dx, dy);  // direction of k, in psi
      const double to_entry = wrap_2pi(alpha - beta - psi0), to_exit = wrap_2pi(alpha + beta - psi0);
      if (in_contact(k)) {
        // At an end of k's blocked arc. At its entry end we move tangentially (decide() found
        // the motion admissible): no event. At its exit end we move away, and re-enter after
        // 2 pi - 2 beta, which can lie on the path for large radius ratios.
        if (to_entry < kArcEnd || to_entry > 2 * kPi - kArcEnd) return;
      } else if (to_exit < to_entry) {
        return;  // inside the blocked arc: only by rounding
      }
      if (psi0 + to_entry < best) {
        best = psi0 + to_entry;
        event = k;
      }
    });
    const int wall = s > 0 ? kRightWall : kLeftWall;
    const double xw = s > 0 ? w_ - r : r;
    if (!in_contact(wall) && s * (xw - xj) < l) {
      const double psi = std::asin(std::max(-1.0, s * (xw - xj) / l));
      if (psi > psi0 && psi < best) {
        best = psi;
        event = wall;
      }
    }
    if (!in_contact(kFloor) && yj < r) {  // a small disk on the floor under a larger moving one
      const double psi = std::acos((r - yj) / l);
      if (psi > psi0 && psi < best) {
        best = psi;
        event = kFloor;
      }
    }
    if (event == kEquator) {  // falls off j
      px = xj + s * l;
      py = yj;
    } else if (event == wall) {
      const double a = std::fabs(xw - xj);
      px = xw;
      py = yj + std::sqrt(std::max(0.0, (l - a) * (l + a)));
    } else if (event == kFloor) {
      const double a = r - yj;
      py = r;
      px = xj + s * std::sqrt(std::max(0.0, (l - a) * (l + a)));
    } else {  // tangent to j and k: entry point of the arc, alpha - s beta in j's vertical angle
      const double dx = xs(event) - xj, dy = ys(event) - yj, m = r + rs(event), d = std::hypot(dx, dy);
      const double ux = dx / d, uy = dy / d;
      const double a = (l * l - m * m + d * d) / (2 * d), h = std::sqrt(std::max(0.0, (l - a) * (l + a)));
      px = xj + a * ux - s * h * uy;
      py = yj + a * uy + s * h * ux;
    }
  }

  Packing& out_;
  double w_, rmax_, cell_;
  GrowingCellGrid grid_;
  long top_row_ = -1;
  std::vector<Contact> contacts_;  // reused workspace
};

}  // namespace

Packing ballistic_deposition(const DepositionOptions& o) {
  o.validate();
  Packing p;
  const double w = o.width * o.radius, h = o.box_height() * o.radius;
  p.box = {0.0, 0.0, w, h};
  p.seed = o.seed;
  Depositor dep(w, h, o.r_max * o.radius, p);
  std::mt19937_64 rng(o.seed);
  std::size_t rejections = 0;
  for (;;) {
    // Draw order, per dropped disk: radius (only if r_min < r_max), then the drop abscissa.
    double r = o.r_min * o.radius;
    if (o.r_max > o.r_min) r = o.radius * (o.r_min + (o.r_max - o.r_min) * uniform01(rng));
    const double x0 = r + (w - 2 * r) * uniform01(rng);
    double x, y;
    dep.settle(r, x0, x, y);
    const bool fits = o.lid == Lid::Centre ? y <= h : y + r <= h;
    if (!fits) {  // stop rule: does not fit below the lid
      if (++rejections >= o.max_rejections) break;
      continue;
    }
    rejections = 0;
    dep.insert(x, y, r);
  }
  return p;
}

std::pair<double, double> drop_disk(const Packing& base, double x0, double r) {
  const Box& b = base.box;
  if (!std::isfinite(b.x_min) || !std::isfinite(b.y_min) || !std::isfinite(b.x_max) || !std::isfinite(b.y_max) ||
      !(b.width() > 0) || !(b.height() > 0))
    throw std::invalid_argument("drop_disk: the base packing's box is not finite with positive size");
  if (!std::isfinite(r) || !(r > 0)) throw std::invalid_argument(fmt::format("drop_disk: radius must be > 0, got {}", r));
  if (!(x0 >= b.x_min + r && x0 <= b.x_max - r))
    throw std::invalid_argument(
        fmt::format("drop_disk: x0 = {} is not in [x_min + r, x_max - r] = [{}, {}]", x0, b.x_min + r, b.x_max - r));
  if (base.y.size() != base.size() || base.r.size() != base.size())
    throw std::invalid_argument("drop_disk: x, y, r of the base packing have different sizes");
  double rmax = r;
  for (std::size_t i = 0; i < base.size(); ++i) {
    if (!std::isfinite(base.x[i]) || !std::isfinite(base.y[i]) || !std::isfinite(base.r[i]) || !(base.r[i] > 0))
      throw std::invalid_argument(fmt::format("drop_disk: base disk {} is not finite with r > 0", i));
    rmax = std::max(rmax, base.r[i]);
  }
  // Work in box coordinates [0, W] x [0, H] (the lid only sizes the search grid).
  Packing work;
  double top = b.height();
  for (std::size_t i = 0; i < base.size(); ++i) top = std::max(top, base.y[i] - b.y_min + base.r[i]);
  Depositor dep(b.width(), top, rmax, work);
  for (std::size_t i = 0; i < base.size(); ++i) dep.insert(base.x[i] - b.x_min, base.y[i] - b.y_min, base.r[i]);
  double x, y;
  dep.settle(r, x0 - b.x_min, x, y);
  return {x + b.x_min, y + b.y_min};
}

}  // namespace netdem::packing
