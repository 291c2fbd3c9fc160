"""Forward simulation through IDAS and exact sensitivities of results columns.

    s = casmech.optimal.sensitivity(model, ["m", "c"], ["bar.y", "pivot.fz"], [0.5, 1.0])
    s.values[k, i]           column i at times[k]
    s.jacobian[k, i, j]      d column i at times[k] / d parameter j

An output is a results column (`bar.y`, `pivot.fz`, `energy`, ...) or `integral(COLUMN)`, its
integral from t0 to the output time (an IDAS quadrature): a scalar of the trajectory.

Derivatives come from CasADi's IDAS sensitivities: forward (`mode="forward"`: one sensitivity
system per parameter) or adjoint (`mode="adjoint"`: one backward sweep per output), both through
the consistent initial state (assembly and velocity projection differentiated as a graph).
Parameters enter the DAE through the model data d(theta) of system.py (the lowering traced over
them), so a geometry parameter (a length, a joint point, an axis, an initial pose) is as exact
as a mass.
"""

from __future__ import annotations

import re
from collections.abc import Sequence

import casadi as ca
import numpy as np

from casmech.core.records import record
from casmech.errors import AnalysisError, FailureContext, UsageError
from casmech.optimal.dae import (
    DAE,
    algebraic_function,
    build_dae,
    columns_function,
    initial_state_function,
)
from casmech.optimal.system import parametric_system
from casmech.runtime import labelled
from casmech.schema.resolved import ResolvedModel

MODES = ("forward", "adjoint")
INTEGRAL = re.compile(r"integral\((.+)\)")


@record
class Sensitivity:
    parameters: tuple[str, ...]
    outputs: tuple[str, ...]
    times: np.ndarray
    values: np.ndarray  # (times, outputs)
    jacobian: np.ndarray  # (times, outputs, parameters)
    mode: str

    def to_dataframe(self):
        """The values and derivatives as a pandas DataFrame: a row per (t, output), columns
        `value` and `d/d<parameter>` (runtime.labelled)."""
        return labelled.sensitivity_frame(self.parameters, self.outputs, self.times,
                                          self.values, self.jacobian, self.mode)


def idas(dae: DAE, grid: Sequence[float], rtol: float, atol: float, t0: float | None = None,
         name: str = "F", quad=None) -> ca.Function:
    """IDAS from t0 (default the DAE's) with outputs at `grid`; `quad` (SX of t, x, z, p):
    integrands of quadratures, integrated from t0."""
    options = {"abstol": atol, "reltol": rtol, "calc_ic": True, "max_num_steps": 100000,
               "fsens_err_con": True,
               # a fully driven model (0 DOF): x is a function of t alone, and IDAS's error
               # test on [q_ddot, lam] failed at t0 with h = 2e-9 on robot_arm_3r.yaml (forward
               # and adjoint alike); z is then left out of the error test (it is a function of
               # x, solved to the Newton tolerance at every step)
               "suppress_algebraic": len(dae.rows) == dae.n}
    start = dae.t0 if t0 is None else t0
    problem = dae.problem() | ({"quad": quad} if quad is not None else {})
    inner = ca.integrator(f"{name}_p_as_x", "idas", _parameters_as_states(problem), start,
                          list(grid), options)
    return _with_parameters(name, inner, dae.x.numel(), dae.p.numel())


