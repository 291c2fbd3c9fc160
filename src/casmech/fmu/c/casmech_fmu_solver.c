/* casmech FMU: the start state, the projection onto the loop closures and the
   Co-Simulation integrator.

   Start (fmi2ExitInitializationMode): Gauss-Newton steps towards the point of the tree's
   configurations, on the loop closures, closest to the file's pose at the parameters' values
   (cm_file_pose), from the start state casmech computed at its own values; then the
   velocities closest to the file's. The generated functions give each problem's residual,
   constraints and their Jacobians (cm_position_terms, cm_velocity_terms); the KKT system is
   formed and solved here (dense LU with partial pivoting). States set before initialization
   are taken as they are (with loops: projected onto the closures).

   Projection (loops): the same position problem with the current pose as the reference, then
   the velocities closest to the current ones on the closures' velocity rows.

   Co-Simulation: Dormand-Prince 5(4) (Hairer, Norsett, Wanner, Solving ODEs I, II.4 and
   II.5): the 5th-order solution is kept, the embedded 4th-order one estimates the error;
   a step is accepted when the error's RMS, weighted by atol + rtol |x|, is at most 1, and the
   next step is 0.9 err^(-1/5) times this one (between 0.2 and 5 times). Inputs are linear in
   time within a communication step (their derivatives from fmi2SetRealInputDerivatives). With
   loops the state is projected after a step whenever the closures drifted past CM_DRIFT. */
#include <math.h>
#include <string.h>
#include <stdio.h>

#include "casmech_fmu.h"

#define MAX_NEWTON 100        /* Gauss-Newton steps of a start or a projection */
#define NEWTON_TOL 1e-12      /* largest step at convergence (joint coordinates: rad or m) */
#define CLOSED_TOL 1e-8       /* largest closure residual accepted after a projection */
#define MAX_STEPS 1000000     /* integrator steps in one fmi2DoStep */
#define MIN_STEP 1e-14        /* relative to the time */

/* Solve the dense K x K system a z = b in place (a row-major, b becomes z) by LU with
   partial pivoting; nonzero when a pivot vanishes (a singular configuration). */
static int lu_solve(int k, double *a, double *b, int *pivots) {
    for (int j = 0; j < k; ++j) {
        int p = j;
        double scale = 0.0;
        for (int i = 0; i < k; ++i) scale = fmax(scale, fabs(a[i * k + j]));
        for (int i = j + 1; i < k; ++i) {
            if (fabs(a[i * k + j]) > fabs(a[p * k + j])) p = i;
        }
        if (!(fabs(a[p * k + j]) > 1e-14 * fmax(scale, 1e-300))) return 1;
        pivots[j] = p;
        if (p != j) {
            for (int c = 0; c < k; ++c) {
                double swap = a[j * k + c];
                a[j * k + c] = a[p * k + c];
                a[p * k + c] = swap;
            }
            double swap = b[j];
            b[j] = b[p];
            b[p] = swap;
        }
        for (int i = j + 1; i < k; ++i) {
            double factor = a[i * k + j] / a[j * k + j];
            if (factor == 0.0) continue;
            for (int c = j; c < k; ++c) a[i * k + c] -= factor * a[j * k + c];
            b[i] -= factor * b[j];
        }
    }
    for (int i = k - 1; i >= 0; --i) {
        double sum = b[i];
        for (int c = i + 1; c < k; ++c) sum -= a[i * k + c] * b[c];
        b[i] = sum / a[i * k + i];
    }
    return 0;
}

/* delta minimizing |r + J delta|^2 subject to v + R delta = 0 (J: nq x n, R: m x n, both
   column-major as CasADi writes them), from the KKT system
   [J^T J, R^T; R, 0] [delta; mu] = -[J^T r; v]; delta in c->solution[0..n). */
