"""What a results expression reads, and the results columns computed from it: the joint
states and the model's `outputs:` (docs/format.md, results contract).

The names (schema/outputs.py, schema/events.py check them) and their values as expressions of
the coordinates `x` (t, q, q_dot, q_ddot) and, for reactions, of the reactions the bundle
computes (`force`, `torque`: 3 x joints, global, the torque about the joint point):

- `<body>.<column>`: the body columns of the results contract (CM position, Euler parameters,
  velocity, angular velocity, acceleration, angular acceleration; runtime.results.row's);
- `<joint>.<attribute>`: the joint states of casmech.core.states (equations/coordinates.py);
- the contact and stop columns (equations/contact.py);
- `<joint>.fx` .. `.tz`: the reaction columns as the joint's `reactions:` writes them (its
  frame, its point; runtime/reaction_frames.py does the same on numbers);
- `<coupling>.torque` / `.force` (gear; rack_pinion, coupler: joint_types.Couples.column):
  the generalized force the coupling's row applies along its output joint's coordinate
  (the reaction torque or force on that joint's body_j about or along its axis) divided by
  the coordinate's coefficient: -lambda of the row;
- an output's name: its value.

`names(ir)` are the columns after the contract's (each joint's states in file order, then the
outputs), `columns(...)` their values, the same on a numeric IR and on a split one (symbols of
the model data).
"""

from __future__ import annotations

import casadi as ca

from casmech.core import euler
from casmech.core.columns import BODY_COLUMNS, JOINT_COLUMNS
from casmech.core.states import split
from casmech.core.values import constant
from casmech.elements.coordinate_kinds import ANGLE
from casmech.elements.coordinate_kinds import REGISTRY as COORDINATE_KINDS
from casmech.elements.joint_types import REGISTRY, attributes
from casmech.equations import contact, coordinates, joint_states
from casmech.equations.symbols import Coordinates
from casmech.model.bindings import coordinate_geometry
from casmech.model.ir import ModelIR


def joint_state_names(ir: ModelIR) -> list[str]:
    """`<joint>.<attribute>` of every joint with states, in file order."""
    return [f"{joint.name}.{a}" for joint in ir.joints for a in attributes(joint.type)]


def coupling_names(ir: ModelIR) -> list[str]:
    """`<coupling>.<column>` of every coupling (gear: torque; rack_pinion, coupler: force)."""
    return [f"{joint.name}.{REGISTRY[joint.type].couples.column}" for joint in ir.joints
            if joint.couples]


def names(ir: ModelIR) -> list[str]:
    """The results columns after the contract's: the joint states, the couplings' columns,
    then the outputs."""
    return joint_state_names(ir) + coupling_names(ir) + [output.name for output in ir.outputs]


def coupling_column(x: Coordinates, joint, force, torque):
    """A coupling's column (module docstring) from its reaction on the output joint's body_j."""
    couples = REGISTRY[joint.type].couples
    axis = x.frame(joint.body_i).A @ constant(joint.geometry["w@i"])
    coordinate = joint.couples[couples.output][1]
    along = torque if COORDINATE_KINDS[coordinate].quantity is ANGLE else force
    return (axis.T @ along) / constant(joint.coefficients[couples.output])


def body_columns(x: Coordinates, k: int) -> dict:
    """Body k's results columns (runtime.results.row's meanings) as expressions of x."""
    p, p_dot = x.p(k), x.p(k, x.q_dot)
    omega = 2 * euler.e_matrix(p) @ p_dot
    alpha = ca.jtimes(omega, ca.vertcat(x.q, x.q_dot), ca.vertcat(x.q_dot, x.q_ddot))
    vectors = [x.r(k), p, x.r(k, x.q_dot), omega, x.r(k, x.q_ddot), alpha]
    return dict(zip(BODY_COLUMNS, ca.vertsplit(ca.vertcat(*vectors)), strict=True))


def _axes(x: Coordinates, joint, frame: str):
    """R: the reaction frame's axes as columns in global components."""
    if frame == "body_j":
        return x.frame(joint.body_j).A
    a_i = x.frame(joint.body_i).A
    if frame == "body_i":
        return a_i
    if frame == "joint":
        return a_i @ ca.horzcat(*(constant(joint.geometry[f"{k}@i"]) for k in "uvw"))
    return ca.DM.eye(3)


