"""The model in joint coordinates for optimal control: the joint formulation's equations for
it, FORMULATIONS["joint"].controlled (formulations.protocol's ControlEquations), with the
controls as inputs.

The controls become effort motors: the model is read again with one parameter per control
(`ocp_u0`, ...) as the value of a `motor:` in torque or force mode on its joint (added to a
motor the joint has in that mode), and the parametric build (optimal/system.py, with those
parameters as theta) gives every function with the controls as an input. So a control acts
exactly as an effort motor does, and the reaction columns include it as they include a motor's.

    x = [theta; u]          the tree's free joint coordinates and velocities
    c = [controls; design]  the controls and the decision parameters (optimal/ocp.py)
    rhs(t, x, c) -> x'      a tree: its ODE; loops: the ODE with the closure multipliers lam
                            solved from the acceleration-level rows (index 1; mu = 0)
    closure(t, x) -> rows   loops: the cut joints' rows Phi_c and d/dt Phi_c (unit rows,
                            those independent at t0), and |p|^2 - 1 of every quaternion among
                            the coordinates: constraints the transcription imposes at its nodes
    columns(t, x, c)        every results column (docs/format.md order, without t)

A mechanism the joint formulation does not take for optimal control (loops with a floating
body, runtime/auto_formulation.py's rule; a control on a joint of a component instance) has
no JointModel (`joint_model` returns None), and the problem stays on body coordinates
(optimal/ocp.py).
"""

from __future__ import annotations

from dataclasses import field
from functools import cached_property

import casadi as ca
import numpy as np
import yaml

from casmech.core import traced
from casmech.core.records import record
from casmech.errors import ModelError, UsageError
from casmech.formulations.protocol import ControlEquations
from casmech.formulations.registry import FORMULATIONS
from casmech.optimal.controls import Control, control_forces
from casmech.optimal.dae import body_columns
from casmech.optimal.system import ParametricSystem, classify, parametric_system, traced_model
from casmech.runtime import assembly
from casmech.runtime.results import column_names
from casmech.schema import load_model_text
from casmech.schema.resolved import ResolvedModel

PREFIX = "ocp_u"  # the controls' parameter names: PREFIX0, PREFIX1, ... (unused ones)


def motored_text(model: ResolvedModel, controls: list[Control]):
    """(the model's text with a motor per control, the controls' parameter names), or None
    when a controlled joint is not written in the file's own `joints:` list (a component's
    joint) or the text is not plain YAML."""
    try:
        document = yaml.safe_load(model.text)
    except yaml.YAMLError:
        return None
    if not isinstance(document, dict):
        return None
    joints = {j.get("name"): j for j in document.get("joints") or [] if isinstance(j, dict)}
    if any(c.joint not in joints for c in controls):
        return None
    parameters = dict(document.get("parameters") or {})
    names, k = [], 0
    for control in controls:
        while f"{PREFIX}{k}" in parameters:
            k += 1
        name = f"{PREFIX}{k}"
        parameters[name] = 0.0
        names.append(name)
        joint = joints[control.joint]
        motor = dict(joint.get("motor") or {})
        given = motor.get(control.kind)
        motor[control.kind] = name if given is None else f"({given}) + {name}"
        joint["motor"] = motor
    document["parameters"] = parameters
    return yaml.safe_dump(document, sort_keys=False), names


