"""casmech import FILE.adm|.mdl|.acf|.urdf|.xml -o MODEL.yaml: convert to casmech YAML.

Sources: an Adams/Solver dataset (.adm), a simEngine3D model or analysis file (.mdl, .acf), a
URDF robot (.urdf) or a MuJoCo MJCF model (.xml, .mjcf); docs/import.md. Warnings (what was
not translated, with the source line) go to stderr; the written YAML is validated by casmech's
own loader, and a model that does not validate is still written (so it can be fixed by hand)
with the diagnostics printed and exit code 1. Meshes found outside the YAML's folder are named
by absolute paths; the validation allows their folder, and the summary says which folder
`--allow-dir` must give to the commands that load the model.
"""

from __future__ import annotations

import math
import os
import sys
from pathlib import Path

from casmech import api
from casmech.errors import ModelError, UsageError
from casmech.importers import TRANSLATORS, translate
from casmech.importers.emit import to_yaml

DESCRIPTION = ("Convert an Adams dataset (.adm), a simEngine3D model (.mdl, .acf), a URDF robot "
               "(.urdf) or a MuJoCo MJCF model (.xml, .mjcf) to casmech YAML. What is not "
               "translated is a warning naming the source's line, kept as a comment.")


def add_arguments(parser) -> None:
    parser.description = DESCRIPTION
    parser.add_argument("source", type=Path, help=f"file to import ({', '.join(TRANSLATORS)})")
    parser.add_argument("-o", "--output", type=Path, default=None,
                        help="YAML file to write (default: the source with suffix .yaml)")
    parser.add_argument("--quiet", action="store_true", help="do not print warnings")
    for key, unit in (("position", "rad or m"), ("velocity", "rad/s or m/s")):
        parser.add_argument(f"--{key}", action="append", default=[], metavar="JOINT=VALUE",
                            help=f"URDF, MJCF: initial {key} of a hinge or slide joint [{unit}] "
                                 "(repeatable; default: the file's pose, at rest)")
    parser.add_argument("--keyframe", default=None, metavar="NAME",
                        help="MJCF: the initial state (qpos, qvel, ctrl) of this <key> (a name "
                             "or an index)")
    parser.add_argument("--mesh-dir", action="append", default=[], type=Path, metavar="DIR",
                        help="URDF, MJCF: a folder where meshes are looked for (package:// "
                             "PKG/path as DIR/PKG/path or DIR/path; repeatable)")
    parser.add_argument("--floating-base", action="store_true",
                        help="URDF: the root link is a free body, not the ground")
    parser.add_argument("--bound-inertia", type=float, default=0.0, metavar="VALUE",
                        help="URDF, MJCF: raise principal moments of inertia below VALUE "
                             "[kg m^2] to it (MuJoCo's boundinertia; a warning per body)")
    parser.add_argument("--balance-inertia", action="store_true",
                        help="URDF, MJCF: principal moments that violate the triangle "
                             "inequality are set to their mean (MuJoCo's balanceinertia)")


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


def _validated(text: str, output: Path, outside: Path | None):
    """The written model loaded by casmech, the meshes' folder allowed for this check only."""
    if outside is None:
        return api.loads(text, file=str(output))
    from casmech.schema import files

    before = os.environ.get(files.ALLOWED_DIRS)
    os.environ[files.ALLOWED_DIRS] = os.pathsep.join(filter(None, (before, str(outside))))
    try:
        return api.loads(text, file=str(output))
    finally:
        if before is None:
            del os.environ[files.ALLOWED_DIRS]
        else:
            os.environ[files.ALLOWED_DIRS] = before


def run(args) -> int:
    output = args.output or args.source.with_suffix(".yaml")
    if output.resolve() == args.source.resolve():
        raise UsageError(f"{output}: the output would overwrite the source; give -o MODEL.yaml")
    if not math.isfinite(args.bound_inertia) or args.bound_inertia < 0:
        raise UsageError(f"--bound-inertia expects a number >= 0, got {args.bound_inertia}")
    model = translate(args.source, output=output,
                      positions=joint_values("position", args.position),
                      velocities=joint_values("velocity", args.velocity),
                      keyframe=args.keyframe, mesh_dirs=tuple(args.mesh_dir),
                      floating_base=args.floating_base, bound_inertia=args.bound_inertia,
                      balance_inertia=args.balance_inertia)
    text, warnings = to_yaml(model), model.warnings
    if not args.quiet:
        for warning in warnings:
            print(warning.format(), file=sys.stderr)
    output.parent.mkdir(parents=True, exist_ok=True)
    output.write_text(text)
    outside = getattr(model, "mesh_folder", None)
    try:
        loaded = _validated(text, output, outside)
    except ModelError as error:
        print(error.format(), file=sys.stderr)
        print(f"{output}: written, but it does not validate (see above)", file=sys.stderr)
        return error.exit_code
    print(f"{args.source} -> {output}: {len(loaded.bodies)} bodies, {len(loaded.joints)} "
          f"joints, {len(loaded.forces)} forces; {len(warnings)} warnings")
    if outside is not None:
        print(f"meshes are read from {outside}: give --allow-dir {outside} to the commands "
              "that load the model (check, run, animate)")
    return 0
