"""A Python controller of a dynamics run: `controller(t, state) -> efforts` gives the torque or
force of effort motors the model declares, as a function of the continuous state.

The controlled motors' laws are replaced by inputs u (as the FMU's inputs replace them,
fmu.model), the system functions and the joint formulation's built over u as their trailing
data (model.parametric's mechanism), and each function that reads u is bound to
u = controller(t, q, q_dot), a casadi.Callback of the r-p state: the integrator's residual or
ODE calls the controller at every evaluation, so the run is the exact solution of the closed
loop (no sampling). The integrators' Jacobians differentiate through the callback by CasADi's
finite differences (`enable_fd`): the one place of casmech that CasADi's AD cannot reach,
since the controller is opaque Python. A Python call per evaluation makes such a run slower
than the same law written as an expression in the model.

The state the controller reads (ControllerState) holds, by results column name, the
position and velocity columns of the bodies and joints at (t, q, q_dot): `<body>.x .. .wz`,
`<joint>.angle`, `.angle_dot`, ... (no accelerations or reactions: they depend on the efforts).

A controller that raises, returns a value that is not finite, or the wrong names or shape,
stops the run; the rows before it are kept, and the error names the time and the fault
(ControllerFault, raised by `run` as an AnalysisError).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import replace

import casadi as ca
import numpy as np

from casmech.core.columns import BODY_COLUMNS
from casmech.elements.forces.terms import Input
from casmech.equations import readings
from casmech.equations.functions import SystemFunctions, build_functions
from casmech.errors import AnalysisError, FailureContext, UsageError
from casmech.formulations.joint_system import build as build_joint_system
from casmech.formulations.tree import spanning_tree
from casmech.model.ir import ModelIR
from casmech.runtime import workspace
from casmech.runtime.buffers import BufferedCall
from casmech.runtime.cancel import CancelToken

# ForceIR type of an effort motor -> the suffix of its input's name
KINDS = {"motor_torque": "torque", "motor_force": "force"}
STATE_BODY_COLUMNS = BODY_COLUMNS[:13]  # position, Euler parameters, velocity, angular velocity
JOINT_SYSTEM_NAMES = ("joint_motion", "joint_acceleration_system", "joint_velocity_jacobian",
                      "joint_relative_states")


def inputs(ir: ModelIR) -> list[str]:
    """`<joint>.torque` / `<joint>.force` of every effort motor, in the IR's order."""
    return [f"{motor.name}.{KINDS[motor.type]}" for motor in ir.motors]


def chosen(ir: ModelIR, controls: Sequence[str] | str | None) -> list[str]:
    """The controlled inputs: `controls` (a motor's input name, or its joint's name where the
    joint has one effort motor), by default every effort motor; a UsageError otherwise."""
    every = inputs(ir)
    if not every:
        raise UsageError("a controller drives effort motors, and this model has none: declare "
                         "one on the controlled joint, e.g. `motor: {torque: 0}` (its law is "
                         "replaced by the controller's value during the run)")
    if controls is None:
        return every
    names = [controls] if isinstance(controls, str) else list(controls)
    picked = []
    for name in names:
        matches = [i for i in every if i == name or i.rsplit(".", 1)[0] == name]
        if len(matches) != 1:
            why = "names two effort motors" if matches else "is not an effort motor"
            raise UsageError(f"controls: '{name}' {why} of the model; effort motors: "
                             f"{', '.join(every)}")
        if matches[0] in picked:
            raise UsageError(f"controls: '{name}' is given twice")
        picked.append(matches[0])
    return picked


class ControllerState(Mapping):
    """The state a controller reads: `state["crank.angle"]`, `state["block.vx"]`, ...;
    `t`, and `q`, `q_dot` (the r-p coordinates: 3 positions per body, then 4 Euler parameters
    per body). Read-only."""

    def __init__(self, t: float, index: Mapping[str, int], values: np.ndarray, q, q_dot):
        self.t, self.q, self.q_dot = t, q, q_dot
        self._index = index  # column name -> its place in `values`
        self._values = values

    def __getitem__(self, name: str) -> float:
        try:
            return float(self._values[self._index[name]])
        except KeyError:
            raise KeyError(f"'{name}' is not a state column; a controller reads the bodies' "
                           f"{', '.join(STATE_BODY_COLUMNS)} and the joints' positions and "
                           f"rates (ControllerState.keys())") from None

    def __iter__(self) -> Iterator[str]:
        return iter(self._index)

    def __len__(self) -> int:
        return len(self._index)

    def __repr__(self) -> str:
        return f"ControllerState(t={self.t:.6g}, {len(self)} columns)"


