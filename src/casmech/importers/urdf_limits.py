"""A URDF joint's `<limit lower upper>` as the casmech joint's `limit:` stop (docs/forces.md).

casmech's coordinate is 0 at the imported pose, the URDF's at its zero: the bounds are the
URDF's less the joint's initial value. URDF gives no stiffness: the stop is MuJoCo's default
soft limit (solref: time constant TIME_CONSTANT, damping ratio 1), a mass-spring-damper with
the inertia the joint moves, stiffness I / tau^2 and damping 2 I / tau (critically damped),
I being the moment of inertia about the joint axis (revolute) or the mass (prismatic) of every
body below the joint at the imported pose. `effort` and `velocity` limits stay comments (not
enforced). A continuous joint has no limit; bounds with lower >= upper are none (URDF's way of
writing "no limit") and are kept as a comment, as are a revolute joint's bounds outside
(-pi, pi] from the imported pose: casmech's angle wraps there (docs/forces.md), so no stop can
hold them.
"""

from __future__ import annotations

import numpy as np

from casmech.importers.urdf_groups import Plan
from casmech.importers.urdf_tree import Joint, State

TIME_CONSTANT = 0.02  # [s] MuJoCo's default solref time constant (damping ratio 1)


def moved_inertia(plan: Plan, state: State, head: str, at: np.ndarray, axis: np.ndarray,
                  sliding: bool) -> float:
    """The mass (sliding) or the moment of inertia about the line (at, axis) of the bodies
    from `head` down the tree, at the imported pose."""
    below, total = {head}, 0.0
    for other in plan.heads:  # parents before children
        if plan.parents.get(other) in below:
            below.add(other)
    for other in below:
        mass, centre, inertia = plan.groups[other].mass_properties()
        if mass <= 0:
            continue
        frame = state.frames[other]
        if sliding:
            total += mass
            continue
        arm = frame.point(centre) - at
        radial = arm - (arm @ axis) * axis
        total += axis @ frame.rotation @ inertia @ frame.rotation.T @ axis + mass * radial @ radial
    return total


def unbounded(joint: Joint, value: dict[str, float], initial: float) -> str | None:
    """Why a joint's <limit> values make no stop (None: they make one)."""
    if joint.type == "continuous":
        return "a continuous joint"
    if "lower" not in value or "upper" not in value or value["lower"] >= value["upper"]:
        return "no lower < upper"
    if joint.type == "revolute" and not (-np.pi < value["lower"] - initial
                                         and value["upper"] - initial <= np.pi):
        return "bounds outside (-pi, pi] from the imported pose, where casmech's angle wraps"
    return None


def stop(joint: Joint, lower: float, upper: float, initial: float, inertia: float) -> dict:
    """The `limit:` of a joint with URDF bounds [lower, upper] imported at `initial`."""
    stiffness = inertia / TIME_CONSTANT ** 2
    damping = 2 * inertia / TIME_CONSTANT
    return {"lower": float(lower - initial), "upper": float(upper - initial),
            "stiffness": float(f"{stiffness:.6g}"), "damping": float(f"{damping:.6g}")}