static fmi2Status least_squares(Instance *c, int n, int m, const double *r) {
    int k = n + m, nq = CM_NQ;
    double *a = c->kkt, *b = c->solution;
    const double *jac = c->jacobian, *rows = c->rows;
    for (int i = 0; i < n; ++i) {
        for (int j = 0; j <= i; ++j) {
            double sum = 0.0;
            for (int q = 0; q < nq; ++q) sum += jac[i * nq + q] * jac[j * nq + q];
            a[i * k + j] = a[j * k + i] = sum;
        }
        double gradient = 0.0;
        for (int q = 0; q < nq; ++q) gradient += jac[i * nq + q] * r[q];
        b[i] = -gradient;
        for (int row = 0; row < m; ++row) {
            a[(n + row) * k + i] = a[i * k + n + row] = rows[i * m + row];
        }
    }
    for (int row = 0; row < m; ++row) {
        for (int col = 0; col < m; ++col) a[(n + row) * k + n + col] = 0.0;
        b[n + row] = -c->values[row];
    }
    if (lu_solve(k, a, b, c->pivots)) {
        cm_log(c, fmi2Error, "logStatusError", "the closest configuration is not defined here "
               "(a singular pose: the closures' rows lost rank)");
        return fmi2Error;
    }
    return fmi2OK;
}

/* Gauss-Newton on the position problem towards q_ref (the module comment) */
static fmi2Status closest(Instance *c, double t, const double *q_ref) {
    for (int k = 0; k < MAX_NEWTON; ++k) {
        double step = 0.0;
        const double *in[4] = {&t, c->s.x, c->jd, q_ref};
        double *out[4] = {c->jacobian, c->residual, c->rows, c->values};
        if (CM_NTH == 0) return fmi2OK;
        if (cm_call(c, cm_position_terms, in, 4, out, 4)) return fmi2Error;
        if (least_squares(c, CM_NTH, CM_NCP, c->residual) != fmi2OK) return fmi2Error;
        for (int i = 0; i < CM_NTH; ++i) {
            if (!isfinite(c->solution[i])) {
                cm_log(c, fmi2Error, "logStatusError", "the closest configuration could not be "
                       "found (the closures cannot be met at these parameter values?)");
                return fmi2Error;
            }
            c->s.x[i] += c->solution[i];
            step = fmax(step, fabs(c->solution[i]));
        }
        if (step <= NEWTON_TOL) return fmi2OK;
    }
    cm_log(c, fmi2Error, "logStatusError", "the closest configuration did not converge in "
           "100 Gauss-Newton steps");
    return fmi2Error;
}

/* the velocities closest to the file's (file != 0) or to the current ones, on the closures */
static fmi2Status velocity(Instance *c, double t, int file) {
    int n = CM_NX - CM_NTH;
    const double *in[3] = {&t, c->s.x, c->jd};
    double *out[5] = {c->jacobian, c->residual, c->rows, c->values, c->target};
    if (n == 0) return fmi2OK;
    if (cm_call(c, cm_velocity_terms, in, 3, out, 5)) return fmi2Error;
    if (!file) {  /* the current rates: jacobian u + base */
        for (int q = 0; q < CM_NQ; ++q) {
            double sum = c->residual[q];
            for (int i = 0; i < n; ++i) sum += c->jacobian[i * CM_NQ + q] * c->s.x[CM_NTH + i];
            c->target[q] = sum;
        }
    }
    for (int q = 0; q < CM_NQ; ++q) c->residual[q] -= c->target[q];  /* base - target */
    if (least_squares(c, n, CM_NCV, c->residual) != fmi2OK) return fmi2Error;
    memcpy(c->s.x + CM_NTH, c->solution, sizeof(double) * (size_t)n);
    return fmi2OK;
}

static fmi2Status closed(Instance *c, double t) {
    double position = 0.0, rate = 0.0;
    const double *in[3] = {&t, c->s.x, c->jd};
    double *out[2] = {&position, &rate};
    if (cm_call(c, cm_drift, in, 3, out, 2)) return fmi2Error;
    if (!(position <= CLOSED_TOL && rate <= CLOSED_TOL)) {
        char message[160];
        snprintf(message, sizeof message, "the loop closures are not met after the projection "
                 "(position %.3g, velocity %.3g): a singular pose?", position, rate);
        cm_log(c, fmi2Error, "logStatusError", message);
        return fmi2Error;
    }
    return fmi2OK;
}