def state_function(ir: ModelIR, names: Sequence[str]) -> tuple[list[str], ca.Function]:
    """(the state's column names, (t, q, q_dot) -> their values): the body columns and the
    joint columns that depend on no acceleration (`names`: the body names)."""
    nb = ir.n_bodies
    t, q, q_dot = ca.SX.sym("t"), ca.SX.sym("q", 7 * nb), ca.SX.sym("q_dot", 7 * nb)
    q_ddot = ca.SX.sym("q_ddot", 7 * nb)
    n_joints = len(ir.joints)
    joints = readings.columns_function(ir)(t, q, q_dot, q_ddot, ca.SX.zeros(3, n_joints),
                                           ca.SX.zeros(3, n_joints))
    joint_names = readings.joint_state_names(ir)
    keep = [k for k in range(len(joint_names)) if not ca.depends_on(joints[k], q_ddot)]
    columns, values = [], []
    for k, body in enumerate(names):
        p = q[3 * nb + 4 * k:3 * nb + 4 * k + 4]
        p_dot = q_dot[3 * nb + 4 * k:3 * nb + 4 * k + 4]
        # omega = 2 G(p) p_dot (global), as the results' body rates
        e0, e = p[0], p[1:]
        g = ca.horzcat(-e, -ca.skew(e) + e0 * ca.SX.eye(3))
        omega = 2 * g @ p_dot
        values += [q[3 * k:3 * k + 3], p, q_dot[3 * k:3 * k + 3], omega]
        columns += [f"{body}.{c}" for c in STATE_BODY_COLUMNS]
    values += [joints[k] for k in keep]
    columns += [joint_names[k] for k in keep]
    return columns, ca.Function("controller_state", [t, q, q_dot],
                                [ca.densify(ca.vertcat(*values))], ["t", "q", "q_dot"],
                                ["state"])


class ControllerFault(Exception):
    """What was wrong with the controller at time t (run turns it into an AnalysisError)."""

    def __init__(self, t: float, message: str):
        self.t, self.message = t, message
        super().__init__(message)


class FaultToken(CancelToken):
    """The run's cancellation token: cancelled by the caller's (`parent`, or Ctrl-C's) or by
    a controller fault, without cancelling the caller's own."""

    def __init__(self, parent: CancelToken | None):
        self.parent, self._own = parent, None
        super().__init__()

    @property
    def signum(self) -> int | None:
        if self._own is not None:
            return self._own
        return self.parent.signum if self.parent is not None else None

    @signum.setter
    def signum(self, value: int | None) -> None:
        self._own = value


class Law(ca.Callback):
    """u = controller(t, state) as a casadi.Callback of (t, q, q_dot); derivatives by CasADi's
    finite differences of it (enable_fd). A fault is kept in `fault`, the run's token
    (`token`) cancelled and KeyboardInterrupt raised, which CasADi turns into the RuntimeError
    the runtime takes for a cancellation (runtime.cancel.check: no traceback printed, the rows
    so far kept); every later evaluation raises the same at once."""

    def __init__(self, controller: Callable, controls: Sequence[str], ir: ModelIR,
                 body_names: Sequence[str]):
        ca.Callback.__init__(self)
        self.controller, self.controls = controller, list(controls)
        self.n_q = 7 * ir.n_bodies
        names, function = state_function(ir, body_names)
        self.index = {name: k for k, name in enumerate(names)}
        self.state = BufferedCall(function)
        self.fault: ControllerFault | None = None
        self.calls = 0
        self.token = FaultToken(None)  # cancelled at a fault (run passes it to the run)
        self.construct("controller", {"enable_fd": True})

    def get_n_in(self):
        return 3

    def get_n_out(self):
        return 1

    def get_name_in(self, i):
        return ("t", "q", "q_dot")[i]

    def get_name_out(self, i):
        return "u"

    def get_sparsity_in(self, i):
        return ca.Sparsity.dense(1 if i == 0 else self.n_q, 1)

    def get_sparsity_out(self, i):
        return ca.Sparsity.dense(len(self.controls), 1)

    def eval(self, arg):
        t = float(arg[0])
        if self.fault is not None:
            raise KeyboardInterrupt
        q, q_dot = (np.array(a.nonzeros()) for a in arg[1:])  # dense columns
        try:
            values = self.efforts(t, q, q_dot)
        except ControllerFault as fault:
            self.fault = fault
            self.token.cancel()  # the run stops at its next poll, its rows kept
            raise KeyboardInterrupt from None
        return [ca.DM(values)]

    def efforts(self, t: float, q: np.ndarray, q_dot: np.ndarray) -> np.ndarray:
        """The controller's efforts at (t, q, q_dot) in `controls` order, checked."""
        self.calls += 1
        (values,) = self.state(t, q, q_dot)
        state = ControllerState(t, self.index, values.ravel(), q, q_dot)
        name = getattr(self.controller, "__qualname__", type(self.controller).__name__)
        try:
            returned = self.controller(t, state)
        except Exception as error:  # noqa: BLE001 -- the user's code: reported, located
            raise ControllerFault(t, f"the controller {name} raised {type(error).__name__}: "
                                     f"{error}") from None
        values = self._values(returned, name, t)
        if not np.isfinite(values).all():
            bad = [c for c, v in zip(self.controls, values, strict=True) if not np.isfinite(v)]
            raise ControllerFault(t, f"the controller {name} returned a value that is not "
                                     f"finite for {', '.join(bad)}")
        return values

    def _values(self, returned, name: str, t: float) -> np.ndarray:
        """The returned efforts as an array in `controls` order (a mapping by input or joint
        name, a sequence in that order, or a number for one control)."""
        n = len(self.controls)
        order = ", ".join(self.controls)
        if isinstance(returned, Mapping):
            by_name = {}
            for key, value in returned.items():
                matches = [c for c in self.controls if key in (c, c.rsplit(".", 1)[0])]
                if len(matches) != 1 or matches[0] in by_name:
                    raise ControllerFault(t, f"the controller {name} returned the key '{key}', "
                                             f"which is not one of the controlled motors "
                                             f"({order})")
                by_name[matches[0]] = value
            missing = [c for c in self.controls if c not in by_name]
            if missing:
                raise ControllerFault(t, f"the controller {name} returned no value for "
                                         f"{', '.join(missing)} (controlled: {order})")
            returned = [by_name[c] for c in self.controls]
        try:
            values = np.asarray(returned, dtype=float)
        except (TypeError, ValueError):
            raise ControllerFault(t, f"the controller {name} returned {type(returned).__name__}"
                                     f", not a mapping of efforts by name or {n} numbers in "
                                     f"the order {order}") from None
        if values.shape not in ((n,), ()) or (values.shape == () and n != 1):
            raise ControllerFault(t, f"the controller {name} returned shape {values.shape}; "
                                     f"expected {n} number{'s' if n > 1 else ''} in the order "
                                     f"{order}, or a mapping by name")
        return values.reshape(n)