def _parameters_as_states(problem: dict) -> dict:
    """The DAE with its parameters p turned into states with p' = 0.

    Reverse-mode derivatives with respect to p of CasADi 3.8's IDAS (and CVODES) come from
    backward quadratures that are not error-controlled, and are wrong: on x'' = -p the adjoint
    gave dx(1)/dp = -0.607 (IDAS) and -0.756 (CVODES) against -0.5, 2 % off even with
    max_step_size 1e-3; with quad_err_con IDAS fails (IDA_TOO_MUCH_WORK). Derivatives with
    respect to initial states are exact in both modes, so p enters as states."""
    p = problem["p"]
    states = ca.SX.sym("p_state", p.numel())
    swap = {key: ca.substitute(problem[key], p, states)
            for key in ("ode", "alg", "quad") if key in problem}
    return {"t": problem["t"], "x": ca.vertcat(problem["x"], states), "z": problem["z"],
            "ode": ca.vertcat(swap["ode"], ca.SX.zeros(p.numel())), "alg": swap["alg"],
            **({"quad": swap["quad"]} if "quad" in swap else {})}


def _with_parameters(name: str, inner: ca.Function, n_x: int, n_p: int) -> ca.Function:
    """inner (p as states) behind the signature of an integrator of the original DAE:
    (x0, z0, p) -> (xf, zf, qf)."""
    x0 = ca.MX.sym("x0", n_x)
    z0 = ca.MX.sym("z0", inner.sparsity_in("z0"))
    p = ca.MX.sym("p", n_p)
    out = inner(x0=ca.vertcat(x0, p), z0=z0)
    return ca.Function(name, [x0, z0, p], [out["xf"][:n_x, :], out["zf"], out["qf"]],
                       ["x0", "z0", "p"], ["xf", "zf", "qf"])


def check_times(times: Sequence[float], t0: float) -> np.ndarray:
    times = np.atleast_1d(np.asarray(times, float))
    if times.size == 0 or np.any(times <= t0) or np.any(np.diff(times) <= 0):
        raise UsageError(f"output times must be increasing and after t0 = {t0:g}; "
                         f"got {', '.join(f'{x:g}' for x in times) or 'none'}")
    return times


def _integrand(output: str) -> str | None:
    """The column inside `integral(COLUMN)`, or None for a pointwise output."""
    match = INTEGRAL.fullmatch(output.replace(" ", ""))
    return match.group(1) if match else None


def _output_indices(names: list[str], outputs: Sequence[str]) -> list[int]:
    outputs = [_integrand(o) or o for o in outputs]
    missing = [o for o in outputs if o not in names]
    if missing:
        raise UsageError(f"unknown output column '{missing[0]}'; results columns are "
                         f"<body>.x/.vx/.wx/..., <joint>.fx/..., energy (see docs/format.md), "
                         "or integral(COLUMN) for its integral from t = 0")
    return [names.index(o) for o in outputs]


def chain(dae: DAE, times: np.ndarray, rtol: float, atol: float, quad=None) -> list[ca.Function]:
    """One IDAS integrator per output interval: each ends at its output time, so an adjoint
    sweep starts from a terminal condition instead of re-initialising inside an interval
    (IDAS's backward problem failed at interior output times of one integrator)."""
    starts = [dae.t0, *times[:-1]]
    return [idas(dae, [end], rtol, atol, t0=begin, name=f"F{k}", quad=quad)
            for k, (begin, end) in enumerate(zip(starts, times, strict=True))]


def output_graph(dae: DAE, outputs: Sequence[str], times: np.ndarray, rtol: float, atol: float,
                 chained: bool = True):
    """(theta MX symbol, outputs stacked time-major as an MX expression of theta).
    `integral(COLUMN)` outputs are IDAS quadratures from t0. `chained`: one integrator per output
    interval (needed for adjoint derivatives); otherwise one integrator with an output grid
    (faster, forward derivatives only)."""
    names, columns = columns_function(dae)
    index = _output_indices(names, outputs)
    integrals = [k for k, o in enumerate(outputs) if _integrand(o)]
    quad = columns(dae.t, dae.x, dae.z, dae.theta)[[index[k] for k in integrals]] \
        if integrals else None
    algebraic = algebraic_function(dae)
    x0 = initial_state_function(dae)
    theta = ca.MX.sym("theta", dae.theta.numel())
    values = dae.system.values
    if not chained:
        z0 = algebraic(dae.t0, x0(values), values)
        result = idas(dae, times, rtol, atol, quad=quad)(x0=x0(theta), z0=z0, p=theta)
        xs = [result["xf"][:, k] for k in range(times.size)]
        qs = [result["qf"][:, k] for k in range(times.size)]
    else:
        integrators = chain(dae, times, rtol, atol, quad)
        xs, qs = _chained_states(dae, integrators, x0, theta, times)
    rows = []
    for t, x, q in zip(times, xs, qs, strict=True):
        row = columns(t, x, algebraic(t, x, theta), theta)[index]
        for j, k in enumerate(integrals):
            row[k] = q[j]
        rows.append(row)
    return theta, ca.vertcat(*rows)


