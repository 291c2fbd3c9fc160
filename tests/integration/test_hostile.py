"""Hostile and careless input (issue 16): every case runs the `casmech` command line in its own
process under a time limit and an address-space limit, and must end with a located error
(`file:line:col: error[CODE]`) or a clean result: never a traceback, a hang, a memory blow-up or
the content of a file nobody asked to see.

Each case is one class of the issue: numbers that overflow NumPy, YAML nesting, aliases and
size, repeat ranges, output grids, tables and component files (devices, huge files, paths
outside the model's folder), accepted nonsense and YAML 1.1 surprises, `check` agreeing with
`run`. The mutated-gallery fuzz test is tests/integration/test_hostile_fuzz.py.
"""

from __future__ import annotations

import json
import os
import re
import resource
import signal
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import pytest

from tests.conftest import ROOT

# the casmech under test, whatever the working directory of the process
ENV = {**os.environ, "OPENBLAS_NUM_THREADS": "1",
       "PYTHONPATH": os.pathsep.join([str(ROOT / "src"), os.environ.get("PYTHONPATH", "")])}

MEMORY = 1536 << 20  # address space of each process: casmech check/run needs ~600 MB
TIMEOUT = 60.0  # [s] hard limit per process (a shared 2-core machine)
LOCATED = re.compile(r"^(?P<file>[^\s:][^:]*):(?P<line>\d+):(?P<col>\d+): "
                     r"error\[(?P<code>E\d{3})\]", re.M)
SECRET = "hunter2-not-for-your-eyes"

BASE = """\
casmech: 1
name: pend
bodies:
  - name: bar
    mass: 1
    inertia: [1, 1, 1]
    position: [0, 0, -1]
joints:
  - name: pivot
    type: revolute
    body_i: ground
    body_j: bar
    at: [0, 0, 0]
    axis: [1, 0, 0]
analysis:
  type: dynamics
  t_end: 1
  output_step: 0.1
"""
LINES = BASE.splitlines()


def base(**lines: str) -> str:
    """BASE with whole lines replaced: base(mass="    mass: 2") replaces the first line whose
    key is `mass`."""
    out, todo = [], dict(lines)
    for line in LINES:
        key = line.strip().lstrip("- ").split(":")[0]
        out.append(todo.pop(key, line))
    return "\n".join(out) + "\n"


def line_of(text: str, start: str) -> int:
    return 1 + next(k for k, line in enumerate(text.splitlines()) if line.startswith(start))


def limit_memory() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY, MEMORY))


def casmech(args, cwd: Path, env: dict | None = None, timeout: float = TIMEOUT):
    """(exit code, stdout + stderr, seconds) of `casmech ARGS` in a limited process."""
    environment = {**ENV, **(env or {})}
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "casmech.cli", *map(str, args)], cwd=cwd,
                          capture_output=True, text=True, timeout=timeout,
                          preexec_fn=limit_memory, env=environment)
    return done.returncode, done.stdout + done.stderr, time.perf_counter() - start


@dataclass
class Case:
    """A model (and files beside it), the command, and what it must print."""

    model: str | bytes
    code: str  # diagnostic code expected
    line: int | None = None  # line of the model it must be located at (None: any)
    exit: int = 1
    args: tuple = ("check",)
    files: dict = field(default_factory=dict)  # name -> text or bytes, beside the model
    seconds: float = 20.0  # wall-clock bound of the whole process


def _deep(depth: int) -> str:
    return "casmech: 1\nname: deep\nbodies: " + "[" * depth + "]" * depth + "\n"


def _laughs(levels: int = 9) -> str:
    lines = ["casmech: 1", "name: laughs", "parameters: {}", "a0: &a0 [x, x, x, x, x, x, x, x]"]
    lines += [f"a{k}: &a{k} [" + ", ".join([f"*a{k - 1}"] * 8) + "]" for k in range(1, levels)]
    return "\n".join([*lines, f"bodies: *a{levels - 1}"]) + "\n"


def _repeat(to: str, nested: str = "") -> str:
    return ("casmech: 1\nname: many\nbodies:\n  - name: \"b{i}\"\n"
            f"    repeat: {nested or '{index: i, from: 1, to: ' + to + '}'}\n"
            "    mass: 1\n    inertia: [1, 1, 1]\n    position: [0, 0, -1]\n")


def _table(path: str, column: str = "lift") -> str:
    return base(axis="    axis: [1, 0, 0]\n    driver: {angle: {table: " + path +
                ", column: " + column + "}}")


