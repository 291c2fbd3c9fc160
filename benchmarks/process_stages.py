"""Where a whole `casmech run` process spends its CPU, stage by stage, without a profiler.

    python benchmarks/process_stages.py --chain 1000 --t-end 1            # this checkout's src/
    python benchmarks/process_stages.py --chain 1000 --t-end 1 --src /tmp/main/src --src src
    python benchmarks/process_stages.py --model models/four_bar.yaml --repeats 5
    python benchmarks/process_stages.py --chain 32 --t-end 10 --warm-compiled  # library cached

Each run is a fresh interpreter (PYTHONPATH=<src>) that starts casmech's command line as the
console script does (its garbage collector set as the tree's main() sets it), importing nothing
the run itself does not: each stage's module is wrapped as the run imports it (an import
hook), with thin wrappers reading the process's CPU clock (time.process_time) around its
stages: loading (cli.run._load: the model kept in the cache, else the file's load; api.
load_model: the file's load, 0 where the kept model is read), the joint system's build
(formulations.joint_system.build), assembly (runtime.assembly.initial_state), the analysis
(api.analyze) with DOP853 (runtime.dop853.Dop853.__call__) or CVODES/IDAS
(runtime.joint_dynamics._Integrator.__call__, whose counters, steps, right-hand sides,
Jacobians and linear setups, are read from the kept integrator), the results row's function
(runtime.results.row_function; row_call: a compiled bundle's loaded, else that one), the
results table with its evaluation (results.table, which includes row_call) and the results
files' writing (streaming flush, which includes the table and the CSV text, io.csv.rows_text).
The stages are printed by an atexit handler, which runs however the command line ends the
process; what the parent measures beyond it is the interpreter's start before casmech.cli and
the process's exit. The steps and rows are metadata.json's. A profiler's cost per Python call
inflates the Python-heavy stages several times over; these wrappers cost a few function calls
per stage. The parent times each child as a whole (wall, and user + sys from getrusage) and
prints medians (ranges) over --repeats runs, round-robin over the source trees so that a change
in the machine's load hits them alike.

`--chain N` writes benchmarks/systems.py's N-link chain through casmech_model.py with its
`t_end` set to --t-end (the generated 10 s span is the benchmark's), into a temporary folder;
the cache is a private folder kept over the runs (warm after the first run of each tree, which
is not timed).
"""

from __future__ import annotations

# (the child, the run's own process, imports nothing the run does not import: the rest is
# imported where the parent uses it)
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
# (label, module, attribute path) of each wrapped stage, in the order the table shows them
STAGES = (
    ("the command's module imported, its parser made (cli._parser)", "casmech.cli", "_parser"),
    ("load (cli.run._load: the kept model, else the file's load)", "casmech.cli.run", "_load"),
    ("load of the file (api.load_model; 0 where the kept model is read)", "casmech.api",
     "load_model"),
    ("validation (in load; the first builds the validators)", "casmech.schema.spec_errors",
     "validate"),
    ("model functions (api.compile)", "casmech.api", "compile"),
    ("joint system build", "casmech.formulations.joint_system", "build"),
    ("joint system build", "casmech.formulations.mapped_system", "build"),
    ("tree kernels (load or build)", "casmech.backends.tree_kernels", "for_tree"),
    ("joint system library (key, load or build)", "casmech.runtime.joint_dynamics",
     "compiled_system"),
    ("joint system library (key, load or build)", "casmech.runtime.joint_dynamics",
     "keyed_system"),
    ("assembly", "casmech.runtime.assembly", "initial_state"),
    ("analysis (api.analyze)", "casmech.api", "analyze"),
    ("DOP853 (in analysis)", "casmech.runtime.dop853", "Dop853.__call__"),
    ("integrator's call (joint_dynamics._Integrator.__call__: DOP853, CVODES or IDAS)",
     "casmech.runtime.joint_dynamics", "_Integrator.__call__"),
    ("results row function", "casmech.runtime.results", "row_function"),
    ("results row (loaded or built; incl. row function)", "casmech.runtime.results", "row_call"),
    ("results table (incl. row function)", "casmech.runtime.results", "table"),
    ("results writing (incl. table)", "casmech.io.streaming", "ResultsWriter.flush"),
    ("results text (in writing)", "casmech.io.csv", "rows_text"),
)
COUNTERS = ("nsteps", "nfevals", "nniters", "nlinsetups", "njevals", "netfails", "nncfails")