def _chained_states(dae: DAE, integrators, x0: ca.Function, theta, times):
    """States and cumulative quadratures at the output times; the algebraic guesses that start
    each IDAS call are numbers (a nominal pass), so no derivative flows through them."""
    algebraic, values = algebraic_function(dae), dae.system.values
    x, guesses = x0(values), []
    for begin, integrator in zip([dae.t0, *times[:-1]], integrators, strict=True):
        guesses.append(algebraic(begin, x, values))
        x = integrator(x0=x, z0=guesses[-1], p=values)["xf"]
    x, xs, qs, total = x0(theta), [], [], 0
    for guess, integrator in zip(guesses, integrators, strict=True):
        result = integrator(x0=x, z0=guess, p=theta)
        x, total = result["xf"], total + result["qf"]
        xs.append(x)
        qs.append(total)
    return xs, qs


def _evaluate(function: ca.Function, theta: np.ndarray, times: np.ndarray):
    try:
        return [np.array(v.full()) for v in function.call([theta])]
    except RuntimeError as error:
        raise AnalysisError(FailureContext(float(times[-1]), "IDAS failed while computing the "
                                           f"trajectory or its sensitivities: {error}"[:600],
                                           [])) from None


def sensitivity(model: ResolvedModel, parameters: Sequence[str], outputs: Sequence[str],
                times: Sequence[float], mode: str = "forward", rtol: float = 1e-10,
                atol: float = 1e-12) -> Sensitivity:
    """Values and derivatives of results columns at `times` w.r.t. `parameters` (file
    parameters, geometry included, or initial velocities `<body>.vx` ... `<body>.wz`)."""
    if mode not in MODES:
        raise UsageError(f"mode '{mode}' is not one of {', '.join(MODES)}")
    if not parameters:
        raise UsageError("name at least one parameter to differentiate with respect to")
    system = parametric_system(model, parameters)
    dae = build_dae(system)
    times = check_times(times, dae.t0)
    theta, y = output_graph(dae, outputs, times, rtol, atol, chained=mode == "adjoint")
    n_p, n_y = theta.numel(), y.numel()
    if mode == "forward":
        jac = ca.jtimes(y, theta, ca.DM.eye(n_p), False)
    else:
        jac = ca.jtimes(y, theta, ca.DM.eye(n_y), True).T
    values, jacobian = _evaluate(ca.Function("sens", [theta], [y, jac]), system.values, times)
    shape = (times.size, len(outputs))
    return Sensitivity(system.names, tuple(outputs), times, values.reshape(shape),
                       jacobian.reshape(*shape, n_p), mode)


def simulate(model: ResolvedModel, outputs: Sequence[str], times: Sequence[float],
             rtol: float = 1e-10, atol: float = 1e-12) -> np.ndarray:
    """Results columns at `times` from the same IDAS problem, without derivatives."""
    system = parametric_system(model)
    dae = build_dae(system)
    times = check_times(times, dae.t0)
    theta, y = output_graph(dae, outputs, times, rtol, atol, chained=False)
    values, = _evaluate(ca.Function("sim", [theta], [y]), system.values, times)
    return values.reshape(times.size, len(outputs))
