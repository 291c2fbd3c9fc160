"""The fixed costs of the default dynamics call: `casmech.analyze(functions, "dynamics", t_end=1,
rtol=r, atol=r/100)` on a benchmark system or a model file, its first call on a bundle and the
same call repeated (CPU time), by stage: the joint system, the start, method auto's stiffness
probe, the integrator, the results rows, and the rest (Python around them).

    python benchmarks/fixed_costs.py chain2 four_bar --mode compiled --rtols 1e-4 1e-8
    python benchmarks/fixed_costs.py robot.yaml --mode interpreted --rtols 1e-7
    python benchmarks/fixed_costs.py chain2 --compare 106e605 --rounds 5   # two commits

--compare runs each target in its own process per commit (src/ of COMMIT exported with git
archive, and this checkout's), alternating for --rounds rounds after one warm-up round, and
prints the medians of each commit's first-call and repeated-call times side by side.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
STAGES = {"joint_system": "joint_system", "_start": "start", "choose_method": "stiffness probe"}


def _bundle(target: str, mode: str):
    import casmech

    if target.endswith(".yaml"):
        return casmech.compile(casmech.load(target), mode)
    sys.path.insert(0, str(HERE))
    from casmech_model import yaml_text
    from systems import make

    return casmech.compile(casmech.loads(yaml_text(make(target)), file=f"<{target}>"), mode)


def _timed(owner, name: str, label: str, spent: dict) -> None:
    original = getattr(owner, name)

    def timed(*args, **kwargs):
        start = time.process_time()
        try:
            return original(*args, **kwargs)
        finally:
            spent[label] = spent.get(label, 0.0) + time.process_time() - start

    setattr(owner, name, timed)


def measure(target: str, mode: str, rtols: list[float], calls: int, stages: bool,
            method: str | None = None) -> dict:
    """{rtol: {"first": s, "again": s, "stages": {...}}} of one process."""
    import casmech
    from casmech.runtime import joint_dynamics

    spent: dict[str, float] = {}
    if stages:
        for name, label in STAGES.items():
            _timed(joint_dynamics, name, label, spent)
        _timed(joint_dynamics._Integrator, "__call__", "integrator", spent)
        _timed(getattr(joint_dynamics, "Recorder", None) or joint_dynamics._Recorder, "rows",
               "results rows", spent)
    functions = _bundle(target, mode)
    out = {}
    for rtol in rtols:
        def call(rtol=rtol):
            spent.clear()
            start = time.process_time()
            result = casmech.analyze(functions, "dynamics", t_end=1.0, rtol=rtol,
                                     atol=rtol / 100, method=method)
            total = time.process_time() - start
            parts = dict(spent, rest=total - sum(spent.values()))
            return total, parts, result.metadata.get("steps")

        first, first_parts, _ = call()
        again = [call() for _ in range(calls)]
        middle = sorted(again, key=lambda run: run[0])[len(again) // 2]
        out[rtol] = {"first": first, "again": middle[0], "steps": middle[2],
                     "first_stages": first_parts, "again_stages": middle[1]}
    return out


def compare(targets, mode, rtols, calls, commit: str, rounds: int) -> None:
    with tempfile.TemporaryDirectory(prefix="casmech_fixed_") as folder:
        archive = subprocess.run(["git", "archive", commit, "src"], cwd=HERE.parent,
                                 check=True, capture_output=True).stdout
        subprocess.run(["tar", "-x", "-C", folder], input=archive, check=True)
        sources = {commit: str(Path(folder) / "src"), "this checkout": str(HERE.parent / "src")}
        for target in targets:
            runs = {name: [] for name in sources}
            for k in range(rounds + 1):  # round 0 fills each commit's compiled cache
                for name, src in sources.items():
                    done = subprocess.run(
                        [sys.executable, __file__, target, "--mode", mode, "--calls", str(calls),
                         "--json", "--rtols", *map(str, rtols)],
                        env=dict(os.environ, PYTHONPATH=src), check=True, capture_output=True,
                        text=True)
                    if k:
                        runs[name].append(json.loads(done.stdout.splitlines()[-1]))
            for rtol in map(str, rtols):
                old, new = ({kind: statistics.median(run[rtol][kind] for run in runs[name])
                             for kind in ("first", "again")} for name in sources)
                print(f"{target} {mode} rtol {rtol}: first {1e3 * old['first']:.2f} -> "
                      f"{1e3 * new['first']:.2f} ms, again {1e3 * old['again']:.3f} -> "
                      f"{1e3 * new['again']:.3f} ms ({new['again'] / old['again']:.2f}x), "
                      f"{commit} -> this checkout, medians of {rounds} processes each")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("targets", nargs="+", help="benchmark systems (chain2, four_bar, ...) "
                        "or model files")
    parser.add_argument("--mode", default="compiled", choices=("compiled", "interpreted"))
    parser.add_argument("--rtols", type=float, nargs="+", default=[1e-4, 1e-8])
    parser.add_argument("--calls", type=int, default=20, help="repeated calls (median)")
    parser.add_argument("--compare", metavar="COMMIT")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--method", default=None, help="the joint ODE's method (default: the "
                        "file's, else auto)")
    parser.add_argument("--json", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    os.environ.setdefault("CASMECH_CACHE_DIR", str(Path(tempfile.gettempdir())
                                                   / "casmech_fixed_costs_cache"))
    if args.compare:
        compare(args.targets, args.mode, args.rtols, args.calls, args.compare, args.rounds)
        return
    for target in args.targets:
        out = measure(target, args.mode, args.rtols, args.calls, not args.json, args.method)
        if args.json:
            print(json.dumps({str(r): v for r, v in out.items()}))
            continue
        for rtol, row in out.items():
            for kind in ("first", "again"):
                parts = ", ".join(f"{name} {1e3 * value:.2f}"
                                  for name, value in row[f"{kind}_stages"].items())
                print(f"{target} {args.mode} rtol {rtol:g} {kind}: {1e3 * row[kind]:.2f} ms "
                      f"({parts}); {row['steps']} steps")


if __name__ == "__main__":
    main()
