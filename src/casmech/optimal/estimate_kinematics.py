"""Parameter estimation on the positions of a fully driven mechanism (`estimate: {analysis:
kinematics}`): kinematic synthesis, such as a four-bar's link lengths that put its coupler
point through given points at given crank angles (models/four_bar_synthesis.yaml).

    minimise  sum_k sum_i w_i (y_i(t_k, q_k, theta) - d_ik)^2
    over      theta (within optional bounds) and q_k, one pose per measurement time,
    such that Phi(t_k, q_k, theta) = 0

With no degrees of freedom the constraints fix each pose q_k (the drivers included), so no
integration is involved: the poses are unknowns beside theta and IPOPT meets the constraints
to its tolerance, with exact first and second derivatives through the parametric model
(optimal/system.py). The columns y_i are results columns of the positions alone (a body's
x .. e3, the joint coordinates, outputs of those); the poses start from the runtime's Newton
solution at the file's values, followed in small time steps from t0 so that they stay on the
assembly the file describes.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import casadi as ca
import numpy as np

from casmech.errors import UsageError
from casmech.optimal.dae import body_columns
from casmech.optimal.estimate import Estimate, solve
from casmech.optimal.sensitivity import check_times
from casmech.optimal.system import parametric_system
from casmech.runtime import assembly
from casmech.runtime.results import column_names
from casmech.schema.resolved import ResolvedModel

FOLLOW_STEP = 0.01  # [s] steps of the Newton solutions that give the poses' initial guess


def _poses(nominal, times: np.ndarray) -> np.ndarray:
    """The poses at `times` at the file's values, followed from the assembled initial pose."""
    t0 = 0.0
    q = assembly.initial_state(nominal, t0)[0]
    poses = []
    for t_k in times:
        steps = max(int(np.ceil((t_k - t0) / FOLLOW_STEP)), 1)
        for t in np.linspace(t0, t_k, steps + 1)[1:]:
            q = assembly.newton(nominal, float(t), q)
        poses.append(q)
        t0 = t_k
    return np.array(poses)


def _outputs(system, outputs: Sequence[str]):
    """(t, q, theta) -> the outputs, checked to depend on positions only."""
    names = column_names(system.nominal)[1:]
    missing = [o for o in outputs if o not in names]
    if missing:
        raise UsageError(f"unknown output column '{missing[0]}'; results columns are "
                         "<body>.x, <joint>.angle, ...")
    n, rows = system.nominal.n_coordinates, system.nominal.n_rows
    t, theta = ca.SX.sym("t"), ca.SX.sym("theta", len(system.names))
    q, rates = ca.SX.sym("q", n), ca.SX.sym("rates", 3 * n + rows - n)
    q_dot, q_ddot, lam = rates[:n], rates[n:2 * n], rates[2 * n:]
    values = body_columns(system)(t, q, q_dot, q_ddot, lam, theta)
    chosen = ca.vertcat(*[values[names.index(o)] for o in outputs])
    moving = [o for k, o in enumerate(outputs) if ca.depends_on(chosen[k], rates)]
    if moving:
        raise UsageError(f"a kinematic estimate fits columns of the positions; "
                         f"{', '.join(moving)} depend on velocities, accelerations or forces")
    return ca.Function("outputs", [t, q, theta], [chosen])


def estimate_kinematics(model: ResolvedModel, parameters: Sequence[str],
                        times: Sequence[float], data: Mapping[str, Sequence[float]],
                        weights: Mapping[str, float] | None = None,
                        bounds: Mapping[str, tuple[float, float]] | None = None,
                        max_iter: int = 200, verbose: bool = False) -> Estimate:
    """Fit `parameters` (from the model's values) to measured position columns of a fully
    driven mechanism (module docstring)."""
    names = tuple(dict.fromkeys(parameters))
    system = parametric_system(model, names)
    nominal = system.nominal
    times = check_times(times, 0.0)
    outputs = list(data)
    measured = np.column_stack([np.asarray(data[o], float) for o in outputs])
    if measured.shape[0] != times.size:
        raise UsageError(f"{measured.shape[0]} measurements per column for {times.size} times")
    poses = _poses(nominal, times)
    n = nominal.n_coordinates
    jacobian = np.array(system["phi_q"](float(times[0]), poses[0], system.values).full())
    free = n - np.linalg.matrix_rank(jacobian)
    if free:
        raise UsageError(f"a kinematic estimate needs a fully driven mechanism; this one has "
                         f"{free} degrees of freedom at t = {times[0]:g} (drive them, or "
                         "estimate on the dynamics: analysis: dynamics)")
    output = _outputs(system, outputs)
    weights = weights or {}
    w = np.sqrt(np.array([float(weights.get(o, 1.0)) for o in outputs]))  # of the misses
    start = np.asarray(system.values, float)
    scale = np.where(start != 0, np.abs(start), 1.0)
    scaled, q = ca.SX.sym("s", len(names)), ca.SX.sym("q", n, times.size)
    theta = scaled * ca.DM(scale)
    misses, constraints = [], []
    for k, t in enumerate(times):
        misses.append(output(t, q[:, k], theta) - ca.DM(measured[k]))
        constraints.append(system["phi"](t, q[:, k], theta))
    r = ca.vertcat(*misses)
    bounds = bounds or {}
    low = np.array([bounds.get(p, (-np.inf, np.inf))[0] for p in names]) / scale
    high = np.array([bounds.get(p, (-np.inf, np.inf))[1] for p in names]) / scale
    nlp = {"x": ca.vertcat(scaled, ca.vec(q)), "f": ca.sumsqr(ca.repmat(ca.DM(w), times.size) * r),
           "g": ca.vertcat(*constraints)}
    options = {"ipopt.max_iter": max_iter, "ipopt.tol": 1e-12,
               "ipopt.print_level": 5 if verbose else 0, "print_time": verbose,
               "ipopt.sb": "yes", "show_eval_warnings": False}  # (NaN trials: no pose)
    x, cost, iterations, status = solve(ca.nlpsol("estimate_kinematics", "ipopt", nlp, options),
                                        low, high, poses.ravel(), float(times[-1]))
    values = x[:len(names)] * scale
    at = ca.Function("r", [scaled, q], [r])(x[:len(names)], x[len(names):].reshape(
        times.size, n).T).full().reshape(measured.shape)
    return Estimate(names, values, start, cost, at, iterations, status)
