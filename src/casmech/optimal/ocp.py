"""Optimal control: in joint coordinates for a tree (`formulation` auto or joints:
optimal/joint_ocp.py), else on the model's index-1 DAE in body coordinates (this module):
direct collocation or multiple shooting.

    problem = OCP(controls=[Control("pivot", "torque", -6, 6)], horizon=3.0, intervals=30,
                  terminal={"bar.z": 0.5, "bar.wx": 0.0})
    solution = solve(model, problem, "collocation")      # or "shooting"
    replay(model, problem, solution)                      # IDAS with the optimal controls

Controls are piecewise constant on `intervals` equal intervals; the objective is
effort * integral(u^T u) dt (exact for piecewise-constant u, so both transcriptions minimise the
same functional) plus terminal weights on results columns (in joint coordinates also integral,
tracking and final terms: optimal/costs.py); `terminal` targets are equality
constraints on results columns at the final time. The initial state is the model's assembled,
consistent state; the initial guess is a forward simulation with small constant controls.
Collocation: Radau IIA (degree 3) on x = [q, q_dot] with z = [q_ddot, lam] at the collocation
points, `elements` per control interval, optionally `stabilized` (GGL: Phi = 0 and
Phi_q q_dot = nu imposed at the points); multiple shooting: one IDAS integrator per interval
with its end state matched. `initial_guess="interpolation"` starts from guess.py's rest-to-rest
path instead of the forward simulation.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import field, replace

import casadi as ca
import numpy as np

from casmech.core.ipopt_options import settings as ipopt_settings
from casmech.core.records import record
from casmech.errors import AnalysisError, FailureContext, UsageError
from casmech.optimal import costs, joint_ocp, warm_start
from casmech.optimal.collocation import DirectCollocation
from casmech.optimal.compiled import Residuals, residuals
from casmech.optimal.controls import Control, control_forces
from casmech.optimal.dae import (
    DAE,
    algebraic_function,
    build_dae,
    columns_function,
    initial_state_function,
)
from casmech.optimal.guess import Guess, inverse_dynamics_controls, target_pose
from casmech.optimal.joint_ocp import (  # noqa: F401 (FORMULATIONS: the API)
    FORMULATIONS,
    control_weights,
    joints_of,
)
from casmech.optimal.sensitivity import idas
from casmech.optimal.system import parametric_system
from casmech.schema.resolved import ResolvedModel

DEGREE = 3
TRANSCRIPTIONS = ("collocation", "shooting")

INITIAL_GUESSES = ("simulation", "interpolation")
# MUMPS pivoting: with its default pivot tolerance (1e-6) the KKT matrices of the 3D arm
# (ocp_arm3d.yaml; absolute coordinates, a light payload) were reported with the wrong inertia
# at nearly every iteration, IPOPT regularised the Hessian by 1e5..1e8 and stalled (dual
# infeasibility 0.3 after 300 iterations); at 1e-4 the same problem converges in 18.
MUMPS = {"ipopt.mumps_pivtol": 1e-4, "ipopt.mumps_pivtolmax": 0.1}


@record
class OCP:
    controls: Sequence[Control]
    horizon: float
    intervals: int = 30
    effort: float = 1.0
    terminal: Mapping[str, float] = field(default_factory=dict)  # column -> value (equality)
    terminal_cost: Mapping[str, tuple[float, float]] = field(default_factory=dict)  # (w, target)
    path: Mapping[str, tuple[float, float]] = field(default_factory=dict)  # column bounds at nodes
    rtol: float = 1e-10
    atol: float = 1e-12
    guess: Sequence[float] | None = None  # constant controls of the initial simulation
    free_time: tuple[float, float] | None = None  # bounds of a free final time (horizon: guess)
    time_weight: float = 0.0  # objective term time_weight * (final time - t0)
    initial_guess: str = "simulation"  # or "interpolation" (guess.py)
    elements: int = 1  # collocation elements per control interval
    mode: str = "interpreted"  # collocation on interpreted | compiled | auto functions
    stabilized: bool = False  # collocation: position and velocity constraints at its points
    formulation: str = "auto"  # auto | joints | bodies (FORMULATIONS)
    degree: int = 3  # joints: collocation polynomial degree
    scheme: str = "radau"  # joints: collocation points, radau | legendre
    piecewise: str = "constant"  # joints: controls constant | linear over each interval
    steps: int = 4  # joints: RK4 steps per interval of multiple shooting
    path_grid: str = "nodes"  # joints: path bounds at the nodes | also inside (fine)
    weights: Mapping[str, float] = field(default_factory=dict)  # control name -> effort weight
    terminal_bounds: Mapping[str, tuple[float, float]] = field(default_factory=dict)
    # decision parameters: model parameters -> (low, high), optimised with the controls
    parameters: Mapping[str, tuple[float, float]] = field(default_factory=dict)
    initial_free: bool = False  # joints: the initial state a variable (on the constraints)
    initial: Mapping[str, float] = field(default_factory=dict)  # column -> value at t0
    initial_bounds: Mapping[str, tuple[float, float]] = field(default_factory=dict)
    # joints: Lagrange terms, expression -> weight (or its resolved (function, weight)):
    # weight * integral expression^2 dt; a Mayer term (expression at the end); tracking,
    # column -> (function of t, weight): weight * integral (column - function)^2 dt
    integral: Mapping[str, object] = field(default_factory=dict)
    final: object = None
    track: Mapping[str, tuple] = field(default_factory=dict)
    solver: Mapping[str, object] = field(default_factory=dict)  # IPOPT options (no prefix)
    guess_file: tuple[str, str] | None = None  # a previous result (optimal/warm_start.py)
    integrator: str = "rk4"  # joints, shooting: rk4 | cvodes | idas (optimal/shooting.py)


def default_guess(problem: OCP) -> np.ndarray:
    """A small push (10% of each finite upper bound): at rest the gradients of terminal
    conditions on orientations often vanish, and IPOPT then declares the problem infeasible."""
    if problem.guess is not None:
        return np.asarray(problem.guess, float)
    return np.array([0.1 * c.upper if np.isfinite(c.upper) else 0.0 for c in problem.controls])


@record
class Solution:
    transcription: str
    times: np.ndarray  # interval boundaries (intervals + 1)
    x: np.ndarray  # (intervals + 1, 2 n) states at the boundaries
    u: np.ndarray  # (intervals, n_u)
    objective: float
    status: str
    iterations: int
    formulation: str = "bodies"  # joints: x holds joint coordinates and velocities
    solver_time: float = float("nan")  # IPOPT's own time [s]
    fine: tuple | None = None  # joints: (times, states, controls) inside the intervals too
    design: np.ndarray = field(default_factory=lambda: np.zeros(0))  # decision parameters

    @property
    def step(self) -> float:
        return float(self.times[1] - self.times[0])


@record
class _Setup:
    dae: DAE
    x0: np.ndarray
    columns: ca.Function
    names: list[str]
    algebraic: ca.Function
    step: float
    functions: Residuals  # the residual and kinematics the collocation imposes


@record
class _Start:
    """The initial guess: states at the interval boundaries, controls, the step and, when
    known, the states at any time (for the collocation points)."""

    x: np.ndarray
    u: np.ndarray
    step: float
    state: Callable[[float], np.ndarray] | None = None

    def at(self, t: float, k: int) -> np.ndarray:
        return self.x[k + 1] if self.state is None else self.state(t)


def _setup(model: ResolvedModel, problem: OCP) -> _Setup:
    if problem.horizon <= 0 or problem.intervals < 1:
        raise UsageError("the horizon must be positive and intervals at least 1")
    controls = control_forces(model, problem.controls)
    dae = build_dae(parametric_system(model), controls)
    names, columns = columns_function(dae)
    for name in [*problem.terminal, *problem.terminal_cost, *problem.path,
                 *problem.terminal_bounds]:
        if name not in names:
            raise UsageError(f"unknown column '{name}' in the optimal control problem; "
                             "columns are results columns (<body>.x, <joint>.fx, energy, ...)")
    x0 = initial_state_function(dae)(np.zeros(0)).full().ravel()
    return _Setup(dae, x0, columns, names, algebraic_function(dae),
                  problem.horizon / problem.intervals,
                  residuals(model, dae, controls, problem.mode))


def _columns(setup: _Setup, t, x, u, z=None):
    """Every results column (without t) at a state; z (accelerations, multipliers) is solved
    for when not given. The DAE's p is [theta (empty), u]."""
    z = setup.algebraic(t, x, u) if z is None else z
    return setup.columns(t, x, z, ca.DM.zeros(0))


