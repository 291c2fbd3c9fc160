"""casmech plot RESULTS.csv [COLUMNS or presets] -o FILE.png|pdf|svg: plot results against time."""

from __future__ import annotations

import json
from pathlib import Path

from casmech.errors import UsageError
from casmech.io import plot
from casmech.io.csv import read_csv
from casmech.io.hdf5 import read_hdf5, read_hdf5_metadata

READERS = {".csv": read_csv, ".h5": read_hdf5, ".hdf5": read_hdf5}  # results file suffix -> reader


def add_arguments(parser) -> None:
    parser.add_argument("results", type=Path, help="results.csv (or results.h5) of casmech run, "
                                                   "or sweep.csv of casmech sweep")
    parser.add_argument("columns", nargs="*",
                        help="column names, globs ('crank.*') or presets: "
                             f"{plot.PRESET_HELP} (default: positions); of a sweep.csv: kept "
                             "outputs (default: all), against the first grid parameter or as "
                             "histograms of a sampled study")
    parser.add_argument("-o", "--output", type=Path, required=True,
                        help="image to write: .png, .pdf or .svg")


def _metadata(results: Path) -> dict:
    """The run's metadata (metadata.json beside a CSV, the file's own for HDF5); empty when
    there is none."""
    try:
        if results.suffix.lower() == ".csv":
            metadata = json.loads((results.parent / "metadata.json").read_text())
        else:
            metadata = read_hdf5_metadata(results)
    except (OSError, ValueError, KeyError):
        return {}
    return metadata if isinstance(metadata, dict) else {}


def output_units(results: Path) -> dict[str, str | None]:
    """output -> its unit, from the run's metadata (`outputs`); empty when it says nothing."""
    described = _metadata(results).get("outputs")
    if not isinstance(described, dict):
        return {}
    return {name: entry.get("unit") if isinstance(entry.get("unit"), str) else None
            for name, entry in described.items() if isinstance(entry, dict)}


def reaction_frames(results: Path) -> dict[str, str]:
    """joint -> the frame of its reaction columns, from the run's metadata (metadata.json
    beside a CSV, the file's own for HDF5); empty (global) when the metadata says nothing."""
    described = _metadata(results).get("reaction_frames")
    if not isinstance(described, dict):
        return {}
    return {joint: entry["frame"] for joint, entry in described.items()
            if isinstance(entry, dict) and isinstance(entry.get("frame"), str)}


def _is_sweep(path: Path) -> bool:
    """Whether a CSV is casmech sweep's table (by its header)."""
    from casmech.study.plot import is_sweep

    try:
        with open(path, encoding="utf-8") as handle:
            return is_sweep(handle.readline().strip().split(","))
    except (OSError, UnicodeDecodeError):
        return False


def run(args) -> int:
    plot.check_output(args.output)
    reader = READERS.get(args.results.suffix.lower())
    if reader is None:
        raise UsageError(f"cannot read '{args.results}': expected a results file ending in "
                         f"{', '.join(READERS)}")
    if args.results.suffix.lower() == ".csv" and _is_sweep(args.results):
        from casmech.study import plot as sweep_plot

        path = plot.save(sweep_plot.figure(args.results, args.columns), args.output)
        print(f"plotted {', '.join(args.columns) or 'the kept outputs'} -> {path}")
        return 0
    args.columns = args.columns or ["positions"]
    names, values = reader(args.results)
    if "t" not in names:
        raise UsageError(f"'{args.results}' has no column 't'; expected a results table of "
                         "casmech run")
    title = f"{args.results.name}: {', '.join(args.columns)}"
    frames = reaction_frames(args.results)
    path = plot.save(plot.figure(names, values, args.columns, title, frames,
                                 output_units(args.results)), args.output)
    print(f"plotted {', '.join(args.columns)} -> {path}")
    return 0
