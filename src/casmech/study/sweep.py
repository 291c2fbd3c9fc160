"""A parameter study end to end: prepare (load, check, build once), run every point, tabulate.

    prepared = prepare(path_or_model, form, settings)   # the study checked against the model
    table, finished, seconds, paths = run(out, prepared, options, workers=2)
    # run: start (metadata.json: status running), collect (each row appended to
    # out/sweep.csv), write (sweep.csv in run order, metadata.json; failed on an error)

With `journal_path`, each finished run is appended to that file as it arrives (study.journal),
so a sweep killed by any signal keeps its finished runs; `resumed(out, prepared)` reads them
back and `collect(..., resumed=rows)` runs only the others.

The table has a row per run that finished, in run order: `run` (its index in the study),
the parameter values, `status` (complete | failed), `wall_s` (the run's own time in its
worker), the kept outputs, and `reason` (why a run failed; empty otherwise).
"""

from __future__ import annotations

import importlib.util
import time
from collections.abc import Mapping
from pathlib import Path

from casmech.core.records import record
from casmech.study import block, execute, journal
from casmech.study.design import Study
from casmech.study.progress import runs_bar
from casmech.study.runner import SETTINGS, Job, Outcome

FIXED = ("run",)  # columns before the parameters; after them:
STATUS = ("status", "wall_s")  # then the kept outputs, then "reason"


@record(frozen=False)
class Prepared:
    model: object  # schema.resolved.ResolvedModel at the file's (and --set) values
    study: Study
    job: Job
    settings: dict  # the analysis settings of every run (output.metadata.resolved_settings)
    overrides: dict[str, str]


def _merged(written: Mapping, given: Mapping) -> tuple[dict, set[str]]:
    """The study of the YAML block with the given (command line, API) keys over it: a given
    grid or sampling replaces the block's whole design. Returns it and the given keys."""
    given = {k: v for k, v in given.items() if v not in (None, {}, (), [])}
    design = {"grid", "normal", "uniform", "samples"}
    form = {k: v for k, v in written.items() if not (design & set(given) and k in design)}
    return {**form, **given}, set(given)


COMPILE_RUNS = 200  # mode auto compiles (and batches) a study of at least this many runs
MODES = ("auto", "interpreted", "compiled", "batched")


def study_mode(model, runs: int, mode: str) -> str:
    """casmech.compile's mode for every run. auto: "compiled" when the model's parametric
    library applies (codegen.parametric: parameters, at most 32 bodies; one library for every
    value) and is cached or the study has COMPILE_RUNS runs or more (where the runs repay the
    library's build: docs/decisions/parameter-studies.md), else "interpreted"."""
    from casmech.backends import codegen, parametric
    from casmech.errors import UsageError

    if mode not in MODES:
        raise UsageError(f"mode '{mode}' is not one of {', '.join(MODES)}")
    applies = parametric.applies(model)
    if mode in ("compiled", "batched") and not applies:
        raise UsageError(f"--mode {mode}: this model has no parametric library (it needs "
                         f"parameters and at most {parametric.MAX_BODIES} bodies), so every "
                         "run would build its own (hint: --mode interpreted)")
    if mode != "auto":
        return "compiled" if mode == "batched" else mode
    if not (codegen.available() and applies):
        return "interpreted"
    return "compiled" if runs >= COMPILE_RUNS or codegen.is_cached(model) else "interpreted"


def prepare(source, given: Mapping | None = None, settings: Mapping | None = None,
            overrides: Mapping[str, str] | None = None, full: bool = False,
            mode: str = "auto") -> Prepared:
    """The study of `source` (a model path or a ResolvedModel) checked: located errors for its
    `study:` block, usage errors for `given` (grid, normal, uniform, samples, seed, keep);
    the model built once (in compiled mode: its library, which every run then loads), its
    analysis settings and kept outputs checked."""
    from casmech import backends
    from casmech.io.metadata import resolved_settings
    from casmech.runtime.analyses import analysis_settings
    from casmech.runtime.results import column_names
    from casmech.schema import load_model, load_model_text
    from casmech.schema.loader import load_document

    overrides = dict(overrides or {})
    if not hasattr(source, "text"):
        model = load_model(source, overrides=overrides)
    elif overrides:  # a loaded model, at these values as every run will be
        model = load_model_text(source.text, file=str(source.file), overrides=overrides)
    else:
        model = source
    document = load_document(model.text, str(model.file))
    written = document.data.get("study") if isinstance(document.data, dict) else None
    form, from_caller = _merged(dict(written or {}), dict(given or {}))
    others = {**{b.name: "body" for b in model.bodies}, **{j.name: "joint" for j in model.joints},
              **{f.name: "force" for f in model.forces}}
    settings = {k: v for k, v in (settings or {}).items() if k in SETTINGS and v is not None}
    try:
        study = block.build(form, model.parameters, others)
        runs = len(study.points())
        wanted, mode = mode, study_mode(model, runs, mode)
        if wanted == "batched":  # why it cannot be, before a library is built for it
            _batched(model, analysis_settings(backends.compile(model, "interpreted"),
                                              **settings), study, full, wanted, True)
        functions = backends.compile(model, mode)
        checked = analysis_settings(functions, **settings)
        block.check_keep(study, column_names(functions), float(checked.t_end),
                         [event.name for event in checked.events])
    except block.StudyProblems as problems:
        raise _reported(problems, from_caller if written else None, document) from None
    batched = study.parameters if wanted == "batched" else _batched(
        model, checked, study, full, wanted, mode == "compiled" and runs >= COMPILE_RUNS)
    resolved = resolved_settings(functions.ir.analysis, type=checked.type, **{
        k: v for k, v in settings.items() if k != "analysis"})
    file = Path(model.file)  # absolute: workers may run elsewhere ("<string>" stays)
    job = Job(str(file.resolve() if file.exists() else file), model.text,
              tuple(sorted(settings.items())), study.keep, full, tuple(sorted(overrides.items())),
              mode, batched)
    return Prepared(model, study, job, resolved, overrides)