def _column(setup: _Setup, name: str, t, x, u, z=None):
    return _columns(setup, t, x, u, z)[setup.names.index(name)]


def _objective_and_terminal(opti, setup: _Setup, problem: OCP, step, x_end, u_last, z_end,
                            u_all):
    horizon = step * problem.intervals
    scales = ca.DM(np.sqrt(control_weights(problem)))
    cost = problem.effort * step * ca.sumsqr(scales * u_all) + problem.time_weight * horizon
    t_end = setup.dae.t0 + horizon
    for name, (weight, target) in problem.terminal_cost.items():
        cost += weight * (_column(setup, name, t_end, x_end, u_last, z_end) - target) ** 2
    for name, target in problem.terminal.items():
        opti.subject_to(_column(setup, name, t_end, x_end, u_last, z_end) == target)
    for name, (low, high) in problem.terminal_bounds.items():
        opti.subject_to(opti.bounded(low, _column(setup, name, t_end, x_end, u_last, z_end),
                                     high))
    return cost


def _path(opti, setup: _Setup, problem: OCP, step, x, u, z):
    """Bounds on results columns at every interval boundary after the first (z[k - 1]: the
    algebraic states there, with the control of the interval that ends there)."""
    for name, (low, high) in problem.path.items():
        for k in range(1, problem.intervals + 1):
            t = setup.dae.t0 + k * step
            value = _column(setup, name, t, x[:, k], u[:, k - 1], z[k - 1])
            opti.subject_to(opti.bounded(low, value, high))


