"""Couplings between joint coordinates: the constraint row sum_k c_k s_k = 0 over two or three
joint coordinates s_k (gear, rack and pinion, coupler, screw; joint_types.py's entries).

A joint coordinate is the measure of its kind over the frames of its joint's two bodies
(elements/coordinate_kinds.py: the expressions equations/coordinates.py reads too).

The row's kind names its coordinates and which of its bodies each reads: `coupling_<pattern>_
<slots>`, the pattern one letter per coordinate (its kind's `letter`: `a` angle, `d`
displacement) and the slots two digits per coordinate, the positions among the row's bodies
(body_i, body_j, then PrimitiveIR.others) of that joint's body i and body j. Its vectors are,
for coordinate k, its kind's vector keys with k appended (`u_ik`, `v_ik`, `u_jk` of an angle,
`w_ik`, `s_ik`, `s_jk` of a displacement), and `c`, the coefficients (3 entries, unused ones 0).

An angle here is any kind with `cos_sin` (it comes back to itself after a turn); any other
kind (a displacement) enters the rows linearly.

A row with exactly one angle (rack and pinion, screw, a coupler of one rotation with slides) is
written c_a sin(theta + D / c_a), D = sum of the displacements' c_k s_k: equal to the linear
row to first order about its solution (the same Jacobian there, so the same multiplier), and
continuous through any number of turns, since it reads theta by its cosine and sine only.

A row of angles only whose coefficients are in the ratios of integers m_k (a gear of ratio
-z_1/z_2: its tooth counts; `integers`) is written (c_0 / m_0) arg(P e^(-i f m_0 / c_0)), P the
product of (cos theta_k + i sin theta_k)^m_k: the linear row itself (with its Jacobian) while
sum_k m_k theta_k - f m_0 / c_0 stays within half a turn of a multiple of 2 pi, and continuous
through any number of turns of the angles (an angle that comes back to itself after a turn
changes sum m_k theta_k by a multiple of 2 pi). It jumps only where the row is violated by
pi / |m_k| in an angle; assembly's continuation, the integrators and the optimizers stay far
closer. Any other row (angles with slides, or ratios that are no
fractions of numerator and denominator up to MAX_DENOMINATOR) is the linear sum of the angles
above: each in (-pi, pi], so it holds while its angles stay inside half a turn of the file's
pose (docs/format.md).
"""

from __future__ import annotations

import math

import casadi as ca

from casmech.elements import primitives
from casmech.elements.coordinate_kinds import BY_LETTER, REGISTRY, View

MAX_COORDINATES = 3
MAX_DENOMINATOR = 1000  # largest denominator of a ratio of coefficients taken as a fraction
FRACTION = 1e-12  # relative distance within which a ratio of coefficients is that fraction
LETTER = View(lambda: {name: kind.letter for name, kind in REGISTRY.items()})  # kind -> letter


def periodic(pattern: str) -> tuple[bool, ...]:
    """Whether each coordinate of a pattern is an angle (its kind has `cos_sin`)."""
    return tuple(BY_LETTER[letter].cos_sin is not None for letter in pattern)


def vector_keys(letter: str) -> tuple[str, ...]:
    """The vector keys of one coordinate of this letter (its kind's measure's)."""
    return tuple(BY_LETTER[letter].vectors)


def keys(pattern: str) -> tuple[str, ...]:
    """The vector keys of a coupling row of this pattern."""
    return tuple(f"{key}{k}" for k, letter in enumerate(pattern)
                 for key in vector_keys(letter)) + ("c",)


def integers(coefficients) -> tuple[int, ...] | None:
    """Coprime integers in the ratios of the coefficients (the first one positive), or None
    when a ratio is no fraction of denominator up to MAX_DENOMINATOR (or is symbolic)."""
    try:
        values = [float(c) for c in coefficients]
    except TypeError:  # traced numbers of symbolic parameters: no fixed ratio
        return None
    from fractions import Fraction  # (a coupling's ratios only)

    ratios = [Fraction(v / values[0]).limit_denominator(MAX_DENOMINATOR) for v in values]
    if any(abs(float(r) - v / values[0]) > FRACTION * max(1.0, abs(v / values[0]))
           for r, v in zip(ratios, values, strict=True)):
        return None
    common = math.lcm(*(r.denominator for r in ratios))
    whole = [int(r * common) for r in ratios]
    divisor = math.gcd(*whole)
    return tuple(w // divisor for w in whole)


def kind(pattern: str, slots: tuple[int, ...], whole: tuple[int, ...] | None = None) -> str:
    """The row kind of a coupling (module docstring), registered in primitives on first use;
    `whole`: the integers of a row of angles only (its sine form), else None."""
    name = f"coupling_{pattern}_{''.join(str(s) for s in slots)}"
    if whole is not None:
        name += "_" + "_".join(f"n{-m}" if m < 0 else str(m) for m in whole)
    if name not in primitives.PRIMITIVES:
        phi = coupling_phi(pattern, slots) if whole is None else whole_phi(pattern, slots,
                                                                            whole)
        primitives.register(name, phi, keys(pattern))
    return name


def _power(z, n: int):
    """(re, im) of z^n for an integer n (z = (re, im) on the unit circle: z^-1 = conj z)."""
    re, im = z if n >= 0 else (z[0], -z[1])
    result, n = (1, 0), abs(n)
    while n:
        if n & 1:
            result = (result[0] * re - result[1] * im, result[0] * im + result[1] * re)
        re, im, n = re * re - im * im, 2 * re * im, n >> 1
    return result


def whole_phi(pattern: str, slots: tuple[int, ...], whole: tuple[int, ...]):
    """phi of a row of angles in integer ratios (module docstring)."""
    def phi(*arguments):
        *frames, v, f = arguments
        product = (1, 0)
        for k, (letter, m) in enumerate(zip(pattern, whole, strict=True)):
            fi, fj = frames[slots[2 * k]], frames[slots[2 * k + 1]]
            kind = BY_LETTER[letter]
            z = _power(kind.cos_sin(fi, fj, *(v[f"{key}{k}"] for key in kind.vectors)), m)
            product = (product[0] * z[0] - product[1] * z[1],
                       product[0] * z[1] + product[1] * z[0])
        scale = v["c"][0] / whole[0]
        shift = f / scale
        re = product[0] * ca.cos(shift) + product[1] * ca.sin(shift)
        im = product[1] * ca.cos(shift) - product[0] * ca.sin(shift)
        return scale * ca.atan2(im, re)
    return phi


def coupling_phi(pattern: str, slots: tuple[int, ...]):
    """phi(*frames, vectors, f) of a coupling row (module docstring)."""
    def phi(*arguments):
        *frames, v, f = arguments
        c = v["c"]
        angles, displacement = [], 0
        for k, letter in enumerate(pattern):
            fi, fj = frames[slots[2 * k]], frames[slots[2 * k + 1]]
            kind = BY_LETTER[letter]
            vectors = [v[f"{key}{k}"] for key in kind.vectors]
            if kind.cos_sin is not None:
                angles.append((k, kind, fi, fj, vectors))
            else:
                displacement = displacement + c[k] * kind.measure(fi, fj, *vectors)
        if len(angles) == 1:
            k, kind, fi, fj, vectors = angles[0]
            cosine, sine = kind.cos_sin(fi, fj, *vectors)
            shift = (displacement - f) / c[k]
            return c[k] * (sine * ca.cos(shift) + cosine * ca.sin(shift))
        total = displacement
        for k, kind, fi, fj, vectors in angles:
            total = total + c[k] * kind.measure(fi, fj, *vectors)
        return total - f
    return phi
