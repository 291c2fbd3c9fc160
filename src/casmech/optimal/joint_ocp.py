"""Optimal control in joint coordinates: the problem of optimal/ocp.py (controls, objective,
terminal conditions, path bounds) on the ODE of optimal/joint_model.py, transcribed by a
method of optimal/shooting.py or optimal/collocation.py with the controls' shape of
optimal/control_shapes.py, solved by IPOPT (casadi.Opti).

    nodes      x_k at t_k = t0 + k h (x_0 the model's assembled state, fixed)
    continuity x_{k+1} - end_k = J(t_{k+1}, x_{k+1})^T nu_k, with J the Jacobian of the
               closure rows (loops: Phi_c and d/dt Phi_c; quaternion norms) and
               closure(t_{k+1}, x_{k+1}) = 0: every node lies on the constraint manifold
               exactly and takes the discretisation's drift as a projection onto it (nu_k is
               of the order of the method's local error); without closure rows (a tree with
               no quaternion coordinates) x_{k+1} = end_k
    path       bounds on results columns at every node after the first (the control of the
               interval ending there) and, with `path_grid: fine`, at every point inside the
               intervals the method has (collocation points; RK4 step ends; a SUNDIALS
               integrator's `steps` outputs); path, terminal and initial conditions read an
               angle column continued past pi as its joint coordinate (costs.continued)
    costs      the integral and tracking terms (optimal/costs.py) as a last state of the ODE,
               from 0 in every interval, its ends summed; the final term at the last node

The replay (replay_nodes) integrates the ODE with scipy's DOP853 from every node with the
optimal controls: an integrator independent of the transcription.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import field
from functools import partial

import casadi as ca
import numpy as np

from casmech.core.records import record
from casmech.errors import AnalysisError, FailureContext, UsageError
from casmech.model.lower import lower
from casmech.optimal import costs
from casmech.optimal.collocation import SCHEMES, DirectCollocation
from casmech.optimal.control_shapes import SHAPES, ControlShape
from casmech.optimal.joint_model import JointModel, joint_model
from casmech.optimal.shooting import INTEGRATORS, MultipleShooting, SundialsShooting
from casmech.schema.resolved import ResolvedModel

REPLAY_RTOL, REPLAY_ATOL = 1e-12, 1e-12  # DOP853's tolerances in replay_nodes
# auto: joint coordinates (optimal/joint_model.py) for a tree they take, else bodies
FORMULATIONS = ("auto", "joints", "bodies")
PATH_GRIDS = ("nodes", "fine")
JOINT_MODELS_KEPT = 8


_JOINT_MODELS: dict = {}


def joints_of(model: ResolvedModel, problem) -> JointModel | None:
    """The joint-coordinate functions the problem is solved on, or None for body coordinates
    (FORMULATIONS; auto takes joint coordinates for a tree, bodies for loops and for the
    settings only bodies have: `stabilized`, a compiled `mode`), kept per model and
    controls."""
    if problem.formulation not in FORMULATIONS:
        raise UsageError(f"formulation '{problem.formulation}' is not one of "
                         f"{', '.join(FORMULATIONS)}")
    if problem.path_grid not in PATH_GRIDS:
        raise UsageError(f"path_grid '{problem.path_grid}' is not one of {', '.join(PATH_GRIDS)}")
    joints_only = [name for name, used in (
        ("decision parameters", bool(problem.parameters)),
        ("a free initial state", problem.initial_free),
        ("integral, tracking and final cost terms", costs.used(problem)),
        (f"integrator {problem.integrator}", problem.integrator != "rk4")) if used]
    if joints_only and problem.formulation == "bodies":
        raise UsageError(f"{' and '.join(joints_only)} are solved in joint coordinates "
                         "only; use formulation auto or joints")
    bodies_only = [name for name, used in (
        ("stabilized", problem.stabilized), ("a compiled mode", problem.mode != "interpreted"),
        ("initial_guess: interpolation", problem.initial_guess == "interpolation"),
        ("couplings of joint coordinates (gears, racks, couplers, screws)",
         any(joint.couples for joint in lower(model).joints))) if used]
    if (problem.formulation == "joints" or joints_only) and bodies_only:
        raise UsageError(f"formulation 'joints' does not take {', '.join(bodies_only)} "
                         "(settings of the body-coordinate transcription)")
    if problem.formulation == "bodies" or (problem.formulation == "auto" and bodies_only):
        return None
    if problem.horizon <= 0 or problem.intervals < 1:
        raise UsageError("the horizon must be positive and intervals at least 1")
    design = tuple(problem.parameters)
    key = (model.file, model.text, tuple(sorted(model.overrides.items())),
           tuple(problem.controls), design)
    if key not in _JOINT_MODELS:
        if len(_JOINT_MODELS) >= JOINT_MODELS_KEPT:
            _JOINT_MODELS.pop(next(iter(_JOINT_MODELS)))
        _JOINT_MODELS[key] = joint_model(model, list(problem.controls), design)
    found = _JOINT_MODELS[key]
    if found is not None and found.equations.n_cut and problem.formulation == "auto" \
            and not joints_only:
        return None  # loops: joint coordinates when asked (docs/optimal.md)
    if found is None and joints_only:
        raise UsageError(f"{' and '.join(joints_only)} need the joint formulation, which does not "
                         "take this model (a control on a component instance's joint, or "
                         "loops holding a floating body)")
    if found is None and problem.formulation == "joints":
        raise UsageError("formulation 'joints' does not take this model: its loops hold a "
                         "floating body, or a control acts on a joint of a component "
                         "instance; use formulation 'bodies' (or auto)")
    return found


@record
class JointResult:
    times: np.ndarray  # the nodes (intervals + 1)
    x: np.ndarray  # (intervals + 1, n_x) joint states at the nodes
    u: np.ndarray  # (values, n_u): per interval (constant) or per node (linear)
    objective: float
    status: str
    iterations: int
    solver_time: float  # IPOPT's own time (t_proc_total of its statistics) [s]
    # (times, states, controls) at the nodes and every point inside the intervals the method
    # has (collocation points, RK4 step ends), in time order
    fine: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
    design: np.ndarray = field(default_factory=lambda: np.zeros(0))  # decision parameters


def control_weights(problem) -> np.ndarray:
    """Each control's weight in the effort integral (`weights` by control name, default 1)."""
    names = [control.name for control in problem.controls]
    for name, weight in problem.weights.items():
        if name not in names:
            raise UsageError(f"weight of '{name}': not a control; the controls are "
                             f"{', '.join(names)} (<joint>.torque or <joint>.force)")
        if not weight >= 0:
            raise UsageError(f"weight of '{name}' is {weight}; weights are at least 0")
    return np.array([float(problem.weights.get(name, 1.0)) for name in names])