def _bounds(opti, problem: OCP, u):
    for k, control in enumerate(problem.controls):
        if np.isfinite(control.lower):
            opti.subject_to(u[k, :] >= control.lower)
        if np.isfinite(control.upper):
            opti.subject_to(u[k, :] <= control.upper)


def _simulated(setup: _Setup, problem: OCP) -> _Start:
    """States at the interval boundaries of a forward simulation with constant controls."""
    u = np.tile(default_guess(problem), (problem.intervals, 1))
    return _Start(replay_states(setup, problem, u), u, setup.step)


def _interpolated(setup: _Setup, problem: OCP) -> _Start:
    """Rest to rest from the initial pose to one meeting the terminal conditions (guess.py)."""
    dae, n = setup.dae, setup.dae.n
    q_end = target_pose(dae, setup.columns, setup.names, dict(problem.terminal), setup.x0[:n])
    path = Guess(dae, setup.x0[:n], q_end, problem.horizon)
    times = dae.t0 + setup.step * np.arange(problem.intervals + 1)
    lower = [c.lower for c in problem.controls]
    upper = [c.upper for c in problem.controls]
    u = inverse_dynamics_controls(dae, path.rates, times, lower, upper)
    x = np.array([setup.x0, *(path.state(t) for t in times[1:])])
    return _Start(x, u, setup.step, path.state)


def _start(setup: _Setup, problem: OCP, solution: Solution | None) -> _Start:
    if solution is not None and solution.formulation == "bodies":
        return _Start(solution.x, solution.u, solution.step)
    if problem.initial_guess not in INITIAL_GUESSES:
        raise UsageError(f"initial guess '{problem.initial_guess}' is not one of "
                         f"{', '.join(INITIAL_GUESSES)}")
    return (_interpolated if problem.initial_guess == "interpolation" else _simulated)(
        setup, problem)


def replay_states(setup: _Setup, problem: OCP, u: np.ndarray, step: float | None = None):
    """IDAS through every interval with its constant control (rtol/atol of the problem)."""
    dae, xs, step = setup.dae, [setup.x0], setup.step if step is None else step
    for k in range(problem.intervals):
        t0 = dae.t0 + k * step
        integrator = idas(dae, [t0 + step], problem.rtol, problem.atol, t0=t0)
        z0 = setup.algebraic(t0, xs[-1], u[k]).full().ravel()
        xs.append(integrator(x0=xs[-1], z0=z0, p=u[k])["xf"].full().ravel())
    return np.array(xs)


