"""The joint space's NumPy calls as a user makes them (`space.forward_dynamics(q, v, tau)`,
`space.forward_dynamics_derivatives(q, v, tau)`: casmech.joint_space's SX functions through
buffers, runtime.joint_space_calls; "compiled": the space of the model compiled with mode
"compiled", its functions in C, backends.joint_space_library, each built on its first call,
timed) and as CasADi's own call of the same functions, against
Pinocchio's Python calls (`pin.aba`, `pin.computeABADerivatives`), on the robots of
joint_derivatives.py (issue 36).

    python benchmarks/joint_space_calls.py --robots ur5 talos_arm --repeats 11

Each timing is the thread's CPU time of a batch of --calls calls; the batches alternate in
one process, --repeats times; the table shows medians per call and the ratios to Pinocchio.
Needs `pin` and `example-robot-data` (pip install ".[bench]").
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from joint_derivatives import ROBOTS, load, per_call, pinocchio_state  # noqa: E402


def measure(name: str, workdir: Path, repeats: int, calls: int) -> list[str]:
    import pinocchio as pin

    import casmech

    space, model = load(name, workdir, stops=False)
    plain = replace(space, calls=None)  # CasADi's own call of the same functions
    data = model.createData()
    rng = np.random.default_rng(7)
    (q, v, tau), (q_pin, v_pin, tau_pin), _ = pinocchio_state(model, space, rng)
    # the space of the model compiled with mode "compiled": its two functions built here, into
    # an empty cache (backends.joint_space_library)
    os.environ["CASMECH_CACHE_DIR"] = str(workdir / f"{name}_cache")
    compiled = casmech.joint_space(casmech.compile(casmech.load(workdir / f"{name}.yaml"),
                                                   "compiled"))
    builds = []
    for call in (compiled.forward_dynamics, compiled.forward_dynamics_derivatives):
        start = time.perf_counter()
        call(q, v, tau)
        builds.append(time.perf_counter() - start)
    candidates = {
        ("rhs", "casmech"): lambda: space.forward_dynamics(q, v, tau),
        ("rhs", "casmech compiled"): lambda: compiled.forward_dynamics(q, v, tau),
        ("rhs", "casadi call"): lambda: plain.forward_dynamics(q, v, tau),
        ("rhs", "Pinocchio"): lambda: pin.aba(model, data, q_pin, v_pin, tau_pin),
        ("Jacobian", "casmech"): lambda: space.forward_dynamics_derivatives(q, v, tau),
        ("Jacobian", "casmech compiled"): lambda: compiled.forward_dynamics_derivatives(
            q, v, tau),
        ("Jacobian", "casadi call"): lambda: plain.forward_dynamics_derivatives(q, v, tau),
        ("Jacobian", "Pinocchio"): lambda: pin.computeABADerivatives(
            model, data, q_pin, v_pin, tau_pin),
    }
    times: dict = {key: [] for key in candidates}
    for _ in range(repeats):
        for key, call in candidates.items():
            times[key].append(per_call(call, calls))
    rows = []
    for what, build in zip(("rhs", "Jacobian"), builds, strict=True):
        peer = statistics.median(times[what, "Pinocchio"])
        for who in ("casmech", "casmech compiled", "casadi call"):
            mine = statistics.median(times[what, who])
            built = f"{build:.1f}" if who == "casmech compiled" else ""
            rows.append(f"| {name} | {what} | {who} | {1e6 * mine:.2f} | {1e6 * peer:.2f} | "
                        f"{mine / peer:.2f} | {built} |")
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--robots", nargs="+", choices=sorted(ROBOTS), default=sorted(ROBOTS))
    parser.add_argument("--repeats", type=int, default=11)
    parser.add_argument("--calls", type=int, default=500)
    options = parser.parse_args()
    print("| robot | what | call | casmech us | Pinocchio us | ratio | first call s (build) |")
    print("|---|---|---|---:|---:|---:|---:|")
    with tempfile.TemporaryDirectory() as folder:
        for name in options.robots:
            for row in measure(name, Path(folder), options.repeats, options.calls):
                print(row, flush=True)


if __name__ == "__main__":
    main()