def _batched(model, checked, study: Study, full: bool, wanted: str, large: bool
             ) -> tuple[str, ...]:
    """The parameters of a study whose runs go in batches (study.batch), else (): asked for
    (a usage error saying why it cannot be), or auto for a large compiled study."""
    from casmech.errors import UsageError
    from casmech.study import batch

    if wanted != "batched" and not (wanted == "auto" and large):
        return ()
    why = batch.obstacle(model, checked, study, full)
    if why is None:
        return study.parameters
    if wanted == "batched":
        raise UsageError(f"--mode batched: this study cannot run in batches ({why}); "
                         "hint: --mode compiled runs it run by run on the same library")
    return ()


def runner_text(job: Job) -> str:
    """How the runs were made, for metadata.json."""
    if job.batched:
        return "batched: the parametric library mapped over parameter sets (study.batch)"
    return {"compiled": "compiled: the parametric library bound per run",
            "interpreted": "interpreted, one build per run"}[job.mode]


def _reported(problems: block.StudyProblems, from_caller: set[str] | None, document):
    """Located errors for what the YAML block wrote, else (from_caller None: the model has no
    block) a usage error."""
    written = [p for p in problems.problems
               if from_caller is not None and p.path[0] not in from_caller]
    if written:
        return block.located(block.StudyProblems(written), document)
    return block.usage(problems)


def collect(prepared: Prepared, workers: int | None = None, scheduler: str | None = None,
            full_path: Path | None = None, journal_path: Path | None = None,
            resumed: list[dict] | tuple = (), dashboard: bool = False
            ) -> tuple[list[dict], bool]:
    """Run every point not among the `resumed` rows (execute.execute); the rows of the
    finished runs (resumed ones included), in run order, and whether every run finished. With
    full_path, every run's results go into one HDF5 file as they arrive (study.full); with
    journal_path, every row is appended to that CSV file as it arrives (study.journal)."""
    points = prepared.study.points()
    rows: dict[int, dict] = {r["run"]: r for r in resumed}
    pending = [k for k in range(len(points)) if k not in rows]
    writer = log = None
    if full_path is not None:
        from casmech.study.full import FullWriter

        writer = FullWriter(full_path, prepared.study.parameters)
    if journal_path is not None:
        log = journal.Journal(journal_path, columns(prepared.study), list(resumed))
    try:
        with runs_bar(len(pending)) as bar:
            def done(position: int, outcome: Outcome) -> None:
                index = pending[position]
                rows[index] = row(index, outcome, prepared.study)
                if log is not None:
                    log.add(rows[index])
                if writer is not None:
                    writer.add(index, outcome)
                if bar is not None:
                    bar(outcome.status)

            finished = execute.execute(prepared.job, [points[k] for k in pending], done,
                                       workers, scheduler, dashboard) if pending else True
    finally:
        if writer is not None:
            writer.close()
        if log is not None:
            log.close()
    return [rows[k] for k in sorted(rows)], finished


