"""The blocks a joint may have and most joints leave out (schema/spec_joints.py): `reactions:`,
`limit:`, `friction:` and the base of `motor:`, imported when a document first has one of them
(spec_base.Deferred)."""

# (annotations are objects here, not strings: no `from __future__ import annotations`, so that
# pydantic makes each class without evaluating them; docs/decisions/pydantic-defer-build.md)

from typing import Literal

from pydantic import ConfigDict

from casmech.core.spec_base import Scalar, Spec, Vector


class MotorBase(Spec):
    model_config = ConfigDict(extra="allow", frozen=True,
                              json_schema_extra={"additionalProperties": False})


class Reactions(Spec):
    """How a joint's reaction columns are written (casmech.runtime.reaction_frames): the frame
    of their components and the point the torque is taken about (global at t = 0, carried by
    body_i; default the joint point)."""

    frame: Literal["global", "body_i", "body_j", "joint"] = "global"
    point: Vector | None = None


class Limit(Spec):
    """A joint stop (equations/limits.py): a one-sided spring-damper in the joint coordinate
    (revolute: the angle, translational and cylindrical: the slide) outside [lower, upper]."""

    lower: Scalar | None = None
    upper: Scalar | None = None
    stiffness: Scalar
    damping: Scalar = 0


class JointFriction(Spec):
    """Joint friction (equations/friction.py): Coulomb and viscous along the joint coordinate,
    with a part proportional to the joint's load (mu, mu_static; radius for an angle), exact
    sticking up to the static limit (runtime/friction.py)."""

    coulomb: Scalar = 0
    viscous: Scalar = 0
    static: Scalar | None = None
    mu: Scalar = 0
    mu_static: Scalar | None = None
    radius: Scalar | None = None
