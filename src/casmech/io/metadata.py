"""What a run was: versions (casmech, CasADi, NumPy, Python) and platform, model (name, sha256,
text), the sha256 of every file the model read, overrides and the parameter values they led to,
settings, the command-line options `casmech run --replay` repeats, timings, mode.

One dict, written as DIR/metadata.json beside results.csv (the CSV stays plain per the results
contract) and into results.h5 (casmech.io.hdf5).
"""

from __future__ import annotations

import hashlib
import json
import os
import platform
import shutil
import sys
from collections.abc import Mapping
from dataclasses import replace
from datetime import datetime, timezone
from pathlib import Path

import casadi
import numpy as np

from casmech.core.option_values import values
from casmech.core.options import DynamicsOptions
from casmech.core.version import VERSION
from casmech.schema.resolved import Analysis, ResolvedModel

SETTINGS = ("type", "t_end", "output_step", "rtol", "atol")
DYNAMICS = ("formulation", "stabilization", "method")  # recorded for every type


def resolved_settings(analysis: Analysis, **given) -> dict:
    """The analysis settings a run uses: the model's `analysis:` block with the caller's
    overrides (None: not given), without the checks of casmech.analyze (analysis_record
    describes a checked one)."""
    settings = replace(analysis, **{k: v for k, v in given.items()
                                    if k in SETTINGS and v is not None})
    if settings.type != analysis.type:  # the options of that type the file wrote
        from casmech.runtime.analyses import options_of

        settings = replace(settings, options=options_of(settings.type, settings.written))
    record = analysis_record(settings)
    return {**record, **{k: given[k] for k in DYNAMICS if given.get(k)}}


def analysis_record(analysis: Analysis) -> dict:
    """metadata.json's `analysis`: type, t_end, output_step, rtol, atol; formulation,
    stabilization and method (of a type without them: the file's, else their defaults);
    modal's at and inputs; and `solver`, every solver option's value (core.options)."""
    record = {name: getattr(analysis, name) for name in SETTINGS}
    written, defaults = dict(analysis.written), DynamicsOptions()
    for key in DYNAMICS:
        record[key] = getattr(analysis.options, key, written.get(key, getattr(defaults, key)))
    options = values(analysis.options)
    record.update({key: options[key] for key in ("at", "inputs") if key in options})
    record["solver"] = options["solver"]
    return record


def sha256(text: str) -> str:
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


STATUSES = ("running", "complete", "failed", "interrupted", "stopped by event")


def source_files(model: ResolvedModel) -> dict[str, dict[str, str]]:
    """The files the model read (model.sources): the path relative to the model's folder (or
    absolute, outside it) -> its absolute path and sha256."""
    folder = Path(model.file).resolve().parent
    files = {}
    for path, digest in model.sources.items():
        relative = os.path.relpath(path, folder)
        name = path if relative.startswith("..") else Path(relative).as_posix()
        files[name] = {"path": path, "sha256": digest}
    return files


def run_metadata(model: ResolvedModel, overrides: Mapping[str, str], settings: dict,
                 timings: Mapping[str, float], result_metadata: Mapping, rows: int,
                 error: str | None = None, status: str | None = None,
                 signal: str | None = None, options: Mapping | None = None) -> dict:
    """Everything needed to tell how a results table was made and to make it again
    (JSON-serialisable). `status`: running (written when the analysis starts: a results file
    from an earlier run is gone), complete, failed, interrupted (`signal` names the signal) or
    stopped by event (a dynamics run a `stop` event ended, runtime.events);
    default: failed when there is an error, else complete. `options`: the command-line
    options besides overrides and settings (mode asked for, formats, allowed folders)."""
    status = status or ("failed" if error else "complete")
    assert status in STATUSES, status
    extra = {"signal": signal} if signal else {}
    return {
        "casmech_version": VERSION,
        "casadi_version": casadi.__version__,
        "numpy_version": np.__version__,
        "python_version": platform.python_version(),
        "platform": platform_text(),
        "python_executable": sys.executable,
        "created_utc": datetime.now(timezone.utc).isoformat(timespec="seconds"),
        "model": {"file": Path(model.file).name, "path": str(model.file),
                  "absolute_path": str(Path(model.file).resolve()), "name": model.name,
                  "sha256": sha256(model.text), "text": model.text},
        "files": source_files(model),
        "overrides": dict(overrides),
        "options": dict(options or {}),
        "parameters": {name: float(value) for name, value in model.parameters.items()},
        "analysis": dict(settings),
        "timings_s": dict(timings),
        "mode": result_metadata.get("mode", "interpreted"),
        "rows": int(rows),
        "status": status,
        **extra,
        "error": error or "",
        "result": {k: _plain(v) for k, v in result_metadata.items()},
    }


def _printable(text: str) -> bool:
    return 0 < len(text) <= 500 and text.isprintable()


def platform_text() -> str:
    """platform.platform(), remembered across processes (backends.stamps, in the cache folder)
    under the kernel's os.uname() and the stamps of what it reads: the interpreter (its C
    library's version), the platform module and the `uname` program it runs for the
    processor's name (a process of its own on Linux)."""
    if not hasattr(os, "uname"):
        return platform.platform()
    from casmech.backends import stamps
    from casmech.backends.folder import cache_dir

    programs = [path for path in (shutil.which("uname"),) if path is not None]
    files = [sys.executable, platform.__file__, *programs]
    return stamps.remembered(json.dumps(["platform.platform", list(os.uname()), programs]),
                             files, platform.platform, _printable, cache_dir())


def _plain(value):
    """numpy scalars and other odd values as JSON-friendly Python values."""
    if isinstance(value, (bool, int, float, str)) or value is None:
        return value
    if isinstance(value, (list, tuple, np.ndarray)):
        return np.asarray(value).tolist()
    if isinstance(value, np.generic):
        return value.item()
    return str(value)


def write_json(path: str | Path, metadata: Mapping) -> Path:
    """Write atomically (core.atomic)."""
    from casmech.core.atomic import atomic

    path = Path(path)
    with atomic(path) as handle:
        handle.write(json.dumps(metadata, indent=2) + "\n")
    return path


def read_json(path: str | Path) -> dict:
    return json.loads(Path(path).read_text())


def rewrite_json(path: str | Path, metadata: Mapping) -> Path:
    """Write in place, over the file's own bytes: where there is no room for a new file (a
    full disk), the old one's blocks are reused."""
    path = Path(path)
    with open(path, "r+") as handle:
        handle.write(json.dumps(metadata, indent=2) + "\n")
        handle.truncate()
    return path
