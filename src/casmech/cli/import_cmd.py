"""casmech import FILE.adm|FILE.mdl|FILE.acf|FILE.urdf -o MODEL.yaml: convert to casmech YAML.

Warnings (what was not translated, with the source line) go to stderr; the written YAML is
validated by casmech's own loader, and a model that does not validate is still written (so it
can be fixed by hand) with the diagnostics printed and exit code 1.
"""

from __future__ import annotations

import sys
from pathlib import Path

from casmech import api
from casmech.errors import ModelError, UsageError
from casmech.importers import TRANSLATORS, import_file


def add_arguments(parser) -> None:
    parser.add_argument("source", type=Path, help=f"file to import ({', '.join(TRANSLATORS)})")
    parser.add_argument("-o", "--output", type=Path, default=None,
                        help="YAML file to write (default: the source with suffix .yaml)")
    parser.add_argument("--quiet", action="store_true", help="do not print warnings")
    for key, unit in (("position", "rad or m"), ("velocity", "rad/s or m/s")):
        parser.add_argument(f"--{key}", action="append", default=[], metavar="JOINT=VALUE",
                            help=f"URDF: initial {key} of a joint [{unit}] (repeatable; "
                                 "default 0)")


def joint_values(flag: str, pairs: list[str]) -> dict[str, float]:
    """--position/--velocity JOINT=VALUE pairs as numbers (a usage error for anything else)."""
    values = {}
    for pair in pairs:
        name, _, text = pair.partition("=")
        try:
            values[name.strip()] = float(text)
        except ValueError:
            raise UsageError(f"--{flag} expects JOINT=NUMBER, got '{pair}'") from None
    return values


def run(args) -> int:
    output = args.output or args.source.with_suffix(".yaml")
    if output.resolve() == args.source.resolve():
        raise UsageError(f"{output}: the output would overwrite the source; give -o MODEL.yaml")
    text, warnings = import_file(args.source,
                                 positions=joint_values("position", args.position),
                                 velocities=joint_values("velocity", args.velocity))
    if not args.quiet:
        for warning in warnings:
            print(warning.format(), file=sys.stderr)
    output.parent.mkdir(parents=True, exist_ok=True)
    output.write_text(text)
    try:
        model = api.loads(text, file=str(output))
    except ModelError as error:
        print(error.format(), file=sys.stderr)
        print(f"{output}: written, but it does not validate (see above)", file=sys.stderr)
        return error.exit_code
    print(f"{args.source} -> {output}: {len(model.bodies)} bodies, {len(model.joints)} joints, "
          f"{len(model.forces)} forces; {len(warnings)} warnings")
    return 0