def child(arguments: list[str]) -> None:
    """Run `casmech <arguments>` here with the stages wrapped; print one JSON line.

    Each stage's module is wrapped as the run imports it (an import hook), so the process
    imports what the run imports, nothing more; the line is printed by an atexit handler,
    which runs however the command line ends the process (cli._leave, or the interpreter)."""
    import atexit

    start = time.process_time()
    spent: dict[str, float] = {"interpreter start (to the child's first line)": start}
    import casmech.cli

    _collector_as_the_command_line(casmech.cli)
    counters: dict[str, int] = {}

    def wrap(label: str, owner, name: str) -> None:
        function = getattr(owner, name)

        def timed(*args, **kwargs):
            begin = time.process_time()
            try:
                return function(*args, **kwargs)
            finally:
                spent[label] = spent.get(label, 0.0) + time.process_time() - begin
        setattr(owner, name, timed)

    def count(buffers) -> None:
        named_call = buffers.NamedCall.__call__

        def counted(self, **inputs):
            try:
                return named_call(self, **inputs)
            finally:
                if self.function.is_a("Integrator", True) or self.function.name() == "joint":
                    stats = self.stats()
                    for key in COUNTERS:
                        counters[key] = counters.get(key, 0) + int(stats.get(key) or 0)
        buffers.NamedCall.__call__ = counted

    def wrap_module(module) -> None:
        for label, name, path in STAGES:
            if name != module.__name__:
                continue
            owner = module
            *classes, attribute = path.split(".")
            for cls in classes:
                owner = getattr(owner, cls, None)
            if owner is not None and hasattr(owner, attribute):  # (a tree may not have it)
                wrap(label, owner, attribute)
        if module.__name__ == "casmech.runtime.buffers":
            count(module)

    wanted = {name for _, name, _ in STAGES} | {"casmech.runtime.buffers"}
    for name in wanted & set(sys.modules):
        wrap_module(sys.modules[name])
    sys.meta_path.insert(0, _WrapOnImport(wanted, wrap_module))
    spent["imports of casmech.cli"] = time.process_time() - start

    def report() -> None:
        spent["total (in process, to the atexit handlers)"] = time.process_time()
        import json

        print("STAGES " + json.dumps({"stages": spent, "counters": counters}), flush=True)
    atexit.register(report)
    sys.argv = ["casmech", *arguments]
    try:
        code = casmech.cli.main()  # (an error is an exit code, as the console script's)
        if code:
            raise SystemExit(code)
    except SystemExit as exit_:
        if exit_.code not in (0, None):
            raise


class _WrapOnImport:
    """A finder in front of sys.meta_path that lets the others find the modules `wanted` and
    calls `then(module)` once each has run, before its importer reads a name of it."""

    def __init__(self, wanted: set[str], then) -> None:
        self.wanted, self.then = wanted, then

    def find_spec(self, name, path, target=None):
        if name not in self.wanted:
            return None
        for finder in sys.meta_path:
            found = finder is not self and getattr(finder, "find_spec", None)
            spec = found(name, path, target) if found else None
            if spec is not None:
                break
        else:
            return None
        run, then = spec.loader.exec_module, self.then

        def exec_module(module):
            run(module)
            then(module)
        spec.loader.exec_module = exec_module
        return spec


def _collector_as_the_command_line(cli) -> None:
    """The garbage collector as the tree's own `main()` sets it first thing (held until the
    analysis, cli.collector), or the young generation's threshold of older trees."""
    import gc

    collector = getattr(cli, "collector", None)
    if collector is not None:
        collector.hold()
    elif hasattr(cli, "YOUNG_OBJECTS"):
        gc.set_threshold(cli.YOUNG_OBJECTS, *gc.get_threshold()[1:])


def chain_model(n: int, t_end: float, folder):
    import re

    sys.path.insert(0, HERE)
    from casmech_model import yaml_text
    from systems import chain

    text = re.sub(r"t_end: [0-9.e+-]+", f"t_end: {t_end!r}", yaml_text(chain(n)), count=1)
    path = folder / f"chain{n}.yaml"
    path.write_text(text)
    return path


