"""The bushing: a 6-DOF linear spring-damper between a frame I on body_i and a frame J on body_j.

Both frames sit at the global point `at` with the given orientation at t = 0 and are fixed in
their bodies. As in Adams' BUSHING, the deflection is measured in the I frame:

    d     = A_I^T (P_J - P_I)          translational displacement of J from I, I components
    theta = rotation vector of A_I^T A_J (I components; 0 at t = 0)

and the bushing acts on J with force and torque (I components) -K d - C d_dot + F0 and
-Kt theta - Ct theta_dot + T0, and on I with the opposite plus the moment of the force's arm.
Here this is one generalized force from virtual work, like a tsda in six directions
(s = [d; theta], tension = K s + C s_dot - preload):

    Q = -s_q^T (K s + C s_dot - preload),   V = 1/2 s^T K s - preload^T s,

so the elastic part is exactly -dV/dq (conservative: the energy column is constant without
damping) and the reaction on I (opposite force plus moment arm) comes out of AD. The torque on J
is -Kt theta exactly when Kt is isotropic (and T0 = 0), to first order in theta otherwise (Adams'
small angles AX, AY, AZ agree with theta to first order too). docs/forces.md.

The rotation vector comes from Euler parameters: s = conj(p_i) p_j c, where the constant c undoes
the relative rotation at t = 0, so S = A_i^T A_j (A_i0^T A_j0)^T and theta = M_i^T theta(S) with
M_i the I frame in body_i. theta(S) = 2 e atan2(|e|, e0)/|e|, by its series near identity.

Here: its checks (`resolve`), lowering, law and linearization inputs (its
casmech.elements.force_types entry); its YAML class is in elements/forces/specs.py.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import casadi as ca
import numpy as np

from casmech.core import euler, traced
from casmech.core.quaternions import conjugate
from casmech.core.values import constant
from casmech.elements.forces.springs import non_negative
from casmech.errors import failed

IDENTITY = (1.0, 0.0, 0.0, 0.0)
SERIES = 1e-3  # below |e|^2 / e0^2 = SERIES, atan(u)/u by its series (5 terms: error < 1e-16)


# a bushing's coefficients under its params names (stiffness0..5 = stiffness then
# rotational_stiffness, ...)
BUSHING_PARAMS = {"stiffness": ("stiffness", "rotational_stiffness"),
                  "damping": ("damping", "rotational_damping"),
                  "preload": ("preload_force", "preload_torque")}

KEYS = tuple(BUSHING_PARAMS)  # params: f"{key}{n}" for n in 0..5 (along d, then theta)


def relative(a, b):
    """Euler parameters of conj(a) b (the rotation A(a)^T A(b)): [a.b; G(a) b]."""
    return ca.vertcat(a.T @ b, euler.g_matrix(a) @ b)


def _atan_ratio(z, e0):
    """atan2(sqrt(z), e0) / sqrt(z): smooth at z = 0 (series), both branches finite."""
    near = ca.logic_and(z < SERIES * e0**2, e0 > 0)
    u = z / ca.if_else(near, e0**2, 1.0)
    series = sum((-u) ** n / (2 * n + 1) for n in range(5)) / ca.if_else(near, e0, 1.0)
    root = ca.sqrt(ca.fmax(z, SERIES * e0**2 + 1e-300))
    return ca.if_else(near, series, ca.atan2(root, e0) / root)


def rotation_vector(p):
    """theta with A(p) = exp(theta~): 2 e atan2(|e|, e0) / |e| (|theta| < pi for e0 > 0)."""
    e = p[1:4]
    return 2 * e * _atan_ratio(e.T @ e, p[0])


def deflection(force, x):
    """s = [d; theta] (6x1), I-frame components."""
    marker = constant(force.axes["marker_i"])  # I frame axes in body_i (columns)
    fi, fj = x.frame(force.body_i), x.frame(force.body_j)
    gap = fj.r + fj.A @ constant(force.points["s_j"]) - fi.r - fi.A @ constant(force.points["s_i"])
    d = marker.T @ fi.A.T @ gap
    s = relative(conjugate(relative(x.p(force.body_i), x.p(force.body_j))),
                 constant(force.axes["rest"]))
    return ca.vertcat(d, marker.T @ rotation_vector(s))


def rest_rotation(p_i, p_j):
    """Euler parameters that undo the relative rotation of the two bodies at t = 0."""
    return conjugate(relative(p_i, p_j))


def law(force, x, read):
    """(generalized force on q, potential energy) of one bushing (it reads no state)."""
    # vertcat, not DM: the model data's split puts SX entries here (a DM of SX is silently NaN)
    k, c, preload = (ca.vertcat(*[force.params[f"{key}{n}"] for n in range(6)]) for key in KEYS)
    s = deflection(force, x)
    s_q = ca.jacobian(s, x.q)
    tension = k * s + c * (s_q @ x.q_dot) - preload
    return -s_q.T @ tension, 0.5 * s.T @ (k * s) - preload.T @ s


def lower(force, model, poses) -> dict[str, Any]:
    """resolved.Force (type bushing) -> the ForceIR fields."""
    at = traced.asarray(force.vectors["at"])
    marker = traced.numeric(euler.rotation, force.vectors["orientation"])
    initial = {b.name: b.euler_parameters for b in model.bodies}
    p0 = [initial.get(name, IDENTITY) for name in (force.body_i, force.body_j)]
    if traced.is_traced(p0):
        rest = traced.numeric(rest_rotation, *(traced.asarray(p) for p in p0)).ravel()
    else:
        rest = np.array(ca.DM(rest_rotation(*map(ca.DM, p0))).full()).ravel()
    params = {}
    for key, vectors in BUSHING_PARAMS.items():  # e.g. stiffness then rotational_stiffness
        values = np.concatenate([force.vectors[name] for name in vectors])
        params.update({f"{key}{n}": traced.scalar(v) for n, v in enumerate(values)})
    points = {"s_i": poses.local(force.body_i, "P", at), "s_j": poses.local(force.body_j, "P", at)}
    axes = {"marker_i": poses.pose[force.body_i][1].T @ marker, "rest": rest}
    return dict(body_i=poses.index[force.body_i], body_j=poses.index[force.body_j],
                points=points, params=params, axes=axes)


def with_inputs(force, u):
    """Stiffness and damping 0, the preload u: the force on body_j is +u (I frame)."""
    params = {f"{key}{n}": 0.0 for key in BUSHING_PARAMS for n in range(6)}
    params |= {f"preload{n}": u[n] for n in range(6)}
    return replace(force, params=params)


# ---------------------------------------------------------------------------- resolution
VECTORS = ("at", "stiffness", "damping", "rotational_stiffness", "rotational_damping",
           "preload_force", "preload_torque")
NON_NEGATIVE = ("stiffness", "damping", "rotational_stiffness", "rotational_damping")


def resolve(check, path, given) -> dict[str, Any] | None:
    """`check.orientation(path, given)` resolves the orientation (schema/force_laws.py)."""
    bodies_ok = check.two_bodies(path, given.body_i, given.body_j)
    vectors = {key: check.numbers((*path, key), getattr(given, key)) for key in VECTORS}
    for key in NON_NEGATIVE:
        vectors[key] = non_negative(check, (*path, key), vectors[key], given.allow_negative)
    vectors["orientation"] = check.orientation((*path, "orientation"), given.orientation)
    if not bodies_ok or failed(vectors.values()):
        return None
    return dict(body_i=given.body_i, body_j=given.body_j, vectors=vectors)
