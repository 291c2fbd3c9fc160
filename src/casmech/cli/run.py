"""casmech run MODEL.yaml: run the model's analysis and write DIR/results.csv (and/or .h5).

--format csv (default) writes results.csv per the results contract plus metadata.json beside it
(versions, model hash and text, overrides, settings, timings, mode); --format hdf5 writes
results.h5 holding the same table and metadata; --format csv,hdf5 writes both. An analysis
may write further files (modal: modes.csv, linear_model.npz; dynamics of a model with
`events:`: events.csv, one line printed per event). A progress bar
is drawn on stderr when it is a terminal and the run lasts more than a second.

The results rows are written as the analysis computes them (output.streaming), so that a run
that ends early keeps them. When the analysis starts, the results files of an earlier run in
DIR are removed and metadata.json says `status: running`, so that a run killed outright
(SIGKILL) never leaves an older results file looking current; then:

- SIGINT (Ctrl-C) or SIGTERM stops the analysis promptly (casmech.runtime.interrupts): the rows
  computed so far are kept with `status: interrupted` and the signal in the metadata, and the
  exit code is 128 + the signal's number (130, 143);
- an analysis failure (exit 3) keeps the rows before it, `status: failed`; a results row that
  is not finite is such a failure (runtime.nonfinite), the rows before it kept;
- a results file that cannot be written (a full disk, a file-size limit, a read-only folder)
  ends the run with exit 4 naming the path and the cause, the rows written before kept and
  metadata.json (where it can still be written) saying `status: failed`.

--option KEY=VALUE (repeatable) sets an option of the analysis type (casmech.core.options;
docs/analyses.md#options): `--option max_step=1e-3`, `--option assembly.tolerance=1e-10`.

--replay DIR/metadata.json runs a recorded run again (cli/replay.py): the same model file
(every file it read checked against its recorded sha256), overrides, settings and options.
"""

from __future__ import annotations

import argparse
import contextlib
import signal
import sys
import time
from pathlib import Path

from casmech import api
from casmech.cli import collector
from casmech.cli.common import add_options, add_overrides, add_span, options, overrides
from casmech.errors import AnalysisError, CasmechError, Interrupted
from casmech.io import events as events_output
from casmech.io.csv import CsvRows
from casmech.io.metadata import analysis_record, rewrite_json, run_metadata, write_json
from casmech.io.progress import progress_bar
from casmech.io.streaming import ResultsWriter, WriteError, writing
from casmech.runtime import events, interrupts, reaction_frames
from casmech.runtime.results import column_names, events_table

# this command starts its process's collector itself, when the analysis starts: loading and
# building make no cycles worth collecting (cli.collector)
RELEASES_COLLECTOR = True
# the process ends when this command returns, without the interpreter's teardown of the modules
# it loaded (cli._leave: atexit handlers run, streams flushed, files closed by the command)
ENDS_AT_ONCE = True
# further files an analysis may write (Result.files), removed with an earlier run's results
ANALYSIS_FILES = ("modes.csv", "linear_model.npz", events_output.FILE)


def _hdf5_rows(path: Path, names: list[str]):
    from casmech.io.hdf5 import Hdf5Rows  # (io.hdf5 where the format is asked for)

    return Hdf5Rows(path, names)


def _h5py():
    from casmech.io.hdf5 import h5py

    return h5py()


