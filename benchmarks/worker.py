"""One tool, one system, one setting, in its own process (run.py starts it, so that a slow run
can be stopped and the tools do not share a process): builds the model, runs the simulation
`--repeats` times and prints one JSON line per event on stdout.

    python benchmarks/worker.py casmech chain8 '{"rtol": 1e-10, "atol": 1e-12}' --repeats 3

Runs shorter than SHORT seconds are repeated at least SHORT_REPEATS times after one untimed
warm-up run."""

from __future__ import annotations

import argparse
import json
import platform
import sys
import time
import traceback

from systems import T_END, make

SHORT = 1.0  # s
SHORT_REPEATS = 7


def runner(tool: str, system):
    if tool.startswith("casmech"):
        from casmech_model import TOOLS, Runner

        return Runner(system, **TOOLS[tool])
    if tool == "casadi-script":
        from casadi_script import Runner

        return Runner(system)
    if tool in ("exudyn", "exudyn-fast"):  # run.py sets EXUDYN_MODULE=fast for exudyn-fast
        from exudyn_model import Runner
    elif tool == "mujoco":
        from mujoco_model import Runner
    else:
        raise ValueError(f"unknown tool {tool!r}")
    return Runner(system)


def emit(**event) -> None:
    print(json.dumps(event), flush=True)


def versions(tool: str) -> dict:
    out = {"python": platform.python_version()}
    if tool.startswith("casmech") or tool == "casadi-script":
        import casadi

        import casmech

        out.update(casadi=casadi.__version__, casmech_file=casmech.__file__)
    elif tool.startswith("exudyn"):
        import exudyn

        out.update(exudyn=exudyn.__version__)
    elif tool == "mujoco":
        import mujoco

        out.update(mujoco=mujoco.__version__)
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("tool")
    parser.add_argument("system")
    parser.add_argument("setting", help="JSON object, e.g. '{\"h\": 0.001}'")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--t-end", type=float, default=T_END)
    args = parser.parse_args(argv)
    setting = json.loads(args.setting)
    try:
        start = time.perf_counter()
        run = runner(args.tool, make(args.system))
        if args.tool == "mujoco":  # MuJoCo compiles per time step: build it here, timed
            run.model(setting["timestep"], setting.get("solref"))
        emit(event="build", seconds=time.perf_counter() - start, parts=run.build_time,
             versions=versions(args.tool))
        repeats, k = args.repeats, 0
        while k < repeats:
            out = run.run(setting, t_end=args.t_end)
            if k == 0 and out["wall"] < SHORT and repeats > 1:
                emit(event="warmup", wall=out["wall"])
                repeats = max(repeats, SHORT_REPEATS)
                out = run.run(setting, t_end=args.t_end)
            emit(event="run", wall=out["wall"], cpu=out.get("cpu"),
                 points=out["points"].tolist(), extra=out["extra"])
            k += 1
    except Exception as error:  # reported to run.py, which records it as the outcome
        emit(event="error", message=f"{type(error).__name__}: {error}",
             traceback=traceback.format_exc())
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