def _component(path: str) -> str:
    return ("casmech: 1\nname: composed\ncomponents:\n  part: {file: " + path + "}\n"
            "instances:\n  - {name: one, component: part}\n")


def _bodies(count: int) -> str:
    body = "  - {{name: b{k}, mass: 1, inertia: [1, 1, 1], position: [0, 0, -1]}}\n"
    return "casmech: 1\nname: big\nbodies:\n" + "".join(body.format(k=k) for k in range(count))


TABLE = "t, lift\n0, 0\n1, 0.1\n2, 0.2\n3, 0.1\n4, 0\n"
FREE = BASE.replace("  type: dynamics", "  type: kinematics")  # kinematics of a free pendulum

CASES = {
    # 1. numbers that reached NumPy as tracebacks
    "axis_1e300": Case(base(axis="    axis: [1e300, 1e300, 0]"), "E411", 14),
    "position_1e300": Case(base(position="    position: [0, 0, -1e300]"), "E411", 7),
    "gravity_1e300": Case(base(name="name: pend\ngravity: [0, 0, -1e300]"), "E411", 3),
    "velocity_1e200": Case(base(position="    position: [0, 0, -1]\n    velocity: [1e200, 0, 0]"),
                           "E411", 8),
    "nesting_500": Case(_deep(500), "E006", 3),
    "output_step_1e-9": Case(base(output_step="  output_step: 1e-9"), "E409", 18,
                             args=("run", "--out", "out")),
    "t_end_1e300": Case(base(t_end="  t_end: 1e300"), "E409", 17, args=("run", "--out", "out")),
    "cli_t_end_inf": Case(BASE, "E409", exit=2, args=("run", "--out", "out", "--t-end", "inf")),
    "cli_t_end_nan": Case(BASE, "E409", exit=2, args=("run", "--out", "out", "--t-end", "nan")),
    "cli_output_step_tiny": Case(BASE, "E409", exit=2,
                                 args=("run", "--out", "out", "--output-step", "1e-12")),
    "cli_rtol_10": Case(BASE, "E409", exit=2, args=("run", "--out", "out", "--rtol", "10")),
    # issue 35 item 10: a subnormal output step overflowed t_end / output_step
    "output_step_subnormal": Case(base(output_step="  output_step: 2e-320"), "E409", 18),
    "output_step_subnormal_run": Case(base(output_step="  output_step: 2e-320"), "E409", 18,
                                      args=("run", "--out", "out")),
    "cli_output_step_subnormal": Case(BASE, "E409", exit=2,
                                      args=("run", "--out", "out", "--output-step", "2e-320")),
    # 2. memory: aliases, repeat ranges, huge files and devices
    "billion_laughs": Case(_laughs(), "E006"),
    "repeat_1e9": Case(_repeat("1e9"), "E105", 5),
    "repeat_nested": Case(_repeat("", "[{index: i, from: 1, to: 5000}, {index: j, from: 1, "
                                      "to: 5000}]"), "E105", 5),
    "table_device": Case(_table("/dev/zero"), "E305", 15),
    "table_huge": Case(_table("huge.csv"), "E306", 15,
                       files={"huge.csv": "t, lift\n" + "0.5, 0.25\n" * 2_000_000}),
    "component_device": Case(_component("/dev/zero"), "E305", 4),
    "component_huge": Case(_component("part.yaml"), "E306", 4,
                           files={"part.yaml": "# " + "x" * (9 << 20) + "\n"}),
    "model_8MB": Case("casmech: 1\nname: big\n# " + "x" * (8 << 20) + "\n", "E006", 1),
    "model_binary": Case(b"casmech: 1\nname: \xff\xfe\x00\x01\n", "E001"),
    # 3. file disclosure: paths outside the model's folder, contents in hints
    "table_outside": Case(_table("../secret.csv"), "E305", 15),
    "table_absolute": Case(_table("/etc/passwd"), "E305", 15),
    "table_environ": Case(_table("/proc/self/environ"), "E305", 15),
    "table_header_secret": Case(_table("secret_header.csv"), "E300", 15,
                                files={"secret_header.csv": f"{SECRET}, lift\n0, 1\n1, 2\n"
                                                            "2, 3\n3, 4\n"}),
    "table_row_secret": Case(_table("secret_row.csv"), "E103", 15,
                             files={"secret_row.csv": f"t, lift\n0, 1\n{SECRET}, 2\n"}),
    "component_outside": Case(_component("../part.yaml"), "E305", 4),
    "mesh_outside": Case(base(position="    position: [0, 0, -1]\n    geometry: "
                                       "[{mesh: /etc/passwd}]"), "E305", 8),
    # 5. accepted nonsense and YAML 1.1 surprises
    "rtol_10": Case(base(output_step="  output_step: 0.1\n  rtol: 10"), "E409", 19),
    "rtol_1e-300": Case(base(output_step="  output_step: 0.1\n  rtol: 1e-300"), "E409", 19),
    "atol_1e-300": Case(base(output_step="  output_step: 0.1\n  atol: 1e-300"), "E409", 19),
    "empty_driver": Case(base(axis="    axis: [1, 0, 0]\n    driver: {}"), "E100", 15),
    "joints_null": Case(base(joints="joints: null").replace(
        "\n  - name: pivot\n    type: revolute\n    body_i: ground\n    body_j: bar\n"
        "    at: [0, 0, 0]\n    axis: [1, 0, 0]", ""), "E102", 8),
    "name_not_identifier": Case(base(name="name: my model; rm -rf"), "E303", 2),
    "sexagesimal": Case(base(mass="    mass: 1:30"), "E004", 5),
    "hexadecimal": Case(base(mass="    mass: 0x10"), "E004", 5),
    "octal": Case(base(mass="    mass: 010"), "E004", 5),
    "underscore": Case(base(mass="    mass: 1_000"), "E004", 5),
    "date": Case(base(mass="    mass: 2001-12-14"), "E004", 5),
    "yes_boolean": Case(_table("profile.csv").replace("column: lift}", "column: lift, "
                                                      "periodic: yes}"), "E004", 15,
                        files={"profile.csv": TABLE}),
    "python_tag": Case(base(mass="    mass: !!python/object/apply:os.system [echo hi]"),
                       "E005", 5),
    "custom_tag": Case(base(mass="    mass: !secret 1"), "E005", 5),
    "check_free_kinematics": Case(FREE, "E501", 16),
    # issue 35: careless input, impossible models
    "driver_rate_1e300": Case(base(axis="    axis: [1, 0, 0]\n    driver: {angle: 1e300*t}"),
                              "E411", 15),
    "mass_subnormal": Case(base(mass="    mass: 2e-320"), "E411", 5),
    "mass_1e-300": Case(base(mass="    mass: 1e-300"), "E411", 5),
    "inertia_1e-300": Case(base(inertia="    inertia: [1e-300, 1e-300, 1e-300]"), "E411", 6),
    "negative_stiffness": Case(BASE.replace("analysis:", "forces:\n  - {name: s, type: rsda, "
                                            "joint: pivot, stiffness: -1e3}\nanalysis:"),
                               "E103", 16),
    "dp1_axis_1e-12": Case(BASE.replace("analysis:", "  - {name: c, type: dp1, body_i: "
                                        "ground, a_i: [0, 0, 1e-12], body_j: bar, "
                                        "a_j: [1, 0, 0]}\nanalysis:"), "E404", 15),
    "distance_unreachable": Case(BASE.replace("analysis:", "  - {name: tether, type: distance, "
                                              "body_i: ground, body_j: bar, at_i: [0, 0, 0], "
                                              "at_j: [0, 0, -1], length: 10}\nanalysis:"),
                                 "E502", 15),
    "driver_far_at_start": Case(base(axis="    axis: [1, 0, 0]\n    driver: {angle: 2e6}"),
                                "E502", 15),  # (the continuation took 4e6 Newton solves)
    "mesh_missing": Case(base(position="    position: [0, 0, -1]\n    geometry: "
                                       "[{mesh: missing.stl}]"), "E410", 8),
}