def timed_child(src: str, model, arguments: list[str], environment: dict) -> dict:
    """The child's stages, its whole process's CPU and wall, and its metadata.json's steps
    and rows."""
    import json
    import resource
    import subprocess
    from pathlib import Path

    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    begin = time.perf_counter()
    done = subprocess.run([sys.executable, __file__, "--child", "--", "run", str(model),
                           *arguments], env=environment | {"PYTHONPATH": src},
                          capture_output=True, text=True, cwd=model.parent)
    wall = time.perf_counter() - begin
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode:
        raise SystemExit(f"{src}: casmech run failed\n{done.stderr[-2000:]}")
    line = next(x for x in done.stdout.splitlines() + done.stderr.splitlines()
                if x.startswith("STAGES "))
    found = json.loads(line[len("STAGES "):])
    found["wall"] = wall
    found["cpu"] = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    out = Path(arguments[len(arguments) - 1 - arguments[::-1].index("--out") + 1])
    metadata = json.loads((out / "metadata.json").read_text())
    found["steps"] = (metadata.get("result") or {}).get("steps") or 0
    found["rows"] = metadata.get("rows") or 0
    return found


def median(values: list[float]) -> str:
    """Median (range) in milliseconds."""
    import statistics

    ms = [1000 * value for value in values]
    return f"{statistics.median(ms):.1f} ({min(ms):.1f}-{max(ms):.1f})"


def main() -> None:
    if "--child" in sys.argv:
        child(sys.argv[sys.argv.index("--") + 1:])
        return
    import argparse
    import statistics
    import tempfile
    from pathlib import Path

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    which = parser.add_mutually_exclusive_group(required=True)
    which.add_argument("--model", type=Path, help="a YAML model")
    which.add_argument("--chain", type=int, help="benchmarks/systems.py's N-link chain")
    parser.add_argument("--t-end", type=float, default=1.0)
    parser.add_argument("--src", action="append", help="source trees (default: ./src)")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--warm-compiled", action="store_true",
                        help="warm the cache with `--mode compiled` (the timed runs keep the "
                             "default mode, which then finds the model's library cached)")
    options, extra = parser.parse_known_args()
    sources = [str(Path(s).resolve()) for s in (options.src or ["src"])]
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        model = (chain_model(options.chain, options.t_end, folder) if options.chain
                 else options.model.resolve())
        arguments = ["--t-end", repr(options.t_end), "-q", "--out",
                     str(folder / "results"), *extra]
        environment = os.environ | {"CASMECH_CACHE_DIR": str(folder / "cache")}
        warm = ["--mode", "compiled"] if options.warm_compiled else []
        for src in sources:  # warm the cache and the bytecode
            timed_child(src, model, [*arguments, *warm], environment)
        runs: dict[str, list[dict]] = {src: [] for src in sources}
        for _ in range(options.repeats):
            for src in sources:
                runs[src].append(timed_child(src, model, arguments, environment))
    print(f"# {model.name}, `casmech run --t-end {options.t_end}`, {options.repeats} runs "
          f"each, {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, load average "
          f"{os.getloadavg()[0]:.1f}; CPU milliseconds, medians (ranges)\n")
    print("| stage | " + " | ".join(sources) + " |")
    print("|---|" + "---:|" * len(sources))
    labels = ["interpreter start (to the child's first line)", "imports of casmech.cli",
              *dict.fromkeys(label for label, _, _ in STAGES),
              "total (in process, to the atexit handlers)"]
    for label in labels:
        print(f"| {label} | " + " | ".join(
            median([r["stages"].get(label, 0.0) for r in runs[s]]) for s in sources) + " |")
    total = "total (in process, to the atexit handlers)"
    print("| the exit, after the atexit handlers (whole process less the total) | " + " | ".join(
        median([r["cpu"] - r["stages"][total] for r in runs[s]]) for s in sources) + " |")
    for key in ("cpu", "wall"):
        name = {"cpu": "whole process, user + sys", "wall": "whole process, wall"}[key]
        print(f"| {name} | " + " | ".join(median([r[key] for r in runs[s]])
                                          for s in sources) + " |")
    for key in ("steps", "rows"):
        print(f"| {key} (metadata.json) | " + " | ".join(
            str(int(statistics.median([r[key] for r in runs[s]]))) for s in sources) + " |")
    for key in COUNTERS:
        print(f"| integrator {key} | " + " | ".join(
            str(int(statistics.median([r["counters"].get(key, 0) for r in runs[s]])))
            for s in sources) + " |")


if __name__ == "__main__":
    main()