def method(problem, transcription: str):
    """The transcription method of the problem's settings."""
    if problem.integrator not in INTEGRATORS:
        raise UsageError(f"integrator '{problem.integrator}' is not one of "
                         f"{', '.join(INTEGRATORS)}")
    if transcription == "collocation" and problem.integrator != "rk4":
        raise UsageError(f"integrator '{problem.integrator}' integrates the intervals of "
                         "multiple shooting; use transcription shooting (collocation has "
                         "no integrator)")
    if transcription == "collocation":
        if problem.scheme not in SCHEMES:
            raise UsageError(f"collocation scheme '{problem.scheme}' is not one of "
                             f"{', '.join(SCHEMES)}")
        if not 1 <= problem.degree <= 9:
            raise UsageError(f"collocation degree {problem.degree} is not between 1 and 9")
        return DirectCollocation(problem.degree, problem.scheme, problem.elements)
    if problem.steps < 1:
        raise UsageError(f"shooting steps {problem.steps} must be at least 1")
    if problem.integrator == "rk4":
        return MultipleShooting(problem.steps)
    return SundialsShooting(problem.integrator, problem.steps, problem.rtol, problem.atol)


def shape_of(problem) -> ControlShape:
    if problem.piecewise not in SHAPES:
        raise UsageError(f"piecewise '{problem.piecewise}' is not one of {', '.join(SHAPES)}")
    return ControlShape(problem.piecewise)


