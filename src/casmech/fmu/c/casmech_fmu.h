/* casmech FMU: the instance and what casmech_fmu.c (the FMI functions) and
   casmech_fmu_solver.c (start state, projection, Co-Simulation integrator) share.

   Value references (casmech_fmu_config.h gives the counts):
     [VR_THETA, VR_X)   independent parameters (fixed or tunable)
     [VR_X, VR_DX)      states x = [joint coordinates; joint velocities]
     [VR_DX, VR_U)      their derivatives
     [VR_U, VR_Y)       inputs (effort motors, ocp controls)
     [VR_Y, VR_C)       outputs (results columns)
     [VR_C, VR_S)       calculated parameters
     [VR_S, VR_END)     structural parameters (constants)
   jd, the data the CasADi functions take, is [d; inputs; tree constants]: cm_data(theta),
   with the inputs written at CM_U_OFFSET. */
#ifndef CASMECH_FMU_H
#define CASMECH_FMU_H

#include "fmi2Functions.h"
#include "casmech_fmu_config.h"
#include "casmech_fmu_functions.h"

#define VR_THETA 0
#define VR_X (VR_THETA + CM_NP)
#define VR_DX (VR_X + CM_NX)
#define VR_U (VR_DX + CM_NX)
#define VR_Y (VR_U + CM_NU)
#define VR_C (VR_Y + CM_NY)
#define VR_S (VR_C + CM_NC)
#define VR_END (VR_S + CM_NS)

/* sizes of arrays that may be empty (C has no zero-length arrays) */
#define CM_SIZE(n) ((n) > 0 ? (n) : 1)

typedef enum {
    MODE_INSTANTIATED, MODE_INITIALIZATION, MODE_EVENT, MODE_CONTINUOUS, MODE_STEP,
    MODE_TERMINATED, MODE_ERROR
} Mode;

/* what an FMU state (fmi2GetFMUstate) holds: everything that evolves */
typedef struct {
    double time;
    double theta[CM_SIZE(CM_NP)];
    double x[CM_SIZE(CM_NX)];
    double u[CM_SIZE(CM_NU)];
    double du[CM_SIZE(CM_NU)];      /* Co-Simulation: input derivatives (fmi2SetRealInputDerivatives) */
    double u_time;                  /* the time the inputs were given at */
    double h;                       /* Co-Simulation: the integrator's next step (0: not chosen) */
    int states_given;               /* states set before initialization: start from them */
    int data_valid;                 /* jd computed from theta */
    int project;                    /* loops: project the state before going on */
    int started;                    /* the start state is computed from what was set */
    Mode mode;
} Snapshot;

typedef struct {
    Snapshot s;
    fmi2Type type;
    fmi2CallbackFunctions functions;
    char *name;
    int logging;
    double rtol, atol;
    double start_time;
    double jd[CM_SIZE(CM_NJD)];
    double dx[CM_SIZE(CM_NX)];
    double y[CM_SIZE(CM_NY)];
    double calculated[CM_SIZE(CM_NC)];
    int dx_valid, y_valid;
    long steps, rejected, projections;  /* Co-Simulation integrator statistics */
    /* integrator stages and work */
    double k[7][CM_SIZE(CM_NX)];
    double x_trial[CM_SIZE(CM_NX)], x_error[CM_SIZE(CM_NX)];
    double q_ref[CM_SIZE(CM_NQ)];
    /* the closest-point problems (casmech_fmu_solver.c): their terms, KKT matrix and pivots */
    double jacobian[CM_SIZE(CM_NQ * (CM_NTH > CM_NX - CM_NTH ? CM_NTH : CM_NX - CM_NTH))];
    double residual[CM_SIZE(CM_NQ)], target[CM_SIZE(CM_NQ)];
    double rows[CM_SIZE((CM_NCP > CM_NCV ? CM_NCP : CM_NCV) * CM_NX)];
    double values[CM_SIZE(CM_NCP > CM_NCV ? CM_NCP : CM_NCV)];
    double kkt[CM_SIZE((CM_NX + CM_NCP) * (CM_NX + CM_NCP))];
    double solution[CM_SIZE(CM_NX + CM_NCP)];
    int pivots[CM_SIZE(CM_NX + CM_NCP)];
    /* CasADi work */
    const casadi_real **arg;
    casadi_real **res;
    casadi_int *iw;
    casadi_real *w;
} Instance;

typedef int (*CmEval)(const casadi_real **, casadi_real **, casadi_int *, casadi_real *, int);

/* casmech_fmu.c */
void cm_log(Instance *c, fmi2Status status, const char *category, const char *message);
int cm_call(Instance *c, CmEval f, const double **in, int n_in, double **out, int n_out);
void cm_data_update(Instance *c);
void cm_inputs_at(Instance *c, double t);

/* casmech_fmu_solver.c */
fmi2Status cm_start_state(Instance *c);
fmi2Status cm_project(Instance *c, double t);
int cm_drifted(Instance *c, double t);
fmi2Status cm_integrate(Instance *c, double t_end);

#endif