def _collocation(opti, setup: _Setup, problem: OCP, step, u, start: _Start):
    """Radau IIA on `elements` equal elements per control interval (the control is constant
    over the interval; more elements: a more accurate trajectory for the same controls)."""
    dae = setup.dae
    tau = np.append(0, ca.collocation_points(DEGREE, "radau"))
    x = opti.variable(dae.x.numel(), problem.intervals + 1)
    opti.subject_to(x[:, 0] == setup.x0)
    opti.set_initial(x, start.x.T)
    ends = []
    for k in range(problem.intervals):
        end = x[:, k]
        for e in range(problem.elements):
            end, z_end = _element(opti, setup, problem, (step, start), u[:, k], end,
                                  (k, e, tau))
        opti.subject_to(x[:, k + 1] == end)  # Radau: the last point is the element's end
        ends.append(z_end)
    return x, ends


def _element(opti, setup: _Setup, problem: OCP, steps, u, begin, where):
    """One collocation element of control interval k: states at the DEGREE Radau points and
    algebraic states there; returns (state, algebraic state) at its end."""
    (step, start), (k, e, tau) = steps, where
    dae, elements = setup.dae, problem.elements
    f = setup.functions.residual
    xc, zc = opti.variable(dae.x.numel(), DEGREE), opti.variable(dae.z.numel(), DEGREE)
    times = dae.t0 + (k + (e + tau[1:]) / elements) * start.step
    x_guess = np.array([start.at(t, k) for t in times]).T
    opti.set_initial(xc, x_guess)
    opti.set_initial(zc, np.hstack([setup.algebraic(t, x_guess[:, j], start.u[k]).full()
                                    for j, t in enumerate(times)]))
    points = ca.horzcat(begin, xc)
    coefficients = DirectCollocation(DEGREE, "radau").coefficients[0]  # slopes at tau
    for j in range(1, DEGREE + 1):
        slope = points @ ca.DM(coefficients[:, j])
        t = dae.t0 + (k + (e + tau[j]) / elements) * step
        ode, alg = f(t, points[:, j], zc[:, j - 1], u)
        if problem.stabilized:
            ode = ode + _stabilization(opti, setup, t, points[:, j])
        opti.subject_to(slope == step / elements * ode)
        opti.subject_to(alg == 0)
    return xc[:, DEGREE - 1], zc[:, DEGREE - 1]


def _stabilization(opti, setup: _Setup, t, x):
    """Gear-Gupta-Leimkuhler terms at a collocation point: q' = q_dot + Phi_q^T mu and
    q_dot' = q_ddot + Phi_q^T eta, with Phi(q) = 0 and Phi_q q_dot = nu imposed there. The
    index-1 DAE keeps these invariants only to the discretisation error, and the optimiser
    exploits the drift (links that stretch); mu and eta vanish on the exact solution."""
    rows = len(setup.dae.rows)
    phi, phi_q, nu = setup.functions.kinematics(t, x)
    mu, eta = opti.variable(rows), opti.variable(rows)
    opti.set_initial(mu, 0)
    opti.set_initial(eta, 0)
    opti.subject_to(phi == 0)
    opti.subject_to(phi_q @ x[setup.dae.n:] == nu)
    return ca.vertcat(phi_q.T @ mu, phi_q.T @ eta)


def _scaled_integrator(dae: DAE, k: int, problem: OCP, name: str) -> ca.Function:
    """IDAS over interval k in scaled time s in [0, 1] (t = t0 + (k + s) h, h a parameter):
    p = [theta, u, h]. Used when the final time is free."""
    s, h = ca.SX.sym("s"), ca.SX.sym("h")
    t = dae.t0 + (k + s) * h
    ode, alg = (ca.substitute(e, dae.t, t) for e in (dae.ode, dae.alg))
    problem_dae = {"t": s, "x": dae.x, "z": dae.z, "p": ca.vertcat(dae.p, h), "ode": h * ode,
                   "alg": alg}
    options = {"abstol": problem.atol, "reltol": problem.rtol, "calc_ic": True,
               "max_num_steps": 100000}
    return ca.integrator(name, "idas", problem_dae, 0.0, [1.0], options)