def _ivp(model: JointModel, control: Callable[[float], np.ndarray], t0: float, t1: float,
         x0, times=None, rtol=REPLAY_RTOL, atol=REPLAY_ATOL):
    from scipy.integrate import solve_ivp  # (casmech optimize --help imports no scipy)

    f = model.rhs

    def rhs(t, x):
        return np.array(f(t, x, control(t)).full()).ravel()

    return solve_ivp(rhs, (t0, t1), np.asarray(x0, float), method="DOP853", rtol=rtol,
                     atol=atol, t_eval=times, dense_output=times is None)


def control_function(shape: ControlShape, times: np.ndarray, u: np.ndarray, k: int,
                     design=()):
    """c = [controls; design] at time t of interval k (u: values x n_u)."""
    h, design = times[1] - times[0], np.asarray(design, float)
    return lambda t: np.concatenate([np.asarray(shape.at(u.T, k, (t - times[k]) / h),
                                                float).ravel(), design])


def replay_nodes(model: JointModel, shape: ControlShape, times, x, u,
                 design=()) -> np.ndarray:
    """The state each node's successor takes when the ODE is integrated (DOP853, tight
    tolerances) from that node with the optimal controls: row k + 1 from node k; row 0 is
    node 0."""
    rows = [np.asarray(x[0], float)]
    for k in range(len(times) - 1):
        solution = _ivp(model, control_function(shape, times, u, k, design), times[k],
                        times[k + 1], x[k], times=[times[k + 1]])
        rows.append(solution.y[:, -1] if solution.success else np.full(len(x[0]), np.nan))
    return np.array(rows)


def _guess(model: JointModel, problem, shape: ControlShape, start, push: np.ndarray):
    """(node states, controls, state at (k, s)) of the initial guess: a previous solution
    interpolated between its nodes, else a forward simulation with the constant `push`."""
    n = problem.intervals
    times = np.linspace(0.0, problem.horizon, n + 1) + model.t0
    if start is not None:
        x, u = np.asarray(start.x, float), np.asarray(start.u, float)
        return x, u, lambda k, s: (1 - s) * x[k] + s * x[k + 1]
    u = np.tile(push, (shape.values(n), 1))
    x0 = model.start[0]
    c = np.concatenate([push, model.design_values])
    simulated = _ivp(model, lambda t: c, times[0], times[-1], x0, rtol=1e-8, atol=1e-10)
    if not simulated.success:
        return np.tile(x0, (n + 1, 1)), u, lambda k, s: x0
    dense = simulated.sol
    x = np.array([dense(t) for t in times])
    return x, u, lambda k, s: dense(times[k] + s * (times[1] - times[0]))


def _step(opti, problem):
    if problem.free_time is None:
        return problem.horizon / problem.intervals
    low, high = problem.free_time
    if not 0 < low <= high:
        raise UsageError(f"free final time bounds must satisfy 0 < low <= high, got {low}, {high}")
    step = opti.variable()
    opti.subject_to(opti.bounded(low / problem.intervals, step, high / problem.intervals))
    opti.set_initial(step, problem.horizon / problem.intervals)
    return step


def _bounds(opti, problem, u):
    for k, control in enumerate(problem.controls):
        if np.isfinite(control.lower):
            opti.subject_to(u[k, :] >= control.lower)
        if np.isfinite(control.upper):
            opti.subject_to(u[k, :] <= control.upper)


def _path(opti, model: JointModel, columns, problem, samples):
    """Bounds on results columns at the samples (t, x, c)."""
    if not problem.path:
        return
    index = {name: model.column(name) for name in problem.path}
    for t, x, c in samples:
        values = columns(t, x, c)
        for name, (low, high) in problem.path.items():
            opti.subject_to(opti.bounded(low, values[index[name]], high))