@pytest.mark.parametrize("name", list(CASES))
def test_hostile_model_gives_a_located_error(tmp_path, name):
    case = CASES[name]
    folder = tmp_path / "model"
    folder.mkdir()
    (tmp_path / "secret.csv").write_text(f"t, {SECRET}\n0, 1\n1, 2\n2, 3\n3, 4\n")
    (tmp_path / "part.yaml").write_text("bodies: []\n")
    for file, content in case.files.items():
        (folder / file).write_bytes(content if isinstance(content, bytes) else content.encode())
    model = folder / "model.yaml"
    model.write_bytes(case.model if isinstance(case.model, bytes) else case.model.encode())
    command, *options = case.args
    code, output, seconds = casmech([command, "model.yaml", *options], folder)
    assert "Traceback" not in output, output
    assert code == case.exit, output
    assert f"error[{case.code}]" in output, output
    if case.exit == 1:
        found = [m for m in LOCATED.finditer(output) if m["code"] == case.code]
        assert found, f"no located {case.code}:\n{output}"
        assert case.line is None or int(found[0]["line"]) == case.line, output
    assert SECRET not in output and "root:" not in output and "PATH=" not in output
    assert seconds < case.seconds, f"{seconds:.1f} s"


# ---------------------------------------------------------------------------- importer
def test_simengine_comment_cannot_inject_yaml(tmp_path):
    """A .mdl comment with line breaks (every YAML line break: \\n, \\r, NEL, LS, PS) stays a
    comment: the imported model has no `forces`, and its gravity is the file's."""
    injected = "harmless\nforces:\n  - {name: f, type: force, body: bar, value: [1e6, 0, 0]}"
    mdl = json.loads((ROOT / "tests" / "data" / "me751_pendulum.mdl").read_text())
    mdl["comment"] = injected
    mdl["bodies"][1]["comment"] = "x\r- {name: evil}\x85gravity: [0, 0, 1e3]\u2028y\u2029z"
    (tmp_path / "evil.mdl").write_text(json.dumps(mdl))
    code, output, _ = casmech(["import", "evil.mdl", "-o", "evil.yaml"], tmp_path)
    assert code == 0, output
    text = (tmp_path / "evil.yaml").read_text()
    import yaml

    data = yaml.safe_load(text)
    assert "forces" not in data and data["gravity"] != [0, 0, 1000.0]
    assert [b["name"] for b in data["bodies"]] == ["body1"] or "evil" not in str(data["bodies"])
    code, output, _ = casmech(["check", "evil.yaml"], tmp_path)
    assert code == 0, output


