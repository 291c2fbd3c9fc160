"""Inertias of imported bodies: checked as casmech's loader checks them, repaired on request.

An importer writes each body's inertia tensor; casmech refuses one that is not positive
definite (E401) or whose principal moments violate the triangle inequality (E402). The
importers check the numbers they are about to write with the same tests, so that the error
names the source file's line instead of a line of the generated YAML.

Two repairs, MuJoCo's compiler options of the same names, are applied only when asked for
(`casmech import --bound-inertia VALUE`, `--balance-inertia`), each with a warning at the
source line: `bound` raises every principal moment below it to it (`boundinertia`), `balance`
sets the three principal moments to their mean where they violate the triangle inequality
(`balanceinertia`). The principal axes are kept.
"""

from __future__ import annotations

import numpy as np

from casmech.core.records import record

HINT = ("--bound-inertia VALUE raises principal moments below VALUE [kg m^2] to it and "
        "--balance-inertia sets moments that violate the triangle inequality to their mean "
        "(MuJoCo's compiler options boundinertia and balanceinertia)")


@record
class Repair:
    bound: float = 0.0  # [kg m^2]: principal moments below it are raised to it (0: none)
    balance: bool = False  # moments violating the triangle inequality -> their mean


def problem(tensor: np.ndarray) -> tuple[str, str, str] | None:
    """(code, message, got) of what casmech's loader would refuse in this inertia, or None
    (schema.bodies.inertia's tests on the same numbers)."""
    from casmech.schema.bodies import UNIT

    moments = np.linalg.eigvalsh((tensor + tensor.T) / 2)
    if moments[0] <= 0:
        return ("E401", "the inertia is not positive definite",
                "principal moments " + ", ".join(f"{m:g}" for m in moments))
    if moments[0] + moments[1] < moments[2] * (1 - UNIT):
        return ("E402", "the principal moments violate the triangle inequality",
                "{:g} + {:g} < {:g}".format(*moments))
    return None


def repaired(tensor: np.ndarray, repair: Repair) -> tuple[np.ndarray, str | None]:
    """The tensor after the requested repairs, and what changed (None: unchanged)."""
    moments, axes = np.linalg.eigh((tensor + tensor.T) / 2)
    new = moments.copy()
    if repair.bound > 0:
        new = np.maximum(new, repair.bound)
    if repair.balance and new[0] + new[1] < new[2]:
        new = np.full(3, new.mean())
    if np.array_equal(new, moments):
        return tensor, None
    change = ("principal moments " + ", ".join(f"{m:g}" for m in moments) + " -> "
              + ", ".join(f"{m:g}" for m in new))
    return axes @ np.diag(new) @ axes.T, change
