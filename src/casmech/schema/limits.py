"""Plausibility limits on the numbers of a model (E411) and on its analysis settings (E409).

Every number of a body, joint, force, instance and gravity is bounded in magnitude: a position
of 1e300 m overflows NumPy's squares and SVDs (a traceback, or a wrong rank with an overflow
warning), and nothing a mechanism means comes near these bounds. Parameters are not bounded
(they may be intermediate values); what they evaluate to where they are used is.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from casmech.schema.loader import Path

LENGTH = 1e6  # [m] positions, points, offsets and sizes: 1000 km (move the origin instead)
SPEED = 1e6  # [m/s], [rad/s] initial velocities
GRAVITY = 1e6  # [m/s^2] 100 000 g
ANY = 1e12  # anything else: masses [kg], inertias, stiffnesses, forces... (squares stay far
#             from overflow, and 1e12 is beyond any physical constant of a mechanism)

# the YAML key a number is written under -> (largest magnitude, what it is, unit)
KEYS: dict[str, tuple[float, str, str]] = {
    **{key: (LENGTH, "a position or length", "m") for key in (
        "position", "at", "at_i", "at_j", "s_i", "s_j", "offset", "length", "free_length",
        "box", "radius")},
    "velocity": (SPEED, "a velocity", "m/s"),
    "angular_velocity": (SPEED, "an angular velocity", "rad/s"),
    "gravity": (GRAVITY, "gravity", "m/s^2"),
    **{key: (ANY, "a direction's component", "") for key in (
        "axis", "axis_i", "axis_j", "a_i", "a_j", "c", "x_axis", "y_axis", "z_axis")},
}
BOUNDED = frozenset({"bodies", "joints", "forces", "instances", "gravity"})  # first path keys

# analysis settings (E409)
MIN_RTOL, MAX_RTOL = 1e-14, 0.1  # below ~100 unit roundoffs IDAS/CVODES stop with "too much
#                                  accuracy requested"; above 10% an integrator controls nothing
MIN_ATOL, MAX_ATOL = 1e-20, 1.0  # the error weight 1/(rtol |y| + atol) stays finite
MAX_T_END = 1e9  # [s] 30 years of simulated time
MIN_TIME = 1e-12  # [s] least t_end and output_step: a picosecond is below every time scale of
#                   a rigid-body model, and far above the subnormal numbers (2e-320) whose
#                   ratios overflow and whose few significant digits make no grid
MAX_ELEMENTS = 10_000  # ocp: intervals x elements, each a block of NLP variables and constraints
#                        as large as the states (beyond, minutes to build and gigabytes)
MAX_ROWS = 1_000_000  # rows of the output grid (t_end / output_step + 1)
MAX_VALUES = 20_000_000  # rows x results columns: the results table passes through CasADi's
#                          DM -> list -> NumPy conversion at ~50 bytes a value (1 GB here)

# the hint of an E409 finding, by setting
HINTS = {
    "output_step": "a larger output_step or a shorter t_end (output_step is the interval of "
                   "the rows written, not the integrator's step)",
    "rtol": "1e-6 (quick) to 1e-10 (tight); the default is 1e-8",
    "atol": "the absolute error allowed in metres and radians; the default is 1e-10",
}

# the methods that integrate joint coordinates only, and what they integrate (E409 where the
# formulation that runs is another: schema.semantic, runtime.auto_formulation)
JOINT_METHODS = {"adams": "a tree", "dop853": "a tree or the projected ODE of its loops"}
# those of them that run on loops (the others integrate a tree only: E409 on loops)
LOOP_METHODS = ("dop853",)
BDF = "IDAS's BDF method"  # what integrates the DAEs of rp, romega and the joint loops' DAE


def joint_method(method: str) -> str:
    """What a method of JOINT_METHODS integrates, as its E409 says it."""
    return f"method {method} integrates joint coordinates of {JOINT_METHODS[method]}"


def limit(path: Path | str) -> tuple[float, str, str] | None:
    """(largest magnitude, what, unit) of the number at `path`, or None (not bounded)."""
    if not isinstance(path, tuple) or not path or path[0] not in BOUNDED:
        return None
    key = next((step for step in reversed(path) if isinstance(step, str)), "")
    return KEYS.get(key, (ANY, "a value", "SI units"))


def implausible(path: Path | str, value: float) -> tuple[str, str] | None:
    """(the problem, what is expected) of `value` at `path`, or None when it is plausible."""
    bound = limit(path)
    if bound is None or abs(value) <= bound[0]:
        return None
    unit = f" {bound[2]}" if bound[2] else ""
    return (f"{bound[1]} of magnitude {abs(value):.3g}{unit} is implausible",
            f"a magnitude of at most {bound[0]:g}{unit}")


def grid_rows(t_end: float, output_step: float) -> float:
    """Rows of the output grid from 0 to t_end every output_step (as a float: may be huge; inf
    when the ratio overflows, as for a subnormal output_step)."""
    ratio = t_end / output_step if output_step > 0 else math.inf
    return math.floor(ratio + 1e-9) + 2 if math.isfinite(ratio) else math.inf


def analysis_problems(settings: dict[str, float], columns: int,
                      step_within: bool = True, grid: bool = True) -> dict[str, str]:
    """{setting: problem} of t_end, output_step, rtol, atol (non-positive, not finite, out of
    range (t_end and output_step below MIN_TIME included), with `grid` an output grid of more
    than MAX_ROWS rows or MAX_VALUES values; with `step_within`, an output_step larger than
    t_end)."""
    problems: dict[str, str] = {}
    for key, value in settings.items():
        if value is None:
            continue
        if not math.isfinite(value):
            problems[key] = f"{key} must be a finite number"
        elif value <= 0:
            problems[key] = f"{key} must be positive"
    t_end, step = settings.get("t_end"), settings.get("output_step")
    rtol, atol = settings.get("rtol"), settings.get("atol")
    if "t_end" not in problems and t_end is not None and t_end > MAX_T_END:
        problems["t_end"] = f"t_end must be at most {MAX_T_END:.0e} s"
    for key in ("t_end", "output_step"):
        value = settings.get(key)
        if key not in problems and value is not None and value < MIN_TIME:
            problems[key] = f"{key} must be at least {MIN_TIME:g} s"
    if "rtol" not in problems and rtol is not None and not MIN_RTOL <= rtol <= MAX_RTOL:
        problems["rtol"] = f"rtol must be between {MIN_RTOL:g} and {MAX_RTOL:g}"
    if "atol" not in problems and atol is not None and not MIN_ATOL <= atol <= MAX_ATOL:
        problems["atol"] = f"atol must be between {MIN_ATOL:g} and {MAX_ATOL:g}"
    if problems.keys() & {"t_end", "output_step"} or t_end is None or step is None:
        return problems
    if step_within and step > t_end:
        problems["output_step"] = "output_step must not exceed t_end"
        return problems
    if not grid:
        return problems
    rows = grid_rows(t_end, step)
    if rows > MAX_ROWS or rows * columns > MAX_VALUES:
        problems["output_step"] = (
            f"the output grid would have {rows:.3g} rows of {columns} columns; at most "
            f"{MAX_ROWS} rows and {MAX_VALUES:.0e} values")
    return problems


def ocp_problems(horizon: float | None, intervals: int, elements: int) -> dict[str, str]:
    """{key: problem} of an ocp block's horizon (within [MIN_TIME, MAX_T_END]), intervals and
    elements (at least 1, their product at most MAX_ELEMENTS)."""
    problems: dict[str, str] = {}
    if horizon is not None and not MIN_TIME <= horizon <= MAX_T_END:
        problems["horizon"] = f"horizon must be between {MIN_TIME:g} and {MAX_T_END:g} s"
    for key, value in (("intervals", intervals), ("elements", elements)):
        if value < 1:
            problems[key] = f"{key} must be at least 1"
    if not problems.keys() & {"intervals", "elements"} and intervals * elements > MAX_ELEMENTS:
        key = "intervals" if intervals >= elements else "elements"
        problems[key] = (f"intervals x elements = {intervals * elements} collocation elements; "
                         f"at most {MAX_ELEMENTS}")
    return problems