fmi2Status cm_project(Instance *c, double t) {
    const double *in[3] = {&t, c->s.x, c->jd};
    double *out[1] = {c->q_ref};
    cm_data_update(c);
    if (cm_call(c, cm_tree_pose, in, 3, out, 1)) return fmi2Error;
    if (closest(c, t, c->q_ref) != fmi2OK) return fmi2Error;
    if (velocity(c, t, 0) != fmi2OK) return fmi2Error;
    c->projections += 1;
    c->dx_valid = c->y_valid = 0;
    c->s.project = 0;
    return closed(c, t);
}

int cm_drifted(Instance *c, double t) {
    double position = 0.0, rate = 0.0;
    const double *in[3] = {&t, c->s.x, c->jd};
    double *out[2] = {&position, &rate};
    if (!CM_LOOPS) return 0;
    cm_data_update(c);
    if (cm_call(c, cm_drift, in, 3, out, 2)) return 1;
    return !(position <= CM_DRIFT && rate <= CM_DRIFT);
}

fmi2Status cm_start_state(Instance *c) {
    double t = c->s.time;
    cm_data_update(c);
    c->dx_valid = c->y_valid = 0;
    if (c->s.states_given) return CM_LOOPS ? cm_project(c, t) : fmi2OK;
    {
        const double *in[1] = {c->jd};
        double *out[1] = {c->q_ref};
        if (cm_call(c, cm_file_pose, in, 1, out, 1)) return fmi2Error;
    }
    if (closest(c, t, c->q_ref) != fmi2OK) return fmi2Error;
    if (velocity(c, t, 1) != fmi2OK) return fmi2Error;
    return CM_LOOPS ? closed(c, t) : fmi2OK;
}

/* ---------------------------------------------------------------- Dormand-Prince 5(4) */

static const double C[7] = {0.0, 1.0 / 5, 3.0 / 10, 4.0 / 5, 8.0 / 9, 1.0, 1.0};
static const double A[7][6] = {
    {0},
    {1.0 / 5},
    {3.0 / 40, 9.0 / 40},
    {44.0 / 45, -56.0 / 15, 32.0 / 9},
    {19372.0 / 6561, -25360.0 / 2187, 64448.0 / 6561, -212.0 / 729},
    {9017.0 / 3168, -355.0 / 33, 46732.0 / 5247, 49.0 / 176, -5103.0 / 18656},
    {35.0 / 384, 0.0, 500.0 / 1113, 125.0 / 192, -2187.0 / 6784, 11.0 / 84}};
/* the 5th-order weights are A[6]; E: 5th minus embedded 4th order */
static const double E[7] = {71.0 / 57600, 0.0, -71.0 / 16695, 71.0 / 1920, -17253.0 / 339200,
                            22.0 / 525, -1.0 / 40};

static int rhs(Instance *c, double t, const double *x, double *dx) {
    const double *in[3] = {&t, x, c->jd};
    double *out[1] = {dx};
    cm_inputs_at(c, t);
    return cm_call(c, cm_ode, in, 3, out, 1);
}

static double weighted_norm(Instance *c, const double *v, const double *x, const double *x_new) {
    double sum = 0.0;
    for (int i = 0; i < CM_NX; ++i) {
        double scale = c->atol + c->rtol * fmax(fabs(x[i]), fabs(x_new[i]));
        sum += (v[i] / scale) * (v[i] / scale);
    }
    return CM_NX ? sqrt(sum / CM_NX) : 0.0;
}

