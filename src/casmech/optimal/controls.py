"""Control inputs on joints: an effort along a joint coordinate (a coordinate kind's effort
mode, casmech.elements.coordinate_kinds: a torque about the axis of a joint type that rotates,
a force along the axis of one that slides), as generalized forces by virtual work (AD), the
same as an effort motor's (equations/motors.py):

    effort u on joint J's coordinate s_J: Q = (d s_J / d q)^T u, s_J the kind's measure
    (the same angle an rsda on J measures; the slide of body j's joint point along the axis
    carried by body i).
"""

from __future__ import annotations

from collections.abc import Sequence

import casadi as ca
import numpy as np

from casmech.core.records import record
from casmech.elements.coordinate_kinds import BY_MODE
from casmech.elements.joint_types import having
from casmech.equations.assemble import Coordinates
from casmech.equations.coordinates import coordinate
from casmech.errors import UsageError
from casmech.model.lower import Poses, joint_coordinates
from casmech.schema.resolved import ResolvedModel


def kinds() -> dict[str, str]:
    """control kind (an effort motor mode) -> the coordinate kind it acts along."""
    return {mode: kind.name for mode, (kind, k) in BY_MODE.items() if k == 2}


@record
class Control:
    joint: str
    kind: str = "torque"  # torque | force
    lower: float = -np.inf
    upper: float = np.inf

    @property
    def name(self) -> str:
        return f"{self.joint}.{self.kind}"


def control_forces(model: ResolvedModel, controls: Sequence[Control]) -> ca.Function:
    """Q_u(q, u): generalized forces of the controls."""
    poses = Poses(model)
    joints = {j.name: j for j in model.joints}
    x = Coordinates.create(len(model.bodies))
    u = ca.SX.sym("u", len(controls))
    total = ca.SX.zeros(x.q.numel())
    for k, control in enumerate(controls):
        joint = joints.get(control.joint)
        along = kinds()
        if control.kind not in along:
            raise UsageError(f"control kind '{control.kind}' is not one of {', '.join(along)}")
        types = having(along[control.kind])
        if joint is None or joint.type not in types:
            raise UsageError(f"control on '{control.joint}': a {control.kind} needs a joint of "
                             f"type {' or '.join(types)} by name")
        s = coordinate(along[control.kind], joint_coordinates(joint, poses), x)
        total += ca.jacobian(s, x.q).T * u[k]
    total = x.ground_fixed(total)
    return ca.Function("controls", [x.q, u], [total], ["q", "u"], ["Q_u"])