@record(frozen=False)
class JointModel:
    """The functions of the joint-coordinate transcription (module docstring)."""

    system: ParametricSystem  # body coordinates, theta = the controls' parameters, the design
    equations: ControlEquations  # FORMULATIONS["joint"].controlled over the model data
    t0: float
    n_design: int = 0  # decision parameters of the model, last in theta
    # parameters derived from decision parameters: name -> Function(decision parameters)
    derived: dict = field(default_factory=dict)

    @property
    def n_x(self) -> int:
        return self.equations.n_x

    @property
    def n_u(self) -> int:
        """How many controls (theta = [controls; design])."""
        return len(self.system.names) - self.n_design

    @property
    def n_c(self) -> int:
        return len(self.system.names)

    @property
    def design_values(self) -> np.ndarray:
        """The decision parameters' values in the file."""
        return np.asarray(self.system.values[self.n_u:], float)

    @cached_property
    def symbols(self):
        return ca.SX.sym("t"), ca.SX.sym("x", self.n_x), ca.SX.sym("c", self.n_c)

    @cached_property
    def _numeric_data(self):
        """The model data at the file's values of the controls and the design."""
        return self.system.data(ca.DM(self.system.values))

    @cached_property
    def start(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(x0, the quaternion signs of the results rows, the rows kept: 1 where a cut row
        is independent at t0) from the assembled r-p state (runtime.assembly)."""
        q0, q_dot0 = assembly.initial_state(self.system.nominal, self.t0)
        x0 = self.state_of(q0, q_dot0)
        keep = self.equations.independent(self.t0, x0, self._numeric_data)
        return x0, self.equations.signs(self.t0, x0, q0, self._numeric_data), keep

    def state_of(self, q, q_dot) -> np.ndarray:
        """x = [theta; u] of the free joint coordinates at the r-p state (q, q_dot)."""
        return self.equations.state(q, q_dot, self._numeric_data)

    def periodic(self) -> list[int]:
        """The indices into x of the free coordinates that are angles: adding 2 pi to one
        leaves its joint's pose unchanged (a revolute joint's angle, not a quaternion's
        component or a displacement)."""
        return self.equations.periodic()

    def _algebraic(self, t, x, c):
        """z = [lam; mu = 0] of the loops (unit rows): the acceleration rows kept, solved."""
        return self.equations.multipliers(t, x, self.system.data(c),
                                          np.flatnonzero(self.start[2]))

    @cached_property
    def efforts(self) -> np.ndarray | None:
        """B with the controls' generalized forces along the tree's free velocities tau =
        B c (a tree), when that map is constant: read off the motors' ODE and the forced
        ODE (ControlEquations.forced) at sample states, kept only where they agree there;
        else None."""
        if self.equations.n_cut or not self.n_u:
            return None
        t, x, c = self.symbols
        n_theta = self.equations.n_coordinates
        tau = ca.SX.sym("tau", self.n_x - n_theta)
        motors = ca.jacobian(self.equations.ode(t, x, self.system.data(c)),
                             c[list(range(self.n_u))])
        torques = ca.jacobian(self.equations.forced(t, x, tau, self._numeric_data), tau)
        slopes = ca.Function("slopes", [x, c, tau], [motors[n_theta:, :], torques[n_theta:, :]])
        samples = np.sin(1.3 * np.arange(1, 3 * self.n_x + 1)).reshape(3, self.n_x) * 1.5
        maps = []
        for sample in samples:
            motor, torque = (np.array(v.full()) for v in slopes(sample, self.system.values,
                                                                np.zeros(tau.numel())))
            maps.append(np.linalg.solve(torque, motor))
            if not np.allclose(torque @ maps[-1], motor, rtol=1e-10, atol=1e-10):
                return None
        if max(np.max(np.abs(b - maps[0])) for b in maps) > 1e-10:
            return None
        return np.round(maps[0], 12)

    @cached_property
    def rhs(self) -> ca.Function:
        """x' at (t, x, c); a tree with constant efforts: the forced ODE (tau = B c, the
        motors' values 0 in the data), which is the motors' ODE without their r-p path."""
        t, x, c = self.symbols
        if self.efforts is not None:
            design = c[list(range(self.n_u, self.n_c))] if self.n_design else ca.SX(0, 1)
            zero = ca.vertcat(ca.DM.zeros(self.n_u), design)
            ode = self.equations.forced(t, x, ca.DM(self.efforts) @ c[list(range(self.n_u))],
                                        self.system.data(zero))
        elif not self.equations.n_cut:
            ode = self.equations.ode(t, x, self.system.data(c))
        else:
            mask = 1.0 - self.start[2]
            ode = self.equations.ode(t, x, self.system.data(c), self._algebraic(t, x, c), mask)
        # common subexpressions merged: a smaller graph for the NLP's derivatives
        return ca.Function("rhs", [t, x, c], [ca.cse(ode)], ["t", "x", "c"], ["ode"])

    @cached_property
    def closure(self) -> ca.Function:
        """Position- and velocity-level rows of the loops and the quaternions' norms."""
        t, x, _ = self.symbols
        kept = list(np.flatnonzero(self.start[2]))
        positions, velocities = self.equations.closure(t, x, self._numeric_data)
        rows = [positions[kept], velocities[kept]] if self.equations.n_cut else []
        rows.append(self.equations.invariants(x))
        return ca.Function("closure", [t, x], [ca.vertcat(*rows)], ["t", "x"], ["rows"])

    @cached_property
    def names(self) -> list[str]:
        return column_names(self.system.nominal)[1:]

    @cached_property
    def columns(self) -> ca.Function:
        """Every results column at (t, x, c): the r-p state of the tree and every joint's
        multipliers (ControlEquations.body), through optimal/dae.py's columns of (t, q,
        q_dot, q_ddot, lam, theta)."""
        t, x, c = self.symbols
        signs = ca.DM(self.start[1])
        q, q_dot, q_ddot, lam = self.equations.body(t, x, self._algebraic(t, x, c), signs,
                                                    self.system.data(c))
        values = body_columns(self.system)(t, q, q_dot, q_ddot, lam, c)
        return ca.Function("columns", [t, x, c], [values], ["t", "x", "c"], ["columns"])

    def column(self, name: str) -> int:
        if name not in self.names:
            raise UsageError(f"unknown column '{name}' in the optimal control problem; "
                             "columns are results columns (<body>.x, <joint>.fx, energy, ...)")
        return self.names.index(name)


def handles(model: ResolvedModel, controls: list[Control]) -> bool:
    """Whether joint_model can take the model with these controls (module docstring)."""
    return motored_text(model, list(controls)) is not None


def joint_model(model: ResolvedModel, controls: list[Control], design=()) -> JointModel | None:
    """The joint-coordinate functions of the model with these controls and the model's
    parameters `design` as inputs after them (c = [controls; design]), or None when the joint
    formulation does not take it (module docstring). The initial state is the one at the
    file's values: a tree's joint coordinates at the file's pose, whatever the geometry."""
    control_forces(model, controls)  # the controls' joints and kinds, checked
    given = motored_text(model, list(controls))
    if given is None:
        return None
    text, names = given
    try:
        motored = load_model_text(text, model.file, model.overrides)
    except ModelError as error:
        raise UsageError(f"a control cannot act on this joint: "
                         f"{error.diagnostics[0].format()}") from None
    system = parametric_system(motored, [*names, *design])
    equations = FORMULATIONS["joint"].controlled(system.split.ir, system.split.symbols)
    if equations is None:
        return None
    return JointModel(system, equations, 0.0, len(tuple(design)), _derived(motored, design))


def _derived(model: ResolvedModel, design) -> dict:
    """The parameters that depend on the decision parameters, as functions of them:
    name -> Function(the decision parameters' values) (the model traced again with them
    symbolic, optimal/system.py)."""
    parameters = classify(model, design)[0]
    if not parameters:
        return {}
    again = traced_model(model, parameters)
    inputs = [again.symbols[name] if name in parameters else ca.SX.sym(name)
              for name in design]
    return {name: ca.Function(name, inputs, [traced.expression(value)])
            for name, value in again.parameters.items()
            if name not in design and traced.is_traced(value)}
