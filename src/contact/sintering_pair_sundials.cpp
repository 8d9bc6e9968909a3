// SUNDIALS backends of the two-particle sintering model (documented reconstruction); see
// sintering_pair_sundials.hpp for the adaptor's rules.
#include "netdem/contact/sintering_pair_sundials.hpp"

#include <arkode/arkode_erkstep.h>
#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace netdem::contact::sinter {

namespace {
std::string flag_text(const std::string& call, int flag) {
  const char* name = nullptr;
  if (call.rfind("CVode", 0) == 0) name = CVodeGetReturnFlagName(flag);
  if (call.rfind("ERKStep", 0) == 0) name = ERKStepGetReturnFlagName(flag);
  std::string s = "SUNDIALS " + call + " failed with flag " + std::to_string(flag);
  if (name != nullptr) {
    s += std::string(" (") + name + ")";
    std::free(const_cast<char*>(name));  // *GetReturnFlagName returns malloc'ed storage
  }
  return s;
}
}  // namespace

SundialsError::SundialsError(const std::string& call, int flag)
    : std::runtime_error(flag_text(call, flag)), flag_(flag) {}

namespace {

void check(int flag, const char* call) {
  if (flag < 0) throw SundialsError(call, flag);
}
template <class T>
T* check_ptr(T* p, const char* call) {
  if (p == nullptr) throw SundialsError(std::string(call) + " returned NULL:", -1);
  return p;
}

// per-advance data seen by the right-hand side callback
struct CallbackData {
  const PairProblem* p = nullptr;
  const SinterMaterial* m = nullptr;
  Diffusivities d{};
  TemperatureProfile::Segment seg{};  // the piece of T(t) of the current segment
  const State* offset = nullptr;      // q0 of the contact with x zeroed: y = q - offset
  long evals = 0;
  bool left_geometry = false;  // a right-hand side failed at a state outside the cap-cone geometry
};

int rhs_callback(sunrealtype t, N_Vector y, N_Vector ydot, void* user) {
  auto* cd = static_cast<CallbackData*>(user);
  ++cd->evals;
  const double* yy = N_VGetArrayPointer(y);
  double* dy = N_VGetArrayPointer(ydot);
  const State& o = *cd->offset;  // SUNDIALS integrates y = q - (0, R_A0, h_A0, R_B0, h_B0)
  const State q{yy[0], o[1] + yy[1], o[2] + yy[2], o[3] + yy[3], o[4] + yy[4]};
  const double T = cd->seg(t);
  if (T != cd->d.T) cd->d = diffusivities(*cd->m, T);
  State r{};
  if (!pair_rhs(q, cd->d, cd->p->F, *cd->m, cd->p->paths, r)) {  // recoverable: cut the step
    cd->left_geometry = cd->left_geometry || check_state(q, 1.0, HUGE_VAL) == PairStatus::ConeDegenerate;
    return 1;
  }
  std::copy(r.begin(), r.end(), dy);
  return 0;
}

// silence SUNDIALS' default printing; the flag is turned into an exception or a status instead
void quiet_handler(int, const char*, const char*, char*, void*) {}
}  // namespace

struct SundialsPairIntegrator::Impl {
  SUNContext ctx = nullptr;
  N_Vector y = nullptr;  // no-copy view over the current contact's State
  void* mem = nullptr;
  SUNMatrix A = nullptr;
  SUNLinearSolver LS = nullptr;
  CallbackData cd;
  State dummy{};
  ~Impl() {
    if (LS != nullptr) SUNLinSolFree(LS);
    if (A != nullptr) SUNMatDestroy(A);
    if (mem != nullptr) {
      if (cvode)
        CVodeFree(&mem);
      else
        ERKStepFree(&mem);
    }
    if (y != nullptr) N_VDestroy(y);
    if (ctx != nullptr) SUNContext_Free(&ctx);
  }
  bool cvode = true;
};

