"""Importers: other tools' model files -> casmech YAML text.

    text, warnings = casmech.importers.import_file("deck.adm")

Suffix -> translator: `.adm` (Adams/Solver dataset, importers/adm.py), `.mdl` / `.acf`
(simEngine3D model / analysis-control JSON, importers/simengine.py), `.urdf` (robot description,
importers/urdf.py), `.xml` / `.mjcf` (MuJoCo MJCF model, importers/mjcf.py). Every translator
returns an `emit.Imported`; what it could not translate is a warning Diagnostic naming the
source line.
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


def _urdf(path: Path, **options) -> Imported:
    from casmech.importers.urdf import import_urdf
    return import_urdf(path, **options)


def _mjcf(path: Path, **options) -> Imported:
    from casmech.importers.mjcf import import_mjcf
    return import_mjcf(path, **options)


TRANSLATORS = {".adm": _adm, ".mdl": _simengine, ".acf": _simengine, ".urdf": _urdf,
               ".xml": _mjcf, ".mjcf": _mjcf}
KINDS = "Adams dataset, simEngine3D model/acf, URDF, MJCF"
# the options each translator takes (import_cmd's flags), beside the path
OPTIONS = {_urdf: {"positions", "velocities", "floating_base", "mesh_dirs", "output",
                   "bound_inertia", "balance_inertia"},
           _mjcf: {"positions", "velocities", "keyframe", "mesh_dirs", "output",
                   "bound_inertia", "balance_inertia"}}
ALWAYS = {"output"}  # given to every translator that takes it, never refused


def translate(path: str | Path, **options) -> Imported:
    """`options`: the URDF and MJCF importers' (importers.urdf.import_urdf,
    importers.mjcf.import_mjcf): initial joint `positions` and `velocities` by name, ...;
    an option a translator does not take is a usage error."""
    path = Path(path)
    translator = TRANSLATORS.get(path.suffix.lower())
    if translator is None:
        raise UsageError(f"{path}: cannot import a '{path.suffix}' file; expected one of "
                         f"{', '.join(TRANSLATORS)} ({KINDS})")
    if not path.is_file():
        raise UsageError(f"{path}:1:1: no such file")
    accepted = OPTIONS.get(translator, set())
    given = {key: value for key, value in options.items() if value}
    refused = sorted(set(given) - accepted - ALWAYS)
    if refused:
        flags = ", ".join("--" + key.rstrip("s").replace("_", "-") for key in refused)
        verb = "is not an option" if len(refused) == 1 else "are not options"
        raise UsageError(f"{path}: {flags} {verb} of a '{path.suffix}' import (URDF and MJCF "
                         "files take them)")
    return translator(path, **{k: v for k, v in given.items() if k in accepted})


def import_file(path: str | Path, **options) -> tuple[str, list[Diagnostic]]:
    """The casmech YAML text of a model file, and the warnings of its translation."""
    model = translate(path, **options)
    return to_yaml(model), model.warnings
