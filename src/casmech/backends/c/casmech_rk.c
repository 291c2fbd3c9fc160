/* An adaptive explicit Runge-Kutta pair with dense output over an output grid: the steps of
 * scipy.integrate's RungeKutta solvers (DOP853: Hairer's 8th-order method, its 5th- and
 * 3rd-order error estimates and 7th-order interpolant), with the tableau passed in by the
 * caller (casmech.numerics.dop853_tableau: scipy's tables), calling CasADi-generated functions
 * through their C entry points. One call integrates from (t0, y0) to the last output time.
 *
 * The step controller is scipy's: the initial step of select_initial_step, the error norm of
 * DOP853._estimate_error_norm, SAFETY, MIN_FACTOR and MAX_FACTOR, no growth after a rejection,
 * the step clipped to the end time, failure below 10 ulps of t. Output times in (t_old, t]
 * of an accepted step are interpolated from that step. An optional projection maps each
 * accepted step's end state (and each interpolated output) onto a manifold; the derivative the
 * next step starts from is evaluated again at the projected state.
 *
 * With hermite_below > 0 (and no projection), an output step after the call's first takes its
 * outputs from the quintic Hermite interpolant through (y, f) at the step's ends and the previous
 * step's start where the estimate of the embedded cubic/quintic pair is below hermite_below,
 * without the interpolant's extra evaluations (casmech.numerics.hermite_pair, the same formulas).
 */
#include <math.h>
#include <string.h>

typedef long long int casadi_int;
typedef int (*cm_eval)(const double** arg, double** res, casadi_int* iw, double* w, int mem);

/* a CasADi function (t, x, ...) -> (out, ...) with its work vectors */
typedef struct {
  cm_eval eval;
  const double** arg; /* its sz_arg inputs: those not t or x NULL (zero) */
  double** res;       /* its sz_res outputs: those not out NULL (not computed) */
  casadi_int* iw;
  double* w;
  int mem;
  int i_t, i_x, i_out; /* positions of t (-1: none), x and the output */
} cm_function;

typedef struct {
  int n_stages;       /* stages of the step (scipy's n_stages) */
  int n_extended;     /* stages with the interpolant's extra ones */
  int n_dense;        /* rows of d */
  const double* a;    /* n_extended x n_extended, row-major */
  const double* b;    /* n_stages */
  const double* c;    /* n_extended */
  const double* e3;   /* n_stages + 1 */
  const double* e5;   /* n_stages + 1 */
  const double* d;    /* n_dense x n_extended */
  double error_order; /* the error estimator's order */
} cm_tableau;

typedef struct {
  double rtol, atol, max_step, first_step; /* first_step <= 0: chosen */
  double safety, min_factor, max_factor;
  casadi_int max_steps;                    /* accepted steps between output times */
  double hermite_below;                    /* the Hermite pair's threshold; 0: never */
} cm_settings;

enum { CM_DONE = 0, CM_TOO_SMALL = 1, CM_MAX_STEPS = 2, CM_EVAL_FAILED = 3, CM_NOT_FINITE = 4 };
enum { S_ACCEPTED, S_REJECTED, S_EVALUATIONS, S_OUTPUTS, S_PROJECTIONS, S_HERMITE, S_COUNT };

/* f at (t, x) into out (not x), counted in *count; a failure or an output not finite */
static int call(cm_function* f, double t, const double* x, double* out, casadi_int* count,
                int n) {
  int k;
  if (f->i_t >= 0) f->arg[f->i_t] = &t;
  f->arg[f->i_x] = x;
  f->res[f->i_out] = out;
  ++*count;
  if (f->eval(f->arg, f->res, f->iw, f->w, f->mem)) return CM_EVAL_FAILED;
  for (k = 0; k < n; ++k)
    if (!isfinite(out[k])) return CM_NOT_FINITE;
  return CM_DONE;
}

static double rms(const double* v, const double* scale, int n) {
  double sum = 0;
  int k;
  for (k = 0; k < n; ++k) sum += (v[k] / scale[k]) * (v[k] / scale[k]);
  return sqrt(sum) / sqrt((double)n);
}

