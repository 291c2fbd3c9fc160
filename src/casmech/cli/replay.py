"""The arguments of `casmech run`: given on the command line, or recorded by an earlier run.

`direct(args)` completes the arguments of `casmech run MODEL ...` (MODEL required, default
format and mode). `replayed(args)` turns `casmech run --replay DIR/metadata.json [--out OUT]`
into the arguments of the run that metadata.json records (io/metadata.py): the same model
file, overrides, analysis settings, formats, reaction frames, allowed folders, compile
mode (the mode that ran, for a complete run) and `--option`s. Every file the run read
(`files`: model, components, tables, meshes, data) must still have its recorded sha256; a
changed or missing file is a usage error naming it. OUT defaults to `DIR_replay/` beside DIR.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from casmech.errors import UsageError

# run's argument -> the key of metadata.json's `analysis` that records it
SETTINGS = {"analysis": "type", "t_end": "t_end", "output_step": "output_step",
            "rtol": "rtol", "atol": "atol", "formulation": "formulation",
            "stabilization": "stabilization", "method": "method"}
RECORDED = (*SETTINGS, "format", "mode", "reactions_frame")  # run's arguments a replay takes


def direct(args: argparse.Namespace) -> argparse.Namespace:
    if args.model is None:
        raise UsageError("casmech run needs a MODEL file (or --replay DIR/metadata.json)")
    return argparse.Namespace(**{**vars(args), "format": args.format or ["csv"],
                                 "mode": args.mode or "auto"})


def replayed(args: argparse.Namespace) -> argparse.Namespace:
    _alone(args)
    record = read_record(args.replay)
    options = record.get("options", {})
    from casmech.schema import files

    for folder in options.get("allow_dir", []):
        files.allow(folder)
    check_files(record, args.replay)
    settings = record["analysis"]
    complete = record.get("status") in ("complete", "stopped by event")
    folder = args.replay.resolve().parent
    return argparse.Namespace(**{
        **vars(args),
        "model": Path(record["model"]["absolute_path"]),
        "set": [f"{name}={value}" for name, value in record["overrides"].items()],
        "out": args.out or folder.with_name(folder.name + "_replay"),
        **{name: settings.get(key) for name, key in SETTINGS.items()},
        # formulation auto ran with the default stabilization: asking for it explicitly would
        # mean the r-p DAE (runtime.analyses.analysis_settings)
        **({"stabilization": None} if settings.get("formulation") == "auto" else {}),
        "option": list(options.get("option", [])),
        "format": list(options.get("format", ["csv"])),
        "reactions_frame": options.get("reactions_frame"),
        "mode": record["mode"] if complete else options.get("mode", "auto"),
        "allow_dir": [*args.allow_dir, *options.get("allow_dir", [])],
    })


def _alone(args: argparse.Namespace) -> None:
    """--replay takes everything from the record: only --out and --allow-dir may be given."""
    given = [f"--{name.replace('_', '-')}" for name in RECORDED if getattr(args, name) is not None]
    given += ["--set"] if args.set else []
    given += ["--option"] if args.option else []
    given += [f"the model file {args.model}"] if args.model is not None else []
    if given:
        raise UsageError(f"--replay runs what {args.replay} records; it takes no "
                         f"{', '.join(given)} (only --out and --allow-dir)")


KEYS = ("model", "files", "overrides", "analysis", "mode")  # what a replay reads


def read_record(path: Path) -> dict:
    try:
        record = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise UsageError(f"{path}: no such file") from None
    except (OSError, UnicodeDecodeError, ValueError) as error:
        raise UsageError(f"{path}: not a metadata.json written by casmech run ({error})") from None
    missing = [key for key in KEYS if not isinstance(record, dict) or key not in record]
    if missing:
        raise UsageError(f"{path}: not a metadata.json that casmech run --replay can repeat "
                         f"(no {', '.join(missing)}; runs of casmech before file hashes were "
                         "recorded cannot be replayed)")
    return record


def check_files(record: dict, path: Path) -> None:
    """Every file the recorded run read has its recorded sha256 (a UsageError naming each one
    that does not)."""
    from casmech.schema.files import digest

    problems = []
    for entry in record["files"].values():
        file = Path(entry["path"])
        if not file.is_file():
            problems.append(f"{file}: no longer exists; the run recorded in {path} read it")
            continue
        now = digest(file)
        if now != entry["sha256"]:
            problems.append(f"{file}: changed since the run recorded in {path} (sha256 "
                            f"{entry['sha256'][:16]}... then, {now[:16]}... now)")
    if problems:
        raise UsageError("--replay runs only the files the run read, unchanged:\n  "
                         + "\n  ".join(problems))
