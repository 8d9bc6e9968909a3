#pragma once
// SUNDIALS backends for the two-particle sintering model (a documented reconstruction; see
// sintering_pair.hpp): CVODE (BDF, dense Newton; the cross-check) and ARKODE ERKStep with the
// Dormand-Prince 5(4) table (measured against the written-out DP45 of sintering_pair.hpp).
//
// Target: netdem_contact_sundials (links SUNDIALS::cvode_shared, SUNDIALS::arkode_shared,
// SUNDIALS::nvecserial_shared, SUNDIALS::sunmatrixdense_shared, SUNDIALS::sunlinsoldense_shared),
// kept apart so that netdem_contact does not depend on SUNDIALS.
//
// The thin adaptor (docs/sintering_pair.md "SUNDIALS"): one SUNContext per integrator object; a
// no-copy N_Vector view (N_VMake_Serial) over the contact's own State storage; every return code
// checked by sundials_check(), which throws SundialsError naming the call and the flag; the
// right-hand side returns SUNDIALS' "recoverable failure" (+1) when a stage leaves the cap-cone
// domain, so that the integrator cuts its step instead of aborting.
//
// One integrator per contact: the SUNDIALS memory is re-initialised (ReInit) from each contact's
// own state and step memory (PairContact::h) at the start of each advance() and at every
// temperature breakpoint, so a restart of one contact never restarts another and error norms are
// never pooled across contacts.
#include <stdexcept>
#include <string>

#include "netdem/contact/sintering_pair.hpp"

namespace netdem::contact::sinter {

/// A SUNDIALS call failed: what() names the call, the flag and its meaning.
class SundialsError : public std::runtime_error {
 public:
  SundialsError(const std::string& call, int flag);
  int flag() const { return flag_; }

 private:
  int flag_;
};

/// Integrates contacts with CVODE (BDF) or ARKODE ERKStep (Dormand-Prince 5(4)).
class SundialsPairIntegrator {
 public:
  /// kind must be IntegratorKind::CVODE or IntegratorKind::ARKODE.
  explicit SundialsPairIntegrator(IntegratorKind kind);
  ~SundialsPairIntegrator();
  SundialsPairIntegrator(const SundialsPairIntegrator&) = delete;
  SundialsPairIntegrator& operator=(const SundialsPairIntegrator&) = delete;

  /// As sinter::advance(): from c.t to t_end, stopping at every temperature breakpoint, checking
  /// the validity limits after every internal step. Returns c.status. Throws SundialsError on a
  /// non-recoverable SUNDIALS failure (a step failure inside the domain sets StepFailure instead).
  /// 1000 steps in a row shorter than 1e-12 t are a step size underflow (StepFailure): CVODE
  /// itself only warns that t + h = t and goes on, to the step cap.
  PairStatus advance(PairContact& c, const PairProblem& p, double t_end, const IntegratorOptions& opts);

  IntegratorKind kind() const { return kind_; }

 private:
  struct Impl;
  Impl* impl_;
  IntegratorKind kind_;
};

/// Any integrator: DP45 / RK4 through sinter::advance(), CVODE / ARKODE through `sundials`
/// (created on first use).
class PairIntegrator {
 public:
  explicit PairIntegrator(IntegratorOptions opts);
  ~PairIntegrator();
  PairIntegrator(const PairIntegrator&) = delete;
  PairIntegrator& operator=(const PairIntegrator&) = delete;
  PairStatus advance(PairContact& c, const PairProblem& p, double t_end);
  const IntegratorOptions& options() const { return opts_; }

 private:
  IntegratorOptions opts_;
  SundialsPairIntegrator* sundials_ = nullptr;
};

}  // namespace netdem::contact::sinter
