"""The part of a run's metadata.json that `casmech run --replay` reads, validated by a schema.

A metadata file may come from anyone (a colleague, an archive, a download): it is read with a
size bound, parsed as JSON and checked against `Record` (pydantic) before anything in it is
used. Each problem is a located diagnostic of the metadata file (line and column of the value,
or of the mapping a missing key belongs in), and all of them make one usage error:

    run/metadata.json:12:13: error[E102] files.model.sha256: a sha256 is 64 hexadecimal digits

Keys the replay does not read (timings, versions, results) are not checked.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    StrictFloat,
    StrictStr,
    ValidationError,
    field_validator,
)

from casmech.errors import Diagnostic, Source, UsageError, escape

MAX_BYTES = 64 << 20  # the model text and solver messages are in it: a few MB at most
Number = StrictFloat  # strict: a JSON integer is taken, a string is not
Digest = Annotated[str, Field(pattern=r"^[0-9a-f]{64}$")]


class _Open(BaseModel):
    model_config = ConfigDict(extra="allow", strict=True)


class FileEntry(_Open):
    path: StrictStr
    sha256: Digest


class ModelEntry(_Open):
    absolute_path: StrictStr


class AnalysisEntry(_Open):
    type: StrictStr
    t_end: Number | None = None
    output_step: Number | None = None
    rtol: Number | None = None
    atol: Number | None = None
    formulation: StrictStr | None = None
    stabilization: StrictStr | None = None
    method: StrictStr | None = None


class Options(_Open):
    allow_dir: list[StrictStr] = []
    format: list[Literal["csv", "hdf5"]] = ["csv"]
    reactions_frame: Any = None  # a frame's name, or joint -> frame
    mode: Literal["interpreted", "compiled", "auto"] | None = None
    option: list[StrictStr] = []  # the --option KEY=VALUE texts

    @field_validator("reactions_frame")
    @classmethod
    def _frames(cls, value):
        if value is None or isinstance(value, str) or (isinstance(value, dict) and all(
                isinstance(k, str) and isinstance(v, str) for k, v in value.items())):
            return value
        raise ValueError("a frame's name, or a mapping of joint names to frame names")


class Record(_Open):
    model: ModelEntry
    files: dict[StrictStr, FileEntry]
    overrides: dict[StrictStr, Any]  # parameter -> its --set text (or a number)
    analysis: AnalysisEntry
    mode: Literal["interpreted", "compiled"]
    status: StrictStr | None = None
    options: Options = Options()

    @field_validator("overrides")
    @classmethod
    def _overrides(cls, value: dict):
        wrong = [name for name, text in value.items()
                 if isinstance(text, bool) or not isinstance(text, (str, int, float))]
        if wrong:
            raise ValueError(f"parameter '{wrong[0]}': a --set text or a number is expected")
        return value


# pydantic's error type -> the diagnostic code (errors.CODES) and what is expected
_CODES = {"missing": "E100", "string_pattern_mismatch": "E103", "literal_error": "E103"}
_EXPECTED = {"string_pattern_mismatch": "a sha256: 64 hexadecimal digits"}


def read(path: Path) -> Record:
    """The record of a metadata.json (a UsageError with located diagnostics otherwise)."""
    try:
        with open(path, "rb") as handle:
            data = handle.read(MAX_BYTES + 1)
    except FileNotFoundError:
        raise UsageError(f"{escape(path)}: no such file") from None
    except OSError as error:
        raise UsageError(f"{escape(path)}: cannot be read ({error.strerror})") from None
    if len(data) > MAX_BYTES:
        raise UsageError(f"{escape(path)}: larger than {MAX_BYTES >> 20} MB; not a "
                         "metadata.json written by casmech run")
    try:
        text = data.decode("utf-8")
        document = json.loads(text)
    except UnicodeDecodeError as error:
        raise _located(path, [Diagnostic("E001", "", f"not UTF-8 text ({error.reason})",
                                         Source(str(path), 1, 1))]) from None
    except ValueError as error:  # json.JSONDecodeError, or a number too deep to convert
        where = Source(str(path), getattr(error, "lineno", 1), getattr(error, "colno", 1))
        message = getattr(error, "msg", str(error))
        raise _located(path, [Diagnostic("E001", "", f"not JSON: {message}", where,
                                         hint="a metadata.json written by casmech run")]) \
            from None
    if not isinstance(document, dict):
        raise _located(path, [Diagnostic("E003", "", "the document is not a JSON object",
                                         Source(str(path), 1, 1),
                                         hint="a metadata.json written by casmech run")])
    try:
        return Record.model_validate(document)
    except ValidationError as error:
        nodes, seen, found = _nodes(text), set(), []
        for item in error.errors(include_url=False):
            if item["loc"] not in seen:
                seen.add(item["loc"])
                found.append(_diagnostic(path, item, nodes))
        raise _located(path, found) from None


def _located(path: Path, diagnostics: list[Diagnostic]) -> UsageError:
    return UsageError(f"{escape(path)} is not a metadata.json casmech run --replay can repeat:\n"
                      + "\n".join(d.format() for d in diagnostics))


def _diagnostic(path: Path, item: dict, nodes) -> Diagnostic:
    kind = item["type"]
    location = tuple(item["loc"])
    code = _CODES.get(kind, "E102")
    line, col = _position(nodes, location)
    message = "missing required key" if kind == "missing" else item["msg"]
    got = None if kind == "missing" else repr(item.get("input"))[:80]
    return Diagnostic(code, _dotted(location), message,
                      Source(str(path), line, col), expected=_EXPECTED.get(kind), got=got)


def _dotted(location: tuple) -> str:
    """files["a.yaml"].sha256: a key that is not a name in brackets, an index as [k]."""
    text = ""
    for part in location:
        if isinstance(part, int):
            text += f"[{part}]"
        elif str(part).isidentifier():
            text += f".{part}" if text else str(part)
        else:
            text += f"[{json.dumps(str(part))}]"
    return text


def _nodes(text: str):
    """The YAML node tree of the JSON text (JSON is YAML), for positions; None if it does
    not compose."""
    import yaml

    try:
        return yaml.compose(text, Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader))
    except yaml.YAMLError:
        return None


def _position(node, location: tuple) -> tuple[int, int]:
    """1-based line and column of the value at `location`, or of the deepest mapping or list
    on its way that exists (where a missing key belongs)."""
    import yaml

    if node is None:
        return 1, 1
    for part in location:
        child = None
        if isinstance(node, yaml.MappingNode):
            child = next((value for key, value in node.value if key.value == str(part)), None)
        elif isinstance(node, yaml.SequenceNode) and isinstance(part, int) \
                and 0 <= part < len(node.value):
            child = node.value[part]
        if child is None:
            break
        node = child
    return node.start_mark.line + 1, node.start_mark.column + 1
