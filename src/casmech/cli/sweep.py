"""casmech sweep MODEL.yaml --out DIR: run the model at every point of a parameter study.

The study is the model's `study:` block, or the command line's (--grid, --samples with --normal
and --uniform, --seed, --keep; a grid or sampling given here replaces the block's design).
Runs go through Dask: a local cluster of --workers processes (default: the machine's cores;
on loopback, TLS with temporary credentials, no dashboard unless --dashboard), an existing
cluster at --scheduler ADDRESS, or this process with --workers 0; a batched study (--mode
batched, or auto from 200 runs where it can be: many runs per mapped call) runs in this
process on every core unless --workers or --scheduler is given. A run that fails is a row
with status failed and its reason; the study goes on. Each finished run is appended to
DIR/sweep.csv as it arrives, so a killed sweep keeps them and --resume runs only the others,
in the mode the earlier part ran in (DIR/metadata.json) unless --mode is given.
Ctrl-C (or SIGTERM) stops it: the finished runs are written and the exit code is 130. Writes
DIR/sweep.csv (in run order at the end), DIR/sweep.parquet (when pyarrow is installed),
DIR/metadata.json (status running until the end) and with --full DIR/runs.h5. docs/sweeps.md,
docs/security.md.
"""

from __future__ import annotations

import sys
from pathlib import Path

from casmech.cli.common import add_overrides, add_span, overrides
from casmech.errors import UsageError

AXES = {"grid": "NAME=VALUES", "normal": "NAME=MEAN,SIGMA", "uniform": "NAME=LOW,HIGH"}


def add_arguments(parser) -> None:
    parser.add_argument("model", type=Path, help="the model file")
    parser.add_argument("--out", type=Path,
                        help="output directory (default MODEL_sweep_results/)")
    parser.add_argument("--grid", action="append", default=[], metavar="NAME=VALUES",
                        help="a grid axis: NAME=START:STOP:COUNT (ends included) or "
                             "NAME=V1,V2,...; several axes make their product (repeatable)")
    parser.add_argument("--samples", type=int, metavar="N",
                        help="N random samples of the --normal and --uniform parameters")
    parser.add_argument("--normal", action="append", default=[], metavar="NAME=MEAN,SIGMA",
                        help="a normally distributed parameter (repeatable)")
    parser.add_argument("--uniform", action="append", default=[], metavar="NAME=LOW,HIGH",
                        help="a uniformly distributed parameter (repeatable)")
    parser.add_argument("--seed", type=int, help="seed of the samples (default 0)")
    parser.add_argument("--keep", action="append", default=[], metavar="OUTPUT",
                        help="a number kept per run: COLUMN@T, max(COLUMN), min(COLUMN), "
                             "final(COLUMN), integral(COLUMN) (trapezoid over the output rows), "
                             "crossing(COLUMN) (first sign change, interpolated), event(NAME) "
                             "(time of the model's event NAME) (repeatable)")
    parser.add_argument("--full", action="store_true",
                        help="also write every run's whole results into DIR/runs.h5, one group "
                             "per run")
    parser.add_argument("--workers", type=int, metavar="N",
                        help="processes of the local Dask cluster (default: the machine's "
                             "cores; 0: run in this process without Dask)")
    parser.add_argument("--scheduler", metavar="ADDRESS",
                        help="run on the existing Dask cluster at ADDRESS (tls://host:8786 "
                             "with Dask's TLS settings, or tcp://); its workers need casmech "
                             "and the model's files (docs/sweeps.md: how to secure it)")
    parser.add_argument("--dashboard", action="store_true",
                        help="serve the local cluster's Dask dashboard (on 127.0.0.1, a port "
                             "printed at the start); off by default")
    parser.add_argument("--resume", action="store_true",
                        help="continue the study whose results DIR/sweep.csv holds (a sweep "
                             "that was stopped or killed): run only the missing runs; the "
                             "model file, --set and settings must be the earlier part's")
    parser.add_argument("--mode", choices=("auto", "interpreted", "compiled", "batched"),
                        help="compiled: the model's parametric library, built once, bound to "
                             "each run's values; batched: that library mapped over many runs "
                             "per call (a tree's dynamics; docs/sweeps.md); interpreted: CasADi "
                             "functions built per run; auto (default): compiled from 200 runs "
                             "or when cached, batched where it can be from 200 runs; with "
                             "--resume the default is the earlier part's mode "
                             "(DIR/metadata.json)")
    add_span(parser)
    add_overrides(parser)


def pairs(option: str, texts: list[str]) -> dict[str, str]:
    """NAME=VALUE texts of an option as a mapping (a usage error for anything else)."""
    result = {}
    for text in texts:
        name, sep, value = text.partition("=")
        if not sep or not name.strip() or not value.strip():
            raise UsageError(f"--{option} expects {AXES[option]}, got '{text}'")
        result[name.strip()] = value.strip()
    return result


def study_form(args) -> dict:
    """The command line's study (the keys given)."""
    return {**{axis: pairs(axis, getattr(args, axis)) for axis in AXES},
            "samples": args.samples, "seed": args.seed, "keep": args.keep}


def run(args) -> int:
    from casmech.study import sweep as study

    if args.workers is not None and args.workers < 0:
        raise UsageError(f"--workers must be >= 0, got {args.workers}")
    if args.scheduler is not None:
        study.execute.scheduler_address(args.scheduler)  # its form, before anything is built
    if args.dashboard and (args.scheduler is not None or args.workers == 0):
        raise UsageError("--dashboard serves a local cluster's dashboard; it takes no "
                         "--scheduler and no --workers 0")
    if args.resume and args.full:
        raise UsageError("--resume cannot add to DIR/runs.h5 (--full writes it whole at the "
                         "end): resume without --full, or start the study again")
    settings = {"t_end": args.t_end, "output_step": args.output_step, "rtol": args.rtol,
                "atol": args.atol}
    given = overrides(args.set)
    out = args.out or args.model.with_name(args.model.stem + "_sweep_results")
    mode, earlier_mode = study.resume_mode(out, args.resume, args.mode)
    prepared = study.prepare(args.model, study_form(args), settings, given, full=args.full,
                             mode=mode)
    total = prepared.study.size()
    earlier = study.resumed(out, prepared) if args.resume else []
    changed = study.changed_mode(earlier_mode, prepared.job)
    if changed:
        print(f"sweep: {changed}", file=sys.stderr)
    batched = bool(prepared.job.batched)
    here = args.workers == 0 or (batched and args.workers is None)
    where = args.scheduler or (
        f"this process ({study.execute.default_workers()} threads)" if here and batched else
        "this process" if here else
        f"{args.workers or study.execute.default_workers()} local workers")
    mode = study.mode_name(prepared.job)
    again = f", {len(earlier)} finished earlier" if args.resume else ""
    print(f"sweep: {total} runs on {where}, {mode}{again}", file=sys.stderr)
    options = {"workers": args.workers, "scheduler": args.scheduler, "full": args.full,
               "mode": mode,
               "allow_dir": [str(Path(d).resolve()) for d in args.allow_dir]}
    table, finished, seconds, paths = study.run(out, prepared, options, args.workers,
                                                args.scheduler, earlier, args.dashboard,
                                                earlier_mode)
    if args.full:
        paths.append(out / "runs.h5")
    failed = int((table["status"] != "complete").sum())
    state = "" if finished else f" (interrupted after {len(table)} of {total})"
    print(f"sweep: {len(table) - failed} complete, {failed} failed, {seconds:.3g} s{state} "
          f"-> {', '.join(map(str, paths))}")
    return 0 if finished else 130
