"""What `casmech check` refuses though loading the model does not: findings that need the run's
time span or that a run would meet at its first row (cli/check.py reports them; `run`
meets them as an analysis failure, runtime.nonfinite, never as a traceback).

- Prescribed motions over the run (E411, E204): every driver (`driver:`, a position or speed
  motor, a basic constraint's `f:`) is evaluated with its first two time derivatives (by
  CasADi) at SAMPLES times from 0 to the end of the run; a value, rate or acceleration beyond
  the plausible magnitudes of schema/limits.py (rates: limits.SPEED; a displacement:
  limits.LENGTH; the rest: limits.ANY), or not finite, is located at the driver's key with the
  time it is reached. A driver `angle: 1e300*t` has the rate 1e300 rad/s, whose square
  overflows the accelerations of the first row.
- A tsda whose points coincide at t = 0 (E404): the direction of its force is undefined there
  (NaN at the first row).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from casmech.elements.coordinate_kinds import REGISTRY as COORDINATES
from casmech.errors import Diagnostic
from casmech.schema import limits
from casmech.schema.loader import format_path, load_document

SAMPLES = 1001  # most times a driver is evaluated at (the output grid when it has fewer)
SPANNED = ("kinematics", "inverse_dynamics", "dynamics")  # analyses over [0, t_end]
POINTS_APART = 1e-12  # [m] least distance of a tsda's points at t = 0
# what a driver measures (a coordinate kind's quantity; "f": a basic constraint's f(t), and a
# quantity not listed) -> (largest value, rate, acceleration)
LARGEST = {"angle": (limits.ANY, limits.SPEED, limits.ANY),
           "length": (limits.LENGTH, limits.SPEED, limits.ANY),
           "f": (limits.ANY, limits.ANY, limits.ANY)}
UNITLESS = ("", "/s", "/s^2")  # units of a basic constraint's f(t) and its rates


def driver_bounds(key: str) -> tuple[tuple[float, ...], tuple[str, ...]]:
    """(largest value, rate, acceleration) of a driver (`f`: a basic constraint's), and their
    units."""
    if key == "f":
        return LARGEST["f"], UNITLESS
    quantity = COORDINATES[key].quantity
    return LARGEST.get(quantity.name, LARGEST["f"]), quantity.units
WHAT = ("value", "rate", "acceleration")


def problems(model) -> list[Diagnostic]:
    """Every finding of this module in `model` (a ResolvedModel)."""
    document = _Locator(model)
    return [*_drivers(model, document), *_tsda(model, document)]


class _Locator:
    """Sources of paths in the model's text (parsed on first use; a component's joint: its
    own source)."""

    def __init__(self, model):
        self.model, self.document = model, None

    def __call__(self, path, fallback):
        try:
            if self.document is None:
                self.document = load_document(self.model.text, self.model.file)
            return self.document.locate(path) or fallback
        except Exception:  # noqa: BLE001 - the location is a courtesy; the message stands alone
            return fallback


def sample_times(analysis) -> np.ndarray:
    """Where the drivers are evaluated: 0 to the end of the run (modal: to `at`)."""
    end = getattr(analysis.options, "at", None) if analysis.type == "modal" else (
        analysis.t_end if analysis.type in SPANNED else None)
    if not end:
        return np.zeros(1)
    step = min(analysis.output_step, end)
    intervals = int(np.floor(end / step + 1e-9))
    if intervals + 1 > SAMPLES:
        return np.linspace(0.0, end, SAMPLES)
    times = step * np.arange(intervals + 1)  # the output grid
    return times if times[-1] >= end - 1e-9 * step else np.append(times, end)


def _drivers(model, locate) -> list[Diagnostic]:
    drivers = [(index, joint, key, function) for index, joint in enumerate(model.joints)
               for key, function in (*joint.drivers.items(), ("f", joint.f))
               if function is not None]
    if not drivers:
        return []
    times = sample_times(model.analysis)
    rows = _evaluate([function for *_, function in drivers], times)
    found = []
    for (index, joint, key, function), values in zip(drivers, rows, strict=True):
        problem = _beyond(values, times, key)
        if problem is None:
            continue
        where = ("joints", index, "driver", key) if key != "f" else ("joints", index, "f")
        source = joint.sources.get(f"driver.{key}" if key != "f" else "f", joint.source)
        code, message, expected = problem
        found.append(Diagnostic(code, format_path(where), message, locate(where, source),
                                expected=expected, got=function.text[:80],
                                hint="SI units: radians, metres, seconds; a motion this fast "
                                     "leaves double precision in the accelerations"))
    return found


def _evaluate(functions, times: np.ndarray) -> np.ndarray:
    """(drivers, 3, times): each driver's value, rate and acceleration at the times (one
    CasADi Function over all of them, mapped over the times)."""
    t = ca.SX.sym("t")
    values = ca.vertcat(*[ca.SX(function.casadi(t=t)) for function in functions])
    rates = ca.jacobian(values, t)
    mapped = ca.Function("drivers", [t], [values, rates, ca.jacobian(rates, t)]).map(len(times))
    outputs = [np.array(out).reshape(len(functions), len(times))
               for out in mapped(times.reshape(1, -1))]
    return np.stack(outputs, axis=1)


def _beyond(rows: np.ndarray, times: np.ndarray, key: str):
    """(code, message, expected) of the first sample where a driver (`rows`: its value, rate
    and acceleration at `times`) is not finite or beyond its `bounds`; None when none is."""
    (bounds, units) = driver_bounds(key)
    with np.errstate(invalid="ignore"):
        bad = ~np.isfinite(rows) | (np.abs(rows) > np.array(bounds)[:, None])
    if not bad.any():
        return None
    sample, which = divmod(int(np.argmax(bad.T.ravel())), len(WHAT))  # the earliest time
    number, unit = rows[which, sample], f" {units[which]}".rstrip()
    at = f"at t = {times[sample]:.6g} s"
    if not np.isfinite(number):
        return ("E204", f"the driver's {WHAT[which]} is {number} {at}",
                "a finite value over the run")
    return ("E411", f"the driver's {WHAT[which]} reaches {abs(number):.3g}{unit} {at}: "
            "implausible", f"a magnitude of at most {bounds[which]:g}{unit} over the run")


def _tsda(model, locate) -> list[Diagnostic]:
    found = []
    for index, force in enumerate(model.forces):
        if force.type != "tsda":
            continue
        length = float(np.linalg.norm(force.vectors["at_j"] - force.vectors["at_i"]))
        if length < POINTS_APART:
            found.append(Diagnostic(
                "E404", format_path(("forces", index, "at_j")), "the tsda's points coincide "
                "at t = 0: the direction of its force is undefined there",
                locate(("forces", index, "at_j"), force.source),
                got=f"|at_j - at_i| = {length:g}",
                hint="attach its ends at distinct points (a spring of zero rest length is "
                     "`free_length: 0` between points apart)"))
    return found