def _shooting(opti, setup: _Setup, problem: OCP, step, u, start: _Start):
    dae = setup.dae
    x = opti.variable(dae.x.numel(), problem.intervals + 1)
    opti.subject_to(x[:, 0] == setup.x0)
    opti.set_initial(x, start.x.T)
    for k in range(problem.intervals):
        t0 = dae.t0 + k * setup.step
        z0 = setup.algebraic(t0, start.x[k], start.u[k]).full().ravel()
        if problem.free_time is None:
            integrator = idas(dae, [t0 + setup.step], problem.rtol, problem.atol, t0=t0,
                              name=f"F{k}")
            end = integrator(x0=x[:, k], z0=z0, p=u[:, k])["xf"]
        else:
            integrator = _scaled_integrator(dae, k, problem, f"F{k}")
            end = integrator(x0=x[:, k], z0=z0, p=ca.vertcat(u[:, k], step))["xf"]
        opti.subject_to(x[:, k + 1] == end)
    ends = [setup.algebraic(dae.t0 + (k + 1) * step, x[:, k + 1], u[:, k])
            for k in range(problem.intervals)]
    return x, ends


def _step(opti, problem: OCP, guess: float):
    """The interval length: a number, or a variable when the final time is free."""
    if problem.free_time is None:
        return problem.horizon / problem.intervals
    low, high = problem.free_time
    if not 0 < low <= high:
        raise UsageError(f"free final time bounds must satisfy 0 < low <= high, got {low}, {high}")
    step = opti.variable()
    opti.subject_to(opti.bounded(low / problem.intervals, step, high / problem.intervals))
    opti.set_initial(step, guess)
    return step


BUILDERS = {"collocation": _collocation, "shooting": _shooting}


def solve(model: ResolvedModel, problem: OCP, transcription: str = "collocation",
          verbose: bool = False, max_iter: int = 500, start: Solution | None = None,
          options: Mapping | None = None) -> Solution:
    """Solve with `transcription`; `start` (another solution) replaces the initial simulation
    as the initial guess (multiple shooting from a collocation solution is far more robust:
    IDAS fails on the wild states IPOPT tries first from a poor guess)."""
    if transcription not in TRANSCRIPTIONS:
        raise UsageError(f"transcription '{transcription}' is not one of "
                         f"{', '.join(TRANSCRIPTIONS)}")
    settings = {"ipopt.print_level": 5 if verbose else 0, "print_time": verbose,
                "ipopt.sb": "yes", "ipopt.max_iter": max_iter, "ipopt.tol": 1e-10, **MUMPS,
                **ipopt_settings(problem.solver.items())}
    problem = replace(problem, **costs.parsed(problem, model.parameters))
    joints = joints_of(model, problem)
    if start is None and problem.guess_file is not None:
        start = warm_start.solution(model, problem, joints)
    if joints is not None:
        found = joint_ocp.solve(joints, problem, transcription,
                                {**settings, "expand": True, **(options or {})},
                                start if start is not None and start.formulation == "joints"
                                else None, default_guess(problem))
        return Solution(transcription, found.times, found.x, found.u, found.objective,
                        found.status, found.iterations, "joints", found.solver_time,
                        found.fine, found.design)
    setup = _setup(model, problem)
    initial = _start(setup, problem, start)
    opti = ca.Opti()
    u = opti.variable(len(problem.controls), problem.intervals)
    opti.set_initial(u, initial.u.T)
    step = _step(opti, problem, initial.step)
    x, z = BUILDERS[transcription](opti, setup, problem, step, u, initial)
    _bounds(opti, problem, u)
    _path(opti, setup, problem, step, x, u, z)
    opti.minimize(_objective_and_terminal(opti, setup, problem, step, x[:, -1], u[:, -1], z[-1],
                                          u))
    if transcription == "shooting" or setup.functions.mode == "compiled":
        # IDAS and the compiled externals give first derivatives only
        settings["ipopt.hessian_approximation"] = "limited-memory"
    else:
        settings["expand"] = True  # SX graphs: far faster exact Hessians for IPOPT
    opti.solver("ipopt", {**settings, **(options or {})})
    try:
        result = opti.solve()
    except RuntimeError as error:
        raise AnalysisError(FailureContext(problem.horizon, f"the optimal control problem "
                                           f"({transcription}) was not solved: {error}"[:600],
                                           [])) from None
    stats = result.stats()
    times = setup.dae.t0 + float(result.value(step)) * np.arange(problem.intervals + 1)
    return Solution(transcription, times, np.atleast_2d(result.value(x)).T,
                    np.atleast_2d(result.value(u)).T.reshape(problem.intervals, -1),
                    float(result.value(opti.f)), str(stats.get("return_status")),
                    int(stats.get("iter_count", -1)),
                    solver_time=float(stats.get("t_proc_total", np.nan)))


