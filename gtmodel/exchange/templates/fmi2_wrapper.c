/* FMI 2.0 model exchange and co-simulation wrapper written by gtmodel (gtmodel.exchange).
 *
 * The model equations are CasADi-generated C in @ID@_model.c:
 *   @ID@_f(t, x, u, p) -> (xdot, y)                 the explicit ODE and the outputs
 *   @ID@_df(t, x, u, p, dx, du, dp) -> (dxdot, dy)  its forward directional derivative
 * Value references: [0, NX) states, [NX, 2 NX) derivatives, then inputs, parameters, outputs.
 *   @ID@_ind(t, x, u, p) -> c, @ID@_jump(t, x, u, p, fire) -> x_new   (NZ > 0: when-clauses)
 * Co-simulation: the classical fixed-step 4th-order Runge-Kutta method with the inputs held
 * over the communication step, substeps of at most STEP seconds (no SUNDIALS); a state event
 * inside a substep is located by bisection of the RK4 step length and handled there.
 * Events (Modelica's when c > 0 / c < 0): a clause fires when its condition is true and was
 * false at the last event (pre); its reinit is applied with the values before the event.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "@ID@_model.h"

#define NX @NX@
#define NU @NU@
#define NP @NP@
#define NY @NY@
#define NZ @NZ@
#define VR_X 0
#define VR_DX (NX)
#define VR_U (2 * NX)
#define VR_P (2 * NX + NU)
#define VR_Y (2 * NX + NU + NP)
#define NV (2 * NX + NU + NP + NY)
#define STEP @STEP@
#define GUID "@GUID@"

static const double START[NV + 1] = {@START@};
static const int DIRECTION[NZ + 1] = {@DIRS@};

typedef struct {
  double v[NV + 1];
  double t;
  int dirty;
  fmi2Type type;
  fmi2CallbackFunctions cb;
  char name[128];
  const double** arg;
  double** res;
  casadi_int* iw;
  double* w;
  double k[4][NX + 1], xs[NX + 1];
  int pre[NZ + 1];
} Inst;

static void logmsg(Inst* m, fmi2Status s, const char* msg) {
  if (m && m->cb.logger) m->cb.logger(m->cb.componentEnvironment, m->name, s, "error", "%s", msg);
}

/* xdot (and the outputs when y != 0) at time t, states x, the instance's inputs and parameters */
static int rhs(Inst* m, double t, const double* x, double* xdot, double* y) {
  m->arg[0] = &t;
  m->arg[1] = x;
  m->arg[2] = m->v + VR_U;
  m->arg[3] = m->v + VR_P;
  m->res[0] = xdot;
  m->res[1] = y;
  return @ID@_f(m->arg, m->res, m->iw, m->w, 0);
}

/* one classical RK4 step of length h from x (time t) into out */
static int rk4(Inst* m, double t, const double* x, double h, double* out) {
  int i, j;
  if (rhs(m, t, x, m->k[0], 0)) return 1;
  for (i = 0; i < NX; ++i) m->xs[i] = x[i] + 0.5 * h * m->k[0][i];
  if (rhs(m, t + 0.5 * h, m->xs, m->k[1], 0)) return 1;
  for (i = 0; i < NX; ++i) m->xs[i] = x[i] + 0.5 * h * m->k[1][i];
  if (rhs(m, t + 0.5 * h, m->xs, m->k[2], 0)) return 1;
  for (i = 0; i < NX; ++i) m->xs[i] = x[i] + h * m->k[2][i];
  if (rhs(m, t + h, m->xs, m->k[3], 0)) return 1;
  for (i = 0; i < NX; ++i) {
    double inc = 0;
    for (j = 0; j < 4; ++j) inc += (j == 0 || j == 3 ? 1.0 : 2.0) * m->k[j][i];
    out[i] = x[i] + h * inc / 6.0;
  }
  return 0;
}