def _terminal(opti, model: JointModel, columns, problem, t_end, x_end, c_end):
    cost = 0
    if not (problem.terminal or problem.terminal_cost or problem.terminal_bounds):
        return cost
    values = columns(t_end, x_end, c_end)
    for name, target in problem.terminal.items():
        opti.subject_to(values[model.column(name)] == target)
    for name, (weight, target) in problem.terminal_cost.items():
        cost += weight * (values[model.column(name)] - target) ** 2
    for name, (low, high) in problem.terminal_bounds.items():
        opti.subject_to(opti.bounded(low, values[model.column(name)], high))
    return cost


def _start_state(opti, model: JointModel, columns, problem, x0, c0) -> None:
    """x(t0): the model's assembled state, or with `initial_free` a variable on the closure
    rows meeting the `initial` equalities and `initial_bounds` on results columns."""
    if not problem.initial_free:
        if problem.initial or problem.initial_bounds:
            raise UsageError("initial conditions (initial:, initial_bounds:) need "
                             "initial_free: true")
        opti.subject_to(x0 == model.start[0])
        return
    if model.closure.size1_out(0):
        opti.subject_to(model.closure(model.t0, x0) == 0)
    if not (problem.initial or problem.initial_bounds):
        return
    values = columns(model.t0, x0, c0)
    for name, target in problem.initial.items():
        opti.subject_to(values[model.column(name)] == target)
    for name, (low, high) in problem.initial_bounds.items():
        opti.subject_to(opti.bounded(low, values[model.column(name)], high))


def _begin(terms, x_k, guess, k: int):
    """(the interval's first state, its guess at fraction s): with a running cost, the
    state has the cost's integral from 0 last."""
    if terms.integrand is None:
        return x_k, partial(guess, k)
    return ca.vertcat(x_k, 0), lambda s: np.append(guess(k, s), 0.0)


def _with_design(shape: ControlShape, u, k: int, design, s):
    """c = [controls at fraction s of interval k; design]."""
    return ca.vertcat(shape.at(u, k, s), design)


