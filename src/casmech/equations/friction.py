"""Joint friction: Coulomb and viscous along a joint's coordinate (docs/forces.md#joint-friction).

The coordinate s is the one a stop acts on (equations/limits.py): the angle of a revolute
joint, the slide of a translational, cylindrical or screw one. Its params are `coulomb` Tc,
`viscous` c, `static` Ts, `mu`, `mu_static`, `radius` (the load part: equations/friction_load.py),
and the mode the runtime sets (runtime/friction.py): `direction` d (+1 or -1 while sliding
that way; 0: by the rate's sign), `stuck` (1: the joint is held by a row the runtime adds,
and this law is 0) and, while a joint with `mu` slides, `load`: the Function (t, q, q_dot) ->
(mu L, ...) of friction_load.sliding. Sliding,

    f = -sign (Tc + mu L + c |s_dot|) = -sign (Tc + mu L) - c s_dot,
    sign = d, or sign(s_dot) when d = 0,

applied as the generalized force s_q^T f (virtual work). With d fixed over a sliding interval
the law is smooth there; the runtime locates where s_dot reaches 0 and decides stick or slip.
The results columns are `<joint>.friction` (f; while stuck, the holding force the runtime
records) and `<joint>.friction_mode` (+1, -1 sliding, 0 stuck). The friction does not enter
the joint's reaction columns.
"""

from __future__ import annotations

import casadi as ca

from casmech.elements.coordinate_kinds import of_type
from casmech.equations import coordinates
from casmech.model.ir import ForceIR

COORDINATE = of_type("friction")  # ForceIR type (each kind's `friction`) -> the kind
COLUMNS = ("friction", "friction_mode")


def coordinate(element: ForceIR, x):
    return coordinates.coordinate(COORDINATE[element.type], element, x)


def law(element: ForceIR, x) -> tuple:
    """(s, f, mode) as expressions of q and q_dot."""
    p = element.params
    s = coordinate(element, x)
    s_dot = x.rate(s)
    d = p["direction"]
    sign = d + (1 - d * d) * ca.sign(s_dot)  # d when it is +-1, sign(s_dot) when it is 0
    mode = (1 - p["stuck"]) * sign
    load = p.get("load")
    loaded = 0 if load is None else load(x.t, x.q, x.q_dot)[0]
    return s, mode * -(p["coulomb"] + loaded) - (1 - p["stuck"]) * p["viscous"] * s_dot, mode


def generalized_force(element: ForceIR, x):
    """(s_q^T f, no potential): a FORCE_ELEMENTS row of equations/eom.py."""
    s, f, _ = law(element, x)
    return ca.jacobian(s, x.q).T * f, 0.0


def outputs(element: ForceIR, x) -> list:
    _, f, mode = law(element, x)
    return [f, mode]


def output_names(element: ForceIR) -> list[str]:
    return [f"{element.name}.{column}" for column in COLUMNS]
