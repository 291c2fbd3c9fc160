"""Names of the state a force law or an event reads: `<body>.<column>`, `<joint>.<attribute>`.

- `<body>.x .y .z .vx .vy .vz .wx .wy .wz` (BODY_STATES): what the results columns of that name
  hold (CM position and velocity, angular velocity, all global);
- `<joint>.angle`, `.angle_dot` (JOINT_COORDINATES "angle": joint types that rotate about their
  axis) and `.displacement`, `.displacement_dot` ("displacement": joint types that slide along
  it). Which joint types have which coordinate is the joint registry's
  (casmech.elements.joint_types).
- further states of joint types without such a coordinate (JOINT_STATES, a type's `states`):
  a universal joint's `angle_i`, `angle_j` (rotations about axis_i, carried by body_i, and
  about axis_j, carried by body_j) and their rates; a spherical joint's `e0 .. e3` (Euler
  parameters of body_j's rotation relative to body_i, in the joint frame: the global axes at
  the file's pose, carried by body_i) and `wx wy wz` (body_j's angular velocity relative to
  body_i, in the same frame).

The formulas are equations/coordinates.py's; schema/force_laws.py and schema/events.py check the
names.
"""

from __future__ import annotations

BODY_STATES: tuple[str, ...] = tuple(f"{kind}{axis}" for kind in ("", "v", "w") for axis in "xyz")
# attribute -> the joint coordinate kind it reads (its value, or its rate for `_dot`): written
# by casmech.elements.coordinate_kinds for every registered kind
JOINT_COORDINATES: dict[str, str] = {}

# joint type -> the state attributes beyond JOINT_COORDINATES' (equations/joint_states.py)
JOINT_STATES: dict[str, tuple[str, ...]] = {
    "universal": ("angle_i", "angle_i_dot", "angle_j", "angle_j_dot"),
    "spherical": ("e0", "e1", "e2", "e3", "wx", "wy", "wz"),
}
# every joint state attribute -> its results column's quantity key (core.columns.QUANTITIES)
# (a coordinate kind's attributes are added by casmech.elements.coordinate_kinds)
JOINT_QUANTITIES: dict[str, str] = {
    "angle_i": "angle", "angle_j": "angle",
    "angle_i_dot": "angle_dot", "angle_j_dot": "angle_dot",
    **{f"e{k}": "relative_e" for k in range(4)},
    **{f"w{axis}": "relative_w" for axis in "xyz"},
}


def split(name: str) -> tuple[str, str]:
    """'leg1.knee.angle' -> ('leg1.knee', 'angle')."""
    owner, _, attribute = name.rpartition(".")
    return owner, attribute

