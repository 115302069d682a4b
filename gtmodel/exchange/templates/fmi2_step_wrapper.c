/* FMI 2.0 co-simulation wrapper of a discrete-time step, written by gtmodel (gtmodel.exchange).
 *
 * The step is CasADi-generated C in @ID@_model.c:
 *   @ID@_step(x, u) -> (x_next, y)      one sample period DT of a controller or filter
 * Value references: [0, NX) states, then inputs, then outputs. fmi2DoStep advances by a
 * whole number of periods (a communication step that is not a multiple of DT is discarded):
 * per period, y is computed from the state and the inputs held over the step, and the state
 * is replaced by x_next.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "@ID@_model.h"

#define NX @NX@
#define NU @NU@
#define NY @NY@
#define VR_X 0
#define VR_U (NX)
#define VR_Y (NX + NU)
#define NV (NX + NU + NY)
#define DT @DT@
#define GUID "@GUID@"

static const double START[NV + 1] = {@START@};

typedef struct {
  double v[NV + 1];
  double xn[NX + 1];
  double t;
  fmi2CallbackFunctions cb;
  char name[128];
  const double** arg;
  double** res;
  casadi_int* iw;
  double* w;
} Inst;

static int step(Inst* m) {
  m->arg[0] = m->v + VR_X;
  m->arg[1] = m->v + VR_U;
  m->res[0] = m->xn;
  m->res[1] = m->v + VR_Y;
  if (@ID@_step(m->arg, m->res, m->iw, m->w, 0)) return 1;
  memcpy(m->v + VR_X, m->xn, NX * sizeof(double));
  return 0;
}

const char* fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char* fmi2GetVersion(void) { return fmi2Version; }
fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t n, const fmi2String cats[]) { (void)c; (void)on; (void)n; (void)cats; return fmi2OK; }

fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid, fmi2String location,
                              const fmi2CallbackFunctions* cb, fmi2Boolean visible, fmi2Boolean logging) {
  Inst* m;
  casadi_int sz_arg, sz_res, sz_iw, sz_w;
  (void)location; (void)visible; (void)logging;
  if (type != fmi2CoSimulation || !guid || strcmp(guid, GUID) != 0) {
    if (cb && cb->logger) cb->logger(cb->componentEnvironment, name, fmi2Error, "error", "co-simulation only; GUID must match");
    return NULL;
  }
  m = (Inst*)calloc(1, sizeof(Inst));
  if (!m) return NULL;
  if (cb) m->cb = *cb;
  strncpy(m->name, name ? name : "", sizeof(m->name) - 1);
  @ID@_step_work(&sz_arg, &sz_res, &sz_iw, &sz_w);
  m->arg = (const double**)calloc(sz_arg + 1, sizeof(double*));
  m->res = (double**)calloc(sz_res + 1, sizeof(double*));
  m->iw = (casadi_int*)calloc(sz_iw + 1, sizeof(casadi_int));
  m->w = (double*)calloc(sz_w + 1, sizeof(double));
  memcpy(m->v, START, sizeof(START));
  return m;
}

void fmi2FreeInstance(fmi2Component c) {
  Inst* m = (Inst*)c;
  if (!m) return;
  free(m->arg); free(m->res); free(m->iw); free(m->w); free(m);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean a, fmi2Real tol, fmi2Real t0, fmi2Boolean b, fmi2Real t1) {
  (void)a; (void)tol; (void)b; (void)t1;
  ((Inst*)c)->t = t0;
  return fmi2OK;
}
fmi2Status fmi2EnterInitializationMode(fmi2Component c) { (void)c; return fmi2OK; }
fmi2Status fmi2ExitInitializationMode(fmi2Component c) { (void)c; return fmi2OK; }
fmi2Status fmi2Terminate(fmi2Component c) { (void)c; return fmi2OK; }
fmi2Status fmi2Reset(fmi2Component c) {
  Inst* m = (Inst*)c;
  memcpy(m->v, START, sizeof(START));
  m->t = 0;
  return fmi2OK;
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Real value[]) {
  Inst* m = (Inst*)c;
  size_t i;
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
    if (vr[i] >= VR_Y) return fmi2Error;
    m->v[vr[i]] = value[i];
  }
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
fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference u[], size_t nu, const fmi2ValueReference k[], size_t nk, const fmi2Real dk[], fmi2Real du[]) {
  (void)c; (void)u; (void)nu; (void)k; (void)nk; (void)dk; (void)du; return fmi2Error;
}
fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Integer o[], const fmi2Real v[]) { (void)c; (void)vr; (void)o; (void)v; return n ? fmi2Error : fmi2OK; }
fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Integer o[], fmi2Real v[]) { (void)c; (void)vr; (void)o; (void)v; return n ? fmi2Error : fmi2OK; }

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t0, fmi2Real H, fmi2Boolean noPrior) {
  Inst* m = (Inst*)c;
  double periods = H / DT;
  long n = (long)floor(periods + 0.5), k;
  (void)noPrior;
  if (n < 1 || fabs(periods - n) > 1e-6 * (periods > 1 ? periods : 1)) {
    if (m->cb.logger) m->cb.logger(m->cb.componentEnvironment, m->name, fmi2Discard, "warning",
                                   "fmi2DoStep: the communication step must be a multiple of the period %g s", DT);
    return fmi2Discard;
  }
  for (k = 0; k < n; ++k) {
    if (step(m)) return fmi2Error;
  }
  m->t = t0 + H;
  return fmi2OK;
}
fmi2Status fmi2CancelStep(fmi2Component c) { (void)c; return fmi2Error; }
fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind k, fmi2Status* v) { (void)c; (void)k; (void)v; return fmi2Discard; }
fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind k, fmi2Real* v) {
  if (k != fmi2LastSuccessfulTime) return fmi2Discard;
  *v = ((Inst*)c)->t;
  return fmi2OK;
}
fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind k, fmi2Integer* v) { (void)c; (void)k; (void)v; return fmi2Discard; }
fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind k, fmi2Boolean* v) { (void)c; (void)k; (void)v; return fmi2Discard; }
fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind k, fmi2String* v) { (void)c; (void)k; (void)v; return fmi2Discard; }