/* y + h sum_j coef[j] K[j] over the first s stages */
static void combine(double* out, const double* y, const double* K, const double* coef, int s,
                    double h, int n) {
  int j, k;
  for (k = 0; k < n; ++k) {
    double sum = 0;
    for (j = 0; j < s; ++j) sum += K[j * n + k] * coef[j];
    out[k] = y[k] + sum * h;
  }
}

/* scipy's select_initial_step; f1 is work of n, ytmp too */
static int initial_step(cm_function* ode, double t0, const double* y0, const double* f0,
                        double t_bound, const cm_settings* set, double order, double* ytmp,
                        double* f1, double* scale, casadi_int* stats, int n, double* h_out) {
  double interval = t_bound - t0, d0, d1, d2, h0, h1, sum = 0;
  int k, status;
  if (interval == 0) { *h_out = 0; return CM_DONE; }
  for (k = 0; k < n; ++k) scale[k] = set->atol + fabs(y0[k]) * set->rtol;
  d0 = rms(y0, scale, n);
  d1 = rms(f0, scale, n);
  h0 = (d0 < 1e-5 || d1 < 1e-5) ? 1e-6 : 0.01 * d0 / d1;
  if (h0 > interval) h0 = interval;
  for (k = 0; k < n; ++k) ytmp[k] = y0[k] + h0 * f0[k];
  status = call(ode, t0 + h0, ytmp, f1, stats + S_EVALUATIONS, n);
  if (status) return status;
  for (k = 0; k < n; ++k) {
    double v = (f1[k] - f0[k]) / scale[k];
    sum += v * v;
  }
  d2 = sqrt(sum) / sqrt((double)n) / h0;
  if (d1 <= 1e-15 && d2 <= 1e-15) h1 = fmax(1e-6, h0 * 1e-3);
  else h1 = pow(0.01 / fmax(d1, d2), 1 / (order + 1));
  *h_out = fmin(fmin(100 * h0, h1), fmin(interval, set->max_step));
  return CM_DONE;
}

/* DOP853's error norm (scipy's DOP853._estimate_error_norm) */
static double error_norm(const cm_tableau* tab, const double* K, double h, const double* scale,
                         int n) {
  double n5 = 0, n3 = 0;
  int j, k;
  for (k = 0; k < n; ++k) {
    double e5 = 0, e3 = 0;
    for (j = 0; j <= tab->n_stages; ++j) {
      e5 += K[j * n + k] * tab->e5[j];
      e3 += K[j * n + k] * tab->e3[j];
    }
    e5 /= scale[k];
    e3 /= scale[k];
    n5 += e5 * e5;
    n3 += e3 * e3;
  }
  if (n5 == 0 && n3 == 0) return 0;
  return fabs(h) * n5 / sqrt((n5 + 0.01 * n3) * n);
}

/* the step's interpolant F (7 x n) from its stages, the extra ones evaluated into K */
static int dense(const cm_tableau* tab, cm_function* ode, double t_old, double h,
                 const double* y_old, const double* y, const double* f, double* K, double* F,
                 double* ytmp, casadi_int* stats, int n) {
  int s, r, j, k, status;
  for (s = tab->n_stages + 1; s < tab->n_extended; ++s) {
    combine(ytmp, y_old, K, tab->a + s * tab->n_extended, s, h, n);
    status = call(ode, t_old + tab->c[s] * h, ytmp, K + s * n, stats + S_EVALUATIONS, n);
    if (status) return status;
  }
  for (k = 0; k < n; ++k) {
    double delta = y[k] - y_old[k];
    F[k] = delta;
    F[n + k] = h * K[k] - delta;
    F[2 * n + k] = 2 * delta - h * (f[k] + K[k]);
  }
  for (r = 0; r < tab->n_dense; ++r)
    for (k = 0; k < n; ++k) {
      double sum = 0;
      for (j = 0; j < tab->n_extended; ++j)
        sum += tab->d[r * tab->n_extended + j] * K[j * n + k];
      F[(3 + r) * n + k] = h * sum;
    }
  return CM_DONE;
}

