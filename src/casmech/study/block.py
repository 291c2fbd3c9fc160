"""A study from its written form: the YAML `study:` block or the command line's options.

Both give a `form` (grid, normal, uniform: name -> text or numbers; samples, seed, keep) that
`build` checks against the model's parameters and turns into a design.Study. A problem is a
`Problem` (a path in the form, an error code, a message, a hint); the YAML block reports it as
a located `file:line:col: error[CODE] study....` (`located`), the command line as a usage error
naming the option (`usage`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from casmech.core.records import record
from casmech.errors import Diagnostic, ModelError, UsageError, did_you_mean
from casmech.study import design, kept
from casmech.study.design import Study, StudyError

AXES = ("grid", "normal", "uniform")  # form keys naming parameters
OPTIONS = {"grid": "--grid", "normal": "--normal", "uniform": "--uniform",
           "samples": "--samples", "seed": "--seed", "keep": "--keep"}


@record
class Problem:
    path: tuple  # inside the form: ("grid", "L"), ("keep", 0), ("samples",)
    code: str  # errors.CODES: E300 unknown name, E103 malformed value, E409 inconsistent
    message: str
    hint: str | None = None
    at_key: bool = False  # located at the mapping key (a name) rather than its value


class StudyProblems(Exception):
    def __init__(self, problems: Sequence[Problem]):
        super().__init__("; ".join(p.message for p in problems))
        self.problems = list(problems)


def _name_problem(path: tuple, name: str, parameters: Mapping, others: Mapping[str, str]
                  ) -> Problem | None:
    """An unknown parameter, or a body/joint/force name (not a parameter)."""
    if name in parameters:
        return None
    what = others.get(name)
    if what:
        return Problem(path, "E300", f"'{name}' is a {what}, not a parameter",
                       "a study varies entries of `parameters:`; name the quantity there and "
                       "use it in the model", at_key=True)
    return Problem(path, "E300", f"unknown parameter '{name}'",
                   did_you_mean(name, parameters) or
                   f"the model's parameters: {', '.join(parameters) or 'none'}", at_key=True)


def build(form: Mapping, parameters: Mapping, others: Mapping[str, str] | None = None) -> Study:
    """The Study of a form, or StudyProblems listing everything wrong with it."""
    problems: list[Problem] = []
    values: dict[str, dict] = {axis: {} for axis in AXES}
    for axis in AXES:
        for name, given in (form.get(axis) or {}).items():
            path = (axis, name)
            problem = _name_problem(path, name, parameters, others or {})
            try:
                values[axis][name] = (design.grid_values(given) if axis == "grid"
                                      else design.distribution(axis, given))
            except StudyError as error:
                problems.append(Problem(path, error.code, str(error), error.hint))
            if problem:
                problems.append(problem)
    for index, text in enumerate(form.get("keep") or ()):
        try:
            kept.parse(text)
        except StudyError as error:
            problems.append(Problem(("keep", index), "E103", str(error), error.hint))
    if problems:
        raise StudyProblems(problems)
    try:
        return Study(values["grid"], {**values["normal"], **values["uniform"]},
                     int(form.get("samples") or 0), int(form.get("seed") or 0),
                     tuple(form.get("keep") or ()))
    except StudyError as error:
        where = error.where or ("seed" if str(error).startswith("seed") else "samples")
        raise StudyProblems([Problem((where,), error.code, str(error), error.hint)]) from None


def check_keep(study: Study, names: Sequence[str], t_end: float,
               events: Sequence[str] = ()) -> None:
    """Every kept output names a results column (at a time within the run) or an event."""
    problems = []
    for index, text in enumerate(study.keep):
        try:
            kept.check(kept.parse(text), names, t_end, events)
        except StudyError as error:
            problems.append(Problem(("keep", index), "E300", str(error), error.hint))
    if problems:
        raise StudyProblems(problems)


def located(problems: StudyProblems, document) -> ModelError:
    """The problems of a YAML `study:` block, located in its file."""
    def where(p: Problem):
        path = ("study", *p.path)
        return document.locate_key(path) if p.at_key else document.locate(path)

    return ModelError([Diagnostic(p.code, _dotted(("study", *p.path)), p.message, where(p),
                                  hint=p.hint) for p in problems.problems])


def usage(problems: StudyProblems) -> UsageError:
    """The problems of the command line's study options."""
    lines = []
    for p in problems.problems:
        option = OPTIONS.get(p.path[0], p.path[0])
        subject = f" {p.path[1]}" if p.path[0] in AXES and len(p.path) > 1 else ""
        hint = f" ({p.hint})" if p.hint else ""
        lines.append(f"error[{p.code}] {option}{subject}: {p.message}{hint}")
    return UsageError("\n".join(lines))


def _dotted(path: tuple) -> str:
    from casmech.schema.loader import format_path

    return format_path(path)


def document_form(path) -> tuple[dict, object]:
    """The `study:` block of a model file as a form (empty when there is none) and the
    document that locates its values."""
    from casmech.schema.loader import load_file

    document = load_file(str(path))
    data = document.data if isinstance(document.data, dict) else {}
    block = data.get("study")
    return (dict(block) if isinstance(block, dict) else {}), document
