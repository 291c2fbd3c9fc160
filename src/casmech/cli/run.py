"""casmech run MODEL.yaml: run the model's analysis and write DIR/results.csv (and/or .h5).

--format csv (default) writes results.csv per the results contract plus metadata.json beside it
(versions, model hash and text, overrides, settings, timings, mode); --format hdf5 writes
results.h5 holding the same table and metadata; --format csv,hdf5 writes both. An analysis
may write further files (modal: modes.csv, linear_model.npz; dynamics of a model with
`events:`: events.csv, one line printed per event). A progress bar
is drawn on stderr when it is a terminal and the run lasts more than a second.

--option KEY=VALUE (repeatable) sets an option of the analysis type (casmech.core.options;
docs/analyses.md#options): `--option max_step=1e-3`, `--option assembly.tolerance=1e-10`.

SIGINT (Ctrl-C) or SIGTERM stops the analysis promptly (casmech.runtime.interrupts): the rows
computed so far are written with `status: interrupted` and the signal in the metadata, and the
exit code is 128 + the signal's number (130, 143); a run whose rows were all computed when the
signal came is complete. When the analysis starts, the results files of an earlier run in DIR
are removed and metadata.json says `status: running`, so that a run killed outright (SIGKILL)
never leaves an older results file looking current.

--replay DIR/metadata.json runs a recorded run again (cli/replay.py): the same model file
(every file it read checked against its recorded sha256), overrides, settings and options.
"""

from __future__ import annotations

import argparse
import signal
import sys
import time
from pathlib import Path

import numpy as np

from casmech import api
from casmech.cli.common import add_options, add_overrides, add_span, options, overrides
from casmech.errors import AnalysisError, Interrupted
from casmech.io import events as events_output
from casmech.io.csv import write_csv
from casmech.io.hdf5 import h5py, write_hdf5
from casmech.io.metadata import analysis_record, run_metadata, write_json
from casmech.io.progress import progress_bar
from casmech.runtime import events, interrupts, reaction_frames, singular_poses
from casmech.runtime.results import column_names, events_table

# further files an analysis may write (Result.files), removed with an earlier run's results
ANALYSIS_FILES = ("modes.csv", "linear_model.npz", events_output.FILE)
# format -> (file name in DIR, writer(path, names, values, metadata), check run before the run)
FORMATS = {
    "csv": ("results.csv", lambda path, names, values, meta: write_csv(path, names, values),
            lambda: None),
    "hdf5": ("results.h5", write_hdf5, h5py),
}


def formats(text: str) -> list[str]:
    """--format: one format or a comma-separated list of them."""
    names = [name.strip() for name in text.split(",") if name.strip()]
    unknown = [name for name in names if name not in FORMATS]
    if unknown or not names:
        raise argparse.ArgumentTypeError(
            f"unknown format '{','.join(unknown) or text}'; expected one or more of "
            f"{', '.join(FORMATS)}, comma-separated (e.g. csv,hdf5)")
    return list(dict.fromkeys(names))


def add_arguments(parser) -> None:
    parser.add_argument("model", type=Path, nargs="?",
                        help="the model file (left out with --replay)")
    parser.add_argument("--replay", type=Path, metavar="METADATA.json",
                        help="run again what a run's metadata.json records (same files, checked "
                             "by sha256, overrides, settings, options); default --out: "
                             "DIR_replay/ beside its DIR")
    parser.add_argument("--out", type=Path, help="output directory (default MODEL_results/)")
    add_span(parser)
    parser.add_argument("--formulation", choices=api.DYNAMICS_OPTIONS["formulation"],
                        help="equations of motion for dynamics (default: the model's, else auto: "
                             "joint coordinates, rp after a loop run that failed or passed a "
                             "singular pose, or with a floating body in a loop)")
    parser.add_argument("--stabilization", choices=api.DYNAMICS_OPTIONS["stabilization"],
                        help="how dynamics keeps the constraints: the stabilized index-2 DAE "
                             "(ggl) or projections of the index-1 DAE (default: the model's, "
                             "else ggl)")
    parser.add_argument("--method", choices=api.DYNAMICS_OPTIONS["method"],
                        help="CVODES's method for joint coordinates on a tree (default: the "
                             "model's, else auto: bdf when the ODE is stiff at t0)")
    parser.add_argument("--analysis", choices=sorted(api.ANALYSES), help="analysis type")
    add_options(parser)
    parser.add_argument("--reactions-frame", choices=list(reaction_frames.FRAMES),
                        help="the frame of every joint's reaction columns, replacing the "
                             "joints' `reactions: {frame: ...}` (default: theirs, else global)")
    parser.add_argument("--format", type=formats, metavar="csv|hdf5",
                        help="results file format(s), comma-separated (default csv)")
    parser.add_argument("--mode", choices=api.COMPILE_MODES,
                        help="compiled C (built once, cached) or interpreted CasADi functions "
                             "(default auto: compiled when cached or from 200 bodies, but "
                             "trees in joint coordinates; else interpreted)")
    add_overrides(parser)


def run(args) -> int:
    from casmech.cli import replay

    args = replay.replayed(args) if args.replay else replay.direct(args)
    for name in args.format:
        FORMATS[name][2]()  # a missing h5py is a usage error before the run
    with interrupts.trap():
        return _run(args)