/* the interpolant at t (scipy's Dop853DenseOutput) */
static void interpolate(const cm_tableau* tab, const double* F, double t_old, double h,
                        const double* y_old, double t, double* out, int n) {
  double x = (t - t_old) / h;
  int rows = 3 + tab->n_dense, i, k;
  for (k = 0; k < n; ++k) {
    double y = 0;
    for (i = 0; i < rows; ++i) {
      y += F[(rows - 1 - i) * n + k];
      y *= (i % 2 == 0) ? x : 1 - x;
    }
    out[k] = y + y_old[k];
  }
}

/* the Hermite pair (m0, c2, c3, alpha, beta) into P (5 x n) over the step from (y, f) to
 * (y_new, f_new) of size h after one from (y_prev, f_prev) of size h_prev; returns its estimate
 * (casmech.numerics.hermite_pair.coefficients and estimate) */
static double hermite_pair(const double* y_prev, const double* f_prev, const double* y,
                           const double* f, const double* y_new, const double* f_new,
                           double h_prev, double h, const cm_settings* set, double* P, int n) {
  double r = h_prev / h, g = r * r * (1 + r) * (1 + r), g_slope = -2 * r * (1 + r) * (1 + 2 * r);
  double sum = 0;
  int k;
  for (k = 0; k < n; ++k) {
    double m0 = h * f[k], m1 = h * f_new[k], delta = y_new[k] - y[k];
    double c2 = 3 * delta - 2 * m0 - m1, c3 = m0 + m1 - 2 * delta;
    double d0 = y_prev[k] - (y[k] - r * m0 + r * r * c2 - r * r * r * c3);
    double d1 = h * f_prev[k] - (m0 - 2 * r * c2 + 3 * r * r * c3);
    double beta = (d1 - g_slope * d0 / g) / g, alpha = d0 / g + r * beta;
    double bound = fmax(fabs(alpha), fabs(alpha + beta)) / 16;
    double scale = set->atol + set->rtol * fmax(fabs(y[k]), fabs(y_new[k]));
    P[k] = m0;
    P[n + k] = c2;
    P[2 * n + k] = c3;
    P[3 * n + k] = alpha;
    P[4 * n + k] = beta;
    sum += (bound / scale) * (bound / scale);
  }
  return sqrt(sum / n) * fmax(1.0, r);
}

/* the pair's quintic at s = (t - t_old) / h */
static void quintic(const double* P, const double* y_old, double s, double* out, int n) {
  double g = s * s * (s - 1) * (s - 1);
  int k;
  for (k = 0; k < n; ++k)
    out[k] = y_old[k] + s * (P[k] + s * (P[n + k] + s * P[2 * n + k]))
             + g * (P[3 * n + k] + P[4 * n + k] * s);
}

/* Integrate from (t0, y0) to times[n_times - 1], writing the state at each of times (all after
 * t0, increasing) into out (n_times x n, row-major). work: (n_extended + 3 + n_dense + 8) n
 * doubles. stats: S_COUNT counters; *t_reached: the last accepted time. Returns CM_DONE or the
 * failure (the outputs before it are written: stats[S_OUTPUTS] of them). */
