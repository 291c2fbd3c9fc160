"""End to end: the `casmech` console script on model files (exit codes, results contract)."""

import contextlib
import gc
import io
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from casmech.cli import _parser, main
from casmech.cli.collector import YOUNG_OBJECTS
from casmech.cli.commands import COMMANDS
from casmech.io.csv import read_csv
from tests.conftest import MODELS, ROOT

SCRIPT = Path(sys.executable).parent / "casmech"  # where pip installs the console script

BODY = ["x", "y", "z", "e0", "e1", "e2", "e3", "vx", "vy", "vz", "wx", "wy", "wz",
        "ax", "ay", "az", "alphax", "alphay", "alphaz"]
JOINT = ["fx", "fy", "fz", "tx", "ty", "tz"]


def casmech(*args, cwd=None):
    return subprocess.run([str(SCRIPT), *map(str, args)], capture_output=True, text=True,
                          cwd=cwd, timeout=300)


# each joint type's state columns, in the order docs/format.md's results contract lists them
STATES = {"revolute": ["angle", "angle_dot"], "translational": ["displacement", "displacement_dot"],
          "universal": ["angle_i", "angle_i_dot", "angle_j", "angle_j_dot"],
          "spherical": ["e0", "e1", "e2", "e3", "wx", "wy", "wz"]}


def contract_columns(bodies, joints, types=()):
    """The column order written in the results contract of docs/format.md (`types`: each
    joint's type, for its joint-state columns after the contract's first ones)."""
    return (["t"] + [f"{b}.{c}" for b in bodies for c in BODY]
            + [f"{j}.{c}" for j in joints for c in JOINT] + ["energy", "constraint_violation"]
            + [f"{j}.{c}" for j, kind in zip(joints, types, strict=False)
               for c in STATES.get(kind, [])])


def test_run_writes_results_per_contract(tmp_path):
    done = casmech("run", MODELS / "slider_crank.yaml", "--out", tmp_path, "--t-end", "0.5")
    assert done.returncode == 0, done.stderr
    names, values = read_csv(tmp_path / "results.csv")
    assert names == contract_columns(["crank", "rod", "slider"],
                                     ["crank_pivot", "crank_pin", "wrist_pin", "slide"],
                                     ["revolute", "spherical", "universal", "translational"])
    # default output_step 0.01 from the model; --t-end overrides t_end
    np.testing.assert_allclose(values[:, 0], np.linspace(0, 0.5, 51), rtol=0, atol=1e-12)
    assert np.all(np.isfinite(values))


def test_run_default_output_directory_beside_model(tmp_path):
    model = tmp_path / "pendulum.yaml"
    model.write_text((MODELS / "me751_pendulum.yaml").read_text())
    done = casmech("run", model, "--t-end", "0.1", "--set", "L=3.0")
    assert done.returncode == 0, done.stderr
    names, values = read_csv(tmp_path / "pendulum_results" / "results.csv")
    # --set L=3 moves the CM to L/2 = 1.5 from the pivot
    radius = np.hypot(values[:, names.index("bar.y")], values[:, names.index("bar.z")])
    np.testing.assert_allclose(radius, 1.5, rtol=0, atol=1e-10)  # Newton tolerance 1e-12


def test_check_reports_dof(tmp_path):
    done = casmech("check", MODELS / "four_bar.yaml")
    assert done.returncode == 0, done.stderr
    assert "degrees of freedom: 0" in done.stdout
    assert "redundant" not in done.stdout


def test_check_reports_redundant_rows_by_joint_and_line(tmp_path):
    model = tmp_path / "redundant.yaml"
    text = (MODELS / "me751_pendulum.yaml").read_text()
    extra = ("  - name: second_pivot\n    type: revolute\n    body_i: ground\n    body_j: bar\n"
             "    at: [0, 0, 0]\n    axis: [1, 0, 0]\n")
    model.write_text(text.replace("\nanalysis:", extra + "\nanalysis:"))
    line = 1 + model.read_text().splitlines().index("  - name: second_pivot")
    done = casmech("check", model)
    assert done.returncode == 0, done.stderr
    assert f"redundant.yaml:{line}:" in done.stdout
    assert "warning[E500] second_pivot" in done.stdout
    assert done.stdout.count("warning[E500]") == 5  # a second revolute repeats all 5 rows


