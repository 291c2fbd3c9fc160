"""What a linearly implicit one-step method would cost a compiled tree's repeated dynamics
call, estimated before building it (issue 36, the Talos arm; docs/decisions/rosenbrock.md).

    python benchmarks/rosenbrock_estimate.py /tmp/exp/talos_arm/talos_arm.yaml

The model file's tree, compiled, 1 s from its start. Three parts:

1. Steps: Hairer and Wanner's RODAS4 and Di Marzo's RODAS5 (Rosenbrock methods of order 4
   and 5 with embedded estimates of order 3 and 4, stiffly accurate), prototyped here in
   NumPy over the compiled ODE and its Jacobian (the RNEA identity, exact), with Hairer's
   predictive step controller (rodas.f: SAFE 0.9, factors 1/6 to 5, no growth after a
   rejection); DOP853 in C (runtime.dop853) beside them. For each half-decade rtol (atol =
   rtol / 100): accepted and rejected steps, ODE evaluations, Jacobians, and the error at
   t = 1 s (the largest distance of a body frame's origin from a DOP853 run at rtol 1e-13:
   robots.py's measure, for imports whose body frames sit at the centres of mass).
2. Costs in C, each a loop of calls in a C program (gcc -O2) without Python around it: the
   compiled ODE (the bundle's own library), its Jacobian by the RNEA identity
   (JointSystem.identity_jacobian) and by CasADi's symbolic AD compiled at -O1 in a library
   of their own, and an n x n LU with partial pivoting and one triangular solve.
3. The estimate: for each method at its loosest rtol reaching --level, evaluations x the ODE's
   cost in DOP853's driver (its measured C time over its evaluations) + Jacobians x the
   cheaper Jacobian + attempts x (LU + stages x solve), against DOP853's measured call (its C
   run and the Python around it); and the Jacobian cost at which the method would match it
   (and --target-ms).

Tables: RODAS4 from Hairer and Wanner, Solving ODEs II (2nd ed., 1996), section IV.7, as in
their rodas.f (ROCOE, METH = 1); RODAS5 from G. Di Marzo, RODAS5(4), Master's thesis,
University of Geneva (1993), in the same transformed form (as OrdinaryDiffEq.jl tabulates it).
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import c_timing  # noqa: E402

A4 = [1.221224509226641, 6.019134481288629, 12.53708332932087, -0.6878860361058950]
RODAS4 = {"gamma": 0.25, "order": 4, "c": [0, 0.386, 0.21, 0.63, 1, 1],
          "d": [0.25, -0.1043, 0.1035, -0.3620000000000023e-01, 0, 0],
          "a": [[], [1.544], [0.9466785280815826, 0.2557011698983284],
                [3.314825187068521, 2.896124015972201, 0.9986419139977817], A4, [*A4, 1.0]],
          "C": [[], [-5.6688], [-2.430093356833875, -0.2063599157091915],
                [-0.1073529058151375, -9.594562251023355, -20.47028614809616],
                [7.496443313967647, -10.24680431464352, -33.99990352819905, 11.70890893206160],
                [8.083246795921522, -7.981132988064893, -31.52159432874371, 16.31930543123136,
                 -6.058818238834054]]}
A5 = [-14.09640773051259, 6.925207756232704, -41.47510893210728, 2.343771018586405,
      24.13215229196062]
RODAS5 = {"gamma": 0.19, "order": 5,
          "c": [0, 0.38, 0.3878509998321533, 0.4839718937873840, 0.4570477008819580, 1, 1, 1],
          "d": [0.19, -0.1823079225333714636, -0.319231832186874912, 0.3449828624725343,
                -0.377417564392089818, 0, 0, 0],
          "a": [[], [2.0], [3.040894194418781, 1.041747909077569],
                [2.576417536461461, 1.622083060776640, -0.9089668560264532],
                [2.760842080225597, 1.446624659844071, -0.3036980084553738,
                 0.2877498600325443], A5, [*A5, 1.0], [*A5, 1.0, 1.0]],
          "C": [[], [-10.31323885133993], [-21.04823117650003, -7.234992135176716],
                [32.22751541853323, -4.943732386540191, 19.44922031041879],
                [-20.69865579590063, -8.816374604402768, 1.260436877740897,
                 -0.7495647613787146],
                [-46.22004352711257, -17.49534862857472, -289.6389582892057, 93.60855400400906,
                 318.3822534212147],
                [34.20013733472935, -14.15535402717690, 57.82335640988400, 25.83362985412365,
                 1.408950972071624, -6.551835421242162],
                [42.57076742291101, -13.80770672017997, 93.98938432427124, 18.77919633714503,
                 -31.58359187223370, -6.685968952921985, -5.810979938412932]]}
METHODS = {"RODAS4": RODAS4, "RODAS5": RODAS5}
RTOLS = tuple(float(f"{m}e{e}") for e in range(-4, -8, -1) for m in (3, 1))

# the timing program's main, after c_timing.PRELUDE
HARNESS = r"""
static void lu(double* a, int* p, int n) {
  for (int k = 0; k < n; k++) {
    int m = k;
    for (int i = k + 1; i < n; i++) if (fabs(a[i*n+k]) > fabs(a[m*n+k])) m = i;
    p[k] = m;
    if (m != k)
      for (int j = 0; j < n; j++) { double t = a[k*n+j]; a[k*n+j] = a[m*n+j]; a[m*n+j] = t; }
    for (int i = k + 1; i < n; i++) {
      double l = a[i*n+k] /= a[k*n+k];
      for (int j = k + 1; j < n; j++) a[i*n+j] -= l * a[k*n+j];
    }
  }
}
static void solve(const double* a, const int* p, double* b, int n) {
  for (int k = 0; k < n; k++) { double t = b[p[k]]; b[p[k]] = b[k]; b[k] = t; }
  for (int i = 0; i < n; i++) for (int j = 0; j < i; j++) b[i] -= a[i*n+j] * b[j];
  for (int i = n - 1; i >= 0; i--) {
    for (int j = i + 1; j < n; j++) b[i] -= a[i*n+j] * b[j];
    b[i] /= a[i*n+i];
  }
}
int main(int argc, char** argv) {
  int n = atoi(argv[2]), N = atoi(argv[3]);
  double *x = calloc(n, 8), *f = calloc(n, 8);
  double *o1 = calloc(n * n + n, 8), *o2 = calloc(n * n + n, 8);
  double *a = calloc(n * n, 8), *b = calloc(n, 8), s = 0, t = 0, start;
  int* p = calloc(n, sizeof(int));
  if (!strcmp(argv[1], "call")) {  /* call n N lib symbol sz_w sz_iw xfile */
    fn g = (fn)dlsym(dlopen(argv[4], RTLD_NOW), argv[5]);
    double* w = calloc(atoi(argv[6]) + 1, 8); ci* iw = calloc(atoi(argv[7]) + 1, 8);
    FILE* in = fopen(argv[8], "r");
    for (int i = 0; i < 2 * n; i++) if (fscanf(in, "%lf", i < n ? &x[i] : &f[i - n]) != 1) return 1;
    const double* arg[8] = {&t, x, f}; double* res[8] = {o1, o2};
    start = now();
    for (int k = 0; k < N; k++) { x[0] += 1e-15; g(arg, res, iw, w, 0); s += o1[0]; }
  } else {  /* lu n N, solve n N */
    int only_solve = !strcmp(argv[1], "solve");
    for (int i = 0; i < n * n; i++) a[i] = sin(1.3 * i) * 0.01 + (i % (n + 1) == 0);
    if (only_solve) lu(a, p, n);
    start = now();
    for (int k = 0; k < N; k++) {
      if (only_solve) { for (int i = 0; i < n; i++) b[i] = i + k; solve(a, p, b, n); s += b[0]; }
      else { for (int i = 0; i < n * n; i++) o1[i] = a[i] + 1e-12 * k; lu(o1, p, n); s += o1[0]; }
    }
  }
  printf("%.6g %g\n", (now() - start) / N, s);
  return 0;
}
"""


def rosenbrock(tableau: dict, ode, jacobian, x0: np.ndarray, rtol: float, atol: float,
               t_end: float = 1.0) -> tuple[np.ndarray, dict]:
    """The state at t_end and the counts of a Rosenbrock run (the module docstring)."""
    gamma, c, d, a, C = (tableau[k] for k in ("gamma", "c", "d", "a", "C"))
    exponent, n = 1 / tableau["order"], len(x0)
    t, y, h = 0.0, x0.copy(), 1e-3
    counts = dict(accepted=0, rejected=0, evaluations=0, jacobians=0)
    first, rejected, h_old, err_old = True, False, 0.0, 1.0
    while t < t_end:
        h = min(h, t_end - t)
        by_t, by_x = jacobian(t, y)
        counts["jacobians"] += 1
        while True:
            factors = np.linalg.inv(np.eye(n) / (gamma * h) - by_x)  # a prototype: no LU
            stages: list[np.ndarray] = []
            for i in range(len(c)):
                argument = y + sum(coef * k for coef, k in zip(a[i], stages, strict=True))
                rhs = ode(t + c[i] * h, argument) + h * d[i] * by_t + sum(
                    coef * k for coef, k in zip(C[i], stages, strict=True)) / h
                stages.append(factors @ rhs)
            counts["evaluations"] += len(c)
            y_new = argument + stages[-1]
            scale = atol + rtol * np.maximum(abs(y), abs(y_new))
            err = float(np.sqrt(np.mean((stages[-1] / scale) ** 2)))
            factor = max(1 / 6, min(5.0, err ** exponent / 0.9))
            if err <= 1:
                if not first:
                    predicted = (h_old / h) * (err * err / err_old) ** exponent / 0.9
                    factor = max(factor, max(1 / 6, min(5.0, predicted)))
                h_new = h / factor
                first, h_old, err_old = False, h, max(0.01, err)
                if rejected:
                    h_new = min(h_new, h)
                rejected = False
                break
            h, rejected = h / factor, True
            counts["rejected"] += 1
        t, y, h = t + h, y_new, h_new
        counts["accepted"] += 1
    return y, counts


def c_costs(harness: Path, functions: dict, x0: np.ndarray, f0: np.ndarray,
            calls: int) -> dict:
    """Seconds a call in C: each compiled function of `functions` (name -> casadi.external
    with inputs (t, x[, ode])), an LU and a triangular solve of len(x0)."""
    from casmech.backends import external_record

    n = len(x0)
    with tempfile.NamedTemporaryFile("w", suffix=".txt", delete=False) as state:
        state.write(" ".join(repr(float(v)) for v in (*x0, *f0)))
    out = {}
    try:
        for label, function in functions.items():
            args = ["call", str(n), str(calls), str(external_record.library(function)),
                    function.name(), str(function.sz_w()), str(function.sz_iw()), state.name]
            out[label] = _median(harness, args)
        out["LU"] = _median(harness, ["lu", str(n), str(calls)])
        out["solve"] = _median(harness, ["solve", str(n), str(calls)])
    finally:
        os.unlink(state.name)
    return out


def _median(harness: Path, args: list[str], repeats: int = 5) -> float:
    return statistics.median(float(subprocess.run(
        [str(harness), *args], capture_output=True, text=True, check=True).stdout.split()[0])
        for _ in range(repeats))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("model", help="a model file whose tree is compiled")
    parser.add_argument("--level", type=float, default=1e-7, help="the error to reach [m]")
    parser.add_argument("--calls", type=int, default=100_000, help="calls per C timing loop")
    parser.add_argument("--target-ms", type=float, help="also: the Jacobian cost at which a "
                        "method's integrator would take this long [ms]")
    options = parser.parse_args()

    import casadi as ca

    import casmech
    from casmech.backends.build import Toolchain
    from casmech.backends.library import compile_functions
    from casmech.runtime import dop853, joint_dynamics
    from casmech.runtime.workspace import of

    functions = casmech.compile(casmech.load(options.model), "compiled")
    casmech.analyze(functions, "dynamics", t_end=1.0)
    workspace = of(functions, None)
    settings = joint_dynamics.DEFAULT
    system = joint_dynamics.joint_system(functions, settings, workspace)
    x0, _, _, signs, _ = joint_dynamics._kept_start(functions, system, 0.0, settings.assembly,
                                                    workspace)
    ode, nb = system.dynamics, functions.n_bodies
    symbolic = joint_dynamics._built(functions, settings, workspace)
    t, x = symbolic.dynamics.sx_in()
    rate = symbolic.dynamics(t, x)
    library = compile_functions({
        "identity": symbolic.identity_jacobian(),
        "ad": ca.Function("ad", [t, x], [ca.jacobian(rate, x)], ["t", "x"], ["jac"])},
        toolchain=Toolchain(flags=("-O1",)))

    def rates(t, y):
        return np.array(ode(t, y)).ravel()

    def jacobian(t, y):
        by_t, by_x = library["identity"](t, y, ode(t, y))
        return np.array(by_t).ravel(), np.array(by_x)

    def origins(y):
        q = np.array(system.motion(1.0, y, np.zeros(0), signs)[0]).ravel()
        return q[:3 * nb].reshape(nb, 3)

    reference = origins(dop853.Dop853(ode, 1e-13, 1e-15)(0.0, [1.0], x0)[:, 0])

    def error(y):
        return float(np.max(np.linalg.norm(origins(y) - reference, axis=1)))

    eig = np.linalg.eigvals(jacobian(0.0, x0)[1])
    print(f"{options.model}: {len(x0)} states; fastest eigenvalues at t0: "
          + ", ".join(f"{v:.4g}" for v in sorted(eig, key=lambda v: v.real)[:4]))
    found = {}
    grid = np.linspace(0.01, 1.0, 100)
    for rtol in RTOLS:
        rk = dop853.Dop853(ode, rtol, rtol / 100)
        y = rk(0.0, grid, x0)[:, -1]
        spent = []
        for _ in range(20):
            start = time.process_time()
            rk(0.0, grid, x0)
            spent.append(time.process_time() - start)
        counts = rk.last
        e = error(y)
        print(f"DOP853 rtol {rtol:g}: {counts.accepted}+{counts.rejected} steps, "
              f"{counts.evaluations} evaluations, {1e3 * statistics.median(spent):.3f} ms a call, "
              f"error {e:.2e} m")
        if e <= options.level and "DOP853" not in found:
            found["DOP853"] = (rtol, statistics.median(spent), counts.evaluations)
    for name, tableau in METHODS.items():
        for rtol in RTOLS:
            y, counts = rosenbrock(tableau, rates, jacobian, x0, rtol, rtol / 100)
            e = error(y)
            print(f"{name} rtol {rtol:g}: {counts['accepted']}+{counts['rejected']} steps, "
                  f"{counts['evaluations']} evaluations, {counts['jacobians']} Jacobians, "
                  f"error {e:.2e} m")
            if e <= options.level and name not in found:
                found[name] = (rtol, counts)

    with tempfile.TemporaryDirectory() as folder:
        harness = c_timing.build(Path(folder), HARNESS)
        costs = c_costs(harness, {"ODE": ode, "Jacobian (RNEA identity, -O1)":
                                  library["identity"], "Jacobian (CasADi AD, -O1)":
                                  library["ad"]}, x0, rates(0.0, x0), options.calls)
    print("C per call: " + ", ".join(f"{k} {1e6 * v:.3f} us" for k, v in costs.items()))
    if "DOP853" not in found:
        print(f"DOP853 reaches {options.level:g} m at no rtol of {RTOLS}")
        return
    rtol, dop_time, evaluations = found["DOP853"]
    per_evaluation = dop_time / evaluations  # the ODE in DOP853's driver, its work included
    jac = min(v for k, v in costs.items() if k.startswith("Jacobian"))
    print(f"DOP853 at its loosest rtol reaching {options.level:g} m ({rtol:g}): "
          f"{1e3 * dop_time:.3f} ms a call, {1e6 * per_evaluation:.3f} us an evaluation")
    for name, tableau in METHODS.items():
        if name not in found:
            print(f"{name}: reaches {options.level:g} m at no rtol of {RTOLS}")
            continue
        rtol, counts = found[name]
        attempts = counts["accepted"] + counts["rejected"]
        without = (counts["evaluations"] * per_evaluation
                   + attempts * (costs["LU"] + len(tableau["c"]) * costs["solve"]))
        total = without + counts["jacobians"] * jac
        even = (dop_time - without) / counts["jacobians"]
        print(f"{name} at rtol {rtol:g}: estimated {1e3 * total:.3f} ms a call "
              f"({total / dop_time:.2f}x DOP853's; {1e3 * without:.3f} ms without the "
              f"Jacobians); it matches DOP853 with a Jacobian of {1e6 * even:.2f} us "
              f"({even / costs['ODE']:.1f} ODE calls)")
        if options.target_ms:
            needed = (1e-3 * options.target_ms - without) / counts["jacobians"]
            print(f"  {options.target_ms:g} ms needs a Jacobian of {1e6 * needed:.2f} us "
                  f"({needed / costs['ODE']:.1f} ODE calls)")


if __name__ == "__main__":
    main()
