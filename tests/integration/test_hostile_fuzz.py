"""Fuzz: thousands of mutated gallery models through `casmech check` (issues 16 and 35).

Every model of models/ is mutated (seeded) by line and token edits: hostile values (1e300,
nan, YAML 1.1 spellings, tags, aliases, devices, paths outside the folder, long text, deep
nesting), deleted, duplicated, swapped and re-indented lines, renamed keys and references,
truncation and stray bytes. Worker processes (an address-space limit each) run `check` on
each in turn with a time limit per model (and `run` on a sample of those check accepts), and
report: no traceback, no timeout, no memory error, every non-zero exit with a located
`file:line:col: error[CODE]`, and no model that check accepts and run rejects.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import random
import re
import resource
import shutil
import signal
import subprocess
import sys
import time
import traceback
from pathlib import Path

import pytest

from tests.conftest import MODELS, ROOT

SEED = 16
COUNT = 2400  # mutated models in the README's test command (issue 16 asks for at least 2000)
SLOW_COUNT = 5000  # mutated models under `-m slow` (issue 35 asks for at least 5000)
WORKERS = 2
MEMORY = 1536 << 20  # address space of a worker [bytes]
PER_MODEL = 20.0  # [s] time limit of one check (the gallery's take 0.01-0.4 s) or run
RUN_EVERY = 6  # one in RUN_EVERY models that `check` accepts is also run (t_end 0.02 s): what
#               check accepts, run must not reject as a model or usage error
LOCATED = re.compile(r"^[^\s:][^:\n]*:\d+:\d+: error\[E\d{3}\]", re.M)
USAGE = re.compile(r"^casmech: ", re.M)

HOSTILE = [
    "1e300", "-1e300", "1e-300", "0", "-1", "nan", ".nan", ".inf", "-.inf", "1e999", "1:30",
    "0x10", "010", "1_000", "yes", "off", "null", "~", "''", "[]", "{}", "[[[[[[]]]]]]",
    "!!python/object/apply:os.system [echo hi]", "!custom 1", "*undefined", "&anchor 1",
    "2001-12-14", "'", '"', "t", "pi", "e", "ground", "sin(", "1/0", "log(0)", "sqrt(-1)",
    "exp(1000)", "10**10**10", "x" * 300, "(" * 60 + "1" + ")" * 60, "-" * 50 + "1",
    "../../etc/passwd", "/dev/zero", "/proc/self/environ", "{table: /dev/zero, column: x}",
    "{table: ../../../etc/passwd, column: t}", "{file: /dev/zero}", "{file: ../x.yaml}",
    "\"a\\nb: 1\"", "[1, 2]", "[1, 2, 3, 4, 5, 6, 7]", "[1e300, 1e300, 0]", "[0, 0, 0]",
    "{index: i, from: 1, to: 1e9}", "\"{i}\"", "link{1e9}", "- a", "a: b", "{a: 1, a: 2}",
    "true", "1e20", "-0", "+.5", "0.0000001", "1e6", "2e6", "1e12", "1e13",
    # issue 35: subnormal and degenerate numbers, drivers leaving double precision, negative
    # coefficients, directions of no length, laws undefined later in the run
    "2e-320", "5e-324", "1e-16", "1e300*t", "-1e3", "-0.5", "[0, 0, 1e-12]", "[1e-12, 0, 0]",
    "'log(0.5 - t)'", "'1/(t - 0.01)'", "'sqrt(0.01 - t)'", "'if(t < 0.01, 0, 1e308*10)'",
]
KEYS = ["name", "type", "mass", "inertia", "position", "orientation", "velocity", "at", "axis",
        "body_i", "body_j", "driver", "angle", "displacement", "motor", "f", "repeat", "table",
        "column", "t_end", "output_step", "rtol", "atol", "gravity", "parameters", "bodies",
        "joints", "forces", "analysis", "components", "instances", "file", "stiffness",
        "damping", "value", "frame", "geometry", "mesh", "casmech", "cut", "from", "to",
        "allow_negative", "free_length", "length", "horizon", "intervals"]
STRAY = ["\t", "\x00", "\x07", "\x1b", "\ufeff", "\u2028", "\x85", "é", "#", ":", "- ", "&",
         "*", "!", "|", ">", "%", "@", "`", "{", "}", "[", "]", ",", "? ", "---\n", "...\n"]
VALUE = re.compile(r"(:\s+|[\[,]\s*)([^\s,\[\]{}:#][^,\[\]{}#\n]*?)(?=\s*[,\]\}]|\s*#|\s*$)",
                   re.M)


# ------------------------------------------------------------------------------ mutations
def _replace_value(text: str, rng: random.Random) -> str:
    spans = [m.span(2) for m in VALUE.finditer(text)]
    if not spans:
        return text
    start, end = rng.choice(spans)
    return text[:start] + rng.choice(HOSTILE) + text[end:]


def _lines(text: str, rng: random.Random, edit: str) -> str:
    lines = text.split("\n")
    k = rng.randrange(len(lines))
    if edit == "delete":
        del lines[k]
    elif edit == "duplicate":
        lines.insert(k, lines[k])
    elif edit == "swap":
        j = rng.randrange(len(lines))
        lines[k], lines[j] = lines[j], lines[k]
    elif edit == "indent":
        lines[k] = " " * rng.choice([0, 1, 2, 3, 4, 6, 8]) + lines[k].lstrip()
    return "\n".join(lines)


def _rename_key(text: str, rng: random.Random) -> str:
    keys = list(re.finditer(r"(?m)^(\s*-?\s*)([a-z_]+):", text))
    if not keys:
        return text
    match = rng.choice(keys)
    return text[:match.start(2)] + rng.choice(KEYS) + text[match.end(2):]


def _rename_reference(text: str, rng: random.Random) -> str:
    names = re.findall(r"name: ([A-Za-z_][\w{}.-]*)", text)
    refs = list(re.finditer(r"(body_i|body_j|body|joint|component): ([A-Za-z_][\w{}.-]*)", text))
    if not names or not refs:
        return text
    match = rng.choice(refs)
    return text[:match.start(2)] + rng.choice(names + ["ground", "nowhere"]) + \
        text[match.end(2):]


def _truncate(text: str, rng: random.Random) -> str:
    return text[:rng.randrange(len(text))]


def _stray(text: str, rng: random.Random) -> str:
    k = rng.randrange(len(text))
    return text[:k] + rng.choice(STRAY) + text[k:]


def _nest(text: str, rng: random.Random) -> str:
    depth = rng.choice([20, 40, 200, 5000])
    return text + f"\nextra: {'[' * depth}{']' * depth}\n"


def _aliases(text: str, rng: random.Random) -> str:
    levels = rng.choice([3, 6, 10])
    lines = ["laugh0: &l0 [a, b, c, d, e, f, g, h, i, j]"]
    lines += [f"laugh{k}: &l{k} [" + ", ".join([f"*l{k - 1}"] * 10) + "]"
              for k in range(1, levels)]
    return "\n".join(lines) + "\n" + text


MUTATIONS = [(_replace_value, 8), (lambda t, r: _lines(t, r, "delete"), 2),
             (lambda t, r: _lines(t, r, "duplicate"), 1), (lambda t, r: _lines(t, r, "swap"), 1),
             (lambda t, r: _lines(t, r, "indent"), 1), (_rename_key, 2),
             (_rename_reference, 2), (_truncate, 1), (_stray, 1), (_nest, 0.3),
             (_aliases, 0.3)]


def mutants(count: int, seed: int = SEED) -> list[tuple[str, str]]:
    """(name, text) of `count` mutated gallery models: 1 to 3 mutations each."""
    rng = random.Random(seed)
    sources = sorted(p for p in MODELS.rglob("*.yaml"))
    texts = {p.relative_to(MODELS).as_posix(): p.read_text() for p in sources}
    operators, weights = zip(*MUTATIONS, strict=True)
    out = []
    for k in range(count):
        source = rng.choice(sorted(texts))
        text = texts[source]
        for operator in rng.choices(operators, weights, k=rng.choice([1, 1, 2, 3])):
            text = operator(text, rng) or text
        out.append((f"{k:05d}_{source.replace('/', '_')}", text))
    return out


# ------------------------------------------------------------------------------ worker
class _Timeout(BaseException):
    pass


def _alarm(signum, frame):
    raise _Timeout()


def command(folder: Path, args: list[str]) -> dict:
    """A casmech command in this process: exit code, output, seconds, and the traceback of
    anything that escaped."""
    from casmech import cli

    output = io.StringIO()
    start = time.perf_counter()
    escaped = None
    signal.setitimer(signal.ITIMER_REAL, PER_MODEL)
    try:
        with contextlib.redirect_stdout(output), contextlib.redirect_stderr(output):
            code = cli.main(args)
    except _Timeout:
        code, escaped = -1, f"more than {PER_MODEL} s"
    except SystemExit as exit_:
        code = exit_.code
    except BaseException:  # noqa: BLE001 - everything that escapes is the finding
        code, escaped = -2, traceback.format_exc()
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
    return {"code": code, "seconds": time.perf_counter() - start, "escaped": escaped,
            "output": output.getvalue()[-2000:]}


def check_one(folder: Path, name: str, text: str, run: bool) -> dict:
    """`casmech check` of one mutated model (and `run`, if `run` and check accepts it)."""
    path = folder / f"fuzz_{name}.yaml"
    path.write_bytes(text.encode("utf-8", "surrogatepass"))
    try:
        result = {"name": name, **command(folder, ["check", str(path)])}
        if run and result["code"] == 0:
            result["run"] = command(folder, ["run", str(path), "--t-end", "0.02", "--out",
                                             str(folder / f"out{os.getpid()}")])
    finally:
        path.unlink(missing_ok=True)
    return result


def worker(cases_file: str, folder: str, report: str) -> None:
    """Check every case of `cases_file`; one JSON line per model in `report` (flushed, so a
    killed worker still says how far it got)."""
    import warnings

    warnings.simplefilter("ignore")  # e.g. "no C compiler": not what the fuzz looks for
    signal.signal(signal.SIGALRM, _alarm)
    cases = json.loads(Path(cases_file).read_text())
    with open(report, "w") as out:
        for k, (name, text) in enumerate(cases):
            out.write(json.dumps({"start": name}) + "\n")
            out.flush()
            result = check_one(Path(folder), name, text, run=k % RUN_EVERY == 0)
            out.write(json.dumps(result) + "\n")
            out.flush()


def _limit() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY, MEMORY))


def problems(result: dict) -> str | None:
    """What is wrong with one model's check (or run), or None."""
    run = result.get("run")
    if run is not None:
        if run["escaped"] or "Traceback" in run["output"]:
            return f"run: {run['escaped'] or run['output']}"
        if run["code"] in (1, 2):
            return f"check accepted it, run refused it: {run['output']}"
        if run["code"] == 3 and "analysis failed" not in run["output"]:
            return f"run: exit 3 without a failure message: {run['output']}"
        if run["code"] not in (0, 3):
            return f"run: exit {run['code']}: {run['output']}"
    output = result["output"]
    if result["escaped"]:
        return result["escaped"]
    if "Traceback" in output or "MemoryError" in output:
        return output
    if result["code"] not in (0, 1, 2):
        return f"exit {result['code']}: {output}"
    if result["code"] == 1 and not LOCATED.search(output):
        return f"exit 1 without a located error: {output}"
    if result["code"] == 2 and not USAGE.search(output):
        return f"exit 2 without a usage message: {output}"
    return None


