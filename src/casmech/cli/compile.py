"""casmech compile MODEL.yaml -o DIR: C sources, header, manifest.json and the shared library."""

from __future__ import annotations

import time
from pathlib import Path

from casmech import api
from casmech.backends import build, codegen
from casmech.cli.common import add_overrides, overrides
from casmech.errors import UsageError


def add_arguments(parser) -> None:
    parser.add_argument("model", type=Path)
    parser.add_argument("-o", "--out", type=Path, required=True, help="output directory")
    parser.add_argument("--flags", metavar="'FLAGS'",
                        help="C compiler flags, e.g. --flags='-O2 -march=native' (default: "
                             "$CASMECH_CFLAGS, else "
                             f"{' '.join(build.DEFAULT_FLAGS)}; -std=c99 -fPIC always)")
    parser.add_argument("--jobs", type=int, help="parallel compiler processes (default: cores)")
    parser.add_argument("--no-dae", action="store_true",
                        help="leave out the DAE residuals dae_[ggl_]rp, dae_[ggl_]romega and their "
                             "Jacobians (about half of the code)")
    add_overrides(parser)


def toolchain(flags: str | None, jobs: int | None) -> codegen.Toolchain:
    chain = codegen.Toolchain() if flags is None else codegen.Toolchain(flags=tuple(flags.split()))
    if jobs is not None:
        if jobs < 1:
            raise UsageError(f"--jobs must be at least 1 (got {jobs})")
        chain = codegen.Toolchain(chain.compiler, chain.flags, jobs)
    return chain


def run(args) -> int:
    model = api.load(args.model, overrides(args.set))
    start = time.perf_counter()
    path, hit = codegen.export(model, args.out, toolchain(args.flags, args.jobs),
                               dae=not args.no_dae)
    how = "from the cache" if hit else f"built in {time.perf_counter() - start:.3g} s"
    print(f"{args.model}: {path.parent / build.LIBRARY} ({how}); manifest {path}")
    return 0