def test_model_error_exit_1_with_location(tmp_path):
    model = tmp_path / "bad.yaml"
    model.write_text((MODELS / "me751_pendulum.yaml").read_text().replace("mass: m", "mass: -m"))
    done = casmech("run", model)
    assert done.returncode == 1
    line = 1 + model.read_text().splitlines().index("    mass: -m")
    assert f"bad.yaml:{line}:" in done.stderr and "error[E400]" in done.stderr
    assert "Traceback" not in done.stderr


def test_usage_error_exit_2(tmp_path):
    assert casmech("run", MODELS / "me751_pendulum.yaml", "--set", "L").returncode == 2
    assert casmech("frobnicate").returncode == 2
    missing = casmech("run", tmp_path / "missing.yaml")
    assert missing.returncode == 2 and "no such file" in missing.stderr


@pytest.mark.parametrize("analysis", ["kinematics", "inverse_dynamics"])
def test_not_fully_driven_exit_1(tmp_path, analysis):
    model = tmp_path / "free.yaml"
    model.write_text((MODELS / "me751_pendulum.yaml").read_text()
                     .replace("    driver:\n      angle: pi/4 * cos(2*t)\n", ""))
    done = casmech("run", model, "--analysis", analysis)
    assert done.returncode == 1
    line = 1 + model.read_text().splitlines().index("  type: inverse_dynamics")
    assert f"free.yaml:{line}:" in done.stderr
    assert f"error[E501] analysis.type: {analysis} needs a fully driven" in done.stderr
    assert "1 degree(s) of freedom" in done.stderr


def test_analysis_failure_exit_3_keeps_rows(tmp_path):
    """A four-bar whose crank is too long to turn fully (a = 1.6 with b = 2, c = 1.5, d = 2)
    reaches its toggle position when |B O4| = b + c, i.e. cos(theta) = (d^2 + a^2 - (b + c)^2)
    / (2 a d): theta = 152.7 deg, t = (152.7 - 90) / 180 s = 0.348 s at omega = pi. The run must
    stop there with exit 3, name the time and joints, and keep the rows computed before."""
    theta = np.degrees(np.arccos((2.0**2 + 1.6**2 - 3.5**2) / (2 * 1.6 * 2.0)))
    t_toggle = (theta - 90.0) / 180.0
    done = casmech("run", MODELS / "four_bar.yaml", "--set", "a=1.6", "--out", tmp_path,
                   "--analysis", "kinematics")
    assert done.returncode == 3, done.stderr
    assert "analysis failed at t = " in done.stderr and "joint '" in done.stderr
    failed_at = float(done.stderr.split("analysis failed at t = ")[1].split(":")[0])
    assert t_toggle - 0.02 <= failed_at <= t_toggle + 0.02  # within two output steps
    names, values = read_csv(tmp_path / "results.csv")
    assert len(values) >= 30 and values[-1, 0] < t_toggle


def test_run_tolerances_from_the_command_line(tmp_path):
    """--rtol/--atol override the model's: a loose run of the A01 pendulum lands farther from
    the tight one than the tight one's own error, and a non-positive tolerance is a usage error."""
    model = MODELS / "validation" / "iftomm_a01_pendulum.yaml"
    runs = {}
    for rtol in ("1e-4", "1e-10"):
        out = tmp_path / rtol
        done = casmech("run", model, "--out", out, "--t-end", "1", "--rtol", rtol,
                       "--atol", "1e-8" if rtol == "1e-4" else "1e-12")
        assert done.returncode == 0, done.stderr
        runs[rtol] = read_csv(out / "results.csv")
    names, loose = runs["1e-4"]
    _, tight = runs["1e-10"]
    x = names.index("mass.x")
    # a 1e-4 run is off by far more than 1e-6 m (measured ~1e-4); the tight one is within 1e-7
    assert np.max(np.abs(loose[:, x] - tight[:, x])) > 1e-6
    done = casmech("run", model, "--out", tmp_path / "bad", "--rtol", "0")
    assert done.returncode == 2 and "rtol must be positive" in done.stderr


