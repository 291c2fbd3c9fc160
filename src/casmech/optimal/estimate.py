"""Parameter estimation: weighted least squares of results columns against measurements.

    fit = casmech.optimal.estimate(model, ["m", "c"], times, {"bar.y": ys, "bar.z": zs})

minimise  sum_k sum_i w_i (y_i(t_k; theta) - d_ik)^2  over theta (within optional bounds), with
IPOPT (bundled in CasADi); the residuals are lifted into variables whose constraint Jacobian
comes from forward IDAS sensitivities, and the Hessian is approximated by L-BFGS. Parameters
are scaled by their starting values. Any parameter system.py takes (geometry and composed
models included) is exact at every theta the solver tries, through d(theta).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import casadi as ca
import numpy as np

from casmech.core.records import record
from casmech.errors import AnalysisError, FailureContext, UsageError
from casmech.optimal.dae import build_dae
from casmech.optimal.sensitivity import check_times, output_graph
from casmech.optimal.system import parametric_system
from casmech.schema.resolved import ResolvedModel


@record
class Estimate:
    parameters: tuple[str, ...]
    values: np.ndarray  # estimated
    initial: np.ndarray
    objective: float
    residuals: np.ndarray  # (times, outputs): model - data at the estimate
    iterations: int
    status: str


def estimate(model: ResolvedModel, parameters: Sequence[str], times: Sequence[float],
             data: Mapping[str, Sequence[float]], weights: Mapping[str, float] | None = None,
             bounds: Mapping[str, tuple[float, float]] | None = None, rtol: float = 1e-9,
             atol: float = 1e-11, max_iter: int = 100, verbose: bool = False) -> Estimate:
    """Fit `parameters` (starting from the model's values) to measured columns."""
    system = parametric_system(model, parameters)
    dae = build_dae(system)
    times = check_times(times, dae.t0)
    outputs = list(data)
    measured = np.column_stack([np.asarray(data[o], float) for o in outputs])
    if measured.shape[0] != times.size:
        raise UsageError(f"{measured.shape[0]} measurements per column for {times.size} times")
    weights = weights or {}
    w = np.array([float(weights.get(o, 1.0)) for o in outputs])
    inner, y = output_graph(dae, outputs, times, rtol, atol, chained=False)
    names = tuple(dict.fromkeys(parameters))
    theta = ca.MX.sym("theta", len(names))
    response = ca.Function("y", [theta], [ca.Function("y", [inner], [y])(theta)])
    n_y = y.numel()
    # lifted least squares: variables [theta / scale, r], r = y(theta) - data; the constraint
    # Jacobian (n_y x n_theta) comes from forward IDAS sensitivities
    start = np.array([model.parameters.get(n, 0.0) for n in names], float)
    scale = np.where(start != 0, np.abs(start), 1.0)
    scaled, r = ca.MX.sym("s", len(names)), ca.MX.sym("r", n_y)
    model_y = response(scaled * ca.DM(scale))
    weight = np.tile(w, times.size)
    bounds = bounds or {}
    low = np.array([bounds.get(n, (-np.inf, np.inf))[0] for n in names]) / scale
    high = np.array([bounds.get(n, (-np.inf, np.inf))[1] for n in names]) / scale
    nlp = {"x": ca.vertcat(scaled, r), "f": ca.sum1(ca.DM(weight) * r ** 2),
           "g": model_y - ca.DM(measured.ravel()) - r}
    options = {"ipopt.hessian_approximation": "limited-memory", "ipopt.max_iter": max_iter,
               "ipopt.tol": 1e-8, "ipopt.print_level": 5 if verbose else 0,
               "print_time": verbose, "ipopt.sb": "yes"}
    x, cost, iterations, status = solve(ca.nlpsol("estimate", "ipopt", nlp, options), low, high,
                                        np.zeros(n_y), float(times[-1]))
    values = x[:len(names)] * scale
    at = response(values).full().reshape(measured.shape) - measured
    return Estimate(names, values, start, cost, at, iterations, status)


def solve(solver: ca.Function, low: np.ndarray, high: np.ndarray, free: np.ndarray,
          t_end: float) -> tuple[np.ndarray, float, int, str]:
    """Run an estimator's NLP over x = [the scaled parameters (start 1, within low, high); the
    unbounded auxiliaries (start `free`)] with equality constraints g = 0: (x, cost, IPOPT's
    iterations, its return status); a solver failure is an AnalysisError at `t_end`."""
    unbounded = np.full(free.size, np.inf)
    try:
        solution = solver(x0=np.concatenate([np.ones(low.size), free]),
                          lbx=np.concatenate([low, -unbounded]),
                          ubx=np.concatenate([high, unbounded]), lbg=0, ubg=0)
    except RuntimeError as error:
        raise AnalysisError(FailureContext(t_end, f"estimation failed: {error}"[:600],
                                           [])) from None
    stats = solver.stats()
    return (np.array(solution["x"].full()).ravel(), float(solution["f"]),
            int(stats.get("iter_count", -1)), str(stats.get("return_status")))
