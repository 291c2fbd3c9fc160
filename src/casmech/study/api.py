"""casmech.sweep: a parameter study from Python, returning its table as a pandas DataFrame.

    table = casmech.sweep("models/four_bar.yaml", grid={"a": "0.4:0.6:5"},
                          keep=["max(crank.wx)", "final(rocker.z)"], workers=2)
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from pathlib import Path

from casmech.study import sweep as study


def sweep(model, grid: Mapping | None = None, samples: int = 0,
          normal: Mapping | None = None, uniform: Mapping | None = None, seed: int | None = None,
          keep: Sequence[str] = (), workers: int | None = None, scheduler: str | None = None,
          out: str | Path | None = None, full: bool = False,
          overrides: Mapping[str, str] | None = None, mode: str | None = None,
          resume: bool = False, dashboard: bool = False, **settings):
    """Run `model` (a path or a casmech.load result) at every point of the study and return
    one row per run (docs/sweeps.md): `run`, the parameter values, `status`, `wall_s`, the
    kept outputs, `reason`. The arguments take the YAML `study:` block's values (grid values as
    "0.8:1.2:5", "100,200" or a list; normal as (mean, sigma); uniform as (low, high)) and
    replace the block's where given. workers: processes of a local Dask cluster (default: the
    machine's cores; 0: run in this process, without Dask); scheduler: the address of an
    existing Dask cluster. mode: "interpreted", "compiled" (the model's parametric library,
    built once), "batched" (that library mapped over many runs per call: a tree's dynamics,
    docs/sweeps.md; without workers or scheduler it runs in this process on every core) or
    "auto" (compiled for a study of 200 runs or more, or when the library is cached; batched
    from 200 runs where it can be); None: auto, or with `resume` the earlier part's mode
    (out/metadata.json). settings: casmech.analyze's (t_end, output_step, rtol, ...).
    With `out`, writes sweep.csv (each run appended as it finishes, in run order at the end;
    sweep.parquet with pyarrow), metadata.json and with `full` runs.h5 there, as
    `casmech sweep` does; `resume` runs only the runs out/sweep.csv does not hold yet, in
    the earlier part's mode unless `mode` is given.
    `dashboard`: serve the local cluster's Dask dashboard (on 127.0.0.1). The DataFrame's
    attrs["finished"] says whether every run finished (False after Ctrl-C)."""
    given = {"grid": grid, "normal": normal, "uniform": uniform, "samples": samples or None,
             "seed": seed, "keep": list(keep) or None}
    resuming = bool(resume and out is not None)
    mode, earlier_mode = study.resume_mode(Path(out or "."), resuming, mode)
    prepared = study.prepare(model, given, settings, overrides, full=bool(out and full),
                             mode=mode)
    changed = study.changed_mode(earlier_mode, prepared.job)
    if changed:
        warnings.warn(changed, stacklevel=2)
    options = {"workers": workers, "scheduler": scheduler, "full": bool(full),
               "mode": study.mode_name(prepared.job)}
    earlier = study.resumed(Path(out), prepared) if resuming else []
    table, finished, _, _ = study.run(None if out is None else Path(out), prepared, options,
                                      workers, scheduler, earlier, dashboard, earlier_mode)
    table.attrs["finished"] = finished
    return table