# format -> (file name in DIR, the writer of its rows as they come, check run before the run)
FORMATS = {
    "csv": ("results.csv", CsvRows, lambda: None),
    "hdf5": ("results.h5", _hdf5_rows, _h5py),
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
                        help="the method for joint coordinates on a tree: CVODES's adams or "
                             "bdf, or dop853 (default: the model's, else auto: bdf when the "
                             "ODE is stiff at t0, adams where contacts or stops cap the step, "
                             "else dop853)")
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
                             "trees in joint coordinates; else interpreted while a niced "
                             "process builds the library for the next run, unless "
                             "$CASMECH_BACKGROUND_BUILD=0)")
    talk = parser.add_mutually_exclusive_group()
    talk.add_argument("--quiet", "-q", action="store_true",
                      help="print nothing but errors: no progress bar, summary, events, notes "
                           "or warnings (they stay in metadata.json)")
    talk.add_argument("--verbose", "-v", action="store_true",
                      help="print more: the time of each stage, the mode and formulation that "
                           "ran, every singular pose on its own line and the solver's messages")
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
    model = _load(args, given)
    from casmech.cli import replay

    replay.check_read(model, args)  # a replay reads only what its record lists
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
    writer = _start(args, out, functions, run)
    collector.release()
    clock = time.perf_counter()
    try:
        try:
            with progress_bar(settings["t_end"], quiet=args.quiet) as callback:
                result = api.analyze(functions, args.analysis, args.t_end,
                                     args.output_step, rtol=args.rtol, atol=args.atol,
                                     formulation=args.formulation,
                                     progress=writer.watching(_rows(callback)),
                                     stabilization=args.stabilization, method=args.method,
                                     options=asked)
            timings["analysis"] = time.perf_counter() - clock
            with interrupts.saving():
                writer.finish(result)  # the last rows (NonFinite: the rows before one)
        except AnalysisError as error:
            timings.setdefault("analysis", time.perf_counter() - clock)
            with interrupts.saving():
                _keep(args, out, functions, error, run, writer)
            raise
        with interrupts.saving():
            paths = _save(args, out, functions, result, run, writer)
    except WriteError as error:
        with interrupts.saving():
            _write_failed(args, out, functions, error, run, writer)
        raise
    except CasmechError as error:  # a model or usage error the analysis found (E501, ...)
        if isinstance(error, AnalysisError):  # (kept above)
            raise
        with interrupts.saving():
            writer.discard()
            if "csv" in args.format:
                model, given, settings, timings, recorded = run
                with contextlib.suppress(OSError):
                    write_json(out / "metadata.json", run_metadata(
                        model, given, settings, timings, {}, 0, str(error), "failed",
                        options=recorded))
        raise
    if not args.quiet:
        _report(args, result, timings, paths)
    return 0


def _load(args, given):
    """The model: kept in the cache from an earlier run of the same file (backends.
    checked_model) unless the run is interpreted (it uses no cache) or a replay."""
    if args.mode == "interpreted" or args.replay:
        return api.load(args.model, given)
    from casmech.backends import checked_model

    return checked_model.load(args.model, given)


def _report(args, result, timings, paths) -> None:
    """The summary line, the events, notes and warnings of a run (and more with --verbose)."""
    meta = result.metadata
    print(f"{meta['analysis']}: {len(result)} rows, {timings['analysis']:.3g} s "
          f"-> {', '.join(map(str, paths))}")
    for record in result.events:
        print(f"event {record.name} ({record.direction}) at t = {record.t:.10g} s"
              f"{': run stopped' if record.action == 'stop' else ''}")
    if args.verbose:
        stages = ", ".join(f"{stage} {seconds:.3g} s" for stage, seconds in timings.items())
        ran = ", ".join(f"{key} {meta[key]}" for key in ("mode", "formulation") if key in meta)
        print(f"timings: {stages}; {ran}", file=sys.stderr)
        for message in meta.get("solver_messages") or ():
            print(f"solver: {message}", file=sys.stderr)
    if "formulation_fallback" in meta:
        print(f"note: formulation auto ran the model again in rp: "
              f"{meta['formulation_fallback']}", file=sys.stderr)
    for line in singular_pose_warnings(meta.get("singular_poses") or (), args.verbose):
        print(f"warning: {line}", file=sys.stderr)
    if interrupts.pending() is not None:  # it came after the last row: nothing was cut short
        name = signal.Signals(interrupts.pending()).name
        print(f"casmech: {name} came after the last row; the run is complete", file=sys.stderr)


def singular_pose_warnings(poses, every: bool = False) -> list[str]:
    """One line per set of joints the run passed singular poses of, with how many times and
    when (`every`: one line per pose, as singular_poses.describe writes it)."""
    if not poses:
        return []
    from casmech.runtime import singular_poses

    groups: dict[tuple, list[dict]] = {}
    for pose in poses:
        key = tuple(sorted(zip(pose["joints"], pose["sources"], strict=True)))
        groups.setdefault(key, []).append(pose)
    if every:
        return [singular_poses.describe(pose) for pose in poses]
    lines = []
    for found in groups.values():
        if len(found) == 1:
            lines.append(singular_poses.describe(found[0]))
            continue
        closest = min(found, key=lambda pose: pose["smallest_singular_value"])
        joints = singular_poses.describe(closest).split("): ", 1)[1]
        times = ", ".join(f"{pose['t']:.6g}" for pose in found)
        lines.append(f"near a singular pose {len(found)} times, at t = {times} s (smallest "
                     f"singular value of the unit constraint rows down to "
                     f"{closest['smallest_singular_value']:.2e}; --verbose lists each): "
                     f"{joints}")
    return lines


def _rows(callback):
    """The analysis' row callback: the progress bar's, or one that does nothing (with a
    callback, dynamics integrates the grid in chunks, so an interrupt keeps the rows before
    it: runtime.driver)."""
    def on_row(t: float) -> None:
        if callback is not None:
            callback(t)

    return on_row


