/* casmech FMU: the FMI 2.0 functions, Model Exchange and Co-Simulation, around the CasADi
   functions of casmech.fmu.system (casmech_fmu_functions.c) and the numerics of
   casmech_fmu_solver.c. casmech_fmu.h lists the value references. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "casmech_fmu.h"

void cm_log(Instance *c, fmi2Status status, const char *category, const char *message) {
    if (c->functions.logger && (c->logging || status >= fmi2Error)) {
        c->functions.logger(c->functions.componentEnvironment, c->name, status, category, "%s",
                            message);
    }
}

static fmi2Status fail(Instance *c, const char *message) {
    cm_log(c, fmi2Error, "logStatusError", message);
    return fmi2Error;
}

/* One CasADi function: inputs and outputs as dense arrays (every function is generated
   with dense outputs). Returns nonzero on failure. */
int cm_call(Instance *c, CmEval f, const double **in, int n_in, double **out, int n_out) {
    for (int k = 0; k < n_in; ++k) c->arg[k] = in[k];
    for (int k = 0; k < n_out; ++k) c->res[k] = out[k];
    if (f(c->arg, c->res, c->iw, c->w, 0)) {
        cm_log(c, fmi2Error, "logStatusError", "a generated function failed");
        return 1;
    }
    return 0;
}

void cm_inputs_at(Instance *c, double t) {
    for (int k = 0; k < CM_NU; ++k) {
        c->jd[CM_U_OFFSET + k] = c->s.u[k] + c->s.du[k] * (t - c->s.u_time);
    }
}

/* jd from theta when a parameter changed, then the inputs */
void cm_data_update(Instance *c) {
    if (!c->s.data_valid) {
        const double *in[1] = {c->s.theta};
        double *out[1] = {c->jd};
        if (cm_call(c, cm_data, in, 1, out, 1)) return;
        if (CM_NC) {
            double *calculated[1] = {c->calculated};
            cm_call(c, cm_calculated, in, 1, calculated, 1);
        }
        c->s.data_valid = 1;
    }
    cm_inputs_at(c, c->s.time);
}

typedef int (*CmWork)(casadi_int *, casadi_int *, casadi_int *, casadi_int *);
static const CmWork WORK[] = {cm_data_work, cm_ode_work, cm_outputs_work, cm_file_pose_work,
                              cm_tree_pose_work, cm_position_terms_work,
                              cm_velocity_terms_work, cm_drift_work, cm_calculated_work};

static void *allocate(Instance *c, size_t n, size_t size) {
    return c->functions.allocateMemory(n ? n : 1, size);
}

/* ---------------------------------------------------------------- common functions */

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component component, fmi2Boolean loggingOn,
                               size_t nCategories, const fmi2String categories[]) {
    Instance *c = (Instance *)component;
    (void)categories;
    (void)nCategories;
    if (!c) return fmi2Error;
    c->logging = loggingOn;
    return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation,
                              const fmi2CallbackFunctions *functions, fmi2Boolean visible,
                              fmi2Boolean loggingOn) {
    Instance *c;
    casadi_int sz_arg = 0, sz_res = 0, sz_iw = 0, sz_w = 0;
    (void)fmuResourceLocation;
    (void)visible;
    if (!functions || !functions->allocateMemory || !functions->freeMemory) return NULL;
    if (!fmuGUID || strcmp(fmuGUID, CM_GUID) != 0) {
        if (functions->logger) {
            functions->logger(functions->componentEnvironment, instanceName, fmi2Error,
                              "logStatusError", "wrong GUID %s, expected %s",
                              fmuGUID ? fmuGUID : "(null)", CM_GUID);
        }
        return NULL;
    }
    c = (Instance *)functions->allocateMemory(1, sizeof(Instance));
    if (!c) return NULL;
    c->functions = *functions;
    c->type = fmuType;
    c->logging = loggingOn;
    c->name = (char *)allocate(c, strlen(instanceName ? instanceName : "") + 1, 1);
    if (c->name) strcpy(c->name, instanceName ? instanceName : "");
    for (size_t k = 0; k < sizeof WORK / sizeof WORK[0]; ++k) {
        casadi_int a, r, i, w;
        WORK[k](&a, &r, &i, &w);
        sz_arg = a > sz_arg ? a : sz_arg;
        sz_res = r > sz_res ? r : sz_res;
        sz_iw = i > sz_iw ? i : sz_iw;
        sz_w = w > sz_w ? w : sz_w;
    }
    c->arg = (const casadi_real **)allocate(c, (size_t)sz_arg, sizeof(casadi_real *));
    c->res = (casadi_real **)allocate(c, (size_t)sz_res, sizeof(casadi_real *));
    c->iw = (casadi_int *)allocate(c, (size_t)sz_iw, sizeof(casadi_int));
    c->w = (casadi_real *)allocate(c, (size_t)sz_w, sizeof(casadi_real));
    if (!c->name || !c->arg || !c->res || !c->iw || !c->w) return NULL;
    memcpy(c->s.theta, cm_theta_start, sizeof c->s.theta);
    memcpy(c->s.x, cm_x_start, sizeof c->s.x);
    memcpy(c->s.u, cm_u_start, sizeof c->s.u);
    c->rtol = CM_RTOL;
    c->atol = CM_ATOL;
    c->s.mode = MODE_INSTANTIATED;
    return c;
}