#if NZ > 0
static int indicators(Inst* m, double t, const double* x, double* c) {
  m->arg[0] = &t;
  m->arg[1] = x;
  m->arg[2] = m->v + VR_U;
  m->arg[3] = m->v + VR_P;
  m->res[0] = c;
  return @ID@_ind(m->arg, m->res, m->iw, m->w, 0);
}
/* the condition of a clause: c > 0 (rising), c < 0 (falling), the sign of c (both) */
static int condition(int dir, double c) { return dir > 0 ? c > 0 : dir < 0 ? c < 0 : (c > 0) - (c < 0); }
static void set_pre(Inst* m, const double* c) {
  int k;
  for (k = 0; k < NZ; ++k) m->pre[k] = condition(DIRECTION[k], c[k]);
}
static int fired(Inst* m, const double* c, double* fire) {
  int k, any = 0;
  for (k = 0; k < NZ; ++k) {
    int now = condition(DIRECTION[k], c[k]);
    fire[k] = DIRECTION[k] != 0 ? (now && !m->pre[k]) : (now != 0 && m->pre[k] != 0 && now != m->pre[k]);
    any |= fire[k] != 0;
  }
  return any;
}
/* event handling at (t, x): fire the clauses, reinit x, update pre; returns 1 if x changed, -1 on error */
static int handle_events(Inst* m, double t, double* x) {
  double c[NZ + 1], fire[NZ + 1], xn[NX + 1];
  int changed = 0, iter;
  for (iter = 0; iter < 10; ++iter) { /* event iteration: until no clause fires */
    if (indicators(m, t, x, c)) return -1;
    if (!fired(m, c, fire)) break;
    set_pre(m, c);
    m->arg[0] = &t;
    m->arg[1] = x;
    m->arg[2] = m->v + VR_U;
    m->arg[3] = m->v + VR_P;
    m->arg[4] = fire;
    m->res[0] = xn;
    if (@ID@_jump(m->arg, m->res, m->iw, m->w, 0)) return -1;
    memcpy(x, xn, NX * sizeof(double));
    changed = 1;
  }
  if (indicators(m, t, x, c)) return -1;
  set_pre(m, c);
  return changed;
}
#endif

static fmi2Status update(Inst* m) {
  if (!m->dirty) return fmi2OK;
  if (rhs(m, m->t, m->v + VR_X, m->v + VR_DX, m->v + VR_Y)) {
    logmsg(m, fmi2Error, "evaluation of the model equations failed");
    return fmi2Error;
  }
  m->dirty = 0;
  return fmi2OK;
}

const char* fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char* fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t n, const fmi2String cats[]) {
  (void)c; (void)on; (void)n; (void)cats;
  return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid, fmi2String location,
                              const fmi2CallbackFunctions* cb, fmi2Boolean visible, fmi2Boolean logging) {
  Inst* m;
  casadi_int sz_arg, sz_res, sz_iw, sz_w, a2, r2, i2, w2;
  (void)location; (void)visible; (void)logging;
  if (!guid || strcmp(guid, GUID) != 0) {
    if (cb && cb->logger) cb->logger(cb->componentEnvironment, name, fmi2Error, "error", "GUID mismatch: %s", guid ? guid : "(null)");
    return NULL;
  }
  m = (Inst*)calloc(1, sizeof(Inst));
  if (!m) return NULL;
  if (cb) m->cb = *cb;
  strncpy(m->name, name ? name : "", sizeof(m->name) - 1);
  m->type = type;
  @ID@_f_work(&sz_arg, &sz_res, &sz_iw, &sz_w);
  @ID@_df_work(&a2, &r2, &i2, &w2);
  if (a2 > sz_arg) sz_arg = a2;
  if (r2 > sz_res) sz_res = r2;
  if (i2 > sz_iw) sz_iw = i2;
  if (w2 > sz_w) sz_w = w2;
#if NZ > 0
  @ID@_ind_work(&a2, &r2, &i2, &w2);
  if (a2 > sz_arg) sz_arg = a2;
  if (r2 > sz_res) sz_res = r2;
  if (i2 > sz_iw) sz_iw = i2;
  if (w2 > sz_w) sz_w = w2;
  @ID@_jump_work(&a2, &r2, &i2, &w2);
  if (a2 > sz_arg) sz_arg = a2;
  if (r2 > sz_res) sz_res = r2;
  if (i2 > sz_iw) sz_iw = i2;
  if (w2 > sz_w) sz_w = w2;
#endif
  m->arg = (const double**)calloc(sz_arg + 1, sizeof(double*));
  m->res = (double**)calloc(sz_res + 1, sizeof(double*));
  m->iw = (casadi_int*)calloc(sz_iw + 1, sizeof(casadi_int));
  m->w = (double*)calloc(sz_w + 1, sizeof(double));
  memcpy(m->v, START, sizeof(START));
  m->dirty = 1;
  return m;
}

void fmi2FreeInstance(fmi2Component c) {
  Inst* m = (Inst*)c;
  if (!m) return;
  free(m->arg); free(m->res); free(m->iw); free(m->w); free(m);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean tolDef, fmi2Real tol, fmi2Real t0, fmi2Boolean stopDef, fmi2Real t1) {
  Inst* m = (Inst*)c;
  (void)tolDef; (void)tol; (void)stopDef; (void)t1;
  m->t = t0;
  m->dirty = 1;
  return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) { (void)c; return fmi2OK; }
fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
  Inst* m = (Inst*)c;
