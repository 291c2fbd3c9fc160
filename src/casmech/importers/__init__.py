"""Importers: other tools' model files -> casmech YAML text.

    text, warnings = casmech.importers.import_file("deck.adm")

Suffix -> translator: `.adm` (Adams/Solver dataset, importers/adm.py), `.mdl` / `.acf`
(simEngine3D model / analysis-control JSON, importers/simengine.py), `.urdf` (robot description,
importers/urdf.py). Every translator returns an `emit.Imported`; what it could not translate is
a warning Diagnostic naming the source line.
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


def _urdf(path: Path, **initial) -> Imported:
    from casmech.importers.urdf import import_urdf
    return import_urdf(path, **initial)


TRANSLATORS = {".adm": _adm, ".mdl": _simengine, ".acf": _simengine, ".urdf": _urdf}


def translate(path: str | Path, **options) -> Imported:
    """`options`: the URDF importer's initial joint `positions` and `velocities` (by name)."""
    path = Path(path)
    translator = TRANSLATORS.get(path.suffix.lower())
    if translator is None:
        raise UsageError(f"{path}: cannot import a '{path.suffix}' file; expected one of "
                         f"{', '.join(TRANSLATORS)} (Adams dataset, simEngine3D model/acf, URDF)")
    if not path.is_file():
        raise UsageError(f"{path}:1:1: no such file")
    if any(options.values()) and translator is not _urdf:
        raise UsageError(f"{path}: initial joint positions and velocities are for URDF files")
    return translator(path, **{k: v for k, v in options.items() if v})


def import_file(path: str | Path, **options) -> tuple[str, list[Diagnostic]]:
    """The casmech YAML text of a model file, and the warnings of its translation."""
    model = translate(path, **options)
    return to_yaml(model), model.warnings
