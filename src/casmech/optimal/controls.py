"""Control inputs on joints: a torque about the axis of a joint type that rotates or a force
along the axis of one that slides (their entries in casmech.elements.joint_types: revolute,
cylindrical,
translational), as generalized forces by virtual work (AD):

    torque tau on joint J: Q = (d angle_J / d q)^T tau, angle_J the joint's relative rotation
    (the same angle an rsda on J measures);
    force f on joint J:    Q = (d (r_j - r_i) / d q)^T (A_i w_bar_i) f, w the joint axis.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import casadi as ca
import numpy as np

from casmech.elements.forces.springs import joint_angle
from casmech.elements.joint_types import COORDINATES, having
from casmech.equations.assemble import Coordinates
from casmech.errors import UsageError
from casmech.model.ir import GROUND_INDEX
from casmech.model.lower import Poses, joint_coordinates
from casmech.schema.resolved import ResolvedModel

# control kind -> the joint coordinate it acts along (its effort motor mode)
KINDS = {c.motor[2]: name for name, c in COORDINATES.items()}


@dataclass(frozen=True)
class Control:
    joint: str
    kind: str = "torque"  # torque | force
    lower: float = -np.inf
    upper: float = np.inf

    @property
    def name(self) -> str:
        return f"{self.joint}.{self.kind}"


def _torque_coordinate(model: ResolvedModel, poses, joint, x: Coordinates):
    """The joint's angle, as an rsda about it measures it."""
    return joint_angle(joint_coordinates(joint, poses), x)


def _force_coordinate(model: ResolvedModel, poses, joint, x: Coordinates):
    """Projection of r_j - r_i on the joint axis carried by body_i (axis frozen: the virtual
    work of a force pair along it)."""
    i, j = poses.index[joint.body_i], poses.index[joint.body_j]
    axis = poses.local(joint.body_i, "axis", np.asarray(joint.vectors["axis"], float))
    axis = axis / np.linalg.norm(axis)
    frame_i = x.frame(i)
    w = frame_i.A @ ca.DM(axis) if i != GROUND_INDEX else ca.DM(axis)
    return ca.jacobian(x.r(j) - frame_i.r, x.q).T @ w


def control_forces(model: ResolvedModel, controls: Sequence[Control]) -> ca.Function:
    """Q_u(q, u): generalized forces of the controls."""
    poses = Poses(model)
    joints = {j.name: j for j in model.joints}
    x = Coordinates.create(len(model.bodies))
    u = ca.SX.sym("u", len(controls))
    total = ca.SX.zeros(x.q.numel())
    for k, control in enumerate(controls):
        joint = joints.get(control.joint)
        if control.kind not in KINDS:
            raise UsageError(f"control kind '{control.kind}' is not one of {', '.join(KINDS)}")
        types = having(KINDS[control.kind])
        if joint is None or joint.type not in types:
            raise UsageError(f"control on '{control.joint}': a {control.kind} needs a joint of "
                             f"type {' or '.join(types)} by name")
        if control.kind == "torque":
            total += ca.jacobian(_torque_coordinate(model, poses, joint, x), x.q).T * u[k]
        else:
            total += _force_coordinate(model, poses, joint, x) * u[k]
    total = x.ground_fixed(total)
    return ca.Function("controls", [x.q, u], [total], ["q", "u"], ["Q_u"])