def _run(args) -> int:
    given = overrides(args.set)
    clock = time.perf_counter()
    model = api.load(args.model, given)
    timings = {"load": time.perf_counter() - clock}
    interrupts.check()
    out = args.out or args.model.with_name(args.model.stem + "_results")
    clock = time.perf_counter()
    functions = api.compile(model, args.mode)
    timings["compile"] = time.perf_counter() - clock
    interrupts.check()  # a signal during a C compiler's run ends it as a failure
    asked = options(args.option)
    checked = api.analysis_settings(  # a usage error before an earlier run's files go
        functions, args.analysis, args.t_end, args.output_step, args.rtol, args.atol,
        args.formulation, args.stabilization, args.method, asked)
    settings = analysis_record(checked)
    recorded = {"mode": args.mode, "format": list(args.format),
                "allow_dir": [str(Path(d).resolve()) for d in args.allow_dir]}
    if args.reactions_frame:  # recorded when given, for --replay
        recorded["reactions_frame"] = args.reactions_frame
    if args.option:
        recorded["option"] = list(args.option)
    run = (model, given, settings, timings, recorded)
    _start(args, out, run)
    clock = time.perf_counter()
    try:
        with progress_bar(settings["t_end"]) as callback:
            result = api.analyze(functions, args.analysis, args.t_end, args.output_step,
                                 rtol=args.rtol, atol=args.atol, formulation=args.formulation,
                                 progress=callback or _rows_as_they_come,
                                 stabilization=args.stabilization,
                                 method=args.method, options=asked)
    except AnalysisError as error:
        timings["analysis"] = time.perf_counter() - clock
        with interrupts.saving():
            _keep(args, out, functions, error, run)
        raise
    timings["analysis"] = time.perf_counter() - clock
    with interrupts.saving():
        paths = _save(args, out, functions, result, run)
    print(f"{result.metadata['analysis']}: {len(result)} rows, {timings['analysis']:.3g} s "
          f"-> {', '.join(map(str, paths))}")
    for record in result.events:
        print(f"event {record.name} ({record.direction}) at t = {record.t:.10g} s"
              f"{': run stopped' if record.action == 'stop' else ''}")
    if "formulation_fallback" in result.metadata:
        print(f"note: formulation auto ran the model again in rp: "
              f"{result.metadata['formulation_fallback']}", file=sys.stderr)
    for pose in result.metadata.get("singular_poses") or ():
        print(f"warning: {singular_poses.describe(pose)}", file=sys.stderr)
    if interrupts.pending() is not None:  # it came after the last row: nothing was cut short
        name = signal.Signals(interrupts.pending()).name
        print(f"casmech: {name} came after the last row; the run is complete", file=sys.stderr)
    return 0


def _rows_as_they_come(t: float) -> None:
    """The progress callback when no bar is drawn: with a callback, dynamics integrates the
    grid in chunks, so an interrupt keeps the rows before it (runtime.dynamics)."""


def _start(args, out: Path, run) -> None:
    """Before the analysis: the results files of an earlier run go, metadata.json says
    running."""
    with interrupts.saving():
        for name in (*(f[0] for f in FORMATS.values()), *ANALYSIS_FILES):
            (out / name).unlink(missing_ok=True)
        (out / "metadata.json").unlink(missing_ok=True)
        if "csv" in args.format:
            model, given, settings, timings, options = run
            write_json(out / "metadata.json", run_metadata(model, given, settings, timings, {},
                                                           0, status="running",
                                                           options=options))


def _keep(args, out: Path, functions, error: AnalysisError, run) -> None:
    """The rows computed before a failure or an interrupt, and the metadata saying which (an
    interrupt before the first row: the header only; a failure: the metadata only)."""
    interrupted = isinstance(error, Interrupted)
    partial = error.partial if error.partial is not None and len(error.partial) else None
    if partial is None and not interrupted:
        if "csv" in args.format:
            model, given, settings, timings, options = run
            write_json(out / "metadata.json", run_metadata(model, given, settings, timings, {},
                                                           0, str(error), "failed",
                                                           options=options))
        return
    paths = _save(args, out, functions, partial, run, str(error),
                  "interrupted" if interrupted else "failed",
                  error.signal_name if interrupted else None)
    rows, when = (len(partial), f" (t = {partial.times[-1]:.6g})") if partial else (0, "")
    print(f"kept {rows} rows computed before the {'interrupt' if interrupted else 'failure'}"
          f"{when} in {', '.join(map(str, paths))}", file=sys.stderr)


def _save(args, out: Path, functions, result, run, error: str | None = None,
          status: str | None = None, signal: str | None = None) -> list[Path]:
    """The table in every requested format, plus metadata.json beside a CSV (result None:
    no rows, the header only)."""
    if result is None:
        names = column_names(functions)
        values, meta, rows = np.zeros((0, len(names))), {}, 0
    else:
        names, values = api.results_table(functions, result, args.reactions_frame)
        meta, rows = result.metadata, len(values)
    model, given, settings, timings, options = run
    if status is None and result is not None and result.status == events.STOPPED:
        status = events.STOPPED
    metadata = run_metadata(model, given, settings, timings, meta, rows, error, status, signal,
                            options)
    ir = functions.ir
    metadata["reaction_frames"] = reaction_frames.describe(
        ir, reaction_frames.chosen(ir, args.reactions_frame), functions.body_names)
    paths = [FORMATS[name][1](out / FORMATS[name][0], names, values, metadata)
             for name in args.format]
    files = {} if result is None else result.files
    paths += [write(out / name) for name, write in files.items()]
    if result is not None and result.event_states is not None:  # the run watched events
        event_names, event_rows = events_table(functions, result, args.reactions_frame)
        paths.append(events_output.write_events(out / events_output.FILE, event_names,
                                                event_rows))
        # in metadata.json only: results.h5's metadata holds no list of records
        metadata["events"] = events_output.metadata_rows(result.events, event_names,
                                                         event_rows)
    if "csv" in args.format:
        write_json(out / "metadata.json", metadata)
    return paths
