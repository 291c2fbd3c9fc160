"""casmech plot RESULTS.csv [COLUMNS or presets] -o FILE.png|pdf|svg: plot results against time."""

from __future__ import annotations

from pathlib import Path

from casmech.errors import UsageError
from casmech.output import plot
from casmech.output.csv import read_csv
from casmech.output.hdf5 import read_hdf5

READERS = {".csv": read_csv, ".h5": read_hdf5, ".hdf5": read_hdf5}  # results file suffix -> reader


def add_arguments(parser) -> None:
    parser.add_argument("results", type=Path, help="results.csv (or results.h5) of casmech run")
    parser.add_argument("columns", nargs="*", default=["positions"],
                        help="column names, globs ('crank.*') or presets: "
                             f"{plot.PRESET_HELP} (default: positions)")
    parser.add_argument("-o", "--output", type=Path, required=True,
                        help="image to write: .png, .pdf or .svg")


def run(args) -> int:
    plot.check_output(args.output)
    reader = READERS.get(args.results.suffix.lower())
    if reader is None:
        raise UsageError(f"cannot read '{args.results}': expected a results file ending in "
                         f"{', '.join(READERS)}")
    names, values = reader(args.results)
    if "t" not in names:
        raise UsageError(f"'{args.results}' has no column 't'; expected a results table of "
                         "casmech run")
    title = f"{args.results.name}: {', '.join(args.columns)}"
    path = plot.save(plot.figure(names, values, args.columns, title), args.output)
    print(f"plotted {', '.join(args.columns)} -> {path}")
    return 0
