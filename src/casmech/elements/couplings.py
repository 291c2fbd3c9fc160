"""Couplings between joint coordinates: the constraint row sum_k c_k s_k = 0 over two or three
joint coordinates s_k (gear, rack and pinion, coupler, screw; joint_types.py's entries).

A joint coordinate is written here once over the frames of its joint's two bodies (the
expressions equations/coordinates.py reads too):

- angle: the rotation of body j about the axis carried by body i, atan2(v_i . u_j, u_i . u_j)
  (u_i, v_i on body i, u_j on body j: the joint frame's u, v at the file's pose), in (-pi, pi];
- displacement: the slide of body j's joint point along the axis carried by body i,
  w_i . (P_j - P_i).

The row's kind names its coordinates and which of its bodies each reads: `coupling_<pattern>_
<slots>`, the pattern one letter per coordinate (`a` angle, `d` displacement) and the slots two
digits per coordinate, the positions among the row's bodies (body_i, body_j, then
PrimitiveIR.others) of that joint's body i and body j. Its vectors are, for coordinate k, `u_ik`,
`v_ik`, `u_jk` (an angle) or `w_ik`, `s_ik`, `s_jk` (a displacement), and `c`, the coefficients
(3 entries, unused ones 0).

A row with exactly one angle (rack and pinion, screw, a coupler of one rotation with slides) is
written c_a sin(theta + D / c_a), D = sum of the displacements' c_k s_k: equal to the linear
row to first order about its solution (the same Jacobian there, so the same multiplier), and
continuous through any number of turns, since it reads theta by its cosine and sine only. A row
of two or more angles is the linear sum of the angles above: each in (-pi, pi], so such a
coupling holds while its angles stay inside one turn of the file's pose (docs/format.md).
"""

from __future__ import annotations

import casadi as ca

from casmech.elements import primitives
from casmech.elements.forces.terms import relative_angle

ANGLE, DISPLACEMENT = "a", "d"
LETTER = {"angle": ANGLE, "displacement": DISPLACEMENT}
MAX_COORDINATES = 3
# vector keys of coordinate k by its letter
VECTOR_KEYS = {ANGLE: ("u_i", "v_i", "u_j"), DISPLACEMENT: ("w_i", "s_i", "s_j")}


def angle_value(fi, fj, u_i, v_i, u_j):
    """The angle of a joint over its bodies' frames (module docstring)."""
    return relative_angle(fi.A, fj.A, u_i, v_i, u_j)


def angle_cos_sin(fi, fj, u_i, v_i, u_j):
    """(cos, sin) of a joint's angle, without atan2."""
    u_j = fj.A @ u_j
    return (fi.A @ u_i).T @ u_j, (fi.A @ v_i).T @ u_j


def displacement_value(fi, fj, w_i, s_i, s_j):
    """The displacement of a joint over its bodies' frames (module docstring)."""
    gap = fj.r + fj.A @ s_j - fi.r - fi.A @ s_i
    return (fi.A @ w_i).T @ gap


def keys(pattern: str) -> tuple[str, ...]:
    """The vector keys of a coupling row of this pattern."""
    return tuple(f"{key}{k}" for k, letter in enumerate(pattern)
                 for key in VECTOR_KEYS[letter]) + ("c",)


def kind(pattern: str, slots: tuple[int, ...]) -> str:
    """The row kind of a coupling (module docstring), registered in primitives on first use."""
    name = f"coupling_{pattern}_{''.join(str(s) for s in slots)}"
    if name not in primitives.PRIMITIVES:
        primitives.register(name, coupling_phi(pattern, slots), keys(pattern))
    return name


def coupling_phi(pattern: str, slots: tuple[int, ...]):
    """phi(*frames, vectors, f) of a coupling row (module docstring)."""
    def phi(*arguments):
        *frames, v, f = arguments
        c = v["c"]
        angles, displacement = [], 0
        for k, letter in enumerate(pattern):
            fi, fj = frames[slots[2 * k]], frames[slots[2 * k + 1]]
            vectors = [v[f"{key}{k}"] for key in VECTOR_KEYS[letter]]
            if letter == ANGLE:
                angles.append((k, fi, fj, vectors))
            else:
                displacement = displacement + c[k] * displacement_value(fi, fj, *vectors)
        if len(angles) == 1:
            k, fi, fj, vectors = angles[0]
            cosine, sine = angle_cos_sin(fi, fj, *vectors)
            shift = (displacement - f) / c[k]
            return c[k] * (sine * ca.cos(shift) + cosine * ca.sin(shift))
        total = displacement
        for k, fi, fj, vectors in angles:
            total = total + c[k] * angle_value(fi, fj, *vectors)
        return total - f
    return phi