#if NZ > 0
  double ind[NZ + 1];
  if (indicators(m, m->t, m->v + VR_X, ind)) return fmi2Error;
  set_pre(m, ind);
#endif
  return update(m);
}
fmi2Status fmi2Terminate(fmi2Component c) { (void)c; return fmi2OK; }

fmi2Status fmi2Reset(fmi2Component c) {
  Inst* m = (Inst*)c;
  memcpy(m->v, START, sizeof(START));
  m->t = 0;
  m->dirty = 1;
  return fmi2OK;
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Real value[]) {
  Inst* m = (Inst*)c;
  size_t i;
  if (update(m) != fmi2OK) return fmi2Error;
  for (i = 0; i < n; ++i) {
    if (vr[i] >= NV) return fmi2Error;
    value[i] = m->v[vr[i]];
  }
  return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Real value[]) {
  Inst* m = (Inst*)c;
  size_t i;
  for (i = 0; i < n; ++i) {
    if (vr[i] >= NV || (vr[i] >= VR_DX && vr[i] < VR_U) || vr[i] >= VR_Y) {
      logmsg(m, fmi2Error, "fmi2SetReal: not an input, parameter or state");
      return fmi2Error;
    }
    m->v[vr[i]] = value[i];
  }
  m->dirty = 1;
  return fmi2OK;
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Integer v[]) { (void)c; (void)vr; (void)v; return n ? fmi2Error : fmi2OK; }
fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Boolean v[]) { (void)c; (void)vr; (void)v; return n ? fmi2Error : fmi2OK; }
fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2String v[]) { (void)c; (void)vr; (void)v; return n ? fmi2Error : fmi2OK; }
fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Integer v[]) { (void)c; (void)vr; (void)v; return n ? fmi2Error : fmi2OK; }
fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Boolean v[]) { (void)c; (void)vr; (void)v; return n ? fmi2Error : fmi2OK; }
fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2String v[]) { (void)c; (void)vr; (void)v; return n ? fmi2Error : fmi2OK; }

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate* s) { (void)c; (void)s; return fmi2Error; }
fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate s) { (void)c; (void)s; return fmi2Error; }
fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate* s) { (void)c; (void)s; return fmi2Error; }
fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate s, size_t* n) { (void)c; (void)s; (void)n; return fmi2Error; }
fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate s, fmi2Byte b[], size_t n) { (void)c; (void)s; (void)b; (void)n; return fmi2Error; }
fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte b[], size_t n, fmi2FMUstate* s) { (void)c; (void)s; (void)b; (void)n; return fmi2Error; }

/* Jacobian times seed of the derivatives and outputs w.r.t. states, inputs and parameters */
fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference unknown[], size_t nUnknown,
                                        const fmi2ValueReference known[], size_t nKnown,
                                        const fmi2Real dvKnown[], fmi2Real dvUnknown[]) {
  Inst* m = (Inst*)c;
  double seed[NV + 1], sens[NV + 1];
  size_t i;
  memset(seed, 0, sizeof(seed));
  memset(sens, 0, sizeof(sens));
  for (i = 0; i < nKnown; ++i) {
    if (known[i] >= VR_Y || (known[i] >= VR_DX && known[i] < VR_U)) return fmi2Error;
    seed[known[i]] = dvKnown[i];
  }
  m->arg[0] = &m->t;
  m->arg[1] = m->v + VR_X;
  m->arg[2] = m->v + VR_U;
  m->arg[3] = m->v + VR_P;
  m->arg[4] = seed + VR_X;
  m->arg[5] = seed + VR_U;
  m->arg[6] = seed + VR_P;
  m->res[0] = sens + VR_DX;
  m->res[1] = sens + VR_Y;
  if (@ID@_df(m->arg, m->res, m->iw, m->w, 0)) return fmi2Error;
  for (i = 0; i < nUnknown; ++i) {
    if (unknown[i] >= NV) return fmi2Error;
    dvUnknown[i] = sens[unknown[i]];
  }
  return fmi2OK;
}