def _start(args, out: Path, functions, run) -> ResultsWriter:
    """Before the analysis: the results files of an earlier run go, metadata.json says
    running, and the results files are opened with their header (output.streaming); an
    OSError of any of it is a WriteError (exit 4)."""
    with interrupts.saving():
        for name in (*(f[0] for f in FORMATS.values()), *ANALYSIS_FILES, "metadata.json"):
            writing(out / name, 0, (out / name).unlink, True)
        writing(out, 0, out.mkdir, 0o777, True, True)
        if "csv" in args.format:
            model, given, settings, timings, options = run
            writing(out / "metadata.json", 0, write_json, out / "metadata.json",
                    run_metadata(model, given, settings, timings, {}, 0, status="running",
                                 options=options))
        names = column_names(functions)
        files = []
        try:
            for name in args.format:
                path = out / FORMATS[name][0]
                files.append(writing(path, 0, FORMATS[name][1], path, names))
        except WriteError:
            for file in files:
                file.close()
            raise
        return ResultsWriter(functions, files, args.reactions_frame)


def _keep(args, out: Path, functions, error: AnalysisError, run, writer) -> None:
    """The rows computed before a failure or an interrupt, and the metadata saying which (an
    interrupt before the first row: the header only; a failure: the metadata only). A
    NonFinite's rows stop before the first row that is not finite."""
    interrupted = isinstance(error, Interrupted)
    partial = error.partial if error.partial is not None and len(error.partial) else None
    model, given, settings, timings, options = run
    if partial is None and not interrupted:
        writer.discard()
        if "csv" in args.format:
            writing(out / "metadata.json", 0, write_json, out / "metadata.json",
                    run_metadata(model, given, settings, timings, {}, 0, str(error), "failed",
                                 options=options))
        return
    writer.finish(partial, strict=False)
    paths = _save(args, out, functions, partial, run, writer, str(error),
                  "interrupted" if interrupted else "failed",
                  error.signal_name if interrupted else None)
    kept = writer.written
    when = f" (t = {partial.times[kept - 1]:.6g})" if partial is not None and kept else ""
    print(f"kept {kept} rows computed before the {'interrupt' if interrupted else 'failure'}"
          f"{when} in {', '.join(map(str, paths))}", file=sys.stderr)


def _write_failed(args, out: Path, functions, error: WriteError, run, writer) -> None:
    """After a WriteError: the files closed with the rows written, metadata.json (when it can
    be written) saying failed and why."""
    model, given, settings, timings, options = run
    metadata = run_metadata(model, given, settings, timings, {}, writer.written if writer
                            else 0, str(error), "failed", options=options)
    if writer is not None:
        with contextlib.suppress(WriteError):
            writer.close(metadata)
    if "csv" in args.format:
        try:
            write_json(out / "metadata.json", metadata)
        except OSError:
            with contextlib.suppress(OSError):  # no room for a new file: the old one's place
                rewrite_json(out / "metadata.json", metadata)


def _save(args, out: Path, functions, result, run, writer, error: str | None = None,
          status: str | None = None, signal: str | None = None) -> list[Path]:
    """The rows written (output.streaming), then the metadata: metadata.json beside a CSV,
    the /metadata group of results.h5; and the analysis' further files (modal, events)."""
    model, given, settings, timings, options = run
    meta = {} if result is None else result.metadata
    if status is None and result is not None and result.status == events.STOPPED:
        status = events.STOPPED
    metadata = run_metadata(model, given, settings, timings, meta, writer.written, error,
                            status, signal, options)
    ir = functions.ir
    metadata["reaction_frames"] = reaction_frames.describe(
        ir, reaction_frames.chosen(ir, args.reactions_frame), functions.body_names)
    if ir.outputs:  # the `outputs:` block: each value and its unit (casmech plot reads it)
        metadata["outputs"] = {o.name: {"value": o.value.text, "unit": o.unit}
                               for o in ir.outputs}
    paths = [out / FORMATS[name][0] for name in args.format]
    files = {} if result is None else result.files
    paths += [writing(out / name, writer.written, write, out / name)
              for name, write in files.items()]
    if result is not None and result.event_states is not None:  # the run watched events
        event_names, event_rows = events_table(functions, result, args.reactions_frame)
        path = out / events_output.FILE
        paths.append(writing(path, writer.written, events_output.write_events, path,
                             event_names, event_rows))
        # in metadata.json only: results.h5's metadata holds no list of records
        events_metadata = events_output.metadata_rows(result.events, event_names, event_rows)
    writer.close(metadata)
    if result is not None and result.event_states is not None:
        metadata["events"] = events_metadata
    if "csv" in args.format:
        writing(out / "metadata.json", writer.written, write_json, out / "metadata.json",
                metadata)
    return paths
