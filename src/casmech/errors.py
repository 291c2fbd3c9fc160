"""Exceptions and diagnostics.

A user mistake is never a traceback: every stage collects `Diagnostic`s and raises one
`ModelError` holding all of them. Each diagnostic renders as

    file:line:col: error[CODE] path: message
      expected: ...
      got: ...
      hint: ...

Everything a diagnostic or an error message echoes goes through `escape`: a control character
(an escape sequence that would restyle or rewrite the terminal, a carriage return, a newline
that would forge a `file:1:1: error[...]` line of its own) or a Unicode direction override in a
name, a key or a value is shown as its escape (\\x1b, \\n, \\u202e), once, here.

Exit codes of the command line (docs/format.md): 0 success, 1 model error, 2 usage error,
3 analysis failure, 128 + the signal's number when SIGINT (130) or SIGTERM (143) stopped it.
"""

from __future__ import annotations

import re
import signal
from collections.abc import Iterable, Sequence
from dataclasses import field
from functools import cache

from casmech.core.records import record

# Every diagnostic code casmech emits, with a one-line title. Tests keep one bad-model fixture
# per code (tests/unit/schema/bad_models/), so adding a code here means adding a fixture.
CODES: dict[str, str] = {
    # E0xx: the YAML text itself
    "E001": "YAML syntax error",
    "E002": "duplicate key",
    "E003": "the document is not a mapping",
    "E004": "a YAML 1.1 spelling that reads differently in YAML 1.2 (1:30, 0x10, yes, a date)",
    "E005": "a YAML tag (!!python/..., !custom): not part of the format",
    "E006": "the input exceeds a limit (file size, nesting depth, values after aliases)",
    # E1xx: structure (shape and types of the format)
    "E100": "missing required key",
    "E101": "unknown key",
    "E102": "wrong type",
    "E103": "invalid value",
    "E104": "unsupported format version",
    "E105": "too many items (repeat copies, bodies, joints, forces, instances)",
    # E2xx: expressions
    "E200": "expression syntax error",
    "E201": "unknown symbol in expression",
    "E202": "time 't' used where no function of time is allowed",
    "E203": "unknown function or wrong number of arguments",
    "E204": "expression cannot be evaluated",
    "E205": "a value of the wrong dimension (units)",
    # E3xx: names and references
    "E300": "unknown reference",
    "E301": "duplicate name",
    "E302": "reserved name",
    "E303": "invalid name",
    "E304": "a joint or force connects a body to itself",
    "E305": "a file the model names is outside its folder or not a regular file",
    "E306": "a file the model names is too large",
    # E4xx: physical sanity
    "E400": "mass must be positive",
    "E401": "inertia not positive definite",
    "E402": "inertia violates the triangle inequality",
    "E403": "Euler parameters not of unit norm",
    "E404": "zero-length vector",
    "E405": "axes not perpendicular",
    "E406": "rotation matrix not orthonormal",
    "E407": "orientation needs exactly one form",
    "E408": "driver not allowed on this joint type",
    "E409": "non-positive or inconsistent analysis setting",
    "E410": "invalid geometry",
    "E411": "a magnitude outside the plausible range",
    "E412": "an initial value that a driver or the joints' initial values already give",
    # E5xx: structure of the assembled mechanism (found by the compiler)
    "E500": "redundant constraints",
    "E501": "mechanism is not fully driven",
    "E502": "the constraints cannot be met (assembly does not converge)",
    "E503": "joints' initial values cannot be met",
    "E504": "joints' initial values overdetermine the mechanism",
}


# C0 and C1 control characters, DEL, and the invisible marks that reorder or break what a
# terminal shows (direction marks, embeddings, overrides and isolates; line and paragraph
# separators)
CONTROL = ("[\x00-\x1f\x7f-\x9f\u200e\u200f\u202a-\u202e\u2066-\u2069"
           "\u2028\u2029]")
_NAMED = {"\n": "\\n", "\r": "\\r", "\t": "\\t"}


def _escaped(match: re.Match) -> str:
    character = match.group()
    code = ord(character)
    return _NAMED.get(character) or (f"\\x{code:02x}" if code < 0x100 else f"\\u{code:04x}")


def escape(text: object, keep_newlines: bool = False) -> str:
    """`text` with every control character written as its escape (module docstring);
    `keep_newlines`: a message's own line breaks stay (each line escaped)."""
    text = str(text)
    control = _pattern(CONTROL)
    if keep_newlines:
        return "\n".join(control.sub(_escaped, line) for line in text.split("\n"))
    return control.sub(_escaped, text)


@cache
def _pattern(text: str) -> re.Pattern:
    """A pattern of this module, compiled when first used (a run that ends well uses none)."""
    return re.compile(text)


@record
class Source:
    """Where something came from: 1-based line and column in a file."""

    file: str
    line: int
    col: int

    def __str__(self) -> str:
        return f"{escape(self.file)}:{self.line}:{self.col}"


@record
class Diagnostic:
    """One finding: its code, path, message, where in the file, and what was expected, what
    was got and a hint."""

    code: str
    path: str
    message: str
    source: Source | None = None
    expected: str | None = None
    got: str | None = None
    hint: str | None = None
    severity: str = "error"  # "error" | "warning" | "note"

    def __post_init__(self) -> None:
        if self.code not in CODES:
            raise ValueError(f"unregistered diagnostic code {self.code}")

    def format(self) -> str:
        where = f"{self.source}: " if self.source else ""
        path = f" {escape(self.path)}:" if self.path else ""
        lines = [f"{where}{self.severity}[{self.code}]{path} {escape(self.message)}"]
        for label, text in (("expected", self.expected), ("got", self.got), ("hint", self.hint)):
            if text:
                lines.append(f"  {label}: {escape(text)}")
        return "\n".join(lines)