/* ---- model exchange */
fmi2Status fmi2EnterEventMode(fmi2Component c) { (void)c; return fmi2OK; }
fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo* e) {
  Inst* m = (Inst*)c;
  int changed = 0;
#if NZ > 0
  changed = handle_events(m, m->t, m->v + VR_X);
  if (changed < 0) return fmi2Error;
  if (changed) m->dirty = 1;
#endif
  (void)m;
  e->newDiscreteStatesNeeded = fmi2False;
  e->terminateSimulation = fmi2False;
  e->nominalsOfContinuousStatesChanged = fmi2False;
  e->valuesOfContinuousStatesChanged = changed ? fmi2True : fmi2False;
  e->nextEventTimeDefined = fmi2False;
  e->nextEventTime = 0;
  return fmi2OK;
}
fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) { (void)c; return fmi2OK; }
fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noPrior, fmi2Boolean* enterEvent, fmi2Boolean* terminate) {
  (void)c; (void)noPrior;
  *enterEvent = fmi2False;
  *terminate = fmi2False;
  return fmi2OK;
}
fmi2Status fmi2SetTime(fmi2Component c, fmi2Real t) {
  Inst* m = (Inst*)c;
  m->t = t;
  m->dirty = 1;
  return fmi2OK;
}
fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t n) {
  Inst* m = (Inst*)c;
  if (n != NX) return fmi2Error;
  memcpy(m->v + VR_X, x, NX * sizeof(double));
  m->dirty = 1;
  return fmi2OK;
}
fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real dx[], size_t n) {
  Inst* m = (Inst*)c;
  if (n != NX || update(m) != fmi2OK) return fmi2Error;
  memcpy(dx, m->v + VR_DX, NX * sizeof(double));
  return fmi2OK;
}
fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real ind[], size_t n) {
#if NZ > 0
  Inst* m = (Inst*)c;
  if (n != NZ) return fmi2Error;
  return indicators(m, m->t, m->v + VR_X, ind) ? fmi2Error : fmi2OK;
#else
  (void)c; (void)ind;
  return n ? fmi2Error : fmi2OK;
#endif
}
fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t n) {
  Inst* m = (Inst*)c;
  if (n != NX) return fmi2Error;
  memcpy(x, m->v + VR_X, NX * sizeof(double));
  return fmi2OK;
}
fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real nom[], size_t n) {
  size_t i;
  (void)c;
  for (i = 0; i < n; ++i) nom[i] = 1.0;
  return fmi2OK;
}

/* ---- co-simulation */
fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Integer order[], const fmi2Real v[]) {
  (void)c; (void)vr; (void)order; (void)v; return n ? fmi2Error : fmi2OK;
}
fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Integer order[], fmi2Real v[]) {
  (void)c; (void)vr; (void)order; (void)v; return n ? fmi2Error : fmi2OK;
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t0, fmi2Real H, fmi2Boolean noPrior) {
  Inst* m = (Inst*)c;
  double* x = m->v + VR_X;
  double xn[NX + 1], h, t = t0, end = t0 + H;
  long n;
  (void)noPrior;
  if (H <= 0) return H == 0 ? fmi2OK : fmi2Error;
  n = (long)ceil(H / STEP - 1e-9);
  if (n < 1) n = 1;
  h = H / n;
  while (end - t > 1e-12 * (fabs(end) + 1.0)) {
    double hs = h < end - t ? h : end - t;
    if (rk4(m, t, x, hs, xn)) goto fail;
#if NZ > 0
    {
      double ind[NZ + 1], fire[NZ + 1], lo = 0.0, hi = hs;
      int it, r;
      if (indicators(m, t + hs, xn, ind)) goto fail;
      if (fired(m, ind, fire)) { /* a state event inside the substep: bisect the step length */
        for (it = 0; it < 60 && hi - lo > 1e-15 * (fabs(t) + 1.0); ++it) {
          double mid = 0.5 * (lo + hi);
          if (rk4(m, t, x, mid, xn) || indicators(m, t + mid, xn, ind)) goto fail;
          if (fired(m, ind, fire)) hi = mid; else lo = mid;
        }
        if (rk4(m, t, x, hi, xn)) goto fail;
        memcpy(x, xn, NX * sizeof(double));
        t += hi;
        r = handle_events(m, t, x);
        if (r < 0) goto fail;
        continue;
      }
    }
#endif
    memcpy(x, xn, NX * sizeof(double));
    t += hs;
  }
  m->t = end;
  m->dirty = 1;
  return update(m);
fail:
  logmsg(m, fmi2Error, "fmi2DoStep: evaluation of the model equations failed");
  return fmi2Error;
}

fmi2Status fmi2CancelStep(fmi2Component c) { (void)c; return fmi2Error; }
fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind k, fmi2Status* v) { (void)c; (void)k; (void)v; return fmi2Discard; }
fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind k, fmi2Real* v) {
  Inst* m = (Inst*)c;
  if (k != fmi2LastSuccessfulTime) return fmi2Discard;
  *v = m->t;
  return fmi2OK;
}
fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind k, fmi2Integer* v) { (void)c; (void)k; (void)v; return fmi2Discard; }
fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind k, fmi2Boolean* v) { (void)c; (void)k; (void)v; return fmi2Discard; }
fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind k, fmi2String* v) { (void)c; (void)k; (void)v; return fmi2Discard; }
