#pragma once
// The measured state of demsolve's plastic-indentation scenes (compact, yield): window samples in
// netsolve's sign convention and column meanings, and netsolve's snapshot files.
#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "netdem/dynamic/solver.hpp"
#include "netdem/packing/packing.hpp"

namespace netdem::app::dem {

using netdem::dem::ContactInfo;
using netdem::dem::DynamicSolver;

/// One sample of the measured state; a history row is the mean of the samples of its window.
struct Sample {
  double S11 = 0, S22 = 0, S12 = 0, S11c = 0, S22c = 0, S12c = 0;  ///< netsolve's sign: compression negative
  double Z = 0, contacts = 0, sliding = 0, mean_fn = 0;
  double dev_mean_ratio = 0, dev_ratio_of_means = 0, affine_ut = 0;
  double kinetic = 0, work = 0;  ///< fluctuating kinetic energy; sum F_N u_N / 2 over the disk contacts
  void add(const Sample& o, double w) {
    S11 += w * o.S11, S22 += w * o.S22, S12 += w * o.S12, S11c += w * o.S11c, S22c += w * o.S22c, S12c += w * o.S12c;
    Z += w * o.Z, contacts += w * o.contacts, sliding += w * o.sliding, mean_fn += w * o.mean_fn;
    dev_mean_ratio += w * o.dev_mean_ratio, dev_ratio_of_means += w * o.dev_ratio_of_means, affine_ut += w * o.affine_ut;
    kinetic += w * o.kinetic, work += w * o.work;
  }
};

/// The measures of the current state (Z, contact counts and the affine-deviation measures as
/// netsolve's src/quasistatic/measures.cpp, over the disk-disk contacts with F_N > 0).
class Meter {
 public:
  Meter(bool walls, double r_mean) : walls_(walls), r_mean_(r_mean) {}

  /// The measures at the current state; E11, E22, E12: the macroscopic strain accumulated so far (the
  /// affine-deviation measures use the strain since each contact formed).
  Sample measure(const DynamicSolver& s, double E11, double E22, double E12 = 0.0);
  const std::vector<ContactInfo>& last_contacts() const { return cs_; }

 private:
  bool walls_;
  double r_mean_;
  std::vector<ContactInfo> cs_;
  std::unordered_map<std::uint64_t, std::array<double, 3>> form_;
  double prev_E11_ = 0.0, prev_E22_ = 0.0, prev_E12_ = 0.0;
};

/// netsolve's snapshot files and field names (apps/netsolve/main.cpp write_snapshot), plus the
/// velocities: particles_<tag>.vtp, contacts_<tag>.vtp (disk-disk contacts).
void write_compact_snapshot(const DynamicSolver& s, const std::filesystem::path& out, const std::string& tag,
                            std::vector<ContactInfo>& cs);


/// The explicit solver's options for the plastic-indentation law on netsolve's scenes (sigma_y = 1,
/// frictionless die walls); damping: both dashpots, fractions of critical damping of the chord.
netdem::dem::DynamicOptions plastic_options(double mu, double k_t, bool reversible, double first_touch, double damping,
                                            double drag, double steps_per_contact);

/// The prescribed particles: every one (affine), none (walls) or netsolve's peripheral layer.
std::vector<std::uint32_t> prescribed_particles(const packing::Packing& pk, bool affine, bool walls);

}  // namespace netdem::app::dem