def replay(model: ResolvedModel, problem: OCP, solution: Solution) -> np.ndarray:
    """States at the interval boundaries from IDAS driven by the solution's controls (body
    coordinates, from the initial state); joint coordinates: each node's successor
    integrated from that node (joint_ocp.replay_nodes, DOP853)."""
    if solution.formulation == "joints":
        return joint_ocp.replay_nodes(joints_of(model, problem), joint_ocp.shape_of(problem),
                                      solution.times, solution.x, solution.u, solution.design)
    return replay_states(_setup(model, problem), problem, solution.u, solution.step)


def replay_error(model: ResolvedModel, problem: OCP, solution: Solution) -> float:
    """The largest difference of the replay's positions (joint coordinates, or body
    coordinates) from the solution's at the nodes."""
    replayed = replay(model, problem, solution)
    n = replayed.shape[1] // 2
    if solution.formulation == "joints":
        n = joints_of(model, problem).equations.n_coordinates
    return float(np.max(np.abs(replayed[:, :n] - solution.x[:, :n])))


def columns_at(model: ResolvedModel, problem: OCP, solution: Solution,
               names: Sequence[str]) -> np.ndarray:
    """Results columns of the solution's states at its interval boundaries. Accelerations and
    reactions depend on the control, which jumps there: boundary k > 0 reports the end of
    interval k - 1 (the value path bounds constrain), boundary 0 the start of interval 0."""
    if solution.formulation == "joints":
        return joint_ocp.columns_at(joints_of(model, problem), joint_ocp.shape_of(problem),
                                    solution.times, solution.x, solution.u, names,
                                    solution.design)
    setup = _setup(model, problem)
    index = [setup.names.index(n) for n in names]
    rows = []
    for k, (t, x) in enumerate(zip(solution.times, solution.x, strict=True)):
        u = solution.u[max(k - 1, 0)]
        rows.append(_columns(setup, t, x, u).full().ravel()[index])
    return np.array(rows)


def from_block(block) -> tuple[OCP, str]:
    """The problem and transcription of a model's `ocp:` block (schema.resolved)."""
    controls = [Control(c.joint, c.type, c.lower, c.upper) for c in block.controls]
    return OCP(controls, block.horizon, block.intervals, block.effort, dict(block.terminal),
               dict(block.terminal_cost), dict(block.path), free_time=block.free_time,
               time_weight=block.time_weight, initial_guess=block.initial_guess,
               elements=block.elements, stabilized=block.stabilized,
               formulation=block.formulation, degree=block.degree, scheme=block.scheme,
               piecewise=block.piecewise, steps=block.steps,
               path_grid=block.path_grid, weights=dict(block.weights),
               terminal_bounds=dict(block.terminal_bounds),
               parameters=dict(block.parameters), initial_free=block.initial_free,
               initial=dict(block.initial), initial_bounds=dict(block.initial_bounds),
               integral=dict(block.integral), final=block.final, track=dict(block.track),
               solver=dict(block.solver), guess_file=block.guess_file,
               integrator=block.integrator), block.transcription


def fine_columns(model: ResolvedModel, problem: OCP, solution: Solution,
                 names: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
    """(times, columns) at the nodes and at every point inside the intervals of a joint
    solution (collocation points, RK4 step ends)."""
    if solution.fine is None:
        raise UsageError("only a solution in joint coordinates has points inside its intervals")
    return solution.fine[0], joint_ocp.fine_columns(joints_of(model, problem), solution.fine,
                                                    names)


def results_table(model: ResolvedModel, problem: OCP, solution: Solution):
    """(names, values): t and every results column at the interval boundaries."""
    names = (joints_of(model, problem).names if solution.formulation == "joints"
             else _setup(model, problem).names)
    return ["t", *names], np.column_stack(
        [solution.times, columns_at(model, problem, solution, names)])
