/* A CasADi-generated function evaluated over rows in one C loop: row i reads input k at
 * in[k] + i * in_stride[k] (a stride 0: the same values for every row; in[k] NULL: zeros)
 * and writes output k at out[k] + i * out_stride[k] (out[k] NULL: not computed). What
 * casadi's map does for a function over columns, without its per-evaluation bookkeeping,
 * the function reached at its C entry point as casmech_rk.c reaches the ODE.
 */

typedef long long int casadi_int;
typedef int (*cm_eval)(const double** arg, double** res, casadi_int* iw, double* w, int mem);

/* casmech_rk.c's cm_function (backends.rk_library.Function): its i_t, i_x, i_out unread */
typedef struct {
  cm_eval eval;
  const double** arg; /* sz_arg entries: the first n_in set per row, the rest NULL */
  double** res;       /* sz_res entries: the first n_out set per row, the rest NULL */
  casadi_int* iw;
  double* w;
  int mem;
  int i_t, i_x, i_out;
} cm_function;

/* 0 when every row was evaluated, else 1 + the index of the row whose evaluation failed
 * (rows before it written) */
casadi_int casmech_rows_run(const cm_function* f, casadi_int n_rows, int n_in,
                            const double* const* in, const casadi_int* in_stride, int n_out,
                            double* const* out, const casadi_int* out_stride) {
  casadi_int i;
  int k;
  for (i = 0; i < n_rows; ++i) {
    for (k = 0; k < n_in; ++k) f->arg[k] = in[k] ? in[k] + i * in_stride[k] : 0;
    for (k = 0; k < n_out; ++k) f->res[k] = out[k] ? out[k] + i * out_stride[k] : 0;
    if (f->eval(f->arg, f->res, f->iw, f->w, f->mem)) return i + 1;
  }
  return 0;
}
