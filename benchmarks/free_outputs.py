"""How many output steps of method auto's bounded DOP853 take the Hermite pair's outputs
(runtime.dop853's free_outputs), by threshold, with the evaluations and the error of q over the
grid against DOP853 at rtol 1e-12: robots.py's robots (its state, seed 36, no stops), compiled.

    python benchmarks/free_outputs.py talos_arm panda --rtols 3e-4 1e-5 --thresholds 0 0.3 1
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import robots  # noqa: E402


def main() -> None:
    os.environ["CASMECH_BACKGROUND_BUILD"] = "0"
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("robots", nargs="+", choices=list(robots.URDFS))
    parser.add_argument("--rtols", nargs="+", type=float, default=[1e-3, 3e-4, 1e-5, 1e-7])
    parser.add_argument("--thresholds", nargs="+", type=float, default=[0.0, 0.1, 0.3, 1.0])
    parser.add_argument("--folder", type=Path, default=Path("/tmp/free_outputs"))
    args = parser.parse_args()
    os.environ["CASMECH_ALLOWED_DIRS"] = str(robots.robots_folder())
    import casmech
    from casmech.runtime import dop853, workspace

    print("| robot | rtol | threshold | steps (rejected) | evaluations | pair's output steps "
          "| max abs q error |\n|---|---:|---:|---:|---:|---:|---:|")
    for name in args.robots:
        folder = args.folder / name
        folder.mkdir(parents=True, exist_ok=True)
        robot = robots.Robot(name, folder)
        q0, v0 = robot.draw_state(np.random.default_rng(36))
        model = casmech.load(robot.write_casmech(q0, v0, stops=False))
        reference = casmech.analyze(casmech.compile(model, "compiled"), "dynamics", t_end=1.0,
                                    rtol=1e-12, atol=1e-14, method="dop853")
        for rtol in args.rtols:
            for threshold in args.thresholds:
                dop853.HERMITE_BELOW = threshold
                functions = casmech.compile(model, "compiled")  # its own workspace
                result = casmech.analyze(functions, "dynamics", t_end=1.0, rtol=rtol,
                                         atol=rtol / 100)
                rk = list(workspace.default(functions).store("dop853").values())[-1]
                s = rk.last
                print(f"| {name} | {rtol:g} | {threshold:g} | {s.accepted} ({s.rejected}) | "
                      f"{s.evaluations} | {s.hermite} | "
                      f"{np.abs(result.q - reference.q).max():.2g} |", flush=True)


if __name__ == "__main__":
    main()