void fmi2FreeInstance(fmi2Component component) {
    Instance *c = (Instance *)component;
    if (!c) return;
    c->functions.freeMemory((void *)c->arg);
    c->functions.freeMemory(c->res);
    c->functions.freeMemory(c->iw);
    c->functions.freeMemory(c->w);
    c->functions.freeMemory(c->name);
    c->functions.freeMemory(c);
}

fmi2Status fmi2SetupExperiment(fmi2Component component, fmi2Boolean toleranceDefined,
                               fmi2Real tolerance, fmi2Real startTime,
                               fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    Instance *c = (Instance *)component;
    (void)stopTimeDefined;
    (void)stopTime;
    if (!c || c->s.mode != MODE_INSTANTIATED) return fmi2Error;
    if (toleranceDefined && tolerance > 0) {  /* atol keeps the model's ratio to rtol */
        c->atol = CM_ATOL / CM_RTOL * tolerance;
        c->rtol = tolerance;
    }
    c->start_time = startTime;
    c->s.time = startTime;
    c->s.started = 0;
    c->s.u_time = startTime;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component component) {
    Instance *c = (Instance *)component;
    if (!c || c->s.mode != MODE_INSTANTIATED) return fmi2Error;
    c->s.mode = MODE_INITIALIZATION;
    return fmi2OK;
}

/* In initialization mode: the start state from the parameters, states and inputs set so far
   (computed again after any of them changes), so that states, derivatives and outputs can be
   read before initialization ends. */
static fmi2Status started(Instance *c) {
    if (c->s.mode == MODE_INITIALIZATION && !c->s.started) {
        if (cm_start_state(c) != fmi2OK) return fmi2Error;
        c->s.started = 1;
    }
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component component) {
    Instance *c = (Instance *)component;
    if (!c || c->s.mode != MODE_INITIALIZATION) return fmi2Error;
    if (started(c) != fmi2OK) {
        c->s.mode = MODE_ERROR;
        return fmi2Error;
    }
    c->s.mode = c->type == fmi2ModelExchange ? MODE_EVENT : MODE_STEP;
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component component) {
    Instance *c = (Instance *)component;
    if (!c) return fmi2Error;
    c->s.mode = MODE_TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component component) {
    Instance *c = (Instance *)component;
    if (!c) return fmi2Error;
    memset(&c->s, 0, sizeof c->s);
    memcpy(c->s.theta, cm_theta_start, sizeof c->s.theta);
    memcpy(c->s.x, cm_x_start, sizeof c->s.x);
    memcpy(c->s.u, cm_u_start, sizeof c->s.u);
    c->rtol = CM_RTOL;
    c->atol = CM_ATOL;
    c->dx_valid = c->y_valid = 0;
    c->s.mode = MODE_INSTANTIATED;
    return fmi2OK;
}

/* ---------------------------------------------------------------- values */

static int evaluated(Instance *c) {
    return c->s.mode != MODE_INSTANTIATED;
}

static fmi2Status derivatives(Instance *c) {
    if (!c->dx_valid) {
        const double *in[3] = {&c->s.time, c->s.x, c->jd};
        double *out[1] = {c->dx};
        cm_data_update(c);
        if (cm_call(c, cm_ode, in, 3, out, 1)) return fmi2Error;
        c->dx_valid = 1;
    }
    return fmi2OK;
}

static fmi2Status outputs(Instance *c) {
    if (!c->y_valid) {
        const double *in[3] = {&c->s.time, c->s.x, c->jd};
        double *out[1] = {c->y};
        cm_data_update(c);
        if (cm_call(c, cm_outputs, in, 3, out, 1)) return fmi2Error;
        c->y_valid = 1;
    }
    return fmi2OK;
}