def did_you_mean(word: str, candidates: Iterable[str]) -> str | None:
    """A 'did you mean ...?' hint, or None when nothing is close (difflib imported here: only
    a mistake needs it)."""
    import difflib

    close = difflib.get_close_matches(str(word), [str(c) for c in candidates], n=1, cutoff=0.6)
    return f"did you mean '{close[0]}'?" if close else None


class CasmechError(Exception):
    """Base of every error casmech raises on purpose; its message is shown escaped (its own
    line breaks kept: module docstring)."""

    exit_code = 1

    def __str__(self) -> str:
        return escape(super().__str__(), keep_newlines=True)


class ModelError(CasmechError):
    """The model is wrong; carries every finding at once."""

    exit_code = 1

    def __init__(self, diagnostics: Sequence[Diagnostic]):
        self.diagnostics = list(diagnostics)
        super().__init__(self.format())

    def format(self) -> str:
        return "\n".join(d.format() for d in self.diagnostics)


class UsageError(CasmechError):
    """The command line or API call is wrong (not the model)."""

    exit_code = 2


# SUNDIALS return flags (IDAS IDA_*, CVODES CV_*) -> what they mean, for failure messages
SOLVER_REASONS = {
    "TOO_MUCH_ACC": "too much accuracy requested (rtol/atol below what double precision "
                    "reaches)",
    "TOO_MUCH_WORK": "too many steps (max_num_steps) before the next output time",
    "ERR_FAIL": "the error test failed repeatedly (or |h| = hmin)",
    "CONV_FAIL": "the corrector did not converge (or |h| = hmin)",
    "CONV_FAILURE": "the corrector did not converge (or |h| = hmin)",
    "LINIT_FAIL": "the linear solver could not be set up",
    "LSETUP_FAIL": "the linear solver's setup failed (a singular iteration matrix?)",
    "LSOLVE_FAIL": "the linear solver failed",
    "RES_FAIL": "the residual function failed (NaN or an interrupt)",
    "RHSFUNC_FAIL": "the right-hand side failed (NaN or an interrupt)",
    "REP_RES_ERR": "the residual function failed repeatedly",
    "CONSTR_FAIL": "the inequality constraints failed",
}
FLAG = r'returned "(?:IDA|CV)_(\w+)"'


def solver_reason(error: BaseException) -> str:
    """What a SUNDIALS solver said, from the RuntimeError CasADi raised ("IDAS: too much
    accuracy requested"), else the error's last line."""
    text = str(error)
    match = _pattern(FLAG).search(text)
    if match:
        solver = "IDAS" if "Idas" in text or '"IDA_' in text else "CVODES"
        return f"{solver}: {SOLVER_REASONS.get(match.group(1), match.group(1))}"
    lines = [line for line in text.strip().splitlines() if line.strip()]
    return lines[-1] if lines else type(error).__name__


class BodyName(str):
    """The name of a body where a failure names joints (its normalization row p^T p - 1):
    `FailureContext` calls it a body."""


@record(frozen=False)
class FailureContext:
    """What an analysis failure names: time, cause, joints involved (with their sources); an
    entry whose name is a BodyName is a body's normalization row."""

    time: float | None
    cause: str
    joints: list[tuple[str, Source | None, float]] = field(default_factory=list)
    measure: str = "residual"  # what the number beside each joint is

    def format(self) -> str:
        at = f"at t = {self.time:.6g}: " if self.time is not None else ""
        lines = [f"analysis failed {at}{escape(self.cause, keep_newlines=True)}"]
        for name, source, residual in self.joints:
            where = f"{source}: " if source else ""
            what = "body" if isinstance(name, BodyName) else "joint"
            lines.append(f"  {where}{what} '{escape(name)}' ({self.measure} {residual:.3e})")
        return "\n".join(lines)


class AnalysisError(CasmechError):
    """An analysis failed (assembly, singular configuration, solver). Keeps partial results."""

    exit_code = 3

    def __init__(self, context: FailureContext, partial=None):
        self.context = context
        self.partial = partial
        super().__init__(context.format())


class Interrupted(AnalysisError, KeyboardInterrupt):
    """SIGINT or SIGTERM stopped an analysis (casmech.runtime.interrupts). An AnalysisError, so that
    the analyses keep the rows computed so far in `partial` as they do for a failure; a
    KeyboardInterrupt, so that a Python caller's Ctrl-C handling sees it. Exit code 128 + the
    signal's number (130 for SIGINT, 143 for SIGTERM)."""

    def __init__(self, signum: int, partial=None):
        self.signum = signum
        self.signal_name = signal.Signals(signum).name
        self.exit_code = 128 + signum
        super().__init__(FailureContext(None, f"interrupted by {self.signal_name}"), partial)

    def __str__(self) -> str:
        return f"interrupted by {self.signal_name}"


def failed(values) -> bool:
    """Whether any of `values` is None (a check that failed and was reported)."""
    return any(value is None for value in values)