# What start-up must not pay for (issue 21; benchmarks/cli_startup.py times the processes): the
# optional heavy libraries, and the parts of casmech a command does not use. Checked on the
# modules a fresh interpreter holds after the command, so a regression fails without a timing.
OPTIONAL = ("matplotlib", "meshio", "h5py", "tqdm", "scipy", "pandas", "jsonschema")
PROBE = """
import json, sys
from casmech import cli
try:
    code = cli.main(sys.argv[2:])
except SystemExit as exit:
    code = exit.code
with open(sys.argv[1], "w") as handle:
    json.dump({"code": code, "modules": sorted(sys.modules)}, handle)
"""


def imported(tmp_path, *args) -> set[str]:
    """The modules a fresh interpreter has imported once `casmech ARGS` is done."""
    report = tmp_path / "modules.json"
    done = subprocess.run([sys.executable, "-c", PROBE, str(report), *map(str, args)],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    probe = json.loads(report.read_text())
    assert probe["code"] in (0, None), done.stderr
    return set(probe["modules"])


def loaded(modules: set[str], packages) -> list[str]:
    return sorted(m for m in modules for p in packages if m == p or m.startswith(p + "."))


def test_help_imports_no_library(tmp_path):
    modules = imported(tmp_path, "--help")
    assert "casmech.cli" in modules  # the probe sees what the command imported
    assert loaded(modules, [*OPTIONAL, "casadi", "numpy", "pydantic", "yaml", "casmech.api",
                            "casmech.schema", "casmech.cli.run"]) == []


def test_check_imports_what_checking_needs(tmp_path):
    modules = imported(tmp_path, "check", MODELS / "four_bar.yaml")
    assert {"casadi", "pydantic", "casmech.schema", "casmech.cli.check"} <= modules
    # code generation (casmech.backends' modules; the package itself only picks the backend)
    generation = [m for m in modules if m.startswith("casmech.backends.")]
    assert loaded(modules, [*OPTIONAL, *generation, "casmech.optimal", "casmech.importers",
                            "casmech.io"]) == []
    assert generation == []


def test_run_imports_no_optional_library(tmp_path):
    modules = imported(tmp_path, "run", MODELS / "me751_pendulum.yaml", "--t-end", "0.05",
                       "--out", tmp_path / "out", "--mode", "interpreted")
    assert (tmp_path / "out" / "results.csv").is_file()
    # tqdm too: the probe's stderr is not a terminal, so no progress bar is drawn
    assert loaded(modules, [*OPTIONAL, "casmech.optimal", "casmech.importers",
                            "casmech.io.plot", "casmech.io.animate"]) == []


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_command_help_imports_no_optional_library(tmp_path, command):
    modules = imported(tmp_path, command, "--help")
    assert f"casmech.cli.{COMMANDS[command][0]}" in modules
    others = [f"casmech.cli.{module}" for name, (module, _) in COMMANDS.items()
              if name != command]
    assert loaded(modules, [*OPTIONAL, *others]) == []


CYCLES = """
import importlib, json, pkgutil, sys
import casmech
names = sorted(m.name for m in pkgutil.walk_packages(casmech.__path__, "casmech.")
               if not m.name.endswith(".__main__"))  # running the command line
shard, shards = int(sys.argv[1]), int(sys.argv[2])
failed = {}
for name in names[shard::shards]:
    for loaded in [m for m in sys.modules if m == "casmech" or m.startswith("casmech.")]:
        del sys.modules[loaded]
    try:
        importlib.import_module(name)
    except ImportError as error:
        failed[name] = str(error)
print(json.dumps({"modules": len(names), "failed": failed}))
"""


def test_every_module_imports_first():
    """Each casmech module imports as the first casmech module of a process: with imports
    deferred to first use, no import order hides a cycle (model.ir -> schema.resolved ->
    schema -> ... -> model.ir failed this way)."""
    shards = 2  # processes side by side, each importing every second module first
    running = [subprocess.Popen([sys.executable, "-c", CYCLES, str(k), str(shards)],
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
               for k in range(shards)]
    reports = []
    for process in running:
        out, err = process.communicate(timeout=300)
        assert process.returncode == 0, err
        reports.append(json.loads(out))
    assert {report["modules"] for report in reports} == {reports[0]["modules"]}
    assert reports[0]["modules"] > 50  # walked the whole package
    assert [report["failed"] for report in reports] == [{}] * shards


@pytest.mark.parametrize("variable, given, expected", [
    ("OPENBLAS_NUM_THREADS", None, "1"), ("OPENBLAS_NUM_THREADS", "2", "2"),
    ("PYDANTIC_DISABLE_PLUGINS", None, "__all__"),
    ("PYDANTIC_DISABLE_PLUGINS", "logfire", "logfire")])
def test_the_command_lines_environment_unless_the_user_chose(variable, given, expected):
    """Importing the command line sets one BLAS thread (before NumPy loads) and turns
    pydantic's plugin lookup off, unless the user set the variable."""
    env = {k: v for k, v in os.environ.items() if k != variable}
    if given is not None:
        env[variable] = given
    env["PYTHONPATH"] = str(ROOT / "src")
    code = ("import os, sys; import casmech.cli; assert 'numpy' not in sys.modules; "
            f"print(os.environ[{variable!r}])")
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         check=True, timeout=60).stdout
    assert out.strip() == expected


def _parsed(parser, argv: list[str]) -> tuple:
    """What parsing `argv` prints and ends with (exit code, or the namespace)."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            result = vars(parser.parse_args(argv))
        except SystemExit as stop:
            result = stop.code
    return result, out.getvalue(), err.getvalue()


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_a_command_given_first_parses_as_with_every_command(command):
    """`casmech COMMAND ...` makes the parser of that command alone (cli._parser): its help,
    usage errors and parsed arguments are those of the parser holding every command (made
    when an option comes first)."""
    alone, _ = _parser([command])
    every, _ = _parser(["--version", command])
    assert len(every._subparsers._group_actions[0].choices) == len(COMMANDS) > 1
    assert list(alone._subparsers._group_actions[0].choices) == [command]
    for argv in ([command, "--help"], [command], [command, "--bogus"],
                 [command, "model.yaml", "--bogus", "1"], [command, "model.yaml", "--version"],
                 [command, "a.yaml", "b.csv"]):
        assert _parsed(alone, argv) == _parsed(every, argv), argv


PLUGINS = """
import sys
from casmech.cli import _parser, main
assert main(["check", sys.argv[1]]) == 0
from pydantic.plugin._schema_validator import create_schema_validator  # (pydantic's caller)
from pydantic.plugin import _loader
print("importlib.metadata" in sys.modules, type(_loader).__name__,
      _loader.PYDANTIC_ENTRY_POINT_GROUP, type(sys.modules["pydantic.plugin._loader"]).__name__)
"""


@pytest.mark.parametrize("given, looked_up", [(None, False), ("1", False), ("logfire", True)])
def test_pydantic_looks_for_no_plugin_unless_the_user_chose(given, looked_up):
    """With plugins off (the command line's default, or the user's `1`), validating a model
    imports no importlib.metadata (pydantic's plugin loader stands aside: core.pydantic_plugins);
    with a plugin named, pydantic's own loader looks them up; either way a name of the loader
    reads pydantic's own module, which then stands in sys.modules."""
    env = {k: v for k, v in os.environ.items() if k != "PYDANTIC_DISABLE_PLUGINS"}
    if given is not None:
        env["PYDANTIC_DISABLE_PLUGINS"] = given
    env["PYTHONPATH"] = str(ROOT / "src")
    out = subprocess.run([sys.executable, "-c", PLUGINS, str(MODELS / "pendulum.yaml")],
                         env=env, capture_output=True, text=True, check=True,
                         timeout=120).stdout.splitlines()[-1].split()
    assert out == [str(looked_up), "module" if looked_up else "_Loader", "pydantic", "module"]


def test_the_processs_own_command_line_collects_less_often():
    """main() as the process's command line raises the young generation's threshold, starts
    the collector before a command other than run and leaves its objects frozen at the end
    (docs/decisions/cli-collector.md); main([...]) from a caller's code leaves it as it was."""
    code = ("import gc, sys; from casmech.cli import main; "
            f"sys.argv = ['casmech', 'check', {str(MODELS / 'pendulum.yaml')!r}]; "
            "code = main(); print(code, gc.get_threshold()[0], gc.isenabled(), "
            "gc.get_freeze_count() > 0)")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=300, check=True)
    assert done.stdout.split()[-4:] == ["0", str(YOUNG_OBJECTS), "True", "True"]
    before = gc.get_threshold(), gc.isenabled(), gc.get_freeze_count()
    assert main(["check", str(MODELS / "pendulum.yaml")]) == 0
    assert (gc.get_threshold(), gc.isenabled(), gc.get_freeze_count()) == before


def test_run_collects_from_its_analysis_on(tmp_path):
    """`casmech run` as the process's own command line loads and compiles with the collector
    stopped and analyzes with it running (cli.collector)."""
    code = ("import atexit, gc, sys; from casmech import api; from casmech.cli import main\n"
            "seen = []; atexit.register(lambda: print(seen))\n"
            "def spy(name):\n"
            "    inner = getattr(api, name)\n"
            "    def call(*a, **k):\n"
            "        seen.append((name, gc.isenabled())); return inner(*a, **k)\n"
            "    setattr(api, name, call)\n"
            "spy('load'); spy('compile'); spy('analyze')\n"
            f"sys.argv = ['casmech', 'run', {str(MODELS / 'pendulum.yaml')!r}, '--t-end', "
            f"'0.1', '-q', '--mode', 'interpreted', '--out', {str(tmp_path)!r}]\n"
            "sys.exit(main())")  # (run ends the process: `seen` printed by atexit)
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=300, check=True)
    assert done.stdout.strip() == "[('load', False), ('compile', False), ('analyze', True)]"