def run(out: Path | None, prepared: Prepared, options: Mapping, workers: int | None = None,
        scheduler: str | None = None, earlier: list[dict] | tuple = (),
        dashboard: bool = False, earlier_mode: str | None = None):
    """A study end to end (start, collect, write; in `out` unless None): (table, finished,
    seconds, paths written). `earlier`: the resumed rows, `earlier_mode` the mode they ran in
    (resume_mode), both recorded in metadata.json's options.resumed. When collect raises (a
    scheduler that does not answer, anything but an interrupt, which collect reports as not
    finished), metadata.json says failed with the error; the runs finished so far stay in
    sweep.csv."""
    if earlier or earlier_mode:
        options = {**options, "resumed": {"earlier_runs": len(earlier),
                                          "earlier_mode": earlier_mode}}
    journal_path = full_path = None
    if out is not None:
        start(out, prepared, options)
        journal_path = out / "sweep.csv"
        full_path = out / "runs.h5" if prepared.job.full else None
    try:
        (rows, finished), seconds = timed(collect, prepared, workers, scheduler, full_path,
                                          journal_path, earlier, dashboard)
    except Exception as error:
        if out is not None:
            failed(out, prepared, options, error)
        raise
    table = dataframe(rows, prepared.study)
    paths = [] if out is None else write(out, prepared, table, finished, {"runs": seconds},
                                         options)
    return table, finished, seconds, paths


def failed(out: Path, prepared: Prepared, options: Mapping, error: Exception) -> Path:
    """metadata.json of a study whose runs stopped on `error` (status failed, the error's
    text; its rows: those sweep.csv kept)."""
    from casmech.io.metadata import write_json

    try:
        kept = len(_journal(out, prepared))
    except Exception:  # a journal cut anyhow: the rows are what the file says, not counted
        kept = 0
    metadata = _metadata(prepared, {}, kept, "failed", options, error=str(error))
    metadata["study"] = prepared.study.describe()
    return write_json(out / "metadata.json", metadata)


def resumed(out: Path, prepared: Prepared) -> list[dict]:
    """The finished rows that an earlier run of this study left in out/sweep.csv (a usage
    error when it holds another study's: `same_study`, then journal.read's columns and
    parameter values)."""
    same_study(out, prepared)
    return _journal(out, prepared)


def _journal(out: Path, prepared: Prepared) -> list[dict]:
    """The rows out/sweep.csv holds, checked against the study's columns and points."""
    study = prepared.study
    return journal.read(out / "sweep.csv", columns(study), study.points(), study.parameters)


def _earlier_metadata(out: Path):
    """out/metadata.json parsed: any JSON value (read, not trusted); OSError or ValueError
    when it cannot be read."""
    import json

    return json.loads((out / "metadata.json").read_text(encoding="utf-8", errors="replace"))


# what a resumed study's runs share with the earlier part's, by metadata.json's keys
SHARED = {"model": "model file", "files": "files the model reads", "overrides": "--set "
          "overrides", "analysis": "analysis settings"}


def same_study(out: Path, prepared: Prepared) -> None:
    """A usage error when out/metadata.json (written before the earlier part's first run)
    records another model text, other files read, --set overrides or analysis settings than
    `prepared`'s: the rows of two studies would mix in one sweep.csv. Nothing to compare when
    the file is missing or unreadable (earlier_mode says so unless --mode is given), nor for a
    key it lacks. The file is read, not trusted: only equality with this study's own values
    is asked."""
    import json

    from casmech.errors import UsageError, escape

    try:
        earlier = _earlier_metadata(out)
    except (OSError, ValueError):
        return
    if not isinstance(earlier, dict):
        return
    now = json.loads(json.dumps(_metadata(prepared, {}, 0, "running", {})))
    now["model"] = now["model"]["sha256"]
    now["files"] = {name: entry["sha256"] for name, entry in now["files"].items()}
    model, files = earlier.get("model"), earlier.get("files")
    if "model" in earlier:
        earlier["model"] = model.get("sha256") if isinstance(model, dict) else None
    if "files" in earlier:
        earlier["files"] = {name: entry.get("sha256") if isinstance(entry, dict) else None
                            for name, entry in files.items()} if isinstance(files, dict) \
            else None
    differ = [what for key, what in SHARED.items()
              if key in earlier and earlier[key] != now[key]]
    if differ:
        raise UsageError(
            f"--resume: {escape(out)} holds a study of other {', '.join(differ)} than this one "
            f"(by {escape(out / 'metadata.json')}): its runs and these would mix in one "
            "sweep.csv; run the study as it was, or start it without --resume (or in another "
            "directory)")


RAN = ("interpreted", "compiled", "batched")  # the modes a study's metadata.json may say


def earlier_mode(out: Path) -> str:
    """The mode the earlier part of the study in `out` ran in: its metadata.json's
    `options.mode`, written by `start` before its first run (a usage error when the file is
    missing, not JSON, or says anything but one of RAN: it is read, not trusted)."""
    from casmech.errors import UsageError, escape

    path = out / "metadata.json"
    hint = "; pass --mode to choose the rest's mode"
    try:
        metadata = _earlier_metadata(out)
    except FileNotFoundError:
        raise UsageError(f"--resume: {escape(path)} does not exist, so the mode of the earlier "
                         f"part is unknown{hint}") from None
    except (OSError, ValueError) as error:
        raise UsageError(f"--resume: {escape(path)} cannot be read ({escape(error)})"
                         f"{hint}") from None
    options = metadata.get("options") if isinstance(metadata, dict) else None
    mode = options.get("mode") if isinstance(options, dict) else None
    if mode not in RAN:
        shown = escape(repr(mode)[:60])
        raise UsageError(f"--resume: {escape(path)}: options.mode is {shown}, not one of "
                         f"{', '.join(RAN)}{hint}")
    return mode


