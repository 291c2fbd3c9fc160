"""casmech animate MODEL.yaml RESULTS.csv -o DIR: a ParaView time series and an HTML player;
with --mode N, mode N of a modal run (RESULTS: its results.csv, linear_model.npz beside it)."""

from __future__ import annotations

from pathlib import Path

from casmech import api
from casmech.cli.common import add_overrides, overrides
from casmech.errors import UsageError
from casmech.io.animate import build_scene
from casmech.io.csv import read_csv
from casmech.io.html_player import write_html
from casmech.io.mode_animation import mode_table, read_linear_model
from casmech.io.overlays import build_overlays
from casmech.io.vtk import write_vtk


def add_arguments(parser) -> None:
    parser.add_argument("model", type=Path)
    parser.add_argument("results", type=Path, help="results.csv written by `casmech run`")
    parser.add_argument("-o", "--out", type=Path,
                        help="output directory (default: animation/ beside the results)")
    frames = parser.add_mutually_exclusive_group()
    frames.add_argument("--every", type=int, metavar="K",
                        help="draw every K-th row (and the last); default: every row")
    frames.add_argument("--fps", type=float,
                        help="draw the row nearest each multiple of 1/FPS of simulated time")
    modes = parser.add_argument_group("mode shapes (a modal run)")
    modes.add_argument("--mode", type=int, metavar="N",
                       help="play mode N of the modal run (numbered as in modes.csv) instead of "
                            "the results' rows")
    modes.add_argument("--amplitude", type=float, default=0.1, metavar="A",
                       help="largest body motion of the mode, in metres or radians "
                            "(default 0.1)")
    modes.add_argument("--cycles", type=float, default=2.0, metavar="C",
                       help="periods of the mode to play (default 2)")
    parser.add_argument("--trail", action="append", default=[], metavar="BODY[@X,Y,Z]",
                        help="draw the path of a body's CM, or of the point of the body at "
                             "X,Y,Z (global at t = 0, like a joint's `at`), in the HTML player; "
                             "repeatable (default: every body's CM, shown on demand)")
    parser.add_argument("--no-vtk", action="store_true", help="write only the HTML player")
    parser.add_argument("--no-html", action="store_true", help="write only the VTK series")
    add_overrides(parser)


def _results(path: Path):
    if not path.is_file():
        raise UsageError(f"{path}: no such results file (hint: write one with `casmech run`)")
    return read_csv(path)


def _metadata(results: Path) -> dict:
    """The run's metadata.json beside the results (its reaction frames), or nothing."""
    from casmech.io.metadata import read_json

    beside = results.parent / "metadata.json"
    try:
        found = read_json(beside) if beside.is_file() else {}
    except (OSError, ValueError):
        return {}
    return found if isinstance(found, dict) else {}


def run(args) -> int:
    if args.no_vtk and args.no_html:
        raise UsageError("--no-vtk and --no-html together leave nothing to write")
    model = api.load(args.model, overrides(args.set))
    if args.mode is None:
        names, values = _results(args.results)
    else:
        linear = read_linear_model(args.results.parent / "linear_model.npz")
        names, values = mode_table(linear, tuple(b.name for b in model.bodies), args.mode,
                                   args.amplitude, args.cycles)
    scene = build_scene(model, names, values, every=args.every, fps=args.fps)
    overlays = None if args.no_html else build_overlays(
        model, scene, names, values, scene.rows,
        _metadata(args.results) if args.mode is None else {}, args.trail)
    out = args.out or args.results.parent / "animation"
    written = []
    if not args.no_vtk:
        written.append(write_vtk(scene, out))
    if overlays is not None:
        written.append(write_html(scene, overlays, out / "animation.html"))
    print(f"{len(scene.times)} frames, {len(scene.bodies)} bodies, {len(scene.parts)} parts -> "
          + ", ".join(str(path) for path in written))
    return 0
