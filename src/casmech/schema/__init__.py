"""YAML model files -> checked, evaluated `ResolvedModel` (see MODEL_FORMAT.md).

    load_model(path, overrides=None)                    read a file
    load_model_text(text, file="<string>", overrides=None)

Both raise `casmech.errors.ModelError` holding every finding (YAML, structure, expressions, names,
physics), each rendered as `file:line:col: error[CODE] path: message`.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

from casmech.errors import Diagnostic, ModelError
from casmech.schema.components import compose, uses_composition
from casmech.schema.loader import Document, load_document, load_file
from casmech.schema.resolved import ResolvedModel
from casmech.schema.semantic import resolve
from casmech.schema.spec_errors import validate


def _order(diagnostic: Diagnostic) -> tuple[int, int]:
    source = diagnostic.source
    return (0, 0) if source is None else (source.line, source.col)


def _in_files(diagnostic: Diagnostic, top: str) -> tuple:
    """The model's own file first, then the component files, each by line."""
    file = diagnostic.source.file if diagnostic.source else top
    return (file != top, file, *_order(diagnostic))


def _resolve(document: Document, overrides: Mapping[str, str] | None) -> ResolvedModel:
    if uses_composition(document.data):  # components, instances, repeat: docs/components.md
        model, found = compose(document, overrides)
        found = sorted(dict.fromkeys(found), key=lambda d: _in_files(d, document.file))
        if found or model is None:
            raise ModelError(found)
        return model
    spec, found = validate(document)
    model = None
    if spec is not None:
        model, found = resolve(document, spec, overrides)
    found = sorted([*document.diagnostics, *found], key=_order)
    if found or model is None:
        raise ModelError(found)
    return model


def load_model(path: str | Path, overrides: Mapping[str, str] | None = None) -> ResolvedModel:
    """Read, validate and evaluate a model file; raises ModelError with every finding."""
    return _resolve(load_file(str(path)), overrides)


def load_model_text(
    text: str, file: str = "<string>", overrides: Mapping[str, str] | None = None
) -> ResolvedModel:
    """As `load_model`, from text (`file` names it in diagnostics)."""
    return _resolve(load_document(text, file), overrides)


__all__ = ["load_model", "load_model_text"]