SundialsPairIntegrator::SundialsPairIntegrator(IntegratorKind kind) : impl_(new Impl), kind_(kind) {
  if (kind != IntegratorKind::CVODE && kind != IntegratorKind::ARKODE) {
    delete impl_;
    throw std::invalid_argument("SundialsPairIntegrator: kind must be cvode or arkode");
  }
  impl_->cvode = kind == IntegratorKind::CVODE;
  try {
    check(SUNContext_Create(nullptr, &impl_->ctx), "SUNContext_Create");
    impl_->y = check_ptr(N_VMake_Serial(5, impl_->dummy.data(), impl_->ctx), "N_VMake_Serial");
    if (impl_->cvode) {
      impl_->mem = check_ptr(CVodeCreate(CV_BDF, impl_->ctx), "CVodeCreate");
      check(CVodeInit(impl_->mem, rhs_callback, 0.0, impl_->y), "CVodeInit");
      check(CVodeSetErrHandlerFn(impl_->mem, quiet_handler, nullptr), "CVodeSetErrHandlerFn");
      impl_->A = check_ptr(SUNDenseMatrix(5, 5, impl_->ctx), "SUNDenseMatrix");
      impl_->LS = check_ptr(SUNLinSol_Dense(impl_->y, impl_->A, impl_->ctx), "SUNLinSol_Dense");
      check(CVodeSetLinearSolver(impl_->mem, impl_->LS, impl_->A), "CVodeSetLinearSolver");
      check(CVodeSetUserData(impl_->mem, &impl_->cd), "CVodeSetUserData");
    } else {
      impl_->mem = check_ptr(ERKStepCreate(rhs_callback, 0.0, impl_->y, impl_->ctx), "ERKStepCreate");
      check(ERKStepSetErrHandlerFn(impl_->mem, quiet_handler, nullptr), "ERKStepSetErrHandlerFn");
      check(ERKStepSetTableNum(impl_->mem, ARKODE_DORMAND_PRINCE_7_4_5), "ERKStepSetTableNum");
      // as many error-test failures in one step as the DP45's own controller allows (it never gives
      // up): the default 7 ends a contact that approaches the geometry's limit u_t -> 0 short of it
      check(ERKStepSetMaxErrTestFails(impl_->mem, 100), "ERKStepSetMaxErrTestFails");
      check(ERKStepSetUserData(impl_->mem, &impl_->cd), "ERKStepSetUserData");
    }
  } catch (...) {
    delete impl_;
    throw;
  }
}

SundialsPairIntegrator::~SundialsPairIntegrator() { delete impl_; }

namespace {
// ERKStep (re)started at (t0, y) with the first step h0 (0: its own estimate)
void erk_start(void* mem, N_Vector y, double t0, double h0, double rtol, double atol, long max_steps) {
  check(ERKStepReInit(mem, rhs_callback, t0, y), "ERKStepReInit");
  check(ERKStepSStolerances(mem, rtol, atol), "ERKStepSStolerances");
  check(ERKStepSetInitStep(mem, h0), "ERKStepSetInitStep");
  check(ERKStepSetMaxNumSteps(mem, max_steps), "ERKStepSetMaxNumSteps");
}
}  // namespace

