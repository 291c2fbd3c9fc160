"""The arguments of `casmech run`: given on the command line, or recorded by an earlier run.

`direct(args)` completes the arguments of `casmech run MODEL ...` (MODEL required, default
format and mode). `replayed(args)` turns `casmech run --replay DIR/metadata.json [--out OUT]`
into the arguments of the run that metadata.json records (io/metadata.py): the same model
file, overrides, analysis settings, formats, reaction frames, compile mode (the mode that
ran, for a complete run) and `--option`s. OUT defaults to `DIR_replay/` beside DIR.

A metadata file is untrusted input (docs/security.md). Before anything it names is read:
  - it is validated by a schema (commands.replay_record: located errors, never a traceback);
  - the model file must be among its `files`, and every file there must lie inside the
    model's folder or inside a folder given by `--allow-dir` on this command line: a folder
    the record's `allow_dir` names is refused unless the command line repeats it;
  - every file must be a regular file with its recorded sha256 (a changed or missing file is a
    usage error naming it).
Once the model is loaded, `check_read` refuses a run that read any file the record does not
list, before the analysis starts or anything is written.
"""

from __future__ import annotations

import argparse
import os
import stat
from pathlib import Path

from casmech.errors import UsageError, escape

# run's argument -> the key of metadata.json's `analysis` that records it
SETTINGS = {"analysis": "type", "t_end": "t_end", "output_step": "output_step",
            "rtol": "rtol", "atol": "atol", "formulation": "formulation",
            "stabilization": "stabilization", "method": "method"}
RECORDED = (*SETTINGS, "format", "mode", "reactions_frame")  # run's arguments a replay takes


def direct(args: argparse.Namespace) -> argparse.Namespace:
    if args.model is None:
        raise UsageError("casmech run needs a MODEL file (or --replay DIR/metadata.json)")
    return argparse.Namespace(**{**vars(args), "format": args.format or ["csv"],
                                 "mode": args.mode or "auto", "replay_files": None})


def replayed(args: argparse.Namespace) -> argparse.Namespace:
    _alone(args)
    from casmech.cli import replay_record  # its pydantic models: only for a replay

    record = replay_record.read(args.replay)
    options = record.options
    given = [Path(folder).expanduser().resolve() for folder in args.allow_dir]
    _recorded_folders(options.allow_dir, given, args.replay)
    model = Path(record.model.absolute_path)
    listed = check_files(record, args.replay, [model.resolve().parent, *given])
    if model.resolve() not in listed:
        raise UsageError(f"{escape(args.replay)}: the model file {escape(model)} is not among "
                         "the files it records with their sha256; only what a record lists "
                         "is replayed")
    settings = record.analysis
    complete = record.status in ("complete", "stopped by event")
    folder = args.replay.resolve().parent
    return argparse.Namespace(**{
        **vars(args),
        "model": model,
        "set": [f"{name}={value}" for name, value in record.overrides.items()],
        "out": args.out or folder.with_name(folder.name + "_replay"),
        **{name: getattr(settings, key) for name, key in SETTINGS.items()},
        # formulation auto ran with the default stabilization: asking for it explicitly would
        # mean the r-p DAE (runtime.analyses.analysis_settings)
        **({"stabilization": None} if settings.formulation == "auto" else {}),
        "option": list(options.option),
        "format": list(options.format),
        "reactions_frame": options.reactions_frame,
        "mode": record.mode if complete else (options.mode or "auto"),
        "allow_dir": [str(folder) for folder in given],
        "replay_files": listed,
    })


def _recorded_folders(recorded: list[str], given: list[Path], path: Path) -> None:
    """Every folder the record allowed is allowed on this command line too (a usage error
    naming the --allow-dir to add otherwise)."""
    missing = [folder for folder in recorded if Path(folder).resolve() not in given]
    if missing:
        repeat = " ".join(f"--allow-dir {escape(folder)}" for folder in missing)
        raise UsageError(f"{escape(path)} lets the model read files outside its folder "
                         f"(allow_dir: {', '.join(escape(f) for f in missing)}); a replay "
                         f"allows such a folder only when its command line does too: add "
                         f"{repeat} if you trust it")


def _alone(args: argparse.Namespace) -> None:
    """--replay takes everything from the record: only --out and --allow-dir may be given."""
    given = [f"--{name.replace('_', '-')}" for name in RECORDED if getattr(args, name) is not None]
    given += ["--set"] if args.set else []
    given += ["--option"] if args.option else []
    given += [f"the model file {args.model}"] if args.model is not None else []
    if given:
        raise UsageError(f"--replay runs what {args.replay} records; it takes no "
                         f"{', '.join(given)} (only --out and --allow-dir)")


def _inside(path: Path, folders: list[Path]) -> bool:
    return any(path == folder or folder in path.parents for folder in folders)


def check_files(record, path: Path, folders: list[Path]) -> set[Path]:
    """Every file the recorded run read lies inside `folders` (symbolic links followed), is
    a regular file and has its recorded sha256; returns their resolved paths (a UsageError
    naming each one that does not; a file outside is never opened)."""
    from casmech.schema.files import digest

    problems, listed = [], set()
    for entry in record.files.values():
        file = Path(entry.path)
        shown = escape(file)
        resolved = file.resolve() if file.is_absolute() else None
        if resolved is None or not _inside(resolved, folders):
            problems.append(f"{shown}: outside the model's folder and every --allow-dir; "
                            "a replay reads nothing there")
            continue
        listed.add(resolved)
        try:
            mode = os.stat(resolved).st_mode
        except OSError:
            problems.append(f"{shown}: no longer exists; the run recorded in "
                            f"{escape(path)} read it")
            continue
        if not stat.S_ISREG(mode):
            problems.append(f"{shown}: not a regular file")
            continue
        now = digest(resolved)
        if now != entry.sha256:
            problems.append(f"{shown}: changed since the run recorded in {escape(path)} "
                            f"(sha256 {entry.sha256[:16]}... then, {now[:16]}... now)")
    if problems:
        raise UsageError("--replay runs only the files the run read, unchanged, inside the "
                         "model's folder:\n  " + "\n  ".join(problems))
    return listed


def check_read(model, args: argparse.Namespace) -> None:
    """A replayed run read only files its record lists (model.sources: every file the model
    read); a usage error naming the others, before the analysis."""
    if getattr(args, "replay_files", None) is None:
        return
    unlisted = sorted(p for p in model.sources if Path(p).resolve() not in args.replay_files)
    if unlisted:
        raise UsageError(f"{escape(args.replay)} does not list "
                         f"{', '.join(escape(p) for p in unlisted)}, which the model read; "
                         "a replay runs only what its record lists")