fmi2Status fmi2GetReal(fmi2Component component, const fmi2ValueReference vr[], size_t nvr,
                       fmi2Real value[]) {
    Instance *c = (Instance *)component;
    if (!c || (nvr && (!vr || !value))) return fmi2Error;
    for (size_t k = 0; k < nvr; ++k) {
        fmi2ValueReference r = vr[k];
        if (r < VR_X) {
            value[k] = c->s.theta[r - VR_THETA];
        } else if (r < VR_DX) {
            if (started(c) != fmi2OK) return fmi2Error;
            value[k] = c->s.x[r - VR_X];
        } else if (r < VR_U) {
            if (!evaluated(c)) return fail(c, "derivatives are known from initialization on");
            if (started(c) != fmi2OK || derivatives(c) != fmi2OK) return fmi2Error;
            value[k] = c->dx[r - VR_DX];
        } else if (r < VR_Y) {
            value[k] = c->s.u[r - VR_U];
        } else if (r < VR_C) {
            if (!evaluated(c)) return fail(c, "outputs are known from initialization on");
            if (started(c) != fmi2OK || outputs(c) != fmi2OK) return fmi2Error;
            value[k] = c->y[r - VR_Y];
        } else if (r < VR_S) {
            cm_data_update(c);
            value[k] = c->calculated[r - VR_C];
        } else if (r < VR_END) {
            value[k] = cm_structural[r - VR_S];
        } else {
            return fail(c, "fmi2GetReal: unknown value reference");
        }
    }
    return fmi2OK;
}

static fmi2Status set_parameter(Instance *c, fmi2ValueReference r, double value) {
    int k = (int)(r - VR_THETA);
    int early = c->s.mode == MODE_INSTANTIATED || c->s.mode == MODE_INITIALIZATION;
    int late = c->s.mode == MODE_EVENT || c->s.mode == MODE_STEP;
    if (!(early || (late && !cm_theta_fixed[k]))) {
        return fail(c, cm_theta_fixed[k]
                           ? "a fixed parameter (it sets the initial state) is set before the "
                             "end of initialization"
                           : "a tunable parameter is set in event mode (Model Exchange) or "
                             "between steps (Co-Simulation)");
    }
    if (c->s.theta[k] != value) {
        c->s.theta[k] = value;
        c->s.started = 0;
        c->s.data_valid = 0;
        c->dx_valid = c->y_valid = 0;
        c->s.project = late && CM_LOOPS;
    }
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component component, const fmi2ValueReference vr[], size_t nvr,
                       const fmi2Real value[]) {
    Instance *c = (Instance *)component;
    if (!c || (nvr && (!vr || !value))) return fmi2Error;
    for (size_t k = 0; k < nvr; ++k) {
        fmi2ValueReference r = vr[k];
        if (r < VR_X) {
            if (set_parameter(c, r, value[k]) != fmi2OK) return fmi2Error;
        } else if (r < VR_DX) {
            if (c->s.mode != MODE_INSTANTIATED && c->s.mode != MODE_INITIALIZATION) {
                return fail(c, "states are set before initialization ends (Model Exchange: "
                               "fmi2SetContinuousStates)");
            }
            c->s.x[r - VR_X] = value[k];
            c->s.states_given = 1;
            c->s.started = 0;
        } else if (r >= VR_U && r < VR_Y) {
            c->s.u[r - VR_U] = value[k];
            c->s.du[r - VR_U] = 0.0;
            c->s.u_time = c->s.time;
            c->dx_valid = c->y_valid = 0;
        } else {
            return fail(c, "fmi2SetReal: not a parameter, state or input");
        }
    }
    return fmi2OK;
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Integer value[]) {
    (void)vr;
    (void)value;
    return c && nvr == 0 ? fmi2OK : fmi2Error;
}
fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Boolean value[]) {
    (void)vr;
    (void)value;
    return c && nvr == 0 ? fmi2OK : fmi2Error;
}
fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         fmi2String value[]) {
    (void)vr;
    (void)value;
    return c && nvr == 0 ? fmi2OK : fmi2Error;
}
fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Integer value[]) {
    (void)vr;
    (void)value;
    return c && nvr == 0 ? fmi2OK : fmi2Error;
}
fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Boolean value[]) {
    (void)vr;
    (void)value;
    return c && nvr == 0 ? fmi2OK : fmi2Error;
}
fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         const fmi2String value[]) {
    (void)vr;
    (void)value;
    return c && nvr == 0 ? fmi2OK : fmi2Error;
}

/* ---------------------------------------------------------------- FMU state */