PairStatus SundialsPairIntegrator::advance(PairContact& c, const PairProblem& p, double t_end,
                                           const IntegratorOptions& opts) {
  if (p.material == nullptr || p.temperature == nullptr) throw std::invalid_argument("advance(): incomplete problem");
  if (c.status != PairStatus::Ok) return c.status;
  Impl& I = *impl_;
  const double Rmin = c.R_min0();
  // a state already outside the validity limits (a contact that starts there): the same end as
  // DP45's and RK4's, before SUNDIALS sees a right-hand side it cannot evaluate
  if (const PairStatus s0 = check_state(c.q, Rmin, opts.x_over_R_max); s0 != PairStatus::Ok) {
    c.status = s0;
    return s0;
  }
  const double atol = opts.atol_scale * opts.rtol * Rmin;
  I.cd.p = &p;
  I.cd.m = p.material;
  I.cd.d = Diffusivities{};
  I.cd.d.T = -1.0;
  I.cd.evals = 0;
  I.cd.left_geometry = false;
  // The integrated variable is y = q - offset, offset = (0, R_A0, h_A0, R_B0, h_B0): rtol then bounds
  // the error of the changes of R_k and h_k (the shrinkage), as the DP45 weights do. The contact's
  // state is shifted in place for each segment (the no-copy view aliases it) and shifted back at the
  // segment's end, so that stopping at a time costs the same round-off whichever call asked for it.
  const State offset{0.0, c.q0[1], c.q0[2], c.q0[3], c.q0[4]};
  I.cd.offset = &offset;
  N_VSetArrayPointer(c.q.data(), I.y);  // the view now aliases this contact's state
  bool shifted = false;
  long steps = 0;    // internal steps of this advance (the step cap)
  long stalled = 0;  // consecutive steps shorter than kStalledStep t (CVODE keeps taking steps of t eps)
  long geo_cuts = 0, clean = 0;  // ARKODE's restarts at the geometry's limit, clean steps since the last
  auto shift = [&](double sign) {
    for (int i = 1; i < 5; ++i) c.q[i] += sign * offset[i];
    shifted = sign < 0.0;
  };
  auto state_now = [&] {
    State q = c.q;
    for (int i = 1; i < 5; ++i) q[i] += offset[i];
    return q;
  };
  auto finish = [&](PairStatus s) {
    c.rhs_evals += I.cd.evals;
    I.cd.evals = 0;
    N_VSetArrayPointer(I.dummy.data(), I.y);
    c.status = s;
    return s;
  };
  try {
    while (c.t < t_end) {
      I.cd.seg = p.temperature->segment_at(c.t);
      const double seg_end = std::min(t_end, I.cd.seg.t1);
      ++c.restarts;
      shift(-1.0);
      if (I.cvode) {
        check(CVodeReInit(I.mem, c.t, I.y), "CVodeReInit");
        check(CVodeSStolerances(I.mem, opts.rtol, atol), "CVodeSStolerances");
        check(CVodeSetInitStep(I.mem, c.h > 0.0 ? std::min(c.h, seg_end - c.t) : 0.0), "CVodeSetInitStep");
        check(CVodeSetStopTime(I.mem, seg_end), "CVodeSetStopTime");
        check(CVodeSetMaxNumSteps(I.mem, opts.max_steps), "CVodeSetMaxNumSteps");
      } else {
        // no stop time: ARKODE clips its step proposal to a stop time ahead of the step, which
        // hides the unclipped proposal from the step memory; it steps past seg_end instead and the
        // state at seg_end is its interpolant (ERKStepGetDky), from which the next segment restarts
        erk_start(I.mem, I.y, c.t, c.h > 0.0 ? std::min(c.h, seg_end - c.t) : 0.0, opts.rtol, atol, opts.max_steps);
      }
      PairStatus s = PairStatus::Ok;
      for (;;) {
        if (++steps > opts.max_steps) {  // ONE_STEP mode: SUNDIALS' own mxstep counts per call
          s = PairStatus::StepFailure;
          break;
        }
        double t = c.t;
        const int flag = I.cvode ? CVode(I.mem, seg_end, I.y, &t, CV_ONE_STEP)
                                 : ERKStepEvolve(I.mem, seg_end, I.y, &t, ARK_ONE_STEP);
        if (flag < 0) {
          const bool step_failure =
              I.cvode ? (flag == CV_TOO_MUCH_WORK || flag == CV_ERR_FAILURE || flag == CV_CONV_FAILURE ||
                         flag == CV_REPTD_RHSFUNC_ERR || flag == CV_RHSFUNC_FAIL || flag == CV_TOO_CLOSE)
                      : (flag == ARK_TOO_MUCH_WORK || flag == ARK_ERR_FAILURE || flag == ARK_REPTD_RHSFUNC_ERR ||
                         flag == ARK_RHSFUNC_FAIL || flag == ARK_TOO_CLOSE);
          const bool first_rhs = I.cvode ? flag == CV_FIRST_RHSFUNC_ERR : flag == ARK_FIRST_RHSFUNC_ERR;
          // ERKStep cannot retry a step whose stage left the cap-cone geometry (the right-hand side's
          // recoverable failure ends it): it restarts from the last accepted state with a quarter of
          // the step, as DP45 cuts, until it stalls at that limit (kStalledSteps)
          if (!I.cvode && flag == ARK_UNREC_RHSFUNC_ERR && I.cd.left_geometry) {
            double h_try = 0.0, h_ok = 0.0;
            check(ERKStepGetCurrentStep(I.mem, &h_try), "ERKStepGetCurrentStep");
            check(ERKStepGetLastStep(I.mem, &h_ok), "ERKStepGetLastStep");
            const double h_cut = 0.25 * (h_ok > 0.0 ? std::min(h_try, h_ok) : h_try);
            clean = 0;
            if (++geo_cuts >= kStalledSteps || !(h_cut > kStalledStep * c.t)) {
              s = PairStatus::ConeDegenerate;
              break;
            }
            I.cd.left_geometry = false;
            erk_start(I.mem, I.y, c.t, h_cut, opts.rtol, atol, opts.max_steps);
            continue;
          }
          if (!step_failure && !first_rhs) throw SundialsError(I.cvode ? "CVode" : "ERKStepEvolve", flag);
          // a right-hand side that cannot be evaluated at a state outside the validity limits is
          // that limit (as for DP45 and RK4); otherwise the step failed
          s = check_state(state_now(), Rmin, opts.x_over_R_max);
          if (s == PairStatus::Ok || s == PairStatus::NonFinite)
            s = I.cd.left_geometry ? PairStatus::ConeDegenerate : PairStatus::StepFailure;
          break;
        }
        ++c.steps;
        if (++clean >= 10) geo_cuts = 0;
        if (!I.cvode && t > seg_end) {
          check(ERKStepGetDky(I.mem, seg_end, 0, I.y), "ERKStepGetDky");
          t = seg_end;
        }
        c.t = t;
        // step memory as in the DP45: the controller's proposal, unless this step was clipped to land
        // on the stop (then the proposal from before the clip is kept, or a larger one)
        double h = 0.0, h_last = 0.0;
        if (I.cvode) {
          check(CVodeGetCurrentStep(I.mem, &h), "CVodeGetCurrentStep");
          check(CVodeGetLastStep(I.mem, &h_last), "CVodeGetLastStep");
        } else {
          check(ERKStepGetCurrentStep(I.mem, &h), "ERKStepGetCurrentStep");
          check(ERKStepGetLastStep(I.mem, &h_last), "ERKStepGetLastStep");
        }
        const bool clipped = t >= seg_end && c.h > 0.0 && h_last < c.h * (1.0 - 1e-9);
        if (h > 0.0) c.h = clipped ? std::max(c.h, h) : h;
        s = check_state(state_now(), Rmin, opts.x_over_R_max);
        if (s != PairStatus::Ok) break;
        // a stalled step is a step size underflow: CVODE warns "t + h = t" and goes on, 1e7 steps of
        // ~1e-20 s at t = 7e-5 s for radii 5e-5, 1e-3 m (42 s, then the step cap)
        // (the geometry flag counts the right-hand side failures of the current stall only)
        stalled = h_last < kStalledStep * t ? stalled + 1 : 0;
        if (stalled == 0) I.cd.left_geometry = false;
        if (stalled >= kStalledSteps) {
          s = I.cd.left_geometry ? PairStatus::ConeDegenerate : PairStatus::StepFailure;
          break;
        }
        if (t >= seg_end) break;
      }
      shift(+1.0);
      if (s != PairStatus::Ok) return finish(s);
      c.t = seg_end;  // the tstop return lands on seg_end to round-off; make it exact
    }
  } catch (...) {  // a SUNDIALS error: leave the contact unshifted, stopped, and the view detached
    if (shifted) shift(+1.0);
    finish(PairStatus::StepFailure);
    throw;
  }
  return finish(PairStatus::Ok);
}

PairIntegrator::PairIntegrator(IntegratorOptions opts) : opts_(opts) { opts_.validate(); }
PairIntegrator::~PairIntegrator() { delete sundials_; }

PairStatus PairIntegrator::advance(PairContact& c, const PairProblem& p, double t_end) {
  if (opts_.kind == IntegratorKind::DP45 || opts_.kind == IntegratorKind::RK4)
    return sinter::advance(c, p, t_end, opts_);
  if (sundials_ == nullptr) sundials_ = new SundialsPairIntegrator(opts_.kind);
  return sundials_->advance(c, p, t_end, opts_);
}

}  // namespace netdem::contact::sinter
