"""The model's own scale, and the floors of masses, inertias and directions it sets (E411, E404).

schema/limits.py bounds every number from above; these floors bound masses, inertias and
directions from below, relative to the model itself, because what breaks is a ratio:

- Masses. The DAEs of the r-p and r-omega forms hold every body's mass block beside the others'
  and beside the constraint Jacobian, whose entries are unit-free (1 per translation); the
  articulated-body algorithm of joint coordinates sums them. A body lighter than MASS_RATIO of
  the heaviest keeps fewer than four of double precision's sixteen digits in those sums and
  eliminations. The heaviest itself must weigh MIN_MASS: beside unit entries (and the
  multipliers' absolute tolerance, in newtons) a lighter mechanism's iteration matrix is
  singular to round-off, and 2e-320 kg (subnormal) overflows 1/m outright. A "massless" link
  is modelled with a millionth of its neighbours' mass, far above both floors.
- Inertias. Each principal moment must be at least INERTIA_RATIO of the model's inertia scale
  (heaviest mass x length scale squared), for the same reason in the rotation blocks; a point
  mass is a body with a small but representable inertia. The floor is lower than the masses':
  a small part far from the origin has a moment far below its mass times the model's length
  squared (gymnasium's pusher: a fingertip at 8e-14 of its inertia scale, which runs), while a
  body failed only from 1e-20 of its neighbours' scale.
- Directions. An axis written (or computed from coordinates of size L) is normalised; its
  components carry round-off of eps L, so one shorter than DIRECTION_RATIO L points somewhere
  round-off chose to within more than 1e-10 rad. A basic constraint's vectors (a_i, a_j, c)
  are not normalised: their length scales the constraint row, and at assembly's tolerance
  (1e-12 on |Phi|) one shorter than MIN_ROW_VECTOR leaves its angle free by more than 1e-9 rad.

The length scale is the larger of the farthest body centre from the origin and the heaviest
body's radius of gyration (at most limits.LENGTH), among the bodies resolved so far: a body's
own orientation axes are checked against it and the bodies before it, joints and forces against
every body.
"""

from __future__ import annotations

import math

import numpy as np

from casmech.core import traced
from casmech.core.records import record
from casmech.schema import limits

MASS_RATIO = 1e-12  # least mass / heaviest mass
INERTIA_RATIO = 1e-15  # least principal moment / (heaviest mass L^2)
MIN_MASS = 1e-15  # [kg] least mass of the heaviest body
DIRECTION_RATIO = 1e-6  # least length of a normalised direction / the length scale
MIN_ROW_VECTOR = 1e-3  # least length of a basic constraint's a_i, a_j, c


@record(frozen=False)
class Scale:
    """The heaviest body (name, mass [kg], radius of gyration [m]) and the farthest centre from
    the origin [m] among the bodies so far."""

    heaviest: str = ""
    mass: float = 0.0
    gyration: float = 0.0
    reach: float = 0.0

    @property
    def length(self) -> float:
        """The length scale [m]."""
        return max(self.reach, self.gyration)

    def add(self, name: str, mass: float | None, inertia: np.ndarray | None,
            position: np.ndarray | None) -> None:
        """A body's mass, inertia and position (None: reported as wrong, left out); the values
        of traced numbers (a check, not model data)."""
        mass, inertia, position = (traced.value(x) for x in (mass, inertia, position))
        if position is not None:
            self.reach = max(self.reach, float(np.linalg.norm(position)))
        if mass is None or mass <= self.mass:
            return
        self.heaviest, self.mass = name, mass
        if inertia is not None:
            gyration = math.sqrt(float(np.max(np.abs(inertia))) / mass)
            self.gyration = min(gyration, limits.LENGTH) if math.isfinite(gyration) else 0.0

    def direction_floor(self, normalised: bool) -> float:
        """The least length of a direction (normalised or a basic constraint's vector)."""
        return DIRECTION_RATIO * self.length if normalised else MIN_ROW_VECTOR


def mass_problem(scale: Scale, mass: float) -> tuple[str, str, str] | None:
    """(problem, expected, hint) of a body's mass below the floors, or None."""
    mass = traced.value(mass)
    if mass >= max(MIN_MASS, MASS_RATIO * scale.mass):
        return None
    if scale.mass * MASS_RATIO > MIN_MASS:
        return (f"mass {mass:.3g} kg is below {MASS_RATIO:g} of the heaviest body's "
                f"({scale.mass:.6g} kg, '{scale.heaviest}')",
                f"a mass of at least {MASS_RATIO * scale.mass:.3g} kg",
                "a nearly massless link is modelled with about 1e-6 of its neighbours' mass")
    return (f"mass {mass:.3g} kg is below the least mass of a mechanism, {MIN_MASS:g} kg",
            f"a mass of at least {MIN_MASS:g} kg", "SI units: kilograms")


def inertia_problem(scale: Scale, moments: np.ndarray) -> tuple[str, str, str] | None:
    """(problem, expected, hint) of a body's smallest principal moment below the floor."""
    moments = traced.value(moments)
    floor = INERTIA_RATIO * scale.mass * scale.length ** 2
    if moments[0] >= floor:
        return None
    return (f"principal moment {moments[0]:.3g} kg m^2 is below {INERTIA_RATIO:g} of the model's "
            f"inertia scale ({scale.mass:.3g} kg x ({scale.length:.3g} m)^2)",
            f"principal moments of at least {floor:.3g} kg m^2",
            "a point mass needs a small inertia, not a vanishing one: "
            "2/5 m r^2 of a sphere of its size; SI units: kg m^2")