fmi2Status fmi2GetFMUstate(fmi2Component component, fmi2FMUstate *state) {
    Instance *c = (Instance *)component;
    Snapshot *copy;
    if (!c || !state) return fmi2Error;
    copy = *state ? (Snapshot *)*state : (Snapshot *)allocate(c, 1, sizeof(Snapshot));
    if (!copy) return fmi2Error;
    *copy = c->s;
    *state = copy;
    return fmi2OK;
}

fmi2Status fmi2SetFMUstate(fmi2Component component, fmi2FMUstate state) {
    Instance *c = (Instance *)component;
    if (!c || !state) return fmi2Error;
    c->s = *(Snapshot *)state;
    c->s.data_valid = 0;
    c->dx_valid = c->y_valid = 0;
    return fmi2OK;
}

fmi2Status fmi2FreeFMUstate(fmi2Component component, fmi2FMUstate *state) {
    Instance *c = (Instance *)component;
    if (!c || !state) return fmi2Error;
    c->functions.freeMemory(*state);
    *state = NULL;
    return fmi2OK;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate state, size_t *size) {
    if (!c || !state || !size) return fmi2Error;
    *size = sizeof(Snapshot);
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate state, fmi2Byte bytes[],
                                 size_t size) {
    if (!c || !state || size < sizeof(Snapshot)) return fmi2Error;
    memcpy(bytes, state, sizeof(Snapshot));
    return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component component, const fmi2Byte bytes[],
                                   size_t size, fmi2FMUstate *state) {
    Instance *c = (Instance *)component;
    if (!c || !state || size != sizeof(Snapshot)) return fmi2Error;
    if (!*state) *state = allocate(c, 1, sizeof(Snapshot));
    if (!*state) return fmi2Error;
    memcpy(*state, bytes, sizeof(Snapshot));
    return fmi2OK;
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference unknown[],
                                        size_t nUnknown, const fmi2ValueReference known[],
                                        size_t nKnown, const fmi2Real dvKnown[],
                                        fmi2Real dvUnknown[]) {
    (void)unknown, (void)nUnknown, (void)known, (void)nKnown, (void)dvKnown, (void)dvUnknown;
    return fail((Instance *)c, "directional derivatives are not provided");
}

/* ---------------------------------------------------------------- Model Exchange */

fmi2Status fmi2EnterEventMode(fmi2Component component) {
    Instance *c = (Instance *)component;
    if (!c || c->type != fmi2ModelExchange) return fmi2Error;
    c->s.mode = MODE_EVENT;
    return fmi2OK;
}

fmi2Status fmi2NewDiscreteStates(fmi2Component component, fmi2EventInfo *info) {
    Instance *c = (Instance *)component;
    if (!c || !info || c->s.mode != MODE_EVENT) return fmi2Error;
    info->newDiscreteStatesNeeded = fmi2False;
    info->terminateSimulation = fmi2False;
    info->nominalsOfContinuousStatesChanged = fmi2False;
    info->valuesOfContinuousStatesChanged = fmi2False;
    info->nextEventTimeDefined = fmi2False;
    info->nextEventTime = 0.0;
    if (CM_LOOPS && (c->s.project || cm_drifted(c, c->s.time))) {
        if (cm_project(c, c->s.time) != fmi2OK) return fmi2Error;
        info->valuesOfContinuousStatesChanged = fmi2True;
    }
    return fmi2OK;
}

fmi2Status fmi2EnterContinuousTimeMode(fmi2Component component) {
    Instance *c = (Instance *)component;
    if (!c || c->s.mode != MODE_EVENT) return fmi2Error;
    c->s.mode = MODE_CONTINUOUS;
    return fmi2OK;
}

fmi2Status fmi2CompletedIntegratorStep(fmi2Component component,
                                       fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi2Boolean *enterEventMode,
                                       fmi2Boolean *terminateSimulation) {
    Instance *c = (Instance *)component;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!c || !enterEventMode || !terminateSimulation) return fmi2Error;
    *enterEventMode = CM_LOOPS && cm_drifted(c, c->s.time) ? fmi2True : fmi2False;
    *terminateSimulation = fmi2False;
    return fmi2OK;
}

fmi2Status fmi2SetTime(fmi2Component component, fmi2Real time) {
    Instance *c = (Instance *)component;
    if (!c) return fmi2Error;
    c->s.time = time;
    c->dx_valid = c->y_valid = 0;
    return fmi2OK;
}

