"""Composite joints as tables of primitives.

A row template names a primitive kind and, for each vector key of that primitive, a joint-frame
quantity and the body whose frame it is expressed in. Joint-frame quantities are GLOBAL at t = 0
(the file's pose): P (the joint point `at`), Q (`at_j`), Pi/Pj (`at_i`/`at_j` of a distance joint),
u, v, w (orthonormal triad, w = axis), axis_i/axis_j (universal), ex/ey/ez (global unit vectors,
used as CD's constant c). `@i` / `@j` turn a global point or direction into body i's / j's frame;
a bare name is used as it is (global).

Each table was checked against Haug (1989) ch. 9 and the ME751 joint definitions:
spherical = 3 CD; universal = spherical + DP1; revolute = spherical + 2 DP1;
cylindrical = 2 DP1 + 2 DP2; translational = cylindrical + DP1; fixed = spherical + 3 DP1;
plus distance (D), revolute_spherical (D + DP2) and planar (2 DP1 + DP2).
"""

from __future__ import annotations

Template = tuple[str, dict[str, str], str]  # (kind, {vector key: quantity@body}, label)


def _cd(axis: str) -> Template:
    return ("cd", {"c": f"e{axis}", "s_i": "P@i", "s_j": "P@j"}, f"joint point, global {axis}")


SPHERICAL = [_cd("x"), _cd("y"), _cd("z")]
PARALLEL = [
    ("dp1", {"a_i": "u@i", "a_j": "w@j"}, "axis_j . u_i = 0"),
    ("dp1", {"a_i": "v@i", "a_j": "w@j"}, "axis_j . v_i = 0"),
]
NO_SPIN = [("dp1", {"a_i": "u@i", "a_j": "v@j"}, "u_i . v_j = 0 (no rotation about the axis)")]
ON_AXIS = [
    ("dp2", {"a_i": "u@i", "s_i": "P@i", "s_j": "P@j"}, "u_i . d_ij = 0 (point on the axis)"),
    ("dp2", {"a_i": "v@i", "s_i": "P@i", "s_j": "P@j"}, "v_i . d_ij = 0 (point on the axis)"),
]

JOINT_ROWS: dict[str, list[Template]] = {
    "spherical": SPHERICAL,
    "universal": SPHERICAL
    + [("dp1", {"a_i": "axis_i@i", "a_j": "axis_j@j"}, "axis_i . axis_j = 0 (cross)")],
    "revolute": SPHERICAL + PARALLEL,
    "cylindrical": PARALLEL + ON_AXIS,
    "translational": PARALLEL + ON_AXIS + NO_SPIN,
    "fixed": SPHERICAL + PARALLEL + NO_SPIN,
    "distance": [("d", {"s_i": "Pi@i", "s_j": "Pj@j"}, "|d_ij|^2 = length^2")],
    "revolute_spherical": [
        ("d", {"s_i": "P@i", "s_j": "Q@j"}, "|d_ij|^2 = length^2"),
        ("dp2", {"a_i": "w@i", "s_i": "P@i", "s_j": "Q@j"}, "axis_i . d_ij = 0"),
    ],
    "planar": PARALLEL
    + [("dp2", {"a_i": "w@i", "s_i": "P@i", "s_j": "P@j"}, "normal_i . d_ij = 0")],
}

# Basic constraints: the file's vectors are used as written (body frames; c global).
BASIC_ROWS: dict[str, list[Template]] = {
    "dp1": [("dp1", {"a_i": "a_i", "a_j": "a_j"}, "a_i . a_j = f(t)")],
    "dp2": [("dp2", {"a_i": "a_i", "s_i": "s_i", "s_j": "s_j"}, "a_i . d_ij = f(t)")],
    "d": [("d", {"s_i": "s_i", "s_j": "s_j"}, "d_ij . d_ij = f(t)")],
    "cd": [("cd", {"c": "c", "s_i": "s_i", "s_j": "s_j"}, "c . d_ij = f(t)")],
}

# Drivers: the joint's free relative motion as a function of time.
DRIVER_ROWS: dict[str, Template] = {
    "angle": ("angle", {"u_i": "u@i", "v_i": "v@i", "u_j": "u@j"}, "rotation angle = f(t)"),
    "displacement": ("dp2", {"a_i": "w@i", "s_i": "P@i", "s_j": "P@j"}, "slide = f(t)"),
}

# The point about which a joint's reaction torque is reported (docs/format.md, results contract),
# as a joint-frame quantity on body i; None means body i's origin (pure couples, e.g. DP1).
REACTION_POINT: dict[str, str | None] = {
    **dict.fromkeys(JOINT_ROWS, "P"),
    "distance": "Pi",
    "dp1": None,
    "dp2": "s_i",
    "d": "s_i",
    "cd": "s_i",
}


def rows_of(joint_type: str) -> list[Template]:
    return JOINT_ROWS.get(joint_type) or BASIC_ROWS[joint_type]