def reaction_columns(ir: ModelIR, x: Coordinates, force, torque, index: int) -> dict:
    """Joint `index`'s six reaction columns as its `reactions:` writes them."""
    joint = ir.joints[index]
    f, t = force[:, index], torque[:, index]
    if joint.reaction_point is not None:
        arm = x.frame(joint.body_i).A @ constant(joint.point_i - joint.reaction_point)
        t = t + ca.cross(arm, f)
    axes = _axes(x, joint, joint.reaction_frame)
    values = ca.vertsplit(ca.vertcat(axes.T @ f, axes.T @ t))
    return dict(zip(JOINT_COLUMNS, values, strict=True))


class Readings:
    """The values of readable names at one state (built on first use, each once)."""

    def __init__(self, ir: ModelIR, x: Coordinates, force=None, torque=None):
        self.ir, self.x, self.force, self.torque = ir, x, force, torque
        self.bodies = {body.name: k for k, body in enumerate(ir.bodies)}
        self.joints = {joint.name: k for k, joint in enumerate(ir.joints)}
        self.outputs = {output.name: output for output in ir.outputs}
        self.elements = {name: k for k, name in enumerate(contact.output_names(ir))}
        self.found: dict = {}
        self.groups: dict = {}

    def __getitem__(self, name: str):
        if name not in self.found:
            self.found[name] = self._value(name)
        return self.found[name]

    def _group(self, key, make):
        if key not in self.groups:
            self.groups[key] = make()
        return self.groups[key]

    def _value(self, name: str):
        if name in self.outputs:
            value = self.outputs[name].value
            return value.casadi(t=self.x.t, **{n: self[n] for n in value.variables if n != "t"})
        if name in self.elements:
            outputs = self._group("elements", lambda: contact.element_outputs(self.ir, self.x))
            return outputs[self.elements[name]]
        owner, attribute = split(name)
        if owner in self.bodies:
            return self._group(owner, lambda: body_columns(self.x, self.bodies[owner]))[attribute]
        index = self.joints[owner]
        if attribute in JOINT_COLUMNS:
            return self._group(("reactions", owner), lambda: reaction_columns(
                self.ir, self.x, self.force, self.torque, index))[attribute]
        if self.ir.joints[index].couples:
            return coupling_column(self.x, self.ir.joints[index], self.force[:, index],
                                   self.torque[:, index])
        if attribute in joint_states.GROUPS:  # every spherical joint's states at once
            spherical = self._group("spherical", self._spherical)
            if owner in spherical:
                return spherical[owner][attribute]
        geometry = coordinate_geometry(self.ir.joints[index])
        group = joint_states.GROUPS.get(attribute)
        if group is not None:  # the joint's states evaluated together, once
            return self._group((group.__name__, owner),
                               lambda: group(geometry, self.x))[attribute]
        return coordinates.JOINT_VALUES[attribute](geometry, self.x)

    def _spherical(self) -> dict:
        """The grouped states (joint_states.GROUPS) of every joint that has them, mapped."""
        grouped = [coordinate_geometry(joint) for joint in self.ir.joints if not joint.couples
                   and set(attributes(joint.type)) & joint_states.GROUPS.keys()]
        return joint_states.spherical_states_of(grouped, self.x)


def columns(ir: ModelIR, x: Coordinates, force, torque):
    """The values of `names(ir)` (a column, ground's pose substituted)."""
    readings = Readings(ir, x, force, torque)
    values = [readings[name] for name in names(ir)]
    return x.ground_fixed(ca.vertcat(*values)) if values else ca.SX(0, 1)


def columns_function(ir: ModelIR, d=None) -> ca.Function:
    """(t, q, q_dot, q_ddot, force, torque[, d]) -> the values of `names(ir)` (SX); `d`: the
    model data symbols of a split IR (model.parametric), its last input then."""
    x = Coordinates.create(ir.n_bodies)
    n_joints = len(ir.joints)
    force, torque = ca.SX.sym("force", 3, n_joints), ca.SX.sym("torque", 3, n_joints)
    data = [] if d is None else [d]
    return ca.Function("joint_states_and_outputs",
                       [x.t, x.q, x.q_dot, x.q_ddot, force, torque, *data],
                       [ca.densify(columns(ir, x, force, torque))],
                       ["t", "q", "q_dot", "q_ddot", "force", "torque", *(["d"] if data else [])],
                       ["values"])

