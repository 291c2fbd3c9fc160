"""The load part of a driven coordinate's joint friction in a dynamics run
(docs/forces.md#joint-friction).

A friction on a coordinate a driver prescribes (a `driver:`, a position or speed motor) acts
along that coordinate as the driver's row does: its generalized force s_q^T f is in the span
of that row's gradient, so the driver's multiplier absorbs it and the motion and every other
multiplier are those without it. Its load part -sign(s_dot) mu L therefore changes only the
driver's multiplier, which is along the joint's axis (a force along a slide, a torque about an
axle) and so no joint's load L, and no other joint's load part depends on it. The run
integrates the law without that part, and its rows (and its events' rows) get it afterwards,
by the prescribed motion's correction (formulations/prescribed_friction.py, through
runtime/kinematics.Loads) of each row's multipliers: L from the joint's reaction in that row,
the driver's multiplier (its actuation) with the load part, the friction column
f = -sign(s_dot) (Tc + mu L) - c s_dot, the loads checked as a prescribed motion's
(runtime/load_checks.py). The correction's system (friction_load.coupled) also holds where
the driver's row is not the only one along the coordinate (redundant rows), the loads then
coupled and solved together.
"""

from __future__ import annotations

import numpy as np

from casmech.formulations import prescribed_friction
from casmech.runtime import friction
from casmech.runtime.kinematics import Loads
from casmech.runtime.results import Result


def elements(ir) -> list:
    """The frictions with a load part on driven coordinates."""
    loaded = {e.name for e in prescribed_friction.elements(ir)}
    return [e for e in friction.on_driven(ir) if e.name in loaded]


def amended(functions, result: Result | None) -> Result | None:
    """`result` (a dynamics run's rows, or None) with the load parts of the driven
    coordinates' frictions in its multipliers and friction columns, and in its events' rows:
    a copy (the results files streamed from `result` are rewritten from it), or `result`
    itself when the model has none."""
    loaded = elements(functions.ir)
    if result is None or not loaded or not len(result):
        return result
    found = _rows(functions, loaded, result)
    if result.event_states is not None and len(result.event_states):
        found.event_states = _rows(functions, loaded, result.event_states)
    return found


def _rows(functions, loaded: list, result: Result) -> Result:
    loads = Loads(functions, loaded)
    lam = loads(np.asarray(result.times), np.hstack([result.q, result.q_dot, result.q_ddot]),
                result.lam)
    found = result.with_lam(lam)
    loads.record(found)
    return found