# `casmech run` as a process's own command line, with what its exit must still do: an atexit
# handler, a line C's stdio holds in its buffer (stdout is a pipe here), and an object of a
# module whose finalizer runs only in the interpreter's teardown
ENDING = """import atexit, ctypes, os, sys, threading, types
from casmech.cli import main
class Teardown:
    def __del__(self, write=os.write):
        write(2, b"teardown\\n")
sys.modules["probe"] = types.ModuleType("probe")
sys.modules["probe"].kept = Teardown()  # (a module's objects go as the teardown clears it)
atexit.register(lambda: print("atexit ran"))
atexit.register(lambda: ctypes.CDLL(None).printf(b"C stdio\\n"))  # (left in C's buffer)
if sys.argv[1] == "thread":  # a thread still running as the command returns
    import time
    import casmech.cli.run as command
    def run(args, inner=command.run):
        try:
            return inner(args)
        finally:
            threading.Thread(target=time.sleep, args=(0.3,)).start()
    command.run = run
sys.argv = ["casmech", "run", sys.argv[2], "--t-end", "0.1", "--mode", "interpreted",
            "--out", sys.argv[3]]
sys.exit(main())
"""
# buffered streams, as in a user's shell (PYTHONUNBUFFERED unbuffers C's stdout as well)
BUFFERED = {k: v for k, v in os.environ.items() if k != "PYTHONUNBUFFERED"}