def solve(model: JointModel, problem, transcription: str, settings: Mapping,
          start=None, push=None) -> JointResult:
    """The problem transcribed (module docstring) and solved; `start`: a previous result (its
    x and u) as the initial guess; `push`: the constant controls of the simulated guess."""
    for name in [*problem.terminal, *problem.terminal_cost, *problem.path,
                 *problem.terminal_bounds, *problem.initial, *problem.initial_bounds]:
        model.column(name)
    how, shape = method(problem, transcription), shape_of(problem)
    n, n_u = problem.intervals, model.n_u
    x_nodes, u_guess, guess = _guess(model, problem, shape, start,
                                     np.zeros(n_u) if push is None else push)
    opti = ca.Opti()
    h = _step(opti, problem)
    u = opti.variable(n_u, shape.values(n))
    opti.set_initial(u, u_guess.T)
    design = opti.variable(model.n_design)
    opti.set_initial(design, model.design_values)
    for k, (low, high) in enumerate(problem.parameters.values()):
        opti.subject_to(opti.bounded(low, design[k], high))
    x = opti.variable(model.n_x, n + 1)
    opti.set_initial(x, x_nodes.T)
    columns = costs.continued(model)  # angle columns continued past pi
    _start_state(opti, model, columns, problem, x[:, 0], _with_design(shape, u, 0, design, 0.0))
    closure = model.closure
    rows = closure.size1_out(0)
    t_sym, x_sym = closure.mx_in()
    jacobian = ca.Function("closure_jacobian", [t_sym, x_sym], [
        ca.jacobian(closure(t_sym, x_sym), x_sym)]) if rows else None
    samples, fine = [], [(model.t0, x[:, 0], _with_design(shape, u, 0, design, 0.0))]
    terms = costs.terms(model, problem, columns)
    rhs, running = model.rhs, 0
    if terms.integrand is not None:  # the running cost: a last state from 0 per interval
        rhs = costs.with_quadrature(model.rhs, terms.integrand, model.n_x)
    for k in range(n):
        t_k = model.t0 + k * h
        control = partial(_with_design, shape, u, k, design)
        begin, guess_k = _begin(terms, x[:, k], guess, k)
        end, points = how.interval(opti, rhs, t_k, h, begin, control, guess_k)
        if terms.integrand is not None:
            running += end[model.n_x]
            end = end[:model.n_x]
            points = [(t, s, xp[:model.n_x]) for t, s, xp in points]
        t_next = model.t0 + (k + 1) * h
        if rows:
            nu = opti.variable(rows)
            opti.set_initial(nu, 0)
            opti.subject_to(x[:, k + 1] - end == jacobian(t_next, x[:, k + 1]).T @ nu)
            opti.subject_to(closure(t_next, x[:, k + 1]) == 0)
        else:
            opti.subject_to(x[:, k + 1] == end)
        inner = [(t, xp, control(s)) for t, s, xp in points[:-1]]
        fine += inner + [(t_next, x[:, k + 1], control(1.0))]
        samples += (inner if problem.path_grid == "fine" else []) + [fine[-1]]
    _bounds(opti, problem, u)
    _path(opti, model, columns, problem, samples)
    horizon = h * n
    scales = ca.DM(np.sqrt(control_weights(problem)))
    cost = problem.effort * shape.effort(scales * u, h) + problem.time_weight * horizon
    c_end = _with_design(shape, u, n - 1, design, 1.0)
    cost += _terminal(opti, model, columns, problem, model.t0 + horizon, x[:, n], c_end) + running
    if terms.final is not None:
        cost += terms.final(model.t0 + horizon, x[:, n], c_end)
    opti.minimize(cost)
    if isinstance(how, SundialsShooting):  # no SX graph to expand; BFGS unless asked
        settings = {"ipopt.hessian_approximation": "limited-memory",
                    **{key: value for key, value in settings.items() if key != "expand"}}
    opti.solver("ipopt", dict(settings))
    try:
        result = opti.solve()
    except RuntimeError as error:
        raise AnalysisError(FailureContext(problem.horizon, f"the optimal control problem "
                                           f"({transcription}, joint coordinates) was not "
                                           f"solved: {error}"[:600], [])) from None
    stats = result.stats()
    times = model.t0 + float(result.value(h)) * np.arange(n + 1)
    fine_values = tuple(np.array([np.atleast_1d(result.value(v)) for v in part])
                        for part in zip(*fine, strict=True))
    return JointResult(times, np.atleast_2d(result.value(x)).T.reshape(n + 1, -1),
                       np.atleast_2d(result.value(u)).T.reshape(shape.values(n), -1),
                       float(result.value(opti.f)), str(stats.get("return_status")),
                       int(stats.get("iter_count", -1)),
                       float(stats.get("t_proc_total", np.nan)), fine_values,
                       np.atleast_1d(result.value(design)) if model.n_design else np.zeros(0))


def fine_columns(model: JointModel, fine, names) -> np.ndarray:
    """Results columns at the points of JointResult.fine."""
    index = [model.column(name) for name in names]
    return np.array([np.array(model.columns(t, x, c).full()).ravel()[index]
                     for t, x, c in zip(*fine, strict=True)])


def columns_at(model: JointModel, shape: ControlShape, times, x, u, names,
               design=()) -> np.ndarray:
    """Results columns at the nodes: node k > 0 with the control at the end of interval
    k - 1 (what path bounds constrain), node 0 with the first interval's."""
    index = [model.column(name) for name in names]
    rows = []
    for k, (t, state) in enumerate(zip(times, x, strict=True)):
        c = np.concatenate([np.asarray(shape.at(u.T, 0, 0.0) if k == 0 else
                                       shape.at(u.T, k - 1, 1.0), float).ravel(), design])
        rows.append(np.array(model.columns(t, state, c).full()).ravel()[index])
    return np.array(rows)
