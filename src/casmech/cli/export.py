"""casmech export MODEL.yaml -o NAME.fmu: an FMI 2.0 FMU (Model Exchange and Co-Simulation)."""

from __future__ import annotations

import sys
import time
from pathlib import Path

from casmech import api
from casmech.backends import build
from casmech.cli.common import add_overrides, overrides


def add_arguments(parser) -> None:
    parser.add_argument("model", type=Path)
    parser.add_argument("-o", "--out", type=Path, required=True, metavar="NAME.fmu",
                        help="the FMU file to write (its name gives the modelIdentifier)")
    parser.add_argument("--outputs", action="append", metavar="COLUMNS",
                        help="results columns the FMU outputs: names or globs, comma-separated "
                             "(repeatable; default: every results column)")
    parser.add_argument("--inputs", action="append", metavar="NAMES",
                        help="which effort motors and ocp: controls are inputs, as "
                             "<joint>.torque or <joint>.force, comma-separated (repeatable; "
                             "'none': no input; default: all of them)")
    parser.add_argument("--flags", metavar="'FLAGS'",
                        help="C compiler flags (default: $CASMECH_CFLAGS, else "
                             f"{' '.join(build.DEFAULT_FLAGS)}; -std=c99 -fPIC always)")
    add_overrides(parser)


def _listed(values: list[str] | None) -> tuple[str, ...] | None:
    if values is None:
        return None
    return tuple(item.strip() for value in values for item in value.split(",") if item.strip())


def run(args) -> int:
    from casmech.fmu.archive import Options, export

    model = api.load(args.model, overrides(args.set))
    start = time.perf_counter()
    chain = build.Toolchain() if args.flags is None else build.Toolchain(
        flags=tuple(args.flags.split()))
    options = Options(outputs=_listed(args.outputs), inputs=_listed(args.inputs),
                      toolchain=chain)
    written = export(model, args.out, options)
    print(f"{args.model}: {written.path} ({written.summary}; built in "
          f"{time.perf_counter() - start:.3g} s)")
    for note in written.notes:
        print(f"note: {note}", file=sys.stderr)
    return 0
