"""THE SEAM of parameter studies: one run of a model at given parameter values.

`Job` is what a worker needs (picklable, hashable: the model's text and file name, the analysis
settings, the kept outputs). `runner_for(job)` prepares it once per process; `Runner.run(values)`
makes one run and returns an `Outcome`. Nothing else in casmech.study knows how a run is made.

A run loads the model text with the values as `--set` overrides and compiles it in the job's
mode (`casmech.loads` + `casmech.compile`). "interpreted": CasADi functions built for these
values. "compiled": the model's parametric library
(codegen.parametric: the model data as an input, keyed on the model's structure), built once
by the study before its runs (study.sweep.prepare), loaded from the cache and bound to the
run's values (milliseconds); a value that changes the structure (a repeat count, a parameter
that is 0 in the file) builds one more library, once.
"""

from __future__ import annotations

import functools
import time
from collections.abc import Mapping
from dataclasses import field

import numpy as np

from casmech.core.records import record
from casmech.errors import AnalysisError, Interrupted, ModelError
from casmech.runtime import interrupts
from casmech.study import kept as kept_outputs

# keyword arguments of casmech.analyze a study may set (None: the model's)
SETTINGS = ("analysis", "t_end", "output_step", "rtol", "atol", "formulation", "stabilization",
            "method")


@record
class Job:
    file: str  # the model file's path: names it in messages, roots the files it reads
    text: str
    settings: tuple[tuple[str, object], ...] = ()  # (name in SETTINGS, value) given
    keep: tuple[str, ...] = ()
    full: bool = False  # return each run's whole results table
    base: tuple[tuple[str, str], ...] = ()  # --set overrides of every run (a run's values win)
    mode: str = "interpreted"  # casmech.compile's mode for every run
    batched: tuple[str, ...] = ()  # the study's parameters when its runs go in batches


@record(frozen=False)
class Outcome:
    values: dict[str, float]
    status: str  # complete | failed
    reason: str = ""
    wall_s: float = 0.0
    kept: dict[str, float] = field(default_factory=dict)
    rows: int = 0
    names: list[str] | None = None  # the whole table when Job.full
    table: np.ndarray | None = None


def overrides(values: Mapping[str, float]) -> dict[str, str]:
    """Parameter values as `--set` texts, exactly (repr round-trips a float)."""
    return {name: repr(float(value)) for name, value in values.items()}


class Runner:
    def __init__(self, job: Job):
        self.job = job
        self.settings = dict(job.settings)
        self.kept = [kept_outputs.parse(text) for text in job.keep]
        self.prepare()

    def prepare(self) -> None:
        """Once per process: today, importing what a run uses (the build is per run)."""
        import casmech.runtime.analyses  # noqa: F401

    def build(self, values: Mapping[str, float]):
        """The system functions at these parameter values."""
        from casmech import backends
        from casmech.schema import load_model_text

        given = {**dict(self.job.base), **overrides(values)}
        model = load_model_text(self.job.text, file=self.job.file, overrides=given)
        return backends.compile(model, self.job.mode)

    def run(self, values: Mapping[str, float]) -> Outcome:
        """One run: complete, or failed with its reason (a model error at these values, an
        analysis failure; the rows before a failure still give the kept outputs)."""
        from casmech.runtime.analyses import analyze
        from casmech.runtime.results import table as results_table

        clock = time.perf_counter()
        outcome = Outcome(dict(values), "complete")
        functions = result = None
        try:
            functions = self.build(values)
            # a progress callback: rows as they come, in chunks an interrupt keeps
            result = analyze(functions, progress=lambda t: None, **self.settings)
        except Interrupted:
            raise
        except AnalysisError as error:
            outcome.status, outcome.reason = "failed", reason(error)
            result = error.partial
        except ModelError as error:
            outcome.status, outcome.reason = "failed", reason(error)
        if functions is not None and result is not None and len(result):
            names, table = results_table(functions, result)
            outcome.kept = kept_outputs.values(self.kept, names, table, result.events)
            outcome.rows = len(table)
            if self.job.full:
                outcome.names, outcome.table = list(names), table
        else:
            outcome.kept = {k.text: float("nan") for k in self.kept}
        outcome.wall_s = time.perf_counter() - clock
        return outcome


REASON_CHARS = 500  # a failure's reason in sweep.csv: its message on one line, cut here


def reason(error: Exception) -> str:
    """The error's message on one line (its lines joined by ' | '), at most REASON_CHARS."""
    lines = [line.strip() for line in str(error).strip().splitlines() if line.strip()]
    return " | ".join(lines)[:REASON_CHARS] or type(error).__name__


@functools.lru_cache(maxsize=4)
def runner_for(job: Job) -> Runner:
    """The process's runner of a job, prepared on first use."""
    return Runner(job)


def run_point(job: Job, values: Mapping[str, float]) -> Outcome:
    """One run through the process's runner."""
    return runner_for(job).run(values)


def run_batch(job: Job, batch: list[Mapping[str, float]]) -> list[Outcome]:
    """A worker's task: consecutive runs (one task each would cost the scheduler's round trip
    per run); a run that raises what Runner does not record fails alone."""
    outcomes = []
    for values in batch:
        try:
            outcomes.append(run_point(job, values))
        except Exception as error:  # noqa: BLE001  (KeyboardInterrupt is not one)
            interrupts.check(error)  # CasADi's RuntimeError made of a Ctrl-C: raised back
            outcomes.append(unexpected(values, error))
    return outcomes


def unexpected(values: Mapping[str, float], error: BaseException) -> Outcome:
    """A run that raised what Runner does not record (a bug, a lost worker): failed, with the
    exception's type and message, so that the study goes on."""
    return Outcome(dict(values), "failed", f"{type(error).__name__}: {reason(error)}")
