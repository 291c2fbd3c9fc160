"""CasADi values of model data that may be numbers or symbols."""

from __future__ import annotations

import casadi as ca


def constant(value):
    """A field of the IR as a CasADi matrix: DM for numbers, as it is when symbolic (the model
    data of model.parametric). The compiler and the force laws read IR vectors through this,
    never ca.DM, which turns a symbol into NaN without an error."""
    return value if isinstance(value, (ca.SX, ca.MX)) else ca.DM(value)
