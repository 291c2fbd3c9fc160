"""Importers: other tools' model files -> casmech YAML text.

    text, warnings = casmech.importers.import_file("deck.adm")

Suffix -> translator: `.adm` (Adams/Solver dataset, importers/adm.py), `.mdl` / `.acf`
(simEngine3D model / analysis-control JSON, importers/simengine.py). Every translator returns an
`emit.Imported`; what it could not translate is a warning Diagnostic naming the source line.
"""

from __future__ import annotations

from pathlib import Path

from casmech.errors import Diagnostic, UsageError
from casmech.importers.emit import Imported, to_yaml


def _adm(path: Path) -> Imported:
    from casmech.importers.adm import import_adm
    return import_adm(path)


def _simengine(path: Path) -> Imported:
    from casmech.importers.simengine import import_simengine
    return import_simengine(path)


TRANSLATORS = {".adm": _adm, ".mdl": _simengine, ".acf": _simengine}


def translate(path: str | Path) -> Imported:
    path = Path(path)
    translator = TRANSLATORS.get(path.suffix.lower())
    if translator is None:
        raise UsageError(f"{path}: cannot import a '{path.suffix}' file; expected one of "
                         f"{', '.join(TRANSLATORS)} (Adams dataset, simEngine3D model/acf)")
    if not path.is_file():
        raise UsageError(f"{path}:1:1: no such file")
    return translator(path)


def import_file(path: str | Path) -> tuple[str, list[Diagnostic]]:
    """The casmech YAML text of a model file, and the warnings of its translation."""
    model = translate(path)
    return to_yaml(model), model.warnings