def with_inputs(ir: ModelIR, controls: Sequence[str], u: ca.SX) -> ModelIR:
    """The IR with the controlled motors' laws replaced by the inputs u."""
    index = {name: k for k, name in enumerate(controls)}
    motors = tuple(
        replace(m, actuator=Input(u[index[f"{m.name}.{KINDS[m.type]}"]]))
        if f"{m.name}.{KINDS[m.type]}" in index else m for m in ir.motors)
    return replace(ir, motors=motors)


def _bound(function: ca.Function, data: Callable, law: Callable, u: ca.SX) -> ca.Function:
    """`function` without its trailing input, which is data(u): u the law's value at the
    function's own (t, q, q_dot) (law(inputs by name) -> u), or zeros where the function does
    not read u."""
    names = function.name_in()[:-1]
    inputs = [ca.MX.sym(n, function.sparsity_in(k)) for k, n in enumerate(names)]
    symbolic = function.call([*function.sx_in()[:-1], data(u)])
    reads = any(ca.depends_on(ca.vec(out), u) for out in symbolic if out.numel())
    value = law(dict(zip(names, inputs, strict=True))) if reads else ca.DM.zeros(u.numel())
    outputs = function.call([*inputs, data(value)])
    return ca.Function(function.name(), inputs, outputs, names, function.name_out())


class _BoundFunctions(Mapping):
    """The functions of `source()` (each with trailing data input), bound when first read."""

    def __init__(self, source: Callable[[], Mapping], bind: Callable[[ca.Function], ca.Function]):
        self._source, self._bind = source, bind
        self._made: Mapping | None = None
        self._bound: dict[str, ca.Function] = {}

    @property
    def source(self) -> Mapping:
        """The functions as built, with their trailing data input."""
        if self._made is None:
            self._made = self._source()
        return self._made

    def __getitem__(self, name: str) -> ca.Function:
        if name not in self._bound:
            self._bound[name] = self._bind(self.source[name])
        return self._bound[name]

    def __iter__(self):
        return iter(self.source)

    def __len__(self) -> int:
        return len(self.source)


def controlled(functions: SystemFunctions, controller: Callable,
               controls: Sequence[str] | str | None = None) -> tuple[SystemFunctions, Law]:
    """The bundle (interpreted) whose controlled motors take the controller's efforts, and the
    Law it calls (its `fault` says what went wrong with the controller), kept in the
    functions' workspace for later runs with the same controls and controller (the Law holds
    the controller, so its id stays its own while kept), its fault and token reset."""
    if not callable(controller):
        raise UsageError(f"controller must be callable as controller(t, state), not "
                         f"{type(controller).__name__}")
    names = chosen(functions.ir, controls)
    bundle, law = workspace.default(functions).kept(
        "controlled", (tuple(names), id(controller)),
        lambda: _controlled(functions, controller, names))
    law.fault, law.calls, law.token = None, 0, FaultToken(None)
    return bundle, law