def test_mutated_gallery_models_give_located_errors(tmp_path):
    fuzz(tmp_path, COUNT, SEED)


@pytest.mark.slow
def test_five_thousand_mutated_gallery_models_give_located_errors(tmp_path):
    """The same over SLOW_COUNT other mutants (issue 35)."""
    fuzz(tmp_path, SLOW_COUNT, SEED + 19)


def fuzz(tmp_path, count: int, seed: int) -> None:
    """`count` mutants (seeded) through check and, a sample, run: no finding (problems)."""
    folder = tmp_path / "models"
    shutil.copytree(MODELS, folder)
    cases = mutants(count, seed)
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "CASMECH_CACHE_DIR": str(tmp_path / "c"),
           "PYTHONPATH": os.pathsep.join([str(ROOT), str(ROOT / "src"),
                                          os.environ.get("PYTHONPATH", "")])}
    processes = []
    for k in range(WORKERS):
        shard = tmp_path / f"cases{k}.json"
        shard.write_text(json.dumps(cases[k::WORKERS]))
        report = tmp_path / f"report{k}.jsonl"
        processes.append((report, subprocess.Popen(
            [sys.executable, "-c", "import sys; "
             "from tests.integration.test_hostile_fuzz import worker; worker(*sys.argv[1:])",
             str(shard), str(folder), str(report)], cwd=ROOT, env=env,
            preexec_fn=_limit, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)))
    results, died = [], []
    for report, process in processes:
        output = process.communicate(timeout=1800 * max(1, count / COUNT))[0]
        lines = [json.loads(line) for line in report.read_text().splitlines()]
        results += [line for line in lines if "code" in line]
        if process.returncode != 0:
            last = [line["start"] for line in lines if "start" in line][-1:]
            died.append(f"worker exit {process.returncode} at {last}: {output[-2000:]}")
    assert not died, died
    assert len(results) == count
    found = {r["name"]: problems(r) for r in results if problems(r)}
    assert not found, "\n\n".join(f"{name}:\n{text}" for name, text in list(found.items())[:5])
    codes = {r["code"] for r in results}
    assert {0, 1} <= codes  # the mutations reach both valid and invalid models
    assert sum("run" in r for r in results) > 50  # and some are run