# ---------------------------------------------------------------------------- interrupts
LONG = """\
casmech: 1
name: long
bodies:
  - {name: a, mass: 1, inertia: [0.1, 0.1, 0.1], position: [0.5, 0, 0]}
  - {name: b, mass: 1, inertia: [0.1, 0.1, 0.1], position: [1.5, 0, 0]}
joints:
  - {name: p1, type: revolute, body_i: ground, body_j: a, at: [0, 0, 0], axis: [0, 1, 0]}
  - {name: p2, type: revolute, body_i: a, body_j: b, at: [1, 0, 0], axis: [0, 1, 0]}
analysis: {type: dynamics, t_end: 30000, output_step: 0.1, rtol: 1e-10, atol: 1e-12,
           formulation: FORMULATION}
"""


@pytest.mark.parametrize("formulation,signum", [
    ("rp", signal.SIGINT), ("joint", signal.SIGTERM), ("romega", signal.SIGINT),
    # DOP853's C driver runs a chunk of output intervals a call; runtime.driver polls between
    ("joint, method: dop853", signal.SIGINT)])
def test_interrupt_keeps_the_rows_computed(tmp_path, formulation, signum):
    """SIGINT/SIGTERM stop the run promptly; results.csv holds the rows computed so far and
    metadata.json says interrupted (an earlier complete results file is not left behind)."""
    (tmp_path / "long.yaml").write_text(LONG.replace("FORMULATION", formulation))
    code, output, _ = casmech(["run", "long.yaml", "--out", "out", "--t-end", "0.5"], tmp_path)
    assert code == 0, output
    process = subprocess.Popen([sys.executable, "-m", "casmech.cli", "run", "long.yaml",
                                "--out", "out"], cwd=tmp_path, stdout=subprocess.PIPE,
                               stderr=subprocess.STDOUT, text=True, preexec_fn=limit_memory,
                               env=ENV)
    written = tmp_path / "out/results.csv"  # the rows stream to it as they are computed
    waited = time.perf_counter() + 6.0
    while time.perf_counter() < waited and (not written.exists() or written.read_bytes().count(
            b"\n") <= 7):  # until more rows than the first run's 6 are on disk (or 6 s)
        time.sleep(0.1)
    assert process.poll() is None, process.communicate()[0]
    process.send_signal(signum)
    sent = time.perf_counter()
    output = process.communicate(timeout=30)[0]
    assert time.perf_counter() - sent < 10.0
    assert "Traceback" not in output, output
    assert process.returncode == 128 + signum, output
    meta = json.loads((tmp_path / "out/metadata.json").read_text())
    assert meta["status"] == "interrupted" and meta["signal"] == signal.Signals(signum).name
    from casmech.io.csv import read_csv

    names, values = read_csv(tmp_path / "out/results.csv")
    assert names[0] == "t" and len(values) == meta["rows"] > 6  # more than the first run's
    assert values[0, 0] == 0.0 and (values[1:, 0] > values[:-1, 0]).all()
