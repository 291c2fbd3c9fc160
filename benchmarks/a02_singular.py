"""Time and accuracy of casmech on the IFToMM A02 N-four-bar, which passes its flat (singular)
poses: both DAEs fail at the first one, and the run is done from t0 by the projected Runge-Kutta
steps of runtime.projected_rk4. No peer here (the issue's peers are timed on the chains and the
four-bar by run.py); the B0 error is against the benchmark's exact solution
(tests/reference/analytic), over the whole span.

    python benchmarks/a02_singular.py --n 2 40 --formulations rp romega --repeats 3

Compilation is not timed; each repeat is one casmech.analyze with the model's settings (rtol
1e-10, atol 1e-12; N = 2 over 10 s with output every 0.01 s, N = 40 over 20 s every 0.05 s, as
the reference files). Prints a Markdown table of medians.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

REFERENCES = {2: ("A02_Nfourbar_N2_0-10s.csv", 10.0, 0.01),
              40: ("A02_Nfourbar_N40_0-20s_dt0.05.csv", 20.0, 0.05)}


def measure(n: int, formulation: str, repeats: int) -> dict:
    from tests.helpers.a02_model import a02_model
    from tests.helpers.reference_data import read_analytic
    from tests.validation.runtime.test_validation_iftomm import a02_b0_error

    import casmech

    name, t_end, step = REFERENCES[n]
    exact = read_analytic(name)
    functions = casmech.compile(casmech.loads(a02_model(n)))
    times, errors, metadata = [], [], {}
    for _ in range(repeats):
        start = time.perf_counter()
        result = casmech.analyze(functions, "dynamics", t_end=t_end, output_step=step,
                                 formulation=formulation)
        times.append(time.perf_counter() - start)
        errors.append(a02_b0_error(functions, result, exact)[0])
        metadata = result.metadata
    return {"n": n, "formulation": formulation, "bodies": functions.n_bodies,
            "time": statistics.median(times), "times": times, "error": max(errors),
            "steps": metadata["rk4_steps"], "rejected": metadata["rk4_rejected"],
            "stalled": len(metadata["rk4_stalled_at"] or []),
            "dae_failed_at": metadata["dae_failed_at"]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, nargs="+", default=[2, 40], choices=sorted(REFERENCES))
    parser.add_argument("--formulations", nargs="+", default=["rp", "romega"])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    print(f"{platform.node()}, {os.cpu_count()} cores, Python {platform.python_version()}, "
          f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, load {os.getloadavg()[0]:.2f}")
    print("\n| N | bodies | formulation | time (median) | runs | max B0 error | RK4 steps | "
          "rejected | stalled | DAE failed in the chunk from |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for n in args.n:
        for formulation in args.formulations:
            row = measure(n, formulation, args.repeats)
            runs = ", ".join(f"{t:.1f}" for t in row["times"])
            print(f"| {n} | {row['bodies']} | {formulation} | {row['time']:.1f} s | {runs} | "
                  f"{row['error']:.1e} m | {row['steps']} | {row['rejected']} | "
                  f"{row['stalled']} | {row['dae_failed_at']} s |", flush=True)
    print(f"\nload at the end {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