def test_run_ends_its_process_as_it_returns_and_loses_nothing(tmp_path):
    """`casmech run` ends the process when it returns (cli._leave): no teardown of the modules,
    but the atexit handlers run, C's and Python's buffered output is written, and the exit code
    and results files are the run's (docs/decisions/warm-process-exit.md)."""
    done = subprocess.run([sys.executable, "-c", ENDING, "alone", MODELS / "pendulum.yaml",
                           tmp_path], capture_output=True, text=True, timeout=300, env=BUFFERED)
    assert done.returncode == 0, done.stderr
    assert "C stdio" in done.stdout and "atexit ran" in done.stdout
    assert "results.csv" in done.stdout  # the run's summary, printed before the exit
    assert "teardown" not in done.stderr
    names, values = read_csv(tmp_path / "results.csv")
    assert names[0] == "t"
    np.testing.assert_allclose(values[-1, 0], 0.1, rtol=0, atol=1e-12)  # (the last output time)
    assert json.loads((tmp_path / "metadata.json").read_text())["status"] == "complete"
    failed = subprocess.run([sys.executable, "-c", ENDING, "alone", tmp_path / "missing.yaml",
                             tmp_path], capture_output=True, text=True, timeout=300, env=BUFFERED)
    assert failed.returncode == 2 and "atexit ran" in failed.stdout


def test_run_leaves_the_exit_to_the_interpreter_while_a_thread_runs(tmp_path):
    """A thread the interpreter would wait for keeps the interpreter's own exit: it is joined,
    and the teardown runs as without casmech."""
    done = subprocess.run([sys.executable, "-c", ENDING, "thread", MODELS / "pendulum.yaml",
                           tmp_path], capture_output=True, text=True, timeout=300, env=BUFFERED)
    assert done.returncode == 0, done.stderr
    assert "C stdio" in done.stdout and "atexit ran" in done.stdout
    assert "teardown" in done.stderr
