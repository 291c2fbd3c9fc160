"""The modal analysis's own keys of `analysis:` (runtime/modal.py): `at`, a time of a dynamics
run to linearize at (0 <= at <= t_end; default: the static equilibrium), and `inputs`, the
effort-motor joints and force elements whose force is an input of the linear model."""

from __future__ import annotations

from dataclasses import replace

from casmech.core.options import ModalOptions
from casmech.elements.force_types import input_types
from casmech.elements.joint_types import listed
from casmech.schema import limits, resolved, spec
from casmech.schema.checker import Checker
from casmech.schema.loader import Path


def modal_settings(check: Checker, given: spec.Analysis, settings: resolved.Analysis | None,
                   joints, forces) -> resolved.Analysis | None:
    """`settings` with `at` (seconds or None) and `inputs` (names or None) in its options
    (modal) and in the keys written (for a modal run of a model of another type), checked:
    E409 for an `at` outside [0, t_end] or in (0, limits.MIN_TIME),
    E300 for an input that is no effort-motor joint or
    force element."""
    path: Path = ("analysis",)
    at = None
    if given.at is not None:
        at = check.setting((*path, "at"), given.at)
        t_end = settings.t_end if settings is not None else None
        if at is not None and (at < 0 or (t_end is not None and at > t_end)):
            check.error("E409", (*path, "at"), "at must be a time of the run, within [0, t_end]",
                        got=f"{at:g}", hint=f"0 <= at <= t_end = {t_end:g}" if t_end else None)
            at = None
        elif at is not None and 0 < at < limits.MIN_TIME:
            check.error("E409", (*path, "at"), f"at must be 0 or at least {limits.MIN_TIME:g} s",
                        got=f"{at:g}", hint="at: 0 linearizes at the initial state")
            at = None
    known = {j.name: "joint" for j in joints if j is not None and j.motor}
    types = input_types()  # force element types that may be inputs (casmech.elements.force_types)
    known |= {f.name: f.type for f in forces if f is not None and f.type in types}
    inputs_ok = True
    what = f"input (an effort-motor joint or a {listed(types, 'or')} element)"
    for index, name in enumerate(given.inputs or ()):
        if not check.reference((*path, "inputs", index), name, known, what):
            inputs_ok = False
    if settings is None or (given.at is not None and at is None) or not inputs_ok:
        return None
    inputs = None if given.inputs is None else tuple(dict.fromkeys(given.inputs))
    written = (*settings.written, *((key, value) for key, value in (("at", at), ("inputs", inputs))
                                    if value is not None))
    options = settings.options
    if isinstance(options, ModalOptions):
        options = replace(options, at=at, inputs=inputs)
    return replace(settings, options=options, written=written)
