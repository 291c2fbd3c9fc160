/* Evaluate a compiled casmech model's constraints Phi(t, q) and Jacobian Phi_q(t, q) in plain C.
 *
 *   casmech compile models/four_bar.yaml -o build
 *   gcc -std=c99 -Wall -Werror -Ibuild evaluate_phi.c -Lbuild -lcasmech_model \
 *       -Wl,-rpath,'$ORIGIN/build' -o evaluate_phi
 *   ./evaluate_phi T Q1 Q2 ... QN       (N = 7 x bodies; no Q: the zero vector)
 *
 * Prints "phi I VALUE" per row and "phi_q I J VALUE" per structural nonzero (0-based), values
 * with 17 significant digits. Uses only the casadi C API of the generated library:
 * NAME_work (buffer sizes), NAME_sparsity_in/out (compressed column), NAME_checkout/release
 * (thread-safe memory) and NAME(arg, res, iw, w, mem).
 */
#include <stdio.h>
#include <stdlib.h>

#include "casmech_model.h"

typedef int (*evaluate_t)(const casadi_real **, casadi_real **, casadi_int *, casadi_real *, int);
typedef int (*work_t)(casadi_int *, casadi_int *, casadi_int *, casadi_int *);

/* Calls f(t, q) with its own work buffers; the first output, `nnz` values, into out. */
static int call(evaluate_t f, work_t work, int (*checkout)(void), void (*release)(int),
                double t, const double *q, double *out) {
  casadi_int n_arg, n_res, n_iw, n_w;
  if (work(&n_arg, &n_res, &n_iw, &n_w)) return 1;
  const casadi_real **arg = malloc((n_arg > 2 ? n_arg : 2) * sizeof *arg);
  casadi_real **res = malloc((n_res > 1 ? n_res : 1) * sizeof *res);
  casadi_int *iw = malloc((n_iw > 0 ? n_iw : 1) * sizeof *iw);
  casadi_real *w = malloc((n_w > 0 ? n_w : 1) * sizeof *w);
  arg[0] = &t;
  arg[1] = q;
  res[0] = out;
  int mem = checkout();
  int flag = f(arg, res, iw, w, mem);
  release(mem);
  free(arg);
  free(res);
  free(iw);
  free(w);
  return flag;
}

int main(int argc, char **argv) {
  const casadi_int *q_sp = phi_sparsity_in(1);  /* [rows, cols, colind..., row...] */
  const casadi_int *phi_sp = phi_sparsity_out(0);
  const casadi_int *jac_sp = phi_q_sparsity_out(0);
  casadi_int n_q = q_sp[0], n_phi = phi_sp[0], n_cols = jac_sp[1];
  casadi_int jac_nnz = jac_sp[2 + n_cols];
  double t = argc > 1 ? atof(argv[1]) : 0.0;
  double *q = calloc(n_q > 0 ? n_q : 1, sizeof *q);
  double *phi_values = calloc(n_phi > 0 ? n_phi : 1, sizeof *phi_values);
  double *jac_values = calloc(jac_nnz > 0 ? jac_nnz : 1, sizeof *jac_values);
  if (argc > 2 && argc - 2 != n_q) {
    fprintf(stderr, "expected %lld coordinates, got %d\n", (long long)n_q, argc - 2);
    return 2;
  }
  for (casadi_int k = 0; k < n_q && argc > 2; ++k) q[k] = atof(argv[2 + k]);
  phi_incref();
  phi_q_incref();
  if (call(phi, phi_work, phi_checkout, phi_release, t, q, phi_values) ||
      call(phi_q, phi_q_work, phi_q_checkout, phi_q_release, t, q, jac_values)) {
    fprintf(stderr, "evaluation failed\n");
    return 1;
  }
  for (casadi_int i = 0; i < n_phi; ++i)  /* phi is a dense column */
    printf("phi %lld %.17g\n", (long long)i, phi_values[i]);
  const casadi_int *colind = jac_sp + 2, *row = jac_sp + 3 + n_cols;
  for (casadi_int j = 0; j < n_cols; ++j)
    for (casadi_int k = colind[j]; k < colind[j + 1]; ++k)
      printf("phi_q %lld %lld %.17g\n", (long long)row[k], (long long)j, jac_values[k]);
  phi_decref();
  phi_q_decref();
  free(q);
  free(phi_values);
  free(jac_values);
  return 0;
}