def _controlled(functions: SystemFunctions, controller: Callable,
                names: list[str]) -> tuple[SystemFunctions, Law]:
    ir = functions.ir
    law = Law(controller, names, ir, functions.body_names)
    u = ca.SX.sym("u", len(names))
    controlled_ir = with_inputs(ir, names, u)

    def rp_law(given: dict):
        """u at a function's (t, q, q_dot), or (t, q, v): the r-omega velocities."""
        q_dot = given.get("q_dot")
        if q_dot is None and "v" in given:  # (q_dot(q, v) reads no effort)
            q_dot = system_functions.source["romega_q_dot"](given["q"], given["v"],
                                                            ca.DM.zeros(len(names)))
        if q_dot is None or "t" not in given or "q" not in given:
            raise AssertionError("a function reads the controls without the state")
        return law(given["t"], given["q"], q_dot)

    system_functions = _BoundFunctions(
        lambda: build_functions(controlled_ir, u).functions,
        lambda f: _bound(f, lambda v: v, rp_law, u))
    joint_state: dict = {}

    def joint_system():
        if "system" not in joint_state:
            joint_state["system"] = build_joint_system(controlled_ir, spanning_tree(ir), u)
        return joint_state["system"]

    def joint_sources() -> dict[str, ca.Function]:
        system = joint_system()
        sources = dict(zip(JOINT_SYSTEM_NAMES, (system.motion, system.acceleration_system,
                                               system.velocity_jacobian,
                                               system.relative_states), strict=True))
        return {system.dynamics.name(): system.dynamics, **sources}

    def joint_law(given: dict):
        system = joint_system()
        m = system.n_cut
        rest = system.data(ca.DM.zeros(len(names)))  # positions and rates read no effort
        q, q_dot = system.motion(given["t"], given["x"], ca.DM.zeros(2 * m),
                                 ca.DM.ones(ir.n_bodies), rest)[:2]
        return law(given["t"], q, q_dot)

    joint_functions = _BoundFunctions(
        joint_sources, lambda f: _bound(f, lambda v: joint_system().data(v), joint_law, u))
    bundle = replace(functions, functions=system_functions, data=None, mode="interpreted",
                     joint_functions=joint_functions, parametric=None)
    return bundle, law


class _Rows:
    """A progress callback that also keeps the Result its rows go to (Result.on_row's
    `rows_added`), so the rows before a fault are kept whatever the solver raised."""

    def __init__(self, progress: Callable | None):
        self.progress, self.result = progress, None

    def __call__(self, t: float) -> None:
        if self.progress is not None:
            self.progress(t)

    def rows_added(self, result, *rows) -> None:
        self.result = result
        added = getattr(self.progress, "rows_added", None)
        if added is not None:
            added(result, *rows)


def run(functions: SystemFunctions, controller: Callable, controls, progress: Callable | None,
        token: CancelToken | None, times: np.ndarray, analyze: Callable):
    """analyze(bundle, progress, token, t_end) on the controlled bundle (`controlled`) over the
    output `times`; a controller fault raised as an AnalysisError at its time with the rows
    before it (status "failed"): those the run kept, completed where the solver call that
    met the fault held more output times before it by a run to the last of them."""
    bundle, law = controlled(functions, controller, controls)
    rows = _Rows(progress)
    law.token.parent = token
    try:
        result = analyze(bundle, rows, law.token, None)
    except (AnalysisError, RuntimeError, KeyboardInterrupt) as error:
        fault = law.fault  # (the run of _before resets the law)
        if fault is None:
            raise
        partial = getattr(error, "partial", None) or rows.result
        partial = _before(functions, controller, controls, token, times, fault.t,
                          partial, analyze) or partial
        if partial is not None:
            partial.status = "failed"
        # (a finite difference of the first evaluation may look before the start)
        raise AnalysisError(FailureContext(max(fault.t, 0.0), fault.message), partial) from None
    result.metadata.update(controller=list(law.controls), controller_calls=law.calls)
    return result


def _before(functions, controller, controls, token, times, t_fault: float, partial,
            analyze: Callable):
    """The rows at the output times before `t_fault` by a run to the last of them, when
    `partial` lacks some (None: it has them all, or that run failed too)."""
    kept = len(partial) if partial is not None else 0
    wanted = int(np.searchsorted(times, t_fault))  # times[:wanted] < t_fault
    if wanted <= max(kept, 1):
        return None
    bundle, law = controlled(functions, controller, controls)
    law.token.parent = token
    try:
        result = analyze(bundle, None, law.token, float(times[wanted - 1]))
    except (AnalysisError, RuntimeError, KeyboardInterrupt):
        if law.fault is None:
            raise
        return None
    return result
