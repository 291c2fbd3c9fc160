"""The fixed CPU cost of one `casmech.analyze` call: many one-step dynamics analyses of a small
chain, compiled, timed by the process's CPU clock; the median per call and a profile.

    PYTHONPATH=src python benchmarks/call_overhead.py [--system chain2] [--calls 300] [--profile]

Run it with another commit's src first on PYTHONPATH to compare two commits in one session.
"""

from __future__ import annotations

import argparse
import cProfile
import os
import pstats
import statistics
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from casmech_model import OUTPUT_STEP, yaml_text  # noqa: E402
from systems import make  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--system", default="chain2")
    parser.add_argument("--calls", type=int, default=300)
    parser.add_argument("--mode", default="compiled")
    parser.add_argument("--profile", action="store_true")
    args = parser.parse_args()
    os.environ.setdefault("CASMECH_CACHE_DIR", tempfile.mkdtemp(prefix="casmech_overhead_"))
    import casmech

    system = make(args.system)
    functions = casmech.compile(casmech.loads(yaml_text(system), file=f"<{system.name}>"),
                                mode=args.mode)

    def one():
        casmech.analyze(functions, "dynamics", t_end=OUTPUT_STEP, output_step=OUTPUT_STEP)

    for _ in range(5):
        one()
    if args.profile:
        profile = cProfile.Profile()
        profile.enable()
        for _ in range(args.calls):
            one()
        profile.disable()
        pstats.Stats(profile).sort_stats("cumulative").print_stats(45)
        return
    times = []
    for _ in range(args.calls):
        start = time.process_time()
        one()
        times.append(time.process_time() - start)
    print(f"{casmech.__file__}: {args.system} {args.mode}: median CPU per call "
          f"{1e3 * statistics.median(times):.3f} ms over {args.calls} calls")


if __name__ == "__main__":
    main()
