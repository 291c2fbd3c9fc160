"""dd/dtheta: the derivative of a model's data (model.parametric) with respect to file
parameters, by central differences of the NumPy lowering.

The model data `d` is every number of the lowered model (masses, inertias, body-frame joint
points and axes, initial poses, lengths, force and driver constants). Geometry goes through the
schema's placements and rotations in NumPy, so d(theta) is differentiated numerically: for each
parameter, the model is re-loaded and lowered at theta +- k h / 2 (k = 1, 2, 3, 4, 6;
h = STEP |theta|, or STEP when theta = 0) and the sixth-order central formula is applied with
step h / 2. This is the lowering alone, never a simulation. The error estimate is the
difference to the same formula with step h (64 times the truncation error at h / 2,
asymptotically: a conservative estimate), plus the round-off of the numbers that move
through the weights (ROUNDING |d| / (h / 2)), which dominates for a number much larger than its
derivative (an initial spin of 87 rad/s that moves by 0.007 per unit of a disc's thickness:
2e-8 relative). Its accuracy on the gallery: docs/decisions/geometry-derivatives.md.
Above SMOOTHNESS the lowering is not smooth at theta (a branch of the lowering switches inside
the stencil) and a smaller step is tried.

A parameter whose change alters the structure (a zero of the data that becomes non-zero, a
repeat count, a model that no longer validates) has no derivative through a build of that
structure: a UsageError located at the parameter says so.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from casmech.core.expressions import parse
from casmech.errors import ModelError, UsageError
from casmech.model import parametric
from casmech.model.ir import ModelIR
from casmech.model.lower import lower
from casmech.schema import load_model_text
from casmech.schema.loader import load_document
from casmech.schema.resolved import ResolvedModel

STEP = 1e-2  # relative step of the stencil
STEPS = (STEP, STEP / 10, STEP / 100)  # tried in turn when the lowering is not smooth
SIXTH = ((1, 3 / 4), (2, -3 / 20), (3, 1 / 60))  # (k, weight of f(x + k h) - f(x - k h))
OFFSETS = (1, 2, 3, 4, 6)  # the stencils at h / 2 and at h, in units of h / 2
SMOOTHNESS = 1e-6  # largest accepted error estimate, relative to the derivative's scale
ROUNDING = 4 * np.finfo(float).eps  # relative error of a number of the lowering


@dataclass(frozen=True)
class DataDerivative:
    split: parametric.Split  # the model's symbolic IR, d's symbols and values
    jacobian: np.ndarray  # (len(d), len(names)): dd/dtheta
    error: np.ndarray  # (len(names),): estimated error (truncation, round-off) of each column,
    # relative to its largest entry
    names: tuple[str, ...]
    moved: np.ndarray  # (len(d),) bool: the entries any parameter's stencil changed


def dependents(model: ResolvedModel, names: Sequence[str]) -> set[str]:
    """The file's parameters whose expressions read `names`, directly or through others
    (`names` included)."""
    written = load_document(model.text, model.file).data.get("parameters") or {}
    reads = {k: parse(v).symbols if isinstance(v, str) else set() for k, v in written.items()}
    found = set(names)
    while True:
        more = {k for k, symbols in reads.items() if symbols & found} - found
        if not more:
            return found
        found |= more


class Lowering:
    """The model re-loaded with parameters moved and every top-level parameter that does not
    depend on them at the value it has (overrides included)."""

    def __init__(self, model: ResolvedModel):
        self.model = model
        self.written = load_document(model.text, model.file).data.get("parameters") or {}
        # parameters moved -> overrides of the others
        self.fixed: dict[tuple[str, ...], dict[str, str]] = {}

    def reloaded(self, values: Mapping[str, float]) -> ResolvedModel:
        """The model with the parameters `values` moved (ModelError if that makes it invalid)."""
        model, names = self.model, tuple(values)
        if names not in self.fixed:
            follow = dependents(model, names)
            self.fixed[names] = {k: repr(float(model.parameters[k])) for k in self.written
                                 if k not in follow and k in model.parameters}
        return load_model_text(model.text, model.file, {
            **self.fixed[names], **{n: repr(float(v)) for n, v in values.items()}})

    def ir(self, name: str, value: float) -> ModelIR:
        return lower(self.reloaded({name: value}))


def located(model: ResolvedModel, name: str, message: str) -> UsageError:
    source = load_document(model.text, model.file).locate_key(("parameters", name))
    return UsageError(f"{source}: parameter '{name}' {message}")


def _stencil(lowering: Lowering, name: str, value: float, half: float, reference: ModelIR,
             signature: str) -> dict[int, np.ndarray]:
    """d at value + k half for k = +-OFFSETS; ValueError when the structure changes or the
    model is invalid there."""
    points = {}
    for k in (*OFFSETS, *(-k for k in OFFSETS)):
        try:
            ir = lowering.ir(name, value + k * half)
        except ModelError as error:
            raise ValueError(f"makes the model invalid at {name} = {value + k * half:.9g} "
                             f"({error.diagnostics[0].format()})") from None
        values, moved = parametric.data(ir)
        if moved != signature:
            raise ValueError(f"changes the model's structure at {name} = "
                             f"{value + k * half:.9g} ({parametric.difference(reference, ir)})")
        points[k] = values
    return points


def _sixth(points: Mapping[int, np.ndarray], unit: int, half: float) -> np.ndarray:
    """The sixth-order central difference with step unit * half."""
    return sum(w * (points[k * unit] - points[-k * unit]) for k, w in SIXTH) / (unit * half)


def _column(points: Mapping[int, np.ndarray], half: float) -> tuple[np.ndarray, float,
                                                                   np.ndarray]:
    """(the sixth-order derivative at step h / 2, its error estimate relative to its largest
    entry, the entries that moved): truncation, as its difference to the same formula at step
    h (64 times its own truncation error, asymptotically), plus round-off (ROUNDING of each
    number that moves, through the weights, over h / 2), entry by entry."""
    fine, coarse = _sixth(points, 1, half), _sixth(points, 2, half)
    stacked = np.array(list(points.values()))
    moved = np.any(stacked != stacked[0], axis=0)  # numbers theta does not reach are exact
    rounding = ROUNDING * np.abs(stacked).max(axis=0) * moved * 2 * sum(
        abs(w) for _, w in SIXTH) / half
    scale = max(np.abs(fine).max(initial=0.0), 1e-300)
    return fine, float((np.abs(fine - coarse) + rounding).max(initial=0.0) / scale), moved


def derivative(model: ResolvedModel, names: Sequence[str]) -> DataDerivative:
    """dd/dtheta of the model's data for the file parameters `names`."""
    names = tuple(names)
    reference = lower(model)
    split = parametric.split(reference)
    lowering = Lowering(model)
    columns, errors, moved = [], [], np.zeros(split.values.size, bool)
    for name in names:
        value = float(model.parameters[name])
        again = parametric.data(lowering.ir(name, value))
        if again[1] != split.signature or not np.array_equal(again[0], split.values):
            computed = sorted(dependents(model, [name]) - {name})
            raise located(model, name, "cannot be moved alone: the model re-loaded with it "
                           "differs from the one given (was a parameter computed from it set "
                           f"on the command line? {', '.join(computed) or 'none'} follow it)")
        problems = []
        for step in STEPS:
            h = step * (abs(value) or 1.0)
            try:
                column, error, changed = _column(_stencil(lowering, name, value, h / 2,
                                                          reference, split.signature), h / 2)
            except ValueError as problem:
                problems.append(str(problem))
                continue
            if error <= SMOOTHNESS:
                break
            problems.append(f"moves the model's numbers non-smoothly near {name} = "
                            f"{value:.9g} (estimated error {error:.1e} with step {h:.1e})")
        else:
            raise located(model, name, f"{problems[-1]}; sensitivities need a parameter that "
                           "keeps the structure (which numbers are zero, repeat counts) and "
                           "moves the model's numbers smoothly")
        columns.append(column)
        errors.append(error)
        moved |= changed
    jacobian = np.stack(columns, axis=1) if columns else np.zeros((split.values.size, 0))
    return DataDerivative(split, jacobian, np.array(errors), names, moved)