int casmech_rk_run(const cm_tableau* tab, const cm_settings* set, cm_function* ode,
                   cm_function* project, int n, double t0, const double* y0, int n_times,
                   const double* times, double* out, double* work, casadi_int* stats,
                   double* t_reached) {
  double *K = work, *F = K + tab->n_extended * n, *y = F + (3 + tab->n_dense) * n;
  double *y_new = y + n, *y_old = y_new + n, *f = y_old + n, *ytmp = f + n, *scale = ytmp + n;
  double *y_prev = scale + n, *f_prev = y_prev + n, h_prev = 0; /* h_prev 0: no step before */
  double t = t0, t_bound = times[n_times - 1], h_abs, exponent = -1 / (tab->error_order + 1);
  int next = 0, status, k, s;
  casadi_int since_output = 0;
  memset(stats, 0, S_COUNT * sizeof(casadi_int));
  *t_reached = t0;
  memcpy(y, y0, n * sizeof(double));
  if ((status = call(ode, t, y, f, stats + S_EVALUATIONS, n))) return status;
  if (set->first_step > 0) h_abs = fmin(set->first_step, t_bound - t0);
  else if ((status = initial_step(ode, t, y, f, t_bound, set, tab->error_order, ytmp, y_new,
                                  scale, stats, n, &h_abs)))
    return status;
  while (next < n_times) {
    double min_step = 10 * fabs(nextafter(t, INFINITY) - t), h, t_new, err;
    int rejected = 0;
    if (t == t_bound) break; /* a grid point not after t0: none left but t_bound itself */
    if (h_abs > set->max_step) h_abs = set->max_step;
    else if (h_abs < min_step) h_abs = min_step;
    if (since_output >= set->max_steps) return CM_MAX_STEPS;
    for (;;) {
      if (h_abs < min_step) return CM_TOO_SMALL;
      h = h_abs;
      t_new = t + h;
      if (t_new > t_bound) t_new = t_bound;
      h = t_new - t;
      h_abs = fabs(h);
      memcpy(K, f, n * sizeof(double));
      for (s = 1; s < tab->n_stages; ++s) {
        combine(ytmp, y, K, tab->a + s * tab->n_extended, s, h, n);
        status = call(ode, t + tab->c[s] * h, ytmp, K + s * n, stats + S_EVALUATIONS, n);
        if (status) return status;
      }
      combine(y_new, y, K, tab->b, tab->n_stages, h, n);
      status = call(ode, t + h, y_new, K + tab->n_stages * n, stats + S_EVALUATIONS, n);
      if (status) return status;
      for (k = 0; k < n; ++k)
        scale[k] = set->atol + fmax(fabs(y[k]), fabs(y_new[k])) * set->rtol;
      err = error_norm(tab, K, h, scale, n);
      if (err < 1) {
        double factor = err == 0 ? set->max_factor
                                 : fmin(set->max_factor, set->safety * pow(err, exponent));
        if (rejected && factor > 1) factor = 1;
        h_abs *= factor;
        break;
      }
      h_abs *= fmax(set->min_factor, set->safety * pow(err, exponent));
      rejected = 1;
      stats[S_REJECTED]++;
    }
    stats[S_ACCEPTED]++;
    since_output++;
    memcpy(y_old, y, n * sizeof(double));
    memcpy(y, y_new, n * sizeof(double));
    memcpy(f, K + tab->n_stages * n, n * sizeof(double));
    if (next < n_times && times[next] <= t_new) {
      /* K's first stage: f at t_old; F holds the pair's rows where it is taken */
      int pair = h_prev > 0 && set->hermite_below > 0 && !project
                 && hermite_pair(y_prev, f_prev, y_old, K, y, f, h_prev, h, set, F, n)
                        < set->hermite_below;
      if (pair) stats[S_HERMITE]++;
      else if ((status = dense(tab, ode, t, h, y_old, y, f, K, F, ytmp, stats, n)))
        return status;
      since_output = 0;
      for (; next < n_times && times[next] <= t_new; ++next) {
        if (pair) quintic(F, y_old, (times[next] - t) / h, out + (casadi_int)next * n, n);
        else interpolate(tab, F, t, h, y_old, times[next], out + (casadi_int)next * n, n);
        if (project) {
          memcpy(ytmp, out + (casadi_int)next * n, n * sizeof(double));
          if ((status = call(project, times[next], ytmp, out + (casadi_int)next * n,
                             stats + S_PROJECTIONS, n)))
            return status;
        }
        stats[S_OUTPUTS] = next + 1;
      }
    }
    memcpy(y_prev, y_old, n * sizeof(double));
    memcpy(f_prev, K, n * sizeof(double));
    h_prev = h;
    t = t_new;
    *t_reached = t;
    if (project) {
      memcpy(ytmp, y, n * sizeof(double));
      if ((status = call(project, t, ytmp, y, stats + S_PROJECTIONS, n))) return status;
      if ((status = call(ode, t, y, f, stats + S_EVALUATIONS, n))) return status;
    }
  }
  return CM_DONE;
}