/* Hairer's initial step (Solving ODEs I, II.4): from the sizes of x, x' and x'' */
static double initial_step(Instance *c, double t, double span) {
    double *x = c->s.x, *f0 = c->k[0], *f1 = c->k[1], *x1 = c->x_trial;
    double d0 = weighted_norm(c, x, x, x), d1 = weighted_norm(c, f0, x, x), h0, h1, d2;
    h0 = (d0 < 1e-5 || d1 < 1e-5) ? 1e-6 : 0.01 * d0 / d1;
    h0 = fmin(h0, span);
    for (int i = 0; i < CM_NX; ++i) x1[i] = x[i] + h0 * f0[i];
    if (rhs(c, t + h0, x1, f1)) return h0;
    for (int i = 0; i < CM_NX; ++i) c->x_error[i] = f1[i] - f0[i];
    d2 = weighted_norm(c, c->x_error, x, x) / h0;
    h1 = fmax(d1, d2) <= 1e-15 ? fmax(1e-6, h0 * 1e-3) : pow(0.01 / fmax(d1, d2), 0.2);
    /* Hairer's min(100 h0, h1), but within 4 orders of h1: a state of round-off (1e-17
       where atol is 1e-12) makes h0 vanish */
    return fmin(fmax(fmin(100 * h0, h1), 1e-4 * h1), span);
}

fmi2Status cm_integrate(Instance *c, double t_end) {
    double t = c->s.time, h = c->s.h;
    int fresh = 0; /* k[0] holds f(t, x) */
    long taken = 0;
    cm_data_update(c);
    if (CM_NX == 0) {  /* every coordinate prescribed: nothing to integrate */
        c->s.time = t_end;
        c->dx_valid = c->y_valid = 0;
        return fmi2OK;
    }
    while (t_end - t > MIN_STEP * fmax(1.0, fabs(t_end))) {
        double err, factor;
        if (!fresh) {
            if (rhs(c, t, c->s.x, c->k[0])) return fmi2Error;
            fresh = 1;
        }
        double wanted;
        if (h <= 0.0) h = initial_step(c, t, t_end - t);
        wanted = h;
        if (t + 1.01 * h >= t_end) h = t_end - t;
        for (int stage = 1; stage < 7; ++stage) {
            for (int i = 0; i < CM_NX; ++i) {
                double sum = 0.0;
                for (int j = 0; j < stage; ++j) sum += A[stage][j] * c->k[j][i];
                c->x_trial[i] = c->s.x[i] + h * sum;
            }
            if (rhs(c, t + C[stage] * h, c->x_trial, c->k[stage])) return fmi2Error;
        }
        /* x_trial is the 5th-order solution (stage 7 is evaluated there: FSAL) */
        for (int i = 0; i < CM_NX; ++i) {
            double sum = 0.0;
            for (int j = 0; j < 7; ++j) sum += E[j] * c->k[j][i];
            c->x_error[i] = h * sum;
        }
        err = weighted_norm(c, c->x_error, c->s.x, c->x_trial);
        if (!isfinite(err)) {
            err = 1e10;
        }
        factor = err > 0.0 ? 0.9 * pow(err, -0.2) : 5.0;
        if (err <= 1.0) {
            t += h;
            memcpy(c->s.x, c->x_trial, sizeof(double) * CM_NX);
            memcpy(c->k[0], c->k[6], sizeof(double) * CM_NX);
            c->steps += 1;
            c->s.time = t;
            if (CM_LOOPS && cm_drifted(c, t)) {
                if (cm_project(c, t) != fmi2OK) return fmi2Error;
                fresh = 0;
            }
            h = fmax(h * fmin(5.0, fmax(0.2, factor)), factor >= 1.0 ? wanted : 0.0);
        } else {
            c->rejected += 1;
            h *= fmin(1.0, fmax(0.2, factor));
        }
        if (++taken > MAX_STEPS || (err > 1.0 && h < MIN_STEP * fmax(1.0, fabs(t)))) {
            char message[200];
            snprintf(message, sizeof message, "the integrator stopped at t = %.9g: %s", t,
                     taken > MAX_STEPS ? "too many steps in one communication step"
                                       : "the step size fell below the round-off of t");
            cm_log(c, fmi2Error, "logStatusError", message);
            return fmi2Error;
        }
    }
    c->s.time = t_end;
    c->s.h = h;
    c->dx_valid = c->y_valid = 0;
    return fmi2OK;
}
