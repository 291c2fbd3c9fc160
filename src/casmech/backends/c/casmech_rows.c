/* A CasADi-generated function evaluated over rows in C loops, as a chain of parts (one part:
 * the function itself; backends.split.parts: part p reads the function's inputs and what the
 * parts before it shared, and writes its own shared values, the last part the outputs), each
 * part over all the rows before the next, so that one part's machine code is run at a time.
 * Row i reads input k at in[k] + i * in_stride[k] (a stride 0: the same values for every row;
 * in[k] NULL: zeros), part p's shared values at shared[p] + i * shared_size[p], and writes
 * output k at out[k] + i * out_stride[k] (out[k] NULL: not computed). What casadi's map does
 * for a function over columns, without its per-evaluation bookkeeping, the parts reached at
 * their C entry points as casmech_rk.c reaches the ODE.
 */

typedef long long int casadi_int;
typedef int (*cm_eval)(const double** arg, double** res, casadi_int* iw, double* w, int mem);

/* casmech_rk.c's cm_function (backends.rk_library.Function): its i_t, i_x, i_out unread */
typedef struct {
  cm_eval eval;
  const double** arg; /* sz_arg entries: the first n_in (+ the part's shared) set per row */
  double** res;       /* sz_res entries: the first n_out (1 but in the last part) set per row */
  casadi_int* iw;
  double* w;
  int mem;
  int i_t, i_x, i_out;
} cm_function;

/* 0 when every row was evaluated, else 1 + the index of the row whose evaluation failed (in
 * the first part that failed; the outputs incomplete) */
casadi_int casmech_rows_run(int n_parts, const cm_function* parts, casadi_int n_rows, int n_in,
                            const double* const* in, const casadi_int* in_stride,
                            double* const* shared, const casadi_int* shared_size, int n_out,
                            double* const* out, const casadi_int* out_stride) {
  casadi_int i;
  int k, p;
  for (p = 0; p < n_parts; ++p) {
    const cm_function* f = parts + p;
    for (i = 0; i < n_rows; ++i) {
      for (k = 0; k < n_in; ++k) f->arg[k] = in[k] ? in[k] + i * in_stride[k] : 0;
      for (k = 0; k < p; ++k) f->arg[n_in + k] = shared[k] + i * shared_size[k];
      if (p + 1 < n_parts) {
        f->res[0] = shared[p] + i * shared_size[p];
      } else {
        for (k = 0; k < n_out; ++k) f->res[k] = out[k] ? out[k] + i * out_stride[k] : 0;
      }
      if (f->eval(f->arg, f->res, f->iw, f->w, f->mem)) return i + 1;
    }
  }
  return 0;
}
