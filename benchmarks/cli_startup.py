"""Start-up of the `casmech` command line, timed as whole processes (issue 21: `casmech check` of
a gallery model <= 0.5 s, `casmech run models/me751_pendulum.yaml` <= 1 s with a warm cache).

    python benchmarks/cli_startup.py                      # this checkout's src/, 7 repeats
    python benchmarks/cli_startup.py --src /work/main/src --src src    # before/after, one run

Every command runs as the console script does (`from casmech.cli import main`) in a fresh
interpreter with PYTHONPATH=<src>, round-robin over commands and source trees so that a change in
the machine's load hits all of them alike. Reported: the median wall time and the median CPU time
(user + sys of the child, less sensitive to other processes on a shared machine) over
`--repeats` runs, after one untimed warm-up of each command (it writes the bytecode cache and
fills the OS file cache). Floors in the same run: `python -c pass` and `python -c "import
casadi"`.

Bytecode is cached in a private folder (PYTHONPYCACHEPREFIX), as after `pip install`, which
byte-compiles; the row "check, no bytecode" shows the cost without: PYTHONDONTWRITEBYTECODE=1
and no prefix, as in an editable install where .pyc files may not be written (casmech's modules
are compiled on every run unless the source tree holds __pycache__ folders; the libraries'
bytecode in site-packages is used).

`run`, warm cache: CASMECH_CACHE_DIR holds the model's compiled library (built once before the
timing by `casmech run --mode compiled`), so `--mode auto` loads it. Cold cache: an empty cache
directory per run, where `--mode auto` runs interpreted (it builds no library for a small model).
"""

from __future__ import annotations

import argparse
import os
import platform
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from datetime import datetime, timezone
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MODELS = ROOT / "models"
CHECK_MODELS = ("four_bar", "double_pendulum", "quadruped_legs")
CONSOLE = "import sys; from casmech.cli import main; sys.exit(main())"  # the console script


def interpreter(*args: str) -> list[str]:
    return [sys.executable, *args]


def casmech(*args: str) -> list[str]:
    return interpreter("-c", CONSOLE, *map(str, args))


def cases(models: list[str], work: Path) -> list[tuple[str, list[str], dict]]:
    """(label, command, extra environment); `{cache}` and `{out}` are filled in per run."""
    pendulum = MODELS / "me751_pendulum.yaml"
    rows = [("python -c pass", interpreter("-c", "pass"), {}),
            ('python -c "import casadi"', interpreter("-c", "import casadi"), {}),
            ("casmech --help", casmech("--help"), {})]
    rows += [(f"casmech check {name}", casmech("check", MODELS / f"{name}.yaml"), {})
             for name in models]
    rows += [(f"casmech check {models[0]}, no bytecode",
              casmech("check", MODELS / f"{models[0]}.yaml"),
              {"PYTHONDONTWRITEBYTECODE": "1", "PYTHONPYCACHEPREFIX": None})]
    rows += [("casmech run me751_pendulum, warm cache", casmech("run", pendulum, "--out", "{out}"),
              {"CASMECH_CACHE_DIR": str(work / "warm")}),
             ("casmech run me751_pendulum, cold cache",
              casmech("run", pendulum, "--out", "{out}"), {"CASMECH_CACHE_DIR": "{cache}"})]
    return rows


def environment(src: Path, work: Path, extra: dict, run: int) -> dict:
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    env.update(PYTHONPATH=str(src), PYTHONPYCACHEPREFIX=str(work / "pycache"),
               CASMECH_CACHE_DIR=str(work / "default-cache"))
    env.update({k: v.format(cache=work / f"cold-{run}") for k, v in extra.items() if v})
    return {k: v for k, v in env.items() if extra.get(k, "") is not None}  # None: unset


