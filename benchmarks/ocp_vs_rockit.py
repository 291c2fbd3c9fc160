"""IPOPT's time on the cart-pole and double-pendulum swing-ups: casmech (from the gallery
YAML, joint coordinates, Radau 3, one element per interval: rockit's DirectCollocation) and
the hand-written rockit scripts of benchmarks/rockit_ocp.py, interleaved, medians of RUNS.
Needs the `bench` extra (rockit-meco).

    python benchmarks/ocp_vs_rockit.py [RUNS]
"""

from __future__ import annotations

import sys
import time
from pathlib import Path
from statistics import median

sys.path.insert(0, str(Path(__file__).parent))

import rockit_ocp  # noqa: E402

import casmech  # noqa: E402
from casmech.optimal.ocp import OCP, from_block, solve  # noqa: E402

MODELS = Path(__file__).parents[1] / "models"
PROBLEMS = (("cart-pole", "ocp_cart_pole_swing_up", rockit_ocp.cart_pole),
            ("double pendulum", "ocp_double_pendulum_swing_up", rockit_ocp.double_pendulum))


def casmech_run(name: str):
    """(cost, IPOPT's time, iterations, the whole solve's time from the YAML file)."""
    start = time.perf_counter()
    model = casmech.load(MODELS / f"{name}.yaml")
    problem, transcription = from_block(model.ocp)
    problem = OCP(**{**problem.__dict__, "elements": 1, "degree": 3, "scheme": "radau"})
    solution = solve(model, problem, transcription, options={"record_time": True})
    return (solution.objective, solution.solver_time, solution.iterations,
            time.perf_counter() - start)


def main(runs: int = 5) -> None:
    for label, name, script in PROBLEMS:
        ours, theirs, totals = [], [], []
        for _ in range(runs):
            cost, seconds, iterations, total = casmech_run(name)
            ours.append(seconds)
            totals.append(total)
            rockit_cost, rockit_seconds, rockit_iterations = script()
            theirs.append(rockit_seconds)
        print(f"{label}: casmech cost {cost:.10g} ({iterations} it), IPOPT median "
              f"{median(ours):.4f} s (whole solve {median(totals):.3f} s); rockit cost "
              f"{rockit_cost:.10g} ({rockit_iterations} it), IPOPT median "
              f"{median(theirs):.4f} s; relative cost difference "
              f"{abs(cost - rockit_cost) / abs(rockit_cost):.2e}")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 5)
