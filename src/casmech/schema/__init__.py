"""YAML model files -> checked, evaluated `ResolvedModel` (see docs/format.md).

    load_model(path, overrides=None, symbolic=())                    read a file
    load_model_text(text, file="<string>", overrides=None, symbolic=())

Both raise `casmech.errors.ModelError` holding every finding (YAML, structure, expressions, names,
physics), each rendered as `file:line:col: error[CODE] path: message`.

`symbolic` names parameters (`L`, an instance's `leg1.L`) evaluated as traced numbers
(casmech.core.traced): everything computed from them (other parameters, masses, inertias,
poses, joint points and axes, placements, force and driver constants) carries its CasADi
expression of their symbols (`ResolvedModel.symbols`), and model.lower keeps it, so the
model data is a function of them (model.parametric). A parameter that sets a structure (a
repeat count, a `{expr}` name) cannot be symbolic (E103). Without `symbolic` no traced number
is made.

The package imports its modules where they are used, so that importing one of them (the
compiler reads `casmech.schema.resolved`) does not import pydantic and the whole checker. The
schema reads the bottom layer (casmech.core, casmech.elements.joint_types), never the compiler.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

from casmech.errors import Diagnostic, ModelError, UsageError

if TYPE_CHECKING:
    from casmech.schema.loader import Document
    from casmech.schema.resolved import ResolvedModel


def _order(diagnostic: Diagnostic) -> tuple[int, int]:
    source = diagnostic.source
    return (0, 0) if source is None else (source.line, source.col)


def _in_files(diagnostic: Diagnostic, top: str) -> tuple:
    """The model's own file first, then the component files, each by line."""
    file = diagnostic.source.file if diagnostic.source else top
    return (file != top, file, *_order(diagnostic))


def _resolve(document: Document, overrides: Mapping[str, str] | None,
             symbolic: Sequence[str] = ()) -> ResolvedModel:
    """Overflows and NaNs are reported as findings (E204, E411), never warned about; paths in
    the model resolve inside its folder (schema/files.py), and the model records the digests
    of the files it read or named (`sources`) and the overrides it was loaded with."""
    import numpy as np

    from casmech.core.traced import NotANumber
    from casmech.schema import files

    symbols = _symbols(symbolic)
    with np.errstate(all="ignore"), files.rooted(document.file) as named:
        try:
            model = _findings(document, overrides, symbols)
        except NotANumber as error:  # a place that needs a plain number (never without symbols)
            raise UsageError(f"{document.file}: {', '.join(symbols)} cannot be symbolic in "
                             f"this model: {error}") from None
    return replace(model, sources=files.digests(document.file, named),
                   overrides=dict(overrides or {}), symbols=symbols)


def _symbols(names: Sequence[str]) -> dict:
    """A CasADi symbol for each symbolic parameter."""
    if isinstance(names, str):
        raise TypeError("symbolic: a sequence of parameter names, not one string")
    if not names:
        return {}
    import casadi as ca

    return {name: ca.SX.sym(name) for name in dict.fromkeys(names)}


def _findings(document: Document, overrides: Mapping[str, str] | None,
              symbols: Mapping) -> ResolvedModel:
    from casmech.schema.repeat import too_many, uses_composition
    from casmech.schema.semantic import resolve
    from casmech.schema.spec_errors import validate

    if uses_composition(document.data):  # components, instances, repeat: docs/components.md
        from casmech.schema.components import compose

        model, found = compose(document, overrides, symbols)
        found = sorted(dict.fromkeys(found), key=lambda d: _in_files(d, document.file))
        if found or model is None:
            raise ModelError(found)
        return model
    found = too_many(document)  # composed models count as they are made (repeat.Budget)
    if found:
        raise ModelError(found)
    spec, found = validate(document)
    model = None
    if spec is not None:
        model, found = resolve(document, spec, overrides, symbols)
    found = sorted([*document.diagnostics, *found], key=_order)
    if found or model is None:
        raise ModelError(found)
    return model


def load_model(path: str | Path, overrides: Mapping[str, str] | None = None,
               symbolic: Sequence[str] = ()) -> ResolvedModel:
    """Read, validate and evaluate a model file; raises ModelError with every finding.
    `symbolic`: parameters evaluated as traced numbers (module docstring)."""
    from casmech.schema.loader import load_file

    return _resolve(load_file(str(path)), overrides, symbolic)


def load_model_text(
    text: str, file: str = "<string>", overrides: Mapping[str, str] | None = None,
    symbolic: Sequence[str] = (),
) -> ResolvedModel:
    """As `load_model`, from text (`file` names it in diagnostics)."""
    from casmech.schema.loader import load_document

    return _resolve(load_document(text, file), overrides, symbolic)


__all__ = ["load_model", "load_model_text"]