def timed(command: list[str], env: dict, out: Path) -> tuple[float, float]:
    """(wall, CPU user + sys) of one process, in seconds."""
    command = [arg.format(out=out) if isinstance(arg, str) else arg for arg in command]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    done = subprocess.run(command, env=env, capture_output=True, text=True, timeout=600)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(command)} failed ({done.returncode}):\n{done.stderr}")
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def warm_cache(src: Path, work: Path) -> None:
    """Build the pendulum's compiled library into the warm cache (not timed)."""
    env = environment(src, work, {"CASMECH_CACHE_DIR": str(work / "warm")}, 0)
    timed(casmech("run", MODELS / "me751_pendulum.yaml", "--mode", "compiled", "--out",
                  "{out}"), env, work / "out")


def measure(sources: list[Path], models: list[str], repeats: int) -> dict:
    """{(label, src index): [(wall, cpu), ...]}"""
    samples: dict = {}
    with tempfile.TemporaryDirectory(prefix="cli-startup-") as folder:
        works = [Path(folder) / str(k) for k in range(len(sources))]
        for src, work in zip(sources, works, strict=True):
            warm_cache(src, work)
        for run in range(repeats + 1):  # run 0: warm-up, not recorded
            for k, (src, work) in enumerate(zip(sources, works, strict=True)):
                for label, command, extra in cases(models, work):
                    sample = timed(command, environment(src, work, extra, run), work / "out")
                    if run:
                        samples.setdefault((label, k), []).append(sample)
    return {"rows": [label for label, _, _ in cases(models, Path())], "samples": samples}


def describe(src: Path) -> str:
    """The commit of a source tree's checkout, + when it has uncommitted changes."""
    commit = git_at(src, "rev-parse", "--short", "HEAD")
    dirty = git_at(src, "status", "--porcelain", "--", str(src))
    return f"{commit}{'+' if dirty not in ('', '?') else ''}"


def git_at(src: Path, *args: str) -> str:
    try:
        return subprocess.run(["git", "-C", str(src), *args], capture_output=True, text=True,
                              check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "?"


def machine() -> str:
    cpu = platform.processor() or platform.machine()
    try:
        names = [line.split(":", 1)[1].strip() for line in Path("/proc/cpuinfo").read_text()
                 .splitlines() if line.startswith("model name")]
        cpu = names[0] if names else cpu
    except OSError:
        pass
    load = " ".join(f"{x:.2f}" for x in os.getloadavg())
    return f"{cpu}, {os.cpu_count()} cores, load average {load} at the end"


def table(result: dict, sources: list[Path], repeats: int) -> str:
    import casadi  # versions for the header only

    heads = [f"{src} @ {describe(src)}" for src in sources]
    lines = [
        f"Machine: {machine()}; Python {platform.python_version()}, casadi "
        f"{casadi.__version__}; date {datetime.now(timezone.utc):%Y-%m-%d %H:%M} UTC; commit "
        f"{describe(sources[-1])}. Median of {repeats} runs after one warm-up; wall / CPU "
        "(user + sys) seconds.", "",
        "| command | " + " | ".join(heads) + " |",
        "|---|" + "---|" * len(sources)]
    for label in result["rows"]:
        cells = []
        for k in range(len(sources)):
            walls, cpus = zip(*result["samples"][(label, k)], strict=True)
            cells.append(f"{statistics.median(walls):.3f} / {statistics.median(cpus):.3f}")
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--src", action="append", type=Path,
                        help="casmech source tree(s) to time, side by side (default: ./src)")
    parser.add_argument("--models", nargs="+", default=list(CHECK_MODELS),
                        help="gallery models for `casmech check` (names in models/)")
    parser.add_argument("--repeats", type=int, default=7, help="timed runs per command (>= 5)")
    args = parser.parse_args()
    sources = [path.resolve() for path in (args.src or [ROOT / "src"])]
    result = measure(sources, args.models, args.repeats)
    print(table(result, sources, args.repeats))


if __name__ == "__main__":
    main()
