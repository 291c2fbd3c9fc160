"""Names of the state a force law or an event reads: `<body>.<column>`, `<joint>.<attribute>`.

- `<body>.x .y .z .vx .vy .vz .wx .wy .wz` (BODY_STATES): what the results columns of that name
  hold (CM position and velocity, angular velocity, all global);
- `<joint>.angle`, `.angle_dot` (JOINT_COORDINATES "angle": joint types that rotate about their
  axis) and `.displacement`, `.displacement_dot` ("displacement": joint types that slide along
  it). Which joint types have which coordinate is the joint registry's
  (casmech.elements.joint_types).

The formulas are equations/coordinates.py's; schema/force_laws.py and schema/events.py check the
names.
"""

from __future__ import annotations

BODY_STATES: tuple[str, ...] = tuple(f"{kind}{axis}" for kind in ("", "v", "w") for axis in "xyz")
# attribute -> the joint coordinate it reads (its value, or its rate for `_dot`)
JOINT_COORDINATES: dict[str, str] = {
    "angle": "angle",
    "angle_dot": "angle",
    "displacement": "displacement",
    "displacement_dot": "displacement",
}


def split(name: str) -> tuple[str, str]:
    """'leg1.knee.angle' -> ('leg1.knee', 'angle')."""
    owner, _, attribute = name.rpartition(".")
    return owner, attribute

