"""A Python controller against the same law written in the model: a PD on a pendulum and on
the double pendulum (a PD per joint), in the joint and r-p formulations, interpreted.

    python benchmarks/controller_cost.py --repeats 5

The expression's runs reuse their bundle (warm: what a repeated run costs); each controlled
run builds its functions over the controls, so its time is the whole call, building
included. Prints a Markdown table: median wall times, their ratio, the controller's calls
and the largest difference of the joint angles between the two runs.
"""

from __future__ import annotations

import argparse
import os
import statistics
import tempfile
import time
from functools import partial
from pathlib import Path

import numpy as np

import casmech

ROOT = Path(__file__).resolve().parents[1]
PENDULUM = """
casmech: 1
name: pd_pendulum
gravity: [0, 0, -9.81]
bodies:
  - {name: bar, mass: 1.0, inertia: [0.1, 0.1, 0.01], position: [0.5, 0, 0]}
joints:
  - {name: pivot, type: revolute, body_i: ground, body_j: bar, at: [0, 0, 0], axis: [0, 1, 0],
     motor: {torque: LAW}}
analysis: {type: dynamics, t_end: 2, output_step: 0.01, rtol: 1e-8, atol: 1e-10}
"""


def double_pendulum() -> str:
    text = (ROOT / "models" / "double_pendulum.yaml").read_text()
    return text.replace("    axis: [0, 1, 0]\n", "    axis: [0, 1, 0]\n    motor: {torque: LAW}\n")


CASES = {"pendulum": (PENDULUM, ["pivot"]), "double_pendulum": (double_pendulum(),
                                                                 ["pivot", "elbow"])}


def timed(call, repeats: int) -> tuple[float, object]:
    times, result = [], None
    for _ in range(repeats):
        start = time.perf_counter()
        result = call()
        times.append(time.perf_counter() - start)
    return statistics.median(times), result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    os.environ.setdefault("CASMECH_CACHE_DIR", tempfile.mkdtemp(prefix="casmech-bench-"))
    print("| model | formulation | expression s | controller s | ratio | calls | max diff rad |")
    print("|---|---|---|---|---|---|---|")
    for name, (text, joints) in CASES.items():
        written = casmech.compile(
            casmech.loads(text.replace("LAW", "'-20*angle - 2*angle_dot'")), "interpreted")
        free = casmech.compile(casmech.loads(text.replace("LAW", "0")), "interpreted")

        def law(t, state, joints=joints):
            return {j: -20 * state[f"{j}.angle"] - 2 * state[f"{j}.angle_dot"] for j in joints}

        for formulation in ("joint", "rp"):
            casmech.analyze(written, formulation=formulation)  # built once, not timed
            expression, a = timed(partial(casmech.analyze, written, formulation=formulation),
                                  args.repeats)
            controlled, b = timed(partial(casmech.analyze, free, formulation=formulation,
                                          controller=law), args.repeats)
            diff = max(float(np.max(np.abs(a.to_dataframe()[f"{j}.angle"]
                                           - b.to_dataframe()[f"{j}.angle"]))) for j in joints)
            print(f"| {name} | {formulation} | {expression:.3f} | {controlled:.3f} | "
                  f"{controlled / expression:.1f} | {b.metadata['controller_calls']} | "
                  f"{diff:.1e} |")


if __name__ == "__main__":
    main()