fmi2Status fmi2SetContinuousStates(fmi2Component component, const fmi2Real x[], size_t nx) {
    Instance *c = (Instance *)component;
    if (!c || nx != CM_NX || (nx && !x)) return fmi2Error;
    memcpy(c->s.x, x, sizeof(double) * nx);
    c->dx_valid = c->y_valid = 0;
    return fmi2OK;
}

fmi2Status fmi2GetDerivatives(fmi2Component component, fmi2Real dx[], size_t nx) {
    Instance *c = (Instance *)component;
    if (!c || nx != CM_NX || (nx && !dx)) return fmi2Error;
    if (derivatives(c) != fmi2OK) return fmi2Error;
    memcpy(dx, c->dx, sizeof(double) * nx);
    return fmi2OK;
}

fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real indicators[], size_t ni) {
    (void)indicators;
    return c && ni == 0 ? fmi2OK : fmi2Error;
}

fmi2Status fmi2GetContinuousStates(fmi2Component component, fmi2Real x[], size_t nx) {
    Instance *c = (Instance *)component;
    if (!c || nx != CM_NX || (nx && !x)) return fmi2Error;
    memcpy(x, c->s.x, sizeof(double) * nx);
    return fmi2OK;
}

fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real nominals[], size_t nx) {
    if (!c || nx != CM_NX || (nx && !nominals)) return fmi2Error;
    for (size_t k = 0; k < nx; ++k) nominals[k] = 1.0;
    return fmi2OK;
}

/* ---------------------------------------------------------------- Co-Simulation */

fmi2Status fmi2SetRealInputDerivatives(fmi2Component component, const fmi2ValueReference vr[],
                                       size_t nvr, const fmi2Integer order[],
                                       const fmi2Real value[]) {
    Instance *c = (Instance *)component;
    if (!c || (nvr && (!vr || !order || !value))) return fmi2Error;
    for (size_t k = 0; k < nvr; ++k) {
        if (vr[k] < VR_U || vr[k] >= VR_Y || order[k] != 1) {
            return fail(c, "input derivatives: first order, of inputs only");
        }
        c->s.du[vr[k] - VR_U] = value[k];
    }
    return fmi2OK;
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                        size_t nvr, const fmi2Integer order[],
                                        fmi2Real value[]) {
    (void)vr, (void)order, (void)value;
    return c && nvr == 0 ? fmi2OK : fmi2Error;
}

fmi2Status fmi2DoStep(fmi2Component component, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize,
                      fmi2Boolean noSetFMUStatePriorToCurrentCommunicationPoint) {
    Instance *c = (Instance *)component;
    fmi2Status status;
    (void)noSetFMUStatePriorToCurrentCommunicationPoint;
    if (!c || c->type != fmi2CoSimulation || c->s.mode != MODE_STEP) return fmi2Error;
    if (communicationStepSize < 0) return fail(c, "a negative communication step");
    if (fabs(currentCommunicationPoint - c->s.time) > 1e-9 * fmax(1.0, fabs(c->s.time))) {
        return fail(c, "the communication point is not the time the FMU is at");
    }
    c->s.time = currentCommunicationPoint;
    if (CM_LOOPS && c->s.project && cm_project(c, c->s.time) != fmi2OK) return fmi2Error;
    status = cm_integrate(c, currentCommunicationPoint + communicationStepSize);
    if (status != fmi2OK) c->s.mode = MODE_ERROR;
    /* the inputs' linear part ends with the step: hold their values at its end */
    for (int k = 0; k < CM_NU; ++k) {
        c->s.u[k] += c->s.du[k] * (c->s.time - c->s.u_time);
        c->s.du[k] = 0.0;
    }
    c->s.u_time = c->s.time;
    return status;
}

fmi2Status fmi2CancelStep(fmi2Component c) {
    (void)c;
    return fmi2Error; /* fmi2DoStep never returns fmi2Pending */
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value) {
    (void)s;
    (void)value;
    return c ? fmi2Discard : fmi2Error;
}

fmi2Status fmi2GetRealStatus(fmi2Component component, const fmi2StatusKind s, fmi2Real *value) {
    Instance *c = (Instance *)component;
    if (!c || !value) return fmi2Error;
    if (s == fmi2LastSuccessfulTime) {
        *value = c->s.time;
        return fmi2OK;
    }
    return fmi2Discard;
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value) {
    (void)s;
    (void)value;
    return c ? fmi2Discard : fmi2Error;
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value) {
    (void)s;
    (void)value;
    return c ? fmi2Discard : fmi2Error;
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value) {
    (void)s;
    (void)value;
    return c ? fmi2Discard : fmi2Error;
}