def resume_mode(out: Path, resume: bool, given: str | None) -> tuple[str, str | None]:
    """The mode to `prepare` a study in, and the mode its earlier part ran in (None when not
    resumed, or when `given` and the earlier metadata cannot tell it). A resumed study keeps
    its earlier part's mode (under method auto the mode picks the method:
    docs/decisions/method-auto.md) unless a mode is given; else `given`, default auto."""
    from casmech.errors import UsageError

    earlier = None
    if resume:
        try:
            earlier = earlier_mode(out)
        except UsageError:
            if given is None:
                raise
    return given or earlier or "auto", earlier


def mode_name(job: Job) -> str:
    """The runs' mode as `--mode` names it (batched, compiled, interpreted)."""
    return "batched" if job.batched else job.mode


def changed_mode(earlier: str | None, job: Job) -> str | None:
    """What to tell a user whose given mode makes the resumed runs differ from the earlier
    part's, else None."""
    if earlier is None or mode_name(job) == earlier:
        return None
    return (f"the earlier runs ran {earlier}, the rest run {mode_name(job)} (as --mode asks): "
            "their rows may differ within the tolerance (method auto depends on the mode, "
            "docs/decisions/method-auto.md)")


def columns(study: Study) -> list[str]:
    return [*FIXED, *study.parameters, *STATUS, *study.keep, "reason"]


def row(index: int, outcome: Outcome, study: Study) -> dict:
    kept = {text: outcome.kept.get(text, float("nan")) for text in study.keep}
    return {"run": index, **{name: outcome.values[name] for name in study.parameters},
            "status": outcome.status, "wall_s": outcome.wall_s, **kept,
            "reason": outcome.reason}


def dataframe(rows: list[dict], study: Study):
    import pandas as pd

    return pd.DataFrame(rows, columns=columns(study))


def parquet_available() -> bool:
    return importlib.util.find_spec("pyarrow") is not None


def start(out: Path, prepared: Prepared, options: Mapping) -> Path:
    """metadata.json of a study that is running (status running), before its first run."""
    from casmech.io.metadata import write_json

    out.mkdir(parents=True, exist_ok=True)
    metadata = _metadata(prepared, {}, 0, "running", options)
    metadata["study"] = prepared.study.describe()
    return write_json(out / "metadata.json", metadata)


def write(out: Path, prepared: Prepared, table, finished: bool, timings: Mapping[str, float],
          options: Mapping) -> list[Path]:
    """sweep.csv, sweep.parquet (when pyarrow is installed) and metadata.json in `out`."""
    from casmech.core.atomic import atomic
    from casmech.io.metadata import write_json

    out.mkdir(parents=True, exist_ok=True)
    paths = [out / "sweep.csv"]
    with atomic(paths[0]) as handle:
        table.to_csv(handle, index=False)
    parquet = parquet_available()
    if parquet:
        from casmech.core.atomic import replaced

        paths.append(out / "sweep.parquet")
        with replaced(paths[-1]) as temporary:
            table.to_parquet(temporary, index=False)
    counts = table["status"].value_counts().to_dict() if len(table) else {}
    metadata = _metadata(prepared, timings, len(table),
                         "complete" if finished else "interrupted", options)
    metadata["study"] = {**prepared.study.describe(), "finished_runs": len(table),
                         "statuses": {str(k): int(v) for k, v in counts.items()},
                         "parquet": parquet, "runner": runner_text(prepared.job)}
    paths.append(write_json(out / "metadata.json", metadata))
    return paths


def _metadata(prepared: Prepared, timings: Mapping[str, float], rows: int, status: str,
              options: Mapping, error: str | None = None) -> dict:
    """A study's metadata.json but its `study`: a run's (io.metadata.run_metadata) whose
    `mode` is the runs' (casmech.compile's mode: compiled for batched runs too; `options.mode`
    and `study.runner` tell batched apart)."""
    from casmech.io.metadata import run_metadata

    metadata = run_metadata(prepared.model, prepared.overrides, prepared.settings, timings, {},
                            rows, error=error, status=status, options=dict(options))
    metadata["mode"] = prepared.job.mode
    return metadata


def timed(function, *args, **kwargs):
    clock = time.perf_counter()
    value = function(*args, **kwargs)
    return value, time.perf_counter() - clock
